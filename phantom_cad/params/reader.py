"""A strict reader over a parsed TOML table.

Every accessor names the dotted field, the value and the rule when it refuses;
``done()`` rejects keys nobody asked for, listing the allowed ones.
"""

from __future__ import annotations

import math
from typing import Any

from .errors import ParamError

_MISSING = object()
#: no number in a parameter file is larger: a guard against typos and overflow in derived values
MAGNITUDE = 1e6


class TomlTable:
    def __init__(self, data: Any, path: str, source: str | None):
        self.path = path
        self.source = source
        if not isinstance(data, dict):
            raise ParamError(path or "<root>", data, "must be a table", source)
        self.data = data
        self.asked: list[str] = []

    # -- helpers -----------------------------------------------------------
    def field(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def error(self, key: str, value, rule: str) -> ParamError:
        return ParamError(self.field(key), value, rule, self.source)

    def _get(self, key: str, default=_MISSING):
        self.asked.append(key)
        if key not in self.data:
            if default is _MISSING:
                raise ParamError(self.field(key), None, "is required but missing", self.source)
            return default
        return self.data[key]

    # -- accessors ---------------------------------------------------------
    def number(self, key: str, *, gt=None, ge=None, lt=None, le=None, default=_MISSING) -> float:
        value = self._get(key, default)
        return self.check_number(key, value, gt=gt, ge=ge, lt=lt, le=le)

    def check_number(self, key, value, *, gt=None, ge=None, lt=None, le=None) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(key, value, "must be a number")
        raw, value = value, float(value)   # errors show the value as written
        if not math.isfinite(value):
            raise self.error(key, raw, "must be finite")
        if abs(value) > MAGNITUDE:
            raise self.error(key, raw, f"must lie within +-{MAGNITUDE:g} (no dimension, angle, stiffness or "
                             "tolerance of a hand comes near it)")
        if gt is not None and not value > gt:
            raise self.error(key, raw, f"must be > {gt:g}")
        if ge is not None and not value >= ge:
            raise self.error(key, raw, f"must be >= {ge:g}")
        if lt is not None and not value < lt:
            raise self.error(key, raw, f"must be < {lt:g}")
        if le is not None and not value <= le:
            raise self.error(key, raw, f"must be <= {le:g}")
        return value

    def string(self, key: str, choices: tuple[str, ...] | None = None, default=_MISSING) -> str:
        value = self._get(key, default)
        if not isinstance(value, str):
            raise self.error(key, value, "must be a string")
        if choices is not None and value not in choices:
            raise self.error(key, value, f"must be one of: {', '.join(choices)}")
        return value

    def vector(self, key: str, n: int, **bounds) -> tuple[float, ...]:
        value = self._get(key)
        if not isinstance(value, list) or len(value) != n:
            raise self.error(key, value, f"must be a list of {n} numbers")
        return tuple(self.check_number(f"{key}[{i}]", v, **bounds) for i, v in enumerate(value))

    def interval(self, key: str, **bounds) -> tuple[float, float]:
        """A [low, high] pair with low < high."""
        value = self._get(key)
        if not isinstance(value, list) or len(value) != 2:
            raise self.error(key, value, "must be a list [low, high] of two numbers")
        lo = self.check_number(f"{key}[0]", value[0], **bounds)
        hi = self.check_number(f"{key}[1]", value[1], **bounds)
        if not lo < hi:
            raise self.error(key, value, "low must be < high")
        return lo, hi

    def table(self, key: str, default=_MISSING) -> "TomlTable":
        value = self._get(key, default)
        return TomlTable(value, self.field(key), self.source)

    def keys(self) -> list[str]:
        return list(self.data)

    def done(self) -> None:
        allowed = list(dict.fromkeys(self.asked))
        for key in self.data:
            if key not in allowed:
                raise ParamError(
                    self.field(key), self.data[key],
                    f"unknown key '{key}' (allowed: {', '.join(allowed)})", self.source,
                )
