"""The grasp library: the paper's Fig. 4, 14-29, as MuJoCo scenes on an export's MJCF (docs/grasps.md).

A grasp (``grasps.toml``, or a user's file of the same format) is an object made here from MuJoCo
primitives or a convex mesh, sized with the hand (its sizes are given at the paper's 189 mm hand
and scale with ``hand_length``), a placement rule against the kinematic model's frames, and the
commands of a posture of the posture library (``phantom_cad.postures``, through the control law).
:func:`run` simulates it with ``export.hold.Trial``, the object presented (held where it was put,
as a user hands it over) while the hand closes: the approach (the object's contacts and gravity off,
:data:`APPROACH_S`), the closing (contacts on, the posture's commands, :data:`CLOSE_S`), the pressing
(the grasp's pressing digits to the end of their travel, :data:`PRESS_S`), the object let go (gravity
off, :data:`RELEASE_S`: the closed state), then from the closed state, gravity in each of the six
directions of the palm frame for :data:`HOLD_S` each. The object is held in a direction when, at the
end, it still touches the hand and has moved at most :data:`HELD_MM` from the closed state. MuJoCo
is imported by ``Trial``; the rest is numpy.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import postures as posture_library
from .. import units
from ..errors import UserError, one_line
from ..kinematics import frames
from ..kinematics.hand_params import HandParams
from ..kinematics.link_frames import link_transforms
from ..kinematics.forearm_layout import heel_clear_y
from ..kinematics.topology import CMC_SERVO, DIGITS, FINGERS, JOINTS, SERVOS, THUMB_CHAIN, chain, digit_links
from .hold import Trial

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

#: the library shipped with the package
LIBRARY = Path(__file__).with_name("grasps.toml")
#: the hand length (mm) at which the library's sizes are given: the paper's hand
REFERENCE_LENGTH_MM = 189.0
CATEGORIES = ("power", "precision", "tool")
PLACES = ("palm", "pinch")
REST = "rest"
REQUIRED = ("figure", "category", "description", "place", "posture", "press", "object")
#: each object kind's sizes (mm), in the order the library documents them
KINDS = {
    "cylinder": ("diameter", "length"),
    "sphere": ("diameter",),
    "handle": ("across", "deep", "length"),
    "key": ("blade_length", "blade_width", "head", "thickness"),
    "wire": ("diameter", "length"),
    "scissors": ("ring", "ring_wire", "length", "thickness"),
    "screwdriver": ("handle", "handle_length", "shaft", "shaft_length"),
    "tape_roll": ("outer", "inner", "width"),
    "tweezers": ("length", "width", "thickness", "gap"),
}
#: the simulated phases (s): approach, closing to the posture, pressing, and each gravity direction
#: from the closed state
APPROACH_S, CLOSE_S, PRESS_S, RELEASE_S, HOLD_S = 1.0, 1.0, 1.0, 0.5, 2.0
#: gravity's six directions, in the palm frame (= the scene's world frame)
DIRECTIONS = {"-z": (0, 0, -1), "+z": (0, 0, 1), "-y": (0, -1, 0), "+y": (0, 1, 0), "-x": (-1, 0, 0), "+x": (1, 0, 0)}
#: how far (mm) the object may move from the closed state and still count as held
HELD_MM = 5.0
#: the clearance (m) between the placed object and the surface it is put against
GAP = 0.0005
#: the object's colour in pictures (yellow: none of the parts is)
COLOUR = (0.95, 0.85, 0.2, 1.0)
#: the thumb's CMC and flexion commands tried (evenly over each travel) to clear the object at the
#: approach (as cad.grasp's power grasp)
THUMB_CMC_STEPS, THUMB_FLEX_STEPS = 21, 5
#: segments of the mesh profiles (the elliptic handle) and boxes of the tape roll's annulus
PROFILE_SEGMENTS, ANNULUS_BOXES, RING_CAPSULES = 32, 16, 12


@dataclass(frozen=True)
class Grasp:
    name: str
    figure: int
    category: str
    description: str
    place: str
    posture: str                  # a posture library name, or "rest"
    press: tuple[str, ...]        # digits commanded to the end of their travel when closing
    kind: str
    size_mm: dict                 # at the reference hand (REFERENCE_LENGTH_MM)
    density: float                # kg/m^3
    source: str


def _fail(source, name, field, value, rule):
    raise UserError(f"{source}: grasp {name!r}: {field} = {one_line(repr(value))}: {rule}")


def _positive(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and x > 0


def read(path) -> dict[str, Grasp]:
    """The grasps of a TOML file: every failure one :class:`UserError` naming the file, grasp, field,
    value and rule. Posture names are checked when the grasp is run (:func:`commands`)."""
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise UserError(f"{path}: not a UTF-8 text file") from None
    except OSError as exc:
        raise UserError(f"{path}: cannot be read ({exc.strerror})") from None
    except tomllib.TOMLDecodeError as exc:
        raise UserError(f"{path}: not valid TOML ({exc})") from None
    if not doc:
        raise UserError(f"{path}: no grasps (each is a table [name] with {', '.join(REQUIRED)})")
    return {name: _grasp(path, name, entry) for name, entry in doc.items()}


def _grasp(path, name, e) -> Grasp:
    if not isinstance(e, dict):
        raise UserError(f"{path}: {name} = {one_line(repr(e))}: must be a table [name] of a grasp")
    if not name or not all(c.isascii() and (c.isalnum() or c in "-_") for c in name):
        _fail(path, name, "name", name, "must be ASCII letters, digits, '-' and '_'")
    for key in e:
        if key not in REQUIRED:
            _fail(path, name, key, e[key], f"unknown key (known: {', '.join(REQUIRED)})")
    for key in REQUIRED:
        if key not in e:
            _fail(path, name, key, None, f"missing (required: {', '.join(REQUIRED)})")
    fig = e["figure"]
    if not isinstance(fig, int) or isinstance(fig, bool) or fig < 1:
        _fail(path, name, "figure", fig, "must be a positive integer (the panel of the paper's Fig. 4)")
    for key, allowed in (("category", CATEGORIES), ("place", PLACES)):
        if e[key] not in allowed:
            _fail(path, name, key, e[key], f"must be one of {', '.join(allowed)}")
    for key in ("description", "posture"):
        if not isinstance(e[key], str) or not e[key].strip():
            _fail(path, name, key, e[key], "must be a non-empty string")
    press = e["press"]
    if not isinstance(press, list) or any(d not in DIGITS for d in press):
        _fail(path, name, "press", press, f"must be a list of digits ({', '.join(DIGITS)})")
    if e["place"] == "pinch" and (not press or press[0] not in FINGERS):
        _fail(path, name, "press", press, f"a pinch is placed on its first pressing finger's pad: must start with "
                                          f"one of {', '.join(FINGERS)}")
    obj = e["object"]
    if not isinstance(obj, dict) or obj.get("kind") not in KINDS:
        _fail(path, name, "object", obj, f"must be a table with kind one of {', '.join(KINDS)}")
    kind = obj["kind"]
    need = KINDS[kind] + ("density_kg_m3",)
    for key, value in obj.items():
        if key != "kind" and key not in need:
            _fail(path, name, f"object.{key}", value, f"unknown size of a {kind} (known: {', '.join(need)})")
    for key in need:
        if not _positive(obj.get(key)):
            _fail(path, name, f"object.{key}", obj.get(key), "must be a positive number (mm, or kg/m^3)")
    size = {k: float(obj[k]) for k in KINDS[kind]}
    if kind == "tape_roll" and size["inner"] >= size["outer"]:
        _fail(path, name, "object.inner", size["inner"], "must be less than object.outer")
    return Grasp(name, fig, e["category"], e["description"].strip(), e["place"], e["posture"].strip(),
                 tuple(press), kind, size, float(obj["density_kg_m3"]), str(path))


def load(extra=None) -> dict[str, Grasp]:
    """The library, and ``extra``'s grasps over it (a grasp of the same name replaces the library's)."""
    out = read(LIBRARY)
    if extra is not None:
        out.update(read(extra))
    return out


# -- the objects ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class Shape:
    """One geom of an object, in its frame (metres): a MuJoCo primitive (type name, size) at a pose,
    or a convex mesh (type "mesh", its vertices)."""
    type: str
    size: tuple
    pos: tuple = (0.0, 0.0, 0.0)
    quat: tuple = (1.0, 0.0, 0.0, 0.0)
    vertices: tuple = ()
    density: float = 0.0


#: a quaternion turning the geom's z onto the object's x
Z_TO_X = (math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0)


def scale(params: HandParams) -> float:
    """The object's scale on this hand: its length over the paper's."""
    return units.mm(params.hand_length) / REFERENCE_LENGTH_MM


def shapes(grasp: Grasp, s: float) -> tuple[list[Shape], np.ndarray]:
    """(the object's geoms, its half extents (m) along its x, y, z) at scale ``s``. Frames: a
    "palm" object's z is its axis (laid along the palm's x); a "pinch" object is thin along its z
    (the pad's normal) and long along its x."""
    z = {k: units.m(v * s) for k, v in grasp.size_mm.items()}
    rho = grasp.density
    k = grasp.kind
    if k == "cylinder":
        r, h = z["diameter"] / 2, z["length"] / 2
        return [Shape("cylinder", (r, h, 0.0), density=rho)], np.array([r, r, h])
    if k == "sphere":
        r = z["diameter"] / 2
        return [Shape("sphere", (r, 0.0, 0.0), density=rho)], np.array([r, r, r])
    if k == "handle":
        a, b, h = z["deep"] / 2, z["across"] / 2, z["length"] / 2
        t = np.linspace(0.0, 2 * math.pi, PROFILE_SEGMENTS, endpoint=False)
        ring = np.stack([a * np.cos(t), b * np.sin(t)], axis=1)
        verts = np.concatenate([np.column_stack([ring, np.full(len(t), -h)]), np.column_stack([ring, np.full(len(t), h)])])
        return [Shape("mesh", (), vertices=tuple(verts.ravel()), density=rho)], np.array([a, b, h])
    if k == "key":
        L, w, head, t = z["blade_length"], z["blade_width"], z["head"], z["thickness"]
        # the blade centred where it is held, the head beyond it along x
        return ([Shape("box", (L / 2, w / 2, t / 2), density=rho),
                 Shape("box", (head / 2, head / 2, t / 2), pos=(L / 2 + head / 2, 0.0, 0.0), density=rho)],
                np.array([L / 2 + head, head / 2, t / 2]))
    if k == "wire":
        r, h = z["diameter"] / 2, z["length"] / 2
        return [Shape("cylinder", (r, h, 0.0), quat=Z_TO_X, density=rho)], np.array([h, r, r])
    if k == "scissors":
        R, rw, L, t = z["ring"] / 2, z["ring_wire"] / 2, z["length"], z["thickness"]
        # the closed blades along x from the held point; two rings side by side behind it (-x)
        out = [Shape("box", (L / 2, rw * 2, t / 2), pos=(L / 2, 0.0, 0.0), density=rho)]
        for side in (-1.0, 1.0):
            c = np.array([-R - rw, side * (R + rw), 0.0])
            for i in range(RING_CAPSULES):
                a0, a1 = 2 * math.pi * i / RING_CAPSULES, 2 * math.pi * (i + 1) / RING_CAPSULES
                p0 = c + R * np.array([math.cos(a0), math.sin(a0), 0.0])
                p1 = c + R * np.array([math.cos(a1), math.sin(a1), 0.0])
                out.append(_capsule(p0, p1, rw, rho))
        return out, np.array([L, 2 * (R + rw), t / 2])
    if k == "screwdriver":
        r, h, rs, hs = z["handle"] / 2, z["handle_length"] / 2, z["shaft"] / 2, z["shaft_length"] / 2
        # the shaft out of the handle's -z end: beyond the index finger (the palm's -x), steel
        return ([Shape("cylinder", (r, h, 0.0), density=rho),
                 Shape("cylinder", (rs, hs, 0.0), pos=(0.0, 0.0, -h - hs), density=7800.0)],
                np.array([r, r, h + 2 * hs]))
    if k == "tape_roll":
        ro, ri, h = z["outer"] / 2, z["inner"] / 2, z["width"] / 2
        rm, n = (ro + ri) / 2, ANNULUS_BOXES
        half_t = rm * math.tan(math.pi / n)
        out = []
        for i in range(n):
            a = 2 * math.pi * i / n
            out.append(Shape("box", ((ro - ri) / 2, half_t, h), pos=(rm * math.cos(a), rm * math.sin(a), 0.0),
                             quat=(math.cos(a / 2), 0.0, 0.0, math.sin(a / 2)), density=rho))
        return out, np.array([ro, ro, h])
    if k == "tweezers":
        L, w, t, gap = z["length"], z["width"], z["thickness"], z["gap"]
        # two plates along x, gap apart across z, joined by a block at their -x end
        out = [Shape("box", (L / 2, w / 2, t / 2), pos=(0.0, 0.0, side * (gap + t) / 2), density=rho)
               for side in (-1.0, 1.0)]
        out.append(Shape("box", (w / 2, w / 2, gap / 2), pos=(-L / 2 + w / 2, 0.0, 0.0), density=rho))
        return out, np.array([L / 2, w / 2, gap / 2 + t])
    raise AssertionError(k)


def _capsule(p0, p1, r, rho) -> Shape:
    """A capsule from p0 to p1 (its axis the geom's z)."""
    c, v = (p0 + p1) / 2, p1 - p0
    half = float(np.linalg.norm(v)) / 2
    zhat = v / (2 * half)
    # the rotation taking z onto zhat (zhat is never -z here: it lies in the x-y plane)
    axis = np.cross([0.0, 0.0, 1.0], zhat)
    angle = math.acos(max(-1.0, min(1.0, float(zhat[2]))))
    n = np.linalg.norm(axis)
    q = (1.0, 0.0, 0.0, 0.0) if n < 1e-12 else (math.cos(angle / 2), *(math.sin(angle / 2) * axis / n))
    return Shape("capsule", (r, half, 0.0), pos=tuple(c), quat=tuple(float(x) for x in q), density=rho)


# -- commands and placement ----------------------------------------------------------------------

@dataclass(frozen=True)
class Plan:
    """How a grasp is made on a hand: servo commands (rad, servo order) and the object's pose."""
    u_approach: np.ndarray
    u_close: np.ndarray
    press: tuple[int, ...]           # servos commanded to the end of their travel when closing
    T_object: np.ndarray             # 4x4, metres, the palm frame
    shapes: tuple
    half: np.ndarray                 # the object's half extents (m) along its x, y, z


def commands(hand, grasp: Grasp, library: dict) -> tuple[np.ndarray, np.ndarray]:
    """(approach, closing) servo commands: the closing posture through the control law
    (``postures.pose``; at rest for "rest"); the approach at rest but, for a pinch, the first
    pressing finger's servo already at the posture's (its pad under the object)."""
    if grasp.posture == REST:
        u = hand.u_min.copy()
    elif grasp.posture not in library:
        raise UserError(f"{grasp.source}: grasp {grasp.name!r}: posture = {grasp.posture!r}: not in the posture "
                        f"library (known: {', '.join(library)}, or {REST})")
    else:
        u = posture_library.pose(hand, library[grasp.posture]).u
    approach = hand.u_min.copy()
    if grasp.place == "pinch":
        for d in grasp.press[:1]:
            approach[chain(d).servo] = u[chain(d).servo]
    return approach, u


def placement(hand, grasp: Grasp, u_approach: np.ndarray, u_close: np.ndarray, half: np.ndarray) -> np.ndarray:
    """The object's pose (4x4, metres, palm frame) from the model's frames: a "palm" object at the
    approach commands, a "pinch" object at the closing posture's."""
    p = hand.params
    out = np.eye(4)
    if grasp.place == "palm":
        T = link_transforms(p, hand.forward(u_approach, compensated=True))
        bases = np.array([T[f"{f}_base"][:3, 3] for f in FINGERS])
        thick = float(np.mean([p.digit(f).thickness for f in FINGERS]))
        out[:3, :3] = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]     # its z along the palm's x
        z = -p.palm.thickness / 2 - half[0] - GAP
        y = bases[:, 1].mean() - thick / 2 - half[1] - GAP
        # clear of the palm's heel (under the palmar face, from its back face heel_length distally):
        # against its front edge when the knuckle rule would put it into the heel; its bounding
        # circle (the larger half extent) against the heel's front corner
        if p.palm.heel_height > 0.0:
            y = max(y, heel_clear_y(p, z, max(half[0], half[1]) + GAP))
        out[:3, 3] = (bases[:, 0].mean(), y, z)
        return out
    # on the pad of the first pressing finger, at the closing posture (the finger is there from the
    # approach on; the thumb then closes onto it): thin along the pad's normal (toward the thumb)
    Tc = link_transforms(p, hand.forward(u_close, compensated=True))
    finger = grasp.press[0]
    pad = Tc[digit_links(finger)[-1].name] @ frames.T_distal_pad(p, finger)
    n = pad[:3, 2] / np.linalg.norm(pad[:3, 2])
    along = Tc[digit_links(finger)[-1].name][:3, 1]
    x = along - n * float(along @ n)               # its length along the finger's, out past its tip
    x /= np.linalg.norm(x)
    out[:3, 0], out[:3, 2] = x, n
    out[:3, 1] = np.cross(n, x)                   # right-handed on a mirrored (left) hand too
    out[:3, 3] = pad[:3, 3] + n * (half[2] + GAP)
    return out


def plan(hand, grasp: Grasp, library: dict) -> Plan:
    u_approach, u_close = commands(hand, grasp, library)
    geoms, half = shapes(grasp, scale(hand.params))
    return Plan(u_approach, u_close, tuple(chain(d).servo for d in grasp.press),
                placement(hand, grasp, u_approach, u_close, half), tuple(geoms), half)


# -- the simulation ------------------------------------------------------------------------------

@dataclass(frozen=True)
class Direction:
    held: bool
    slip_mm: float                   # how far the object moved from the closed state
    touching: int                    # its contacts with the hand at the end


@dataclass(frozen=True)
class Result:
    grasp: Grasp
    mass_g: float
    size_mm: dict                    # the object's sizes on this hand
    released_mm: float               # how far it moved when let go (gravity off)
    contacts: tuple[str, ...]        # the hand's bodies touching it once let go (gravity off)
    directions: dict                 # direction name -> Direction
    torque: np.ndarray               # the servos' torques when closed (N m, servo order)
    stall: np.ndarray                # their stall torques (N m)
    warnings: dict
    u_approach: np.ndarray           # the approach's servo commands (rad), the thumb cleared
    cleared: bool                    # whether a thumb command pair cleared the object (else: as planned)

    @property
    def held(self) -> bool:
        return all(d.held for d in self.directions.values())

    @property
    def max_slip_mm(self) -> float:
        return max(d.slip_mm for d in self.directions.values())

    @property
    def torque_ratio(self) -> float:
        """The largest |torque| / stall over the servos when closed."""
        return float(np.max(np.abs(self.torque) / self.stall))


def _add(mujoco, spec, body, shapes_) -> None:
    for i, sh in enumerate(shapes_):
        kw = dict(name=f"object_{i}", pos=list(sh.pos), quat=list(sh.quat), density=sh.density, rgba=list(COLOUR))
        if sh.type == "mesh":
            mesh = spec.add_mesh(name=f"object_mesh_{i}", uservert=list(sh.vertices))
            body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh.name, **kw)
        else:
            body.add_geom(type=getattr(mujoco.mjtGeom, f"mjGEOM_{sh.type.upper()}"), size=list(sh.size), **kw)


def _build(shapes_):
    def build(mujoco, spec, body):
        # the exported MJCF gives every body its inertia (inertiafromgeom false): the object's comes
        # from its geoms' densities, compiled alone
        probe = mujoco.MjSpec()
        alone = probe.worldbody.add_body(name="object")
        alone.add_freejoint()
        _add(mujoco, probe, alone, shapes_)
        pm = probe.compile()
        body.mass, body.ipos, body.iquat = float(pm.body_mass[1]), list(pm.body_ipos[1]), list(pm.body_iquat[1])
        body.inertia, body.explicitinertial = list(pm.body_inertia[1]), True
        _add(mujoco, spec, body, shapes_)
    return build


def clear_thumb(t: Trial, hand, u: np.ndarray) -> np.ndarray | None:
    """``u`` with the thumb's two servos at the first pair of a grid over their travel (the CMC's
    outermost, as ``cad.grasp``'s power grasp turns the thumb away) at which none of the thumb's
    parts touches the placed object: the export's collision shapes at the model's joint angles
    (``hand.forward``), the object's contacts on. None when no pair clears it."""
    import mujoco

    m = t.m
    d = mujoco.MjData(m)
    mujoco.mj_copyData(d, m, t.d)
    adr = [int(m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j.name)]) for j in JOINTS]
    thumb = {mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, ln.name) for ln in digit_links(THUMB_CHAIN.digit)}
    mine = set(int(g) for g in t.geoms)
    k1, k6 = THUMB_CHAIN.servo, CMC_SERVO
    for s6 in np.linspace(0.0, 1.0, THUMB_CMC_STEPS):
        for s1 in np.linspace(0.0, 1.0, THUMB_FLEX_STEPS):
            v = np.array(u, dtype=float)
            v[k6] = hand.u_min[k6] + s6 * (hand.u_max[k6] - hand.u_min[k6])
            v[k1] = hand.u_min[k1] + s1 * (hand.u_max[k1] - hand.u_min[k1])
            d.qpos[adr] = hand.forward(v, compensated=True)
            mujoco.mj_forward(m, d)
            if not any((int(c.geom1) in mine and int(m.geom_bodyid[c.geom2]) in thumb)
                       or (int(c.geom2) in mine and int(m.geom_bodyid[c.geom1]) in thumb) for c in d.contact[:d.ncon]):
                return v
    return None


def run(scene, hand, grasp: Grasp, library: dict, closed=None) -> Result:
    """Simulate ``grasp`` on the hand of ``scene`` (an export's ``description/mjcf/scene.xml``;
    ``hand`` its kinematic model); ``closed(trial)``, if given, is called when the hand has closed
    on the presented object, before it is let go (bench/grasp_figures.py draws it there)."""
    pl = plan(hand, grasp, library)
    t = Trial(scene, pl.T_object, _build(pl.shapes), presented=True)
    servos = range(len(pl.u_approach))
    # the thumb out of the object's way for the approach (at rest it lies under the palm, where a
    # palm object goes); when nothing clears it, the approach as planned (the result says so)
    approach = clear_thumb(t, hand, pl.u_approach)
    cleared = approach is not None
    approach = pl.u_approach if approach is None else approach
    t.approach({k: float(approach[k]) for k in servos}, APPROACH_S)
    start = t.position_mm()
    t.close({k: float(pl.u_close[k]) for k in servos}, CLOSE_S)
    t.command(t.top(pl.press))
    t.run(PRESS_S)
    if closed is not None:
        closed(t)
    t.release()
    t.run(RELEASE_S)
    closed_mm, saved = t.position_mm(), t.save()
    names = {}
    for b, _ in t.touching():
        names[b] = t.mj.mj_id2name(t.m, t.mj.mjtObj.mjOBJ_BODY, b)
    torque, stall = t.servo_torques(), t.stall_torques()
    g = float(np.linalg.norm(t.gravity))
    directions = {}
    for name, v in DIRECTIONS.items():
        t.restore(saved)
        t.hold(g * np.array(v, float), HOLD_S)
        slip = float(np.linalg.norm(t.position_mm() - closed_mm))
        n = len(t.touching())
        directions[name] = Direction(bool(n > 0 and slip <= HELD_MM), slip, n)
    s = scale(hand.params)
    return Result(grasp, float(t.m.body_mass[t.body]) / units.KG_PER_G, {k: v * s for k, v in grasp.size_mm.items()},
                  float(np.linalg.norm(closed_mm - start)), tuple(sorted(names.values())), directions, torque, stall,
                  t.warnings(), approach, cleared)


# -- reporting -----------------------------------------------------------------------------------

#: the table of docs/grasps.md and of ``phantom-cad grasp``: its columns
COLUMNS = ("grasp", "fig.", "object", "mass (g)") + tuple(DIRECTIONS) + ("max slip held (mm)", "torque / stall")


def describe(r: Result) -> str:
    """The object and its sizes on this hand, e.g. "cylinder 35.0 x 90.0 mm"."""
    return f"{r.grasp.kind.replace('_', ' ')} " + " x ".join(f"{v:.1f}" for v in r.size_mm.values()) + " mm"


def row(r: Result) -> tuple[str, ...]:
    """One line of the table: held or dropped per direction; the largest slip over the directions
    in which it is held ("-": none); the largest |servo torque| / stall torque when closed."""
    held = [d.slip_mm for d in r.directions.values() if d.held]
    return ((r.grasp.name, str(r.grasp.figure), describe(r), f"{r.mass_g:.1f}")
            + tuple("held" if d.held else "dropped" for d in r.directions.values())
            + (f"{max(held):.1f}" if held else "-", f"{r.torque_ratio:.2f}"))


#: the servo torques in the closed state: their columns
TORQUE_COLUMNS = ("servo torque / stall torque (N m)",) + tuple(s.label for s in SERVOS)


def torque_row(r: Result) -> tuple[str, ...]:
    return (r.grasp.name,) + tuple(f"{r.torque[s.index]:+.3f} / {r.stall[s.index]:.3f}" for s in SERVOS)


def as_dict(r: Result) -> dict:
    g = r.grasp
    return {"grasp": g.name, "figure": g.figure, "category": g.category, "description": g.description,
            "source": g.source, "object": {"kind": g.kind, "size_mm": r.size_mm, "mass_g": r.mass_g},
            "approach_deg": {sv.label: float(units.deg(r.u_approach[sv.index])) for sv in SERVOS},
            "thumb_cleared": r.cleared, "held": r.held, "released_mm": r.released_mm, "contacts": list(r.contacts),
            "directions": {k: {"held": d.held, "slip_mm": d.slip_mm, "contacts": d.touching}
                           for k, d in r.directions.items()},
            "max_slip_mm": r.max_slip_mm,
            "servos": {s.label: {"name": s.name, "torque_nm": float(r.torque[s.index]),
                                 "stall_nm": float(r.stall[s.index])} for s in SERVOS},
            "torque_ratio": r.torque_ratio, "warnings": r.warnings}
