"""Canonical data, the one place: plain/frozen copies of parameter documents, canonical JSON
and SHA-256 digests (the same data always gives the same bytes). Stdlib and numpy only.
"""

from __future__ import annotations

import hashlib
import json
import math
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np


def plain(obj):
    """Mutable plain containers (dict, list) from a frozen document."""
    if isinstance(obj, Mapping):
        return {k: plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [plain(v) for v in obj]
    return obj


def freeze(obj):
    """A read-only copy (MappingProxyType, tuples) of a parsed document."""
    if isinstance(obj, Mapping):
        return MappingProxyType({k: freeze(v) for k, v in obj.items()})
    if isinstance(obj, list):
        return tuple(freeze(v) for v in obj)
    return obj


def jsonable(obj: Any) -> Any:
    """Plain JSON types from params values (MappingProxy, tuples, numpy scalars/arrays, dataclasses)."""
    if isinstance(obj, Mapping):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return repr(obj)
    if obj is None or isinstance(obj, (bool, int, float, str)):
        return obj
    if hasattr(obj, "__dataclass_fields__"):
        return {k: jsonable(getattr(obj, k)) for k in obj.__dataclass_fields__}
    return repr(obj)


def canonical(obj: Any) -> bytes:
    """Canonical JSON bytes: sorted keys, no whitespace."""
    return json.dumps(jsonable(obj), sort_keys=True, separators=(",", ":")).encode()


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def digest(document: Mapping[str, Any]) -> str:
    """SHA-256 of a document's canonical JSON: same parameters, same digest."""
    return sha256(canonical(document))
