"""The measurement CSV format: every bad-input rule with its exact message, and the good path."""

import math

import numpy as np
import pytest

from phantom_cad.calibration.data import DataError, motion_direction, read_measurements, write_measurements

U = "u1,u2,u3,u4,u5,u6"


def write(tmp_path, text, name="m.csv"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def error_of(path, **kw):
    with pytest.raises(DataError) as exc:
        read_measurements(path, **kw)
    return str(exc.value)


def test_missing_column(tmp_path):
    p = write(tmp_path, "u1,u2,u4,u5,u6,q3\n0,0,0,0,0,0\n0,0.1,0,0,0,0.1\n")
    assert error_of(p) == f"{p}, line 1, column u3: required column is missing"


def test_text_in_number_cell(tmp_path):
    p = write(tmp_path, f"{U},q3\n0,0,0,0,0,0,0\n0,0.1,0,0,0,0,abc\n")
    assert error_of(p) == f"{p}, line 3, column q3: 'abc' is not a number"


def test_nan(tmp_path):
    p = write(tmp_path, f"{U},q3\n0,0,0,0,0,0,0\n0,0.1,0,0,0,0,nan\n")
    assert error_of(p) == f"{p}, line 3, column q3: 'nan' is not a finite number"


def test_infinity(tmp_path):
    p = write(tmp_path, f"{U},q3\n0,inf,0,0,0,0,0\n0,0.1,0,0,0,0,0\n")
    assert error_of(p) == f"{p}, line 2, column u2: 'inf' is not a finite number"


def test_angles_that_are_obviously_degrees(tmp_path):
    p = write(tmp_path, f"{U},q3\n0,0,0,0,0,0,0\n0,45,0,0,0,0,0.3\n")
    assert error_of(p) == (f"{p}, line 3, column u2: 45 looks like degrees (angles are radians, |angle| <= 2 pi); "
                           "convert it or pass --degrees")


def test_empty_file(tmp_path):
    p = write(tmp_path, "")
    assert error_of(p) == f"{p}: is empty: expected a header row and at least one data row"


def test_only_comments_is_empty(tmp_path):
    p = write(tmp_path, "# nothing here\n\n# still nothing\n")
    assert error_of(p) == f"{p}: is empty: expected a header row and at least one data row"


def test_header_without_rows(tmp_path):
    p = write(tmp_path, f"{U},q3\n")
    assert error_of(p) == f"{p}: has a header but no data rows"


def test_sweep_with_one_row(tmp_path):
    p = write(tmp_path, f"sweep,{U},q3\na,0,0,0,0,0,0,0\na,0,0.1,0,0,0,0,0.1\nb,0,0.2,0,0,0,0,0.2\n")
    assert error_of(p) == f"{p}, line 4, column sweep: sweep 'b' has a single row; a sweep needs at least two"


def test_single_row_without_sweep_column(tmp_path):
    p = write(tmp_path, f"# one sample\n{U},q3\n0,0.1,0,0,0,0,0.1\n")
    assert error_of(p) == f"{p}, line 3: the file has a single data row; a sweep needs at least two"


def test_unknown_column(tmp_path):
    p = write(tmp_path, f"{U},q16\n0,0,0,0,0,0,0\n0,0,0,0,0,0,0\n")
    assert error_of(p).startswith(f"{p}, line 1, column q16: unknown column (allowed: u1, u2, u3, u4, u5, u6, q1,")


def test_duplicate_column(tmp_path):
    p = write(tmp_path, f"{U},q3,q3\n0,0,0,0,0,0,0,0\n0,0,0,0,0,0,0,0\n")
    assert error_of(p) == f"{p}, line 1, column q3: duplicate column"


def test_wrong_number_of_cells(tmp_path):
    p = write(tmp_path, f"{U},q3\n0,0,0,0,0,0,0\n0,0,0,0,0,0\n")
    assert error_of(p) == f"{p}, line 3: has 6 cells, the header has 7"


def test_empty_servo_cell(tmp_path):
    p = write(tmp_path, f"{U},q3\n0,0,0,0,0,0,0\n0,,0,0,0,0,0\n")
    assert error_of(p) == f"{p}, line 3, column u2: empty cell (this column is required on every row)"


def test_empty_sweep_cell(tmp_path):
    p = write(tmp_path, f"sweep,{U},q3\na,0,0,0,0,0,0,0\n,0,0,0,0,0,0,0\n")
    assert error_of(p) == f"{p}, line 3, column sweep: empty cell"


def test_missing_file(tmp_path):
    p = tmp_path / "nope.csv"
    assert error_of(p) == f"{p}: no such file"


def test_not_utf8(tmp_path):
    p = tmp_path / "latin.csv"
    p.write_bytes(f"{U},q3\n0,0,0,0,0,0,0\n".encode() + b"0,0,0,0,0,0,\xe9\n")
    assert error_of(p) == f"{p}: is not UTF-8 text (invalid continuation byte at byte 47)"  # 21 + 14 + 12 bytes before it


def test_good_file_comments_empty_cells_and_degrees(tmp_path):
    p = write(tmp_path, "# header comment\n"
                        f"sweep,t,{U},q3,q5\n"
                        "s1,0.0,0,0,0,0,0,0,0,\n"
                        "# a comment between rows\n"
                        "s1,0.1,0,45,0,0,0,0,30,20\n"
                        "s1,0.2,0,90,0,0,0,0,,40\n")
    m = read_measurements(p, degrees=True)
    assert len(m) == 3
    assert list(m.lines) == [3, 5, 6]
    assert m.q_columns == ("q3", "q5")
    assert m.u[1, 1] == pytest.approx(math.pi / 4)
    assert m.q[1, 2] == pytest.approx(math.radians(30))
    assert math.isnan(m.q[0, 4]) and math.isnan(m.q[2, 2])
    assert np.isnan(m.q[:, 0]).all()          # q1 not measured
    assert list(m.t) == [0.0, 0.1, 0.2]
    assert m.sweep_ids == ("s1",)


def test_write_read_round_trip(tmp_path):
    u = np.zeros((4, 6))
    u[:, 2] = [0.0, 0.2, 0.4, 0.2]
    q = np.full((4, 15), np.nan)
    q[:, 5] = [0.0, 0.1, 0.25, 0.12]
    p = tmp_path / "rt.csv"
    write_measurements(p, u, q, sweep=["a", "a", "b", "b"], q_columns=["q6"])
    m = read_measurements(p)
    assert m.q_columns == ("q6",)
    assert np.allclose(m.u, u) and np.allclose(m.q[:, 5], q[:, 5])
    assert list(m.sweep) == [0, 0, 1, 1]


def test_direction_of_motion_known_answer():
    # flat start, rise, flat top (turning point held), fall, flat, rise again
    col = [0.0, 0.0, 0.1, 0.2, 0.2, 0.1, 0.0, 0.0, 0.1]
    u = np.zeros((9, 6))
    u[:, 3] = col
    d = motion_direction(u)
    assert list(d[:, 3]) == [1, 1, 1, 1, 1, -1, -1, -1, 1]
    assert not d[:, [0, 1, 2, 4, 5]].any()     # servos that never move: 0


def test_direction_is_per_sweep():
    u = np.zeros((4, 6))
    u[:, 1] = [0.0, 0.3, 0.3, 0.1]
    d = motion_direction(u, np.array([0, 0, 1, 1]))
    assert list(d[:, 1]) == [1, 1, -1, -1]


@pytest.mark.parametrize("cell", ["0.0_1", "١٢", "1_000"])
def test_numbers_are_plain_ascii_decimals(tmp_path, cell):
    """float() accepts underscores and non-ASCII digits; a CSV does not."""
    path = tmp_path / "m.csv"
    path.write_text(f"u1,u2,u3,u4,u5,u6\n0,0,0,0,0,0\n0,{cell},0,0,0,0\n", encoding="utf-8")
    with pytest.raises(DataError) as exc:
        read_measurements(path)
    assert str(exc.value) == f"{path}, line 3, column u2: '{cell}' is not a number"


def test_byte_order_mark_and_folders(tmp_path):
    """A UTF-8 BOM is read, not reported as an unknown column; a folder given as the file gives
    one error line, no traceback."""
    path = tmp_path / "bom.csv"
    path.write_text("\ufeffu1,u2,u3,u4,u5,u6\n0,0,0,0,0,0\n0,0.5,0,0,0,0\n", encoding="utf-8")
    assert read_measurements(path).u[1, 1] == 0.5
    with pytest.raises(DataError) as exc:
        read_measurements(tmp_path)
    assert str(exc.value) == f"{tmp_path}: is a folder, not a CSV file"


# -- the column-wise reader and writer (1,000,000-row files) ------------------------------

def _exact(path, monkeypatch, **kw):
    """The table as the exact cell-by-cell reader reads it (the column-wise one switched off)."""
    from phantom_cad.calibration import data

    with monkeypatch.context() as m:
        m.setattr(data, "_read_fast", lambda *a, **k: None)
        try:
            return data.read_measurements(path, **kw)
        except DataError as exc:
            return str(exc)


def _both(path, monkeypatch, **kw):
    fast = _exact_or_fast(path, **kw)
    return fast, _exact(path, monkeypatch, **kw)


def _exact_or_fast(path, **kw):
    try:
        return read_measurements(path, **kw)
    except DataError as exc:
        return str(exc)


def _same(a, b):
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    return (np.array_equal(a.u, b.u) and np.array_equal(a.q, b.q, equal_nan=True)
            and np.array_equal(a.measured, b.measured) and np.array_equal(a.sweep, b.sweep)
            and a.sweep_ids == b.sweep_ids and np.array_equal(a.lines, b.lines)
            and ((a.t is None and b.t is None) or np.array_equal(a.t, b.t)))


_CELLS = ["0", "0.5", "-0.25", "+.5", "1e-3", "2.5E+0", "", "1.", "3.14159265358979", "7", "0.0_1", "1e999",
          "٣", "nan", " 0.5", "abc", "-", "1e", "6.3", "-6.29", ".", "1,5", '"0.5"', "0x1", "-0", "+0.000",
          "1e-30", "12345678901234567890.5", "0.1234567890123456789", "1e22", "5e-23", "9007199254740993", "1E+1"]


@pytest.mark.parametrize("seed", range(40))
def test_column_reader_agrees_with_the_exact_reader(tmp_path, monkeypatch, seed):
    """Random files, mostly plain grids with a few bad cells, comments, blank lines, quotes:
    the column-wise reader returns the exact reader's table or leaves the file to it (same
    error). Known answer: the exact reader, cell by cell with float() and a regex."""
    rng = np.random.default_rng(seed)
    cols = ["sweep", *U.split(","), "q3", "q4", "t"][: 7 + int(rng.integers(0, 4))]
    if rng.random() < 0.3:
        cols = cols[1:]
    lines = ["# a comment"] * int(rng.integers(0, 3)) + [",".join(cols)]
    rows = int(rng.integers(2, 40))
    for k in range(rows):
        cells = []
        for c in cols:
            if c == "sweep":
                cells.append(str(rng.choice(["a", "b", "up 1", "a"])))
            elif rng.random() < 0.02 * (seed % 4):
                cells.append(str(rng.choice(_CELLS)))
            elif c.startswith("q") and rng.random() < 0.3:
                cells.append("")
            else:
                cells.append(repr(float(rng.uniform(-6, 6))) if rng.random() < 0.5 else f"{rng.uniform(-3, 3):.6f}")
        lines.append(",".join(cells))
        if seed % 5 == 0 and rng.random() < 0.05:
            lines.append(str(rng.choice(["", "# comment between rows", "   "])))
    p = write(tmp_path, "\n".join(lines) + ("\n" if seed % 2 else ""))
    for kw in ({}, {"degrees": True}, {"sweeps": False}):
        fast, exact = _both(p, monkeypatch, **kw)
        assert _same(fast, exact), (kw, fast, exact)


def test_column_reader_reads_a_plain_grid(tmp_path, monkeypatch):
    """The fast path is taken (not only the fallback) and gives the exact values: a file of
    70,000 rows (two chunks), a sweep column, empty cells, degrees."""
    from phantom_cad.calibration import fastcsv

    n = 70_000
    rng = np.random.default_rng(0)
    u = rng.uniform(0, 1.5, (n, 6))
    q = rng.uniform(0, 1, (n, 15))
    q[rng.random((n, 15)) < 0.4] = np.nan
    q[:, 0] = np.nan
    sweep = ["up" if k < n // 2 else "down" for k in range(n)]
    p = tmp_path / "big.csv"
    write_measurements(p, u, q, sweep=sweep)
    calls = []
    real = fastcsv.parse_grid
    monkeypatch.setattr(fastcsv, "parse_grid", lambda *a, **k: calls.append(real(*a, **k)) or calls[-1])
    m = read_measurements(p)
    assert calls and calls[0] is not None
    exact = _exact(p, monkeypatch)
    assert _same(m, exact)
    assert m.sweep_ids == ("up", "down") and m.lines[0] == 2 and m.lines[-1] == n + 1
    # written in fixed point with 12 decimals: within 0.5e-12 rad (+ the rounding of the scaling)
    assert np.abs(m.u - u).max() <= 0.51e-12
    assert np.array_equal(np.isnan(m.q), np.isnan(q))
    assert np.abs(m.q - q)[~np.isnan(q)].max() <= 0.51e-12


def test_fixed_point_text_known_answers():
    """The writer's number format, against values written by hand."""
    from phantom_cad.calibration.fastcsv import format_grid

    x = np.array([0.0, -0.0, 1.0, -1.5, 0.5, 4e-13, 6e-13, -6e-13, 0.9999999999999, 10.0, 100.5, 1000.25,
                  np.nan, -2.5e-5, 0.1 + 0.2, 3.14159265358979, 2.5e6, -np.inf])
    text = format_grid({"a": x, "s": ["a", "b,c", ' d', 'e"f', "g", "h", "i", "j", "k", "l", "m", "n", "o", "p", "q",
                                      "r", "s", "t"]}).decode()
    assert text.splitlines() == [
        "0.0,a", "0.0,\"b,c\"", "1.0, d", "-1.5,\"e\"\"f\"", "0.5,g", "0.0,h", "0.000000000001,i",
        "-0.000000000001,j", "1.0,k", "10.0,l", "100.5,m", "1000.25,n", ",o", "-0.000025,p", "0.3,q",
        "3.14159265359,r", "2500000,s", "-inf,t"]


def test_compiled_parser_converts_numbers_as_float_does():
    """Every plain decimal form, on the compiled fast path (one multiplication or division by an
    exact power of ten) and on its fallback (numpy's parser for 17-digit mantissas and large
    exponents): the same double as Python's float(), bit for bit, signed zeros included."""
    from phantom_cad.calibration import fastcsv

    cells = ["0", "-0", "+0.000", "0.5", "-0.25", "+.5", "1.", "1e-3", "2.5E+0", "1E+1", "6.3", "-6.29",
             "3.14159265358979", "0.1", "0.30000000000000004", "1e-30", "5e-23", "1e22", "1e23",
             "12345678901234567890.5", "0.1234567890123456789", "9007199254740993", "9007199254740992",
             "0.000000000001", "-0.000025", "1000.25", "123456.123456789012", "4.9e-324", "1.7976931348623157e308"]
    rng = np.random.default_rng(0)
    cells += [repr(float(v)) for v in rng.normal(size=200) * 10.0 ** rng.integers(-30, 30, 200)]
    cells += [f"{v:.12f}" for v in rng.normal(size=200)]
    data = "".join(f"a,{c}\n" for c in cells).encode()
    got = fastcsv.parse_grid(data, ["sweep", "u1"], ["sweep"], [])
    assert got is not None
    values, text = got
    want = np.array([float(c) for c in cells])
    assert values["u1"].view(np.uint64).tolist() == want.view(np.uint64).tolist()
    assert list(text["sweep"]) == ["a"] * len(cells)
    # not plain decimal numbers: left to the exact reader
    for bad in ["0.0_1", "nan", "inf", "1e", ".", "-", "+", "0x1", " 1", "1 ", "1e+", "--1", "1.2.3", "1e5.5"]:
        assert fastcsv.parse_grid(f"a,0\na,{bad}\n".encode(), ["sweep", "u1"], ["sweep"], []) is None, bad
