"""CO401Memory1 end to end: python-canopen as the CANopen master and a serial host on the
simulator's RS232 port, both against `coforge sim co401memory1`.

Every test starts its own simulator with the serial host on a TCP port (`--serial 0`) and its
console on stdin (`supply <mV>`, `corrupt <bank> <offset> <value>`, `outputs`) for fault
injection. The CANopen side uses the EDS file `coforge eds` exports; the serial side is a plain
pyserial `socket://` port, i.e. the byte stream of the RS232 line. Expected bytes are the
datasheet's examples in their corrected form (spec `serial.commands[].examples`, errata
MEM-21..MEM-25) and the frames of `firmware/devices/co401memory1/tests/device.rs`.

Facts about a fresh simulator the tests rely on: blank EEPROM banks are formatted at boot, so
both bank status bytes (6000h.1/.2) read 0x40 "bank cleared" and both bank-error emergencies
are active until the host sends command 0x91 to 6200h.1/.2; every memory byte reads 0.

Sections: 1. python-canopen (SDO access to the memory and checksums, TPDO1 default and
remapped, RPDO1 commands, supply guard, corrupted banks); 2. the serial host (datasheet
examples, negative answers, garbage and resync, memory shared with SDO); 3. erratum MEM-27 and
NMT resets.

Timing: the simulator runs in real time and frames and serial bytes travel over TCP, so every
wait has a timeout; the serial receiver resynchronises after a pause of 100 ms, which the tests
make 250 ms. Console commands take effect at the module's next step, so tests wait for their
consequence (an emergency), not for the console's answer.
"""

import pathlib
import re
import subprocess
import tempfile
import time
import types

from bus import Recorder, connect_attached
from simproc import SerialLine, SimProcess
import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError
from serial.urlhandler import protocol_socket
from host import COFORGE, ROOT

SPEC = ROOT / "spec" / "co401memory1.yaml"

# The simulated board puts this node-ID on the ID0..ID6 pins (--node-id sets the pins).
NODE_ID = 0x15

START, STOP, PRE_OP, RESET_NODE, RESET_COMM = 0x01, 0x02, 0x80, 0x81, 0x82
OPERATIONAL, PRE_OPERATIONAL, STOPPED = 0x05, 0x7F, 0x04

CLEAR = 0x91  # 6200h command: clear all error flags and status of the bank
CLEARED = 0x40  # 6000h bit 6: the bank was formatted
CORRUPT = 0x30  # 6000h bits 4 + 5: checksum error, data rewritten from the other bank

# CiA 301 SDO abort codes
ABORT_STATE = 0x08000022  # data cannot be stored because of the present device state
ABORT_NO_OBJECT = 0x06020000
ABORT_NO_SUB = 0x06090011
ABORT_READ_ONLY = 0x06010002
ABORT_WRITE_ONLY = 0x06010001

BLOCK, RECORD = 128, 4  # bank layout: per block 128 data bytes, then a 4-byte commit record

SERIAL_PAUSE = 0.25  # > the 100 ms resync pause of the nibble framing
SDO_TIMEOUT = 1.0


def coforge(*args):
    return subprocess.run([COFORGE, *map(str, args)], check=True, capture_output=True, text=True, timeout=60).stdout


def h(text):
    """'44 12 50' -> bytes."""
    return bytes.fromhex(text)


def spec_emcy_example(name):
    """The `example:` frame of emergency `name` in the spec (canonical layout, one key a line)."""
    text = SPEC.read_text()
    part = text[text.index("\nemergencies:") : text.index("\nserial:")]
    m = re.search(rf"^  - name: {name}\n(?:    .*\n)*?    example: ([0-9A-Fa-f ]+)$", part, re.M)
    assert m, f"no example for emergency {name} in the spec"
    return bytes.fromhex(m.group(1))


def eventually(fn, timeout=1.0):
    """Polls `fn` until it returns something true (python-canopen handles frames on its own
    thread, just after the recorder sees them)."""
    deadline = time.monotonic() + timeout
    while True:
        got = fn()
        if got or time.monotonic() > deadline:
            return got
        time.sleep(0.01)


def eeprom_offset(index, sub):
    """Offset of the data byte of memory object `index`, sub-index `sub` in a bank."""
    block = index - 0x5000
    return block * (BLOCK + RECORD) + sub - 1


# --------------------------------------------------------------------------------------------
# The serial host: a pyserial port on the simulator's RS232 line.
# --------------------------------------------------------------------------------------------


class SerialHost(SerialLine):
    def __init__(self, url):
        super().__init__(url)
        self.log = []  # (request, answer) of every xfer, as hex text

    def answer(self, timeout=2.0):
        """One frame from the device (command byte, then LEN data bytes), or None."""
        deadline = time.monotonic() + timeout
        head = self._read(1, deadline)
        if not head:
            return None
        data = self._read(head[0] & 0x0F, deadline)
        assert len(data) == head[0] & 0x0F, f"answer cut short: {(head + data).hex(' ')}"
        return head + data

    def xfer(self, request, timeout=2.0):
        """Sends one frame and returns the device's answer as hex text ('' for none)."""
        stale = self.port.read_all() if self.port.in_waiting else b""
        assert not stale, f"unexpected bytes from the device before {request.hex(' ')}: {stale.hex(' ')}"
        self.send(request)
        a = self.answer(timeout)
        text = a.hex(" ").upper() if a else ""
        self.log.append((request.hex(" ").upper(), text))
        return text

    def silent(self, timeout=0.3):
        """Nothing arrives within `timeout`."""
        deadline = time.monotonic() + timeout
        got = self._read(1, deadline)
        return got == b""

    def pause(self):
        time.sleep(SERIAL_PAUSE)


def X(text):
    """Canonical hex text of an answer ('32 01 23')."""
    return text.upper()


# --------------------------------------------------------------------------------------------
# A simulator with python-canopen and the serial host connected.
# --------------------------------------------------------------------------------------------


@pytest.fixture(scope="session")
def od():
    """The dictionary python-canopen builds from our EDS file, imported once (8000+ entries)."""
    with tempfile.TemporaryDirectory() as d:
        eds = pathlib.Path(d) / "co401memory1.eds"
        coforge("eds", SPEC, "-o", eds)
        return canopen.import_od(str(eds), NODE_ID)


class Sim:
    def __init__(self, od):
        self.node_id = NODE_ID
        args = [COFORGE, "sim", "co401memory1", "--node-id", str(NODE_ID), "--port", "0", "--serial", "0"]
        self.sim = SimProcess(args)
        self.net = self.serial = None
        try:
            serial_url = self.sim.banner(r"serial host on (socket://\S+)")
            can_url = self.sim.banner(rf"co401memory1 node-ID {NODE_ID} on slcan (socket://\S+)")
            self.net = canopen.Network()
            self.net.NOTIFIER_CYCLE = 0.05
            self.rec = Recorder()
            self.net.listeners.insert(0, self.rec)  # sees each frame before python-canopen does
            connect_attached(self.net, can_url, 500000)
            self.node = canopen.RemoteNode(NODE_ID, od)
            self.node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT
            self.net.add_node(self.node)
            self.serial = SerialHost(serial_url)
        except BaseException:
            self.close()
            raise

    def console(self, command, timeout=5.0):
        return self.sim.console(command, timeout)

    def close(self):
        try:
            with pytest.MonkeyPatch.context() as mp:
                # pyserial's socket:// close() sleeps 0.3 s "in case of quick reconnects".
                mp.setattr(protocol_socket, "time", types.SimpleNamespace(sleep=lambda _s: None))
                if self.serial is not None:
                    self.serial.close()
                if self.net is not None:
                    self.net.disconnect()
        finally:
            self.sim.stop()

    # CANopen helpers -------------------------------------------------------------------------

    @property
    def emcy_cob(self):
        return 0x80 + self.node_id

    @property
    def tpdo1_cob(self):
        return 0x180 + self.node_id

    @property
    def rpdo1_cob(self):
        return 0x200 + self.node_id

    def nmt(self, command):
        self.node.nmt.send_command(command)

    def guarded_state(self, timeout=1.0):
        """The NMT state from a node guarding answer (also proves earlier frames were handled)."""
        cob = 0x700 + self.node_id
        mark = self.rec.mark()
        self.net.send_message(cob, b"", remote=True)
        f = self.rec.wait(cob, mark, timeout, lambda f: len(f.data) == 1 and f.data != b"\x00")
        assert f is not None, "no answer to the node guarding request"
        return f.data[0] & 0x7F

    def read(self, index, sub=0):
        return self.node.sdo.upload(index, sub)

    def read_int(self, index, sub=0):
        return int.from_bytes(self.read(index, sub), "little")

    def write_int(self, index, sub, value, size=1):
        self.node.sdo.download(index, sub, value.to_bytes(size, "little"))

    def abort_code(self, fn, *args):
        with pytest.raises(SdoAbortedError) as e:
            fn(*args)
        return e.value.code

    def wait_emcy(self, mark, data, timeout=2.0):
        """The first EMCY after `mark` whose 8 bytes are `data`, or None."""
        return self.rec.wait(self.emcy_cob, mark, timeout, lambda f: f.data == data)

    def emcys(self, mark):
        return [f.data.hex(" ") for f in self.rec.since(mark, self.emcy_cob)]

    def clear_banks(self):
        """Command 0x91 to both banks over SDO; waits for the emergencies that follow."""
        mark = self.rec.mark()
        self.write_int(0x6200, 1, CLEAR)
        self.write_int(0x6200, 2, CLEAR)
        assert self.wait_emcy(mark, bytes(8)) is not None, f"no error reset after clearing both banks: {self.emcys(mark)}"
        assert (self.read_int(0x6000, 1), self.read_int(0x6000, 2)) == (0, 0)


@pytest.fixture
def sim(od):
    s = Sim(od)
    try:
        yield s
    finally:
        s.close()


# ============================================================================================
# 1. python-canopen through the simulator hub
# ============================================================================================


def test_boot_state(sim):
    """A fresh module: formatted banks reported as cleared, both bank errors active."""
    assert sim.node.sdo[0x1008].raw == "CO401Memory1"
    assert sim.read_int(0x1014) == 0x80 + NODE_ID, "the node-ID comes from the ID pins"
    assert (sim.read_int(0x6000, 0), sim.read_int(0x6000, 1), sim.read_int(0x6000, 2)) == (2, CLEARED, CLEARED)
    assert sim.read_int(0x2105) == 0x03, "2105h: bank 1 and bank 2 error"
    assert sim.read_int(0x1001) == 0x01
    assert sim.read_int(0x5F00) == 24000
    assert (sim.read_int(0x5C00, 0), sim.read_int(0x5C00, 1), sim.read_int(0x5C00, 2)) == (2, 0, 0)
    assert "mem1_error: true, mem2_error: true, new_can_data: false, voltage_low: false" in sim.console("outputs")
    assert sim.serial.xfer(h("00")) == X("04 40 40 03 00")


def test_sdo_memory_bytes_and_bank_checksums(sim):
    """Memory bytes over SDO (several objects and subs, 503Fh sub 80h, sub 0 = 128) and the
    5C00h bank checksums against a host-side sum of everything written."""
    for index in (0x5000, 0x5001, 0x5012, 0x5020, 0x503F):
        assert sim.node.sdo[index][0].raw == 128, f"{index:04X}h sub 0"
    assert sim.read_int(0x503F, 0x80) == 0
    written = {}

    def write(index, sub, value):
        sim.node.sdo[index][sub].raw = value
        written[(index, sub)] = value

    values = {
        (0x5000, 0x01): 0x11,
        (0x5000, 0x80): 0xFF,
        (0x5001, 0x01): 0x5A,
        (0x5012, 0x04): 0x23,
        (0x5020, 0x40): 0x80,
        (0x502A, 0x7F): 0x01,
        (0x503F, 0x01): 0xC3,
        (0x503F, 0x80): 0xA5,
    }
    for (index, sub), value in values.items():
        write(index, sub, value)
    for (index, sub), value in values.items():
        assert sim.node.sdo[index][sub].raw == value, f"{index:04X}h sub {sub:#04x}"
        assert sim.read(index, sub) == bytes([value])
    # Neighbours stay untouched.
    assert sim.read_int(0x503F, 0x7F) == 0 and sim.read_int(0x5001, 0x02) == 0
    # Overwrite some: the checksums follow the stored contents, not the write history.
    write(0x5000, 0x80, 0x01)
    write(0x5012, 0x04, 0x00)
    write(0x503F, 0x80, 0xFE)
    expected = sum(written.values())
    assert expected == 0x11 + 0x01 + 0x5A + 0x00 + 0x80 + 0x01 + 0xC3 + 0xFE
    assert sim.node.sdo[0x5C00][1].raw == expected
    assert sim.node.sdo[0x5C00][2].raw == expected
    assert sim.read(0x5C00, 1) == expected.to_bytes(4, "little"), "5C00h is UNSIGNED32"
    # Refusals: read-only sub 0, no sub 81h, no object 5040h, checksums read-only.
    assert sim.abort_code(sim.write_int, 0x5000, 0, 1) == ABORT_READ_ONLY
    assert sim.abort_code(sim.write_int, 0x5000, 0x81, 1) == ABORT_NO_SUB
    assert sim.abort_code(sim.read, 0x503F, 0x81) == ABORT_NO_SUB
    assert sim.abort_code(sim.write_int, 0x5040, 1, 1) == ABORT_NO_OBJECT
    assert sim.abort_code(sim.write_int, 0x5C00, 1, 0, 4) == ABORT_READ_ONLY
    assert sim.abort_code(sim.read, 0x5E00, 1) == ABORT_WRITE_ONLY, "monitoring bytes: the host reads them with C0"
    assert sim.node.sdo[0x5C00][1].raw == expected
    # The serial host sees the same bytes.
    assert sim.serial.xfer(h("33 3F 50 80")) == X("32 01 FE")


def test_default_tpdo1_sends_bank_status_on_change(sim):
    """TPDO1 maps 6000h.1/.2 by default (event-driven, type 255); a change of the bank status
    sends it in Operational and only there."""
    assert sim.read_int(0x1800, 1) == 0x180 + NODE_ID
    assert sim.read_int(0x1800, 2) == 255
    assert [sim.read_int(0x1A00, s) for s in range(3)] == [2, 0x60000108, 0x60000208]
    sim.node.tpdo.read()
    tpdo = sim.node.tpdo[1]
    assert [(v.index, v.subindex) for v in tpdo.map] == [(0x6000, 1), (0x6000, 2)]
    assert tpdo.cob_id == sim.tpdo1_cob and tpdo.enabled

    # Pre-operational: clearing bank 1 changes the status, but no PDO goes out.
    mark = sim.rec.mark()
    sim.write_int(0x6200, 1, CLEAR)
    assert sim.read_int(0x6000, 1) == 0
    assert sim.rec.wait(sim.tpdo1_cob, mark, 0.3) is None, "TPDO1 sent in pre-operational"

    sim.nmt(START)
    assert sim.guarded_state() == OPERATIONAL
    # Clearing bank 2 in Operational: TPDO1 right away (its 1 s event timer is not needed).
    mark = sim.rec.mark()
    sim.write_int(0x6200, 2, CLEAR)
    written = time.monotonic()
    f = sim.rec.wait(sim.tpdo1_cob, mark, 1.5, lambda f: f.data == h("00 00"))
    assert f is not None, f"no TPDO1 00 00 after clearing bank 2: {[str(x) for x in sim.rec.since(mark, sim.tpdo1_cob)]}"
    assert f.t - written < 0.5, f"TPDO1 {f.t - written:.3f} s after the change"
    assert eventually(lambda: [v.raw for v in tpdo.map] == [0, 0]), "python-canopen decodes 6000h.1/.2 from TPDO1"
    # The default event timer (1800h.5 = 1000 ms) repeats it without a change.
    assert sim.read_int(0x1800, 5) == 1000
    again = sim.rec.wait(sim.tpdo1_cob, sim.rec.mark(), 2.0)
    assert again is not None and again.data == h("00 00"), f"event timer TPDO1: {again}"
    gap = again.t - f.t
    assert 0.7 <= gap <= 1.5, f"TPDO1 repeated after {gap:.3f} s, event timer 1000 ms"


def test_tpdo1_remapped_by_python_canopen(sim):
    """Remapping TPDO1 in pre-operational through python-canopen's PDO API: 6000h.2, 1001h,
    6000h.1 without event timer; the status TPDO follows each change, and only a change."""
    sim.node.tpdo.read()
    tpdo = sim.node.tpdo[1]
    tpdo.clear()
    tpdo.add_variable(0x6000, 2, 8)
    tpdo.add_variable(0x1001, 0, 8)
    tpdo.add_variable(0x6000, 1, 8)
    tpdo.trans_type = 255
    tpdo.event_timer = 0
    tpdo.enabled = True
    tpdo.save()
    assert [sim.read_int(0x1A00, s) for s in range(4)] == [3, 0x60000208, 0x10010008, 0x60000108]
    assert sim.read_int(0x1800, 5) == 0 and sim.read_int(0x1800, 1) == sim.tpdo1_cob

    sim.nmt(START)
    assert sim.guarded_state() == OPERATIONAL
    # The mapping cannot change in Operational (erratum MEM-35).
    assert sim.abort_code(sim.write_int, 0x1A00, 0, 0) == ABORT_STATE
    assert sim.read_int(0x1A00, 0) == 3
    mark = sim.rec.mark()
    assert sim.rec.wait(sim.tpdo1_cob, mark, 0.4) is None, "event timer 0 and no event: no TPDO"

    # RPDO1 clears bank 1: status 00/40, error register still 01 (bank 2).
    mark = sim.rec.mark()
    sim.net.send_message(sim.rpdo1_cob, bytes([CLEAR, 0x00]))
    f = sim.rec.wait(sim.tpdo1_cob, mark, 1.0)
    assert f is not None and f.data == h("40 01 00"), f"TPDO1 after clearing bank 1: {f}"
    # Bank 2 as well: everything clear.
    mark = sim.rec.mark()
    sim.net.send_message(sim.rpdo1_cob, bytes([0x00, CLEAR]))
    f = sim.rec.wait(sim.tpdo1_cob, mark, 1.0)
    assert f is not None and f.data == h("00 00 00"), f"TPDO1 after clearing bank 2: {f}"
    assert eventually(lambda: tpdo.data == f.data)
    assert [(v.index, v.subindex, v.raw) for v in tpdo.map] == [(0x6000, 2, 0), (0x1001, 0, 0), (0x6000, 1, 0)]
    # 0x91 again changes nothing, so nothing is sent.
    mark = sim.rec.mark()
    sim.net.send_message(sim.rpdo1_cob, bytes([CLEAR, CLEAR]))
    assert sim.rec.wait(sim.tpdo1_cob, mark, 0.3) is None, "TPDO1 without a status change"


def test_rpdo1_command_clears_bank_status(sim):
    """RPDO1 (200h + node-ID, 2 bytes = 6200h.1, 6200h.2) carries the bank commands."""
    assert sim.read_int(0x1400, 1) == 0x200 + NODE_ID
    assert [sim.read_int(0x1600, s) for s in range(3)] == [2, 0x62000108, 0x62000208]
    # Not processed outside Operational.
    sim.net.send_message(sim.rpdo1_cob, bytes([CLEAR, CLEAR]))
    assert (sim.read_int(0x6000, 1), sim.read_int(0x6000, 2)) == (CLEARED, CLEARED)
    assert sim.read_int(0x6200, 1) == 0

    sim.nmt(START)
    mark = sim.rec.mark()
    sim.net.send_message(sim.rpdo1_cob, bytes([CLEAR, 0x00]))
    assert (sim.read_int(0x6000, 1), sim.read_int(0x6000, 2)) == (0, CLEARED)
    assert (sim.read_int(0x6200, 1), sim.read_int(0x6200, 2)) == (CLEAR, 0)
    # Error reset; bank 2's code (CO40xx 0x20) is still active.
    assert sim.wait_emcy(mark, h("00 00 01 00 20 00 00 00")) is not None, sim.emcys(mark)
    assert sim.read_int(0x2105) == 0x02

    # Bank 2 through python-canopen's RPDO API.
    sim.node.rpdo.read()
    rpdo = sim.node.rpdo[1]
    assert [(v.index, v.subindex) for v in rpdo.map] == [(0x6200, 1), (0x6200, 2)]
    rpdo.map[0].raw = 0x00
    rpdo.map[1].raw = CLEAR
    mark = sim.rec.mark()
    rpdo.transmit()
    assert sim.wait_emcy(mark, bytes(8)) is not None, f"no error reset: {sim.emcys(mark)}"
    assert (sim.read_int(0x6000, 1), sim.read_int(0x6000, 2)) == (0, 0)
    assert (sim.read_int(0x6200, 1), sim.read_int(0x6200, 2)) == (0, CLEAR)
    assert sim.read_int(0x1001) == 0 and sim.read_int(0x2105) == 0
    assert eventually(lambda: sim.node.emcy.active == [])
    assert sim.serial.xfer(h("00")) == X("04 00 00 00 00")


def test_low_supply_refuses_writes_and_sends_the_voltage_emergencies(sim):
    sim.clear_banks()
    sim.node.sdo[0x5000][1].raw = 0x11
    sim.node.emcy.reset()
    mark = sim.rec.mark()
    assert sim.console("supply 14000") == "supply 14000 mV"
    voltage_low = spec_emcy_example("voltage_low")
    assert voltage_low == h("00 10 01 00 40 00 00 00")
    emcy = sim.wait_emcy(mark, voltage_low)
    assert emcy is not None, f"no voltage-low EMCY: {sim.emcys(mark)}"
    assert sim.read_int(0x5F00) == 14000
    # SDO write refused, value unchanged; 2105h bit 7, 1001h.
    assert sim.abort_code(sim.write_int, 0x5000, 1, 0x22) == ABORT_STATE
    assert sim.node.sdo[0x5000][1].raw == 0x11, "a refused write stores nothing"
    assert sim.read_int(0x2105) & 0x80
    assert sim.read_int(0x1001) == 0x01
    # The serial host is refused too and sees STATE7# in SOR.
    assert sim.serial.xfer(h("44 00 50 01 22")) == X("41 00")
    assert sim.serial.xfer(h("00")) == X("04 00 00 80 00")
    assert sim.serial.xfer(h("33 00 50 01")) == X("32 01 11"), "reading still works"
    assert "voltage_low: true" in sim.console("outputs")
    # python-canopen's EMCY consumer.
    active = eventually(lambda: [(e.code, e.register, e.data) for e in sim.node.emcy.active])
    assert active == [(0x1000, 0x01, h("00 40 00 00 00"))]

    # Critical (below 11 V): both codes ORed.
    mark = sim.rec.mark()
    sim.console("supply 10000")
    assert sim.wait_emcy(mark, h("00 10 01 00 C0 00 00 00")) is not None, sim.emcys(mark)
    # Inside the 200 mV hysteresis nothing changes.
    mark = sim.rec.mark()
    sim.console("supply 11100")
    time.sleep(0.2)
    assert sim.emcys(mark) == []
    assert sim.abort_code(sim.write_int, 0x5000, 1, 0x22) == ABORT_STATE

    # Recovery: one error reset per condition, the last one with nothing left.
    mark = sim.rec.mark()
    sim.console("supply 24000")
    last = sim.wait_emcy(mark, bytes(8))
    assert last is not None, f"no error reset EMCY after recovery: {sim.emcys(mark)}"
    assert sim.emcys(mark) == ["00 00 01 00 80 00 00 00", "00 00 00 00 00 00 00 00"]
    assert eventually(lambda: sim.node.emcy.active == [])
    sim.node.sdo[0x5000][1].raw = 0x22
    assert sim.node.sdo[0x5000][1].raw == 0x22
    assert sim.read_int(0x2105) == 0 and sim.read_int(0x1001) == 0
    assert sim.read_int(0x5F00) == 24000

    # 15 V threshold with hysteresis: below 15000 low, back only at 15200.
    mark = sim.rec.mark()
    sim.console("supply 14999")
    assert sim.wait_emcy(mark, h("00 10 01 00 40 00 00 00")) is not None, sim.emcys(mark)
    sim.console("supply 15100")
    assert sim.abort_code(sim.write_int, 0x5000, 1, 0x33) == ABORT_STATE
    mark = sim.rec.mark()
    sim.console("supply 15200")
    assert sim.wait_emcy(mark, bytes(8)) is not None, sim.emcys(mark)
    sim.write_int(0x5000, 1, 0x33)
    assert sim.read_int(0x5000, 1) == 0x33


@pytest.mark.parametrize("bank", [1, 2])
def test_corrupt_bank_is_detected_reported_and_repaired(sim, bank):
    """A byte corrupted in one bank: the next read detects it (EMCY, 6000h = 0x30, TPDO1),
    returns the committed value and repairs the bank; 0x91 clears the report."""
    index, sub, value = 0x5030, 3, 0x77  # block 48: the 1 s/block scrub reaches it after ~49 s
    sim.clear_banks()
    sim.node.sdo[index][sub].raw = value
    sim.nmt(START)
    assert sim.guarded_state() == OPERATIONAL
    offset = eeprom_offset(index, sub)
    # The console reports the old byte: the layout is as documented.
    assert sim.console(f"corrupt {bank} {offset} 0x78") == f"bank {bank} offset {offset}: 0x77 -> 0x78"
    other = 3 - bank
    code = 0x10 if bank == 1 else 0x20

    mark = sim.rec.mark()
    assert sim.read_int(index, sub) == value, "the committed value, from the intact bank"
    expected = spec_emcy_example(f"memory_bank{bank}_error")
    assert expected == bytes([0x00, 0x10, 0x01, 0x00, code, 0, 0, 0])
    emcy = sim.wait_emcy(mark, expected)
    assert emcy is not None, f"no bank {bank} error EMCY: {sim.emcys(mark)}"
    assert sim.emcys(mark) == [emcy.data.hex(" ")], "exactly one EMCY"
    assert sim.read_int(0x6000, bank) == CORRUPT
    assert sim.read_int(0x6000, other) == 0
    assert sim.read_int(0x2105) == (0x01 if bank == 1 else 0x02)
    assert sim.read_int(0x1001) == 0x01
    status = h("30 00") if bank == 1 else h("00 30")
    f = sim.rec.wait(sim.tpdo1_cob, mark, 1.5, lambda f: f.data == status)
    assert f is not None, f"no TPDO1 {status.hex(' ')}: {[str(x) for x in sim.rec.since(mark, sim.tpdo1_cob)]}"
    assert sim.serial.xfer(h("00")) == X(f"04 {status.hex(' ')} {1 << (bank - 1):02X} 00")
    assert sim.serial.xfer(h("33 30 50 03")) == X("32 01 77")
    # Repaired: the bank holds the committed byte again, and both checksums agree.
    assert sim.console(f"corrupt {bank} {offset} 0x77") == f"bank {bank} offset {offset}: 0x77 -> 0x77"
    assert sim.read_int(0x5C00, 1) == sim.read_int(0x5C00, 2) == value

    # 0x91 by RPDO1 clears the report: error reset, TPDO1 00 00.
    mark = sim.rec.mark()
    sim.net.send_message(sim.rpdo1_cob, bytes([CLEAR if bank == 1 else 0, CLEAR if bank == 2 else 0]))
    assert sim.wait_emcy(mark, bytes(8)) is not None, sim.emcys(mark)
    assert sim.rec.wait(sim.tpdo1_cob, mark, 1.5, lambda f: f.data == h("00 00")) is not None
    assert sim.read_int(0x6000, bank) == 0 and sim.read_int(0x1001) == 0


# ============================================================================================
# 2. The serial host
# ============================================================================================


def spec_serial_examples():
    """`bytes:` of every serial.commands[].examples entry of the spec (no YAML library needed:
    the canonical spec layout has one `- bytes: ...` line per example)."""
    text = SPEC.read_text()
    serial_part = text[text.index("\nserial:") : text.index("\nerrata:")]
    return [m.group(1).upper() for m in re.finditer(r'^\s*- bytes: "?([0-9A-Fa-f ]+?)"?\s*$', serial_part, re.M)]


def test_serial_datasheet_examples(sim):
    host = sim.serial
    # Read Status: 04 MS1 MS2 SOR Res (banks formatted, both error outputs active).
    assert host.xfer(h("00")) == X("04 40 40 03 00")
    # Write Command Registers, ADR 1 and 2 (0x12, MEM-22; ADR 2 = 6200h.2, MEM-23).
    assert host.xfer(h("12 01 91")) == X("11 01")
    assert host.xfer(h("12 02 91")) == X("11 01")
    assert host.xfer(h("00")) == X("04 00 00 00 00")
    assert (sim.read_int(0x6200, 1), sim.read_int(0x6200, 2)) == (CLEAR, CLEAR)
    # Write then Read Memory Array Data of 5012h.04 (example 33 12 50 04, MEM-24).
    assert host.xfer(h("44 12 50 04 23")) == X("41 01")
    assert host.xfer(h("33 12 50 04")) == X("32 01 23")
    assert sim.read_int(0x5012, 4) == 0x23
    # Setup CAN Monitoring for 0x123: RPDO2's COB-ID.
    assert host.xfer(h("83 00 23 01")) == X("81 01")
    assert sim.read_int(0x1401, 1) == 0x123
    # A frame 0x123 B1..B5 from another node on the bus.
    sim.net.send_message(0x123, h("B1 B2 B3 B4 B5"))
    assert sim.read_int(0x2105) == 0x10, "2105h bit 4: new CAN monitoring data"  # SDO after the frame: seen
    assert host.xfer(h("00")) == X("04 00 00 10 00"), "SOR bit 4 (STATE4#)"
    # Read Received CAN Data (C0, MEM-25).
    assert host.xfer(h("C0")) == X("C6 01 B1 B2 B3 B4 B5")
    assert sim.read_int(0x2105) == 0
    assert host.xfer(h("C0")) == X("C1 00"), "nothing new: the negative answer"
    # Write CAN data: the frame goes out on the bus.
    mark = sim.rec.mark()
    assert host.xfer(h("D5 23 01 B1 B2 B3")) == X("D1 01")
    f = sim.rec.wait(0x123, mark, 1.0)
    assert f is not None, "no CAN frame 0x123 after D5 23 01 B1 B2 B3"
    assert f.data == h("B1 B2 B3") and not f.rtr
    # MEM-36: monitored frames of any length, in any NMT state, are not RPDOs (no 8210h).
    sim.nmt(START)
    assert sim.guarded_state() == OPERATIONAL
    mark = sim.rec.mark()
    sim.net.send_message(0x123, h("AA"))
    assert sim.read_int(0x2105) == 0x10
    assert host.xfer(h("C0")) == X("C2 01 AA")
    sim.net.send_message(0x123, b"")
    assert sim.read_int(0x2105) == 0x10
    assert host.xfer(h("C0")) == X("C1 01"), "an empty monitored frame: positive, no data"
    assert sim.emcys(mark) == []
    # In Stopped the module cannot transmit: D1 00, nothing on the bus.
    sim.nmt(STOP)
    assert sim.guarded_state() == STOPPED
    mark = sim.rec.mark()
    assert host.xfer(h("D5 23 01 B1 B2 B3")) == X("D1 00")
    assert sim.rec.wait(0x123, mark, 0.3) is None
    # Identifier 0 stops monitoring (in any NMT state): frames on 0x123 are not captured.
    assert host.xfer(h("83 00 00 00")) == X("81 01")
    sim.net.send_message(0x123, h("01"))
    assert sim.guarded_state() == STOPPED  # the frame has been handled
    assert host.xfer(h("C0")) == X("C1 00")
    assert host.xfer(h("00")) == X("04 00 00 00 00")
    sim.nmt(PRE_OP)
    assert sim.read_int(0x1401, 1) == 0x80000123, "RPDO2 invalid again"

    # Every example exchange of the spec (serial.commands[].examples) took place above.
    examples = spec_serial_examples()
    assert len(examples) >= 9, examples
    exchanged = {x for pair in host.log for x in pair}
    assert [e for e in examples if e not in exchanged] == [], f"spec examples not exchanged; log: {host.log}"


NEGATIVE_CASES = [
    # request, answer, why
    ("33 00 10 00", "32 00 00", "1000h is outside the non-volatile data area"),
    ("33 00 50 00", "32 00 00", "sub 0 has host access none"),
    ("33 00 50 81", "32 00 00", "no sub-index 81h"),
    ("33 40 50 01", "32 00 00", "no object 5040h"),
    ("33 00 5C 01", "32 00 00", "5C00h is not host-readable"),
    ("33 00 5E 01", "32 00 00", "5E00h is read with C0 only"),
    ("31 00", "32 00 00", "wrong length"),
    ("44 00 60 01 07", "41 00", "6000h is not host-writable"),
    ("44 00 50 00 07", "41 00", "sub 0 is not host-writable"),
    ("44 00 50 81 07", "41 00", "no sub-index 81h"),
    ("42 00 50", "41 00", "wrong length"),
    ("12 03 91", "11 00", "no command register 3"),
    ("12 00 91", "11 00", "no command register 0"),
    ("11 01", "11 00", "wrong length"),
    ("83 01 23 01", "81 00", "register 1 is not defined"),
    ("83 00 15 06", "81 00", "0x615: this node's SDO requests (MEM-37)"),
    ("83 00 15 07", "81 00", "0x715: this node's node guarding (MEM-37)"),
    ("83 00 15 02", "81 00", "0x215: RPDO1 (MEM-37)"),
    ("83 00 80 00", "81 00", "0x080: SYNC (MEM-37)"),
    ("83 00 00 08", "81 00", "identifier above 0x7FF"),
    ("D2 00 08", "D1 00", "identifier above 0x7FF"),
    ("D1 23", "D1 00", "wrong length"),
]


def test_serial_negative_answers(sim):
    assert NODE_ID == 0x15, "the MEM-37 cases name this node's identifiers"
    host = sim.serial
    answers = {req: host.xfer(h(req)) for req, _, _ in NEGATIVE_CASES}
    wrong = {req: (got, want, why) for (req, want, why), got in zip(NEGATIVE_CASES, answers.values()) if got != X(want)}
    assert wrong == {}, "answers (got, wanted, why)"
    # An unknown command and a malformed Read Status (which has no negative form) get none.
    for req in ("F0", "01 00", "E2 01 02"):
        host.send(h(req))
        assert host.silent(0.3), f"answer to {req}"
    # Nothing was changed by any of it.
    assert host.xfer(h("00")) == X("04 40 40 03 00")
    assert sim.read_int(0x1401, 1) == 0x80000300 + NODE_ID, "RPDO2 still disabled"
    assert sim.read_int(0x5000, 1) == 0 and sim.read_int(0x5C00, 1) == 0
    assert sim.read_int(0x6200, 1) == 0


def test_serial_garbage_truncated_frames_and_resync(sim):
    host = sim.serial
    assert host.xfer(h("44 12 50 04 23")) == X("41 01")
    # A frame cut short, then a pause: the partial frame is dropped and the next byte starts
    # a new frame.
    host.send(h("44 12 50"))
    assert host.silent(SERIAL_PAUSE)
    assert host.xfer(h("00")) == X("04 40 40 03 00")
    # The rest of a cut frame after the pause is a frame of its own (here an incomplete
    # Read Status of length 4), dropped at the next pause.
    host.send(h("44 12 50"))
    host.pause()
    host.send(h("04 55"))
    assert host.silent(SERIAL_PAUSE)
    assert host.xfer(h("33 12 50 04")) == X("32 01 23"), "the cut write stored nothing"
    # Garbage that frames as an unknown command with 15 data bytes, cut short, then a pause.
    host.send(bytes([0xEF, 0x01, 0x02, 0x03]))
    assert host.silent(SERIAL_PAUSE)
    assert host.xfer(h("33 00 50 01")) == X("32 01 00")
    # Complete frames of unknown commands need no pause: the next frame is answered.
    host.send(h("F0 E1 FF"))
    assert host.xfer(h("00")) == X("04 40 40 03 00")
    # Bytes of one frame a little apart (well under 100 ms) still make one frame.
    for b in h("33 12 50 04"):
        host.send(bytes([b]))
        time.sleep(0.01)
    assert host.answer() == h("32 01 23")
    # Several frames in one write are answered in order.
    host.send(h("00 33 12 50 04 12 01 91"))
    assert [host.answer() for _ in range(3)] == [h("04 40 40 03 00"), h("32 01 23"), h("11 01")]
    assert host.silent(0.2)
    # Nothing stored changed.
    assert sim.read_int(0x5012, 4) == 0x23
    assert sim.read_int(0x5C00, 1) == sim.read_int(0x5C00, 2) == 0x23


def test_serial_and_sdo_share_the_memory(sim):
    host = sim.serial
    # Serial -> SDO.
    assert host.xfer(h("44 3F 50 80 A5")) == X("41 01")
    assert sim.node.sdo[0x503F][0x80].raw == 0xA5
    # SDO -> serial.
    sim.node.sdo[0x5001][1].raw = 0x5A
    assert host.xfer(h("33 01 50 01")) == X("32 01 5A")
    expected = {(0x503F, 0x80): 0xA5, (0x5001, 0x01): 0x5A}
    # More addresses both ways.
    for n, (index, sub) in enumerate([(0x5000, 0x01), (0x5007, 0x40), (0x5010, 0x7F), (0x5025, 0x02), (0x503E, 0x80)]):
        value = 0x30 + 7 * n
        assert host.xfer(bytes([0x44, index & 0xFF, index >> 8, sub, value])) == X("41 01")
        expected[(index, sub)] = value
        assert sim.read_int(index, sub) == value
    for n, (index, sub) in enumerate([(0x5000, 0x02), (0x5008, 0x01), (0x5011, 0x80), (0x5026, 0x55), (0x503F, 0x7F)]):
        value = 0xF0 - 5 * n
        sim.write_int(index, sub, value)
        expected[(index, sub)] = value
        assert host.xfer(bytes([0x33, index & 0xFF, index >> 8, sub])) == X(f"32 01 {value:02X}")
    # Overwrite over serial what SDO wrote, and the other way round.
    assert host.xfer(h("44 01 50 01 00")) == X("41 01")
    expected[(0x5001, 0x01)] = 0
    sim.write_int(0x503F, 0x80, 0x01)
    expected[(0x503F, 0x80)] = 0x01
    assert sim.read_int(0x5001, 1) == 0
    assert host.xfer(h("33 3F 50 80")) == X("32 01 01")
    assert sim.node.sdo[0x5001][0].raw == 128
    total = sum(expected.values())
    assert sim.read_int(0x5C00, 1) == total and sim.read_int(0x5C00, 2) == total


# ============================================================================================
# 3. Erratum MEM-27 and NMT resets
# ============================================================================================


def test_rpdo_event_timer_is_no_deadline_monitor(sim):
    """Erratum MEM-27: 1400h.5 exists (1000 ms) but a DS301 4.0 module does not monitor RPDO
    deadlines, so silence after an RPDO raises no 8250h emergency."""
    sim.clear_banks()
    sim.nmt(START)
    assert sim.read_int(0x1400, 5) == 1000
    mark = sim.rec.mark()
    sim.net.send_message(sim.rpdo1_cob, bytes([0x00, 0x00]))  # one command, then silence
    assert sim.guarded_state() == OPERATIONAL
    time.sleep(1.5)
    assert sim.emcys(mark) == [], "EMCY without an error of the module"
    assert sim.read_int(0x1001) == 0


def test_bootup_message_after_reset_node(sim):
    """The boot-up message is always sent: 2110h is this module's function-less "CiA
    Compatibility Test" (erratum MEM-12), not the CO401GW1's boot-up switch."""
    assert sim.read_int(0x2110) == 0
    mark = sim.rec.mark()
    sim.nmt(RESET_NODE)
    boot = sim.rec.wait(0x700 + NODE_ID, mark, 1.0, lambda f: f.data == b"\x00")
    assert boot is not None, f"no boot-up message after NMT reset node (2110h = {sim.read_int(0x2110)})"


@pytest.mark.parametrize("command", [RESET_NODE, RESET_COMM], ids=["reset_node", "reset_communication"])
def test_active_errors_survive_an_nmt_reset(sim, command):
    """An NMT reset forgets the active emergencies; conditions that persist are raised again."""
    mark = sim.rec.mark()
    sim.console("supply 14000")
    # The module samples the supply at its next step: wait for the emergency, not the console.
    assert sim.wait_emcy(mark, h("00 10 01 00 70 00 00 00")) is not None, sim.emcys(mark)
    assert sim.read_int(0x2105) == 0x83 and sim.read_int(0x1001) == 0x01
    mark = sim.rec.mark()
    sim.nmt(command)
    assert sim.rec.wait(0x700 + NODE_ID, mark, 1.0, lambda f: f.data == b"\x00") is not None, "boot-up"
    assert sim.guarded_state() == PRE_OPERATIONAL
    # The conditions are still there...
    assert sim.read_int(0x2105) == 0x83
    assert (sim.read_int(0x6000, 1), sim.read_int(0x6000, 2)) == (CLEARED, CLEARED)
    assert sim.abort_code(sim.write_int, 0x5000, 1, 1) == ABORT_STATE
    # ... so the error register and the emergencies must say so.
    assert sim.read_int(0x1001) == 0x01, "1001h after the reset"
    assert sim.wait_emcy(mark, h("00 10 01 00 70 00 00 00"), 1.0) is not None, sim.emcys(mark)
