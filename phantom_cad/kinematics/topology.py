"""The hand's fixed topology: joint and servo indices of the paper's Table I.

Pure data, no numbers that describe a particular hand.

Joint vector q (15, radians), 0-based index -> paper label:
    0 q1 thumb IP, 1 q2 thumb MP,
    2..4 q3..q5 index DIP, PIP, MCP, 5..7 middle, 8..10 ring, 11..13 pinky,
    14 q15 thumb CMC.
Servo vector u (6, radians): 0 u1 thumb flexion, 1..4 u2..u5 index..pinky, 5 u6 thumb CMC.
"""

from __future__ import annotations

from dataclasses import dataclass

FINGERS = ("index", "middle", "ring", "pinky")
DIGITS = ("thumb",) + FINGERS
N_JOINTS = 15
N_SERVOS = 6

#: tendon-driven finger joints, distal first, as in Table I
FINGER_JOINTS = ("dip", "pip", "mcp")
THUMB_JOINTS = ("ip", "mp")


@dataclass(frozen=True)
class Chain:
    """One tendon: a servo and the joints it flexes, reference (cosine-law) joint first."""

    digit: str
    servo: int                   # 0-based servo index
    joints: tuple[str, ...]      # joint names, reference joint first (mcp or mp)
    q_index: tuple[int, ...]     # 0-based q indices, same order as joints


def _finger_chain(i: int, name: str) -> Chain:
    base = 2 + 3 * i  # dip index
    return Chain(name, 1 + i, ("mcp", "pip", "dip"), (base + 2, base + 1, base))


THUMB_CHAIN = Chain("thumb", 0, ("mp", "ip"), (1, 0))
FINGER_CHAINS = tuple(_finger_chain(i, n) for i, n in enumerate(FINGERS))
#: the five tendon chains in servo order (servo 0..4)
CHAINS = (THUMB_CHAIN,) + FINGER_CHAINS
CMC_Q = 14
CMC_SERVO = 5

#: joint names in q order, e.g. "index_dip"
JOINT_NAMES = ("thumb_ip", "thumb_mp") + tuple(
    f"{f}_{j}" for f in FINGERS for j in FINGER_JOINTS
) + ("thumb_cmc",)
#: column names of the measurement format
Q_COLUMNS = tuple(f"q{i + 1}" for i in range(N_JOINTS))
U_COLUMNS = tuple(f"u{i + 1}" for i in range(N_SERVOS))
SERVO_NAMES = ("thumb_flexion",) + tuple(f"{f}_flexion" for f in FINGERS) + ("thumb_cmc",)


def joint_index(digit: str, joint: str) -> int:
    """0-based q index of ``digit``'s ``joint`` (e.g. ``("index", "dip") -> 2``)."""
    return JOINT_NAMES.index(f"{digit}_{joint}")
