"""``phantom-cad check``: every row green on the default hand (the functional rows too: opposition,
the power grasp and its hold, walls, tendon paths), the rows comparing sources on the left hand and a
second parameter file, three sized hands (205 x 95 mm as a left hand and a person measured digit by
digit all green; 160 x 72 mm failing its palm's walls and its hold), and each deliberate corruption
of an export is caught and named.

The corruptions are made here with ElementTree / numpy on copies of a built export: a joint
origin shifted by 0.1 mm, a mimic multiplier changed, a mass scaled, a mesh moved by 0.3 mm,
an MJCF coupling changed. The check measures with yourdfpy, MuJoCo and the STEP solids.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from phantom_cad.params.io import load_params

ROOT = Path(__file__).resolve().parents[2]
PARAMS = ROOT / "params" / "phantom.toml"

pytest.importorskip("mujoco")
pytest.importorskip("yourdfpy")


def _copy(export: Path, dest: Path) -> Path:
    shutil.copytree(export, dest, ignore=shutil.ignore_patterns("renders", "stl", "slicer"))
    return dest


def _failed(rows) -> dict[str, str]:
    """check -> worst item of the rows that failed."""
    return {r.check: r.item for r in rows if r.ok is False}


def _edit_urdfs(export: Path, edit) -> None:
    """Apply ``edit(root)`` to both URDFs (the package:// one and the local one)."""
    for path in (export / "description" / "urdf").glob("*.urdf"):
        tree = ET.parse(path)
        edit(tree.getroot())
        tree.write(path, encoding="utf-8", xml_declaration=True)


def _joint(root, name):
    return next(j for j in root.iter("joint") if j.get("name") == name)


@pytest.fixture(scope="module")
def export(hand_build):
    result, _ = hand_build
    return result.out_dir


def _check(export, **kw):
    from phantom_cad.export.check import check_export

    return check_export(export, load_params(PARAMS), **kw)


def test_the_default_hand_is_all_green(export):
    rows = _check(export, samples=8, settle=3)
    # every row ok; check_urdf may be "not run" where liburdfdom-tools is missing
    assert [(r.check, r.item, r.measured) for r in rows if not r.ok and not r.check.startswith("check_urdf")] == []
    checks = " | ".join(r.check for r in rows)
    for what in ("URDF link positions", "MJCF body positions", "URDF joint angles", "MJCF twin settled",
                 "MJCF twin settled (the file's EA, k_s) = hand.forward(u, compensated=True)",
                 "bores measured in the solids", "URDF masses", "MJCF inertia tensors", "visual meshes",
                 "mesh references", "MuJoCo model test", "parts apart over the command grid",
                 "fingertips to the palm at full travel", "thumb-finger pinch contacts",
                 "thumb pad to the index, middle, ring pads", "power grasp: a 35.0 mm cylinder across the palm "
                 "enclosed", "power grasp: a 35.0 mm cylinder across the palm held palm down",
                 "walls >= two perimeters on every part", "tendon paths outside material"):
        assert what in checks


@pytest.fixture(scope="module")
def sized_checks():
    """{fixture name: the check's rows} of the sized hands, each checked once (``_sized_rows``)."""
    return {}


def _sized_rows(request, sized_checks, hand: str):
    """The check's rows on a hand ``phantom-cad size`` makes (tests/conftest.py): ``sized_hand``,
    160 x 72 mm; ``sized_hand_205``, 205 x 95 mm, a left hand; ``sized_hand_digits``, a person
    measured digit by digit."""
    from phantom_cad.export.check import check_export
    from phantom_cad.params import parse

    if hand not in sized_checks:
        doc, result = request.getfixturevalue(hand)
        sized_checks[hand] = check_export(result.out_dir, parse(doc), samples=4, settle=2)
    return sized_checks[hand]


@pytest.mark.slow
@pytest.mark.parametrize("hand", ["sized_hand", "sized_hand_205", "sized_hand_digits"])
def test_a_sized_hand_is_green(request, sized_checks, hand):
    """Every row of a sized hand's check is green, the power grasp's hold in MuJoCo among them
    (its cylinder laid against the heel ``size`` placed); check_urdf may be "not run" where
    liburdfdom-tools is missing."""
    rows = _sized_rows(request, sized_checks, hand)
    assert [(r.check, r.item, r.measured) for r in rows
            if not r.ok and not r.check.startswith("check_urdf")] == []
    assert len([r for r in rows if "held palm down" in r.check]) == 1


def test_the_fist_row_reports_the_fingertips_distances(export):
    """The fist row (every tendon servo at the end of its travel) reports each fingertip's distance
    to the palm and never fails; its numbers agree with manifold3d's on the exported visual meshes
    (loaded by trimesh), posed by the URDF (yourdfpy) at the model's joint angles: the least
    distance between the two surfaces (``min_gap``, triangle to triangle), which the tessellation
    (stl_tolerance 0.02 mm) and the row's 0.1 mm rounding bound."""
    import build123d as bd
    import manifold3d
    import trimesh
    import yourdfpy

    from phantom_cad.cad.grasp import full_travel
    from phantom_cad.export.check import Export, fist_rows
    from phantom_cad.kinematics.model import Hand
    from phantom_cad.kinematics.topology import FINGERS, joint

    p = load_params(PARAMS)
    hand = Hand(p)
    names = ["palm"] + [f"{f}_distal" for f in FINGERS]
    solids = {n: bd.import_step(export / "step" / f"{n}.step") for n in names}
    (row,) = fist_rows(hand, solids)
    assert row.ok is True and row.item == "index / middle / ring / pinky"
    reported = [float(v) for v in row.measured.removesuffix(" mm").split(" / ")]

    robot = yourdfpy.URDF.load(str(Export.open(export).local_urdf), load_meshes=False,
                               build_collision_scene_graph=False)
    q = hand.forward(full_travel(hand))
    robot.update_cfg({n: float(q[joint(n).index]) for n in robot.actuated_joint_names})
    meshes = {}
    for n in names:
        m = trimesh.load(export / "description" / "meshes" / "visual" / f"{n}.stl", force="mesh")
        m.apply_transform(robot.get_transform(n, robot.base_link))
        m.apply_scale(1e3)
        meshes[n] = m

    def solid(m):
        return manifold3d.Manifold(manifold3d.Mesh(vert_properties=np.asarray(m.vertices, np.float32),
                                                   tri_verts=np.asarray(m.faces, np.uint32)))

    palm = solid(meshes["palm"])
    assert palm.status() == manifold3d.Error.NoError
    measured = [palm.min_gap(solid(meshes[f"{f}_distal"]), 100.0) for f in FINGERS]     # beyond 100 mm: 100
    assert reported == pytest.approx(measured, abs=0.1)
    assert min(measured) > 10.0         # the curl of Table I: no fingertip comes within 10 mm


def test_the_wall_row_names_a_part_thinner_than_two_perimeters():
    """``wall_rows`` on two meshes made here: a 2 mm plate (two perimeters and more) and a tube of
    radii 5 and 5.6 mm, whose 0.6 mm wall is under the default hand's bar (0.8 mm less twice its STL
    tolerance): the row fails on the tube, at its wall within the facets' chord error."""
    import trimesh

    from phantom_cad.export.check import wall_rows

    p = load_params(PARAMS)
    tube = trimesh.creation.cylinder(radius=5.6, height=20.0, sections=256).difference(
        trimesh.creation.cylinder(radius=5.0, height=22.0, sections=256))
    meshes = {n: (np.asarray(m.vertices, float), np.asarray(m.faces, np.int64))
              for n, m in (("plate", trimesh.creation.box((40.0, 30.0, 2.0))), ("tube", tube))}
    (row,) = wall_rows(p, meshes)
    assert row.ok is False and row.item == "tube"
    assert float(row.measured.removesuffix(" mm")) == pytest.approx(0.6, abs=0.02)
    (row,) = wall_rows(p, {"plate": meshes["plate"]})
    assert row.ok is True and float(row.measured.removesuffix(" mm")) == pytest.approx(2.0, rel=1e-3)


def test_a_shifted_joint_origin_is_named(export, tmp_path):
    ex = _copy(export, tmp_path / "x")

    def shift(root):
        o = _joint(root, "index_pip").find("origin")
        xyz = np.array([float(v) for v in o.get("xyz").split()]) + [0.0, 1e-4, 0.0]     # 0.1 mm
        o.set("xyz", " ".join(repr(float(v)) for v in xyz))

    _edit_urdfs(ex, shift)
    failed = _failed(_check(ex, samples=3, settle=0, sweep=False, functional=False))
    assert failed["URDF link positions (yourdfpy) = posed CAD assembly"] in ("index_middle", "index_distal")
    assert failed["joint axes (URDF) on the bores measured in the solids: offset"].startswith("index_pip /")
    assert not any(c.startswith("MJCF") for c in failed)           # the MJCF was left alone


def test_a_changed_multiplier_is_named(export, tmp_path):
    ex = _copy(export, tmp_path / "x")
    _edit_urdfs(ex, lambda root: _joint(root, "middle_dip").find("mimic").set("multiplier", "1.1"))
    failed = _failed(_check(ex, samples=3, settle=0, sweep=False, functional=False))
    assert failed["URDF joint angles (mimic applied) = hand.forward(u)"] == "middle_dip"
    assert failed["URDF link rotations (yourdfpy) = posed CAD assembly"] == "middle_distal"


def test_a_scaled_mass_is_named(export, tmp_path):
    ex = _copy(export, tmp_path / "x")

    def scale(root):
        link = next(ln for ln in root.iter("link") if ln.get("name") == "ring_distal")
        m = link.find("inertial/mass")
        m.set("value", repr(1.5 * float(m.get("value"))))

    _edit_urdfs(ex, scale)
    failed = _failed(_check(ex, samples=2, settle=0, sweep=False, functional=False))
    assert failed == {"URDF masses = the solids' (relative)": "ring_distal"}


def test_a_moved_mesh_is_named(export, tmp_path):
    from phantom_cad.export.step_stl import read_stl, stl_bytes

    ex = _copy(export, tmp_path / "x")
    path = ex / "description" / "meshes" / "visual" / "pinky_middle.stl"
    v, f = read_stl(path.read_bytes())
    path.write_bytes(stl_bytes(v + [3e-4, 0.0, 0.0], f, "pinky_middle", "m"))        # 0.3 mm
    failed = _failed(_check(ex, samples=2, settle=0, sweep=False, functional=False))
    assert failed == {"visual meshes: centre = the solid's": "pinky_middle"}


def test_a_changed_mjcf_coupling_is_named(export, tmp_path):
    """The ring's PIP-DIP loop wraps a groove 10 % larger in the MJCF than the routing model says:
    the twin's ring DIP no longer follows the model (the tendons alone couple the joints), neither
    near-rigid nor as written."""
    ex = _copy(export, tmp_path / "x")
    path = ex / "description" / "mjcf" / "phantom.xml"
    tree = ET.parse(path)
    geom = next(e for e in tree.getroot().iter("geom") if e.get("name") == "ring_pip_dip_groove_ring_dip")
    r, half = (float(v) for v in geom.get("size").split()[:2])
    geom.set("size", f"{1.1 * r!r} {half!r}")
    tree.write(path, encoding="utf-8")
    failed = _failed(_check(ex, samples=2, settle=1, sweep=False, functional=False))
    assert failed == {"MJCF twin settled (near-rigid tendons) = hand.forward(u) (1 commands)": "ring_dip",
                      "MJCF twin settled (the file's EA, k_s) = hand.forward(u, compensated=True) (1 commands)":
                      "ring_dip"}


def _cli_check(tmp_path, cache, *args) -> subprocess.CompletedProcess:
    env = {**os.environ, "PHANTOM_CAD_CACHE": str(cache)}
    return subprocess.run([sys.executable, "-m", "phantom_cad", "check", "--samples", "4", "--settle", "2",
                           "--out", str(tmp_path / "export"), *args], capture_output=True, text=True, env=env,
                          cwd=ROOT)


@pytest.mark.parametrize("kind, args", [("left", ("--side", "left", "--no-functional")),
                                         ("slender", ("--params", str(ROOT / "params" / "examples" / "slender.toml")))],
                         ids=["left", "slender"])
def test_check_builds_and_passes_the_left_hand_and_a_second_file(tmp_path, hand_export, part_cache, kind, args):
    """The command builds the hand's export with the run's part cache, where the session's export of
    the same hand (``hand_export``) left its parts (unsliced, as they are), and checks it: the left
    hand's sources agree (its functional rows are tests/cad's and tests/export/test_mjcf.py's), and
    every row of slender.toml's passes, its flat palm's cylinder held palm down included
    (docs/descriptions.md)."""
    hand_export(kind)
    proc = _cli_check(tmp_path, part_cache, "--no-slice", *args)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    assert " 0 failed" in proc.stdout and "FAIL" not in proc.stdout
    assert ("(left)" in proc.stdout) == ("left" in args)


def test_check_exits_1_on_a_mismatch_and_2_on_an_error(export, tmp_path):
    ex = _copy(export, tmp_path / "export")
    _edit_urdfs(ex, lambda root: _joint(root, "thumb_ip").find("mimic").set("multiplier", "0.5"))
    proc = subprocess.run([sys.executable, "-m", "phantom_cad", "check", "--samples", "2", "--settle", "0", "--no-sweep",
                           "--no-functional", "--out", str(ex)], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 1 and "FAIL" in proc.stdout and "thumb_ip" in proc.stdout
    proc = subprocess.run([sys.executable, "-m", "phantom_cad", "check", "--params", str(tmp_path / "none.toml")],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 2 and proc.stderr.startswith("error: ") and len(proc.stderr.splitlines()) == 1
