"""Typed errors for parameter files: :class:`ParamError`, defined in the foundation
(``phantom_cad.errors``) so that the models can raise it too."""

from __future__ import annotations

from ..errors import ParamError

__all__ = ["ParamError"]
