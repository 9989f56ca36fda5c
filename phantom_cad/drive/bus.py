"""The serial bus (pyserial): sends the protocol's packets and reads the servos' status packets.
Every failure is a :class:`DriveError` naming the port, the servo and what went wrong."""

from __future__ import annotations

import time

from . import protocol as P
from .protocol import DriveError

#: how long a servo has to answer (s): a status packet takes well under a millisecond at 1 Mbaud
TIMEOUT = 0.1


class Bus:
    """One serial port with servos of one family on it. ``names`` maps a bus ID to the servo's
    name for messages (``u3``)."""

    def __init__(self, port: str, baud: int, big_endian: bool, timeout: float = TIMEOUT,
                 names: dict[int, str] | None = None):
        import serial

        self.port, self.big_endian, self.timeout = port, big_endian, timeout
        self.names = dict(names or {})
        try:
            self.serial = serial.Serial(port, baud, timeout=timeout, write_timeout=timeout)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise DriveError(f"port {port}: cannot be opened ({_reason(exc)}); give the bus adapter's "
                             "port with --port") from None

    def close(self) -> None:
        self.serial.close()

    def __enter__(self) -> "Bus":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def who(self, servo_id: int) -> str:
        name = self.names.get(servo_id)
        return f"servo {name} (ID {servo_id})" if name else f"servo ID {servo_id}"

    # -- transport -----------------------------------------------------------------

    def send(self, frame: bytes) -> None:
        self.serial.reset_input_buffer()    # a late answer to an earlier packet is not this one's
        try:
            self.serial.write(frame)
            self.serial.flush()
        except Exception as exc:  # pyserial raises SerialException or OSError, by platform
            raise DriveError(f"port {self.port}: cannot be written ({_reason(exc)})") from None

    def receive(self, servo_id: int, missing_ok: bool = False) -> P.Status | None:
        """The status packet of ``servo_id``: DriveError on no answer (None if ``missing_ok``), a
        corrupt packet, or error bits the servo reports."""
        deadline = time.monotonic() + self.timeout
        buf, got = b"", 0
        while True:
            start = buf.find(P.HEADER)
            if start < 0:
                buf = buf[-1:] if buf.endswith(b"\xff") else b""   # the first byte of a header, maybe
                need = 4
            else:
                buf = buf[start:]
                need = 4 if len(buf) < 4 else 4 + buf[3]
                if len(buf) >= need:
                    frame = buf[:need]
                    break
            left = deadline - time.monotonic()
            if left <= 0:
                if not got and missing_ok:
                    return None
                what = "no answer" if not got else f"an incomplete answer ({got} bytes)"
                raise DriveError(f"{self.who(servo_id)} on {self.port}: {what} within {self.timeout * 1e3:.0f} ms "
                                 "(timeout): check its cable, its power and its ID (phantom-cad drive scan)")
            self.serial.timeout = left
            chunk = self.serial.read(need - len(buf))
            got += len(chunk)
            buf += chunk
        try:
            status = P.parse_status(frame)
        except ValueError as exc:
            raise DriveError(f"{self.who(servo_id)} on {self.port}: corrupt status packet ({exc}): "
                             "check the bus's wiring and baud rate") from None
        if status.servo_id != servo_id:
            raise DriveError(f"{self.who(servo_id)} on {self.port}: answered by ID {status.servo_id}: "
                             "two servos share an ID (phantom-cad drive assign-ids)")
        if status.error:
            raise P.ServoFault(f"{self.who(servo_id)} on {self.port} reports {P.error_text(status.error)} "
                             f"(status error 0x{status.error:02X})")
        return status

    # -- instructions --------------------------------------------------------------

    def ping(self, servo_id: int) -> bool:
        """Whether a servo answers at ``servo_id`` (no answer within the timeout: False)."""
        self.send(P.ping(servo_id))
        return self.receive(servo_id, missing_ok=True) is not None

    def read(self, servo_id: int, address: int, length: int) -> bytes:
        self.send(P.read(servo_id, address, length))
        data = self.receive(servo_id).params
        if len(data) != length:
            raise DriveError(f"{self.who(servo_id)} on {self.port}: read {length} bytes at address {address}, "
                             f"got {len(data)}")
        return data

    def read_word(self, servo_id: int, address: int) -> int:
        return P.unword(self.read(servo_id, address, 2), self.big_endian)

    def write(self, servo_id: int, address: int, data: bytes) -> None:
        self.send(P.write(servo_id, address, data))
        self.receive(servo_id)

    def write_word(self, servo_id: int, address: int, value: int) -> None:
        self.write(servo_id, address, P.word(value, self.big_endian))

    def sync_write(self, address: int, data: dict[int, bytes]) -> None:
        """One broadcast packet: every servo takes its bytes at once; none answers."""
        self.send(P.sync_write(address, data))

    def sync_write_words(self, address: int, values: dict[int, int]) -> None:
        self.sync_write(address, {i: P.word(v, self.big_endian) for i, v in values.items()})


def _reason(exc: Exception) -> str:
    return str(getattr(exc, "strerror", None) or exc).strip() or type(exc).__name__
