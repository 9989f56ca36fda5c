"""The wrist joint between the palm and the forearm module (numpy only, palm frame, mm).

The palm ends at its back face (the wrist crease, or the back of the thenar where the CMC's
column sits further back, ``servo_geometry.palm_back``); the forearm module's front face stands a
clearance behind it (``servo_geometry.forearm_front``). A tab of the module lies on the palm's dorsal face
there and two M2 screws hold it: the palm drills their pilots, the module their clearance holes.
Both parts read this one description; the palm moves a screw in along the tab off its cuts.
"""

from __future__ import annotations


import numpy as np

from ... import units
from ...kinematics import forearm_layout as FL
from ...kinematics import frames as F
from ...kinematics import routing
from ...kinematics import routing_paths
from ...kinematics import servo_geometry as SG
from ...kinematics.hand_params import HandParams
from ...kinematics.topology import THUMB_CHAIN
from .common import mm


#: the fastening tab's length over the palm (mm, along y) [choice]
TAB_LENGTH = 10.0


def socket_x(params: HandParams) -> tuple[float, float]:
    """x extent (mm) of the palm's finger sockets (``frames.socket_x``)."""
    lo, hi = F.socket_x(params)
    return mm(lo), mm(hi)


def forearm_block(params: HandParams) -> tuple[float, float, float, float, float, float]:
    """x0, x1, y0, y1, z0, z1 (palm frame, mm) of the forearm module's block
    (``forearm_layout.forearm_box``)."""
    lo, hi = FL.forearm_box(params)
    return (mm(lo[0]), mm(hi[0]), mm(lo[1]), mm(hi[1]), mm(lo[2]), mm(hi[2]))


def tab(params: HandParams) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) of the forearm module's tab on the palm: across the metacarpal block where the
    module covers it, from the module's front face to TAB_LENGTH ahead of the palm's back face,
    one palm wall thick on the palm's dorsal face."""
    forearm_x = forearm_block(params)[:2]
    px0, px1 = socket_x(params)
    top = mm(params.palm.thickness) / 2.0
    return (np.array([max(forearm_x[0], px0), mm(SG.forearm_front(params)), top]),
            np.array([min(forearm_x[1], px1), mm(SG.palm_back(params)) + TAB_LENGTH, top + mm(params.palm.wall)]))


def tab_screw_places(params: HandParams) -> list[tuple[np.ndarray, float]]:
    """(centre, inward) of each of the tab's two screws at its place on the palm's dorsal face: half a
    tab length in from its end, halfway along the tab's length over the palm; ``inward`` the sign of
    x toward the tab's middle. The palm moves a screw in from there off its cuts
    (``Palm.tab_screws``)."""
    lo, hi = tab(params)
    y = (mm(SG.palm_back(params)) + hi[1]) / 2.0
    inset = TAB_LENGTH / 2.0
    return [(np.array([lo[0] + inset, y, lo[2]]), 1.0), (np.array([hi[0] - inset, y, lo[2]]), -1.0)]


def thumb_drive_path(params: HandParams) -> list[np.ndarray]:
    """Palm-frame points (mm, right hand) of the thumb drive where the routing model runs it on the
    forearm module and the palm: where it leaves servo 1's pulley (tangent), its turn onto the CMC
    axis above the CMC pulley's cavity, the CMC axis at the cavity's ceiling (``kinematics.routing``).
    Both parts cut its channel."""
    st = next(s for r in routing.routes(params, right_handed=True)
              if r.tendon.kind == "drive" and r.tendon.digit == THUMB_CHAIN.digit for s in r.strands)
    run = next(r for r in routing_paths.runs(params, right_handed=True) if r.strand == st.name and "palm" in r.links)
    tangent = np.asarray(units.mm(np.array(run.ends["palm"][0])), float)
    pts = [np.asarray(units.mm(np.array(e.pos)), float) for e in st.elements
           if isinstance(e, routing.Point) and e.link == "palm"]
    return [tangent] + pts
