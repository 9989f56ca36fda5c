"""The project's user-facing errors: below every layer, so any of them can raise them and the
command line prints each as one line (``error: ...``), exit code 2, never a traceback.
``ParamError`` is the params layer's (``phantom_cad.params`` exports it); it is defined here so
that the models, which check what only they compute (the routing model's clamps), raise it
without importing the params layer."""

from __future__ import annotations


class UserError(Exception):
    """An error whose message is for the user: printed without a traceback, exit code 2."""


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


def one_line(text) -> str:
    """``text`` on one printable line: control characters (a newline in a file name) escaped as
    Python escapes them, so an error stays one line and a comment stays a comment."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(text))
