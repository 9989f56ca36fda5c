"""Every link's frame at joint angles q: the joint transforms T_parent_child, the links'
T_palm_link (mirrored for a left hand) and the actuated joints' origins and axes as a
robot-description writer reads them. numpy only; conventions in :mod:`.frames`."""

from __future__ import annotations


import numpy as np

from .forearm_layout import T_palm_forearm, T_palm_servo
from .frames import T_palm_finger_base, T_palm_thumb_cmc_base, flex, mirror, rot_y, segment_length, trans
from .hand_params import HandParams
from .thenar import T_cmc_base_pulley
from .topology import CMC_Q, JOINTS, LINKS, N_JOINTS, THUMB_CHAIN, joint, link

#: the joint the thumb's twist turns: its chain's reference joint, the MP
THUMB_MP = THUMB_CHAIN.joint_names[0]


def rest_transforms(params: HandParams) -> dict[str, np.ndarray]:
    """Joint origins T_parent_child at rest, named after their frames (right hand, metres)."""
    return joint_transforms(params, np.zeros(N_JOINTS))


def _joint_transform(params: HandParams, ln, q) -> np.ndarray:
    """T_parent_child of link ``ln`` at joint angles q: a fixed mount on the palm (finger base,
    servo pulley), the CMC (about the CMC base's z) or a flexion joint behind the parent's
    segment."""
    if ln.parent_joint is None:
        if ln.segment == "forearm":
            return T_palm_forearm(params)
        if ln.segment == "servo_pulley":
            T = T_palm_servo(params, ln.servo)
            if ln.parent != "palm":          # mounted on the forearm module
                T = np.linalg.inv(_joint_transform(params, link(ln.parent), q)) @ T
            return T
        if ln.segment == "cmc_pulley":
            return T_cmc_base_pulley(params)
        return T_palm_finger_base(params, ln.digit)
    j = joint(ln.parent_joint)
    if j.index == CMC_Q:
        return T_palm_thumb_cmc_base(params, float(q[j.index]))
    T = joint_origin(params, ln)
    return flex(float(q[j.index])) if T is None else T @ flex(float(q[j.index]))


def joint_origin(params: HandParams, ln) -> np.ndarray | None:
    """Where the flexion joint of link ``ln`` sits in its parent's frame before it turns (right
    hand, metres): at the end of the parent's segment, on the parent's y; the thumb's MP turned
    there by ``thumb.twist`` about that y (the metacarpal's length). None where the joint sits at
    the parent's origin untwisted (the fingers' MCPs on their bases)."""
    L = segment_length(params, link(ln.parent))
    j = joint(ln.parent_joint)
    psi = params.thumb.twist if j.name == THUMB_MP else 0.0
    if L == 0.0 and psi == 0.0:
        return None
    T = trans(0, L, 0)
    return T if psi == 0.0 else T @ rot_y(psi)


def joint_transforms(params: HandParams, q) -> dict[str, np.ndarray]:
    """T_parent_child (named ``T_<parent>_<child>``) for every link but the palm at joint angles
    q (15,), right hand, metres."""
    q = np.zeros(N_JOINTS) if q is None else np.asarray(q, float)
    if q.shape != (N_JOINTS,):
        raise ValueError(f"q must have shape ({N_JOINTS},), got {q.shape}")
    return {_transform_name(ln): _joint_transform(params, ln, q) for ln in LINKS if ln.parent is not None}


def _transform_name(ln) -> str:
    return f"T_{ln.parent}_{ln.name}"


#: link -> (parent link, joint transform name), from the topology; palm is the root
LINK_PARENTS: dict[str, tuple[str, str]] = {ln.name: (ln.parent, _transform_name(ln))
                                            for ln in LINKS if ln.parent is not None}


def link_transforms(params: HandParams, q=None, mirrored: bool = True) -> dict[str, np.ndarray]:
    """T_palm_link (metres) of every link at joint angles q (None = rest), mirrored for a left hand
    (``mirrored=False``: the right hand's frames whatever the side, for what a mirror leaves alone)."""
    joints = joint_transforms(params, q)
    out = {"palm": np.eye(4)}
    for name, (parent, jname) in LINK_PARENTS.items():   # topology order: parents first
        out[name] = out[parent] @ joints[jname]
    if mirrored and params.side == "left":
        out = {k: mirror(v) for k, v in out.items()}
    return out


def joints(params: HandParams) -> list[dict]:
    """The 15 actuated joints, in q order (Table I), as a robot-description writer would use
    them: name (``index_dip``, ...), parent and child link, ``origin`` = T_parent_child at rest
    (metres, mirrored for a left hand), ``axis`` (unit vector in the child frame; q turns the
    child about it by +q), ``q_index`` and ``limits`` (rad) from the parameters."""
    rest = joint_transforms(params, None)
    left = params.side == "left"
    out = []
    for j in JOINTS:
        T = rest[_transform_name(link(j.child))]
        digit = params.digit(j.digit)
        if j.index == CMC_Q:
            # the CMC's own rotation Rz(q15) is the joint, not part of its origin
            axis = np.array([0.0, 0.0, -1.0 if left else 1.0])
            limits = params.thumb.cmc_limits
        else:
            axis = np.array([-1.0, 0.0, 0.0])
            limits = dict(zip(digit.chain.joints, digit.chain.limits))[j.key]
        out.append({"name": j.name, "parent": j.parent, "child": j.child,
                    "origin": mirror(T) if left else T, "axis": axis, "q_index": j.index,
                    "limits": tuple(float(v) for v in limits)})
    return out
