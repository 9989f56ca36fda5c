"""`fit --robust` from the command line: a few large vision glitches written into data with hidden
joint offsets (both written out in test_noise_floor, never simulate); the fit lists the glitched
cells as outliers (sweep, row, file line, joint) and its offsets stay at the truth, where least
squares is pulled off by the glitches."""

import re

import pytest

from phantom_cad.calibration.data import write_measurements
from phantom_cad.calibration.labels import Labels
from phantom_cad.params import load_document

from ._cli import run_cli as run
from .test_noise_floor import GLITCHES, OFFSETS, glitched_data

pytestmark = pytest.mark.slow     # each test runs the command line in processes of its own



@pytest.fixture(scope="module")
def data(hand, tmp_path_factory):
    d = tmp_path_factory.mktemp("robust")
    m = glitched_data(hand)
    write_measurements(d / "data.csv", m.u, m.q, sweep=Labels(m.sweep_ids, m.sweep), q_columns=m.q_columns)
    return d, m


def offsets(path):
    table = load_document(path)["effects"]["joint_offset"]
    return {int(k[1:].split("_")[0]) - 1: v for k, v in table.items()}


def test_fit_robust_lists_the_glitches_and_keeps_the_truth(data):
    d, m = data
    r = run("fit", d / "data.csv", "--effects", "joint_offset", "--robust", "--out", d / "robust.toml")
    assert r.returncode == 0, r.stderr
    line = next(t for t in r.stdout.splitlines() if t.startswith("outliers ("))
    assert line.startswith(f"outliers ({len(GLITCHES)} cells beyond 5 noise sd")
    listed = re.findall(r"sweep (\w+) row (\d+) \(line (\d+)\) (q\d+) ([+-][0-9.]+)", line)
    # the file has no comment line: row k is on line k + 2 (after the header)
    expected = {(m.sweep_ids[m.sweep[row]], row, row + 2, f"q{j + 1}") for row, j, _ in GLITCHES}
    assert {(s, int(row), int(ln), q) for s, row, ln, q, _ in listed} == expected
    for s, row, ln, q, res in listed:
        glitch = next(g for rr, j, g in GLITCHES if rr == int(row))
        assert float(res) == pytest.approx(glitch, abs=0.5)       # the glitch plus noise
    fitted = offsets(d / "robust.toml")
    for j in {j for _, j, _ in GLITCHES} | set(OFFSETS):
        assert fitted.get(j, 0.0) == pytest.approx(OFFSETS.get(j, 0.0), abs=0.05), j
    text = (d / "robust.toml").read_text()
    assert "--effects joint_offset --robust`" in text
    assert f"{len(GLITCHES)} cells beyond the outlier limit (5 noise sd)" in text


def test_least_squares_is_bent_by_the_glitches(data):
    d, m = data
    r = run("fit", d / "data.csv", "--effects", "joint_offset", "--out", d / "ls.toml")
    assert r.returncode == 0, r.stderr
    assert f"outliers ({len(GLITCHES)} cells beyond 5 noise sd; --robust keeps them from bending the fit)" in r.stdout
    ls = offsets(d / "ls.toml")
    err_ls = max(abs(ls.get(j, 0.0) - OFFSETS.get(j, 0.0)) for _, j, _ in GLITCHES)
    # a glitch of g deg on one of n cells moves that joint's offset by about g / n (n = 60 here)
    assert err_ls > 0.1
