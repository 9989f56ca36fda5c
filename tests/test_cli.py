"""The command line, run as a user runs it (a subprocess)."""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import tomli_w

from tests.test_model import Q_REF_STAR, U_STAR, easy_document

pytestmark = pytest.mark.slow     # each test runs the command line in processes of its own


def cli(*args, check=True):
    proc = subprocess.run([sys.executable, "-m", "phantom_cad", *map(str, args)],
                          capture_output=True, text=True)
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


def read_csv(path):
    import csv

    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    return list(csv.DictReader(lines))


def test_help_everywhere():
    for args in ([], ["params"], ["model"], ["model", "forward"], ["model", "inverse"], ["params", "show"]):
        proc = cli(*args, "--help")
        assert "Usage" in proc.stdout


def test_model_forward_known_answer(tmp_path, document):
    params = tmp_path / "easy.toml"
    params.write_text(tomli_w.dumps(easy_document(document)))
    inp = tmp_path / "u.csv"
    inp.write_text(f"# one pose\nu1,u2,u3,u4,u5,u6\n0,{U_STAR!r},0,0,0,0.25\n")
    out = tmp_path / "q.csv"
    cli("model", "forward", "--in", inp, "--out", out, "--params", params)
    row = read_csv(out)[0]
    assert float(row["u2"]) == pytest.approx(U_STAR)
    assert float(row["q5"]) == pytest.approx(Q_REF_STAR, abs=1e-11)       # index MCP, 30 deg
    assert float(row["q4"]) == pytest.approx(1.25 * Q_REF_STAR, abs=1e-11)
    assert float(row["q15"]) == pytest.approx(0.25)
    assert float(row["q1"]) == 0.0


def test_model_forward_degrees(tmp_path, document):
    params = tmp_path / "easy.toml"
    params.write_text(tomli_w.dumps(easy_document(document)))
    inp = tmp_path / "u.csv"
    inp.write_text(f"u1,u2,u3,u4,u5,u6\n0,{math.degrees(U_STAR)!r},0,0,0,0\n")
    out = tmp_path / "q.csv"
    cli("model", "forward", "--in", inp, "--out", out, "--params", params, "--degrees")
    assert float(read_csv(out)[0]["q5"]) == pytest.approx(30.0, abs=1e-9)


def test_model_inverse_degrees(tmp_path, document):
    params = tmp_path / "easy.toml"
    params.write_text(tomli_w.dumps(easy_document(document)))
    q = [0.0] * 15
    q[2], q[3], q[4] = 30.0, 37.5, 30.0          # index DIP, PIP, MCP on the 4:5:4 curve, degrees
    inp = tmp_path / "q.csv"
    inp.write_text(",".join(f"q{i + 1}" for i in range(15)) + "\n" + ",".join(map(str, q)) + "\n")
    out = tmp_path / "u.csv"
    cli("model", "inverse", "--in", inp, "--out", out, "--params", params, "--degrees", "--ideal")
    row = read_csv(out)[0]
    assert float(row["u2"]) == pytest.approx(math.degrees(U_STAR), abs=1e-9)
    assert float(row["u1"]) == 0.0


def test_model_round_trip_through_files(tmp_path):
    inp = tmp_path / "u.csv"
    rows = ["sweep,u1,u2,u3,u4,u5,u6"]
    for k in range(11):
        v = 0.1 * k
        rows.append(f"{'a' if k < 6 else 'b'},{v},{v},{v},{v},{v},{min(v, 1.5)}")
    inp.write_text("\n".join(rows) + "\n")
    q = tmp_path / "q.csv"
    u = tmp_path / "u_back.csv"
    cli("model", "forward", "--in", inp, "--out", q, "--compensated")
    cli("model", "inverse", "--in", q, "--out", u)
    back = read_csv(u)
    assert [r["sweep"] for r in back] == ["a"] * 6 + ["b"] * 5
    for k, r in enumerate(back):
        for j in range(1, 7):
            assert float(r[f"u{j}"]) == pytest.approx(min(0.1 * k, 1.5) if j == 6 else 0.1 * k, abs=1e-9)


def test_bad_input_file_names_line_and_column(tmp_path):
    inp = tmp_path / "u.csv"
    inp.write_text("u1,u2,u3,u4,u5,u6\n0,0,0,0,0,0\n0,abc,0,0,0,0\n")
    proc = cli("model", "forward", "--in", inp, "--out", tmp_path / "q.csv", check=False)
    assert proc.returncode == 2
    assert proc.stderr.strip() == f"error: {inp}, line 3, column u2: 'abc' is not a number"
    assert not (tmp_path / "q.csv").exists()


def test_degrees_in_a_radian_file(tmp_path):
    inp = tmp_path / "u.csv"
    inp.write_text("u1,u2,u3,u4,u5,u6\n0,45,0,0,0,0\n")
    proc = cli("model", "forward", "--in", inp, "--out", tmp_path / "q.csv", check=False)
    assert proc.returncode == 2
    assert proc.stderr.strip() == (f"error: {inp}, line 2, column u2: 45 looks like degrees "
                                   "(angles are radians, |angle| <= 2 pi); convert it or pass --degrees")


def test_inverse_needs_all_joints(tmp_path):
    inp = tmp_path / "q.csv"
    inp.write_text("q1,q2\n0,0\n")
    proc = cli("model", "inverse", "--in", inp, "--out", tmp_path / "u.csv", check=False)
    assert proc.returncode == 2
    assert proc.stderr.strip() == f"error: {inp}, line 1, column q3: required column is missing"


def test_params_validate_good_and_bad(tmp_path, document):
    proc = cli("params", "validate")
    assert proc.stdout.startswith("OK ")
    document["fingers"]["index"]["pulley_radius_mm"]["dip"] = 0
    bad = tmp_path / "bad.toml"
    bad.write_text(tomli_w.dumps(document))
    proc = cli("params", "validate", bad, check=False)
    assert proc.returncode == 2
    assert proc.stderr.strip() == f"error: {bad}: fingers.index.pulley_radius_mm.dip = 0: must be > 0"


def test_params_show_prints_derived_quantities():
    out = cli("params", "show").stdout
    assert "ip: 0.8000 / 0.7915" in out or "ip: 0.8000 /" in out   # thumb coupling from 5:4 radii
    assert "pip: 1.2500 /" in out
    assert "q15  thumb_cmc" in out
    assert "opposition (thumb pad to fingertip pad" in out and "(not required)" in out


def test_params_opposition_solves_a_placement_the_file_then_reaches(tmp_path):
    """--solve prints parameter-file lines; pasted into a copy of the file, the hand they describe
    is read back through the parameter path, validates (the palm's thenar holds the CMC there) and
    its thumb meets the three pads."""
    import re
    import tomllib

    from phantom_cad.params import DEFAULT_PARAMS

    out = cli("params", "opposition", "--solve").stdout
    assert "index   pads -" in out                  # the file's own placement already meets them
    assert "the palm's thenar holds it within a palm of human breadth" in out
    lines = out[out.index("[palm]"):].splitlines()
    solved = tomllib.loads("\n".join(lines))["palm"]
    text = Path(DEFAULT_PARAMS).read_text()
    for key in ("thumb_cmc_offset_mm", "thumb_cmc_axis_deg"):
        text, n = re.subn(rf"^{key} = \[[^\]]*\]", f"{key} = {solved[key]}", text, flags=re.M)
        assert n == 1
    # the pockets' lift the placement needs, in place of the file's
    text = re.sub(r"^magnet_lift_mm = .*\n", "", text, flags=re.M)
    text = text.replace("\n[palm]\n", f"\n[palm]\nmagnet_lift_mm = {solved['magnet_lift_mm']}\n", 1)
    f = tmp_path / "solved.toml"
    f.write_text(text)
    again = cli("params", "opposition", "-p", f).stdout
    for finger in ("index", "middle", "ring"):
        row = next(ln for ln in again.splitlines() if ln.strip().startswith(finger))
        pad = float(re.search(r"pads ([+-][0-9.]+) mm", row).group(1))
        margin = float(re.search(r"margin ([+-][0-9.]+) deg", row).group(1))
        assert pad <= 0.0 and margin > 0.0, row
    assert "pinky" in again and "(not required)" in again
    assert cli("params", "validate", "-p", f).returncode == 0


def test_params_opposition_pads_face_holds_the_normals():
    """--pads-face prints the reach with the pads' normals held within PAD_OPPOSE of facing: the
    margins of ``opposition.reach(hand, oppose=PAD_OPPOSE)``, to the printed tenth of a degree."""
    import re

    from phantom_cad.kinematics import opposition
    from phantom_cad.kinematics.model import Hand
    from phantom_cad.params.io import load_params

    out = cli("params", "opposition", "--pads-face").stdout
    assert "the pads' normals within 30 deg of facing each other" in out
    want = opposition.reach(Hand(load_params(None)), fingers=opposition.OPPOSED, oppose=opposition.PAD_OPPOSE)
    for finger, r in want.items():
        row = next(ln for ln in out.splitlines() if ln.strip().startswith(finger))
        assert float(re.search(r"margin ([+-][0-9.]+) deg", row).group(1)) == pytest.approx(math.degrees(r.margin), abs=0.05)


def test_model_commands_never_import_cad(tmp_path):
    inp = tmp_path / "u.csv"
    inp.write_text("u1,u2,u3,u4,u5,u6\n0,0.5,0,0,0,0\n")
    code = textwrap.dedent(f"""
        import sys
        from phantom_cad.cli import app
        import phantom_cad
        phantom_cad.load_hand().inverse([0.1] * 15)
        try:
            app(["model", "forward", "--in", {str(inp)!r}, "--out", {str(tmp_path / 'q.csv')!r}],
                standalone_mode=False)
            app(["params", "show"], standalone_mode=False)
        finally:
            heavy = sorted(m for m in sys.modules if m.split(".")[0] in ("OCP", "build123d", "cadquery"))
            print("HEAVY", heavy)
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "HEAVY []" in proc.stdout


@pytest.fixture(scope="module")
def small_sweep(tmp_path_factory):
    """A five-point simulated sweep (read, never written, by the tests that take it)."""
    sweep = tmp_path_factory.mktemp("sweep") / "sweep.csv"
    cli("simulate", "--points", "5", "--out", sweep)
    return sweep


@pytest.mark.parametrize("command", [
    ["build", "--no-slice", "--out"],
    ["compare", "{sweep}", "--report"],
    ["diagnose", "{sweep}", "--candidates", "joint_offset", "--report"],
])
@pytest.mark.parametrize("victim", ["file", "folder"])
def test_outputs_never_replace_user_data(tmp_path, small_sweep, command, victim):
    """An output never replaces user data: `build -o params/phantom.toml` (a typo for -p) must not
    replace the parameter file with an export folder, nor `--out mydata` / `--report mydata`
    delete what the folder holds."""
    sweep = small_sweep
    target = tmp_path / "mydata"
    if victim == "file":
        target.write_text("my parameters\n")
    else:
        target.mkdir()
        (target / "thesis.tex").write_text("three years of work\n")
    before = sorted(p.read_text() for p in ([target] if target.is_file() else target.iterdir()))
    r = cli(*[a.format(sweep=sweep) for a in command], target, check=False)
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith(f"error: {target}: exists and is not ")
    assert "refusing to replace it" in r.stderr and "Traceback" not in r.stderr
    after = sorted(p.read_text() for p in ([target] if target.is_file() else target.iterdir()))
    assert after == before


@pytest.mark.parametrize("command", [("params", "validate", "{file}"),
                                     ("build", "--params", "{file}", "--out", "{out}"),
                                     ("check", "--params", "{file}", "--out", "{out}")])
def test_every_command_checks_the_effects_table(tmp_path, document, command):
    """The params layer checks [effects.*] with the effect library its caller hands it: a command
    that builds refuses the file as `params validate` does, before anything is built or written."""
    document["effects"] = {"tendon_slack": {"bogus": 3.0}}
    bad = tmp_path / "bad.toml"
    bad.write_text(tomli_w.dumps(document))
    out = tmp_path / "out"
    proc = cli(*(a.format(file=bad, out=out) for a in command), check=False)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().splitlines()[-1] == (
        f"error: {bad}: effects.tendon_slack.bogus = 3.0: unknown parameter of tendon_slack "
        "(allowed: u1_deg, u2_deg, u3_deg, u4_deg, u5_deg)")
    assert not out.exists()


def test_params_validate_goes_on_after_a_bad_file(tmp_path):
    """A multi-file `params validate` reports every file: one unreadable file does not abort it."""
    from phantom_cad.params import DEFAULT_PARAMS

    binary = tmp_path / "binary.toml"
    binary.write_bytes(b"\xff\xfe\x00")
    r = cli("params", "validate", DEFAULT_PARAMS, binary, tmp_path, DEFAULT_PARAMS, check=False)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert r.stdout.count(f"OK {DEFAULT_PARAMS}") == 2
    assert r.stderr.splitlines() == [
        f"error: <file> = {str(binary)!r}: is not UTF-8 text (invalid start byte at byte 0)",
        f"error: <file> = {str(tmp_path)!r}: is a folder, not a parameter file"]


def test_model_warns_outside_the_travel_and_strict_refuses(tmp_path):
    """`model forward` warns about servo angles outside the travel (the model extrapolates there)
    and --strict refuses them. 5 rad of servo 2 is beyond any travel (the cosine law of the
    default index has its end at 1.62 rad); a joint target of -0.5 rad is below the joint's
    lower limit of 0 in the parameter file."""
    far = tmp_path / "far.csv"
    far.write_text("u1,u2,u3,u4,u5,u6\n0,0,0,0,0,0\n0,5,0,0,0,0\n")
    r = cli("model", "forward", "--in", far, "--out", tmp_path / "q.csv")
    assert r.stderr.startswith(f"warning: {far}, line 3, column u2: 5 rad is outside [0, ")
    assert "1 of 2 rows have servo angles outside the travel; the model extrapolates there" in r.stderr
    r = cli("model", "forward", "--in", far, "--out", tmp_path / "strict.csv", "--strict", check=False)
    assert r.returncode == 2 and r.stderr.startswith(f"error: {far}, line 3, column u2: 5 rad is outside")
    assert not (tmp_path / "strict.csv").exists()
    inside = tmp_path / "inside.csv"
    inside.write_text("u1,u2,u3,u4,u5,u6\n0,0,0,0,0,0\n0,0.5,0,0,0,0\n")
    r = cli("model", "forward", "--in", inside, "--out", tmp_path / "q2.csv", "--strict")
    assert r.stderr == ""
    targets = tmp_path / "targets.csv"
    targets.write_text(",".join(f"q{i}" for i in range(1, 16)) + "\n" + ",".join(["0"] * 2 + ["-0.5"] + ["0"] * 12)
                       + "\n")
    r = cli("model", "inverse", "--in", targets, "--out", tmp_path / "u.csv")
    assert r.stderr.startswith(f"warning: {targets}, line 2, column q3: -0.5 rad is outside [0, ")
    assert "joint targets outside the workspace; the control law clips them" in r.stderr
    r = cli("model", "inverse", "--in", targets, "--out", tmp_path / "u2.csv", "--strict", check=False)
    assert r.returncode == 2 and not (tmp_path / "u2.csv").exists()
