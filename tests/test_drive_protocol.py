"""The Feetech packets of phantom_cad/drive/protocol.py: against Feetech's own SDK (``scservo_sdk``,
PyPI feetech-servo-sdk) as the independent known answer, and a few worked by hand from the
documented format ``0xFF 0xFF ID LEN INSTR PARAMS... ~(ID+LEN+INSTR+sum(PARAMS))``."""

from __future__ import annotations

import pytest

from phantom_cad.drive import protocol as P
from phantom_cad.params import servos

scs = pytest.importorskip("scservo_sdk")


class Capture:
    """The SDK's port, keeping what it writes; nothing ever answers."""

    def __init__(self):
        self.is_using = False
        self.sent = []

    def clearPort(self):
        pass

    def writePort(self, packet):
        self.sent.append(bytes(packet))
        return len(packet)

    def readPort(self, length):
        return b""

    def setPacketTimeout(self, length):
        pass

    def isPacketTimeout(self):
        return True


def sdk(big_endian: bool):
    # the SDK keeps the byte order in a module global: set it for each use
    return scs.PacketHandler(1 if big_endian else 0), Capture()


def test_hand_worked_packets():
    # PING ID 1: sum 1 + 2 + 1 = 4, ~4 & 0xFF = 0xFB
    assert P.ping(1) == bytes([0xFF, 0xFF, 0x01, 0x02, 0x01, 0xFB])
    # READ ID 1, present position (56 = 0x38), 2 bytes: sum 1 + 4 + 2 + 56 + 2 = 65 = 0x41 -> 0xBE
    assert P.read(1, 56, 2) == bytes([0xFF, 0xFF, 0x01, 0x04, 0x02, 0x38, 0x02, 0xBE])
    # a status packet of ID 1 reporting overload (0x20), no parameters: sum 1 + 2 + 0x20 = 0x23 -> 0xDC
    status = P.parse_status(bytes([0xFF, 0xFF, 0x01, 0x02, 0x20, 0xDC]))
    assert (status.servo_id, status.error, status.params) == (1, 0x20, b"")
    assert P.error_text(status.error) == "overload"
    with pytest.raises(ValueError, match="checksum"):
        P.parse_status(bytes([0xFF, 0xFF, 0x01, 0x02, 0x20, 0xDD]))


@pytest.mark.parametrize("family", sorted(servos.BUS_FAMILIES))
def test_packets_match_feetechs_sdk(family):
    big = servos.BUS_FAMILIES[family].big_endian
    table = P.CONTROL_TABLES[family]
    ph, port = sdk(big)
    ph.ping(port, 3)
    ph.readTxRx(port, 4, table.present_position, 2)
    ph.write1ByteTxRx(port, 5, table.torque_enable, 1)
    ph.write2ByteTxRx(port, 6, table.goal_position, 0x0123)
    ph.write2ByteTxRx(port, 2, table.min_angle, 700)
    sync = scs.GroupSyncWrite(port, ph, table.goal_position, 2)
    for i, v in ((1, 100), (2, 1023), (6, 513)):
        sync.addParam(i, [scs.SCS_LOBYTE(v), scs.SCS_HIBYTE(v)])
    sync.txPacket()
    ours = [P.ping(3), P.read(4, table.present_position, 2), P.write(5, table.torque_enable, b"\x01"),
            P.write(6, table.goal_position, P.word(0x0123, big)), P.write(2, table.min_angle, P.word(700, big)),
            P.sync_write(table.goal_position, {i: P.word(v, big) for i, v in ((1, 100), (2, 1023), (6, 513))})]
    assert port.sent == ours


def test_word_order_is_the_familys():
    assert P.word(0x0123, True) == b"\x01\x23" and P.word(0x0123, False) == b"\x23\x01"
    assert P.unword(b"\x01\x23", True) == 0x0123 == P.unword(b"\x23\x01", False)
    assert servos.BUS_FAMILIES[servos.bus_family(servos.DEFAULT)].big_endian   # the SCS0009: SCS, high byte first


class Replay(Capture):
    """The SDK's port, answering with ``data``."""

    def __init__(self, data: bytes):
        super().__init__()
        self.data = data

    def readPort(self, length):
        out, self.data = self.data[:length], self.data[length:]
        return out


@pytest.mark.parametrize("family", sorted(servos.BUS_FAMILIES))
def test_the_sdk_reads_our_status_packets(family):
    # the simulated bus answers with P.packet(id, error, params): the SDK's receiver takes it, its
    # error byte and its word in the family's order; and refuses it with a wrong checksum
    big = servos.BUS_FAMILIES[family].big_endian
    ph, _ = sdk(big)
    frame = P.packet(4, 0x20, P.word(700, big))
    value, result, error = ph.read2ByteRx(Replay(frame), 4)
    assert (value, result, error) == (700, scs.COMM_SUCCESS, 0x20)
    _, result, _ = ph.read2ByteRx(Replay(frame[:-1] + bytes([frame[-1] ^ 1])), 4)
    assert result == scs.COMM_RX_CORRUPT


def test_sync_read_matches_feetechs_sdk():
    ph, port = sdk(False)
    sync = scs.GroupSyncRead(port, ph, P.CONTROL_TABLES["feetech-sts"].present_position, 2)
    for i in (1, 2, 6):
        sync.addParam(i)
    sync.txPacket()
    assert port.sent == [P.sync_read(P.CONTROL_TABLES["feetech-sts"].present_position, 2, (1, 2, 6))]
