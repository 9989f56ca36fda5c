"""The walk-through of docs/effects.md ("From an unexplained residual to your own effect") runs as
printed: its commands are those of docs/examples/servo_ripple/walkthrough.py, every output line the
page quotes is in that command's output (numbers within the last printed digit), the fitted
amplitudes are the hidden ones worked out by hand, and the calibrated control law drives the hand
with the hidden ripple to its targets."""

import importlib.util
import math
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "effects.md"
NUMBER = re.compile(r"[-+]?\d+\.\d+|[-+]?\d+")


def _walkthrough():
    spec = importlib.util.spec_from_file_location("walkthrough", ROOT / "docs/examples/servo_ripple/walkthrough.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


WT = _walkthrough()


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    d = tmp_path_factory.mktemp("walkthrough")
    return d, WT.run(d)


def doc_blocks() -> list[tuple[str, list[str]]]:
    """(command, quoted output lines) of every "$ " line in the walk-through's text blocks."""
    text = DOC.read_text()
    section = text[text.index("## From an unexplained residual to your own effect"):]
    section = section[:section.find("\n## ", 5)] if "\n## " in section[5:] else section
    out = []
    for block in re.findall(r"```text\n(.*?)```", section, re.S):
        for line in block.splitlines():
            if line.startswith("$ "):
                out.append((line[2:], []))
            elif line.strip():
                out[-1][1].append(line)
    return out


def same_line(quoted: str, output: str) -> bool:
    """``quoted`` is a line of ``output`` with the same words and every number equal to the last
    digit it prints (one unit of it: a different machine's last bit may round the other way)."""
    skeleton = NUMBER.sub("#", quoted)
    want = NUMBER.findall(quoted)
    for line in output.splitlines():
        if NUMBER.sub("#", line) != skeleton:
            continue
        got = NUMBER.findall(line)
        if all(abs(float(g) - float(w)) <= 1.01 * 10.0 ** -(len(w.split(".")[1]) if "." in w else 0)
               for g, w in zip(got, want)):
            return True
    return False


def test_the_page_prints_the_commands_that_run():
    assert [c for c, _ in doc_blocks()] == WT.COMMANDS


@pytest.mark.slow
def test_every_quoted_line_is_in_the_output(run):
    _, outputs = run
    for command, quoted in doc_blocks():
        for line in quoted:
            assert same_line(line, outputs[command]), f"{command}: not in its output: {line}"


@pytest.mark.slow
def test_the_library_alone_does_not_explain_it_and_says_what_it_sees(run):
    d, _ = run
    import json

    out = json.loads((d / "report_analytic" / "diagnosis.json").read_text())
    assert out["explained"] is False
    assert set(out["left"]) == {"q3", "q4", "q5", "q9", "q10", "q11"}
    assert abs(out["signature"]["before"]["periodic"]["period_deg"] - 40.0) <= 2.0
    assert out["mae_deg_after"] > 3 * out["noise_floor_deg"]


@pytest.mark.slow
def test_with_the_plugin_it_is_explained_and_the_amplitudes_are_the_hidden_ones(run):
    d, _ = run
    import json

    out = json.loads((d / "report_plugin" / "diagnosis.json").read_text())
    assert out["selected"] == ["servo_ripple"] and out["explained"] is True
    assert out["mae_deg_after"] <= 1.5 * out["noise_floor_deg"]
    p = out["effects"]["servo_ripple"]["parameters"]
    # a sin(w u) + b (cos(w u) - 1) = A (sin(w u + phi) - sin(phi)): a = A cos(phi), b = A sin(phi)
    hidden = {2: (1.5, 0.6), 4: (1.2, -1.1)}
    for servo in range(1, 6):
        A, phi = hidden.get(servo, (0.0, 0.0))
        for key, want in (("a", A * math.cos(phi)), ("b", A * math.sin(phi))):
            got = p[f"u{servo}_{key}_deg"]
            assert abs(got["value"] - want) <= max(3.0 * got["std"], 0.005), (servo, key, got, want)


@pytest.mark.slow
def test_the_calibrated_control_law_reaches_the_targets(run):
    d, _ = run
    u, err_nominal, err_cal = WT.control_law_errors(d / "cal" / "calibrated.toml")
    index = [2, 3, 4]
    assert np.abs(err_nominal[:, index]).max() > 2.0                 # the ripple, uncorrected
    assert np.abs(err_cal[:-1, index]).max() < 0.05                  # corrected, short of the travel's end
    assert np.abs(err_cal[:, index]).mean() < 0.02
    # the other digits are untouched by either
    assert np.abs(err_cal[:, [j for j in range(15) if j not in index]]).max() < 1e-9


def test_the_plugin_is_25_lines_of_code():
    lines = (ROOT / "docs/examples/servo_ripple/servo_ripple.py").read_text().splitlines()
    code = [x for x in lines if x.strip() and not x.strip().startswith(("#", '"""'))]
    assert len(code) <= 25


def test_the_page_shows_the_plugin_as_it_is():
    text = DOC.read_text()
    section = text[text.index("## From an unexplained residual to your own effect"):]
    shown = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    assert shown.strip() in (ROOT / "docs/examples/servo_ripple/servo_ripple.py").read_text()
