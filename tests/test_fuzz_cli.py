"""Every command, every bad input: one line ``error: ...``, exit 2, no traceback, nothing written
(the fuzz test of that rule).

The commands run in-process through the entry point ``phantom_cad.cli.main`` (what the
``phantom-cad`` script and ``python -m phantom_cad`` call), so a few hundred cases take seconds;
tests/test_cli.py runs the same entry point as a subprocess.
"""

from __future__ import annotations

import os
import shutil
import stat

import pytest

from phantom_cad.cli import main
from phantom_cad.params import DEFAULT_PARAMS

GOOD_CSV = ("# phantom-cad simulate (hand-written for the fuzz test)\n"
            "sweep,u1,u2,u3,u4,u5,u6,q1,q2,q3,q4,q5,q6,q7,q8,q9,q10,q11,q12,q13,q14,q15\n"
            + "".join(f"s,0,{0.1 * k},0,0,0,0,,,{0.05 * k},{0.05 * k},{0.04 * k},,,,,,,,,,\n" for k in range(6)))


def _fixtures(d):
    """The bad inputs of the issue, made in folder ``d``; returns {name: path}."""
    (d / "good.csv").write_text(GOOD_CSV)
    (d / "good.toml").write_bytes(DEFAULT_PARAMS.read_bytes())
    (d / "binary").write_bytes(b"\x00\xff\xfe\x89PNG\r\n\x1a\n" * 4)
    (d / "latin1").write_bytes("name = 'main caf\xe9'\n".encode("latin-1"))
    (d / "bom.csv").write_bytes(b"\xef\xbb\xbf" + b"u1,u2\n1,2\n")
    (d / "empty").write_text("")
    (d / "garbage").write_text("this is ] not [ toml, nor, a csv\n\"unclosed\n")
    (d / "folder").mkdir()
    (d / "folder" / "keep.txt").write_text("a user's file\n")
    os.symlink(d / "loop_b", d / "loop_a")
    os.symlink(d / "loop_a", d / "loop_b")
    (d / "userfile").write_text("three years of work\n")
    return {
        "binary": "binary", "latin1": "latin1", "empty": "empty", "garbage": "garbage", "folder": "folder",
        "loop": "loop_a", "missing": "missing.txt", "bom": "bom.csv",
    }


def _readonly(d):
    """A folder nothing can be created in (root ignores permission bits: /sys refuses even root)."""
    if os.geteuid() == 0:
        return "/sys/phantom_fuzz/out"
    ro = d / "readonly"
    ro.mkdir()
    ro.chmod(stat.S_IRUSR | stat.S_IXUSR)
    return str(ro / "out")


# commands with their good arguments; {P} parameter file, {IN} data file, {OUT} output path
COMMANDS = {
    "params validate": ["params", "validate", "{P}"],
    "params show": ["params", "show", "-p", "{P}"],
    "force": ["force", "-p", "{P}"],
    "model forward": ["model", "forward", "--in", "{IN}", "--out", "{OUT}", "-p", "{P}"],
    "model inverse": ["model", "inverse", "--in", "{IN}", "--out", "{OUT}", "-p", "{P}"],
    "simulate": ["simulate", "--points", "3", "--out", "{OUT}", "-p", "{P}"],
    "compare": ["compare", "{IN}", "--report", "{OUT}", "-p", "{P}"],
    "diagnose --json": ["diagnose", "{IN}", "--candidates", "joint_offset", "--json", "{OUT}", "-p", "{P}"],
    "diagnose --report": ["diagnose", "{IN}", "--candidates", "joint_offset", "--report", "{OUT}", "-p", "{P}"],
    "fit": ["fit", "{IN}", "--effects", "joint_offset", "--out", "{OUT}", "-p", "{P}"],
    "build": ["build", "--no-slice", "--no-render", "--out", "{OUT}", "-p", "{P}"],
    "demo": ["demo", "--no-slice", "--out", "{OUT}", "-p", "{P}"],
    "pose": ["pose", "fist", "-p", "{P}"],
}
READS_DATA = [c for c, a in COMMANDS.items() if "{IN}" in a]
WRITES = [c for c, a in COMMANDS.items() if "{OUT}" in a]
BAD_FILES = ["binary", "latin1", "empty", "garbage", "folder", "loop", "missing"]
BAD_OUTPUTS = ["parent is a file", "read-only folder", ".", "", "user file", "user folder"]

CASES = (
    [(c, "params", bad) for c in COMMANDS for bad in BAD_FILES]
    + [(c, "data", bad) for c in READS_DATA for bad in BAD_FILES + ["bom"]]
    + [(c, "out", bad) for c in WRITES for bad in BAD_OUTPUTS]
)


def _tree(d):
    """Every path under ``d`` with its content (files) or None (folders, links)."""
    out = {}
    for root, dirs, files in os.walk(d):
        for name in dirs + files:
            p = os.path.join(root, name)
            out[p] = open(p, "rb").read() if os.path.isfile(p) and not os.path.islink(p) else None
    return out


def run(argv, capsys):
    with pytest.raises(SystemExit) as exit_:
        main([str(a) for a in argv])
    cap = capsys.readouterr()
    return exit_.value.code, cap.out, cap.err


@pytest.mark.parametrize("command, slot, bad", CASES, ids=[f"{c}-{s}-{b or 'empty-string'}" for c, s, b in CASES])
@pytest.mark.slow
def test_bad_input_is_one_error_line(tmp_path, monkeypatch, capsys, command, slot, bad):
    monkeypatch.chdir(tmp_path)
    files = _fixtures(tmp_path)
    values = {"P": "good.toml", "IN": "good.csv", "OUT": "new_output"}
    if slot == "params":
        values["P"] = files[bad]
    elif slot == "data":
        values["IN"] = files[bad]
    else:
        values["OUT"] = {"parent is a file": "userfile/out", "read-only folder": _readonly(tmp_path),
                         ".": ".", "": "", "user file": "userfile", "user folder": "folder"}[bad]
    argv = [a.format(**values) for a in COMMANDS[command]]
    before = _tree(tmp_path)
    code, out, err = run(argv, capsys)
    assert "Traceback" not in err + out
    assert code == 2, (argv, err)
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), (argv, err)
    assert _tree(tmp_path) == before, "a refused command changed the folder"


@pytest.mark.parametrize("argv, message", [
    (["build", "--bogus"], "No such option: --bogus"),
    (["build", "--jobs", "0"], "Invalid value for '--jobs' / '-j'"),
    (["simulate", "--seed", "x", "--out", "x.csv"], "Invalid value for '--seed'"),
    (["simulate", "--seed", "-1", "--out", "x.csv"], "--seed -1: must be >= 0"),
    (["simulate", "--noise-deg", "nan", "--out", "x.csv"], "--noise-deg nan: must be a finite number >= 0"),
    (["simulate", "--travel", "inf", "--out", "x.csv"], "--travel"),
    (["model", "forward"], "Missing option '--in'"),
    (["simulate", "--points", "1", "--out", "x.csv"], "--points 1: must be in [2, 100000]"),
    (["nosuch"], "No such command 'nosuch'"),
    (["fit", "good.csv", "--effects", "", "--out", "x.toml"], "--effects: name at least one effect"),
    (["fit", "good.csv", "--effects", "gravity", "--out", "x.toml"], "unknown effect 'gravity'"),
    (["build", "--side", "middle"], "hand.side = 'middle': must be one of: right, left"),
    (["diagnose", "good.csv", "--candidates", "magic"], "unknown effect 'magic'"),
])
def test_bad_options_are_one_error_line(tmp_path, monkeypatch, capsys, argv, message):
    """Click's usage errors (printed by typer as a framed multi-line box) and our own option rules."""
    monkeypatch.chdir(tmp_path)
    _fixtures(tmp_path)
    before = _tree(tmp_path)
    code, out, err = run(argv, capsys)
    assert code == 2 and "Traceback" not in err
    assert len(err.splitlines()) == 1 and err.startswith("error: ") and message in err, err
    assert _tree(tmp_path) == before


def test_a_newline_in_a_file_name_stays_one_line(tmp_path, monkeypatch, capsys):
    """`fit` with a newline in the data file name writes a valid TOML: the name in the header
    comment stays on one line."""
    monkeypatch.chdir(tmp_path)
    _fixtures(tmp_path)
    data = "two\nlines.csv"
    shutil.copy("good.csv", data)
    code, out, err = run(["fit", data, "--effects", "joint_offset", "--out", "cal.toml", "-p", "good.toml"], capsys)
    assert code == 0, err
    import tomllib

    text = (tmp_path / "cal.toml").read_text()
    assert text.splitlines()[0] == "# Calibrated by `phantom-cad fit two\\nlines.csv --effects joint_offset`"
    tomllib.loads(text)
    code, out, err = run(["compare", "no\nsuch.csv"], capsys)
    assert code == 2 and err == "error: no\\nsuch.csv: no such file\n"


def test_internal_errors_are_one_line_too(tmp_path, monkeypatch, capsys):
    """A defect of phantom-cad itself (here: forced) is one line and exit 1, not a traceback;
    PHANTOM_CAD_DEBUG=1 shows the traceback."""
    import phantom_cad

    def broken(*a, **k):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(phantom_cad, "load_hand", broken)
    code, out, err = run(["params", "show"], capsys)
    assert code == 1
    assert err.startswith("error: internal error (ZeroDivisionError: float division by zero); please report")
    assert len(err.splitlines()) == 1
    monkeypatch.setenv("PHANTOM_CAD_DEBUG", "1")
    with pytest.raises(ZeroDivisionError):
        main(["params", "show"])


def test_outputs_of_the_same_kind_are_replaced(tmp_path, monkeypatch, capsys):
    """The refusal rule is not a refusal of everything: a command overwrites its own earlier output
    (recognised by its first line), and refuses another command's."""
    monkeypatch.chdir(tmp_path)
    _fixtures(tmp_path)
    for _ in range(2):
        assert run(["model", "forward", "--in", "good.csv", "--out", "q.csv"], capsys)[0] == 0
        assert run(["fit", "good.csv", "--effects", "joint_offset", "--out", "cal.toml"], capsys)[0] == 0
        assert run(["diagnose", "good.csv", "--candidates", "joint_offset", "--json", "d.json"], capsys)[0] == 0
    # a CSV written by phantom-cad is not a parameter file written by fit, nor a diagnosis
    code, out, err = run(["fit", "good.csv", "--effects", "joint_offset", "--out", "q.csv"], capsys)
    assert code == 2 and "exists and is not a parameter file written by phantom-cad fit" in err
    code, out, err = run(["diagnose", "good.csv", "--candidates", "joint_offset", "--json", "cal.toml"], capsys)
    assert code == 2 and "exists and is not a JSON written by phantom-cad diagnose" in err
    code, out, err = run(["simulate", "--out", "good.toml"], capsys)
    assert code == 2 and "exists and is not a CSV written by phantom-cad" in err
    assert (tmp_path / "good.toml").read_bytes() == DEFAULT_PARAMS.read_bytes()
