"""Memoisation by the parameters' digest: the one helper for every pure function of a hand's
parameters that several callers ask for (the routes, their runs, the travel poses, the posed
nodes of a strand, a link's tendon features in the CAD layer).

A key starts with ``params.digest`` (which covers every field, the side included), so two hands
never share an entry; each store is a plain dict cleared when it passes ``cap`` entries (a
process builds a handful of hands). Callers must treat what they get as read-only.
"""

from __future__ import annotations

from typing import Any, Callable


#: every store :func:`memoised` has filled, for :func:`clear`
_STORES: list[dict] = []


def memoised(store: dict, key: tuple, make: Callable[[], Any], cap: int = 64) -> Any:
    """``store[key]``, made by ``make()`` the first time (``store`` cleared past ``cap``)."""
    try:
        return store[key]
    except KeyError:
        pass
    if len(store) >= cap:
        store.clear()
    if not any(s is store for s in _STORES):
        _STORES.append(store)
    value = store[key] = make()
    return value


def clear() -> None:
    """Empty every store: for a caller that changes what a function of the parameters returns
    without changing the parameters (a test that swaps the forearm module's layout)."""
    for store in _STORES:
        store.clear()
