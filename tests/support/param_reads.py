"""Which parameters a piece of code reads: a recording stand-in for :class:`HandParams`.

:func:`recording` wraps a hand's parameters in a proxy that logs every value read through it,
as a path: ``params.fingers["index"].proximal`` logs the field ``("fingers", "index", "proximal")``,
``params.document["palm"]["wall_mm"]`` the document key ``("palm", "wall_mm")``. Properties and
methods of the parameter objects (``params.digit(d)``, ``guide.L0``) run on the proxy, so what
they read is logged too. ``params.digest`` gives a token of its own to every recording: a memo
keyed by the digest (``kinematics.memo``) never answers from an earlier computation, whose reads
would go unseen.

:func:`field_sources` maps each field of the frozen parameters to the document keys it is made
from, found by the parser itself: every key the parser asks for (defaults included) is nudged
alone and the document parsed again; the fields that change come from that key.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import itertools
import types
from collections.abc import Mapping
from typing import Any

from phantom_cad.params import parse
from phantom_cad.params.errors import ParamError
from phantom_cad.params.reader import TomlTable

Path = tuple

_TOKENS = itertools.count()


class Reads:
    """What one recording saw: ``fields`` (paths of parameter fields), ``keys`` (document key paths
    read as values), ``tables`` (document tables iterated whole)."""

    def __init__(self):
        self.fields: set[Path] = set()
        self.keys: set[Path] = set()
        self.tables: set[Path] = set()
        self.token = f"recording-{next(_TOKENS)}"


def _wrap(value, path: Path, reads: Reads):
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return _Fields(value, path, reads)
    if isinstance(value, Mapping):
        return _FieldMap(value, path, reads)
    reads.fields.add(path)
    return value


class _Fields:
    """A frozen parameter object (HandParams, Finger, Guide...) that logs what is read of it."""

    __slots__ = ("_target", "_path", "_reads")

    def __init__(self, target, path: Path, reads: Reads):
        object.__setattr__(self, "_target", target)
        object.__setattr__(self, "_path", path)
        object.__setattr__(self, "_reads", reads)

    @property
    def __class__(self):       # isinstance() sees the parameter object's class
        return type(object.__getattribute__(self, "_target"))

    def __getattr__(self, name: str):
        target = object.__getattribute__(self, "_target")
        path = object.__getattribute__(self, "_path")
        reads = object.__getattribute__(self, "_reads")
        if path == () and name == "digest":
            return reads.token
        if path == () and name == "document":
            return _Document(target.document, (), reads)
        attr = getattr(type(target), name, None)
        if isinstance(attr, property):
            return attr.fget(self)
        if isinstance(attr, functools.cached_property):
            return attr.func(self)
        if isinstance(attr, types.FunctionType):
            return types.MethodType(attr, self)
        return _wrap(getattr(target, name), path + (name,), reads)

    def __setattr__(self, name, value):
        raise dataclasses.FrozenInstanceError(f"cannot assign to field {name!r}")

    def __repr__(self) -> str:
        return f"<recording {object.__getattribute__(self, '_target')!r}>"


class _FieldMap(Mapping):
    """A mapping of parameter objects (``params.fingers``) that logs what is read of it."""

    def __init__(self, target: Mapping, path: Path, reads: Reads):
        self._target, self._path, self._reads = target, path, reads

    def __getitem__(self, key):
        return _wrap(self._target[key], self._path + (key,), self._reads)

    def __contains__(self, key) -> bool:
        return key in self._target

    def __iter__(self):
        return iter(self._target)

    def __len__(self) -> int:
        return len(self._target)


class _Document(Mapping):
    """A table of the parameter document that logs the keys read as values, and itself when it is
    iterated (``canon.plain`` of a table iterates it and reads every value)."""

    def __init__(self, target: Mapping, path: Path, reads: Reads):
        self._target, self._path, self._reads = target, path, reads

    def __getitem__(self, key):
        value = self._target[key]
        if isinstance(value, Mapping):
            return _Document(value, self._path + (key,), self._reads)
        self._reads.keys.add(self._path + (key,))
        return value

    def __contains__(self, key) -> bool:
        return key in self._target

    def __iter__(self):
        self._reads.tables.add(self._path)
        return iter(self._target)

    def __len__(self) -> int:
        return len(self._target)


class _Retokened:
    """``params`` under a recording's digest, nothing logged: makes a memo entry a recording will
    find, at the speed of the parameters themselves."""

    __slots__ = ("_target", "digest")

    def __init__(self, target, token: str):
        object.__setattr__(self, "_target", target)
        object.__setattr__(self, "digest", token)

    @property
    def __class__(self):
        return type(object.__getattribute__(self, "_target"))

    def __getattr__(self, name: str):
        return getattr(object.__getattribute__(self, "_target"), name)


def ahead(params, reads: Reads):
    """``params`` under ``reads``' digest, read without logging: for a computation made ahead of a
    recording (its memo entry is the recording's), whose reads the recording must not see."""
    return _Retokened(params, reads.token)


def recording(params) -> tuple[Any, Reads]:
    """(a stand-in for ``params`` that logs what is read through it, the log)."""
    reads = Reads()
    return _Fields(params, (), reads), reads


# ---------------------------------------------------------------------------
# fields -> document keys
# ---------------------------------------------------------------------------

def flatten(obj, path: Path = ()) -> dict[Path, Any]:
    """{field path: value} of every leaf of a parameter object, as :func:`recording` names them
    (the document, the source file and the plugin list aside)."""
    out: dict[Path, Any] = {}
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        for f in dataclasses.fields(obj):
            if path == () and f.name in ("document", "source", "plugins"):
                continue
            out.update(flatten(getattr(obj, f.name), path + (f.name,)))
    elif isinstance(obj, Mapping):
        for k, v in obj.items():
            out.update(flatten(v, path + (k,)))
    else:
        out[path] = obj
    return out


@contextlib.contextmanager
def _asked():
    """Log (document key path, value) of every value the parser asks for, defaults included."""
    asked: dict[Path, Any] = {}
    get = TomlTable._get

    def logged(self, key, *args, **kwargs):
        value = get(self, key, *args, **kwargs)
        if not isinstance(value, dict):
            asked[tuple(self.path.split(".")) + (key,) if self.path else (key,)] = value
        return value

    TomlTable._get = logged
    try:
        yield asked
    finally:
        TomlTable._get = get


def _nudges(value):
    """Values near ``value`` to try in its place."""
    if isinstance(value, bool):
        return [not value]
    if isinstance(value, (int, float)):
        return [value + 1e-4, value - 1e-4] if value == 0 else [value * (1 + 1e-4), value * (1 - 1e-4)]
    if isinstance(value, str):
        return {"right": ["left"], "left": ["right"]}.get(value, [value + "x"])
    if isinstance(value, list):
        return [value[:i] + [n] + value[i + 1:] for i, v in enumerate(value) for n in _nudges(v)]
    return []


def _put(doc: dict, path: Path, value) -> dict:
    import copy

    out = copy.deepcopy(doc)
    table = out
    for k in path[:-1]:
        table = table.setdefault(k, {})
    table[path[-1]] = value
    return out


def nudges(document: Mapping) -> tuple[list[tuple[Path, dict]], list[Path]]:
    """([(a document key the parser asks for, the document with that key alone nudged)], the keys no
    nudge could move without the parser refusing the document) of the hand ``document`` (a plain
    dict): every nudge the parser accepts, defaults included."""
    with _asked() as asked:
        parse(document)
    out, stuck = [], []
    for key, value in asked.items():
        moved = False
        for v in _nudges(value):
            doc = _put(document, key, v)
            try:
                parse(doc)
            except ParamError:
                continue
            moved = True
            out.append((key, doc))
        if not moved:
            stuck.append(key)
    return out, stuck


def field_sources(document: Mapping) -> tuple[dict[Path, set[Path]], list[Path]]:
    """({field path: the document keys it is made from}, the keys no nudge could move) of the hand
    ``document`` (a plain dict)."""
    base = flatten(parse(document))
    sources: dict[Path, set[Path]] = {f: set() for f in base}
    moved, stuck = nudges(document)
    for key, doc in moved:
        for f, v in flatten(parse(doc)).items():
            if repr(v) != repr(base.get(f)):
                sources.setdefault(f, set()).add(key)
    return sources, stuck


def covered(key: Path, cover: Reads, document: Mapping) -> bool:
    """Whether the document key ``key`` is in what ``cover`` (a part's ``inputs()``) read: read as a
    value, or, for a key absent from the document (a default), its nearest table taken whole."""
    def present(path: Path) -> bool:
        table = document
        for k in path:
            if not isinstance(table, Mapping) or k not in table:
                return False
            table = table[k]
        return True

    if key in cover.keys:
        return True
    if present(key):
        return False
    parent = key[:-1]
    while parent and not present(parent):
        parent = parent[:-1]
    return parent in cover.tables


def uncovered(reads: Reads, cover: Reads, sources: dict[Path, set[Path]], document: Mapping) -> list[str]:
    """The document keys ``reads`` read (directly, or through the fields made from them) that are
    not :func:`covered` by ``cover``; a field no known key makes is named too."""
    def dotted(path: Path) -> str:
        return ".".join(map(str, path))

    out = []
    for f in reads.fields:
        if f not in sources:
            out.append(f"field {dotted(f)}: no document key is known to make it")
            continue
        out += [f"{dotted(k)} (read as {dotted(f)})" for k in sources[f] if not covered(k, cover, document)]
    out += [dotted(k) for k in reads.keys if not covered(k, cover, document)]
    return sorted(set(out))
