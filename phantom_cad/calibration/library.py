"""The library's built-in effects (docs/effects.md), registered in ``framework.REGISTRY`` on import:

    servo      backlash, drive_friction (plays on the drive), tendon_slack (a dead band)
    reference  pulley_radius_error
    tension    tendon_elasticity, tendon_elasticity_per_finger (the paper's eq. 13), routed_elasticity,
               routed_elasticity_per_finger (the printed routing's statics), friction_hysteresis (capstan)
    joint      joint_offset
    measurement camera_scale

and the play (backlash) operator the drive's plays share (:func:`apply_play`). numpy only.
"""

from __future__ import annotations

import hashlib

import numpy as np

from ..kinematics.memo import memoised
from ..kinematics.statics import hand_statics, reference_angles
from ..kinematics.topology import CHAINS, CMC_SERVO, DISTAL_JOINTS, JOINTS, N_SERVOS, SERVOS, TENDON_SERVOS, servo_joints
from ..units import DEG
from .framework import CHAIN_SERVOS, MEASUREMENT, Context, Effect, Param, Runs, Signature, register_effect

@register_effect
class TendonSlack(Effect):
    name = "tendon_slack"
    stage = "servo"
    order = 10
    explanation = ("joints lag by a constant servo angle from the start of travel, the same in both "
                   "directions, and stay at rest for the first degrees: slack in the tendon (a dead band "
                   "before it pulls)")
    formula = "u_eff = u_min + max(u - u_min - delta_j, 0) for the tendon servos u1..u5"
    signature = ("zero in a band at the start of travel, then a lag of about delta_j * dq/du on every joint "
                 "of the chain (MCP included); independent of the direction")
    reference = "dead-zone / backlash models of cable drives, e.g. Kaneko et al., IEEE T-RA 7(3), 1991"
    leaves = Signature(direction="same", at_rest="zero", trend="flat", joints="all", reversal="none")

    def parameters(self, hand):
        return [Param(f"{sv.label}_deg", 0.0, 15.0, (1.0, 4.0), False, servo_joints(sv.index), True,
                      f"dead band of servo {sv.label} before its tendon pulls, degrees")
                for sv in CHAIN_SERVOS]

    def apply(self, ctx, x):
        lo = ctx.hand.u_min[TENDON_SERVOS]
        d = x * DEG
        ctx.u_eff[:, TENDON_SERVOS] = lo + np.maximum(ctx.u_eff[:, TENDON_SERVOS] - lo - d, 0.0)

    invertible = True

    def invert(self, hand, u_eff, x):
        u = u_eff.copy()
        u[..., TENDON_SERVOS] = u_eff[..., TENDON_SERVOS] + x * DEG
        return u


@register_effect
class PulleyRadiusError(Effect):
    name = "pulley_radius_error"
    stage = "reference"
    order = 20
    explanation = ("every joint of the chain, MCP included, drifts in proportion to the servo angle, the same "
                   "in both directions: the servo pulley's effective radius differs from nominal")
    formula = "r_eff,j = r_j (1 + e_j) in eq. (5)-(6): L = L0 - r_eff u"
    signature = ("grows with u (about e_j * u * dq/du), on the MCP as much as on PIP/DIP; zero at rest; "
                 "independent of the direction")
    reference = "eq. (5)-(6) of the paper; effective radius = pulley radius + half the tendon diameter"
    leaves = Signature(direction="same", at_rest="zero", trend="grows", joints="all", reversal="none")

    def parameters(self, hand):
        return [Param(f"{sv.label}_relative", -0.2, 0.2, (0.015, 0.04), True, servo_joints(sv.index), True,
                      f"relative error of servo {sv.label}'s effective pulley radius")
                for sv in CHAIN_SERVOS]

    def apply(self, ctx, x):
        ctx.radius_scale = ctx.radius_scale * (1.0 + x)


@register_effect
class TendonElasticity(Effect):
    name = "tendon_elasticity"
    stage = "tension"
    stretch = "paper"
    order = 30
    explanation = ("distal joints (PIP, DIP, thumb IP) lag in proportion to flexion, the MCP does not, the same "
                   "in both directions: the return spring's tension stretches the tendon (eq. 11-14)")
    formula = ("T = k_s sum_i R_i q_i, b_j = T l_j / (EA R_j); M q = A q_MCP with C_j = (k_s/EA) l_j / R_j; "
               "fitted: the compliance ratio c = k_s / EA (1/m), one for the whole hand")
    signature = "negative on PIP/DIP/IP, growing with flexion, zero on MCP/MP/CMC; no direction dependence"
    reference = "the paper's mechanics-based compensation, eq. (11)-(14)"
    leaves = Signature(direction="same", at_rest="zero", trend="grows", joints="distal", reversal="none",
                       digits="all")

    def parameters(self, hand):
        return [Param("compliance_per_m", 0.0, 5.0, (0.07, 0.27), False, DISTAL_JOINTS, True,
                      "k_s / EA: spring rate over tendon axial stiffness, 1/m (only the ratio is identifiable)")]

    def apply(self, ctx, x):
        # replaces the base k_s / EA and only it: what other tension-stage effects added (before
        # or after this one) stays
        ctx.compliance += x[0] - ctx.compliance_base
        ctx.compliance_base = float(x[0])
        # `fit` writes compliance 0 when the data showed no elasticity: the base compensation is
        # then off, but the tendon's stiffness that friction stretches stays the [mechanics] one,
        # as it was when friction was fitted without this effect
        if x[0] > 0.0:
            ctx.compliance_ref = float(x[0])


@register_effect
class TendonElasticityPerFinger(Effect):
    name = "tendon_elasticity_per_finger"
    stage = "tension"
    stretch = "paper"
    order = 31
    simpler = "tendon_elasticity"
    explanation = ("distal joints lag in proportion to flexion, the MCP does not, by a different amount on each "
                   "finger: each tendon (or its return spring) has its own compliance (eq. 11-14 per finger)")
    formula = "C_j = c_k l_j / R_j for chain k: the compliance ratio k_s / EA fitted per finger (5 values)"
    signature = ("negative on PIP/DIP/IP, growing with flexion, zero on MCP/MP/CMC, its size different from "
                 "finger to finger; no direction dependence")
    reference = "the paper's mechanics-based compensation, eq. (11)-(14), one compliance per tendon"
    leaves = Signature(direction="same", at_rest="zero", trend="grows", joints="distal", reversal="none")

    def parameters(self, hand):
        return [Param(f"{c.digit}_per_m", 0.0, 5.0, (0.07, 0.27), False, c.q_index[1:], True,
                      f"k_s / EA of the {c.digit} tendon, 1/m") for c in CHAINS]

    def apply(self, ctx, x):
        # replaces the base k_s / EA (or tendon_elasticity's, which runs before) chain by chain
        ctx.compliance += x - ctx.compliance_base
        ctx.compliance_base = 0.0
        ctx.compliance_ref = np.where(x > 0.0, x, ctx.compliance_ref)


@register_effect
class FrictionHysteresis(Effect):
    name = "friction_hysteresis"
    stage = "tension"
    #: after both elasticity effects: the capstan term stretches the tendon whose compliance they set
    order = 35
    directional = True
    explanation = ("residual flips sign with the direction of motion and grows with tension: friction in the "
                   "tendon path (capstan)")
    formula = ("capstan: the elastic segments carry T exp(d mu Theta), Theta = sum of the chain's joint angles "
               "(the tendon's wrap on the joint pulleys), d = +1 flexing / -1 extending; the extra stretch "
               "T (exp(d mu Theta) - 1) l_j / (EA R_j) enters eq. (13) as a compliance k_s/EA (exp(d mu Theta) - 1)")
    signature = ("PIP/DIP/IP lag when flexing and lead when extending (a hysteresis loop), the gap grows with "
                 "flexion; MCP untouched; zero when the direction is unknown")
    reference = "capstan equation T2 = T1 exp(mu theta) (Euler-Eytelwein); Kaneko et al., IEEE T-RA 7(3), 1991"
    leaves = Signature(direction="flips", at_rest="zero", trend="grows", joints="distal", reversal="jump",
                       digits="all")

    def parameters(self, hand):
        return [Param("mu", 0.0, 1.0, (0.08, 0.25), False, DISTAL_JOINTS, True,
                      "friction coefficient of the tendon on its pulleys and guides")]

    def apply(self, ctx, x):
        if ctx.direction is None or x[0] == 0.0:
            return
        if ctx.s is None:
            raise RuntimeError("friction_hysteresis needs the reference angles")
        # Theta = s * sum(A): the sum of the chain's joint angles, the tendon's wrap on its pulleys
        theta = ctx.s[:, TENDON_SERVOS] * ctx.hand.coupling_ideal.sum(axis=1)[TENDON_SERVOS]
        f = np.exp(ctx.direction[:, TENDON_SERVOS] * x[0] * theta)
        ctx.compliance += ctx.compliance_ref * (f - 1.0)


@register_effect
class JointOffset(Effect):
    name = "joint_offset"
    stage = "joint"
    order = 90
    explanation = ("a constant per joint, present at rest and in both directions: a zero offset "
                   "(assembly or the measurement's reference)")
    formula = "q_i = q_model,i + o_i"
    signature = "constant per joint over the whole sweep, nonzero at rest, independent of direction and servo"
    reference = "standard zero-offset calibration of joint encoders (e.g. Hollerbach & Wampler 1996)"
    leaves = Signature(direction="same", at_rest="nonzero", trend="flat", joints="any", reversal="none")

    def parameters(self, hand):
        return [Param(f"{j.label}_deg", -10.0, 10.0, (0.5, 2.0), True, (j.index,), False,
                      f"zero offset of joint {j.label}, degrees") for j in JOINTS]

    def apply(self, ctx, x):
        ctx.q += x * DEG

    invertible = True

    def invert(self, hand, q, x):
        return q - x * DEG


def play_start(runs: Runs, half) -> np.ndarray:
    """The output of the play (backlash) operator of half width ``half`` when each run starts: a
    sweep starts with the output at the command; a run flexing ends at max(y0, u_end - half), one
    extending at min(y0, u_end + half) (the command is monotone within a run). ``half``: one value,
    or one per run (the half width at the run's last command, for a play whose width follows the
    command: drive_friction)."""
    y0 = np.empty(runs.direction.size)
    halves = np.broadcast_to(np.asarray(half, dtype=float), runs.direction.shape)
    y = 0.0
    for i, (d, first, us, ue, h) in enumerate(zip(runs.direction, runs.first, runs.u_start, runs.u_end, halves)):
        y = us if first else y
        y0[i] = y
        if d > 0:
            y = max(y, ue - h)
        elif d < 0:
            y = min(y, ue + h)
    return y0


def play(u: np.ndarray, rows: np.ndarray, runs: Runs, half, y0: np.ndarray) -> np.ndarray:
    """The play operator's output at ``rows`` of the history (their commands ``u``): within a run
    flexing max(y0, u - half), extending min(y0, u + half), at rest y0. ``half``: one value or one
    per row (u - half must not fall as u grows: a width that grows by less than the command)."""
    r = runs.of_row[rows]
    d, start = runs.direction[r], y0[r]
    return np.where(d > 0, np.maximum(start, u - half),
                    np.where(d < 0, np.minimum(start, u + half), np.clip(start, u - half, u + half)))


def apply_play(ctx: Context, key, half_width, servos) -> None:
    """Add a play (a dead band at each reversal) to the drive of ``servos`` (0-based indices or a
    slice): its half width in rad ``half_width(rows)`` (len(rows), 6) at rows of the history (one
    value per servo, from the command there; 0 on the other servos). ``key`` names the play and its
    parameters (the cache of the run starts). Plays in series (the servo gear's backlash, then the
    drive tendon's friction band) act as one play of the summed width: after a reversal the output stands still until the
    command has crossed both bands, then trails it by both halves. So the servo stage keeps one play,
    of every width added so far: its contribution to u_eff (``ctx.play_delta``) is replaced, what
    other servo-stage effects did stays (exact for constant widths; a width that follows the
    command is taken at the command). The output at the start of each run comes from the whole
    history (play_start), computed once per set of plays."""
    h = ctx.history
    ctx.plays.append((key, half_width, frozenset(int(j) for j in np.arange(N_SERVOS)[servos])))
    keys = tuple(k for k, _, _ in ctx.plays)

    def total(rows):
        return sum(f(rows) for _, f, _ in ctx.plays)

    half_rows = total(ctx.rows)
    delta = np.zeros_like(ctx.u_eff)
    for j in sorted(set().union(*(sv for _, _, sv in ctx.plays))):
        runs = h.runs(j)
        y0 = h.cached(("play", keys, j), lambda runs=runs, j=j: play_start(runs, total(runs.last)[:, j]))
        delta[:, j] = play(ctx.u[:, j], ctx.rows, runs, half_rows[:, j], y0) - ctx.u[:, j]
    ctx.u_eff = ctx.u_eff - ctx.play_delta + delta
    ctx.play_delta = delta


@register_effect
class CameraScale(Effect):
    name = "camera_scale"
    stage = MEASUREMENT
    order = 10
    explanation = ("one joint's measured angle is a fixed multiple of the model's, in both directions and "
                   "zero at rest: a scale error of the measurement (camera calibration, marker placement), "
                   "not of the hand; never used by the control law")
    formula = "q_measured,i = (1 + k_i) q_i"
    signature = "proportional to the joint angle on one joint, zero at rest, independent of direction"
    reference = "scale calibration of vision-based joint measurement (e.g. Hollerbach & Wampler 1996)"
    leaves = Signature(direction="same", at_rest="zero", trend="grows", joints="any", reversal="none")

    def parameters(self, hand):
        return [Param(f"{j.label}_relative", -0.2, 0.2, (0.01, 0.04), True, (j.index,), True,
                      f"scale error of the measurement of joint {j.label}, relative") for j in JOINTS]

    def apply(self, ctx, x):
        ctx.q *= 1.0 + x


@register_effect
class Backlash(Effect):
    name = "backlash"
    stage = "servo"
    #: first: the play is in the servo's drive, ahead of the tendon's slack (slack(play(u)))
    order = 5
    directional = True
    explanation = ("after each reversal the joints stay still while the servo turns through a dead band, then "
                   "follow it lagging by half the band, on every joint of the chain: backlash (play) in the drive")
    formula = ("play operator per servo within each sweep, full width b_j: u_eff,k = min(max(u_eff,k-1, u_k - b/2), "
               "u_k + b/2), u_eff = u at the start of a sweep")
    signature = ("a band of about b_j * dq/du between the flexing and the extending branch, the same width over "
                 "the travel, on every joint of the chain (MCP included); after each reversal the residual ramps "
                 "across the band within b_j of servo travel; zero when the history is unknown")
    reference = "play / backlash operator (Krasnosel'skii & Pokrovskii 1989; Tao & Kokotovic, Automatica 1993)"
    leaves = Signature(direction="flips", at_rest="any", trend="flat", joints="all", reversal="jump")

    def parameters(self, hand):
        return [Param(f"{sv.label}_deg", 0.0, 10.0, (1.0, 3.5), False, servo_joints(sv.index), True,
                      f"full width of the play of servo {sv.label}'s drive, degrees") for sv in SERVOS]

    def apply(self, ctx, x):
        if ctx.history is None or not np.any(x):
            return
        half = 0.5 * np.asarray(x, dtype=float) * DEG
        apply_play(ctx, ("backlash", tuple(half)), lambda rows: np.broadcast_to(half, (len(rows), N_SERVOS)),
                   np.flatnonzero(half > 0))

    #: the control law does not know the direction of the next move: it aims at the middle of the
    #: play (u = u_eff), as it aims at the middle of the friction band
    invertible = True


@register_effect
class DriveFriction(Effect):
    name = "drive_friction"
    stage = "servo"
    #: after the drive's play (5), before the tendon's slack (10): the friction acts along the
    #: drive tendon between the servo pulley and the finger
    order = 7
    directional = True
    explanation = ("every joint of the chain, MCP included, lags when flexing and leads when extending by a "
                   "band already there at rest and wider as the spring's tension grows, and stands still for "
                   "the band's width after each reversal: friction along the drive tendon's path (guides, "
                   "palm channels), loaded by the return spring's pre-tension and tension")
    formula = ("a play of full width w(u) on each tendon servo's command, within each sweep: flexing "
               "u_eff = max(u_eff,prev, u - w/2), extending min(u_eff,prev, u + w/2), u_eff = u at the start "
               "of a sweep; w(u) = w_rest + w_growth (s - s_min) / (s_max - s_min), s = eq. (6)'s MCP "
               "reference angle, to which the spring's tension (eq. 11, T = k_s sum R_i q_i) is proportional; "
               "in series with backlash the two plays act as one of the summed width")
    signature = ("a band between the flexing and the extending branch on every joint of the chain (MCP "
                 "included), present where the travel starts back (at rest) and widening with flexion; after "
                 "each reversal the joints stand still through the band; the same width law on every digit")
    reference = ("Coulomb friction in series with an elastic tendon is a play (Prandtl's elastic-plastic "
                 "element; Krasnosel'skii & Pokrovskii 1989); tension-proportional friction in tendon-sheath "
                 "and guide paths: Kaneko et al., IEEE T-RA 7(3), 1991")
    leaves = Signature(direction="flips", at_rest="any", trend="any", joints="all", reversal="jump",
                       digits="all")

    def parameters(self, hand):
        servos = tuple(j for sv in CHAIN_SERVOS for j in servo_joints(sv.index))
        return [Param("width_at_rest_deg", 0.0, 10.0, (0.8, 2.0), False, servos, True,
                      "full width of the friction band at rest (the spring's pre-tension), servo degrees"),
                Param("width_growth_deg", 0.0, 10.0, (0.8, 2.0), False, servos, True,
                      "what the band's full width gains from rest to full flexion (the spring's tension), "
                      "servo degrees")]

    @staticmethod
    def tension(hand, u) -> np.ndarray:
        """(s - s_min) / (s_max - s_min) at commands u (..., 6): the spring's tension from rest (0) to
        full flexion (1), s = eq. (6)'s reference angle (0 on the CMC's direct drive)."""
        s = hand.reference_angles(np.asarray(u, dtype=float), hand.servo_radius)
        out = np.zeros(np.shape(u))
        span = hand.s_max - hand.s_min
        out[..., TENDON_SERVOS] = ((s - hand.s_min) / np.where(span > 0, span, 1.0))[..., TENDON_SERVOS]
        return out

    @staticmethod
    def band(tension, x) -> np.ndarray:
        """w / 2 in rad, per servo (0 on the CMC's direct drive), at the tensions of :meth:`tension`."""
        out = 0.5 * (x[0] + x[1] * tension) * DEG
        out[..., CMC_SERVO] = 0.0
        return out

    def apply(self, ctx, x):
        if ctx.history is None or not np.any(x):
            return
        h, hand, x = ctx.history, ctx.hand, np.asarray(x, dtype=float)
        # the tension at every row of the recording does not depend on x: computed once
        t = h.cached(("drive_friction tension",), lambda: self.tension(hand, h.u))
        apply_play(ctx, ("drive_friction", tuple(x)), lambda rows: self.band(t[rows], x), TENDON_SERVOS)

    #: the control law aims at the middle of the band (u = u_eff), as for backlash and friction
    invertible = True


_ROUTED: dict = {}


def routed_statics(hand, scale) -> tuple:
    """The routed statics of every tendon chain (servo order) with the strands' compliance k_s / EA
    scaled by ``scale`` (5,) (kinematics.statics.hand_statics; not checked: a fit may try a scale
    that leaves a joint no coupling and must be free to move away from it). Memoised: a fit's
    Jacobian evaluates many parameter steps at one scale."""
    scale = np.asarray(scale, dtype=float)
    return memoised(_ROUTED, (hand.params.digest, scale.tobytes()),
                    lambda: hand_statics(hand.params, scale, check=False), cap=64)


def routed_reference_angles(hand, statics, u_eff, radius_scale) -> np.ndarray:
    """s (N, 6): the routed servo law's reference angles (the drive's stretch included) at u_eff
    (N, 6) with the effective servo radii r * radius_scale (the law reads r u only, so the
    command is scaled instead); s6 = g u6."""
    s = np.empty(u_eff.shape)
    u = u_eff[:, TENDON_SERVOS] * radius_scale
    chains = hand.params.chains
    # at u = 0 no tension, no stretch: s = 0 exactly. A recording sweeps one servo at a time, so
    # most of a chain's rows are at rest and only the others are solved, every chain's at once
    moved = [np.flatnonzero(u[:, k] != 0.0) if c.linear else slice(None) for k, c in enumerate(statics)]
    s[:, TENDON_SERVOS] = 0.0
    solved = reference_angles([u[rows, k] for k, rows in enumerate(moved)], chains, statics)
    for k, rows in enumerate(moved):
        s[rows, k] = solved[k]
    s[:, CMC_SERVO] = u_eff[:, CMC_SERVO] * hand.params.thumb.cmc_gain
    return s


_ROUTED_S: dict = {}


def apply_routed(ctx: Context, scale) -> None:
    """Put the routed statics with compliance scale ``scale`` (5,) in the model: the reference
    angles become the routed servo law's (the drive stretches), the coupling the routed one
    (pipeline.couple). It replaces the base k_s / EA of the paper's form, as tendon_elasticity does
    (what other tension-stage effects add stays); friction then stretches strands of compliance
    scale x the file's k_s / EA."""
    scale = np.asarray(scale, dtype=float)
    ctx.routed_scale = scale
    ctx.routed = routed_statics(ctx.hand, scale)
    # memoised on everything the law reads: a fit's Jacobian steps many parameters (offsets,
    # friction) that leave it where it was. The commands by their digest (a key of a few bytes
    # for a batch of up to a fit's chunk of rows); a copy, as the context's arrays are the pipeline's own
    u, radius = np.ascontiguousarray(ctx.u_eff), ctx.radius_scale
    key = (ctx.hand.params.digest, scale.tobytes(), radius.tobytes(), u.shape,
           hashlib.blake2b(u, digest_size=16).digest())
    ctx.s = memoised(_ROUTED_S, key, lambda: routed_reference_angles(ctx.hand, ctx.routed, u, radius), cap=8).copy()
    ctx.compliance -= ctx.compliance_base
    ctx.compliance_base = 0.0
    mech = ctx.params.mechanics
    ctx.compliance_ref = np.where(scale > 0.0, scale * mech.spring_k / mech.tendon_EA, ctx.compliance_ref)


#: the joints of the tendon chains: the routed stretch moves the MCP (the drive) as well as the distal joints
_CHAIN_JOINTS = tuple(sorted(i for c in CHAINS for i in c.q_index))


@register_effect
class RoutedElasticity(Effect):
    name = "routed_elasticity"
    stage = "tension"
    stretch = "routed"
    #: before the paper's form: both replace the base k_s / EA, what the other adds stays
    order = 28
    routed = True
    explanation = ("every joint of each chain lags in proportion to the return spring's tension, the distal "
                   "joints most, the MCP by the drive's stretch, the same in both directions: the strands of "
                   "the printed routing stretch more (or less) than the file's k_s / EA says")
    formula = ("the routed statics (docs/transmission.md, kinematics/statics.py) with the strands' compliance "
               "k_s / EA scaled by c: T = k_s sum R_i q_i, loop k carries (n - 1 - k) T and the drive n T R_0 / arm, "
               "each strand stretching over its whole length by F L c / EA; fitted: c (1 = the file's k_s / EA)")
    signature = ("negative on PIP/DIP/IP and smaller on MCP/MP, growing with flexion, zero on the CMC; no "
                 "direction dependence")
    reference = "the routed compensation of docs/transmission.md (eq. 11 for T; Hooke's law per strand)"
    leaves = Signature(direction="same", at_rest="zero", trend="grows", joints="all", reversal="none",
                       digits="all")
    # only k_s / EA is seen in joint angles (gravity off): softer strands and a stiffer return
    # cord are the same scale

    def parameters(self, hand):
        return [Param("compliance_scale", 0.0, 5.0, (0.5, 2.0), False, _CHAIN_JOINTS, True,
                      "the strands' compliance k_s / EA over the file's (1: as the file says; 2: strands half "
                      "as stiff or a return cord twice as stiff)")]

    def apply(self, ctx, x):
        apply_routed(ctx, np.full(len(CHAINS), x[0]))


@register_effect
class RoutedElasticityPerFinger(Effect):
    name = "routed_elasticity_per_finger"
    stage = "tension"
    stretch = "routed"
    order = 29
    routed = True
    simpler = "routed_elasticity"
    explanation = ("every joint of each chain lags in proportion to the return spring's tension, by a different "
                   "amount on each finger: each finger's strands (or return cord) have their own compliance "
                   "(the routed statics per finger)")
    formula = "routed_elasticity with one compliance scale c_k per tendon chain (5 values; replaces the common one)"
    signature = ("as routed_elasticity, its size different from finger to finger; no direction dependence")
    reference = "the routed compensation of docs/transmission.md, one strand compliance per finger"
    leaves = Signature(direction="same", at_rest="zero", trend="grows", joints="all", reversal="none")

    def parameters(self, hand):
        return [Param(f"{c.digit}_scale", 0.0, 5.0, (0.5, 2.0), False, c.q_index, True,
                      f"the {c.digit} strands' compliance k_s / EA over the file's") for c in CHAINS]

    def apply(self, ctx, x):
        apply_routed(ctx, x)
