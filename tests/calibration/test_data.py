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
    """Issue 8, defect 8: float() accepts underscores and non-ASCII digits; a CSV does not."""
    path = tmp_path / "m.csv"
    path.write_text(f"u1,u2,u3,u4,u5,u6\n0,0,0,0,0,0\n0,{cell},0,0,0,0\n", encoding="utf-8")
    with pytest.raises(DataError) as exc:
        read_measurements(path)
    assert str(exc.value) == f"{path}, line 3, column u2: '{cell}' is not a number"


def test_byte_order_mark_and_folders(tmp_path):
    """Issue 8, defect 7: a UTF-8 BOM was reported as "column sweep: unknown column"; a folder
    given as the file gave a traceback."""
    path = tmp_path / "bom.csv"
    path.write_text("\ufeffu1,u2,u3,u4,u5,u6\n0,0,0,0,0,0\n0,0.5,0,0,0,0\n", encoding="utf-8")
    assert read_measurements(path).u[1, 1] == 0.5
    with pytest.raises(DataError) as exc:
        read_measurements(tmp_path)
    assert str(exc.value) == f"{tmp_path}: is a folder, not a CSV file"
