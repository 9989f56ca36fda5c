"""The Feetech serial-bus servo protocol (SCS and STS families): packets, the control table,
status errors. Pure bytes: no port, no time (``bus.py`` sends them; ``simbus.py`` answers them).

An instruction packet is ``0xFF 0xFF ID LEN INSTR PARAMS... CHECKSUM`` with ``LEN = len(PARAMS) + 2``
and ``CHECKSUM = ~(ID + LEN + INSTR + sum(PARAMS)) & 0xFF``; a status packet is the same with the
servo's error byte in place of ``INSTR``. Two-byte registers are high byte first on the SCS family
and low byte first on the STS family (``BusFamily.big_endian`` in the servo catalogue).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import UserError

HEADER = b"\xff\xff"
BROADCAST_ID = 0xFE
MAX_ID = 0xFD

PING = 0x01
READ = 0x02
WRITE = 0x03
SYNC_READ = 0x82
SYNC_WRITE = 0x83

#: status error bits, as the servo reports them (the SDK's ERRBIT_*)
ERROR_BITS = {0x01: "input voltage", 0x02: "angle sensor", 0x04: "overheat", 0x08: "overcurrent",
              0x20: "overload"}


class DriveError(UserError):
    """A bus or servo error (no port, no answer, a corrupt packet, a servo reporting an error) or a
    command the driver refuses: one ``error:`` line on the command line."""


class ServoFault(DriveError):
    """A servo's status packet reports an error bit (overload, overheat, ...)."""


@dataclass(frozen=True)
class ControlTable:
    """Register addresses of a servo family (the Feetech memory tables SCSCL and SMS_STS)."""

    firmware: int = 0           # major, minor (1 byte each)
    model: int = 3              # 2 bytes
    id: int = 5
    baud: int = 6
    min_angle: int = 9          # 2 bytes, position counts (EEPROM): the servo refuses goals beyond
    max_angle: int = 11
    max_torque: int = 16        # 2 bytes, per mille of stall (EEPROM)
    torque_enable: int = 40
    goal_position: int = 42     # 2 bytes, then goal time (44) and goal speed (46)
    lock: int = 48              # 0: EEPROM writable; 1: locked
    present_position: int = 56  # 2 bytes, then speed (58), load (60), voltage (62, 0.1 V), temperature (63, deg C)
    moving: int = 66


CONTROL_TABLES = {"feetech-scs": ControlTable(), "feetech-sts": ControlTable(lock=55)}


def checksum(body: bytes) -> int:
    """``~sum(body) & 0xFF`` over ID, LEN, INSTR/ERROR and the parameters."""
    return ~sum(body) & 0xFF


def packet(servo_id: int, instruction: int, params: bytes = b"") -> bytes:
    """An instruction packet (or, with an error byte as ``instruction``, a status packet)."""
    if not 0 <= servo_id <= BROADCAST_ID:
        raise ValueError(f"servo ID {servo_id} is outside 0..{BROADCAST_ID}")
    body = bytes([servo_id, len(params) + 2, instruction]) + bytes(params)
    return HEADER + body + bytes([checksum(body)])


def ping(servo_id: int) -> bytes:
    return packet(servo_id, PING)


def read(servo_id: int, address: int, length: int) -> bytes:
    return packet(servo_id, READ, bytes([address, length]))


def write(servo_id: int, address: int, data: bytes) -> bytes:
    return packet(servo_id, WRITE, bytes([address]) + bytes(data))


def sync_write(address: int, data: dict[int, bytes]) -> bytes:
    """One broadcast packet writing ``data[id]`` (all the same length) at ``address`` of every servo."""
    lengths = {len(d) for d in data.values()}
    if len(lengths) != 1:
        raise ValueError("a sync write gives every servo the same number of bytes")
    params = bytes([address, lengths.pop()]) + b"".join(bytes([i]) + bytes(d) for i, d in data.items())
    return packet(BROADCAST_ID, SYNC_WRITE, params)


def sync_read(address: int, length: int, ids) -> bytes:
    return packet(BROADCAST_ID, SYNC_READ, bytes([address, length, *ids]))


def word(value: int, big_endian: bool) -> bytes:
    """A two-byte register value in the family's byte order."""
    return int(value & 0xFFFF).to_bytes(2, "big" if big_endian else "little")


def unword(data: bytes, big_endian: bool) -> int:
    return int.from_bytes(bytes(data[:2]), "big" if big_endian else "little")


def signed(value: int, sign_bit: int) -> int:
    """A sign-magnitude register (present speed and load: bit 15 or 10 is the sign)."""
    return -(value & ~(1 << sign_bit)) if value & (1 << sign_bit) else value


@dataclass(frozen=True)
class Status:
    servo_id: int
    error: int
    params: bytes


def parse_status(frame: bytes) -> Status:
    """A status packet's fields; ValueError naming what is wrong (header, length, checksum)."""
    if len(frame) < 6 or frame[:2] != HEADER:
        raise ValueError("no status packet header (0xFF 0xFF)")
    length = frame[3]
    if len(frame) != length + 4:
        raise ValueError(f"status packet of {len(frame)} bytes, its length byte says {length + 4}")
    if frame[-1] != checksum(frame[2:-1]):
        raise ValueError(f"checksum 0x{frame[-1]:02X}, expected 0x{checksum(frame[2:-1]):02X}")
    return Status(frame[2], frame[4], bytes(frame[5:-1]))


def error_text(error: int) -> str:
    """The status error bits by name (``overload``, ``overheat and input voltage``)."""
    names = [n for bit, n in ERROR_BITS.items() if error & bit]
    unknown = error & ~sum(ERROR_BITS) & 0xFF
    if unknown:
        names.append(f"bits 0x{unknown:02X}")
    return " and ".join(names)
