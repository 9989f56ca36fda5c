"""The posed hand as a ``cadquery.Assembly``, for CQ-editor users.

In CQ-editor (or any cadquery script)::

    from phantom_cad import load_hand
    from phantom_cad.interop.cadquery import hand_assembly

    hand = load_hand("params/phantom.toml")
    assy = hand_assembly(hand)                      # rest pose
    show_object(assy)                               # CQ-editor
    # assy.export("hand.step")  /  assy.export("hand.glb")

    import numpy as np
    from phantom_cad.kinematics.topology import N_JOINTS, chain
    q = np.zeros(N_JOINTS)
    q[list(chain("index").q_index)] = 0.6           # flex the index (rad)
    show_object(hand_assembly(hand, q, name="index_flexed"))

Parts are build123d solids (``build_part`` of the assembly interface,
phantom_cad.export.interface: phantom_cad.cad.assembly) converted through their OCP
``TopoDS_Shape`` (``cadquery.Shape.cast(part.shape.wrapped)``), named like the exported
files, coloured, and located with ``assembly.pose_transforms(params, q)``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:       # the annotations only: cadquery loads in the functions that use it
    import cadquery


def location(T) -> "cadquery.Location":
    """A cadquery Location from a 4x4 homogeneous transform (mm)."""
    import cadquery as cq
    from OCP.gp import gp_Trsf

    T = np.asarray(T, dtype=float)
    if T.shape != (4, 4):
        raise ValueError(f"a placement must be a 4x4 matrix, got shape {T.shape}")
    trsf = gp_Trsf()
    trsf.SetValues(*T[0, :4], *T[1, :4], *T[2, :4])
    return cq.Location(trsf)


def hand_assembly(hand, q=None, *, name: str | None = None, parts: list[str] | None = None):
    """A ``cadquery.Assembly`` of every part of ``hand`` (a phantom_cad ``Hand``, or
    ``HandParams``) at joint angles ``q`` (topology.N_JOINTS,) rad (None = rest pose).

    ``parts`` restricts the assembly to some part names (default: all)."""
    import cadquery as cq

    from ..export.interface import assembly

    asm = assembly()
    params = getattr(hand, "params", hand)
    names = list(asm.part_names(params))
    if parts is not None:
        unknown = sorted(set(parts) - set(names))
        if unknown:
            raise ValueError(f"unknown part(s) {unknown}; the hand has {names}")
        names = [n for n in names if n in set(parts)]
    poses = asm.pose_transforms(params, None if q is None else np.asarray(q, dtype=float))
    assy = cq.Assembly(name=name or f"{params.name}_{params.side}")
    for n in names:
        built = asm.build_part(params, n)
        shape = cq.Shape.cast(built.shape.wrapped)
        assy.add(shape, name=n, color=cq.Color(*map(float, built.color)), loc=location(poses[n]))
    return assy
