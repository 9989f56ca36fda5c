"""The project's user-facing error: below every layer, so any of them can raise it and the
command line prints it as one line (``error: ...``), exit code 2, never a traceback."""

from __future__ import annotations


class UserError(Exception):
    """An error whose message is for the user: printed without a traceback, exit code 2."""


def one_line(text) -> str:
    """``text`` on one printable line: control characters (a newline in a file name) escaped as
    Python escapes them, so an error stays one line and a comment stays a comment."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(text))
