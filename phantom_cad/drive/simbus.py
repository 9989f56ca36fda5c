"""A simulated servo bus: a pseudo-terminal whose other end answers the Feetech protocol from a
thread, as six servos would (``phantom-cad drive sim``; the driver's tests).

Each servo keeps the family's control table in memory and moves its position toward its goal
at its rated speed (rate limited, counted on the wall clock), only while its torque is on and
within the angle limits written to it. Faults can be injected per servo, after a number of
packets addressed to it: ``missing`` (never answers), ``timeout`` (stops answering),
``checksum`` (answers with a corrupt checksum), ``overload`` (reports the overload error bit and
drops its torque, as the servo's own protection does).
"""

from __future__ import annotations

import os
import select
import threading
import time
import tty
from dataclasses import dataclass, field

from ..params import servos as catalogue
from . import protocol as P

FAULTS = ("missing", "timeout", "checksum", "overload")
#: the model number and firmware (major, minor) a simulated servo reports
SIM_MODEL = 9
SIM_FIRMWARE = (3, 10)


@dataclass(frozen=True)
class Fault:
    kind: str                   # one of FAULTS
    servo_id: int
    after: int = 0              # packets addressed to the servo that are answered normally first


@dataclass
class SimServo:
    servo_id: int
    counts: int
    big_endian: bool
    speed: float                # counts per second at full speed
    table: P.ControlTable
    position: float = 0.0
    mem: bytearray = field(default_factory=lambda: bytearray(128))
    goals: list[int] = field(default_factory=list)   # every goal written, in order
    last: float = field(default_factory=time.monotonic)
    seen: int = 0

    def __post_init__(self):
        t = self.table
        self.position = float(self.counts // 2)
        self.mem[t.firmware], self.mem[t.firmware + 1] = SIM_FIRMWARE
        self._put(t.model, SIM_MODEL)
        self.mem[t.id] = self.servo_id
        self._put(t.min_angle, 0)
        self._put(t.max_angle, self.counts - 1)
        self._put(t.max_torque, 1000)
        self.mem[t.lock] = 1
        self._put(t.goal_position, int(self.position))
        self.mem[62], self.mem[63] = 60, 30   # 6.0 V, 30 deg C

    def _put(self, address: int, value: int) -> None:
        self.mem[address:address + 2] = P.word(value, self.big_endian)

    def _get(self, address: int) -> int:
        return P.unword(self.mem[address:address + 2], self.big_endian)

    @property
    def goal(self) -> int:
        return self._get(self.table.goal_position)

    def step(self) -> None:
        now = time.monotonic()
        dt, self.last = now - self.last, now
        if self.mem[self.table.torque_enable]:
            d = self.goal - self.position
            self.position += max(-self.speed * dt, min(self.speed * dt, d))
        self._put(self.table.present_position, int(round(self.position)))
        self.mem[self.table.moving] = int(abs(self.goal - self.position) > 0.5)

    def write(self, address: int, data: bytes) -> None:
        self.step()
        t = self.table
        for k, b in enumerate(data):
            a = address + k
            if a < t.torque_enable and self.mem[t.lock] and a != t.lock:
                continue    # EEPROM is written only unlocked, as on the servo
            self.mem[a] = b
        if address <= t.goal_position < address + len(data):
            lo, hi = self._get(t.min_angle), self._get(t.max_angle)
            goal = min(max(self.goal, lo), hi)    # the servo holds its goal within its angle limits
            self._put(t.goal_position, goal)
            self.goals.append(goal)
        if address <= t.id < address + len(data):
            self.servo_id = self.mem[t.id]


class SimBus:
    """Six (or ``ids``) simulated servos of a catalogue bus family (``servos.BUS_FAMILIES``) on a
    pseudo-terminal: ``port`` is its name."""

    def __init__(self, family, ids=range(1, 7), faults=(), speed_deg_s: float = 600.0):
        self.family = family
        self.table = P.CONTROL_TABLES[next(k for k, f in catalogue.BUS_FAMILIES.items() if f == family)]
        speed = speed_deg_s * family.counts / family.span_deg
        self.servos = [SimServo(i, family.counts, family.big_endian, speed, self.table) for i in ids]
        self.faults = list(faults)
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        self.port = os.ttyname(self._slave)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="simbus", daemon=True)
        self._thread.start()

    def __enter__(self) -> "SimBus":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        self._stop.set()
        self._thread.join()
        os.close(self._master)
        os.close(self._slave)

    def servo(self, servo_id: int) -> SimServo | None:
        return next((s for s in self.servos if s.servo_id == servo_id), None)

    def fault(self, servo_id: int, seen: int) -> str | None:
        return next((f.kind for f in self.faults if f.servo_id == servo_id and seen > f.after), None)

    # -- the servos' side of the wire ----------------------------------------------

    def _run(self) -> None:
        buf = b""
        while not self._stop.is_set():
            ready, _, _ = select.select([self._master], [], [], 0.02)
            if not ready:
                continue
            try:
                buf += os.read(self._master, 4096)
            except OSError:
                return
            while True:
                start = buf.find(P.HEADER)
                if start < 0 or len(buf) < start + 4 or len(buf) < start + 4 + buf[start + 3]:
                    buf = buf[start:] if start >= 0 else buf[-1:]
                    break
                end = start + 4 + buf[start + 3]
                frame, buf = buf[start:end], buf[end:]
                if frame[-1] == P.checksum(frame[2:-1]):   # a servo ignores a corrupt instruction
                    self._answer(frame[2], frame[4], frame[5:-1])

    def _answer(self, servo_id: int, instruction: int, params: bytes) -> None:
        if servo_id == P.BROADCAST_ID:
            if instruction == P.SYNC_WRITE:
                address, n = params[0], params[1]
                for k in range(2, len(params), n + 1):
                    s = self.servo(params[k])
                    if s is not None and self.fault(s.servo_id, s.seen) not in ("missing", "timeout"):
                        s.write(address, params[k + 1:k + 1 + n])
            return
        s = self.servo(servo_id)
        if s is None:
            return
        s.seen += 1
        kind = self.fault(servo_id, s.seen)
        if kind in ("missing", "timeout"):
            return
        s.step()
        error = 0
        data = b""
        if instruction == P.READ:
            data = bytes(s.mem[params[0]:params[0] + params[1]])
        elif instruction == P.WRITE:
            s.write(params[0], params[1:])
        if kind == "overload":
            error = 0x20
            s.mem[self.table.torque_enable] = 0
        frame = P.packet(servo_id, error, data)
        if kind == "checksum":
            frame = frame[:-1] + bytes([frame[-1] ^ 0x5A])
        os.write(self._master, frame)
