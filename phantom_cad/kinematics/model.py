"""The kinematic model: servo angles u (6) <-> joint angles q (15).

Forward, analytic (eq. 2-10):    q = H(u) u, q_ref = alpha - arccos(...), q_i = (R_ref / R_i) q_ref, q15 = g u6.
Forward, compensated:             the statics of the printed routing (``compensation="routed"``,
                                  the default: kinematics.statics, docs/transmission.md), or the
                                  paper's eq. (11)-(14), q_comp = (M^-1 A) q_ref (``compensation="paper"``).
Inverse, control law (eq. 15):    u* = H^+(clip(q_d) + b(clip(q_d))).

Every digit's reachable set is a curve q = c s(u) with a constant vector c (A, M^-1 A or the
routed coupling; :meth:`Hand.coupling_vectors` is the paper's) and the reference angle s = q_MCP
(q_MP for the thumb); a loop preload makes the routed curve piecewise affine, q = c s + d. The
control law (:meth:`Hand.control_law`) projects each digit's target onto its curve by least
squares (s = c.q / c.c, which for a target on the curve is exactly eq. 15), clips s to the
servo travel's image, and inverts the servo's law in closed form: the cosine law, or with the
routed compensation the cosine law with the drive's stretch.

The model knows the parameters by duck typing (``params.chains``, ``params.thumb``,
``params.mechanics``): the kinematics layer never imports the params layer. Fitted effects
(the calibration layer's EffectStack) are passed in by whoever loads them
(``phantom_cad.load_hand``); they build on the compensation they name (the routed statics with a
routed elasticity among them, else the paper's). All functions broadcast
over any leading batch shape. numpy only.
"""

from __future__ import annotations


import numpy as np

from . import closed_form as cf
from . import statics as st
from .hand_params import HandParams
from .topology import CHAINS, CMC_Q, CMC_SERVO, N_JOINTS, N_SERVOS, TENDON_SERVOS


#: rows per block of a batched forward (a block's temporaries fit a core's L2 cache)
_BLOCK = 8192
#: the compensations ``Hand`` knows: the printed routing's statics, the paper's eq. (11)-(14)
COMPENSATIONS = ("routed", "paper")
#: every tendon chain's joints, chain after chain (each chain's in its own order), and the servo
#: and the chain of each: the couplings of all chains in one array operation
_CHAIN_JOINTS = np.array([i for spec in CHAINS for i in spec.q_index])
_JOINT_SERVO = np.array([spec.servo for spec in CHAINS for _ in spec.q_index])
_JOINT_CHAIN = np.array([k for k, spec in enumerate(CHAINS) for _ in spec.q_index])


class Hand:
    """The kinematic model of one hand, built from its validated parameters (``HandParams``).

    ``effects``: an object with ``forward(hand, u, compensated)`` and ``inverse(hand, q, compensated)``
    (the calibration layer's EffectStack) that replaces the plain model, or None. A parameter file
    that carries fitted effects must be given them: ``phantom_cad.load_hand`` does.

    ``compensation``: what ``compensated=True`` means, ``"routed"`` (the statics of the printed
    routing, :mod:`.statics`; the default) or ``"paper"`` (eq. 11-14). A hand with fitted effects
    uses the one they were fitted with (``effects.compensation``: "routed" when they hold a routed
    elasticity, else "paper"), which is its default.
    """

    def __init__(self, params: HandParams, effects=None, compensation: str | None = None):
        if params.effects and not effects:
            raise ValueError(f"{params.source or 'these parameters'} carry fitted effects "
                             f"({', '.join(params.effects)}): build the hand with phantom_cad.load_hand "
                             "or pass effects=")
        # fitted effects name their own compensation: a routed elasticity the routed statics, else the paper's
        fitted = getattr(effects, "compensation", "paper") if effects else None
        if compensation is None:
            compensation = fitted or "routed"
        if compensation not in COMPENSATIONS:
            raise ValueError(f"compensation must be one of {', '.join(COMPENSATIONS)}, got {compensation!r}")
        if fitted and compensation != fitted:
            raise ValueError(f"these fitted effects build on the {fitted} compensation: use compensation='{fitted}'")
        self.params = params
        #: the fitted effects this hand applies in forward and inverse (None: the plain model)
        self.effects = effects or None
        #: what ``compensated=True`` means: "routed" or "paper"
        self.compensation = compensation
        chains = params.chains
        thumb = params.thumb
        self._d1 = np.array([c.guide.d1 for c in chains])
        self._d2 = np.array([c.guide.d2 for c in chains])
        self._alpha = np.array([c.guide.alpha for c in chains])
        #: servo pulley radii r_j of the tendon chains (5,)
        self.servo_radius = np.array([c.servo_radius for c in chains])
        self._cosine = cf.cosine_coefficients(self._d1, self._d2, self._alpha, self.servo_radius)
        self._chord = cf.chord_constants(self._d1, self._d2, self._alpha)
        # the same constants as columns, for the chain-major (5, block) layout of a batched forward
        self._cosine_columns = tuple(np.reshape(v, (-1, 1)) for v in self._cosine)
        self._alpha_column = self._alpha[:, None]
        self._cmc_gain = thumb.cmc_gain
        self._coupling_constants = [cf.coupling_constants(c.radii, c.path_lengths) for c in chains]
        # the same per joint of _CHAIN_JOINTS, as columns, for coupling every chain in one pass
        self._joint_constants = tuple(
            np.concatenate([np.broadcast_to(c[i], np.shape(c[0])) for c in self._coupling_constants])[:, None]
            for i in range(4))
        #: k_s / EA (1/m): the compliance of eq. (13)/(14) in the parameter file
        self.compliance = params.mechanics.spring_k / params.mechanics.tendon_EA
        #: the routed statics of each chain (servo order), or None with the paper's compensation
        self.statics = st.hand_statics(params) if compensation == "routed" else None
        self._law = st.RoutedLaw(params.chains, self.statics) if self.statics is not None else None
        self._linear = self.statics is None or all(c.linear for c in self.statics)

        #: (6, 15) maps the per-servo reference angles s to q: q = s @ P
        self.coupling_ideal = self.coupling_matrix(0.0)
        #: the compensation's coupling (with a loop preload, the routed one at rest)
        self.coupling_compensated = (self.coupling_matrix(self.compliance) if self.statics is None else
                                     self._routed_matrix([c.regime(0.0) for c in self.statics]))
        self._project = {False: _projection(self.coupling_ideal), True: _projection(self.coupling_compensated)}

        q_min = np.zeros(N_JOINTS)
        q_max = np.zeros(N_JOINTS)
        for chain in chains:
            for qi, (lo, hi) in zip(chain.spec.q_index, chain.limits):
                q_min[qi], q_max[qi] = lo, hi
        q_min[CMC_Q], q_max[CMC_Q] = thumb.cmc_limits
        self.q_min, self.q_max = q_min, q_max

        tendon = [c.travel for c in chains]
        self.u_min = np.array([t[0] for t in tendon] + [thumb.cmc_travel[0]])
        self.u_max = np.array([t[1] for t in tendon] + [thumb.cmc_travel[1]])
        # image of the servo travel in reference-angle space (the routed compensation's own:
        # the drive's stretch lowers s)
        self.s_min = self.reference_angles(self.u_min)
        self.s_max = self.reference_angles(self.u_max)
        self._s_range = {False: (self.s_min, self.s_max), True: (self.s_min, self.s_max)}
        if self.statics is not None:
            self._s_range[True] = (self.reference_angles(self.u_min, compensated=True),
                                   self.reference_angles(self.u_max, compensated=True))

    # -- eq. (13)/(14): the coupling vectors ------------------------------------
    def coupling_vectors(self, compliance) -> list[np.ndarray]:
        """Per tendon chain (servo order): q_chain = c s, c = M(kappa)^-1 A (eq. 13/14, closed form).

        ``compliance`` kappa = k_s / EA felt by each chain: a scalar, (5,) or (..., 5); each vector
        has shape (..., n_joints of the chain). kappa = 0 gives the analytic coupling A (eq. 2).
        """
        kappa = np.asarray(compliance, dtype=float)
        if kappa.ndim == 0:
            kappa = np.full(len(CHAINS), float(kappa))
        return [cf.coupling_vector(c.radii, c.path_lengths, kappa[..., k], constants)
                for k, (c, constants) in enumerate(zip(self.params.chains, self._coupling_constants))]

    def _routed_matrix(self, regimes) -> np.ndarray:
        """(6, 15) P of the routed statics, each chain in the given regime."""
        P = np.zeros((N_SERVOS, N_JOINTS))
        for spec, c, m in zip(CHAINS, self.statics, regimes):
            P[spec.servo, list(spec.q_index)] = c.c[m]
        P[CMC_SERVO, CMC_Q] = 1.0
        return P

    def coupling_matrix(self, compliance) -> np.ndarray:
        """(6, 15) P with q = s @ P for one compliance (scalar or per chain (5,)); the CMC row is 1."""
        P = np.zeros((N_SERVOS, N_JOINTS))
        for spec, c in zip(CHAINS, self.coupling_vectors(compliance)):
            P[spec.servo, list(spec.q_index)] = c
        P[CMC_SERVO, CMC_Q] = 1.0
        return P

    def couple(self, s: np.ndarray, vectors) -> np.ndarray:
        """q (..., 15) from reference angles s (..., 6) and per-chain coupling vectors (:meth:`coupling_vectors`)."""
        q = np.empty(s.shape[:-1] + (N_JOINTS,))
        for spec, c in zip(CHAINS, vectors):
            q[..., list(spec.q_index)] = s[..., spec.servo, None] * c
        q[..., CMC_Q] = s[..., CMC_SERVO]
        return q

    def couple_compliant(self, s: np.ndarray, compliance) -> np.ndarray:
        """``couple(s, coupling_vectors(compliance))`` for a compliance per sample and chain
        (..., 5), in one pass over every chain's joints: the same arithmetic on each joint, without
        a vector per chain (a fit evaluates this thousands of times on a few thousand rows)."""
        kappa = np.broadcast_to(np.asarray(compliance, dtype=float), s.shape[:-1] + (len(CHAINS),))
        # coupling_vector's constants as columns: each joint's kappa meets its own chain's
        c = cf.coupling_vector(None, None, kappa[..., _JOINT_CHAIN], self._joint_constants)[..., 0]
        q = np.empty(s.shape[:-1] + (N_JOINTS,))
        q[..., _CHAIN_JOINTS] = s[..., _JOINT_SERVO] * c
        q[..., CMC_Q] = s[..., CMC_SERVO]
        return q

    def coupling(self, compensated: bool) -> np.ndarray:
        return self.coupling_compensated if compensated else self.coupling_ideal

    def _couple_routed(self, s: np.ndarray) -> np.ndarray:
        """q (..., 15) of the routed statics at reference angles s (..., 6), each chain in its regime."""
        if self._linear:
            return s @ self.coupling_compensated
        return couple_routed(self.statics, s)

    # -- reference angles (eq. 6, 8, 9) ------------------------------------------
    def reference_angles(self, u: np.ndarray, radius: np.ndarray | None = None,
                         out: np.ndarray | None = None, compensated: bool = False) -> np.ndarray:
        """s (..., 6): q_MCP / q_MP of each tendon chain (eq. 6, 8) and q15 = g u6 (eq. 9).

        ``radius`` overrides the servo pulley radii (an effective radius, (5,)). Beyond the
        cosine law's domain the joint stops folded at alpha (closed_form.reference_angle).
        ``compensated`` with the routed compensation: the drive's stretch included (statics).
        """
        s = np.empty(np.shape(u)) if out is None else out
        if compensated and self._law is not None:
            s[..., TENDON_SERVOS] = self._law.reference_angles(u[..., TENDON_SERVOS])
            np.multiply(u[..., CMC_SERVO], self._cmc_gain, out=s[..., CMC_SERVO])
            return s
        coefficients = self._cosine if radius is None else None
        cf.reference_angle(u[..., TENDON_SERVOS], self._d1, self._d2, self._alpha,
                           self.servo_radius if radius is None else radius,
                           out=s[..., TENDON_SERVOS], coefficients=coefficients)
        np.multiply(u[..., CMC_SERVO], self._cmc_gain, out=s[..., CMC_SERVO])
        return s

    def servo_angles(self, s: np.ndarray, radius: np.ndarray | None = None, compensated: bool = False) -> np.ndarray:
        """Inverse of :meth:`reference_angles` (``radius``: effective servo pulley radii)."""
        u = np.empty(np.shape(s))
        if compensated and self._law is not None:
            u[..., TENDON_SERVOS] = self._law.servo_angles(s[..., TENDON_SERVOS])
            np.divide(s[..., CMC_SERVO], self._cmc_gain, out=u[..., CMC_SERVO])
            return u
        u[..., TENDON_SERVOS] = cf.servo_angle(s[..., TENDON_SERVOS], self._d1, self._d2, self._alpha,
                                               self.servo_radius if radius is None else radius, self._chord)
        np.divide(s[..., CMC_SERVO], self._cmc_gain, out=u[..., CMC_SERVO])
        return u

    # -- the control law's core ---------------------------------------------------
    def control_law(self, q: np.ndarray, coupling: np.ndarray, s_range=None, radius=None,
                    projection: np.ndarray | None = None) -> np.ndarray:
        """u (..., 6) for joint targets q (..., 15) already clipped to the workspace: project each
        digit's target onto its curve q = c s (``coupling`` P, (6, 15)), clip s to ``s_range``
        (default: the travel's image), invert the cosine law (``radius``: effective servo pulley
        radii), clip to the servo travel. :meth:`inverse` and the effect stack both call it."""
        s = q @ (_projection(coupling) if projection is None else projection)
        lo, hi = (self.s_min, self.s_max) if s_range is None else s_range
        _clip(s, lo, hi, out=s)
        u = self.servo_angles(s, radius)
        return _clip(u, self.u_min, self.u_max, out=u)

    # -- public API ------------------------------------------------------------
    def forward(self, u, compensated: bool = False) -> np.ndarray:
        """Joint angles q (..., 15) for servo angles u (..., 6), radians."""
        u = _as_batch(u, N_SERVOS, "u")
        if self.effects:  # fitted effects (phantom_cad.calibration.effects.EffectStack)
            return self.effects.forward(self, u, compensated)
        if compensated and self.statics is not None:
            return self._forward_routed(u)
        P = self.coupling(compensated)
        flat = u.reshape(-1, N_SERVOS)
        n = flat.shape[0]
        if n <= _BLOCK:
            return self.reference_angles(u) @ P
        # a large batch runs in blocks, transposed to (servo, pose): each ufunc then runs along
        # a contiguous row of a block whose temporaries stay in the CPU cache, so the passes
        # around the arccos cost little next to it (docs/performance.md)
        q = np.empty((n, N_JOINTS))
        s = np.empty((N_SERVOS, _BLOCK))
        work = np.empty((len(CHAINS), _BLOCK))
        for i in range(0, n, _BLOCK):
            j = min(i + _BLOCK, n)
            uT, sT = flat[i:j].T, s[:, :j - i]
            cf.reference_angle(uT[TENDON_SERVOS], self._d1, self._d2, self._alpha_column, self.servo_radius,
                               out=sT[TENDON_SERVOS], coefficients=self._cosine_columns, work=work[:, :j - i])
            np.multiply(uT[CMC_SERVO], self._cmc_gain, out=sT[CMC_SERVO])
            np.matmul(sT.T, P, out=q[i:j])
        return q.reshape(u.shape[:-1] + (N_JOINTS,))

    def _forward_routed(self, u: np.ndarray) -> np.ndarray:
        flat = u.reshape(-1, N_SERVOS)
        n = flat.shape[0]
        if n <= _BLOCK:
            return self._couple_routed(self.reference_angles(u, compensated=True))
        # blocks, chain-major as the analytic forward: the Newton steps' temporaries stay in the CPU cache
        q = np.empty((n, N_JOINTS))
        s = np.empty((N_SERVOS, _BLOCK))
        work = np.empty((8, len(CHAINS), _BLOCK))
        for i in range(0, n, _BLOCK):
            j = min(i + _BLOCK, n)
            uT, sT = flat[i:j].T, s[:, :j - i]
            self._law.reference_angles(uT[TENDON_SERVOS], columns=True, out=sT[TENDON_SERVOS],
                                       work=work[:, :, :j - i])
            np.multiply(uT[CMC_SERVO], self._cmc_gain, out=sT[CMC_SERVO])
            if self._linear:
                np.matmul(sT.T, self.coupling_compensated, out=q[i:j])
            else:
                q[i:j] = self._couple_routed(sT.T)
        return q.reshape(u.shape[:-1] + (N_JOINTS,))

    def inverse(self, q_d, compensated: bool = True) -> np.ndarray:
        """Control law (eq. 15): servo angles u* (..., 6) for target joint angles q_d (..., 15).

        Targets are clipped to the workspace [q_min, q_max], projected onto each digit's
        reachable curve, and the result respects the servo travel [u_min, u_max].
        """
        q = _clip(_as_batch(q_d, N_JOINTS, "q_d"), self.q_min, self.q_max)
        if self.effects:  # the control law with the fitted effects inverted (docs/effects.md)
            return self.effects.inverse(self, q, compensated)
        if not (compensated and self.statics is not None):
            return self.control_law(q, self.coupling(compensated), projection=self._project[compensated])
        lo, hi = self._s_range[True]
        s = q @ self._project[True] if self._linear else project_routed(self.statics, q, lo, hi)
        _clip(s, lo, hi, out=s)
        u = self.servo_angles(s, compensated=True)
        return _clip(u, self.u_min, self.u_max, out=u)

    def jacobian(self, u, compensated: bool = False) -> np.ndarray:
        """dq/du (..., 15, 6) of the model without effects."""
        u = _as_batch(u, N_SERVOS, "u")
        if compensated and self.statics is not None:
            J = np.zeros(u.shape[:-1] + (N_JOINTS, N_SERVOS))
            for spec, chain, c in zip(CHAINS, self.params.chains, self.statics):
                s, rate = st.reference_angle(u[..., spec.servo], chain, c, rate=True)
                J[..., list(spec.q_index), spec.servo] = np.asarray(rate)[..., None] * c.c[c.regime(s)]
            J[..., CMC_Q, CMC_SERVO] = self._cmc_gain
            return J
        rate = np.empty(u.shape)
        rate[..., TENDON_SERVOS] = cf.reference_angle_rate(u[..., TENDON_SERVOS], self._d1, self._d2,
                                                           self._alpha, self.servo_radius)
        rate[..., CMC_SERVO] = self._cmc_gain
        return np.swapaxes(rate[..., :, None] * self.coupling(compensated), -1, -2)

    def H(self, u) -> np.ndarray:
        """Eq. (10): the 15 x 6 function-type mapping matrix, q_ideal = H(u) u.

        H_ij(u_j) = q_i(u_j) / u_j; at u_j = 0 its limit, the slope dq_i/du_j.
        """
        u = _as_batch(u, N_SERVOS, "u")
        s = self.reference_angles(u)
        small = np.abs(u) < 1e-9
        ratio = np.divide(s, u, out=np.zeros_like(s), where=~small)
        if np.any(small):
            slope = np.empty(u.shape)
            slope[..., TENDON_SERVOS] = cf.reference_angle_rate(np.zeros_like(u[..., TENDON_SERVOS]), self._d1,
                                                                self._d2, self._alpha, self.servo_radius)
            slope[..., CMC_SERVO] = self._cmc_gain
            ratio = np.where(small, slope, ratio)
        return np.swapaxes(ratio[..., :, None] * self.coupling_ideal, -1, -2)

    def bias(self, q) -> np.ndarray:
        """Eq. (11)-(12): b(q) = q_ideal - q_comp for actual joint angles q (..., 15).

        Zero for MCP, thumb MP and CMC; for the others T v_j / EA (closed_form.elastic_lever),
        with T = k_s * sum_i R_i q_i over the joint's own tendon chain.
        """
        q = _as_batch(q, N_JOINTS, "q")
        b = np.zeros(q.shape)
        EA = self.params.mechanics.tendon_EA
        for chain in self.params.chains:
            idx = list(chain.spec.q_index)
            T = self.params.mechanics.spring_k * (q[..., idx] @ np.asarray(chain.radii))
            b[..., idx] = T[..., None] * cf.elastic_lever(chain.radii, chain.path_lengths) / EA
        return b

    # -- workspace -------------------------------------------------------------
    def workspace(self, compensated: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Per-joint image [low, high] (15,) of the whole servo travel."""
        q_lo = self.forward(self.u_min, compensated)
        q_hi = self.forward(self.u_max, compensated)
        return np.minimum(q_lo, q_hi), np.maximum(q_lo, q_hi)


def couple_routed(statics, s: np.ndarray) -> np.ndarray:
    """q (..., 15) of routed statics (one :class:`~.statics.ChainStatics` per tendon chain, servo
    order) at reference angles s (..., 6), each chain in its regime; the CMC's q15 = s6."""
    q = np.empty(s.shape[:-1] + (N_JOINTS,))
    if all(c.linear for c in statics):
        # one regime each, q = c s: every chain's joints in one product (ChainStatics.joints' arithmetic)
        q[..., _CHAIN_JOINTS] = s[..., _JOINT_SERVO] * np.concatenate([c.c[-1] for c in statics])
    else:
        for spec, c in zip(CHAINS, statics):
            q[..., list(spec.q_index)] = c.joints(s[..., spec.servo])
    q[..., CMC_Q] = s[..., CMC_SERVO]
    return q


def project_routed(statics, q: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """s (..., 6): each digit's target q (..., 15) projected onto its piecewise affine routed curve
    (``statics`` as for :func:`couple_routed`; the nearest point over its regimes' segments within
    [lo, hi], (6,))."""
    s = np.empty(q.shape[:-1] + (N_SERVOS,))
    for spec, c in zip(CHAINS, statics):
        x = q[..., list(spec.q_index)]
        bounds = np.append(c.s_from, np.inf)
        best = np.full(q.shape[:-1], np.inf)
        for m in range(len(c.s_from)):
            a, b = max(bounds[m], lo[spec.servo]), min(bounds[m + 1], hi[spec.servo])
            if a > b:
                continue
            t = np.clip((x - c.d[m]) @ c.c[m] / (c.c[m] @ c.c[m]), a, b)
            err = np.sum((x - t[..., None] * c.c[m] - c.d[m]) ** 2, axis=-1)
            better = err < best
            best = np.where(better, err, best)
            s[..., spec.servo] = np.where(better, t, s[..., spec.servo])
    s[..., CMC_SERVO] = q[..., CMC_Q]
    return s


def _projection(P: np.ndarray) -> np.ndarray:
    """(15, 6): least-squares projection onto each digit's curve, s_k = c_k . q / (c_k . c_k)."""
    return (P / np.sum(P ** 2, axis=1, keepdims=True)).T.copy()


def _clip(x, lo, hi, out=None):
    """np.clip(x, lo, hi, out=out) (NaN stays NaN), at half its cost on one pose."""
    return np.minimum(np.maximum(x, lo, out=out), hi, out=out)


def _as_batch(x, n: int, name: str) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.ndim == 0 or x.shape[-1] != n:
        raise ValueError(f"{name} must have shape (..., {n}), got {x.shape}")
    return x
