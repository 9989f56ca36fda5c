"""Which module provides the parts: the export pipeline (and interop) code against an
*assembly interface*, not against the part classes.

The interface is the set of functions of :mod:`phantom_cad.cad.assembly` (its module doc lists
them): ``part_names``, ``part_inputs``, ``build_part`` (returns a ``Built``: name, shape,
T_hand_link, color, print_rotation, digit), ``pose_transforms``, ``designed_contacts``,
``bill_of_materials`` and, optionally, ``verify_part``. The tests install a stand-in module
with the same functions (tests/export/standin_assembly.py) by setting
:data:`ASSEMBLY_MODULE`; worker processes receive the module's name with their task.
"""

from __future__ import annotations

import importlib

#: the module providing the parts
ASSEMBLY_MODULE = "phantom_cad.cad.assembly"


def assembly(module: str | None = None):
    """The parts module (imported lazily; it imports OCP only inside build_part)."""
    return importlib.import_module(module or ASSEMBLY_MODULE)
