"""Synthetic measurements from a hand with hidden effects (``phantom-cad simulate``).

Every servo is swept over its travel, flexing then extending, the others held at 0 (one sweep
per servo, id ``u1``..``u6``). The truth is the analytic model plus the hidden effects; when
``tendon_elasticity`` is hidden the truth is the paper's compensated model with the hidden
compliance k_s / EA (with ``routed_elasticity``, the routed statics at the hidden scale). Each hidden parameter is drawn uniformly from its effect's ``typical`` range
(a random sign for signed ones) unless given explicitly; noise is Gaussian per measured cell.
Two independent random streams (effects, noise) come from the seed: same seed, same file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..kinematics.topology import N_JOINTS, N_SERVOS, Q_COLUMNS, U_COLUMNS, servo_joints
from ..units import DEG
from .data import Measurements
from .framework import REGISTRY, History, get_effect
from .pipeline import effect_values, run_pipeline


#: most samples per direction per servo: 12 x 100,000 rows of 21 columns is about 0.2 GB in memory
MAX_POINTS = 100_000


class SimulationError(ValueError):
    pass


@dataclass
class Simulation:
    measurements: Measurements
    hidden: dict[str, dict[str, float]]   # {effect: {key: value}} in file units
    clean: np.ndarray                      # noise-free q (N, 15), NaN where not measured
    noise: np.ndarray                      # the noise added, radians (NaN where not measured)

    @property
    def noise_mae_deg(self) -> float:
        """The noise floor: the MAE of the noise alone, degrees."""
        return float(np.nanmean(np.abs(self.noise)) / DEG)


def draw_hidden(hand, effects, seed: int, explicit: dict | None = None) -> dict[str, dict[str, float]]:
    """Hidden magnitudes per effect. An effect with explicit values takes them (its other
    parameters are 0); otherwise every parameter is drawn from its typical range."""
    explicit = explicit or {}
    for name in explicit:
        if name not in effects:
            raise SimulationError(f"--effect-param {name}.*: effect '{name}' is not in --effects")
    rng = np.random.default_rng([seed, 1])
    hidden = {}
    for name in REGISTRY:                       # fixed order: same seed, same draws
        eff = REGISTRY[name]
        plist = eff.parameters(hand)
        lo = np.array([p.typical[0] for p in plist])
        hi = np.array([p.typical[1] for p in plist])
        mag = rng.uniform(lo, hi)
        sign = np.where(rng.random(len(plist)) < 0.5, -1.0, 1.0)
        if name not in effects:
            continue
        if name in explicit:
            x = effect_values(name, explicit[name], hand, "--effect-param")
        else:
            x = np.where([p.signed for p in plist], sign * mag, mag)
        hidden[name] = {p.key: float(v) for p, v in zip(plist, x) if v != 0.0}
    return hidden


def sweep_commands(hand, points: int, travel: float = 1.0):
    """u (N, 6) and sweep labels: each servo flexes over ``points`` steps and returns over ``points``."""
    if not 2 <= points <= MAX_POINTS:
        raise SimulationError(f"--points {points}: must be in [2, {MAX_POINTS}] (the file has about "
                              f"{2 * N_SERVOS} x points rows)")
    if not 0.0 < travel <= 1.0:
        raise SimulationError(f"--travel {travel}: must be in (0, 1]")
    us, labels = [], []
    for j in range(N_SERVOS):
        lo = hand.u_min[j]
        hi = lo + travel * (hand.u_max[j] - lo)
        path = np.concatenate([np.linspace(lo, hi, points), np.linspace(hi, lo, points + 1)[1:]])
        u = np.zeros((path.size, N_SERVOS))
        u[:, j] = path
        us.append(u)
        labels += [U_COLUMNS[j]] * path.size
    return np.vstack(us), labels


def simulate(hand, effects=(), *, noise_deg: float = 0.1, seed: int = 0, points: int = 50,
             explicit: dict | None = None, travel: float = 1.0, measure: str = "chain",
             joints=None) -> Simulation:
    """Measurements a hand with ``effects`` hidden would give.

    ``measure``: "chain" records, in each sweep, the joints of the swept servo only (other cells
    empty, as a camera following one finger would); "all" records every joint on every row.
    ``joints``: the q columns to write at all (default: all 15).
    """
    for name in effects:
        get_effect(name, "--effects")
    if not (math.isfinite(noise_deg) and noise_deg >= 0):
        raise SimulationError(f"--noise-deg {noise_deg}: must be a finite number >= 0")
    if seed < 0:
        raise SimulationError(f"--seed {seed}: must be >= 0")
    if measure not in ("chain", "all"):
        raise SimulationError(f"--measure {measure}: must be 'chain' or 'all'")
    cols = list(Q_COLUMNS) if joints is None else list(joints)
    for c in cols:
        if c not in Q_COLUMNS:
            raise SimulationError(f"--joints: unknown column '{c}' (allowed: q1..q15)")
    hidden = draw_hidden(hand, effects, seed, explicit)
    u, labels = sweep_commands(hand, points, travel)
    ids = tuple(dict.fromkeys(labels))
    sweep = np.array([ids.index(s) for s in labels])
    measured = np.array([c in cols for c in Q_COLUMNS])
    m0 = Measurements(u, np.zeros((len(u), N_JOINTS)), measured, sweep, ids, None,
                      np.arange(len(u)) + 2, "<simulate>", True)
    items = [(get_effect(n), effect_values(n, hidden[n], hand)) for n in REGISTRY if n in hidden]
    clean = run_pipeline(hand, items, u, m0.direction, 0.0, History.of(m0))
    mask = np.zeros(clean.shape, dtype=bool)
    mask[:, measured] = True
    if measure == "chain":
        own = np.zeros(clean.shape, dtype=bool)
        for j in range(N_SERVOS):
            rows = sweep == ids.index(U_COLUMNS[j])
            own[np.ix_(rows, list(servo_joints(j)))] = True
        mask &= own
    rng = np.random.default_rng([seed, 2])
    noise = rng.normal(0.0, noise_deg * DEG, clean.shape)
    noise[~mask] = np.nan
    clean = np.where(mask, clean, np.nan)
    q = clean + noise
    m = Measurements(u, q, measured, sweep, ids, None, m0.lines, "<simulate>", True)
    return Simulation(m, hidden, clean, noise)


def parse_effect_params(items) -> dict[str, dict[str, float]]:
    """``["friction_hysteresis.mu=0.1", ...]`` -> {"friction_hysteresis": {"mu": 0.1}}."""
    out: dict[str, dict[str, float]] = {}
    for item in items or ():
        name_key, sep, value = item.partition("=")
        name, dot, key = name_key.strip().partition(".")
        if not sep or not dot or not key:
            raise SimulationError(f"--effect-param '{item}': expected EFFECT.PARAM=VALUE, e.g. friction_hysteresis.mu=0.1")
        try:
            v = float(value)
        except ValueError:
            raise SimulationError(f"--effect-param '{item}': '{value}' is not a number") from None
        out.setdefault(name, {})[key] = v
    return out


__all__ = ["simulate", "Simulation", "draw_hidden", "sweep_commands", "parse_effect_params",
           "SimulationError"]
