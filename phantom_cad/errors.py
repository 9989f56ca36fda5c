"""The project's user-facing error: below every layer, so any of them can raise it and the
command line prints it as one line (``error: ...``), exit code 2, never a traceback."""

from __future__ import annotations


class UserError(Exception):
    """An error whose message is for the user: printed without a traceback, exit code 2."""
