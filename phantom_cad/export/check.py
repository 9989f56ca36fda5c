"""``phantom-cad check``: the parts, the descriptions and the model of an export describe the same
mechanism, measured by other tools.

Every row compares what one source says with what another measures, at random servo commands
``u`` (the analytic model ``Hand(params).forward(u)`` gives the joint angles ``q``):

- the URDF's link poses (yourdfpy, mimic applied) and the MJCF's body poses (MuJoCo) against the
  posed CAD assembly (``cad.assembly.pose_transforms``);
- the URDF's joint angles (read back from yourdfpy's link transforms) against ``q``; the MJCF's
  tendon twin settled under its six actuators (contacts and gravity off, tendons made near-rigid:
  stiffness x :data:`NEAR_RIGID`) against ``hand.forward`` at the servo angles it reached: the
  routed tendons alone (no joint equality) must impose the model; and the twin as written (the
  file's EA and k_s) against ``hand.forward(u, compensated=True)``, the routed compensation: the
  statics of the printed routing;
- each joint axis against the bearing bores measured in the exported STEP solids;
- URDF and MJCF inertials against the STEP solids' mass properties (mass: the slicer's filament
  estimate when the export was sliced, else volume x density x infill);
- each visual mesh against its solid (volume, centre, bounding box);
- every mesh reference resolves, ``check_urdf`` accepts the URDF, MuJoCo's model test;
- no two parts collide over a grid of servo commands (:func:`collision_rows`); reported, never
  failing: the thumb-finger pinch contacts there and where they begin, and each fingertip's
  distance to the palm with every tendon servo at the end of its travel (:func:`fist_rows`).

Then what the hand must do (``functional``), each computed by the package function the tests call:
the thumb's pad reaching the index, middle and ring pads on the solids (:func:`opposition_rows`);
a cylinder scaled with the hand enclosed on the solids and held palm down in MuJoCo
(:func:`power_grasp_rows`); every wall two perimeters thick (:func:`wall_rows`); every tendon path
outside material (:func:`tendon_rows`).

A row names the worst item (link, joint, file); ``ok`` None = not run (a tool missing).
Needs the ``cad`` extra (build123d, trimesh, mujoco, yourdfpy); imports them inside the checks.
"""

from __future__ import annotations

import importlib.util
import json
import math
import shutil
import subprocess
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import units
from ..errors import UserError
from ..kinematics import thenar as TH
from ..kinematics.hand_params import HandParams
from ..kinematics.model import Hand
from ..kinematics.topology import CMC_Q, JOINTS, LINK_NAMES, SERVOS, joint
from ..kinematics.vectors import clipped_acos
from . import twin
from .pipeline import export_problem

#: poses: position (mm) and rotation (deg) tolerances of the issue
TOL_MM, TOL_DEG = 0.01, 0.01
#: joint angles read back from the URDF (rad): arithmetic only
TOL_Q = 1e-6
#: the MJCF twin's static equilibrium (near-rigid tendons) against the analytic model (rad): 0.1 deg
TOL_EQUILIBRIUM = units.rad(0.1)
#: near-rigid: every tendon strand but the return cord this many times stiffer (and damped), the
#: simulation step shortened to stay stable, the settling time
NEAR_RIGID, NEAR_RIGID_STEP, SETTLE_S = 200.0, 2e-5, 1.0
#: the twin as written settles until no joint moves faster than this (rad/s), or for at most
#: TWIN_SETTLE_S: softer strands settle slower
TWIN_SETTLED, TWIN_SETTLE_S = 1e-6, 10.0
#: inertials: relative, of the mass and of the largest tensor entry; the STEP round trip and the
#: 6-7 significant digits the files keep
TOL_MASS, TOL_TENSOR = 1e-4, 1e-3
#: a visual mesh against its solid: volume (relative) and centre (mm); the tessellation's chord
#: error is stl_tolerance (0.02 mm), the bounding box may differ by it
TOL_MESH_VOLUME, TOL_MESH_CENTRE = 5e-3, 0.01


@dataclass(frozen=True)
class Row:
    check: str
    item: str
    expected: str
    measured: str
    tolerance: str
    ok: bool | None


@dataclass
class Export:
    """The files of one export and what the check reads from them."""

    folder: Path
    manifest: dict
    urdf: Path                 # package:// URIs
    local_urdf: Path           # relative paths
    mjcf: Path
    scene: Path

    @classmethod
    def open(cls, folder: Path) -> "Export":
        try:
            manifest = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise UserError(f"{folder / 'manifest.json'}: not a phantom-cad export ({exc.__class__.__name__}); "
                            "run phantom-cad build first")
        d = manifest.get("description")
        if not isinstance(d, dict):
            raise UserError(f"{folder / 'manifest.json'}: the export has no description package; rebuild it")
        return cls(folder, manifest, folder / d["urdf"], folder / d["local_urdf"], folder / d["mjcf"],
                   folder / d["scene"])


def _worst(errors: dict[str, float]) -> tuple[str, float]:
    item = max(errors, key=lambda k: errors[k])
    return item, errors[item]


def _row(check: str, errors: dict[str, float], tol: float, unit: str, fmt: str = ".4g") -> Row:
    """A row of the largest of ``errors`` (item -> |measured - expected|) against ``tol``."""
    item, err = _worst(errors)
    ok = bool(np.isfinite(err) and err <= tol)
    return Row(check, item, f"0 {unit}", f"{err:{fmt}} {unit}", f"{tol:g} {unit}", ok)


def _rotation_deg(Ra: np.ndarray, Rb: np.ndarray) -> float:
    c = (np.trace(Ra.T @ Rb) - 1.0) / 2.0
    return units.deg(clipped_acos(c))


def _pose_errors(poses: dict[str, np.ndarray], posed_mm: dict[str, np.ndarray], pos: dict, rot: dict) -> None:
    for name, T in poses.items():
        P = posed_mm[name]
        pos[name] = max(pos.get(name, 0.0), float(np.linalg.norm(T[:3, 3] / units.MM - P[:3, 3])))
        rot[name] = max(rot.get(name, 0.0), _rotation_deg(T[:3, :3], P[:3, :3]))


def commands(hand: Hand, n: int, seed: int, margin: float = 0.05) -> np.ndarray:
    """``n`` random servo commands inside the travel (``margin`` of it from either end)."""
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(hand.u_min, float), np.asarray(hand.u_max, float)
    return lo + rng.uniform(margin, 1.0 - margin, (n, len(lo))) * (hi - lo)


# -- URDF -----------------------------------------------------------------------------------------

def _urdf_joint_angle(robot, j) -> float:
    """The angle of a revolute joint read from yourdfpy's link transforms: T_parent_child =
    origin . rot(axis, q)."""
    T = robot.get_transform(j.child, j.parent)
    R = (np.linalg.inv(j.origin) @ T)[:3, :3]
    a = np.asarray(j.axis, float) / np.linalg.norm(j.axis)
    s = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) @ a
    c = (np.trace(R) - 1.0) / 2.0         # R = cI + s[a]x + (1 - c) a a^T: trace = 1 + 2c
    return math.atan2(s, c)


def load_urdf(export: Export):
    """The export's local URDF read by yourdfpy (meshes not loaded): loaded once per check."""
    import yourdfpy

    return yourdfpy.URDF.load(str(export.local_urdf), load_meshes=False, build_collision_scene_graph=False)


def urdf_rows(robot, params: HandParams, hand: Hand, U: np.ndarray) -> list[Row]:
    """Link poses and joint angles of the URDF (``robot``, yourdfpy) at the commands ``U``."""
    from ..cad.assembly import pose_transforms

    names = {j.name: j for j in robot.robot.joints}
    missing = [j.name for j in JOINTS if j.name not in names]
    if missing:
        return [Row("URDF joints = topology", ", ".join(missing), "present", "missing", "-", False)]
    pos, rot, dq = {}, {}, {}
    for u in U:
        q = hand.forward(u)
        robot.update_cfg({n: float(q[joint(n).index]) for n in robot.actuated_joint_names})
        poses = {ln: robot.get_transform(ln, robot.base_link) for ln in LINK_NAMES}
        _pose_errors(poses, pose_transforms(params, q), pos, rot)
        for j in JOINTS:
            dq[j.name] = max(dq.get(j.name, 0.0), abs(_urdf_joint_angle(robot, names[j.name]) - q[j.index]))
    return [_row("URDF link positions (yourdfpy) = posed CAD assembly", pos, TOL_MM, "mm"),
            _row("URDF link rotations (yourdfpy) = posed CAD assembly", rot, TOL_DEG, "deg"),
            _row("URDF joint angles (mimic applied) = hand.forward(u)", dq, TOL_Q, "rad")]


def urdf_files_rows(export: Export) -> list[Row]:
    """Both URDFs name the same meshes, every mesh reference resolves inside the package, and
    check_urdf accepts the URDF."""
    pkg = export.urdf.parent.parent
    name = export.manifest["description"]["package"]
    bad: dict[str, float] = {}
    texts = {}
    for path, resolve in ((export.urdf, lambda u: pkg / u.removeprefix(f"package://{name}/")),
                          (export.local_urdf, lambda u: path.parent / u)):
        root = ET.parse(path).getroot()
        uris = [m.get("filename") for m in root.iter("mesh")]
        for u in uris:
            p = resolve(u).resolve()
            bad[f"{path.name}: {u}"] = 0.0 if (p.is_file() and pkg.resolve() in p.parents) else 1.0
        for m in root.iter("mesh"):
            m.set("filename", Path(m.get("filename")).name)
        texts[path] = ET.tostring(root)
    if not bad:
        bad["(no mesh)"] = 1.0
    item, err = _worst(bad)
    rows = [Row("URDF mesh references resolve in the package", item if err else f"{len(bad)} references",
                "all", "missing" if err else "all", "-", err == 0.0),
            Row("URDF (package://) = local URDF but for mesh paths", export.urdf.name,
                "same", "same" if len(set(texts.values())) == 1 else "differ", "-", len(set(texts.values())) == 1)]
    tool = shutil.which("check_urdf")
    if tool is None:
        rows.append(Row("check_urdf accepts the URDF", export.urdf.name, "accepted", "not run (check_urdf "
                        "missing: apt-get install liburdfdom-tools)", "-", None))
    else:
        proc = subprocess.run([tool, str(export.urdf)], capture_output=True, text=True)
        msg = (proc.stderr.strip().splitlines() or ["accepted"])[-1] if proc.returncode else "accepted"
        rows.append(Row("check_urdf accepts the URDF", export.urdf.name, "accepted", msg[:60], "-",
                        proc.returncode == 0))
    return rows


# -- MJCF -----------------------------------------------------------------------------------------

def _mj_name(mujoco, m, obj, i) -> str:
    return mujoco.mj_id2name(m, obj, i) or ""


def mjcf_rows(export: Export, params: HandParams, hand: Hand, U: np.ndarray, settle: int) -> tuple[list[Row], dict]:
    """The MJCF's rows, and its inertials by body (for :func:`inertial_rows`)."""
    import mujoco

    from ..cad.assembly import pose_transforms

    try:
        m = mujoco.MjModel.from_xml_path(str(export.scene))
    except ValueError as exc:
        return [Row("MuJoCo compiles the MJCF", export.scene.name, "compiles", str(exc).splitlines()[0][:60],
                    "-", False)], {}
    d = mujoco.MjData(m)
    B = mujoco.mjtObj.mjOBJ_BODY
    jid = {j.name: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j.name) for j in JOINTS}
    missing = [n for n, i in jid.items() if i < 0]
    if missing:
        return [Row("MJCF joints = topology", ", ".join(missing), "present", "missing", "-", False)], {}
    bid = {ln: mujoco.mj_name2id(m, B, ln) for ln in LINK_NAMES}
    root = next(ln for ln in LINK_NAMES if ln == _mj_name(mujoco, m, B, 1))

    def body(i):
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = d.xmat[i].reshape(3, 3), d.xpos[i]
        return T

    pos, rot = {}, {}
    for u in U:
        q = hand.forward(u)
        d.qpos[:] = 0.0
        for j in JOINTS:
            d.qpos[m.jnt_qposadr[jid[j.name]]] = q[j.index]
        mujoco.mj_kinematics(m, d)
        T_root = np.linalg.inv(body(bid[root]))
        poses = {ln: T_root @ body(i) for ln, i in bid.items() if i >= 0}
        _pose_errors(poses, pose_transforms(params, q), pos, rot)
    for ln, i in bid.items():
        if i < 0:
            pos[ln] = rot[ln] = math.inf
    rows = [_row("MJCF body positions (MuJoCo) = posed CAD assembly", pos, TOL_MM, "mm"),
            _row("MJCF body rotations (MuJoCo) = posed CAD assembly", rot, TOL_DEG, "deg")]

    # static equilibrium under the actuators: the transmission, not the grasp
    off = mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_GRAVITY
    m.opt.disableflags |= off
    step = m.opt.timestep
    stiff, damp = m.tendon_stiffness.copy(), m.tendon_damping.copy()
    cords = [t for t in range(m.ntendon) if not _mj_name(mujoco, m, mujoco.mjtObj.mjOBJ_TENDON, t).endswith("_return")]
    m.tendon_stiffness[cords] *= NEAR_RIGID
    m.tendon_damping[cords] *= NEAR_RIGID
    m.opt.timestep = NEAR_RIGID_STEP
    key = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "home")
    act = {s.index: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, s.actuator) for s in SERVOS}
    hinge = {s.index: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, s.name) for s in SERVOS}
    dq: dict[str, float] = {}
    for u in U[:settle]:
        mujoco.mj_resetDataKeyframe(m, d, max(key, 0))
        for k, a in act.items():
            d.ctrl[a] = u[k]
        for _ in range(int(SETTLE_S / m.opt.timestep)):
            mujoco.mj_step(m, d)
        reached = np.array(u, float)
        for k, i in hinge.items():          # the model at the angles the servos reached
            reached[k] = d.qpos[m.jnt_qposadr[i]] if i >= 0 else math.nan
        q = hand.forward(reached)
        for j in JOINTS:
            dq[j.name] = max(dq.get(j.name, 0.0), abs(d.qpos[m.jnt_qposadr[jid[j.name]]] - q[j.index]))
    m.tendon_stiffness[:], m.tendon_damping[:], m.opt.timestep = stiff, damp, step
    if dq:
        rows.append(_row(f"MJCF twin settled (near-rigid tendons) = hand.forward(u) ({len(U[:settle])} commands)",
                         dq, TOL_EQUILIBRIUM, "rad"))
    # the twin as written: its strands stretch as the routed compensation says
    dq = {}
    for u in U[:settle]:
        mujoco.mj_resetDataKeyframe(m, d, max(key, 0))
        for k, a in act.items():
            d.ctrl[a] = u[k]
        twin.settle(mujoco, m, d, TWIN_SETTLED, TWIN_SETTLE_S)
        reached = np.array(u, float)
        for k, i in hinge.items():
            reached[k] = d.qpos[m.jnt_qposadr[i]] if i >= 0 else math.nan
        q = hand.forward(reached, compensated=True)
        for j in JOINTS:
            dq[j.name] = max(dq.get(j.name, 0.0), abs(d.qpos[m.jnt_qposadr[jid[j.name]]] - q[j.index]))
    m.opt.disableflags &= ~off
    if dq:
        rows.append(_row(f"MJCF twin settled (the file's EA, k_s) = hand.forward(u, compensated=True) "
                         f"({len(U[:settle])} commands)", dq, TOL_EQUILIBRIUM, "rad"))

    # MuJoCo Menagerie's model test: 1 s of random controls, contacts on
    mujoco.mj_resetDataKeyframe(m, d, max(key, 0))
    rng = np.random.default_rng(0)
    lo, hi = m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1]
    finite = True
    for k in range(int(1.0 / m.opt.timestep)):
        if k % int(0.1 / m.opt.timestep) == 0:
            d.ctrl[:] = lo + rng.random(m.nu) * (hi - lo)
        mujoco.mj_step(m, d)
        finite = finite and bool(np.isfinite(d.qpos).all() and np.isfinite(d.qvel).all())
    warnings = {mujoco.mjtWarning(i).name: int(d.warning[i].number) for i in range(len(d.warning))
                if d.warning[i].number}
    rows.append(Row("MuJoCo model test: 1 s of random controls", ", ".join(warnings) or export.scene.name,
                    "no warning, finite", ("finite" if finite else "NaN/inf") + (f", {warnings}" if warnings else
                                                                                 ", no warning"), "-",
                    finite and not warnings))
    inertials = {}
    for i in range(1, m.nbody):                  # (mass, centre, tensor about it) in the body frame
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, m.body_iquat[i])
        R = R.reshape(3, 3)
        inertials[_mj_name(mujoco, m, B, i)] = (float(m.body_mass[i]), np.array(m.body_ipos[i]),
                                                 R @ np.diag(m.body_inertia[i]) @ R.T)
    return rows, inertials


# -- the solids -----------------------------------------------------------------------------------

def _solids(export: Export) -> tuple[dict[str, object], dict[str, dict]]:
    """({part: its STEP solid}, {part: its mass properties}), each measured once."""
    import build123d as bd

    from ..cad.measure import mass_properties

    solids = {p["name"]: bd.import_step(export.folder / "step" / f"{p['name']}.step") for p in export.manifest["parts"]}
    return solids, {name: mass_properties(shape) for name, shape in solids.items()}


def axis_rows(robot, params: HandParams, solids: dict) -> list[Row]:
    """Each joint's axis (URDF, at rest) on the bores measured in the solids, each solid placed
    where the CAD assembly puts it at rest: the parent's axle press bore and the child's bearing
    seat and axle bore (a tongue without a bearing turns on the axle in its bore); for the CMC the
    palm's journal and the CMC base's column."""
    from ..cad.assembly import pose_transforms
    from ..cad.measure import cylinders
    from ..cad.parts.common import Tolerances

    tol = Tolerances(params)        # the modelled (compensated) bores, mm
    press, seat, clear = tol.axle_press / 2.0, tol.bearing_seat / 2.0, tol.axle_clear / 2.0
    th = TH.thenar(params)
    journal, column = th["journal_r"] / units.MM, th["column_r"] / units.MM
    robot.update_cfg(np.zeros(len(robot.actuated_joint_names)))
    names = {j.name: j for j in robot.robot.joints}
    rest = pose_transforms(params, np.zeros(len(JOINTS)))
    cyl = {}
    dist, ang = {}, {}
    for j in JOINTS:
        uj = names.get(j.name)
        if uj is None:
            dist[j.name] = ang[j.name] = math.inf
            continue
        T = robot.get_transform(j.child, robot.base_link)
        a = T[:3, :3] @ (np.asarray(uj.axis, float) / np.linalg.norm(uj.axis))
        p = T[:3, 3] / units.MM
        seats = ([(j.parent, (journal,), "journal"), (j.child, (column,), "column")] if j.index == CMC_Q
                 else [(j.parent, (press,), "axle press bore"), (j.child, (seat, clear), "bearing seat and axle bore")])
        for part, radii, what in seats:
            if part not in cyl:
                cyl[part] = cylinders(solids[part])
            Tp = rest[part]
            found = [(np.linalg.norm(np.cross(Tp[:3, :3] @ c["point"] + Tp[:3, 3] - p, a)),
                      units.deg(clipped_acos(abs(float((Tp[:3, :3] @ c["direction"]) @ a)))))
                     for c in cyl[part] if any(abs(c["radius"] - r) < 1e-6 for r in radii)]
            key = f"{j.name} / {part} {what}"
            if not found:
                dist[key] = ang[key] = math.inf
                continue
            best = min(found, key=lambda f: f[0] + f[1])
            dist[key], ang[key] = best
    return [_row("joint axes (URDF) on the bores measured in the solids: offset", dist, TOL_MM, "mm"),
            _row("joint axes (URDF) on the bores measured in the solids: angle", ang, TOL_DEG, "deg")]


def _expected_inertials(export: Export, params: HandParams,
                        props: dict) -> dict[str, tuple[float, np.ndarray, np.ndarray]]:
    """(mass kg, centre m, tensor kg m^2 about it) of each part from its STEP solid's mass
    properties ``props``."""
    out = {}
    for p in export.manifest["parts"]:
        mp = props[p["name"]]
        vol = float(mp["volume_mm3"])
        sliced = (p.get("print") or {}).get("filament_g")
        mass = (float(sliced) * units.KG_PER_G if sliced
                else vol * units.MM ** 3 * params.print.density * params.print.infill)
        density = mass / vol
        I = np.asarray(mp["inertia_mm5"], float) * density * units.MM ** 2
        out[p["name"]] = (mass, np.asarray(mp["com_mm"], float) * units.MM, (I + I.T) / 2)
    return out


def _urdf_inertials(robot) -> dict[str, tuple[float, np.ndarray, np.ndarray]]:
    """(mass kg, centre m, tensor kg m^2 about the centre in the link frame) of each URDF link
    with an inertial (``robot``, yourdfpy)."""
    out = {}
    for ln in robot.robot.links:
        ine = ln.inertial
        if ine is None:
            continue
        T = np.eye(4) if ine.origin is None else np.asarray(ine.origin, float)
        I = np.asarray(ine.inertia, float)
        out[ln.name] = (float(ine.mass), T[:3, 3].copy(), T[:3, :3] @ I @ T[:3, :3].T)
    return out


def inertial_rows(export: Export, robot, params: HandParams, props: dict, mjcf_inertials: dict) -> list[Row]:
    expected = _expected_inertials(export, params, props)
    rows = []
    for label, got in (("URDF", _urdf_inertials(robot)), ("MJCF", mjcf_inertials)):
        if label == "MJCF" and not got:
            continue
        mass, com, ten = {}, {}, {}
        for name, (m0, c0, I0) in expected.items():
            if name not in got:
                mass[name] = com[name] = ten[name] = math.inf
                continue
            m1, c1, I1 = got[name]
            mass[name] = abs(m1 - m0) / m0
            com[name] = float(np.linalg.norm(c1 - c0)) / units.MM
            ten[name] = float(np.abs(I1 - I0).max() / np.abs(I0).max())
        rows += [_row(f"{label} masses = the solids' (relative)", mass, TOL_MASS, "", ".2e"),
                 _row(f"{label} centres of mass = the solids'", com, TOL_MM, "mm"),
                 _row(f"{label} inertia tensors = the solids' (relative)", ten, TOL_TENSOR, "", ".2e")]
    return rows


def mesh_rows(export: Export, props: dict) -> list[Row]:
    """Each visual mesh (metres, link frame) against its solid's mass properties ``props``:
    volume and centre."""
    import trimesh

    pkg = export.urdf.parent.parent
    vol, centre = {}, {}
    for name, mp in props.items():
        path = pkg / "meshes" / "visual" / f"{name}.stl"
        if not path.is_file():
            vol[name] = centre[name] = math.inf
            continue
        mesh = trimesh.load(path, force="mesh")
        v0 = float(mp["volume_mm3"])
        vol[name] = abs(mesh.volume / units.MM ** 3 - v0) / v0
        centre[name] = float(np.linalg.norm(mesh.center_mass / units.MM - np.asarray(mp["com_mm"], float)))
    return [_row("visual meshes: volume = the solid's (relative)", vol, TOL_MESH_VOLUME, "", ".2e"),
            _row("visual meshes: centre = the solid's", centre, TOL_MESH_CENTRE, "mm")]


def fist_rows(hand: Hand, solids: dict) -> list[Row]:
    """The fingertips' distances to the palm at full travel (``cad.grasp.fingertips_to_palm``, on
    the STEP solids): a report that never fails. Under the paper's Table I limits a curled fingertip
    stays 11-26 mm from the palm, and the power grasp's cylinder needs that room (docs/parts.md)."""
    from ..cad.grasp import fingertips_to_palm

    far = fingertips_to_palm(hand, solids)
    return [Row("fingertips to the palm at full travel (reported: Table I's curl, docs/parts.md)",
                " / ".join(far), "-", " / ".join(f"{d:.1f}" for d in far.values()) + " mm", "-", True)]


def visual_meshes(export: Export) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """{link: (vertices mm, faces)} of the description's visual meshes (link frames), each read once."""
    from .step_stl import read_stl

    pkg = export.urdf.parent.parent
    meshes = {}
    for name in LINK_NAMES:
        path = pkg / "meshes" / "visual" / f"{name}.stl"
        if path.is_file():
            v, f = read_stl(path.read_bytes())
            meshes[name] = (v / units.MM, f)
    return meshes


def collision_rows(export: Export, params: HandParams, hand: Hand, log=lambda msg: None,
                   meshes: dict | None = None) -> list[Row]:
    """No two parts interpenetrate over the grid of servo commands of
    ``interference.command_sweep`` (the description's visual meshes, posed by the assembly
    interface): a joint's parent and child and the designed contacts may touch; the pinch
    contacts (a thumb part with a finger part) are listed in a row that never fails, each with the
    thumb flexion where it begins."""
    from . import interface
    from .interference import SWEEP_FRACTIONS, SWEEP_TOL_MM3, command_sweep, may_touch

    asm = interface.assembly()
    meshes = visual_meshes(export) if meshes is None else meshes
    r = command_sweep(meshes, hand, lambda q: asm.pose_transforms(params, q),
                      may_touch(asm.designed_contacts(params)))
    grid = ", ".join(f"{f:.0%}" for f in SWEEP_FRACTIONS)
    for e in r["pinch"]:
        at = " ".join(f"{k} {v:.0%}" for k, v in e["commands"].items())
        log(f"check: pinch contact {e['parts'][0]} x {e['parts'][1]}: from thumb flexion "
            f"{e['from_thumb_flexion']:.0%}, largest {e['volume_mm3']:.2f} mm^3 at {at}")
    errors = {" x ".join(e["parts"]): e["volume_mm3"] for e in r["collisions"]} or {"-": 0.0}
    by_finger: dict[str, list[float]] = {}
    for e in r["pinch"]:
        finger = next(n for n in e["parts"] if not n.startswith("thumb")).split("_")[0]
        by_finger.setdefault(finger, []).append(e["from_thumb_flexion"])
    begin = " / ".join(f"{f} {len(v)} from {min(v):.0%}" for f, v in sorted(by_finger.items())) or "none"
    return [_row(f"parts apart over the command grid ({grid} of each travel; {r['poses']} poses, manifold3d)",
                 errors, SWEEP_TOL_MM3, "mm^3"),
            Row("thumb-finger pinch contacts on the command grid: part pairs, the thumb flexion where they begin "
                "(reported)", f"{len(r['pinch'])} pairs (each on stderr)", "-", begin, "-", True)]


def opposition_rows(params: HandParams, solids: dict, meshes: dict) -> list[Row]:
    """The thumb's pad reaches the index, middle and ring pads on the solids
    (``cad.grasp.solid_contact``: of the kinematic model's contacts, ``kinematics.opposition``, the
    first where the finger flexing onto the still thumb comes within (0, REACH_MM] of it pad to pad),
    and there the two tips share no volume (OpenCascade's boolean) and no two parts interpenetrate
    (manifold3d on the visual meshes; a joint's parent and child and the designed contacts may
    touch)."""
    from ..cad import assembly, grasp, measure
    from ..kinematics.opposition import OPPOSED, THUMB
    from ..kinematics.topology import digit_links
    from .interference import SWEEP_TOL_MM3, interference, may_touch

    hand = Hand(params)
    allowed = may_touch(assembly.designed_contacts(params))
    thumb = digit_links(THUMB)[-1].name
    measured, problems = {}, {}
    for finger in OPPOSED:
        c = grasp.solid_contact(hand, solids, finger)
        if c is None:
            measured[finger], problems[finger] = "-", "no pad-to-pad contact"
            continue
        T = assembly.pose_transforms(params, hand.forward(c.u, compensated=True))
        tip = digit_links(finger)[-1].name
        a, b = measure.placed(solids[thumb], T[thumb]), measure.placed(solids[tip], T[tip])
        overlap = measure.intersection_volume(a, b)
        collisions = interference(meshes, T, allowed, tol_mm3=SWEEP_TOL_MM3)["collisions"]
        measured[finger] = f"{c.distance_mm:.3f}"
        if overlap > 0.0:
            problems[finger] = f"tips overlap {overlap:.3g} mm^3"
        elif collisions:
            problems[finger] = "overlap " + ", ".join(" x ".join(e["parts"]) for e in collisions)
    ok = not problems
    return [Row(f"thumb pad to the {', '.join(OPPOSED)} pads on the solids (cad.grasp.solid_contact), no "
                "interpenetration", "; ".join(f"{f}: {why}" for f, why in problems.items()) or " / ".join(OPPOSED),
                f"(0, {grasp.REACH_MM:g}] mm", " / ".join(measured.values()) + " mm", f"<= {grasp.REACH_MM:g} mm",
                ok)]


def power_grasp_rows(export: Export, params: HandParams, solids: dict, log=lambda msg: None) -> list[Row]:
    """The power grasp of a cylinder scaled with the hand (``kinematics.power_grasp``): enclosed on
    the solids (``cad.grasp.power_grasp``: laid against the palm's heel, every finger touches it
    past its equator, the thumb clear), then held palm down in MuJoCo (``export.hold.hold_cylinder``).
    The commands follow the paper's compensation, as the MuJoCo hold was tuned on it."""
    from ..cad import grasp
    from ..kinematics.power_grasp import laid_axis_y, power_grasp_diameter_mm
    from .hold import HOLD_KG, MOVED_MM, RELEASED_MM, hold_cylinder

    diameter = power_grasp_diameter_mm(params)
    g, tried = grasp.power_grasp(Hand(params, None, "paper"), solids, diameter)
    name = f"power grasp: a {diameter:.1f} mm cylinder across the palm"
    if g is None:
        last = tried[-1] if tried else None
        wraps = " / ".join("-" if c is None else f"{c.wrap_deg:.0f}" for c in (last.fingers.values() if last else ()))
        where = ("no position across the palm" if laid_axis_y(params, diameter) is None or last is None else
                 f"against the heel (axis y {last.axis_y_mm:.1f} mm)")
        return [Row(f"{name} enclosed (cad.grasp.power_grasp)", where, "every finger past its equator",
                    f"wrap {wraps} deg" + ("" if last is None or len(tried) == 1 else " (last tried)"), "> 90 deg",
                    False)]
    wraps = [c.wrap_deg for c in g.fingers.values()]
    rows = [Row(f"{name} enclosed (cad.grasp.power_grasp)", " / ".join(g.fingers) + f" (axis y {g.axis_y_mm:.1f} mm)",
                "every finger past its equator", "wrap " + " / ".join(f"{w:.0f}" for w in wraps) + " deg",
                "> 90 deg", True)]
    if importlib.util.find_spec("mujoco") is None:
        rows.append(Row(f"{name} held palm down (MuJoCo)", export.scene.name, "held", "not run (mujoco missing)", "-",
                        None))
        return rows
    log("check: the power grasp's hold (MuJoCo)")
    h = hold_cylinder(export.scene, g)
    why = h.problems()
    rows.append(Row(f"{name} held palm down, {HOLD_KG * 1e3:g} g (MuJoCo, export.hold)", export.scene.name, "held",
                    "; ".join(why) if why else f"let go, moved {h.released_mm:.1f} mm; palm down, {h.moved_mm:.1f} mm",
                    f"let go < {RELEASED_MM:g}, palm down < {MOVED_MM:g} mm, at rest", not why))
    return rows


def wall_rows(params: HandParams, meshes: dict) -> list[Row]:
    """Every wall of every part at least two perimeters (``export.walls.part_walls`` on the visual
    meshes: ray casting; the bar allows for the mesh's tolerance)."""
    from .walls import part_walls, wall_bar_mm

    bar = wall_bar_mm(params)
    walls = part_walls(meshes, params)
    thin = {n: r["wall_thinnest"] for n, r in walls.items()}
    item = min(thin, key=lambda n: thin[n])
    return [Row(f"walls >= two perimeters on every part ({len(walls)} parts; export.walls, trimesh rays)", item,
                f">= {bar:.2f} mm", f"{thin[item]:.3f} mm", f">= {bar:.2f} mm", bool(thin[item] >= bar))]


def tendon_rows(params: HandParams, solids: dict) -> list[Row]:
    """No tendon passes through material: ``cad.clearance.tendon_hits`` over the routing model's strands
    at 0-100 % of every travel, on the solids (a left hand's mirrored back into the right-handed
    frames its parts are built in)."""
    from ..cad.clearance import FRACTIONS, STEP_MM, tendon_hits

    shapes = solids
    if params.side == "left":
        import build123d as bd

        shapes = {n: s.mirror(bd.Plane.YZ) for n, s in solids.items()}
    hits = tendon_hits(params, shapes)
    first = (f"{hits[0].strand} in {hits[0].part} at {hits[0].fraction:.0%}" if hits else
             f"every strand, {len(FRACTIONS)} poses")
    return [Row(f"tendon paths outside material (cad.clearance, a point every {STEP_MM:g} mm, OpenCascade)", first,
                "0 points", f"{sum(h.n_points for h in hits)} points", "0", not hits)]


def check_export(export_dir: Path, params: HandParams, samples: int = 8, settle: int = 3, seed: int = 0,
                 log=lambda msg: None, sweep: bool = True, functional: bool = True) -> list[Row]:
    """Every row of the check of the export in ``export_dir`` built from ``params``."""
    export = Export.open(Path(export_dir))
    problem = export_problem(export.folder, params.digest, params.side)
    if problem is not None:
        raise UserError(f"{problem} ({params.source}); build it again")
    hand = Hand(params)
    U = commands(hand, samples, seed)
    rows = []
    log("check: URDF (yourdfpy)")
    robot = load_urdf(export)
    rows += urdf_rows(robot, params, hand, U)
    rows += urdf_files_rows(export)
    log("check: MJCF (MuJoCo)")
    mj_rows, mj_inertials = mjcf_rows(export, params, hand, U, settle)
    rows += mj_rows
    log("check: the solids (STEP)")
    solids, props = _solids(export)
    rows += axis_rows(robot, params, solids)
    rows += inertial_rows(export, robot, params, props, mj_inertials)
    rows += mesh_rows(export, props)
    rows += fist_rows(hand, solids)
    meshes = visual_meshes(export) if sweep or functional else {}
    if sweep:
        log("check: collisions over the command grid (manifold3d)")
        rows += collision_rows(export, params, hand, log, meshes)
    if functional:
        log("check: opposition on the solids")
        rows += opposition_rows(params, solids, meshes)
        log("check: the power grasp on the solids")
        rows += power_grasp_rows(export, params, solids, log)
        log("check: walls (ray casting)")
        rows += wall_rows(params, meshes)
        log("check: tendon paths (OpenCascade)")
        rows += tendon_rows(params, solids)
    return rows


def table(rows: list[Row]) -> str:
    """The rows as a plain-text table (check, item, expected, measured, tolerance, ok)."""
    head = ("check", "worst item", "expected", "measured", "tolerance", "ok")
    cells = [head] + [(r.check, r.item, r.expected, r.measured, r.tolerance,
                       {True: "ok", False: "FAIL", None: "not run"}[r.ok]) for r in rows]
    widths = [max(len(c[i]) for c in cells) for i in range(len(head))]
    lines = ["  ".join(c[i].ljust(widths[i]) for i in range(len(head))).rstrip() for c in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)
