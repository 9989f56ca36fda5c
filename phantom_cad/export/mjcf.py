"""The MJCF of a hand, built with MuJoCo's model-editing API (``mujoco.MjSpec``), and its scene.

Written from the format-neutral :class:`~phantom_cad.export.robot.RobotModel` (the same tree,
names, inertials and meshes as the URDF). What MuJoCo adds (docs/descriptions.md):

* **Joint limits** carry a stiff constraint (:data:`LIMIT_SOLREF`, :data:`LIMIT_SOLIMP`).
* **The transmission is the routed tendons** (``kinematics.routing``, docs/transmission.md), as
  printed: no joint equality couples any joint. Every strand is a spatial tendon through sites at
  its anchors and via points, wrapping cylinders (class ``pulley``: group 4, no contact, no mass)
  at its pulleys, a side site choosing the side. A strand pulls and never pushes: its spring has
  the dead band [0, rest length] (``springlength``; a coupling loop's strand tied with the file's
  loop preload P starts at rest length (1 - P / EA)), stiffness EA / rest length (a tendon) or k_s
  (the return cord, whose tension is then k_s sum R_i q_i, eq. 11), damping stiffness x
  :data:`~phantom_cad.export.robot.STRAND_TAU`.
* **Servos**: each servo's pulley turns on a hinge (named after the servo, ``index_flexion``, ...,
  ``thumb_abduction``; armature kv^2 / (4 kp): the position loop critically damped), driven by a position
  actuator ``servo<n>`` (control = u in radians); a drive tendon is clamped on the pulley and
  wound by it; ``servo6``'s pulley turns the CMC pulley through the two strands of the CMC loop
  (q15 = cmc_gain u6 while they hold).
* kp = stall torque / stall error (``servo.stall_error_deg``), kv = stall torque / no-load speed.
* Geoms: the visual mesh (class ``visual``: group 2, no contact) and the convex collision mesh
  (class ``collision``: group 3); contact excluded between every parent and child body.
* Sensors: joint positions, actuator forces, tendon lengths; sites ``<digit>_tip`` (the URDF's tip
  frames) and every strand's points (``<strand>_<role>``, e.g. ``index_drive_guide_g1``); a
  ``home`` keyframe (q = 0, every servo at the start of its travel).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from ..kinematics.routing import Point
from .robot import RobotModel, ServoDrive

#: simulation step (s) and integrator: implicit in the velocity terms (actuator damping)
TIMESTEP = 0.0005
#: the joint limits' constraint: time constant of two steps, critically damped; impedance near 1
LIMIT_SOLREF = (2 * TIMESTEP, 1.0)
LIMIT_SOLIMP = (0.99, 0.999, 0.001, 0.5, 2.0)
#: colour of the tendons and of the pulleys they wrap (group 4)
TENDON_RGBA = (0.9, 0.75, 0.2, 1.0)
RETURN_RGBA = (0.2, 0.6, 0.9, 1.0)
PULLEY_RGBA = (0.9, 0.75, 0.2, 0.3)
#: colour of the collision geoms (shown in group 3)
COLLISION_RGBA = (0.8, 0.3, 0.3, 0.35)


def _quat(R: np.ndarray) -> list[float]:
    import mujoco

    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, float).reshape(9))
    return [float(v) for v in q]


def _frame_z(axis) -> np.ndarray:
    """A rotation whose z is ``axis`` (a cylinder's axis)."""
    z = np.asarray(axis, float) / np.linalg.norm(axis)
    x = np.cross([0.0, 1.0, 0.0], z) if abs(z[1]) < 0.9 else np.cross([1.0, 0.0, 0.0], z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _children(model: RobotModel) -> dict[str, list]:
    out: dict[str, list] = {}
    for j in model.joints:
        out.setdefault(j.parent, []).append(j)
    return out


def _slug(text: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in text.lower()).strip("_")


def _strand_names(strand) -> tuple[list[str | None], list[str | None]]:
    """Site names of a strand's points and geom/side-site names of its pulleys (None elsewhere)."""
    sites, geoms, seen = [], [], {}
    for e in strand.elements:
        if isinstance(e, Point):
            base = f"{strand.name}_{_slug(e.role)}"
            seen[base] = seen.get(base, 0) + 1
            sites.append(base if seen[base] == 1 else f"{base}_{seen[base]}")
            geoms.append(None)
        else:
            sites.append(None)
            geoms.append(f"{strand.tendon}_{_slug(e.role)}_{e.joint}")
    return sites, geoms


def mjcf_spec(model: RobotModel, meshdir: str = "../meshes"):
    """The ``mujoco.MjSpec`` of the hand (not compiled). ``meshdir``: the folder of the
    ``visual/`` and ``collision/`` meshes, relative to the MJCF file."""
    import mujoco

    spec = mujoco.MjSpec()
    spec.modelname = model.name
    spec.meshdir = meshdir
    spec.compiler.degree = False
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    spec.option.timestep = TIMESTEP
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    # Coulomb's round friction cone: MuJoCo's default pyramid has its four edges in each contact's
    # tangent frame, which does not follow a mirror, so on it a left hand grips unlike the right
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC

    visual = spec.add_default("visual", spec.default)
    visual.geom.group, visual.geom.contype, visual.geom.conaffinity = 2, 0, 0
    visual.geom.type = mujoco.mjtGeom.mjGEOM_MESH
    collision = spec.add_default("collision", spec.default)
    collision.geom.group = 3
    collision.geom.type = mujoco.mjtGeom.mjGEOM_MESH
    collision.geom.rgba = COLLISION_RGBA

    links = {ln.name: ln for ln in model.links}
    for ln in model.links:
        if ln.mesh is not None:
            spec.add_mesh(name=f"{ln.name}_visual", file=f"visual/{ln.mesh}.stl")
            for stem in ln.collision:
                spec.add_mesh(name=f"{stem}_collision", file=f"collision/{stem}.stl")

    pulley = spec.add_default("pulley", spec.default)
    pulley.geom.group, pulley.geom.contype, pulley.geom.conaffinity = 4, 0, 0
    pulley.geom.type = mujoco.mjtGeom.mjGEOM_CYLINDER
    pulley.geom.rgba = PULLEY_RGBA

    children = _children(model)
    servo_hinge = {d.link: d for d in model.drives if isinstance(d, ServoDrive)}
    # per link: the strands' sites (name, pos) and pulley cylinders (name, centre, axis, radius, width)
    sites: dict[str, list] = {}
    cylinders: dict[str, dict] = {}
    strand_names = {st.name: _strand_names(st) for st in model.strands}
    for st in model.strands:
        names, geoms = strand_names[st.name]
        for k, e in enumerate(st.elements):
            if names[k] is not None:
                sites.setdefault(e.link, []).append((names[k], e.pos))
            else:
                cylinders.setdefault(e.link, {})[geoms[k]] = e
                link, pos = st.sides[k]
                sites.setdefault(link, []).append((f"{st.name}_side_{k}", pos))

    def add_link(body, name: str) -> None:
        ln = links[name]
        if ln.inertial is not None:
            i = ln.inertial
            body.explicitinertial = True
            body.mass = i.mass
            body.ipos = list(i.com)
            ixx, ixy, ixz, iyy, iyz, izz = i.inertia
            body.fullinertia = [ixx, iyy, izz, ixy, ixz, iyz]
        if ln.mesh is not None:
            body.add_geom(name=f"{name}_visual", default=visual, meshname=f"{name}_visual",
                          rgba=[*ln.color, 1.0])
            for stem in ln.collision:
                body.add_geom(name=f"{stem}_collision", default=collision, meshname=f"{stem}_collision")
        for sname, pos in sites.get(name, []):
            body.add_site(name=sname, pos=list(pos), size=[0.0004, 0, 0], group=4)
        for gname, e in cylinders.get(name, {}).items():
            body.add_geom(name=gname, default=pulley, pos=list(e.centre), quat=_quat(_frame_z(e.axis)),
                          size=[e.radius, e.width / 2.0, 0.0])
        for j in children.get(name, []):
            child = links[j.child]
            if child.inertial is None and child.mesh is None:        # a massless frame: a site
                body.add_site(name=j.child, pos=[float(v) for v in j.origin[:3, 3]],
                              quat=_quat(j.origin[:3, :3]), size=[0.002, 0, 0])
                continue
            b = body.add_body(name=j.child, pos=[float(v) for v in j.origin[:3, 3]],
                              quat=_quat(j.origin[:3, :3]))
            if j.type == "revolute":
                b.add_joint(name=j.name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=list(j.axis),
                            range=[j.lower, j.upper], limited=mujoco.mjtLimited.mjLIMITED_TRUE,
                            solref_limit=list(LIMIT_SOLREF), solimp_limit=list(LIMIT_SOLIMP))
            elif j.child in servo_hinge:                               # a tendon servo's pulley turns
                sd = servo_hinge[j.child]
                b.add_joint(name=sd.joint, type=mujoco.mjtJoint.mjJNT_HINGE, axis=list(sd.axis),
                            range=list(sd.travel), limited=mujoco.mjtLimited.mjLIMITED_TRUE,
                            armature=sd.armature, solref_limit=list(LIMIT_SOLREF),
                            solimp_limit=list(LIMIT_SOLIMP))
            add_link(b, j.child)

    root = model.joints[0].parent
    add_link(spec.worldbody.add_body(name=root), root)

    for a, b in model.adjacent:
        spec.add_exclude(bodyname1=a, bodyname2=b)
    for st in model.strands:
        names, geoms = strand_names[st.name]
        t = spec.add_tendon(name=st.name, stiffness=st.stiffness, damping=st.damping,
                            springlength=[0.0, st.slack_length], width=0.0003,
                            rgba=list(RETURN_RGBA if st.kind == "return" else TENDON_RGBA))
        for k, e in enumerate(st.elements):
            if names[k] is not None:
                t.wrap_site(names[k])
            else:
                t.wrap_geom(geoms[k], f"{st.name}_side_{k}")

    for d in model.drives:
        act = spec.add_actuator(name=d.actuator, ctrlrange=list(d.travel),
                                ctrllimited=mujoco.mjtLimited.mjLIMITED_TRUE,
                                forcelimited=mujoco.mjtLimited.mjLIMITED_TRUE,
                                gaintype=mujoco.mjtGain.mjGAIN_FIXED,
                                biastype=mujoco.mjtBias.mjBIAS_AFFINE)
        gain = np.zeros(10)
        gain[0] = d.stiffness
        bias = np.zeros(10)
        gear = np.zeros(6)
        act.trntype = mujoco.mjtTrn.mjTRN_JOINT
        act.target = d.joint
        gear[0] = 1.0
        bias[:3] = (0.0, -d.stiffness, -d.damping)
        act.forcerange = [-d.torque, d.torque]
        act.gear, act.gainprm, act.biasprm = list(gear), list(gain), list(bias)

    for j in model.joints:
        if j.type == "revolute":
            spec.add_sensor(name=f"{j.name}_pos", type=mujoco.mjtSensor.mjSENS_JOINTPOS,
                            objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=j.name)
    for d in model.drives:
        spec.add_sensor(name=f"{d.actuator}_force", type=mujoco.mjtSensor.mjSENS_ACTUATORFRC,
                        objtype=mujoco.mjtObj.mjOBJ_ACTUATOR, objname=d.actuator)

    for st in model.strands:
        spec.add_sensor(name=f"{st.name}_length", type=mujoco.mjtSensor.mjSENS_TENDONPOS,
                        objtype=mujoco.mjtObj.mjOBJ_TENDON, objname=st.name)

    n_q = sum(1 for j in model.joints if j.type == "revolute") + len(servo_hinge)
    spec.add_key(name="home", qpos=[0.0] * n_q, ctrl=[float(d.travel[0]) for d in model.drives])
    return spec


def mjcf_bytes(model: RobotModel, folder, meshdir: str = "../meshes") -> bytes:
    """The MJCF of ``model`` to be written in ``folder``, its meshes under ``meshdir`` relative
    to it: compiled by MuJoCo first (which checks the model and reads every mesh)."""
    from pathlib import Path

    spec = mjcf_spec(model, meshdir=meshdir)
    spec.modelfiledir = str(Path(folder).resolve())          # what meshdir is relative to
    spec.compile()
    return spec.to_xml().encode("utf-8")


def scene_bytes(hand_file: str, model_name: str) -> bytes:
    """``scene.xml``: the hand (included) above a floor, with a light and a sky, as in MuJoCo
    Menagerie. ``mujoco.MjModel.from_xml_path("scene.xml")`` loads both."""
    root = ET.Element("mujoco", model=f"{model_name} scene")
    ET.SubElement(root, "include", file=hand_file)
    ET.SubElement(root, "statistic", center="0.02 0.03 -0.02", extent="0.3")
    vis = ET.SubElement(root, "visual")
    ET.SubElement(vis, "headlight", diffuse="0.6 0.6 0.6", ambient="0.3 0.3 0.3", specular="0 0 0")
    ET.SubElement(vis, "global", azimuth="130", elevation="-20")
    asset = ET.SubElement(root, "asset")
    ET.SubElement(asset, "texture", type="skybox", builtin="gradient", rgb1="0.3 0.5 0.7",
                  rgb2="0 0 0", width="512", height="3072")
    ET.SubElement(asset, "texture", type="2d", name="groundplane", builtin="checker", mark="edge",
                  rgb1="0.2 0.3 0.4", rgb2="0.1 0.2 0.3", markrgb="0.8 0.8 0.8", width="300",
                  height="300")
    ET.SubElement(asset, "material", name="groundplane", texture="groundplane", texuniform="true",
                  texrepeat="5 5", reflectance="0.2")
    world = ET.SubElement(root, "worldbody")
    ET.SubElement(world, "light", pos="0 0 1", dir="0 0 -1", directional="true")
    ET.SubElement(world, "geom", name="floor", pos="0 0 -0.25", size="0 0 0.05", type="plane",
                  material="groundplane")
    ET.indent(root)
    return ET.tostring(root, encoding="utf-8", xml_declaration=False) + b"\n"
