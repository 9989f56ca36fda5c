"""What a person's hand gives the sizing: the hand length and breadth, and optionally measured
segment lengths and widths (a TOML file, docs/sizing.md). Every malformed or contradictory input is
a :class:`~phantom_cad.errors.UserError` of one line that names the input, its value, its limit and
the nearest input that works. numpy-free."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

from ..errors import UserError, one_line
from ..kinematics.topology import DIGITS, chain

#: the keys a digit's table of a segments file may hold: its segments (the fingers' metacarpals lie
#: inside the palm, where a person's cannot be measured on the skin) and its width
SEGMENT_KEYS = {d: tuple(s for s in chain(d).segments if d == "thumb" or s != "metacarpal") + ("width",)
                for d in DIGITS}


@dataclass(frozen=True)
class Person:
    """A person's hand in millimetres: ``segments[digit][key]`` the measured lengths and widths
    (any subset of :data:`SEGMENT_KEYS`)."""
    hand_length: float
    hand_breadth: float
    side: str = "right"
    name: str = "sized"
    segments: dict = field(default_factory=dict)


def read_segments(path: str | os.PathLike) -> dict[str, dict[str, float]]:
    """The measured lengths of a segments file: ``{digit: {key: mm}}``; a UserError naming the
    file, the key and the rule for anything else."""
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except FileNotFoundError:
        raise UserError(f"{path}: no such segments file") from None
    except IsADirectoryError:
        raise UserError(f"{path}: is a folder, not a segments file") from None
    except UnicodeDecodeError as exc:
        raise UserError(f"{path}: is not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise UserError(f"{path}: cannot be read ({exc.strerror})") from None
    except tomllib.TOMLDecodeError as exc:
        raise UserError(f"{path}: is not valid TOML: {exc}") from None
    out: dict[str, dict[str, float]] = {}
    for digit, table in doc.items():
        if digit not in SEGMENT_KEYS:
            raise UserError(f"{path}: unknown table [{one_line(digit)}] (allowed: {', '.join(DIGITS)})")
        if not isinstance(table, dict):
            raise UserError(f"{path}: {one_line(digit)} = {one_line(table)!s}: must be a table [{digit}] of "
                            f"lengths in mm ({', '.join(SEGMENT_KEYS[digit])})")
        out[digit] = {}
        for key, value in table.items():
            where = f"{path}: {digit}.{one_line(key)}"
            if key not in SEGMENT_KEYS[digit]:
                raise UserError(f"{where}: unknown key (allowed in [{digit}]: {', '.join(SEGMENT_KEYS[digit])}, "
                                "lengths in mm, joint centre to joint centre)")
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise UserError(f"{where} = {one_line(value)}: must be a length in mm (a finite number)")
            if value <= 0.0:
                raise UserError(f"{where} = {value:g} mm: must be > 0 mm (a length, joint centre to joint "
                                "centre)")
            out[digit][key] = float(value)
    return out


def check_person(person: Person, lengths: dict[str, dict[str, float]]) -> None:
    """Refuse a person whose measured lengths contradict the hand length: a segment as long as the
    hand, or a middle finger (metacarpal, phalanges) that leaves no carpus between the metacarpals'
    bases and the wrist crease the hand length is measured from."""
    hl = person.hand_length
    for digit, segs in lengths.items():
        for key, v in segs.items():
            if v >= hl:
                raise UserError(f"segments {digit}.{key} = {v:g} mm: must be shorter than the hand length "
                                f"({hl:g} mm, wrist crease to the middle fingertip); nearest that works: "
                                f"--hand-length {math.floor(v) + 1:g} or {digit}.{key} < {hl:g}")
    m = lengths["middle"]
    total = sum(m.values())
    if total >= hl:
        given = ", ".join(k for k in person.segments.get("middle", {}) if k != "width")
        raise UserError(f"the middle finger (metacarpal + proximal + middle + distal = {total:.1f} mm, "
                        f"{given or 'none'} from --segments) must be shorter than the hand length "
                        f"({hl:g} mm, wrist crease to the middle fingertip: the carpus lies between); nearest "
                        f"that works: --hand-length {math.floor(total) + 1:g}, or middle-finger segments "
                        f"{total - hl + 1:.1f} mm shorter in all")
