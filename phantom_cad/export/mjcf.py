"""The MJCF of a hand, built with MuJoCo's model-editing API (``mujoco.MjSpec``), and its scene.

Written from the format-neutral :class:`~phantom_cad.export.robot.RobotModel` (the same tree,
names, inertials and meshes as the URDF). What MuJoCo adds (docs/descriptions.md):

* **Joint limits** carry the same stiff constraint as the couplings.
* **Couplings** (this issue; the transmission issue replaces them by the tendons themselves):
  each follower joint (PIP, DIP, thumb IP) is tied to its chain's reference joint by a joint
  equality q_f = m q_ref with the multiplier of eq. (2) and a stiff ``solref``/``solimp``
  (:data:`COUPLING_SOLREF`, :data:`COUPLING_SOLIMP`): MuJoCo's defaults let the coupling give
  way under load without a warning.
* **Drive tendons**: a spatial tendon from the guide G1 (on the reference joint's parent) to G2
  (on its child). Its length is the chord L of eq. (4)-(5), so the servo angle is
  u = (L0 - L) / r: the actuator ``servo<n>`` has gear -1/r on the tendon (actuator length
  -L / r) and an affine bias, force = kp (u_cmd - (L0 - L) / r) - kv du/dt, limited to
  [0, stall torque] (a tendon pulls, it does not push).
* **Direct drive**: ``servo6`` turns the CMC with gear 1 / cmc_gain (q = cmc_gain u), force
  within +-stall torque.
* **Return springs** (eq. 11): a fixed tendon sum R_i q_i over each chain's joints with
  stiffness k_s and rest length 0, so its tension is k_s sum R_i q_i.
* kp = stall torque / stall error (``servo.stall_error_deg``), kv = stall torque / no-load speed.
* Geoms: the visual mesh (class ``visual``: group 2, no contact) and the convex collision mesh
  (class ``collision``: group 3); contact excluded between every parent and child body.
* Sensors: joint positions, actuator forces; sites ``<digit>_tip`` (the URDF's tip frames) and
  the guides ``<digit>_drive_g1`` / ``_g2``; a ``home`` keyframe (q = 0, every servo at the
  start of its travel).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from .robot import JointDrive, RobotModel, TendonDrive

#: simulation step (s) and integrator: implicit in the velocity terms (actuator damping)
TIMESTEP = 0.0005
#: the couplings' constraint: time constant of two steps, critically damped; impedance near 1
COUPLING_SOLREF = (2 * TIMESTEP, 1.0)
COUPLING_SOLIMP = (0.99, 0.999, 0.001, 0.5, 2.0)
#: colour of the collision geoms (shown in group 3)
COLLISION_RGBA = (0.8, 0.3, 0.3, 0.35)


def _quat(R: np.ndarray) -> list[float]:
    import mujoco

    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, float).reshape(9))
    return [float(v) for v in q]


def _children(model: RobotModel) -> dict[str, list]:
    out: dict[str, list] = {}
    for j in model.joints:
        out.setdefault(j.parent, []).append(j)
    return out


def mjcf_spec(model: RobotModel, meshdir: str = "../meshes", coupling_solref=COUPLING_SOLREF,
              coupling_solimp=COUPLING_SOLIMP):
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

    children = _children(model)
    sites = {}
    for d in model.drives:
        if isinstance(d, TendonDrive):
            for s in d.sites:
                sites.setdefault(s.link, []).append(s)

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
        for s in sites.get(name, []):
            body.add_site(name=s.name, pos=list(s.pos), size=[0.0008, 0, 0])
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
                            solref_limit=list(coupling_solref), solimp_limit=list(coupling_solimp))
            add_link(b, j.child)

    root = model.joints[0].parent
    add_link(spec.worldbody.add_body(name=root), root)

    for a, b in model.adjacent:
        spec.add_exclude(bodyname1=a, bodyname2=b)
    for j in model.joints:
        if j.mimic is not None:
            data = np.zeros(mujoco.mjNEQDATA)
            data[1] = j.mimic.multiplier
            data[0] = j.mimic.offset
            spec.add_equality(name=f"{j.name}_coupling", type=mujoco.mjtEq.mjEQ_JOINT,
                              name1=j.name, name2=j.mimic.joint, data=list(data),
                              solref=list(coupling_solref), solimp=list(coupling_solimp))

    for sp in model.springs:
        t = spec.add_tendon(name=sp.tendon, stiffness=sp.stiffness, springlength=[0.0, 0.0])
        for jn, R in zip(sp.joints, sp.radii):
            t.wrap_joint(jn, R)

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
        if isinstance(d, TendonDrive):
            t = spec.add_tendon(name=d.tendon)
            for s in d.sites:
                t.wrap_site(s.name)
            act.trntype = mujoco.mjtTrn.mjTRN_TENDON
            act.target = d.tendon
            gear[0] = -1.0 / d.radius
            bias[:3] = (-d.stiffness * d.rest_length / d.radius, -d.stiffness, -d.damping)
            act.forcerange = [0.0, d.torque]
        elif isinstance(d, JointDrive):
            act.trntype = mujoco.mjtTrn.mjTRN_JOINT
            act.target = d.joint
            gear[0] = 1.0 / d.ratio
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

    n_q = sum(1 for j in model.joints if j.type == "revolute")
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
