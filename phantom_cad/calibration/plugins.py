"""A user's effects in a plugin file (``--plugin FILE.py``, or ``plugins = [...]`` in a parameter
file): executed once per process, refused with a one-line error naming the file and the line
(docs/effects.md, "Your own effect").
"""

from __future__ import annotations

from ..params.errors import ParamError
from . import library as _library  # noqa: F401  (a plugin may not take a built-in effect's name)
from .framework import REGISTRY, unregister_effect

#: resolved plugin path -> the effect names it registered (a file is executed once per process)
PLUGINS: dict[str, tuple[str, ...]] = {}


class PluginError(ParamError):
    """A plugin file that cannot be loaded: names the file, the line and the rule."""

    def __init__(self, path: str, rule: str, where: str | None = None):
        self.field, self.value, self.rule, self.source = where or "--plugin", path, rule, None
        ValueError.__init__(self, f"{where + ': ' if where else ''}plugin {path}: {rule}")


def load_plugin(path, where: str | None = None) -> tuple[str, ...]:
    """Execute the Python file ``path`` once; return the names of the effects it registered.

    Refused (PluginError, naming the file and the line): a missing file, a syntax error, an
    exception while it runs (an import error included), no effect registered, or an effect whose
    name is already taken by the library or another plugin."""
    import hashlib
    import importlib.util
    import os
    import sys
    import traceback

    path = os.path.abspath(os.fspath(path))
    if path in PLUGINS:
        return PLUGINS[path]

    def fail(rule: str):
        return PluginError(path, rule, where)

    if not os.path.isfile(path):
        raise fail("no such file" if not os.path.exists(path) else "is not a file")
    if not path.endswith(".py"):
        raise fail("a plugin must be a Python file (.py)")
    module_name = "phantom_cad_plugin_" + hashlib.sha256(path.encode()).hexdigest()[:12]
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    before = dict(REGISTRY)
    try:
        spec.loader.exec_module(module)
    except SyntaxError as exc:
        _restore(before)
        raise fail(f"line {exc.lineno}: syntax error: {exc.msg}") from None
    except Exception as exc:
        _restore(before)
        frames = [f for f in traceback.extract_tb(exc.__traceback__) if os.path.abspath(f.filename) == path]
        line = f"line {frames[-1].lineno}: " if frames else ""
        raise fail(f"{line}{type(exc).__name__}: {exc}") from None
    new = tuple(n for n, e in REGISTRY.items() if before.get(n) is not e)
    taken = [n for n in new if n in before]
    if taken:
        _restore(before)
        raise fail(f"effect '{taken[0]}' is already defined (by the library or another plugin); give yours "
                   "another name")
    if not new:
        raise fail("registers no effect (decorate an Effect subclass with @register_effect)")
    sys.modules[module_name] = module
    PLUGINS[path] = new
    return new


def _restore(before: dict) -> None:
    REGISTRY.clear()
    REGISTRY.update(before)


def unload_plugin(path) -> None:
    """Forget a plugin and unregister its effects (tests)."""
    import os

    for name in PLUGINS.pop(os.path.abspath(os.fspath(path)), ()):
        unregister_effect(name)
