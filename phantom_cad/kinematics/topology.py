"""The hand's one topology: servos, joints, links and tendons as records.

Pure data (no numpy, no numbers that describe a particular hand), imported by every layer:
every index, name list and parent table the code needs is derived here from the records, and
no other module retypes one. Numbering is 0-based in code; labels (``q1``, ``u1``,
``servo_pulley_1``) are 1-based, as in the paper.

Joint vector q (15, radians), index -> label (the paper's Table I):
    0 q1 thumb IP, 1 q2 thumb MP,
    2..4 q3..q5 index DIP, PIP, MCP, 5..7 middle, 8..10 ring, 11..13 pinky,
    14 q15 thumb CMC.
Servo vector u (6, radians): 0 u1 thumb flexion, 1..4 u2..u5 index..pinky, 5 u6 thumb CMC.
Every servo sits in the forearm module; servo 6 turns the CMC through a closed cable loop of equal
pulley radii (q15 = cmc_gain u6, eq. 9).
"""

from __future__ import annotations

from dataclasses import dataclass

FINGERS = ("index", "middle", "ring", "pinky")
#: the fingers whose pads the thumb's pad must reach (the paper's opposition postures 1-3)
OPPOSED_FINGERS = ("index", "middle", "ring")
DIGITS = ("thumb",) + FINGERS


# ---------------------------------------------------------------------------
# records
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class Servo:
    """One servo: ``index`` 0-5 in u order; it drives a tendon chain, or the thumb CMC through a
    closed cable loop."""

    index: int
    digit: str
    drive: str          # "tendon" (a chain's drive tendon) or "loop" (the CMC's cable loop)

    @property
    def label(self) -> str:
        """``u1``..``u6``: the measurement column and the paper's name."""
        return f"u{self.index + 1}"

    @property
    def bus_id(self) -> int:
        """The servo's ID on the serial bus (``phantom-cad drive assign-ids``): its number, 1..6,
        as in its label."""
        return self.index + 1

    @property
    def name(self) -> str:
        return f"{self.digit}_flexion" if self.drive == "tendon" else f"{self.digit}_abduction"

    @property
    def link(self) -> str:
        """The servo's pulley link, on the forearm module (:data:`SERVO_MOUNT`)."""
        return f"servo_pulley_{self.index + 1}"

    @property
    def actuator(self) -> str:
        """``servo1``..``servo6``: the actuator's name in the MJCF."""
        return f"servo{self.index + 1}"

    @property
    def title(self) -> str:
        """``servo 1``..``servo 6``: how messages and documents name the servo."""
        return f"servo {self.index + 1}"


@dataclass(frozen=True)
class Joint:
    """One revolute joint: ``index`` 0-14 in q order (Table I)."""

    index: int
    digit: str
    key: str            # "mcp", "pip", "dip", "mp", "ip", "cmc"
    parent: str         # parent link name
    child: str          # child link name
    servo: int          # the servo that moves it
    reference: str      # its chain's reference (cosine-law) joint; the CMC is its own

    @property
    def name(self) -> str:
        return f"{self.digit}_{self.key}"

    @property
    def label(self) -> str:
        return f"q{self.index + 1}"

    @property
    def is_reference(self) -> bool:
        return self.reference == self.name


@dataclass(frozen=True)
class Link:
    """One rigid link (one printed part): ``parent_joint`` None means fixed to ``parent``."""

    name: str
    parent: str | None       # None for the root (palm)
    parent_joint: str | None
    digit: str | None
    segment: str             # "palm", "forearm", "base", "cmc_base", "cmc_pulley", "proximal", "middle",
                             # "distal", "servo_pulley"
    servo: int | None = None

    @property
    def length_key(self) -> str | None:
        """The ``length_fraction`` key of the segment whose length runs from this link's
        proximal joint to the next one (None: the palm, finger bases, servo pulleys)."""
        return {"cmc_base": "metacarpal", "proximal": "proximal", "middle": "middle",
                "distal": "distal"}.get(self.segment)


@dataclass(frozen=True)
class Chain:
    """A tendon-driven digit: its servo and the joints it flexes, reference joint first."""

    digit: str
    servo: int
    keys: tuple[str, ...]        # ("mcp", "pip", "dip") or ("mp", "ip")
    q_index: tuple[int, ...]     # 0-based q indices, same order
    segments: tuple[str, ...]    # length keys proximal -> distal, e.g. ("metacarpal", "proximal", ...)

    @property
    def spans(self) -> tuple[tuple[str, str], ...]:
        """(path key, crossed segment) between consecutive joints: ``("mcp_pip", "proximal")``, ..."""
        return tuple((f"{a}_{b}", self.segments[k + 1]) for k, (a, b) in enumerate(zip(self.keys, self.keys[1:])))

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(f"{self.digit}_{k}" for k in self.keys)


@dataclass(frozen=True)
class Tendon:
    """A cable: ``kind`` drive (servo -> reference joint), coupling (figure-eight loop between
    adjacent joints), return (the dorsal cable-spring) or loop (the closed loop from servo 6's
    pulley to the CMC's); ``links`` the links it runs on."""

    name: str
    kind: str
    digit: str
    links: tuple[str, ...]
    joints: tuple[str, ...]      # the joints it crosses
    servo: int | None = None


# ---------------------------------------------------------------------------
# the hand
# ---------------------------------------------------------------------------

_FINGER_KEYS = ("mcp", "pip", "dip")                 # reference joint first
_FINGER_SEGMENTS = ("metacarpal", "proximal", "middle", "distal")
_FINGER_LINKS = ("base", "proximal", "middle", "distal")
_THUMB_KEYS = ("mp", "ip")
_THUMB_SEGMENTS = ("metacarpal", "proximal", "distal")
_THUMB_LINKS = ("cmc_base", "proximal", "distal")

#: servos in u order: one tendon servo per digit (thumb first), then the CMC's loop drive
SERVOS = tuple(Servo(i, d, "tendon") for i, d in enumerate(DIGITS)) + (Servo(len(DIGITS), "thumb", "loop"),)
N_SERVOS = len(SERVOS)
CMC_SERVO = SERVOS[-1].index
#: the forearm module: the link (fixed to the palm behind the wrist crease) that carries the servos
FOREARM = "forearm"
#: the link a servo of each drive is mounted on: every servo in the forearm module (the tendon
#: drives and the CMC's loop cross the wrist; docs/parts.md says why servo 6 is not at the CMC)
SERVO_MOUNT = {"tendon": FOREARM, "loop": FOREARM}
#: the pulley the CMC's loop turns: a link fixed to the CMC base, on its column inside the palm
CMC_PULLEY = "thumb_cmc_pulley"
#: the tendon servos' slice of u (servos 0..4)
TENDON_SERVOS = slice(0, len(DIGITS))


def _digit_links(digit: str, segments: tuple[str, ...], keys: tuple[str, ...], root_joint: str | None):
    """The links of one digit, proximal first; the first hangs on the palm."""
    names = [f"{digit}_{s}" for s in segments]
    out = [Link(names[0], "palm", root_joint, digit, segments[0])]
    for parent, name, seg, key in zip(names, names[1:], segments[1:], keys):
        out.append(Link(name, parent, f"{digit}_{key}", digit, seg))
    return out


def _build():
    links = [Link("palm", None, None, None, "palm"), Link(FOREARM, "palm", None, None, "forearm")]
    for f in FINGERS:
        links += _digit_links(f, _FINGER_LINKS, _FINGER_KEYS, None)
    links += _digit_links("thumb", _THUMB_LINKS, _THUMB_KEYS, "thumb_cmc")
    links.append(Link(CMC_PULLEY, "thumb_cmc_base", None, None, "cmc_pulley"))
    links += [Link(s.link, SERVO_MOUNT[s.drive], None, None, "servo_pulley", s.index) for s in SERVOS]
    by_child = {ln.parent_joint: ln for ln in links if ln.parent_joint}

    chains, joints = [], []
    # q order of Table I: thumb IP, MP; each finger DIP, PIP, MCP; thumb CMC last
    for servo in SERVOS[:len(DIGITS)]:
        digit = servo.digit
        keys = _THUMB_KEYS if digit == "thumb" else _FINGER_KEYS
        segments = _THUMB_SEGMENTS if digit == "thumb" else _FINGER_SEGMENTS
        base = len(joints)
        q_index = tuple(base + len(keys) - 1 - k for k in range(len(keys)))   # distal first in q
        for key in reversed(keys):
            child = by_child[f"{digit}_{key}"]
            joints.append(Joint(len(joints), digit, key, child.parent, child.name, servo.index,
                                f"{digit}_{keys[0]}"))
        chains.append(Chain(digit, servo.index, keys, q_index, segments))
    cmc = by_child["thumb_cmc"]
    joints.append(Joint(len(joints), "thumb", "cmc", cmc.parent, cmc.name, CMC_SERVO, "thumb_cmc"))

    tendons = []
    for ch in chains:
        ln = [f"{ch.digit}_{s}" for s in (_THUMB_LINKS if ch.digit == "thumb" else _FINGER_LINKS)]
        names = ch.joint_names
        tendons.append(Tendon(f"{ch.digit}_drive", "drive", ch.digit,
                              (SERVOS[ch.servo].link, FOREARM, "palm", ln[0], ln[1]), names[:1], ch.servo))
        for k, (a, b) in enumerate(zip(ch.keys, ch.keys[1:])):
            tendons.append(Tendon(f"{ch.digit}_{a}_{b}", "coupling", ch.digit, tuple(ln[k:k + 3]),
                                  (names[k], names[k + 1])))
        tendons.append(Tendon(f"{ch.digit}_return", "return", ch.digit, tuple(ln), names))
    tendons.append(Tendon("thumb_cmc_loop", "loop", "thumb", (SERVOS[CMC_SERVO].link, FOREARM, "palm", CMC_PULLEY),
                          ("thumb_cmc",), CMC_SERVO))
    return tuple(links), tuple(joints), tuple(chains), tuple(tendons)


LINKS, JOINTS, CHAINS, TENDONS = _build()
N_JOINTS = len(JOINTS)
CMC_Q = JOINTS[-1].index
THUMB_CHAIN = CHAINS[0]
FINGER_CHAINS = CHAINS[1:]

#: names in q / u / tree order
JOINT_NAMES = tuple(j.name for j in JOINTS)
Q_COLUMNS = tuple(j.label for j in JOINTS)
U_COLUMNS = tuple(s.label for s in SERVOS)
SERVO_NAMES = tuple(s.name for s in SERVOS)
LINK_NAMES = tuple(ln.name for ln in LINKS)
#: the servo of every joint, q order
JOINT_SERVO = tuple(j.servo for j in JOINTS)
#: joints that carry a tendon deviation (PIP, DIP, thumb IP): every chain joint but the reference
DISTAL_JOINTS = tuple(sorted(i for c in CHAINS for i in c.q_index[1:]))

_JOINT = {j.name: j for j in JOINTS}
_LINK = {ln.name: ln for ln in LINKS}
_CHAIN = {c.digit: c for c in CHAINS}


def joint(name: str) -> Joint:
    return _JOINT[name]


def link(name: str) -> Link:
    return _LINK[name]


def chain(digit: str) -> Chain:
    """The tendon chain of ``digit``."""
    return _CHAIN[digit]


def joint_index(digit: str, key: str) -> int:
    """0-based q index of ``digit``'s joint ``key`` (e.g. ``("index", "dip") -> 2``)."""
    return _JOINT[f"{digit}_{key}"].index


def servo_joints(servo: int) -> tuple[int, ...]:
    """q indices moved by ``servo`` (0-based), its chain's reference joint first."""
    if servo == CMC_SERVO:
        return (CMC_Q,)
    return CHAINS[servo].q_index


def digit_links(digit: str) -> tuple[Link, ...]:
    """The links of ``digit`` (its base first)."""
    return tuple(ln for ln in LINKS if ln.digit == digit)
