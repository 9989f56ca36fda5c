"""The fingertip force a stalled servo gives: the routed statics (:mod:`.statics`) with a load at
the fingertip pad (docs/force.md).

Per tendon chain (joints k = 0..n-1, reference first, pulley radii R_k), at joint angles q, with
the servo at its stall torque tau:

* the drive pulls with F_d = tau / r (r the servo pulley's radius) and turns the reference joint
  with F_d a, a = d1 d2 sin(alpha - q_0) / L its moment arm (:func:`closed_form.drive_moment_arm`);
* the return cord pulls every joint back with T R_k, T = k_s sum R_k q_k (eq. 11);
* loop k (between joints k and k + 1) with tension F_k turns joint k + 1 by F_k R_{k+1} and holds
  joint k back by F_k R_k;
* a plate at the pad pushes back along the pad's inward normal with f: on joint k that is
  -f m_k, m_k = n . (axis_k x (p - o_k)) the normal's lever about the joint (the transposed
  Jacobian of the pad point, p, along the pad's outward normal, n).

Joint k balances when its tendon torque tau_k = F_d a [k = 0] - T R_k + F_{k-1} R_k - F_k R_k
equals f m_k. Weighting joint k by R_0 / R_k (the ideal coupling, eq. 2) cancels every loop:

    f = (F_d a - n T R_0) / sum_k (R_0 / R_k) m_k,

and the loops follow back from the tip, F_{k-1} = F_k + T + f m_k / R_k. The chain is statically
determinate: the strands' stretch sets the posture (:mod:`.statics`), not the force at it. The
pad and its normal are ``frames.T_distal_pad``'s; the thumb's CMC, held by servo 6, takes the
torque f m_CMC. numpy only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import closed_form as cf
from .frames import T_distal_pad
from .hand_params import HandParams
from .link_frames import link_transforms
from .statics import chain_strands
from .topology import CHAINS, N_JOINTS, chain, digit_links, joint

#: a flexion joint turns its child by +q about the child frame's -x (docs/frames.md)
FLEXION_AXIS = np.array([-1.0, 0.0, 0.0])


@dataclass(frozen=True)
class DigitForce:
    """One digit pressing a plate at its pad with its servo stalled."""

    digit: str
    #: the plate's push on the pad along its normal (N); not above 0: the pad moves off the plate
    force: float
    #: the drive's tension tau / r (N) and its torque about the reference joint (N m)
    drive_tension: float
    drive_torque: float
    #: the return cord's tension (N)
    return_tension: float
    #: per chain joint (reference first): the normal's lever m_k (m) and the tendons' net torque
    #: f m_k that the plate balances (N m)
    levers: tuple[float, ...]
    joint_torques: tuple[float, ...]
    #: per coupling loop (reference side first): its tension (N)
    loop_tensions: tuple[float, ...]
    #: the thumb: the torque (N m) the plate puts on the CMC, which servo 6 holds; None for a finger
    cmc_torque: float | None = None


def pad_levers(params: HandParams, q, digit: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(p, n, m) of a digit's pad at joint angles q (15,): the pad centre and its outward normal
    (palm frame, metres, right hand's frames: a mirror changes no force) and the normal's lever
    m_k = n . (axis_k x (p - o_k)) about each joint of its chain (reference first), the thumb's
    CMC appended: the pad's normal velocity per unit joint rate, the transposed Jacobian's row."""
    q = np.asarray(q, dtype=float)
    if q.shape != (N_JOINTS,):
        raise ValueError(f"q must have shape ({N_JOINTS},), got {q.shape}")
    T = link_transforms(params, q, mirrored=False)
    pad = T[digit_links(digit)[-1].name] @ T_distal_pad(params, digit)
    p, n = pad[:3, 3], pad[:3, 2]
    spec = chain(digit)
    levers = []
    for name in spec.joint_names:
        child = T[joint(name).child]
        axis = child[:3, :3] @ FLEXION_AXIS
        levers.append(float(n @ np.cross(axis, p - child[:3, 3])))
    if digit == "thumb":
        base = T[joint("thumb_cmc").child]
        levers.append(float(n @ np.cross(base[:3, 2], p - base[:3, 3])))
    return p, n, np.array(levers)


def digit_force(params: HandParams, q, digit: str, stall_torque: float | None = None) -> DigitForce:
    """The fingertip force of ``digit`` at joint angles q (15,) with its servo at ``stall_torque``
    (N m; default the file's ``servo.stall_torque_Nm``): the module's statics."""
    q = np.asarray(q, dtype=float)
    c = params.digit(digit).chain
    tau = params.servo.stall_torque if stall_torque is None else float(stall_torque)
    R = np.asarray(c.radii)
    qc = q[list(c.spec.q_index)]
    g = c.guide
    F_d = tau / c.servo_radius
    drive = F_d * float(cf.drive_moment_arm(qc[0], g.d1, g.d2, g.alpha))
    T = float(cf.return_tension(params.mechanics.spring_k, R, qc))
    _, _, levers = pad_levers(params, q, digit)
    m = levers[:len(R)]
    A = cf.ideal_coupling(R)
    f = (drive - T * float(R @ A)) / float(A @ m)
    loops = np.cumsum((T + f * m / R)[:0:-1])[::-1]        # F_{k-1} = F_k + T + f m_k / R_k
    return DigitForce(digit, float(f), float(F_d), float(drive), T, tuple(float(v) for v in m),
                      tuple(float(f * v) for v in m), tuple(float(v) for v in loops),
                      float(f * levers[-1]) if digit == "thumb" else None)


def fingertip_forces(params: HandParams, q, stall_torque: float | None = None) -> tuple[DigitForce, ...]:
    """:func:`digit_force` of every digit (thumb first) at joint angles q (15,)."""
    return tuple(digit_force(params, q, c.digit, stall_torque) for c in CHAINS)



def drive_give(params: HandParams, digit: str, tension: float) -> float:
    """The servo angle (rad) the drive's stretch alone takes at ``tension`` (N): T L_d / (EA r), L_d
    its rest length (the routing model's). A servo that has less of its travel left past contact
    reaches the end of it before its stall torque, and presses with less than :func:`digit_force`
    (the loops' give takes more still)."""
    strands = chain_strands(params)[chain(digit).servo]       # servo order
    return tension * strands.drive / (params.mechanics.tendon_EA * params.digit(digit).chain.servo_radius)
