"""``phantom-cad view`` (phantom_cad/cli/view.py): the hand in the browser, driven by the model.

* without a browser: the link poses the viewer sends equal the forward kinematics of the URDF
  at the model's joint angles, computed here twice, independently of the viewer: by hand from the
  URDF's joint origins and axes, and with yourdfpy on a copy of the URDF without ``<mimic>``;
* in headless Chromium (selenium + chromedriver; skipped only when they are absent): the page
  loads, shows the six servo sliders and the parameter digest, keyboard input on a slider and a
  click on the compensated toggle change what the server computes (= ``hand.forward``), and the
  three.js canvas is not blank;
* the command's error path: one line ``error: ...``, exit 2.

The default hand is exported once (module fixture, into a folder of its own, with the session's
part cache). docs/viewer.md.
"""

from __future__ import annotations

import io
import math
import re
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from phantom_cad.kinematics.topology import JOINTS, LINK_NAMES, SERVOS

pytest.importorskip("viser")
pytest.importorskip("yourdfpy")

#: builds the default hand and drives headless Chromium
pytestmark = pytest.mark.slow

CHROMIUM = Path("/usr/bin/chromium")
CHROMEDRIVER = Path("/usr/bin/chromedriver")
#: flags that work on a closed-network machine as root; the last three give WebGL in software
CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                  "--window-size=1280,800")


@pytest.fixture(scope="module")
def export(tmp_path_factory, part_cache):
    """The default hand's export (robot description included), built with the session's part cache."""
    pytest.importorskip("build123d")
    from phantom_cad.export.pipeline import build_hand

    root = tmp_path_factory.mktemp("viewer")
    result = build_hand(None, root / "exports" / "phantom", cache_dir=part_cache, jobs=2, slice=False)
    return result.out_dir


@pytest.fixture(scope="module")
def model():
    from phantom_cad import load_hand

    return load_hand()


@pytest.fixture
def viewer(export):
    from phantom_cad.cli.view import start_viewer

    messages = []
    v = start_viewer(None, export, host="127.0.0.1", port=0, log=messages.append)
    assert messages == []      # the export is current: nothing to build
    yield v
    v.stop()


# -- independent forward kinematics ----------------------------------------------------

def _rot(axis, angle) -> np.ndarray:
    """Rodrigues: rotation by ``angle`` about the unit vector ``axis``."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _rpy(r, p, y) -> np.ndarray:
    return _rot((0, 0, 1), y) @ _rot((0, 1, 0), p) @ _rot((1, 0, 0), r)


def urdf_fk_by_hand(urdf: Path, angles: dict[str, float]) -> dict[str, np.ndarray]:
    """Every link's pose in the root link's frame: 4x4, from the URDF's joint origins and axes
    (URDF convention: T_child = T_parent @ origin @ rot(axis, q)); joints not in ``angles``
    (fixed, or a revolute joint we do not set) at 0, ``<mimic>`` ignored."""
    root = ET.parse(urdf).getroot()
    joints = {}
    for j in root.iter("joint"):
        o = j.find("origin")
        xyz = [float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
        rpy = [float(v) for v in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
        a = j.find("axis")
        axis = [float(v) for v in a.get("xyz").split()] if a is not None else [1.0, 0.0, 0.0]
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = _rpy(*rpy), xyz
        joints[j.find("child").get("link")] = (j.find("parent").get("link"), T, axis, j.get("name"), j.get("type"))
    links = [ln.get("name") for ln in root.iter("link")]
    poses = {ln: np.eye(4) for ln in links if ln not in joints}
    assert len(poses) == 1, "one root link"

    def pose(link):
        if link not in poses:
            parent, T, axis, name, kind = joints[link]
            M = np.eye(4)
            if kind in ("revolute", "continuous"):
                M[:3, :3] = _rot(axis, angles.get(name, 0.0))
            poses[link] = pose(parent) @ T @ M
        return poses[link]

    return {ln: pose(ln) for ln in links}


def urdf_fk_yourdfpy(urdf: Path, angles: dict[str, float], keep_mimic: bool = False) -> dict[str, np.ndarray]:
    """The same with yourdfpy: a copy of the URDF without its ``<mimic>`` elements (or with them,
    setting only the joints they do not drive), no meshes."""
    import yourdfpy

    text = urdf.read_text()
    if not keep_mimic:
        text = re.sub(r"<mimic\b[^>]*/>", "", text)
    model = yourdfpy.URDF.load(io.BytesIO(text.encode()), build_scene_graph=True, load_meshes=False)
    model.update_cfg({n: v for n, v in angles.items() if n in model.actuated_joint_names})
    return {ln: model.get_transform(ln, model.base_link) for ln in model.link_map}


def frame_pose(frame) -> np.ndarray:
    """The 4x4 pose a viser frame handle holds (wxyz quaternion, position), by hand."""
    w, x, y, z = np.asarray(frame.wxyz, float)
    T = np.eye(4)
    T[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                 [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                 [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    T[:3, 3] = frame.position
    return T


def shown_degrees(markdown: str) -> dict[str, float]:
    """label -> degrees of the viewer's joint table (``| q5 | index_mcp | 12.3456 |``)."""
    return {m.group(1): float(m.group(2)) for m in re.finditer(r"\|\s*([uq]\d+)\s*\|[^|]*\|\s*(-?[\d.]+)\s*\|",
                                                                markdown)}


# -- without a browser ------------------------------------------------------------------

def test_link_poses_follow_the_model_not_the_mimic_ratios(viewer, model):
    from phantom_cad.cli.view import SHOWN_DECIMALS

    assert viewer.params.digest == model.params.digest
    rng = np.random.default_rng(7)
    urdf = viewer.urdf_path
    for compensated in (False, True):
        u = model.u_min + rng.uniform(0.2, 0.9, len(SERVOS)) * (model.u_max - model.u_min)
        viewer.set_u(u, compensated=compensated)
        np.testing.assert_array_equal([s.value for s in viewer.sliders], u)
        q = model.forward(u, compensated=compensated)
        np.testing.assert_allclose(viewer.q, q, rtol=0, atol=1e-12)
        angles = {j.name: float(q[j.index]) for j in JOINTS}
        by_hand = urdf_fk_by_hand(urdf, angles)
        with_yourdfpy = urdf_fk_yourdfpy(urdf, angles)
        assert set(LINK_NAMES) <= set(viewer.frames)
        for link in viewer.frames:          # every link of the URDF (the pad frames too)
            shown = frame_pose(viewer.frames[link])
            np.testing.assert_allclose(shown, by_hand[link], rtol=0, atol=1e-9, err_msg=link)
            np.testing.assert_allclose(shown, with_yourdfpy[link], rtol=0, atol=1e-9, err_msg=link)
        # the URDF's <mimic> ratios are the analytic coupling: they give the analytic pose and
        # miss the compensated one (why the viewer sets every joint itself)
        mimic = urdf_fk_yourdfpy(urdf, angles, keep_mimic=True)
        gap = max(np.abs(frame_pose(viewer.frames[link]) - mimic[link]).max() for link in LINK_NAMES)
        assert gap < 1e-9 if not compensated else gap > 1e-4
        table = shown_degrees(viewer.joints_md.content)
        for j in JOINTS:
            assert table[j.label] == pytest.approx(math.degrees(q[j.index]), abs=0.6 * 10 ** -SHOWN_DECIMALS)
        for sv in SERVOS:
            assert table[sv.label] == pytest.approx(math.degrees(u[sv.index]), abs=0.6 * 10 ** -SHOWN_DECIMALS)
        assert f"**{'compensated' if compensated else 'analytic'}**" in viewer.joints_md.content


def test_gui_lists_servos_travel_and_digest(viewer, model):
    assert [s.label for s in viewer.sliders] == [f"{sv.label} {sv.name}" for sv in SERVOS]
    np.testing.assert_array_equal([s.min for s in viewer.sliders], model.u_min)
    np.testing.assert_array_equal([s.max for s in viewer.sliders], model.u_max)
    assert model.params.digest in viewer.info.content


@pytest.mark.parametrize("stale", ["params digest", "code digest"])
def test_stale_export_is_rebuilt(export, part_cache, tmp_path, monkeypatch, stale):
    """An export whose manifest records another parameter digest, or another code digest (built by
    other phantom_cad code), is rebuilt (from the cache) before viewing."""
    import json

    from phantom_cad.cli.view import ensure_export
    from phantom_cad.export.cache import code_digest

    copy = tmp_path / "phantom"
    shutil.copytree(export, copy)
    man = json.loads((copy / "manifest.json").read_text())
    if stale == "params digest":
        man["params"]["digest"] = "0" * 64
    else:
        man["code_digest"] = "0" * 64
    (copy / "manifest.json").write_text(json.dumps(man))
    monkeypatch.setenv("PHANTOM_CAD_CACHE", str(part_cache))   # the fixture's cache
    messages = []
    params, out, urdf = ensure_export(None, copy, messages.append)
    assert len(messages) == 1 and "000000000000" in messages[0] and "building" in messages[0]
    assert ("other phantom_cad code" in messages[0]) == (stale == "code digest")
    man = json.loads((copy / "manifest.json").read_text())
    assert (man["params"]["digest"], man["code_digest"]) == (params.digest, code_digest())
    assert urdf.is_file() and urdf.name.endswith(".local.urdf")


def test_missing_params_file_is_one_line_exit_2():
    proc = subprocess.run([sys.executable, "-m", "phantom_cad", "view", "--params", "/nonexistent.toml"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and "/nonexistent.toml" in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr


def test_not_an_export_is_refused(tmp_path):
    """--out naming a folder that holds something else: the build refuses to replace it."""
    from phantom_cad import cli

    (tmp_path / "mine.txt").write_text("not an export\n")
    with pytest.raises(SystemExit) as exit_:
        cli.main(["view", "--out", str(tmp_path), "--port", "0"])
    assert exit_.value.code == 2
    assert (tmp_path / "mine.txt").read_text() == "not an export\n"


def test_unknown_host_is_one_line_exit_2(tmp_path, capsys):
    """An address this machine cannot listen on: refused before anything is built (viser itself
    would wait for it forever)."""
    from phantom_cad import cli

    with pytest.raises(SystemExit) as exit_:
        cli.main(["view", "--out", str(tmp_path / "export"), "--host", "no-such-host.invalid", "--port", "0"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: --host no-such-host.invalid"), err
    assert not (tmp_path / "export").exists()


# -- in the browser -----------------------------------------------------------------------

@pytest.fixture
def browser(tmp_path):
    if not (CHROMIUM.exists() and CHROMEDRIVER.exists()):
        pytest.skip("chromium / chromedriver not installed (as root: bash .ci/sysdeps)")
    webdriver = pytest.importorskip("selenium.webdriver")
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = str(CHROMIUM)
    for flag in (*CHROMIUM_FLAGS, f"--user-data-dir={tempfile.mkdtemp(dir=tmp_path)}"):
        opts.add_argument(flag)
    driver = webdriver.Chrome(service=Service(str(CHROMEDRIVER)), options=opts)
    driver.set_page_load_timeout(60)
    yield driver
    driver.quit()


def wait_for(condition, timeout=30.0, what="condition"):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = condition()
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


def canvas_pixels(driver) -> np.ndarray:
    """The RGB pixels of the page's three.js canvas: a screenshot, cropped to the largest canvas,
    with everything else on the page (the control panel over the canvas, the axes gizmo) hidden
    for the moment of the shot (visibility only: the layout does not change)."""
    from PIL import Image

    rect = driver.execute_script(
        "const c = [...document.querySelectorAll('canvas')].sort((a, b) => b.width * b.height - a.width * a.height)[0];"
        "c.setAttribute('data-probe', '1');"
        "let s = document.getElementById('probe-style');"
        "if (!s) { s = document.createElement('style'); s.id = 'probe-style'; document.head.appendChild(s); }"
        "s.textContent = 'body * { visibility: hidden !important; }'"
        "  + ' canvas[data-probe] { visibility: visible !important; }';"
        "const r = c.getBoundingClientRect(); return [r.left, r.top, r.width, r.height, window.devicePixelRatio];")
    try:
        png = driver.get_screenshot_as_png()
    finally:
        driver.execute_script("document.getElementById('probe-style').textContent = '';")
    x, y, w, h, dpr = rect
    img = Image.open(io.BytesIO(png)).convert("RGB")
    box = [round(v * dpr) for v in (x, y, x + w, y + h)]
    return np.asarray(img.crop(box))


def settled_canvas(driver, timeout=60.0) -> np.ndarray:
    """The canvas once it stopped changing (software WebGL fades the scene in over seconds)."""
    end = time.monotonic() + timeout
    last = canvas_pixels(driver)
    while time.monotonic() < end:
        time.sleep(1.0)
        now = canvas_pixels(driver)
        if now.shape == last.shape and np.abs(now.astype(int) - last.astype(int)).max() <= 2:
            return now
        last = now
    return last


def test_browser_sliders_drive_the_model(viewer, model, browser):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    browser.get(viewer.url)
    thumbs = wait_for(lambda: (lambda t: t if len(t) == len(SERVOS) else None)(
        browser.find_elements(By.CSS_SELECTOR, "[role=slider]")), 60, "six slider thumbs")
    text = wait_for(lambda: (lambda s: s if model.params.digest in s else None)(
        browser.execute_script("return document.body.textContent")), 30, "the parameter digest")
    for sv in SERVOS:
        assert f"{sv.label} {sv.name}" in text

    # key presses (CDP key events, as a user types them) on two focused slider thumbs: End (to
    # the end of the travel) and three arrow steps
    before = viewer.updates
    end_servo, step_servo = SERVOS[1], SERVOS[2]
    browser.execute_script("arguments[0].focus()", thumbs[end_servo.index])
    ActionChains(browser).send_keys(Keys.END).perform()
    browser.execute_script("arguments[0].focus()", thumbs[step_servo.index])
    ActionChains(browser).send_keys(Keys.ARROW_RIGHT * 3).perform()
    wait_for(lambda: viewer.sliders[step_servo.index].value > 0.0025, 60, "the server to see the arrow keys")
    wait_for(lambda: viewer.sliders[end_servo.index].value > 0.9 * model.u_max[end_servo.index], 60,
             "the server to see the End key")
    time.sleep(0.5)
    assert viewer.updates > before
    u = np.array([s.value for s in viewer.sliders])
    assert u[end_servo.index] == pytest.approx(model.u_max[end_servo.index], abs=1e-3)
    assert u[step_servo.index] == pytest.approx(0.003, abs=1e-9)
    others = [sv.index for sv in SERVOS if sv not in (end_servo, step_servo)]
    assert np.all(u[others] == 0.0)
    np.testing.assert_allclose(viewer.u, u, rtol=0, atol=0)
    np.testing.assert_allclose(viewer.q, model.forward(u, compensated=False), rtol=0, atol=1e-9)
    assert np.abs(viewer.q).max() > 0.5        # the index finger flexed

    # the browser shows the new angles
    q = viewer.q
    moved = [j for j in JOINTS if j.servo == end_servo.index]
    wait_for(lambda: all(f"{math.degrees(q[j.index]):.4f}" in browser.execute_script(
        "return document.body.textContent") for j in moved), 60, "the new joint angles in the page")

    # the analytic / compensated toggle, clicked in the browser
    toggles = [e for e in browser.find_elements(By.CSS_SELECTOR, "input[type=checkbox]") if e.rect["width"] > 0]
    assert len(toggles) == 1      # (the client keeps a hidden settings checkbox of its own)
    ActionChains(browser).move_to_element(toggles[0]).click().perform()
    wait_for(lambda: viewer.model == "compensated", 60, "the compensated model")
    np.testing.assert_allclose(viewer.q, model.forward(u, compensated=True), rtol=0, atol=1e-9)
    assert np.abs(viewer.q - model.forward(u, compensated=False)).max() > 1e-3

    # the three.js canvas shows the hand: many distinct colours, a good share of non-background
    # (the canvas alone: with the hand hidden it is one colour, 0 % covered)
    pixels = settled_canvas(browser)
    assert pixels.shape[0] > 200 and pixels.shape[1] > 200
    colours = np.unique(pixels.reshape(-1, 3), axis=0)
    background = np.median(pixels.reshape(-1, 3), axis=0)
    covered = (np.abs(pixels.astype(int) - background).sum(axis=2) > 30).mean()
    assert len(colours) > 500, f"{len(colours)} distinct colours in the canvas"
    assert covered > 0.03, f"{covered:.1%} of the canvas differs from the background"
