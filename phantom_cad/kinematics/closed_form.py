"""Closed-form pieces of the paper's model (eq. 4-6, 8, 11-14), as plain functions.

Numbers in, numbers out: no parameter objects, so the schema's validation and the
model share exactly one implementation of each formula. numpy only.
"""

from __future__ import annotations

import numpy as np


def chord_rest(d1, d2, alpha):
    """Eq. (4): L0 = sqrt(d1^2 + d2^2 - 2 d1 d2 cos(alpha))."""
    return np.sqrt(d1 * d1 + d2 * d2 - 2.0 * d1 * d2 * np.cos(alpha))


def cosine_argument(u, d1, d2, alpha, r):
    """Argument of the arccos in eq. (5)/(6) at servo angle u."""
    L = chord_rest(d1, d2, alpha) - r * u
    return (d1 * d1 + d2 * d2 - L * L) / (2.0 * d1 * d2)


def reference_angle(u, d1, d2, alpha, r):
    """Eq. (6)/(8): q_MCP (or thumb q_MP) = alpha - arccos((d1^2 + d2^2 - (L0 - r u)^2) / (2 d1 d2))."""
    return alpha - np.arccos(cosine_argument(u, d1, d2, alpha, r))


def servo_angle(q_ref, d1, d2, alpha, r, L0=None):
    """Inverse of eq. (6): the servo angle that puts the reference joint at q_ref.
    ``L0`` (eq. 4) may be passed in precomputed."""
    L = np.sqrt(d1 * d1 + d2 * d2 - 2.0 * d1 * d2 * np.cos(alpha - q_ref))
    return ((chord_rest(d1, d2, alpha) if L0 is None else L0) - L) / r


def ideal_coupling(radii):
    """Eq. (2): R_ref q_ref = R_i q_i  ->  q_i = (R_ref / R_i) q_ref. ``radii[0]`` is the reference joint."""
    radii = np.asarray(radii, dtype=float)
    return radii[0] / radii


def compliance_matrix(radii, path_lengths, k_s, EA):
    """Eq. (13)/(14): the matrix M of M q_comp = A q_ref.

    ``radii`` are the chain's pulley radii, reference joint first (MCP, PIP, DIP or MP, IP);
    ``path_lengths[k]`` the tendon length between joint k and joint k+1. Joint j > 0 loses
    b_j = T * (sum of path lengths up to j) / (EA R_j), with T = k_s * sum_i R_i q_i (eq. 11-12).
    """
    radii = np.asarray(radii, dtype=float)
    n = radii.size
    cumulative = np.concatenate(([0.0], np.cumsum(path_lengths)))
    C = k_s * cumulative / (EA * radii)   # C[0] = 0: the reference joint has no deviation
    return np.eye(n) + np.outer(C, radii)


def compensated_coupling(radii, path_lengths, k_s, EA):
    """q_comp = (M^-1 A) q_ref: the constant vector of eq. (13)/(14)."""
    return np.linalg.solve(compliance_matrix(radii, path_lengths, k_s, EA), ideal_coupling(radii))


def reference_angle_rate(u, d1, d2, alpha, r):
    """d q_ref / d u = r L / (d1 d2 sin(phi)), phi the current included angle."""
    L = chord_rest(d1, d2, alpha) - r * u
    x = (d1 * d1 + d2 * d2 - L * L) / (2.0 * d1 * d2)
    return r * L / (d1 * d2 * np.sqrt(1.0 - x * x))
