"""Typed errors for parameter files."""

from __future__ import annotations


class ParamError(ValueError):
    """A parameter file breaks a rule.

    ``field`` is the dotted path of the offending key (``fingers.index.guide.d1_mm``),
    ``value`` the value found, ``rule`` the rule it breaks, ``source`` the file.
    """

    def __init__(self, field: str, value, rule: str, source: str | None = None):
        self.field = field
        self.value = value
        self.rule = rule
        self.source = source
        where = f"{source}: " if source else ""
        super().__init__(f"{where}{field} = {value!r}: {rule}")
