"""Vectorized reading and writing of the plain numeric CSV grids that measurement files are
(1,000,000 rows in seconds, not minutes; issue 8, defect 10).

Reading: :func:`parse_grid` takes the data lines of a file (after its header) and returns the
parsed columns, or None when the text is not a plain grid it can vouch for (comments or blank
lines among the rows, quotes, non-ASCII text, a cell that is not a plain decimal number, an empty
cell where none is allowed, a number out of range...). The caller (``data.read_table``) then
reads the file with its exact, cell-by-cell reader, which is the definition of the format and
names the line and column of the error. A test checks that both readers agree on random files.

Writing: :func:`format_grid` formats columns of floats in fixed point with up to
:data:`DECIMALS` decimals (trailing zeros dropped, at least one kept), NaN as an empty cell,
text cells as the csv module quotes them; magnitudes of :data:`FIXED_LIMIT` or more, and
infinities, in ``%.12g``.
"""

from __future__ import annotations

import csv
import io
from typing import Mapping, Sequence

import numpy as np

DECIMALS = 12           # fixed-point decimals written: 0.5e-12 rad, far below any measurement
FIXED_LIMIT = 1e6       # |v| below this is written in fixed point (its scaled value fits an int64)
CHUNK_ROWS = 65536      # rows formatted / parsed at once (bounds the memory of a 1e6-row file)

_ALLOWED = np.zeros(256, dtype=bool)  # the bytes of a plain decimal number (and the separators)
_ALLOWED[np.frombuffer(b"0123456789.+-eE,\n", dtype=np.uint8)] = True
_COMMA, _NEWLINE, _SPACE = 44, 10, 32


# -- reading ------------------------------------------------------------------

def parse_grid(data: bytes, header: Sequence[str], text_columns: Sequence[str], allow_empty: Sequence[str]):
    """Parse the data lines ``data`` (UTF-8 bytes) of a CSV whose header is ``header``.

    Returns ``(values, text)``: ``values`` {numeric column: float array, NaN for an empty cell},
    ``text`` {text column: tuple of str}; or None when the fast reader cannot vouch for the text
    (the exact reader decides then). Range checks (finite, radians) are the caller's."""
    if not data.isascii():
        return None
    view = memoryview(data)
    stop = len(data) - 1 if data.endswith(b"\n") else len(data)
    if (stop <= 0 or data.startswith(b"\n") or data.find(b"\n\n", 0, stop) >= 0
            or any(data.find(c) >= 0 for c in (b"#", b'"', b"\r"))):
        return None
    numeric = [j for j, c in enumerate(header) if c not in text_columns]
    texts = [j for j, c in enumerate(header) if c in text_columns]
    empty_ok = np.array([header[j] in allow_empty for j in numeric])
    n = data.count(b"\n", 0, stop) + 1
    values = {header[j]: np.empty(n) for j in numeric}     # filled chunk by chunk: no second copy
    labels: list[list[np.ndarray]] = [[] for _ in texts]
    start, row = 0, 0
    while start < stop:
        end = _chunk_end(data, start, stop)
        got = _parse_chunk(view[start:end], len(header), numeric, texts, empty_ok)
        if got is None:
            return None
        v, lab = got
        for k, j in enumerate(numeric):
            values[header[j]][row:row + len(v)] = v[:, k]
        for k in range(len(texts)):
            labels[k].append(lab[k])
        row += len(v)
        start = end + 1
    text = {}
    for k, j in enumerate(texts):
        uniq, inverse = np.unique(np.concatenate(labels[k]), return_inverse=True)
        names = [u.decode("ascii") for u in uniq]
        text[header[j]] = tuple(names[i] for i in inverse)
    return values, text


def _chunk_end(data: bytes, start: int, stop: int) -> int:
    """End (a newline, or ``stop``) of the chunk of about CHUNK_ROWS lines from ``start``."""
    guess = start + CHUNK_ROWS * 64
    if guess >= stop:
        return stop
    end = data.find(b"\n", guess, stop)
    return stop if end < 0 else end


def _parse_chunk(chunk: bytes, ncols: int, numeric: list[int], texts: list[int], empty_ok: np.ndarray):
    arr = np.frombuffer(chunk, dtype=np.uint8)
    is_sep = (arr == _COMMA) | (arr == _NEWLINE)
    seps = np.flatnonzero(is_sep)
    nlines = int(np.count_nonzero(arr == _NEWLINE)) + 1
    if seps.size != nlines * ncols - 1:
        return None
    ends = np.append(seps, arr.size).reshape(nlines, ncols)      # every line has ncols cells iff
    if not (arr[ends[:, -1][:-1]] == _NEWLINE).all():            # its last separator is a newline
        return None
    if ncols > 1 and (arr[ends[:, :-1]] != _COMMA).any():
        return None
    starts = np.empty_like(ends)
    starts[:, 1:] = ends[:, :-1] + 1
    starts[0, 0] = 0
    starts[1:, 0] = ends[:-1, -1] + 1
    width = ends - starts
    # text cells: non-empty, no surrounding spaces (the exact reader strips them), gathered by position
    labels = []
    for j in texts:
        s, w = starts[:, j], width[:, j]
        if (w == 0).any() or (arr[s] == _SPACE).any() or (arr[s + w - 1] == _SPACE).any():
            return None
        wmax = int(w.max())
        idx = s[:, None] + np.arange(wmax)
        cells = np.where(np.arange(wmax) < w[:, None], arr[np.minimum(idx, arr.size - 1)], 0).astype(np.uint8)
        labels.append(cells.view(f"S{wmax}").ravel())
    # numeric cells: plain decimal characters only (any other byte lies in a text cell)
    other = np.flatnonzero(~_ALLOWED[arr])
    if other.size:
        if not texts:
            return None
        s = starts[:, texts].ravel()
        e = ends[:, texts].ravel()
        order = np.argsort(s, kind="stable")
        s, e = s[order], e[order]
        cell = np.searchsorted(s, other, side="right") - 1
        if (cell < 0).any() or (other >= e[np.maximum(cell, 0)]).any():
            return None
    # empty cells only where allowed; a column empty in every row of the chunk is not parsed
    empty = width[:, numeric] == 0
    if (empty & ~empty_ok).any():
        return None
    v = np.full((nlines, len(numeric)), np.nan)
    all_empty = empty.all(axis=0)
    use = [k for k in range(len(numeric)) if not all_empty[k]]
    if use:
        partly = empty[:, use]
        if partly.any():   # a few empty cells: "nan" is inserted there (the text has no "nan" of its own)
            at = starts[:, [numeric[k] for k in use]][partly]
            arr = np.insert(arr, np.repeat(at, 3), np.tile(np.frombuffer(b"nan", dtype=np.uint8), at.size))
        try:
            got = np.loadtxt(io.StringIO(arr.tobytes().decode("ascii")), delimiter=",",
                             usecols=[numeric[k] for k in use], dtype=float, ndmin=2, comments=None,
                             quotechar=None)
        except ValueError:
            return None
        if got.shape != (nlines, len(use)):
            return None
        v[:, use] = got
    return v, labels


# -- writing ------------------------------------------------------------------

def format_grid(columns: Mapping[str, object]) -> bytes:
    """The CSV data lines (no header) of ``columns``: {name: float array or sequence of str}, all
    of one length; every line ends with a newline."""
    names = list(columns)
    n = len(next(iter(columns.values()))) if columns else 0
    out = []
    for a in range(0, n, CHUNK_ROWS):
        b = min(n, a + CHUNK_ROWS)
        blocks = []
        for k, name in enumerate(names):
            blocks.append(_cells(columns[name], a, b))
            blocks.append(np.full((b - a, 1), _NEWLINE if k == len(names) - 1 else _COMMA, dtype=np.uint8))
        grid = np.concatenate(blocks, axis=1).ravel()
        out.append(grid[grid != 0].tobytes())
    return b"".join(out)


def _cells(col, a: int, b: int) -> np.ndarray:
    """Rows a..b of one column as a NUL-padded (rows, width) byte matrix."""
    if isinstance(col, np.ndarray) and col.dtype.kind == "f":
        x = col[a:b]
        other = np.flatnonzero(np.isinf(x) | (np.abs(np.nan_to_num(x)) >= FIXED_LIMIT))
        if not other.size:
            return fixed_point(x)
        cells = fixed_point(np.where(np.isin(np.arange(x.size), other), np.nan, x))
        special = _as_bytes([f"{v:.12g}" for v in x[other].tolist()])   # huge or infinite: %.12g
        out = np.zeros((x.size, max(cells.shape[1], special.shape[1])), dtype=np.uint8)
        out[:, :cells.shape[1]] = cells
        out[other, :special.shape[1]] = special
        return out
    labels, inverse = np.unique(np.asarray(col[a:b], dtype=str), return_inverse=True)
    return _as_bytes([_quote(str(v)) for v in labels])[inverse.ravel()]


def _quote(cell: str) -> str:
    if any(c in cell for c in ',"\n\r'):
        fh = io.StringIO()
        csv.writer(fh, lineterminator="").writerow([cell])
        return fh.getvalue()
    return cell


def _as_bytes(cells: list[str]) -> np.ndarray:
    enc = np.array([c.encode("utf-8") for c in cells], dtype=bytes)
    width = max(enc.dtype.itemsize, 1)
    return np.frombuffer(enc.astype(f"S{width}").tobytes(), dtype=np.uint8).reshape(len(cells), width)


# 0..999 as 3 ASCII digits and a NUL, one uint32 each (a 4-byte gather is much faster than a row gather)
_GROUPS = np.frombuffer(b"".join(f"{g:03d}".encode() + b"\0" for g in range(1000)), dtype=np.uint32)
_TRAILING_ZEROS = np.array([3] + [len(str(g).zfill(3)) - len(str(g).zfill(3).rstrip("0")) for g in range(1, 1000)])
_INT_GROUPS = 3             # integer part: up to 9 digits (|v| < FIXED_LIMIT needs 7)
_FRAC_GROUPS = DECIMALS // 3
_POW10 = 10 ** np.arange(1, 3 * _INT_GROUPS, dtype=np.int64)


def _divmod1000(n: np.ndarray):
    q = n // 1000
    return q, n - q * 1000


def fixed_point(x: np.ndarray) -> np.ndarray:
    """Finite |x| < FIXED_LIMIT (or NaN) as fixed-point text with up to DECIMALS decimals, as a
    NUL-padded (rows, width) byte matrix: sign, integer digits, point, decimals without trailing
    zeros (one kept); NaN all NUL (an empty cell). Digits come three at a time from a table."""
    finite = np.isfinite(x)
    a = np.abs(np.where(finite, x, 0.0))
    whole = np.floor(a)                              # a = whole + (a - whole), both exact
    frac = np.rint((a - whole) * 10.0 ** DECIMALS).astype(np.int64)
    whole = whole.astype(np.int64)
    carry = frac == 10 ** DECIMALS                   # 0.9999999999999 rounds up to 1.0
    whole += carry
    frac[carry] = 0
    groups = np.empty((x.size, _INT_GROUPS + _FRAC_GROUPS), dtype=np.int64)
    rest = frac
    for k in range(_INT_GROUPS + _FRAC_GROUPS - 1, _INT_GROUPS - 1, -1):
        rest, groups[:, k] = _divmod1000(rest)
    rest = whole
    for k in range(_INT_GROUPS - 1, -1, -1):
        rest, groups[:, k] = _divmod1000(rest)
    digits = _GROUPS[groups].view(np.uint8).reshape(x.size, -1, 4)[:, :, :3].reshape(x.size, -1)
    nint = 3 * _INT_GROUPS
    # integer digits shown: at least one; decimals shown: up to the last non-zero one, at least one
    shown_int = 1 + np.searchsorted(_POW10, whole, side="right")
    fg = groups[:, _INT_GROUPS:]
    last = np.where(fg != 0, np.arange(1, _FRAC_GROUPS + 1), 0).max(axis=1)   # last non-zero group, 1-based
    shown_dec = np.maximum(3 * last - _TRAILING_ZEROS[fg[np.arange(x.size), np.maximum(last - 1, 0)]], 1)
    out = np.zeros((x.size, 2 + digits.shape[1]), dtype=np.uint8)
    out[:, 0] = np.where((x < 0) & ((whole > 0) | (frac > 0)), ord("-"), 0)
    out[:, 1:1 + nint] = np.where(np.arange(nint, 0, -1) <= shown_int[:, None], digits[:, :nint], 0)
    out[:, 1 + nint] = ord(".")
    out[:, 2 + nint:] = np.where(np.arange(1, DECIMALS + 1) <= shown_dec[:, None], digits[:, nint:], 0)
    out[~finite] = 0
    return out
