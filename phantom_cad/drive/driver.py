"""The hand's six servos on their bus, with the safety the paper puts at the driver level
(docs/driving.md): every goal inside the servo's travel in the parameter file, ramps at a
speed no faster than the servo's rating, the servo's own angle limits and torque limit written
when it is zeroed, and a defined state after any bus error.

- Before a move writes any goal, every servo must answer with no error bit; the goals of a
  step go to all six servos in one sync write, so the hand is never half-moved: a ramp stopped
  by an error leaves every servo holding the same step's goal.
- A servo reporting overload (or overheat, overcurrent) turns every servo's torque off (the
  return cords take the fingers back toward rest); after a timeout or a corrupt packet the
  servos hold their last goal.
- A command outside the travel is refused (or, asked for, clipped into it); NaN is refused.

Servo angle ``u`` (rad) and position count: ``count = zero + sign * u / resolution``, with
``zero`` the count at u = 0 found by ``zero`` (the tendon taut with the digit straight) and
stored in a zero file, as the SCS family has no offset register.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..atomic import write_json_atomic
from ..kinematics.topology import N_SERVOS, SERVOS
from ..params import servos as catalogue
from ..units import DEG, deg
from . import protocol as P
from .bus import Bus
from .protocol import DriveError

#: goals per second of a ramp (and samples per second of a sweep)
RATE = 50.0
#: default speeds (deg/s): a move, and a sweep (slow, for the camera)
MOVE_SPEED = 90.0
SWEEP_SPEED = 30.0
#: how long a move waits at its end for the servos to reach the goal (s)
SETTLE = 0.5
ZERO_FORMAT = "phantom-cad drive zero 1"


def family_of(params) -> tuple[str, catalogue.BusFamily]:
    """The bus family of the parameter file's servo; DriveError for a servo without one."""
    name = catalogue.named(params.servo)
    key = catalogue.bus_family(name)
    if key is None:
        what = name or "the file's own servo"
        drives = ", ".join(n for n in catalogue.CATALOGUE if catalogue.bus_family(n))
        raise DriveError(f"{params.source}: [servo] is {what}, not a bus servo "
                         f"phantom-cad drive speaks to (it drives: {drives})")
    return key, catalogue.BUS_FAMILIES[key]


@dataclass(frozen=True)
class Zero:
    """Each servo's count at u = 0 and its sense (+1: the count grows as the digit flexes)."""

    counts: tuple[int, ...]
    signs: tuple[int, ...]
    source: str = "<memory>"

    def to_json(self) -> dict:
        return {"format": ZERO_FORMAT,
                "servos": {s.label: {"id": s.bus_id, "zero": self.counts[s.index], "sign": self.signs[s.index]}
                           for s in SERVOS}}


def read_zero(path) -> Zero:
    path = Path(path)
    try:
        obj = json.loads(path.read_text())
    except FileNotFoundError:
        raise DriveError(f"{path}: no zero file: zero the servos first (phantom-cad drive zero; "
                         "docs/driving.md)") from None
    except (OSError, ValueError) as exc:
        raise DriveError(f"{path}: not a zero file ({exc})") from None
    if not isinstance(obj, dict) or obj.get("format") != ZERO_FORMAT or not isinstance(obj.get("servos"), dict):
        raise DriveError(f"{path}: not a zero file (expected format {ZERO_FORMAT!r})")
    counts, signs = [], []
    for s in SERVOS:
        e = obj["servos"].get(s.label)
        if (not isinstance(e, dict) or not isinstance(e.get("zero"), int) or e.get("sign") not in (1, -1)
                or e.get("id") != s.bus_id):
            raise DriveError(f"{path}: servo {s.label}: expected {{\"id\": {s.bus_id}, \"zero\": <count>, "
                             f"\"sign\": 1 or -1}}, found {e!r}")
        counts.append(e["zero"])
        signs.append(e["sign"])
    return Zero(tuple(counts), tuple(signs), str(path))


class Driver:
    """The hand (``hand``: its travel and servo) on ``bus``; ``zero`` None until zeroed."""

    def __init__(self, bus: Bus, hand, zero: Zero | None = None):
        self.bus, self.hand, self.zero = bus, hand, zero
        self.family_name, self.family = family_of(hand.params)
        self.table = P.CONTROL_TABLES[self.family_name]
        self.resolution = self.family.span_deg * DEG / self.family.counts     # rad per count
        self.ids = {s.bus_id: s.label for s in SERVOS}
        self.bus.names.update(self.ids)
        self.rated_speed = hand.params.servo.speed                            # rad/s
        self.lo, self.hi = np.asarray(hand.u_min, float), np.asarray(hand.u_max, float)
        if zero is not None:
            self.bounds = self.count_bounds(zero)

    # -- units -----------------------------------------------------------------------

    def count_bounds(self, zero: Zero) -> tuple[np.ndarray, np.ndarray]:
        """The lowest and highest count of each servo whose angle lies inside its travel;
        DriveError when the travel does not fit in the servo's counts from its zero."""
        z, sg = np.asarray(zero.counts, float), np.asarray(zero.signs, float)
        ends = np.stack([z + sg * self.lo / self.resolution, z + sg * self.hi / self.resolution])
        cmin = np.ceil(ends.min(axis=0) - 1e-9).astype(int)
        cmax = np.floor(ends.max(axis=0) + 1e-9).astype(int)
        for s in SERVOS:
            i = s.index
            if cmin[i] < 0 or cmax[i] > self.family.counts - 1:
                raise DriveError(f"{zero.source}: servo {s.label}'s travel [{deg(self.lo[i]):.1f}, "
                                 f"{deg(self.hi[i]):.1f}] deg from its zero count {zero.counts[i]} needs counts "
                                 f"[{cmin[i]}, {cmax[i]}], beyond the servo's 0..{self.family.counts - 1}: "
                                 "move its horn a spline tooth toward the middle and zero again")
        return cmin, cmax

    def to_counts(self, u) -> np.ndarray:
        """Goal counts of angles inside the travel, rounded and kept inside it."""
        z, sg = np.asarray(self.zero.counts, float), np.asarray(self.zero.signs, float)
        c = np.rint(z + sg * np.asarray(u, float) / self.resolution).astype(int)
        return np.clip(c, *self.bounds)

    def to_angles(self, counts) -> np.ndarray:
        z, sg = np.asarray(self.zero.counts, float), np.asarray(self.zero.signs, float)
        return sg * (np.asarray(counts, float) - z) * self.resolution

    def checked(self, u, clip: bool = False) -> np.ndarray:
        """``u`` (6 angles, rad) if every one is a number inside its servo's travel; with ``clip``
        the ones outside are clipped into it. DriveError otherwise, naming the servo, the value
        and the travel."""
        u = np.asarray(u, dtype=float)
        if u.shape != (N_SERVOS,):
            raise DriveError(f"a command gives {N_SERVOS} servo angles (u1..u6), not {u.size}")
        for s in SERVOS:
            i = s.index
            if not math.isfinite(u[i]):
                raise DriveError(f"servo {s.label}: {u[i]} is not a number: refused")
            if not clip and not self.lo[i] - 1e-9 <= u[i] <= self.hi[i] + 1e-9:
                raise DriveError(f"servo {s.label}: {deg(u[i]):.2f} deg is outside its travel [{deg(self.lo[i]):.2f}, "
                                 f"{deg(self.hi[i]):.2f}] deg ({self.hand.params.source}): refused "
                                 "(--clip clips it into the travel)")
        return np.clip(u, self.lo, self.hi)

    def speed(self, deg_s: float) -> float:
        """A ramp speed (rad/s) no faster than the servo's rating."""
        if not (math.isfinite(deg_s) and deg_s > 0):
            raise DriveError(f"speed {deg_s} deg/s: must be a positive number")
        if deg_s * DEG > self.rated_speed * (1 + 1e-9):
            raise DriveError(f"speed {deg_s:g} deg/s is above the servo's rated {deg(self.rated_speed):g} deg/s "
                             f"({self.hand.params.source} [servo] speed_deg_s): refused")
        return deg_s * DEG

    # -- bus -------------------------------------------------------------------------

    def scan(self, max_id: int) -> list[tuple[int, int, tuple[int, int], int, str | None]]:
        """(ID, model number, firmware (major, minor), present position count, servo label or None)
        of every servo answering at IDs 0..max_id."""
        found = []
        for i in range(max_id + 1):
            if self.bus.ping(i):
                fw = self.bus.read(i, self.table.firmware, 2)
                found.append((i, self.bus.read_word(i, self.table.model), (fw[0], fw[1]),
                              self.bus.read_word(i, self.table.present_position), self.ids.get(i)))
        return found

    def present(self) -> np.ndarray:
        """Every servo's present position (counts): each must answer with no error bit."""
        return np.array([self.bus.read_word(s.bus_id, self.table.present_position) for s in SERVOS])

    def positions(self) -> np.ndarray:
        return self.to_angles(self.present())

    def torque(self, on: bool) -> None:
        """Torque on or off on every servo (on: each servo goes to its goal register: see :meth:`hold`)."""
        self.present()      # every servo answers before any is written
        self.bus.sync_write(self.table.torque_enable, {s.bus_id: bytes([int(on)]) for s in SERVOS})

    def hold(self, speed: float) -> np.ndarray:
        """Torque on, each servo held where it is, or brought at ``speed`` to the nearest end of its
        travel if it is outside."""
        return self.move(np.clip(self.positions(), self.lo, self.hi), speed)

    def assign_id(self, label: str, old_id: int) -> int:
        """Give the one servo on the bus at ``old_id`` the bus ID of servo ``label``."""
        servo = next((s for s in SERVOS if s.label == label), None)
        if servo is None:
            raise DriveError(f"no servo {label!r} (servos: {', '.join(s.label for s in SERVOS)})")
        if not self.bus.ping(old_id):
            raise DriveError(f"no servo answers at ID {old_id} on {self.bus.port}: connect the servo to number "
                             f"alone, and give its present ID with --from (a new servo has ID "
                             f"{self.family.factory_id})")
        if old_id != servo.bus_id and self.bus.ping(servo.bus_id):
            raise DriveError(f"ID {servo.bus_id} ({label}) already answers on {self.bus.port}: connect only the "
                             "servo to number, alone on the bus")
        if old_id != servo.bus_id:
            self._eeprom(old_id, self.table.id, bytes([servo.bus_id]), servo.bus_id)
        if not self.bus.ping(servo.bus_id):
            raise DriveError(f"servo {label}: no answer at its new ID {servo.bus_id} on {self.bus.port}")
        return servo.bus_id

    def _eeprom(self, servo_id: int, address: int, data: bytes, new_id: int | None = None) -> None:
        """Write the servo's EEPROM: unlock, write, lock again (at its new ID when the write changes it)."""
        self.bus.write(servo_id, self.table.lock, b"\x00")
        self.bus.write(servo_id, address, data)
        self.bus.write(servo_id if new_id is None else new_id, self.table.lock, b"\x01")

    def set_zero(self, signs=None, torque_limit: float = 1.0) -> Zero:
        """The tensioning step (docs/assembly.md): with every digit straight and its tendon taut,
        the present positions are u = 0. Writes each servo's angle limits (its travel) and torque
        limit into its EEPROM, so the servo itself refuses to leave the travel."""
        if not 0.0 < torque_limit <= 1.0:
            raise DriveError(f"torque limit {torque_limit}: must be in (0, 1] (a fraction of the stall torque)")
        signs = tuple(signs or (1,) * N_SERVOS)
        self.torque(False)
        zero = Zero(tuple(int(c) for c in self.present()), signs)
        cmin, cmax = self.count_bounds(zero)
        for s in SERVOS:
            i = s.index
            self._eeprom(s.bus_id, self.table.min_angle, P.word(int(cmin[i]), self.family.big_endian)
                         + P.word(int(cmax[i]), self.family.big_endian))
            self._eeprom(s.bus_id, self.table.max_torque, P.word(round(1000 * torque_limit), self.family.big_endian))
        self.zero, self.bounds = zero, (cmin, cmax)
        return zero

    # -- motion ----------------------------------------------------------------------

    def _goals(self, u) -> None:
        self.bus.sync_write_words(self.table.goal_position,
                                  {s.bus_id: int(c) for s, c in zip(SERVOS, self.to_counts(u))})

    def move(self, u, speed: float, clip: bool = False, sample=None) -> np.ndarray:
        """Ramp every servo from where it is to ``u`` (rad, checked against the travel) at
        ``speed`` (rad/s, the fastest servo's); ``sample(t)`` is called after each step.
        Returns the present angles at the end."""
        if self.zero is None:
            raise DriveError("the servos are not zeroed: phantom-cad drive zero first")
        target = self.checked(u, clip)
        start = np.clip(self.positions(), self.lo, self.hi)    # every servo answers first
        steps = max(1, math.ceil(float(np.abs(target - start).max()) / speed * RATE))
        t0 = time.monotonic()
        try:
            # the goal registers first: torque on sends a servo to whatever its register holds
            self._goals(start)
            self.bus.sync_write(self.table.torque_enable, {s.bus_id: b"\x01" for s in SERVOS})
            for k in range(1, steps + 1):
                self._goals(start + (target - start) * (k / steps))
                _sleep_until(t0 + k / RATE)
                if sample is not None:
                    sample(time.monotonic() - t0)
            goal = self.to_counts(target)
            for k in range(steps + 1, steps + 1 + math.ceil(SETTLE * RATE)):
                if np.abs(self.present() - goal).max() <= 1:
                    break
                _sleep_until(t0 + k / RATE)
                if sample is not None:     # the end of the ramp, where the servos catch up: sampled too
                    sample(time.monotonic() - t0)
            end = self.positions()
            if sample is not None:
                sample(time.monotonic() - t0)
            return end
        except DriveError as exc:
            raise self.stopped(exc) from None

    def stopped(self, exc: DriveError) -> DriveError:
        """After an error: torque off if a servo reported an error bit, else hold; the message says which."""
        if isinstance(exc, P.ServoFault):
            try:
                self.bus.sync_write(self.table.torque_enable, {s.bus_id: b"\x00" for s in SERVOS})
                return DriveError(f"{exc}; torque off on every servo")
            except DriveError:
                pass
        return DriveError(f"{exc}; the servos hold their last goal")

    def sweep(self, speed: float):
        """The calibration sweep: each servo in turn from rest up its travel and back down at
        ``speed`` (rad/s), the others at rest, sampling every servo's present position.
        Returns (t, sweep labels, u): the times (s), each row's servo label, the angles (rad)."""
        rows_t, rows_s, rows_u = [], [], []
        t_start = time.monotonic()
        rest = self.lo.copy()
        self.move(rest, min(MOVE_SPEED * DEG, self.rated_speed))
        for s in SERVOS:
            def sample(_t, label=s.label):
                rows_t.append(time.monotonic() - t_start)
                rows_s.append(label)
                rows_u.append(self.positions())
            up = rest.copy()
            up[s.index] = self.hi[s.index]
            sample(0.0)
            self.move(up, speed, sample=sample)
            self.move(rest, speed, sample=sample)
        return np.array(rows_t), rows_s, np.array(rows_u)


def _sleep_until(t: float) -> None:
    left = t - time.monotonic()
    if left > 0:
        time.sleep(left)


def write_zero(path, zero: Zero) -> None:
    write_json_atomic(path, zero.to_json())
