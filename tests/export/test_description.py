"""The robot description package of the default hand, loaded by the tools that use it.

Known answers come from the parameter file by hand (the pulley radii 5:4:5 and 5:4, the servo's
2.3 kgf cm), from other tools (check_urdf, yourdfpy, Pinocchio, PyBullet, trimesh on the
written meshes) and from the posed CAD assembly, never from the writer itself.
"""

from __future__ import annotations

import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from phantom_cad.params.io import load_params

PARAMS = Path(__file__).resolve().parents[2] / "params" / "phantom.toml"

#: by hand from params/phantom.toml: q_i = (R_ref / R_i) q_ref (eq. 2)
MIMIC = {f"{f}_{k}": (f"{f}_mcp", m) for f in ("index", "middle", "ring", "pinky")
         for k, m in (("pip", 5.0 / 4.0), ("dip", 5.0 / 5.0))}
MIMIC["thumb_ip"] = ("thumb_mp", 4.0 / 5.0)
REFERENCE = ("thumb_mp", "index_mcp", "middle_mcp", "ring_mcp", "pinky_mcp", "thumb_cmc")


@pytest.fixture(scope="module")
def urdf(pkg):
    return pkg / "urdf" / "phantom.local.urdf"


def test_package_layout_and_uris_resolve(pkg):
    xml = ET.parse(pkg / "package.xml").getroot()
    assert xml.get("format") == "3" and xml.findtext("name") == "phantom_description"
    assert {e.text for e in xml.findall("exec_depend")} >= {"robot_state_publisher", "joint_state_publisher_gui",
                                                            "rviz2", "xacro"}
    assert xml.find("export/build_type").text == "ament_cmake"
    assert "ament_package()" in (pkg / "CMakeLists.txt").read_text()
    for name, resolve in (("phantom.urdf", lambda u: pkg / u.removeprefix("package://phantom_description/")),
                          ("phantom.local.urdf", lambda u: pkg / "urdf" / u)):
        root = ET.parse(pkg / "urdf" / name).getroot()
        assert [len(ln.findall("visual")) for ln in root.iter("link") if ln.find("visual") is not None] == [1] * 28
        pieces = {ln.get("name"): len(ln.findall("collision")) for ln in root.iter("link")
                  if ln.find("visual") is not None}
        # one convex hull per link; the palm's convex solids: its block, the thenar block, the heel,
        # 4 socket blocks, 2 limiter rails per finger; the forearm module's block and tab
        assert pieces.pop("palm") == 1 + 1 + 1 + 4 + 2 * 4
        assert pieces.pop("forearm") == 2 and set(pieces.values()) == {1}
        uris = [m.get("filename") for m in root.iter("mesh")]
        for u in uris:
            path = resolve(u).resolve()
            assert path.is_file() and pkg.resolve() in path.parents, u


@pytest.mark.skipif(shutil.which("check_urdf") is None, reason="check_urdf (liburdfdom-tools) not installed")
def test_check_urdf_accepts_it(urdf):
    out = subprocess.run(["check_urdf", str(urdf)], capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "root Link: palm" in out.stdout


def test_joints_names_limits_mimic_and_efforts(urdf):
    root = ET.parse(urdf).getroot()
    joints = {j.get("name"): j for j in root.iter("joint")}
    revolute = {n: j for n, j in joints.items() if j.get("type") == "revolute"}
    assert len(revolute) == 15
    for name, j in revolute.items():
        m = j.find("mimic")
        if name in MIMIC:
            ref, mult = MIMIC[name]
            assert m.get("joint") == ref and float(m.get("multiplier")) == pytest.approx(mult, abs=1e-12)
            assert revolute[ref].find("mimic") is None       # never a mimic of a mimic
        else:
            assert m is None and name in REFERENCE
        lim = j.find("limit")
        assert float(lim.get("effort")) > 0 and float(lim.get("velocity")) > 0
        assert float(lim.get("lower")) < float(lim.get("upper"))
    # efforts by hand: 0.226 N m / 7 mm servo pulley = 32.29 N of tension, times R_MCP = 5 mm;
    # the CMC: 0.226 N m / cmc_gain
    p = load_params(PARAMS)
    assert float(revolute["index_mcp"].find("limit").get("effort")) == pytest.approx(0.226 / 7.0 * 5.0, rel=1e-9)
    assert float(revolute["index_pip"].find("limit").get("effort")) == pytest.approx(0.226 / 7.0 * 4.0, rel=1e-9)
    assert float(revolute["thumb_cmc"].find("limit").get("effort")) == pytest.approx(0.226 / p.thumb.cmc_gain,
                                                                                      rel=1e-9)
    lim = revolute["ring_pip"].find("limit")
    assert (float(lim.get("lower")), float(lim.get("upper"))) == pytest.approx(p.fingers["ring"].chain.limits[1])


def test_yourdfpy_forward_kinematics_matches_the_posed_assembly(urdf):
    """At random servo-shaped configurations (mimic joints following), every link sits where the
    CAD assembly poses its part."""
    yourdfpy = pytest.importorskip("yourdfpy")
    from phantom_cad.cad import assembly

    robot = yourdfpy.URDF.load(str(urdf), load_meshes=False, build_collision_scene_graph=False)
    assert sorted(robot.actuated_joint_names) == sorted(REFERENCE)
    p = load_params(PARAMS)
    rng = np.random.default_rng(7)
    from phantom_cad.kinematics.topology import JOINT_NAMES, LINK_NAMES
    for _ in range(5):
        cfg = {n: rng.uniform(0.0, 0.9) for n in robot.actuated_joint_names}
        robot.update_cfg(cfg)
        q = np.array([cfg[n] if n in cfg else MIMIC[n][1] * cfg[MIMIC[n][0]] for n in JOINT_NAMES])
        posed = assembly.pose_transforms(p, q)                       # mm
        for link in LINK_NAMES:
            T = robot.get_transform(link, "palm")
            assert np.allclose(T[:3, :3], posed[link][:3, :3], atol=1e-9), link
            assert np.allclose(T[:3, 3] * 1000.0, posed[link][:3, 3], atol=1e-5), link


def test_inertials_match_the_written_meshes(urdf, pkg):
    """Mass = the slicer's filament estimate of the part (when sliced) or volume x density x
    infill; centre of mass and tensor of the uniform solid at that mass, measured here with
    trimesh on the visual meshes; every tensor physically valid."""
    import json

    trimesh = pytest.importorskip("trimesh")
    p = load_params(PARAMS)
    density = p.print.density * p.print.infill                     # kg/m^3 of the printed part
    manifest = json.loads((pkg.parent / "manifest.json").read_text())
    sliced = {e["name"]: e["print"]["filament_g"] / 1000.0 for e in manifest["parts"] if e.get("print")}
    assert manifest["description"]["mass_source"] == (["slicer"] if sliced else ["volume x density x infill"])
    root = ET.parse(urdf).getroot()
    n = 0
    for link in root.iter("link"):
        ine = link.find("inertial")
        if ine is None:
            assert link.get("name").endswith("_tip")
            continue
        n += 1
        mesh = trimesh.load(pkg / "meshes" / "visual" / f"{link.get('name')}.stl")
        mass = float(ine.find("mass").get("value"))
        assert mass == pytest.approx(sliced.get(link.get("name"), mesh.volume * density), rel=2e-3)
        com = np.array([float(v) for v in ine.find("origin").get("xyz").split()])
        assert np.allclose(com, mesh.center_mass, atol=2e-5)
        a = ine.find("inertia").attrib
        I = np.array([[a["ixx"], a["ixy"], a["ixz"]], [a["ixy"], a["iyy"], a["iyz"]], [a["ixz"], a["iyz"], a["izz"]]],
                     float)
        mesh.density = mass / mesh.volume
        assert np.allclose(I, mesh.moment_inertia, rtol=0, atol=5e-3 * np.abs(I).max())
        ev = np.linalg.eigvalsh(I)
        assert ev.min() > 0 and ev[0] + ev[1] >= ev[2] * (1 - 1e-9)
    assert n == 28


def test_collision_meshes_are_light_convex_and_cover_the_visual(pkg):
    """Every collision piece is convex, closed and light (a few hundred faces at most); a link
    with one hull covers its visual mesh: no visual vertex lies more than 0.1 mm outside it
    (scipy's qhull planes of the written collision vertices). A link of several pieces (the palm,
    the forearm module) is covered by their union: every visual vertex lies within 0.1 mm inside
    one of them; the union (manifold3d) holds the part and more only by its filled cuts (channels,
    pockets: the palm's largest is servo 6's pocket, 23.2 x 12.1 x 25.3 mm = 7.1 cm^3)."""
    trimesh = pytest.importorskip("trimesh")
    manifold3d = pytest.importorskip("manifold3d")
    from scipy.spatial import ConvexHull

    collision = sorted((pkg / "meshes" / "collision").glob("*.stl"))
    assert len(collision) > 28
    split: dict[str, list] = {}
    for path in collision:
        piece = trimesh.load(path)
        assert piece.is_watertight and piece.is_convex and piece.volume > 0, path.name
        assert len(piece.faces) <= 300, (path.name, len(piece.faces))
        visual = pkg / "meshes" / "visual" / path.name
        if not visual.exists():
            split.setdefault(path.stem.rsplit("_", 1)[0], []).append(piece)
            continue
        mesh = trimesh.load(visual)
        planes = ConvexHull(piece.vertices).equations
        outside = (mesh.vertices @ planes[:, :3].T + planes[:, 3]).max()
        assert outside <= 1e-4 + 1e-9, (path.name, outside)
        assert piece.volume >= mesh.convex_hull.volume * 0.98, path.name
    assert sorted(split) == ["forearm", "palm"]
    for name, pieces in split.items():
        mesh = trimesh.load(pkg / "meshes" / "visual" / f"{name}.stl")
        worst = np.full(len(mesh.vertices), np.inf)
        union = None
        for piece in pieces:
            planes = ConvexHull(piece.vertices).equations
            worst = np.minimum(worst, (mesh.vertices @ planes[:, :3].T + planes[:, 3]).max(axis=1))
            m = manifold3d.Manifold.hull_points(np.asarray(piece.vertices))
            union = m if union is None else union + m
        assert worst.max() <= 1e-4 + 1e-9, (name, worst.max())
        assert union.volume() >= mesh.volume * (1 - 1e-3), name
        if name == "palm":
            assert union.volume() - mesh.volume < 2 * 7.1e-6, union.volume() - mesh.volume


def test_tip_frames_sit_on_the_fingertip_pads(urdf, pkg):
    """Each <digit>_tip lies on its distal phalanx's surface and its z axis points out of it
    (the mesh's nearest face normal, measured with trimesh)."""
    trimesh = pytest.importorskip("trimesh")
    yourdfpy = pytest.importorskip("yourdfpy")
    robot = yourdfpy.URDF.load(str(urdf), load_meshes=False, build_collision_scene_graph=False)
    for digit in ("thumb", "index", "middle", "ring", "pinky"):
        T = robot.get_transform(f"{digit}_tip", f"{digit}_distal")
        mesh = trimesh.load(pkg / "meshes" / "visual" / f"{digit}_distal.stl")
        closest, dist, tri = trimesh.proximity.closest_point(mesh, T[:3, 3][None])
        assert dist[0] < 2e-5, digit       # the tessellation's chord error on the round
        assert T[:3, 2] @ mesh.face_normals[tri[0]] > 0.99, digit
        # on the round, 45 deg from palmar toward the tip: z = (0, sin 45, -cos 45) in the link
        assert T[:3, 2] == pytest.approx([0.0, 0.5 ** 0.5, -(0.5 ** 0.5)])


def test_pinocchio_and_pybullet_load_it(urdf):
    pin = pytest.importorskip("pinocchio")
    model = pin.buildModelFromUrdf(str(urdf))
    assert model.nq == 15 and model.nv == 15
    names = set(model.names)
    assert {"index_mcp", "thumb_cmc", "pinky_dip"} <= names
    data = model.createData()
    q = pin.neutral(model)
    pin.crba(model, data, q)
    assert np.all(np.linalg.eigvalsh((data.M + data.M.T) / 2.0) > 0)     # inertias physically valid
    total = sum(model.inertias[i].mass for i in range(model.njoints))
    assert total > 0.05

    pybullet = pytest.importorskip("pybullet")
    cid = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(urdf), flags=pybullet.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid)
        revolute = [pybullet.getJointInfo(body, i, physicsClientId=cid) for i in
                    range(pybullet.getNumJoints(body, physicsClientId=cid))]
        assert sum(j[2] == pybullet.JOINT_REVOLUTE for j in revolute) == 15
    finally:
        pybullet.disconnect(cid)


def test_mujoco_loads_the_urdf(urdf):
    """MuJoCo's own URDF import (the <mujoco> compiler element keeps paths, fixed links and
    visuals): every link a body, the 15 hinges, the 9 mimic joints as joint equalities with
    the multipliers by hand, and the same masses and link poses as yourdfpy."""
    mujoco = pytest.importorskip("mujoco")
    yourdfpy = pytest.importorskip("yourdfpy")
    m = mujoco.MjModel.from_xml_path(str(urdf))
    robot = yourdfpy.URDF.load(str(urdf), load_meshes=False, build_collision_scene_graph=False)
    body = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, i): i for i in range(1, m.nbody)}
    assert set(body) == set(robot.link_map)
    assert m.njnt == 15 and all(t == mujoco.mjtJoint.mjJNT_HINGE for t in m.jnt_type)
    name = lambda obj, i: mujoco.mj_id2name(m, obj, i)                               # noqa: E731
    eqs = {name(mujoco.mjtObj.mjOBJ_JOINT, m.eq_obj1id[k]): (name(mujoco.mjtObj.mjOBJ_JOINT, m.eq_obj2id[k]),
                                                             m.eq_data[k][1]) for k in range(m.neq)}
    assert eqs == {f: (r, pytest.approx(k)) for f, (r, k) in MIMIC.items()}
    for ln, ine in ((ln.name, ln.inertial) for ln in robot.robot.links if ln.inertial is not None):
        assert m.body_mass[body[ln]] == pytest.approx(ine.mass, rel=1e-6), ln
    d = mujoco.MjData(m)
    cfg = {n: 0.3 + 0.1 * k for k, n in enumerate(REFERENCE)}
    robot.update_cfg(cfg)
    for jn, v in cfg.items():
        d.qpos[m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, jn)]] = v
    for f, (r, k) in MIMIC.items():
        d.qpos[m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f)]] = k * cfg[r]
    mujoco.mj_kinematics(m, d)
    palm = body["palm"]
    Tp = np.eye(4)
    Tp[:3, :3], Tp[:3, 3] = d.xmat[palm].reshape(3, 3), d.xpos[palm]
    for ln, i in body.items():
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = d.xmat[i].reshape(3, 3), d.xpos[i]
        T = np.linalg.inv(Tp) @ T
        assert np.allclose(T, robot.get_transform(ln, "palm"), atol=1e-8), ln
