"""Joint angles from a camera or encoders merged into a sweep by time (``phantom-cad drive merge``)."""

from __future__ import annotations

import numpy as np

from ..kinematics.topology import N_JOINTS, Q_COLUMNS
from .protocol import DriveError


def merge_by_time(sweep, table) -> tuple[np.ndarray, list[str]]:
    """(q, columns): ``sweep``'s (Measurements) rows with each q column of ``table`` (a Table with
    ``t``) linearly interpolated at the sweep's times, between the two readings around each one;
    a time outside the readings' span (or next to an empty reading) stays empty (NaN)."""
    t = np.asarray(table.values["t"], float)
    if np.any(np.diff(t) <= 0):
        raise DriveError(f"{table.path}: the times t must increase from row to row")
    q = np.full((len(sweep), N_JOINTS), np.nan)
    columns = [c for c in Q_COLUMNS if c in table.values]
    if not columns:
        raise DriveError(f"{table.path}: no joint-angle column (q1..q15) to merge")
    for c in columns:
        i = Q_COLUMNS.index(c)
        v = np.asarray(table.values[c], float)
        k = np.searchsorted(t, sweep.t, side="right")      # t[k-1] <= time < t[k]
        inside = (k > 0) & (k < len(t)) | (sweep.t == t[-1])
        k = np.clip(k, 1, len(t) - 1)
        w = (sweep.t - t[k - 1]) / (t[k] - t[k - 1])
        q[:, i] = np.where(inside, v[k - 1] + w * (v[k] - v[k - 1]), np.nan)
    return q, columns
