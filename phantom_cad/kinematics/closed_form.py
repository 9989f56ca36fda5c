"""Closed-form pieces of the paper's model (eq. 4-6, 8, 11-14), as plain functions: the one
implementation of each formula.

Numbers in, numbers out: no parameter objects, so the schema's validation, the model and the
effect library share exactly these. numpy only; everything broadcasts.
"""

from __future__ import annotations

import numpy as np


def chord_rest(d1, d2, alpha):
    """Eq. (4): L0 = sqrt(d1^2 + d2^2 - 2 d1 d2 cos(alpha))."""
    return np.sqrt(d1 * d1 + d2 * d2 - 2.0 * d1 * d2 * np.cos(alpha))


def cosine_coefficients(d1, d2, alpha, r):
    """The cosine law's argument as a polynomial in the servo angle u (eq. 5-6):

    x(u) = (d1^2 + d2^2 - (L0 - r u)^2) / (2 d1 d2) = a + u (b + c u),
    a = cos(alpha), b = L0 r / (d1 d2), c = -r^2 / (2 d1 d2).
    """
    two_d1d2 = 2.0 * d1 * d2
    return np.cos(alpha), 2.0 * chord_rest(d1, d2, alpha) * r / two_d1d2, -(r * r) / two_d1d2


def cosine_argument(u, d1, d2, alpha, r):
    """Argument of the arccos in eq. (5)/(6) at servo angle u."""
    a, b, c = cosine_coefficients(d1, d2, alpha, r)
    return a + u * (b + c * u)


def reference_angle(u, d1, d2, alpha, r, out=None, coefficients=None, work=None):
    """Eq. (6)/(8): q_MCP (or thumb q_MP) = alpha - arccos((d1^2 + d2^2 - (L0 - r u)^2) / (2 d1 d2)).

    Beyond the law's domain (a servo angle far outside its travel) the argument is clipped to
    [-1, 1]: the chord cannot shorten past |d1 - d2|, the joint stops folded at alpha.
    ``out`` receives the result (it may be a strided view); ``coefficients`` may be passed in
    precomputed (:func:`cosine_coefficients`). The work runs in place on one C-contiguous
    array (``work``, or a new one), the fast layout for numpy's loops.
    """
    a, b, c = cosine_coefficients(d1, d2, alpha, r) if coefficients is None else coefficients
    x = np.empty(np.broadcast(u, c).shape) if work is None else work
    np.multiply(u, c, out=x)
    x += b
    x *= u
    x += a
    np.clip(x, -1.0, 1.0, out=x)
    np.arccos(x, out=x)
    np.subtract(alpha, x, out=x if out is None else out)
    return (x if out is None else out)[()]


def chord_constants(d1, d2, alpha):
    """(d1^2 + d2^2, 2 d1 d2, L0): what the inverse cosine law needs, for precomputing."""
    return d1 * d1 + d2 * d2, 2.0 * d1 * d2, chord_rest(d1, d2, alpha)


def servo_angle(q_ref, d1, d2, alpha, r, constants=None):
    """Inverse of eq. (6): the servo angle that puts the reference joint at q_ref,
    u = (L0 - L) / r with L = sqrt(d1^2 + d2^2 - 2 d1 d2 cos(alpha - q_ref)).
    ``constants`` may be passed in precomputed (:func:`chord_constants`)."""
    sumsq, two_d1d2, L0 = chord_constants(d1, d2, alpha) if constants is None else constants
    L = np.sqrt(sumsq - two_d1d2 * np.cos(alpha - q_ref))
    return (L0 - L) / r


def stretched_servo_angle(q_ref, alpha, r, stretch, constants):
    """The servo angle that puts the reference joint at q_ref when the drive stretches:
    u = (L0 - L + stretch L / sin(alpha - q_ref)) / r, ``stretch`` the drive's stretch per unit
    of L / sin(alpha - q_ref) (its tension over its moment arm d1 d2 sin / L, times L_d / EA;
    kinematics.statics). ``constants``: :func:`chord_constants`."""
    sumsq, two_d1d2, L0 = constants
    phi = alpha - q_ref
    L = np.sqrt(sumsq - two_d1d2 * np.cos(phi))
    return (L0 - L + stretch * L / np.sin(phi)) / r


def drive_moment_arm(q_ref, d1, d2, alpha):
    """The drive chord's moment arm about the reference joint at q_ref: d1 d2 sin(alpha - q_ref) / L,
    L the chord (eq. 5): the rate at which the chord shortens as the joint flexes, -dL/dq_ref."""
    phi = alpha - q_ref
    return d1 * d2 * np.sin(phi) / np.sqrt(d1 * d1 + d2 * d2 - 2.0 * d1 * d2 * np.cos(phi))


def return_tension(spring_k, radii, q):
    """Eq. (11): the return cord's tension T = k_s sum_i R_i q_i over one chain's joints (q (..., n))."""
    return spring_k * (np.asarray(q, dtype=float) @ np.asarray(radii, dtype=float))


def reference_angle_rate(u, d1, d2, alpha, r):
    """d q_ref / d u = r L / (d1 d2 sin(phi)), phi the current included angle."""
    L = chord_rest(d1, d2, alpha) - r * u
    x = cosine_argument(u, d1, d2, alpha, r)
    return r * L / (d1 * d2 * np.sqrt(1.0 - x * x))


def ideal_coupling(radii):
    """Eq. (2): R_ref q_ref = R_i q_i  ->  q_i = (R_ref / R_i) q_ref. ``radii[0]`` is the reference joint."""
    radii = np.asarray(radii, dtype=float)
    return radii[0] / radii


def elastic_lever(radii, path_lengths):
    """Eq. (12) per unit tension and unit EA: v_j = (tendon path from the reference joint to joint j) / R_j.

    ``radii`` reference joint first; ``path_lengths[k]`` the tendon between joints k and k + 1.
    A tension T stretches the tendon so that joint j loses b_j = T v_j / EA (v_0 = 0).
    """
    radii = np.asarray(radii, dtype=float)
    return np.concatenate(([0.0], np.cumsum(path_lengths))) / radii


def coupling_constants(radii, path_lengths):
    """(A, v, R.A, R.v) of one chain: what :func:`coupling_vector` needs, for precomputing."""
    radii = np.asarray(radii, dtype=float)
    A = ideal_coupling(radii)
    v = elastic_lever(radii, path_lengths)
    return A, v, float(radii @ A), float(radii @ v)


def coupling_vector(radii, path_lengths, compliance, constants=None):
    """Eq. (13)/(14) in closed form: q_comp = (M^-1 A) q_ref for a compliance kappa = k_s / EA.

    M = I + kappa v R^T (v the :func:`elastic_lever`, since T = k_s R.q), so by Sherman-Morrison
    M^-1 A = A - v kappa (R.A) / (1 + kappa R.v). ``compliance`` broadcasts: a scalar gives (n,),
    an array (...,) gives (..., n). kappa = 0 is the analytic model (A itself). ``constants``
    may be passed in precomputed (:func:`coupling_constants`).
    """
    A, v, RA, Rv = coupling_constants(radii, path_lengths) if constants is None else constants
    kappa = np.asarray(compliance, dtype=float)[..., None]
    return A - (kappa * RA / (1.0 + kappa * Rv)) * v
