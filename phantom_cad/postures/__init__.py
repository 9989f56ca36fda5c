"""Postures: named joint-space targets (the paper's Fig. 4, 1-13, in ``library.toml``, and a user's
own file) and what the control law makes of them on a hand (docs/postures.md). numpy only: builds
no geometry.

A posture gives the 15 joint targets (degrees, by joint name; a joint it leaves out is at 0), a
tolerance, and what to do when the commands would drive the thumb's tip into a fingertip
(``on_contact``: ``"stop"`` at the first contact or ``"refuse"``); an opposition posture names the
finger whose pad it is for. :func:`pose` clips the target into the workspace (the image of the servo
travel), runs the control law (``hand.inverse``), and, along the straight line of commands from rest
to the result, finds the first contact of the thumb's tip capsule with a fingertip capsule
(``kinematics.opposition.tip_gaps``); the error is the model's joint angles at the final commands
(``hand.forward(u, compensated=True)``) less the target as written.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import UserError, one_line
from ..kinematics import opposition
from ..kinematics.topology import FINGERS, JOINT_NAMES, N_JOINTS
from ..units import DEG

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

#: the library shipped with the package: the paper's 13 postures
LIBRARY = Path(__file__).with_name("library.toml")
ON_CONTACT = ("stop", "refuse")
#: the keys a posture must have, and those it may have
REQUIRED = ("description", "tolerance_deg", "joints_deg", "on_contact")
OPTIONAL = ("finger", "figure")
#: the first contact along the commands is found on this many steps from rest, then bisected
PATH_STEPS = 200
BISECTIONS = 30


@dataclass(frozen=True)
class Posture:
    name: str
    description: str
    target: np.ndarray          # (15,) rad, q order
    tolerance: float            # rad
    on_contact: str             # "stop" or "refuse"
    finger: str | None          # the finger an opposition posture's thumb meets
    figure: int | None          # the panel of the paper's Fig. 4, if it is one of its postures
    source: str


@dataclass(frozen=True)
class Contact:
    finger: str                 # the finger the thumb's tip meets first
    fraction: float             # how far along the commands from rest to the control law's (0..1)


@dataclass(frozen=True)
class Pose:
    """What the control law makes of a posture on a hand."""
    posture: Posture
    clipped: np.ndarray         # (15,) rad: the target clipped into the workspace
    u_law: np.ndarray           # (6,) rad: the control law's commands for the clipped target
    u: np.ndarray               # (6,) rad: the commands given (u_law, or stopped at the first contact)
    q: np.ndarray               # (15,) rad: hand.forward(u, compensated=True)
    error: np.ndarray           # (15,) rad: q - the target
    contact: Contact | None     # the first contact on the way to u_law, if any

    @property
    def worst(self) -> int:
        return int(np.argmax(np.abs(self.error)))

    @property
    def max_error(self) -> float:
        return float(np.abs(self.error).max())

    @property
    def within(self) -> np.ndarray:
        return np.abs(self.error) <= self.posture.tolerance

    @property
    def refused(self) -> bool:
        return self.contact is not None and self.posture.on_contact == "refuse"

    @property
    def wrong_finger(self) -> bool:
        """An opposition posture whose thumb meets another finger first."""
        return (self.contact is not None and self.posture.finger is not None
                and self.contact.finger != self.posture.finger)

    @property
    def reached(self) -> bool:
        return not self.refused and not self.wrong_finger and bool(self.within.all())


def _fail(source, name, field, value, rule):
    where = f"posture {name!r}: " if name is not None else ""
    raise UserError(f"{source}: {where}{field} = {one_line(repr(value))}: {rule}")


def _number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def read(path, hand) -> dict[str, Posture]:
    """The postures of a TOML file, validated against ``hand``'s joint limits (the parameter file's
    Table I): every failure one :class:`UserError` naming the file, posture, field, value and rule."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise UserError(f"{path}: not a UTF-8 text file") from None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise UserError(f"{path}: not valid TOML ({exc})") from None
    if not doc:
        raise UserError(f"{path}: no postures (each is a table [name] with {', '.join(REQUIRED)})")
    return {name: _posture(path, name, entry, hand) for name, entry in doc.items()}


def _posture(path, name, entry, hand) -> Posture:
    if not isinstance(entry, dict):
        _fail(path, None, name, entry, "must be a table [name] of a posture")
    if not name or not all(c.isascii() and (c.isalnum() or c in "-_") for c in name):
        _fail(path, name, "name", name, "must be ASCII letters, digits, '-' and '_'")
    for key in entry:
        if key not in REQUIRED + OPTIONAL:
            _fail(path, name, key, entry[key], f"unknown key (known: {', '.join(REQUIRED + OPTIONAL)})")
    for key in REQUIRED:
        if key not in entry:
            _fail(path, name, key, None, "missing (required: " + ", ".join(REQUIRED) + ")")
    desc = entry["description"]
    if not isinstance(desc, str) or not desc.strip():
        _fail(path, name, "description", desc, "must be a non-empty string")
    tol = entry["tolerance_deg"]
    if not _number(tol) or not 0.0 < tol <= 90.0:
        _fail(path, name, "tolerance_deg", tol, "must be a number in (0, 90] deg")
    mode = entry["on_contact"]
    if mode not in ON_CONTACT:
        _fail(path, name, "on_contact", mode, f"must be one of {', '.join(ON_CONTACT)}")
    finger = entry.get("finger")
    if finger is not None and finger not in FINGERS:
        _fail(path, name, "finger", finger, f"must be one of {', '.join(FINGERS)}")
    figure = entry.get("figure")
    if figure is not None and (not isinstance(figure, int) or isinstance(figure, bool) or figure < 1):
        _fail(path, name, "figure", figure, "must be a positive integer (the panel of the paper's Fig. 4)")
    joints = entry["joints_deg"]
    if not isinstance(joints, dict):
        _fail(path, name, "joints_deg", joints, "must be a table of joint name = degrees")
    target = np.zeros(N_JOINTS)
    for joint, value in joints.items():
        field = f"joints_deg.{joint}"
        if joint not in JOINT_NAMES:
            _fail(path, name, field, value, "unknown joint (known: " + ", ".join(JOINT_NAMES) + ")")
        if not _number(value):
            _fail(path, name, field, value, "must be a number of degrees")
        i = JOINT_NAMES.index(joint)
        lo, hi = hand.q_min[i] / DEG, hand.q_max[i] / DEG
        # the limits are radians in the parameter file: a value at a limit written in degrees
        # (rounded to 1e-6) is inside
        if not lo - 1e-6 <= value <= hi + 1e-6:
            _fail(path, name, field, value, f"outside the joint's limits [{lo:.6g}, {hi:.6g}] deg (Table I, "
                  f"{hand.params.source or 'the parameter file'})")
        target[i] = value * DEG
    return Posture(name, desc.strip(), target, tol * DEG, mode, finger, figure, str(path))


def load(hand, extra=None) -> dict[str, Posture]:
    """The library, and ``extra``'s postures over it (a posture of the same name replaces the
    library's)."""
    out = read(LIBRARY, hand)
    if extra is not None:
        out.update(read(extra, hand))
    return out


def first_contact(hand, u_from: np.ndarray, u_to: np.ndarray) -> Contact | None:
    """The first point of the straight line of commands from ``u_from`` to ``u_to`` where the thumb's
    tip capsule meets a fingertip's (None: it meets none): found on :data:`PATH_STEPS` steps, then
    bisected to where the gap is 0."""
    t = np.linspace(0.0, 1.0, PATH_STEPS + 1)
    path = u_from + t[:, None] * (u_to - u_from)
    gaps = opposition.tip_gaps(hand, path)
    hit = np.nonzero(gaps.min(axis=1) <= 0.0)[0]
    if not len(hit):
        return None
    k = int(hit[0])
    finger = int(np.argmin(gaps[k]))
    if k == 0:
        return Contact(FINGERS[finger], 0.0)
    lo, hi = t[k - 1], t[k]
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        if opposition.tip_gaps(hand, u_from + mid * (u_to - u_from))[0, finger] <= 0.0:
            hi = mid
        else:
            lo = mid
    # the last point still apart: commands stopped there do not press into the finger
    return Contact(FINGERS[finger], float(lo))


def command(hand, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the target clipped into the workspace, the control law's servo commands for it): joint
    targets (..., 15) rad onto the six servos, within their travel."""
    lo, hi = hand.workspace(compensated=True)
    clipped = np.clip(target, lo, hi)
    return clipped, hand.inverse(clipped, compensated=True)


def pose(hand, posture: Posture) -> Pose:
    """Clip the target into the workspace, run the control law, stop or refuse at the first contact
    of the thumb with a finger on the way from rest (the servos at the start of their travel)."""
    clipped, u_law = command(hand, posture.target)
    rest = hand.u_min.copy()
    contact = first_contact(hand, rest, u_law)
    u = u_law if contact is None or posture.on_contact == "refuse" else rest + contact.fraction * (u_law - rest)
    q = hand.forward(u, compensated=True)
    return Pose(posture, clipped, u_law, u, q, q - posture.target, contact)
