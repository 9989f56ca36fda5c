"""Load and dump parameter files (TOML)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

from ..atomic import write_atomic
from .errors import ParamError
from ..canon import plain
from .schema import EffectLibrary, HandParams, parse

#: the default hand shipped with the package's source tree
DEFAULT_PARAMS = Path(__file__).resolve().parents[2] / "params" / "phantom.toml"


def load_document(path: str | os.PathLike) -> dict[str, Any]:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise ParamError("<file>", str(path), "no such parameter file") from None
    except IsADirectoryError:
        raise ParamError("<file>", str(path), "is a folder, not a parameter file") from None
    except UnicodeDecodeError as exc:
        raise ParamError("<file>", str(path), f"is not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:   # permissions, a symlink loop, ...
        raise ParamError("<file>", str(path), f"cannot be read ({exc.strerror})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ParamError("<file>", str(path), f"is not valid TOML: {exc}", str(path)) from None


def load_params(path: str | os.PathLike | None = None, effects: EffectLibrary | None = None) -> HandParams:
    """Read and validate a parameter file (default: params/phantom.toml); ``effects`` as in
    :func:`~.schema.parse` (``phantom_cad.load_params`` passes the calibration layer's)."""
    path = Path(path) if path is not None else DEFAULT_PARAMS
    return parse(load_document(path), source=str(path), effects=effects)


def dumps(document: Mapping[str, Any]) -> str:
    import tomli_w

    return tomli_w.dumps(plain(document))


def dump_params(document: Mapping[str, Any], path: str | os.PathLike, header: str = "",
                effects: EffectLibrary | None = None) -> None:
    """Validate ``document`` (``effects`` as in :func:`~.schema.parse`) and write it atomically to
    ``path`` (nothing is written if invalid)."""
    parse(document, source=str(path), effects=effects)
    text = header + dumps(document)
    if any(line.strip() and not line.lstrip().startswith("#") for line in header.splitlines()):
        raise ValueError(f"dump_params: the header must be comment lines, got {header!r}")
    tomllib.loads(text)  # what is written reads back (a header line broken by a newline would not)
    write_atomic(path, text)
