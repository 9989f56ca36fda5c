"""Compiled reading and writing of the plain numeric CSV grids that measurement files are
(fast enough that a 1,000,000-row file reads or writes in about a second).

Reading: :func:`parse_grid` takes the data lines of a file (after its header) and returns the
parsed columns, or None when the text is not a plain grid it can vouch for (comments or blank
lines among the rows, quotes, non-ASCII text, a cell that is not a plain decimal number, an empty
cell where none is allowed, a wrong number of cells...). The caller (``data.read_table``) then
reads the file with its exact, cell-by-cell reader, which is the definition of the format and
names the line and column of the error. A test checks that both readers agree on random files.
Numbers are converted exactly: a decimal with at most 15 significant digits and a power of ten
within 1e+-22 is one correctly rounded product or quotient of two exact doubles (Clinger's fast
path); any other number (17-digit ``repr`` output, large exponents) is collected and converted by
numpy's correctly rounded parser.

Writing: :func:`format_grid` formats columns of floats in fixed point with up to
:data:`DECIMALS` decimals (trailing zeros dropped, at least one kept), NaN as an empty cell,
text cells as the csv module quotes them; magnitudes of :data:`FIXED_LIMIT` or more, and
infinities, in ``%.12g``.

The byte loops are compiled with numba (``cache=True``: compiled once per installation, then
loaded in about 0.1 s; ``make install`` compiles them).
"""

from __future__ import annotations

import csv
import io
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from typing import Iterator, Mapping, Sequence

import numba
import numpy as np

from .labels import Labels

DECIMALS = 12           # fixed-point decimals written: 0.5e-12 rad, far below any measurement
FIXED_LIMIT = 1e6       # |v| below this is written in fixed point (its scaled value fits an int64)
CHUNK_ROWS = 65536      # rows formatted at once (bounds the memory of a 1e6-row file)
_CELL_WIDTH = 1 + 6 + 1 + DECIMALS   # the widest fixed-point cell: -999999.999999999999

_COMMA, _NEWLINE, _SPACE = 44, 10, 32
_SLOW = np.uint64(0x7FF8_0000_5EC0_0001)   # a NaN payload marking a cell left to the exact parser
_POW10 = np.array([10.0 ** k for k in range(23)])   # exact doubles
_MAX_EXACT = 2 ** 53


# -- reading ------------------------------------------------------------------

def parse_grid(data: bytes, header: Sequence[str], text_columns: Sequence[str], allow_empty: Sequence[str],
               start: int = 0):
    """Parse the data lines ``data[start:]`` (UTF-8 bytes) of a CSV whose header is ``header``.

    Returns ``(values, text)``: ``values`` {numeric column: float array, NaN for an empty cell},
    ``text`` {text column: :class:`Labels`}; or None when the fast reader cannot vouch for the
    text (the exact reader decides then). Range checks (finite, radians) are the caller's."""
    if not data.isascii():
        return None
    stop = len(data) - 1 if data.endswith(b"\n") else len(data)
    if (stop <= start or data.startswith(b"\n", start) or data.find(b"\n\n", start, stop) >= 0
            or any(data.find(c, start) >= 0 for c in (b"#", b'"', b"\r"))):
        return None
    arr = np.frombuffer(data, dtype=np.uint8)[start:stop]
    ncols = len(header)
    numeric = [j for j, c in enumerate(header) if c not in text_columns]
    texts = [j for j, c in enumerate(header) if c in text_columns]
    slot = np.full(ncols, -1, dtype=np.int64)       # column -> index among the numeric / text columns
    slot[numeric] = np.arange(len(numeric))
    slot[texts] = np.arange(len(texts))
    is_text = np.isin(np.arange(ncols), texts)
    empty_ok = np.array([c in allow_empty for c in header])
    nrows = data.count(b"\n", start, stop) + 1
    values = np.empty((nrows, len(numeric)))
    spans = np.empty((nrows, len(texts), 2), dtype=np.int64)
    slow_text = np.empty(arr.size + 1, dtype=np.uint8)    # pages are touched only where written
    slow, size = _parse(arr, slot, is_text, empty_ok, values, spans, slow_text)
    if slow < 0:
        return None
    if slow and not _parse_slow(slow_text[:size], values, slow):
        return None
    text = {}
    for k, j in enumerate(texts):
        s, w = spans[:, k, 0], spans[:, k, 1] - spans[:, k, 0]
        wmax = int(w.max())
        idx = np.minimum(s[:, None] + np.arange(wmax), arr.size - 1)
        cells = np.where(np.arange(wmax) < w[:, None], arr[idx], 0).astype(np.uint8)
        uniq, inverse = np.unique(cells.view(f"S{wmax}").ravel(), return_inverse=True)
        text[header[j]] = Labels(tuple(u.decode("ascii") for u in uniq), inverse.ravel().astype(np.int64))
    return {header[j]: values[:, k] for k, j in enumerate(numeric)}, text


def _parse_slow(text, values, count: int) -> bool:
    """Convert the cells :func:`_parse` left (marked ``_SLOW``, their text one per line in
    ``text``) with numpy's correctly rounded parser; False when numpy refuses one."""
    try:
        got = np.loadtxt(io.StringIO(text.tobytes().decode("ascii")), dtype=float, ndmin=1,
                         comments=None, quotechar=None)
    except ValueError:
        return False
    flat = values.reshape(-1)
    at = np.flatnonzero(flat.view(np.uint64) == _SLOW)
    if got.shape != (count,) or at.size != count:
        return False
    flat[at] = got
    return True


@numba.njit(cache=True, nogil=True)
def _number(arr, s, e):
    """The plain decimal number in arr[s:e]: (1, value) converted exactly, (2, 0.0) a valid number
    for the exact parser, (-1, 0.0) not a plain decimal number."""
    i = s
    neg = False
    if arr[i] == 43 or arr[i] == 45:            # + -
        neg = arr[i] == 45
        i += 1
    mant = 0
    nd = 0          # significant digits kept in mant
    exp10 = 0
    seen = 0        # digits seen
    lost = False
    while i < e and 48 <= arr[i] <= 57:
        d = arr[i] - 48
        seen += 1
        if mant == 0 and d == 0:
            pass
        elif nd < 18:
            mant = mant * 10 + d
            nd += 1
        else:
            exp10 += 1
            lost = True
        i += 1
    if i < e and arr[i] == 46:                 # .
        i += 1
        while i < e and 48 <= arr[i] <= 57:
            d = arr[i] - 48
            seen += 1
            if mant == 0 and d == 0:
                exp10 -= 1
            elif nd < 18:
                mant = mant * 10 + d
                nd += 1
                exp10 -= 1
            else:
                lost = True
            i += 1
    if seen == 0:
        return -1, 0.0
    if i < e and (arr[i] == 101 or arr[i] == 69):   # e E
        i += 1
        eneg = False
        if i < e and (arr[i] == 43 or arr[i] == 45):
            eneg = arr[i] == 45
            i += 1
        if i >= e:
            return -1, 0.0
        ev = 0
        while i < e and 48 <= arr[i] <= 57:
            if ev < 100000:
                ev = ev * 10 + (arr[i] - 48)
            i += 1
        exp10 += -ev if eneg else ev
    if i != e:
        return -1, 0.0
    if mant == 0:
        return 1, -0.0 if neg else 0.0
    if lost or mant > _MAX_EXACT or exp10 < -22 or exp10 > 22:
        return 2, 0.0
    v = mant * _POW10[exp10] if exp10 >= 0 else mant / _POW10[-exp10]
    return 1, -v if neg else v


@numba.njit(cache=True, nogil=True)
def _parse(arr, slot, is_text, empty_ok, values, spans, slow_text):
    """Fill ``values`` (rows x numeric columns) and ``spans`` (rows x text columns x [start, end))
    from the grid in ``arr``. Returns (the number of cells left to the exact parser, the bytes of
    ``slow_text`` used): those cells are marked ``_SLOW`` in ``values`` and their text copied to
    ``slow_text``, one per line, in row order. (-1, 0) when the text is not a plain grid of these
    columns."""
    n = arr.size
    ncols = slot.size
    marks = values.reshape(-1).view(np.uint64)
    nnum = values.shape[1]
    pos = 0
    slow = 0
    size = 0
    for row in range(values.shape[0]):
        for j in range(ncols):
            s = pos
            e = s
            while e < n and arr[e] != 44 and arr[e] != 10:
                e += 1
            if j < ncols - 1:
                if e >= n or arr[e] != 44:
                    return -1, 0
            elif e < n and arr[e] != 10:
                return -1, 0
            k = slot[j]
            if is_text[j]:
                if e == s or arr[s] == 32 or arr[e - 1] == 32:
                    return -1, 0
                spans[row, k, 0] = s
                spans[row, k, 1] = e
            elif e == s:
                if not empty_ok[j]:
                    return -1, 0
                values[row, k] = np.nan
            else:
                status, v = _number(arr, s, e)
                if status < 0:
                    return -1, 0
                if status == 1:
                    values[row, k] = v
                else:
                    marks[row * nnum + k] = _SLOW
                    slow += 1
                    for i in range(s, e):
                        slow_text[size] = arr[i]
                        size += 1
                    slow_text[size] = 10
                    size += 1
            pos = e + 1
    if pos < n:
        return -1, 0
    return slow, size


# -- writing ------------------------------------------------------------------

def format_grid(columns: Mapping[str, object]) -> bytes:
    """The CSV data lines (no header) of ``columns``: {name: float array, :class:`Labels` or
    sequence of str}, all of one length; every line ends with a newline."""
    return b"".join(iter_grid(columns))


def iter_grid(columns: Mapping[str, object]) -> Iterator[bytes]:
    """:func:`format_grid` in chunks of :data:`CHUNK_ROWS` rows, formatted on two threads (the
    compiled loop releases the GIL)."""
    names = list(columns)
    n = len(next(iter(columns.values()))) if columns else 0
    if not names:
        return
    floats = [k for k, c in enumerate(names) if _is_float(columns[c])]
    texts = [k for k, c in enumerate(names) if k not in floats]
    slot = np.full(len(names), -1, dtype=np.int64)
    slot[floats] = np.arange(len(floats))
    slot[texts] = np.arange(len(texts))
    is_text = np.isin(np.arange(len(names)), texts)
    # text cells and the rare huge or infinite numbers: codes into one table of encoded cells
    table: dict[str, int] = {}
    codes = np.empty((n, len(texts)), dtype=np.int64)
    for k, j in enumerate(texts):
        col = columns[names[j]]
        if not isinstance(col, Labels):
            labels, inverse = np.unique(np.asarray(col, dtype=str), return_inverse=True)
            col = Labels(tuple(str(v) for v in labels), inverse.ravel())
        to_table = np.array([table.setdefault(_quote(v), len(table)) for v in col.labels], dtype=np.int64)
        codes[:, k] = to_table[col.codes] if n else []
    values = np.empty((n, len(floats)))
    special_at, special_code = [], []
    for k, j in enumerate(floats):
        x = np.asarray(columns[names[j]], dtype=float)
        values[:, k] = x
        other = np.flatnonzero(np.isinf(x) | (np.abs(np.nan_to_num(x)) >= FIXED_LIMIT))
        for r in other.tolist():
            special_at.append(r * len(names) + j)
            special_code.append(table.setdefault(f"{x[r]:.12g}", len(table)))
    order = np.argsort(np.array(special_at, dtype=np.int64), kind="stable")
    special = np.array(special_at, dtype=np.int64)[order]
    special_codes = np.array(special_code, dtype=np.int64)[order]
    encoded = [c.encode("utf-8") for c in table]
    label_bytes = np.frombuffer(b"".join(encoded) or b"\0", dtype=np.uint8)
    label_end = np.cumsum([len(c) for c in encoded], dtype=np.int64)
    label_width = max((len(c) for c in encoded), default=0)
    width = len(floats) * _CELL_WIDTH + len(texts) * label_width + len(names)
    if special.size:
        width += label_width * len(names)

    def chunk(a: int) -> bytes:
        b = min(n, a + CHUNK_ROWS)
        buf = np.empty((b - a) * width, dtype=np.uint8)
        size = _format(values[a:b], codes[a:b], a, slot, is_text, special, special_codes,
                       label_bytes, label_end, buf)
        return buf[:size].tobytes()

    with ThreadPoolExecutor(max_workers=2) as pool:    # at most three chunks in memory
        pending: deque = deque()
        for a in range(0, n, CHUNK_ROWS):
            pending.append(pool.submit(chunk, a))
            if len(pending) > 2:
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()


def _is_float(col) -> bool:
    return isinstance(col, np.ndarray) and col.dtype.kind == "f"


def _quote(cell: str) -> str:
    if any(c in cell for c in ',"\n\r'):
        fh = io.StringIO()
        csv.writer(fh, lineterminator="").writerow([cell])
        return fh.getvalue()
    return cell


_GROUPS = np.frombuffer(b"".join(f"{g:03d}".encode() for g in range(1000)), dtype=np.uint8)   # 0..999, 3 digits
_KEEP = np.array([1] + [len(f"{g:03d}".rstrip("0")) for g in range(1, 1000)], dtype=np.int64)  # digits up to the last non-zero


@numba.njit(cache=True, nogil=True, inline="always")
def _group(buf, size, g, keep):
    buf[size] = _GROUPS[3 * g]
    buf[size + 1] = _GROUPS[3 * g + 1]
    buf[size + 2] = _GROUPS[3 * g + 2]
    return size + keep


@numba.njit(cache=True, nogil=True)
def _fixed(buf, size, x):
    """Finite |x| < FIXED_LIMIT as fixed-point text: sign, integer digits (at least one), point,
    up to DECIMALS decimals without trailing zeros (at least one). Digits come three at a time
    from a table."""
    a = abs(x)
    whole = np.floor(a)                      # a = whole + (a - whole), both exact
    frac = np.int64(np.rint((a - whole) * 1e12))
    w = np.int64(whole)
    if frac == 1_000_000_000_000:            # 0.9999999999999 rounds up to 1.0
        w += 1
        frac = 0
    if x < 0 and (w > 0 or frac > 0):
        buf[size] = 45
        size += 1
    if w < 10:
        buf[size] = 48 + w
        size += 1
    else:
        digits = 1
        t = w
        while t >= 10:
            t //= 10
            digits += 1
        for i in range(digits - 1, -1, -1):
            buf[size + i] = 48 + w % 10
            w //= 10
        size += digits
    buf[size] = 46
    size += 1
    g3 = frac % 1000
    frac //= 1000
    g2 = frac % 1000
    frac //= 1000
    g1 = frac % 1000
    g0 = frac // 1000
    # three digits written for every group up to the last non-zero one (the buffer has room for a
    # full cell); the cursor moves past the digits kept
    size = _group(buf, size, g0, 3 if (g1 or g2 or g3) else _KEEP[g0])
    if g1 or g2 or g3:
        size = _group(buf, size, g1, 3 if (g2 or g3) else _KEEP[g1])
        if g2 or g3:
            size = _group(buf, size, g2, 3 if g3 else _KEEP[g2])
            if g3:
                size = _group(buf, size, g3, _KEEP[g3])
    return size


@numba.njit(cache=True, nogil=True)
def _format(values, codes, row0, slot, is_text, special, special_codes, label_bytes, label_end, buf):
    """Rows of the grid as CSV lines into ``buf``; returns the bytes written. Text cells, and the
    float cells listed in ``special`` (flat row * columns + column, sorted), are copied from the
    label table; NaN is an empty cell."""
    ncols = slot.size
    size = 0
    p = np.searchsorted(special, row0 * ncols)
    for r in range(values.shape[0]):
        for j in range(ncols):
            code = -1
            if is_text[j]:
                code = codes[r, slot[j]]
            elif p < special.size and special[p] == (row0 + r) * ncols + j:
                code = special_codes[p]
                p += 1
            if code >= 0:
                start = label_end[code - 1] if code > 0 else 0
                for i in range(start, label_end[code]):
                    buf[size] = label_bytes[i]
                    size += 1
            else:
                x = values[r, slot[j]]
                if x == x:
                    size = _fixed(buf, size, x)
            buf[size] = 10 if j == ncols - 1 else 44
            size += 1
    return size


def compile() -> None:
    """Compile (or load from numba's cache) the byte loops: ``make install`` runs this once."""
    format_grid({"sweep": ["a", "b"], "u": np.array([0.5, np.inf])})
    parse_grid(b"a,0.5\nb,0.12345678901234567\n", ["sweep", "u"], ["sweep"], [])
