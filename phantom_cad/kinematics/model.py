"""The paper's kinematic model: servo angles u (6) <-> joint angles q (15).

Forward, analytic (eq. 2-10):    q = H(u) u, q_ref = alpha - arccos(...), q_i = (R_ref / R_i) q_ref, q15 = g u6.
Forward, compensated (eq. 11-14): q_comp = (M^-1 A) q_ref per tendon chain.
Inverse, control law (eq. 15):    u* = H^+(clip(q_d) + b(clip(q_d))).

Every digit's reachable set is a curve q = c s(u) with a constant vector c (A or M^-1 A)
and the reference angle s = q_MCP (q_MP for the thumb). The inverse clips the target to
the workspace, projects each digit's target onto its curve by least squares
(s = c.q / c.c, which for a target on the curve is exactly eq. 15), clips s to the
servo travel's image, and inverts the cosine law in closed form.

All functions broadcast over any leading batch shape. numpy only.
"""

from __future__ import annotations

import numpy as np

from ..params.schema import HandParams
from . import closed_form as cf
from .topology import CHAINS, CMC_Q, CMC_SERVO, N_JOINTS, N_SERVOS


class Hand:
    """The kinematic model of one hand, built from its validated parameters."""

    def __init__(self, params: HandParams):
        self.params = params
        chains = params.chains
        thumb = params.thumb
        g = [c.guide for c in chains]
        self._d1 = np.array([x.d1 for x in g])
        self._d2 = np.array([x.d2 for x in g])
        self._alpha = np.array([x.alpha for x in g])
        self._r = np.array([c.servo_radius for c in chains])
        self._L0 = cf.chord_rest(self._d1, self._d2, self._alpha)
        self._sumsq = self._d1 ** 2 + self._d2 ** 2
        self._two_d1d2 = 2.0 * self._d1 * self._d2
        self._cmc_gain = thumb.cmc_gain

        k_s, EA = params.mechanics.spring_k, params.mechanics.tendon_EA
        #: (6, 15) maps the per-servo reference angles s to q: q = s @ P
        self.coupling_ideal = self._coupling([c.ideal_coupling for c in chains])
        self.coupling_compensated = self._coupling(
            [cf.compensated_coupling(c.radii, c.path_lengths, k_s, EA) for c in chains])
        # least-squares projection onto each digit's curve: s_k = c_k . q / (c_k . c_k)
        self._project = {
            False: (self.coupling_ideal / np.sum(self.coupling_ideal ** 2, axis=1, keepdims=True)).T.copy(),
            True: (self.coupling_compensated / np.sum(self.coupling_compensated ** 2, axis=1, keepdims=True)).T.copy(),
        }

        q_min = np.zeros(N_JOINTS)
        q_max = np.zeros(N_JOINTS)
        for spec, chain in zip(CHAINS, chains):
            for qi, (lo, hi) in zip(spec.q_index, chain.limits):
                q_min[qi], q_max[qi] = lo, hi
        q_min[CMC_Q], q_max[CMC_Q] = thumb.cmc_limits
        self.q_min, self.q_max = q_min, q_max

        u_min = np.array([c.travel[0] for c in chains] + [thumb.cmc_travel[0]])
        u_max = np.array([c.travel[1] for c in chains] + [thumb.cmc_travel[1]])
        self.u_min, self.u_max = u_min, u_max
        # image of the servo travel in reference-angle space
        self._s_min = self._reference(u_min)
        self._s_max = self._reference(u_max)

        # the effects of phantom_cad.calibration this hand was fitted with (if any)
        from .effects_hook import resolve_effects

        self.effects = resolve_effects(params)

    @staticmethod
    def _coupling(vectors) -> np.ndarray:
        P = np.zeros((N_SERVOS, N_JOINTS))
        for spec, c in zip(CHAINS, vectors):
            P[spec.servo, list(spec.q_index)] = c
        P[CMC_SERVO, CMC_Q] = 1.0
        return P

    # -- reference angles ----------------------------------------------------
    def _reference(self, u: np.ndarray, r: np.ndarray | None = None) -> np.ndarray:
        """s (..., 6): q_MCP / q_MP of each tendon chain (eq. 6, 8) and q15 = g u6 (eq. 9).

        The in-place form of closed_form.reference_angle, the one the model and the effect
        library use; ``r`` overrides the servo pulley radii (an effective radius). Beyond the
        cosine law's domain (a servo angle far outside its travel) the argument is clipped to
        [-1, 1]: the chord cannot shorten past |d1 - d2|, the joint stops folded at alpha.
        """
        s = np.empty(u.shape)
        L = self._L0 - (self._r if r is None else r) * u[..., :5]
        np.multiply(L, L, out=L)
        np.subtract(self._sumsq, L, out=L)
        np.divide(L, self._two_d1d2, out=L)
        np.clip(L, -1.0, 1.0, out=L)
        np.arccos(L, out=L)
        np.subtract(self._alpha, L, out=s[..., :5])
        np.multiply(u[..., 5], self._cmc_gain, out=s[..., 5])
        return s

    def _servo(self, s: np.ndarray, r: np.ndarray | None = None) -> np.ndarray:
        """Inverse of :meth:`_reference` (``r``: effective servo pulley radii)."""
        u = np.empty(s.shape)
        u[..., :5] = cf.servo_angle(s[..., :5], self._d1, self._d2, self._alpha,
                                    self._r if r is None else r, self._L0)
        np.divide(s[..., 5], self._cmc_gain, out=u[..., 5])
        return u

    def coupling(self, compensated: bool) -> np.ndarray:
        return self.coupling_compensated if compensated else self.coupling_ideal

    # -- public API ------------------------------------------------------------
    def forward(self, u, compensated: bool = False) -> np.ndarray:
        """Joint angles q (..., 15) for servo angles u (..., 6), radians."""
        u = _as_batch(u, N_SERVOS, "u")
        if self.effects:  # fitted effects (phantom_cad.calibration.effects.EffectStack)
            return self.effects.forward(self, u, compensated)
        return self._reference(u) @ self.coupling(compensated)

    def inverse(self, q_d, compensated: bool = True) -> np.ndarray:
        """Control law (eq. 15): servo angles u* (..., 6) for target joint angles q_d (..., 15).

        Targets are clipped to the workspace [q_min, q_max], projected onto each digit's
        reachable curve, and the result respects the servo travel [u_min, u_max].
        """
        q = _as_batch(q_d, N_JOINTS, "q_d")
        q = np.clip(q, self.q_min, self.q_max)
        if self.effects:  # the control law with the fitted effects inverted (docs/effects.md)
            return self.effects.inverse(self, q, compensated)
        s = q @ self._project[compensated]
        np.clip(s, self._s_min, self._s_max, out=s)
        u = self._servo(s)
        return np.clip(u, self.u_min, self.u_max, out=u)

    def jacobian(self, u, compensated: bool = False) -> np.ndarray:
        """dq/du (..., 15, 6) of the model without effects."""
        u = _as_batch(u, N_SERVOS, "u")
        rate = np.empty(u.shape)
        rate[..., :5] = cf.reference_angle_rate(u[..., :5], self._d1, self._d2, self._alpha, self._r)
        rate[..., 5] = self._cmc_gain
        return np.swapaxes(rate[..., :, None] * self.coupling(compensated), -1, -2)

    def H(self, u) -> np.ndarray:
        """Eq. (10): the 15 x 6 function-type mapping matrix, q_ideal = H(u) u.

        H_ij(u_j) = q_i(u_j) / u_j; at u_j = 0 its limit, the slope dq_i/du_j.
        """
        u = _as_batch(u, N_SERVOS, "u")
        s = self._reference(u)
        small = np.abs(u) < 1e-9
        ratio = np.divide(s, u, out=np.zeros_like(s), where=~small)
        if np.any(small):
            slope = np.empty(u.shape)
            slope[..., :5] = cf.reference_angle_rate(np.zeros_like(u[..., :5]), self._d1, self._d2,
                                                     self._alpha, self._r)
            slope[..., 5] = self._cmc_gain
            ratio = np.where(small, slope, ratio)
        return np.swapaxes(ratio[..., :, None] * self.coupling_ideal, -1, -2)

    def bias(self, q) -> np.ndarray:
        """Eq. (11)-(12): b(q) = q_ideal - q_comp for actual joint angles q (..., 15).

        Zero for MCP, thumb MP and CMC; for the others T * (path to the joint) / (EA R_j),
        with T = k_s * sum_i R_i q_i over the joint's own tendon chain.
        """
        q = _as_batch(q, N_JOINTS, "q")
        b = np.zeros(q.shape)
        k_s, EA = self.params.mechanics.spring_k, self.params.mechanics.tendon_EA
        for spec, chain in zip(CHAINS, self.params.chains):
            idx = list(spec.q_index)
            T = k_s * (q[..., idx] @ np.asarray(chain.radii))
            cumulative = np.concatenate(([0.0], np.cumsum(chain.path_lengths)))
            b[..., idx] = T[..., None] * cumulative / (EA * np.asarray(chain.radii))
        return b

    # -- workspace -------------------------------------------------------------
    def workspace(self, compensated: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Per-joint image [low, high] (15,) of the whole servo travel."""
        q_lo = self.forward(self.u_min, compensated)
        q_hi = self.forward(self.u_max, compensated)
        return np.minimum(q_lo, q_hi), np.maximum(q_lo, q_hi)


def _as_batch(x, n: int, name: str) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.ndim == 0 or x.shape[-1] != n:
        raise ValueError(f"{name} must have shape (..., {n}), got {x.shape}")
    return x
