"""One parameter file describes one hand: schema, load/dump, digest."""

from .errors import ParamError
from .io import DEFAULT_PARAMS, dump_params, dumps, load_document, load_params
from .schema import EffectLibrary, HandParams, parse

__all__ = ["ParamError", "EffectLibrary", "HandParams", "parse", "load_params", "load_document",
           "dump_params", "dumps", "DEFAULT_PARAMS"]
