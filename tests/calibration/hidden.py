"""Hidden physics written out here, independently of the effect library, for test_hidden_matrix.

Nothing here calls ``simulate``, ``run_pipeline``, ``Hand.forward`` or an effect class to make
data: the geometry is read from ``hand.params`` (guides, pulley radii, joint radii, path lengths,
mechanics), the servo travel from ``hand.u_min / u_max``, and the physics is numpy, stage by stage
in the order the hand works:

    drive      play of full width b_s in the servo's drive (test_backlash.played), then the drive
               tendon's friction band (a second play, in series, of full width w_rest + w_growth
               (s - s_min) / (s_max - s_min) at the angle it receives, s the cosine law's MCP angle:
               the spring's tension), then the tendon's slack: a dead band delta_s at the start of
               travel (tendon servos u1..u5)
    cosine law q_MCP = alpha - arccos((d1^2 + d2^2 - L^2) / (2 d1 d2)), L = L0 - r (1 + e) u_eff
    tendon     eq. (13): M q = A q_MCP, row k >= 1 of M is e_k + kappa (l_1 + .. + l_k) / R_k R^T,
               kappa per chain and per row = elastic compliance (common, per finger, or both
               added) + the capstan's extra stretch kappa_ref (exp(d mu Theta) - 1), Theta =
               q_MCP * sum(A) (the tendon's wrap), kappa_ref = the elastic compliance when one is
               hidden, else k_s / EA of [mechanics]
    joints     zero offsets, then any extra physics (gravity sag, a soft stop)
    camera     what the camera reads: (1 + c_j) q_j

The magnitudes are drawn from each effect's ``typical`` range (read from the registry's
``parameters(hand)``: the magnitude tuples only)."""

from __future__ import annotations

import math

import numpy as np

from phantom_cad.calibration.effects import get_effect

from .test_backlash import played

#: the hand effects of the library, and the measurement-side one
HAND_EFFECTS = ("tendon_slack", "pulley_radius_error", "tendon_elasticity", "tendon_elasticity_per_finger",
                "friction_hysteresis", "joint_offset", "backlash", "drive_friction")
MEASUREMENT_EFFECTS = ("camera_scale",)


def draw(hand, name: str, rng) -> np.ndarray:
    """Every parameter of effect ``name`` drawn uniformly from its typical range (a random sign for
    signed ones), in the effect's file units and parameter order."""
    plist = get_effect(name).parameters(hand)
    lo = np.array([p.typical[0] for p in plist])
    hi = np.array([p.typical[1] for p in plist])
    mag = rng.uniform(lo, hi)
    sign = np.where(rng.random(len(plist)) < 0.5, -1.0, 1.0)
    return np.where([p.signed for p in plist], sign * mag, mag)


def directions(u, sweep) -> np.ndarray:
    """+1 flexing / -1 extending / 0 never moving, per row and servo, from the order of the
    commands within each sweep: the sign of the last nonzero step (held through flat steps, so the
    sample at the turning point, commanded twice, still counts as flexing), the first rows take the
    sign of the sweep's first move."""
    d = np.zeros(u.shape)
    for k in np.unique(sweep):
        rows = np.flatnonzero(sweep == k)
        for s in range(u.shape[1]):
            x = u[rows, s]
            last = 0.0
            col = np.zeros(rows.size)
            for i in range(1, rows.size):
                step = np.sign(x[i] - x[i - 1])
                if step != 0:
                    last = step
                col[i] = last
            moves = np.flatnonzero(col)
            if moves.size:
                col[: moves[0]] = col[moves[0]]
            d[rows, s] = col
    return d


def slack(hand, u, delta_deg) -> np.ndarray:
    """Dead band at the start of travel of the tendon servos u1..u5 (delta in degrees per servo)."""
    y = np.array(u, dtype=float)
    for s in range(5):
        lo = hand.u_min[s]
        y[:, s] = lo + np.maximum(u[:, s] - lo - math.radians(delta_deg[s]), 0.0)
    return y


def friction_band(hand, y, sweep, rest_deg, growth_deg) -> np.ndarray:
    """The drive tendon's friction band on the angle ``y`` (N, 6) the drive delivers, row by row:
    the finger's side moves only when the drive is more than w/2 away, then trails it by w/2, with
    w = rest + growth (s(y) - s(u_min)) / (s(u_max) - s(u_min)) degrees (the spring's tension grows
    with the MCP angle s of the cosine law); each sweep starts with the output at its input; the
    tendon servos u1..u5 only."""
    out = np.array(y, dtype=float)
    s = mcp_angles(hand, y)
    s0 = mcp_angles(hand, hand.u_min[None, :])[0]
    s1 = mcp_angles(hand, hand.u_max[None, :])[0]
    for k in range(5):
        half = np.radians(rest_deg + growth_deg * (s[:, k] - s0[k]) / (s1[k] - s0[k])) / 2.0
        z = None
        for i in range(len(y)):
            if i == 0 or sweep[i] != sweep[i - 1]:
                z = y[i, k]
            elif y[i, k] - z > half[i]:
                z = y[i, k] - half[i]
            elif z - y[i, k] > half[i]:
                z = y[i, k] + half[i]
            out[i, k] = z
    return out


def mcp_angles(hand, u_eff, radius_rel=None) -> np.ndarray:
    """q_MCP (thumb q_MP) of each tendon chain (N, 5) by the cosine law with the pulley radius
    r (1 + e_s); the reference angle of the CMC is u6 itself (gain 1)."""
    e = np.zeros(5) if radius_rel is None else np.asarray(radius_rel, dtype=float)
    s = np.zeros((u_eff.shape[0], 6))
    for chain in hand.params.chains:
        g, k = chain.guide, chain.spec.servo
        r = chain.servo_radius * (1.0 + e[k])
        L0 = math.sqrt(g.d1 ** 2 + g.d2 ** 2 - 2 * g.d1 * g.d2 * math.cos(g.alpha))
        L = L0 - r * u_eff[:, k]
        s[:, k] = g.alpha - np.arccos((g.d1 ** 2 + g.d2 ** 2 - L ** 2) / (2 * g.d1 * g.d2))
    s[:, 5] = u_eff[:, 5]
    return s


def ideal_ratios(chain) -> np.ndarray:
    """A: q_k / q_MCP of the analytic model (eq. 2), R_MCP / R_k."""
    R = np.array(chain.radii)
    return R[0] / R


def chain_coupling(chain, kappa) -> np.ndarray:
    """(N, n) q_k / q_MCP with the compliance kappa (N,) felt by the chain: eq. (13), M q = A q_MCP,
    row k >= 1 of M is e_k + kappa (sum of the path lengths up to joint k) / R_k R^T; solved row by row."""
    R = np.array(chain.radii)
    A = R[0] / R
    kappa = np.atleast_1d(np.asarray(kappa, dtype=float))
    n = R.size
    M = np.broadcast_to(np.eye(n), (kappa.size, n, n)).copy()
    for k in range(1, n):
        M[:, k, :] += (kappa * sum(chain.path_lengths[:k]) / R[k])[:, None] * R[None, :]
    return np.linalg.solve(M, np.broadcast_to(A, (kappa.size, n))[..., None])[..., 0]


def truth(hand, u, sweep, hidden: dict, extra=None) -> np.ndarray:
    """Noise-free q (N, 15) the camera reads for commands u of the sweeps ``sweep`` with the effects
    ``hidden`` ({name: parameter vector in file units}) and ``extra`` (callable (s, q) -> q on the
    hand's joint angles, before the camera) written out as in the module docstring."""
    h = {k: np.asarray(v, dtype=float) for k, v in hidden.items()}
    chains = hand.params.chains
    # drive: play in the drive, then the tendon's slack on what the drive delivers
    u_eff = played(u, sweep, h["backlash"]) if "backlash" in h else np.array(u, dtype=float)
    if "drive_friction" in h:
        u_eff = friction_band(hand, u_eff, sweep, *h["drive_friction"])
    if "tendon_slack" in h:
        u_eff = slack(hand, u_eff, h["tendon_slack"])
    s = mcp_angles(hand, u_eff, h.get("pulley_radius_error"))
    # the compliance each chain's elastic segments feel, per row
    n = u.shape[0]
    kappa = np.zeros((n, 5))
    mech = hand.params.mechanics
    ref = np.full(5, mech.spring_k / mech.tendon_EA)   # the tendon's compliance friction stretches
    if "tendon_elasticity" in h:
        kappa[:] = h["tendon_elasticity"][0]
        ref[:] = h["tendon_elasticity"][0]
    if "tendon_elasticity_per_finger" in h:
        # each finger's own compliance; hidden with tendon_elasticity, on top of the common one
        kappa += h["tendon_elasticity_per_finger"]
        ref = kappa[0].copy()
    if "friction_hysteresis" in h:
        mu = h["friction_hysteresis"][0]
        d = directions(u, sweep)
        for chain in chains:
            k = chain.spec.servo
            theta = s[:, k] * ideal_ratios(chain).sum()
            kappa[:, k] += ref[k] * (np.exp(d[:, k] * mu * theta) - 1.0)
    q = np.zeros((n, 15))
    for chain in chains:
        k = chain.spec.servo
        ratio = chain_coupling(chain, kappa[:, k])
        for i, qi in enumerate(chain.spec.q_index):
            q[:, qi] = ratio[:, i] * s[:, k]
    q[:, 14] = s[:, 5]
    if "joint_offset" in h:
        q += np.radians(h["joint_offset"])
    if extra is not None:
        q = extra(s, q)
    if "camera_scale" in h:
        q *= 1.0 + h["camera_scale"]
    return q


def hidden_values(hand, names, seed) -> dict:
    """{name: drawn parameter vector} for the effects ``names``, from one seed."""
    rng = np.random.default_rng([seed, 4242])
    return {n: draw(hand, n, rng) for n in names}


# -- physics outside the library -----------------------------------------------------------------

def gravity_sag(hand, g_deg=(1.0, 0.6, 0.3)):
    """The palm held horizontal, palm down: the weight of the links beyond each finger joint
    flexes it by g_i cos(phi_i), phi_i the absolute angle of the link that joint carries (the sum
    of the chain's joint angles up to it; 0 = horizontal, the moment arm shrinks as the link turns
    down). g (deg) for MCP, PIP, DIP of the four fingers; the thumb (its own plane) is left out.
    Returns extra(s, q) for :func:`truth`."""
    g = np.radians(np.asarray(g_deg, dtype=float))
    fingers = [c for c in hand.params.chains if c.spec.digit != "thumb"]

    def extra(s, q):
        out = q.copy()
        for chain in fingers:
            phi = np.zeros(q.shape[0])
            for i, qi in enumerate(chain.spec.q_index):
                phi = phi + q[:, qi]
                out[:, qi] += g[i] * np.cos(phi)
        return out

    return extra


def soft_stop(hand, digit="ring", at=0.85, slope=0.8):
    """The MCP of one finger meets a compliant stop at ``at`` of the angle it reaches at full
    travel; beyond it, it turns only ``slope`` of what the tendon asks (the distal joints, driven by
    the same tendon excursion, follow their coupling to the unblocked reference angle).
    Returns (extra(s, q) for :func:`truth`, the joint index, the stop angle in rad)."""
    chain = next(c for c in hand.params.chains if c.spec.digit == digit)
    mcp = chain.spec.q_index[0]
    top = mcp_angles(hand, hand.u_max[None, :])[0, chain.spec.servo]
    q_stop = at * top

    def extra(s, q):
        out = q.copy()
        x = q[:, mcp]
        out[:, mcp] = np.where(x > q_stop, q_stop + slope * (x - q_stop), x)
        return out

    return extra, mcp, q_stop
