"""The measurement CSV format (docs/measurements.md).

UTF-8, a header row, one row per sample, angles in radians (``degrees=True`` converts):
``u1``..``u6`` commanded servo angles, any subset of ``q1``..``q15`` measured joint
angles (an empty cell means not measured), optional ``sweep`` (rows with the same id
form one sweep, in row order) and ``t`` (seconds). Lines starting with ``#`` are
comments. Every refusal names the line and the column.
"""

from __future__ import annotations

import codecs
import csv
import io
import itertools
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Mapping, Sequence

import numpy as np

from ..atomic import write_atomic
from ..kinematics.topology import N_JOINTS, Q_COLUMNS, U_COLUMNS
from ..units import deg, rad
from .labels import Labels

ANGLE_COLUMNS = frozenset(U_COLUMNS + Q_COLUMNS)
#: an angle beyond this in a radian file is taken for degrees
RADIAN_LIMIT = 2.0 * math.pi


#: a decimal number as CSV files write it (ASCII digits, optional sign, point, exponent; inf/nan
#: parse here and are refused as not finite below)
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?|[+-]?(inf|infinity|nan)", re.IGNORECASE | re.ASCII)


class DataError(ValueError):
    """A measurement file breaks the format; ``line`` and ``column`` say where."""

    def __init__(self, path, line: int | None, column: str | None, message: str):
        self.path, self.line, self.column = str(path), line, column
        where = str(path)
        if line is not None:
            where += f", line {line}"
        if column is not None:
            where += f", column {column}"
        super().__init__(f"{where}: {message}")


@dataclass(frozen=True)
class Table:
    """A parsed CSV: float columns (NaN = empty cell) and the file line of every row."""

    path: str
    columns: tuple[str, ...]
    values: Mapping[str, np.ndarray]
    text: Mapping[str, tuple[str, ...]]
    lines: np.ndarray

    def __len__(self) -> int:
        return len(self.lines)


def read_table(path, *, required: Sequence[str], optional: Sequence[str] = (),
               text_columns: Sequence[str] = (), degrees: bool = False,
               allow_empty: Sequence[str] = ()) -> Table:
    """Read a CSV strictly.

    ``required`` columns must be present; ``optional`` may be; any other column is refused.
    Number cells must parse as finite floats; empty cells are allowed only in ``allow_empty``
    columns (as NaN). Angle columns (u*, q*) are converted from degrees when ``degrees``;
    in radians, a magnitude above 2 pi is refused as "looks like degrees".
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise DataError(path, None, None, "no such file") from None
    except IsADirectoryError:
        raise DataError(path, None, None, "is a folder, not a CSV file") from None
    except OSError as exc:
        raise DataError(path, None, None, f"cannot be read ({exc.strerror})") from None
    if data.startswith(codecs.BOM_UTF8):     # a byte-order mark is not part of the header
        data = data[len(codecs.BOM_UTF8):]
    if data.isascii():
        fast = _read_fast(path, data, required, optional, text_columns, degrees, allow_empty)
        if fast is not None:
            return fast
    try:
        raw = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DataError(path, None, None, f"is not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    del data
    rows: list[tuple[int, list[str]]] = []
    for lineno, line in enumerate(raw.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        rows.append((lineno, line))
    if not rows:
        raise DataError(path, None, None, "is empty: expected a header row and at least one data row")
    parsed = list(csv.reader([line for _, line in rows]))
    header_line = rows[0][0]
    header = [h.strip() for h in parsed[0]]
    allowed = list(required) + list(optional) + list(text_columns)
    seen: set[str] = set()
    for name in header:
        if name in seen:
            raise DataError(path, header_line, name, "duplicate column")
        if name not in allowed:
            raise DataError(path, header_line, name or "<empty>",
                            f"unknown column (allowed: {', '.join(allowed)})")
        seen.add(name)
    for name in required:
        if name not in seen:
            raise DataError(path, header_line, name, "required column is missing")
    if len(rows) < 2:
        raise DataError(path, None, None, "has a header but no data rows")

    n = len(rows) - 1
    values = {c: np.empty(n) for c in header if c not in text_columns}
    text = {c: [] for c in header if c in text_columns}
    lines = np.empty(n, dtype=int)
    for k, ((lineno, _), cells) in enumerate(zip(rows[1:], parsed[1:])):
        lines[k] = lineno
        if len(cells) != len(header):
            raise DataError(path, lineno, None, f"has {len(cells)} cells, the header has {len(header)}")
        for name, cell in zip(header, cells):
            cell = cell.strip()
            if name in text:
                if not cell:
                    raise DataError(path, lineno, name, "empty cell")
                text[name].append(cell)
                continue
            if cell == "":
                if name not in allow_empty:
                    raise DataError(path, lineno, name, "empty cell (this column is required on every row)")
                values[name][k] = np.nan
                continue
            if not _NUMBER.fullmatch(cell.strip()):   # float() also takes '0.0_1' and non-ASCII digits
                raise DataError(path, lineno, name, f"'{cell}' is not a number")
            v = float(cell)
            if not math.isfinite(v):
                raise DataError(path, lineno, name, f"'{cell}' is not a finite number")
            if name in ANGLE_COLUMNS:
                if degrees:
                    v = rad(v)
                elif abs(v) > RADIAN_LIMIT:
                    raise DataError(path, lineno, name,
                                    f"{v:g} looks like degrees (angles are radians, |angle| <= 2 pi); "
                                    "convert it or pass --degrees")
            values[name][k] = v
    return Table(str(path), tuple(header), values, {c: tuple(v) for c, v in text.items()}, lines)


def _read_fast(path, raw: bytes, required, optional, text_columns, degrees: bool, allow_empty) -> Table | None:
    """The table of a plain grid file (ASCII bytes), read column-wise (fastcsv), when every rule
    of the exact reader below is seen to hold; None otherwise, and the exact reader reads the file
    (and names the line and column of what is wrong)."""
    from . import fastcsv

    pos, lineno = 0, 1
    while True:   # skip the comment and blank lines before the header
        end = raw.find(b"\n", pos)
        line = raw[pos:] if end < 0 else raw[pos:end]
        if line.strip() and not line.lstrip().startswith(b"#"):
            break
        if end < 0:
            return None
        pos, lineno = end + 1, lineno + 1
    if end < 0 or b"\r" in line or b'"' in line:
        return None
    header = [h.strip() for h in line.decode("ascii").split(",")]
    allowed = set(required) | set(optional) | set(text_columns)
    if len(set(header)) != len(header) or not set(header) <= allowed or not set(required) <= set(header):
        return None
    got = fastcsv.parse_grid(raw, header, text_columns, allow_empty, start=end + 1)
    if got is None:
        return None
    values, text = got
    n = len(next(iter(values.values()))) if values else len(next(iter(text.values())))
    for name, v in values.items():
        cells = v[~np.isnan(v)] if name in allow_empty else v
        if not np.isfinite(cells).all():
            return None
        if name in ANGLE_COLUMNS:
            if degrees:
                values[name] = rad(v)
            elif (np.abs(cells) > RADIAN_LIMIT).any():
                return None
    order = {c: values[c] for c in header if c in values}
    return Table(str(path), tuple(header), order, text, np.arange(lineno + 1, lineno + 1 + n))


@dataclass(frozen=True)
class Measurements:
    """Servo commands and measured joint angles.

    ``u`` (N, 6); ``q`` (N, 15) with NaN where a joint was not measured;
    ``measured`` (15,) which q columns the file has; ``sweep`` (N,) integer sweep codes
    (0..S-1, in order of first appearance) and ``sweep_ids`` their labels; ``t`` (N,) or None;
    ``lines`` the file line of each row.
    """

    u: np.ndarray
    q: np.ndarray
    measured: np.ndarray
    sweep: np.ndarray
    sweep_ids: tuple[str, ...]
    t: np.ndarray | None
    lines: np.ndarray
    source: str = "<memory>"
    #: whether the file had a ``sweep`` column (without it the file is one sweep)
    has_sweep_column: bool = False

    def __len__(self) -> int:
        return len(self.u)

    def sweeps(self) -> list[np.ndarray]:
        """Row indices of each sweep, in row order."""
        return [np.flatnonzero(self.sweep == k) for k in range(len(self.sweep_ids))]

    @property
    def q_columns(self) -> tuple[str, ...]:
        return tuple(c for c, m in zip(Q_COLUMNS, self.measured) if m)

    def require_joints(self) -> "Measurements":
        """Self, or DataError when no joint angle was measured (no q column, or every q cell empty):
        there is nothing to compare a model with."""
        if not np.isfinite(self.q).any():
            raise DataError(self.source, None, None, "no joint angle was measured (every q cell is empty)")
        return self

    @property
    def direction(self) -> np.ndarray:
        """(N, 6) direction of motion of every servo: +1 flexing, -1 extending, 0 never moved
        (see :func:`motion_direction`)."""
        return motion_direction(self.u, self.sweep)


def motion_direction(u, sweep=None) -> np.ndarray:
    """Direction of motion per row and servo, from the commanded servo angle within each sweep.

    The sign of u[k] - u[k-1]; at flat steps (and turning points reached by a flat step) the
    previous sign is held; rows before the first move of a sweep take the sign of that first move;
    a servo that never moves within a sweep gets 0. Sweeps are independent (no sign carries over).
    """
    u = np.asarray(u, dtype=float)
    n = u.shape[0]
    sweep = np.zeros(n, dtype=int) if sweep is None else np.asarray(sweep)
    out = np.zeros(u.shape)
    for k in np.unique(sweep):
        rows = np.flatnonzero(sweep == k)
        step = np.sign(np.diff(u[rows], axis=0))
        d = np.zeros((rows.size, u.shape[1]))
        for j in range(u.shape[1]):
            moves = np.flatnonzero(step[:, j])
            if moves.size == 0:
                continue
            # row i+1 gets the sign of step i; hold through zeros (forward fill)
            idx = np.zeros(rows.size - 1, dtype=int)
            idx[moves] = moves
            np.maximum.accumulate(idx, out=idx)
            col = step[idx, j]
            col[: moves[0]] = step[moves[0], j]
            d[1:, j] = col
            d[0, j] = step[moves[0], j]
        out[rows] = d
    return out


def read_measurements(path, degrees: bool = False, sweeps: bool = True) -> Measurements:
    """Read the measurement format. With ``sweeps`` (calibration) every sweep, or the whole
    file when it has no ``sweep`` column, needs at least two rows; without it (the model
    commands, which map poses one by one) a single row is fine."""
    table = read_table(path, required=U_COLUMNS, optional=Q_COLUMNS + ("t",),
                       text_columns=("sweep",), degrees=degrees, allow_empty=Q_COLUMNS)
    n = len(table)
    u = np.column_stack([table.values[c] for c in U_COLUMNS])
    q = np.full((n, N_JOINTS), np.nan)
    measured = np.zeros(N_JOINTS, dtype=bool)
    for i, c in enumerate(Q_COLUMNS):
        if c in table.values:
            q[:, i] = table.values[c]
            measured[i] = True
    if "sweep" in table.text:
        labels = table.text["sweep"]
        if isinstance(labels, Labels):
            labels = labels.in_order_of_appearance()
            ids, sweep = labels.labels, labels.codes
        else:
            ids = tuple(dict.fromkeys(labels))
            code = {s: k for k, s in enumerate(ids)}
            sweep = np.array([code[s] for s in labels], dtype=int)
    else:
        ids, sweep = ("0",), np.zeros(n, dtype=int)
    for k, sid in enumerate(ids if sweeps else ()):
        rows = np.flatnonzero(sweep == k)
        if rows.size < 2:
            if "sweep" not in table.text:
                raise DataError(path, int(table.lines[rows[0]]), None,
                                "the file has a single data row; a sweep needs at least two")
            raise DataError(path, int(table.lines[rows[0]]), "sweep",
                            f"sweep '{sid}' has a single row; a sweep needs at least two")
    t = table.values.get("t")
    return Measurements(u, q, measured, sweep, ids, t, table.lines, str(path), "sweep" in table.text)


def write_table(path, columns: Mapping[str, Iterable], comments: Sequence[str] = (),
                degrees: bool = False) -> None:
    """Write columns to a CSV atomically: numbers in fixed point with up to 12 decimals (0.5e-12
    rad; magnitudes of 1e6 or more in %.12g), NaN as an empty cell, text as the csv module quotes
    it (fastcsv.format_grid). With ``degrees`` the angle columns (u*, q*), given in radians, are
    written in degrees, as ``read_table(..., degrees=True)`` reads them back."""
    from .fastcsv import iter_grid

    path = Path(path)
    data = {}
    for c, col in columns.items():
        if isinstance(col, Labels):
            pass
        elif isinstance(col, np.ndarray) and col.dtype.kind in "fiu":
            col = np.asarray(col, dtype=float)
        elif not isinstance(col, np.ndarray) and all(isinstance(v, (int, float, np.number)) for v in col):
            col = np.asarray(col, dtype=float)
        else:
            col = [str(v) for v in col]
        data[c] = deg(col) if degrees and c in ANGLE_COLUMNS and isinstance(col, np.ndarray) else col
    n = {len(col) for col in data.values()}
    if len(n) > 1:
        raise ValueError("all columns must have the same length")
    fh = io.StringIO()
    for c in comments:
        fh.write(f"# {c}\n")
    csv.writer(fh, lineterminator="\n").writerow(list(data))
    write_atomic(path, itertools.chain([fh.getvalue().encode("utf-8")], iter_grid(data)))


def write_measurements(path, u, q=None, sweep=None, t=None, q_columns: Sequence[str] | None = None,
                       comments: Sequence[str] = (), degrees: bool = False) -> None:
    """Write the measurement format: u1..u6, then the q columns (all 15 unless ``q_columns``)."""
    u = np.asarray(u, dtype=float)
    cols: dict[str, Iterable] = {}
    if sweep is not None:
        cols["sweep"] = sweep if isinstance(sweep, Labels) else [str(s) for s in sweep]
    if t is not None:
        cols["t"] = np.asarray(t, dtype=float)
    for i, c in enumerate(U_COLUMNS):
        cols[c] = u[:, i]
    if q is not None:
        q = np.asarray(q, dtype=float)
        for i, c in enumerate(Q_COLUMNS):
            if q_columns is None or c in q_columns:
                cols[c] = q[:, i]
    write_table(path, cols, comments, degrees=degrees)
