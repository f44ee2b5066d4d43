"""CANopenIA's remote-access protocol end to end: a host written from the manual (chapter 6:
start byte, length, payload, CRC-16) on the coprocessor's serial line, and python-canopen as a
CANopen master on the same bus. Every test runs against two targets that run the same code:
- `sim`: `coforge sim canopenia --node-id 2 --port 0 --serial 0`;
- `qemu`: the Cortex-M3 image (lm3s6965evb, built by `cargo xtask dist`, path in
  COFORGE_IA_QEMU_IMAGE), node-ID 2, UART0 the host's line, UART1 an SLCAN adapter of its
  node that `coforge hub --connect` puts on a hub python-canopen joins.

The host side encodes and checks every frame itself, from the manual and errata COIA-01..03
(CRC-16/XMODEM over length and payload, sent low byte first; the length counts the payload).
Expected bytes are the manual's examples where it prints them (spec `serial.commands[].examples`).
Answers may be preceded by indications (D); the host separates them by their letter, as a real
host does. Every wait has a timeout; the simulator runs in real time.
"""

import os
import pathlib
import subprocess
import tempfile
import time

from bus import Recorder, connect_attached
from simproc import SerialLine, SimProcess
from qemu import QemuProcess
import canopen
import pytest
from host import COFORGE, ROOT

SPEC = ROOT / "spec" / "canopenia.yaml"

NODE_ID = 2
# Absolute: QEMU runs in a test's own directory, where it keeps the parameter file.
IA_IMAGE = str(pathlib.Path(os.environ.get("COFORGE_IA_QEMU_IMAGE", ROOT / "target" / "dist" / "images" / "canopenia-qemu.bin")).resolve())
WAIT = 3.0
SDO_TIMEOUT = 1.0  # the coprocessor's SDO client gives up after 1 s

BIT_NOT_FOUND, BIT_LENGTH, BIT_INVALID, BIT_BUSY = 1 << 0, 1 << 1, 1 << 2, 1 << 3
BIT_ABORTED, BIT_TIMEOUT, BIT_NOT_SUPPORTED = 1 << 6, 1 << 9, 1 << 11


def crc16(data):
    """CRC-16/XMODEM (erratum COIA-01: polynomial 0x1021, start 0, no reflection)."""
    crc = 0
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def encode(payload, start=0x11):
    """A frame: start byte (bit 4: CRC, bit 5: 16-bit length), length, payload, CRC."""
    length = len(payload).to_bytes(2 if start & 0x20 else 1, "little")
    frame = bytes([start]) + length + payload
    if start & 0x10:
        frame += crc16(length + payload).to_bytes(2, "little")
    return frame


class Host(SerialLine):
    """The host end: frames in, frames out, each checked against the framing."""

    def __init__(self, url):
        super().__init__(url)
        self.pending = b""
        self.indications = []

    def frame(self, timeout=WAIT):
        """The next frame from the device: (start byte, payload). Fails on a bad one."""
        deadline = time.monotonic() + timeout
        while True:
            got = self.parse()
            if got is not None:
                return got
            more = self._read(1, deadline)
            assert more, f"no frame from the device within {timeout} s (have {self.pending.hex(' ')})"
            self.pending += more

    def parse(self):
        if not self.pending:
            return None
        start = self.pending[0]
        assert start & 0x0F and not start & 0xC0, f"bad start byte {start:02X}"
        lb = 2 if start & 0x20 else 1
        if len(self.pending) < 1 + lb:
            return None
        n = int.from_bytes(self.pending[1 : 1 + lb], "little")
        total = 1 + lb + n + (2 if start & 0x10 else 0)
        if len(self.pending) < total:
            return None
        frame, self.pending = self.pending[:total], self.pending[total:]
        payload = frame[1 + lb : 1 + lb + n]
        if start & 0x10:
            assert int.from_bytes(frame[-2:], "little") == crc16(frame[1 : 1 + lb + n]), f"bad CRC in {frame.hex(' ')}"
        assert len(payload) <= 35, "never more than 35 payload bytes"
        return start, payload

    def answer(self, timeout=WAIT):
        """The next frame that is not an indication (indications are kept)."""
        while True:
            start, payload = self.frame(timeout)
            if payload[:1] == b"D":
                self.indications.append(payload)
            else:
                return start, payload

    def xfer(self, payload, start=0x11, timeout=WAIT):
        self.send(encode(payload, start))
        return self.answer(timeout)

    def raw_xfer(self, frame, timeout=WAIT):
        """A frame as the manual prints it; the answer frame re-encoded as it came."""
        self.send(frame)
        start, payload = self.answer(timeout)
        return encode(payload, start)

    def silent(self, timeout=0.3):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.pending += self._read(1, deadline)
            while True:
                got = self.parse()
                if got is None:
                    break
                assert got[1][:1] == b"D", f"unexpected answer {got[1].hex(' ')}"
                self.indications.append(got[1])

    def ready(self, timeout=10.0):
        """Until the coprocessor answers a read of 1000h (an image in QEMU starts slowly, and
        may lose what came before its loop ran); then whatever else came is dropped."""
        deadline = time.monotonic() + timeout
        while True:
            self.send(encode(b"R\x00\x10\x00"))
            try:
                if self.answer(0.5)[1][:1] == b"R":
                    break
            except AssertionError:
                self.pending = b""
                assert time.monotonic() < deadline, "the coprocessor does not answer its host"
        end = time.monotonic() + 0.3
        while time.monotonic() < end:
            self._read(64, end)
        self.pending = b""
        self.indications = []

    def indication(self, payload, timeout=WAIT):
        """Waits until `payload` was indicated."""
        deadline = time.monotonic() + timeout
        while payload not in self.indications:
            left = deadline - time.monotonic()
            assert left > 0, f"no indication {payload.hex(' ')}; got {[i.hex(' ') for i in self.indications]}"
            self.silent(min(left, 0.1))


def err_of(payload, at):
    return int.from_bytes(payload[at : at + 2], "little")


class Target:
    """A running coprocessor, `kind` "sim" or "qemu", with python-canopen and the host."""

    def __init__(self, kind, workdir, store=False):
        """`store`: the simulator keeps its memories in files in `workdir` (QEMU always does),
        so that they survive a restart."""
        self.net = self.host = None
        if kind == "sim":
            keep = ["--store", str(pathlib.Path(workdir) / "canopenia")] if store else []
            self.sim = SimProcess([COFORGE, "sim", "canopenia", "--node-id", str(NODE_ID), "--port", "0", "--serial", "0", *keep])
        else:
            self.sim = QemuProcess(IA_IMAGE, workdir)
        try:
            if kind == "sim":
                serial_url = self.sim.banner(r"serial host on (socket://\S+)")
                can_url = self.sim.banner(rf"canopenia node-ID {NODE_ID} on slcan (socket://\S+)")
                self.sim_can_url = can_url
            else:
                serial_url, can_url = self.sim.serial_url, self.sim.can_url
            self.sim_can_url = can_url
            with tempfile.TemporaryDirectory() as d:
                eds = pathlib.Path(d) / "canopenia.eds"
                subprocess.run([COFORGE, "eds", SPEC, "-o", eds], check=True, timeout=60)
                od = canopen.import_od(str(eds), NODE_ID)
            self.net = canopen.Network()
            self.rec = Recorder()
            self.net.listeners.insert(0, self.rec)
            connect_attached(self.net, can_url, 500000)
            self.node = canopen.RemoteNode(NODE_ID, od)
            self.node.sdo.RESPONSE_TIMEOUT = 1.0
            self.net.add_node(self.node)
            self.host = Host(serial_url)
            self.host.ready()
        except BaseException:
            self.close()
            raise

    def close(self):
        try:
            if self.host is not None:
                self.host.close()
            if self.net is not None:
                self.net.disconnect()
        finally:
            self.sim.stop()

    def start_node(self):
        """python-canopen starts the coprocessor; the host is told of its new state."""
        mark = self.rec.mark()
        self.node.nmt.send_command(0x01)
        self.host.indication(b"D" + bytes([NODE_ID]) + bytes.fromhex("00 5F 02 05"))
        return mark


@pytest.fixture(params=["sim", "qemu"])
def sim(request, tmp_path):
    s = Target(request.param, tmp_path)
    try:
        yield s
    finally:
        s.close()


def test_the_manuals_local_examples_byte_for_byte(sim):
    sim.start_node()
    host = sim.host
    mark = sim.rec.mark()
    # Transmit NMT "start all nodes" through 5F0Ah (section 9.4): accepted, and on the bus.
    assert host.raw_xfer(bytes.fromhex("11 06 57 0A 5F 01 01 00 8A FA")) == bytes.fromhex("11 06 57 0A 5F 01 00 00 BB C9")
    assert sim.rec.wait(0x000, mark, WAIT, lambda f: f.data == bytes([0x01, 0x00])) is not None
    # Own NMT state (operational) and own node-ID, as the manual's answers print them.
    assert host.raw_xfer(bytes.fromhex("11 04 52 00 5F 02 96 2F")) == bytes.fromhex("11 07 52 00 5F 02 00 00 05 6A 80")
    assert host.raw_xfer(encode(b"R\x00\x5F\x01")) == bytes.fromhex("11 07 52 00 5F 01 00 00 02 51 6B")
    # 1000h, the device type of the spec.
    start, payload = host.xfer(bytes.fromhex("52 00 10 00"))
    assert payload == b"R\x00\x10\x00\x00\x00" + (0x000F0191).to_bytes(4, "little")


def test_the_manuals_remote_examples_byte_for_byte(sim, tmp_path):
    """Section 4.2's steps 3..5 as the spec's S/U examples: the host configures the coprocessor
    itself (node 2, serial number 04040D41h) with S and U to its own node-ID, which it serves
    with the bus's rules (erratum COIA-44), and it resets into bootloader mode as node 70h."""
    if isinstance(sim.sim, SimProcess):
        sim.sim.console("serial-number 04040D41")
    # The serial number is the chip's from the next initialisation on (QEMU's board gives it
    # at power-on already).
    mark = sim.rec.mark()
    sim.node.nmt.send_command(0x81)
    assert sim.rec.wait(0x700 + NODE_ID, mark, WAIT) is not None
    host = sim.host
    host.silent(0.3)
    assert host.raw_xfer(bytes.fromhex("11 05 55 02 18 10 04 39 31")) == bytes.fromhex("11 0B 55 02 18 10 04 00 00 41 0D 04 04 11 08")
    assert host.raw_xfer(bytes.fromhex("11 09 53 02 50 1F 01 41 0D 04 04 B3 C2")) == bytes.fromhex("11 07 53 02 50 1F 01 00 00 06 93")
    mark = sim.rec.mark()
    assert host.raw_xfer(bytes.fromhex("11 06 53 02 51 1F 01 00 3E 04")) == bytes.fromhex("11 07 53 02 51 1F 01 00 00 57 39")
    assert sim.rec.wait(0x770, mark, WAIT, lambda f: f.data == b"\x00") is not None, "boot-up of node 70h"
    host.indication(b"D\x70" + bytes.fromhex("00 5F 01 70"))


def gateway_dictionary():
    """The dictionary of chapter 8's node 1 (a CiA 447 gateway), as far as its indications show
    it: TPDO1 maps 6007h, 6050h, 6053h and 6055h (8 + 16 + 16 + 24 bits), TPDO2 60B0h.1 and
    6080h."""
    from canopen.objectdictionary import ODArray, ODRecord, ODVariable, UNSIGNED8, UNSIGNED16, UNSIGNED24, UNSIGNED32

    od = canopen.ObjectDictionary()

    def var(index, sub, dtype, default, name=None, access="rw"):
        v = ODVariable(name or f"{index:04X}sub{sub}", index, sub)
        v.data_type, v.default, v.access_type = dtype, default, access
        return v

    def record(index, members, kind=ODRecord):
        r = kind(f"{index:04X}", index)
        for m in members:
            r.add_member(m)
        od.add_object(r)

    od.add_object(var(0x1000, 0, UNSIGNED32, 0x01BF_0191, "Device type", "ro"))
    od.add_object(var(0x1017, 0, UNSIGNED16, 0, "Producer heartbeat time"))
    record(0x1018, [var(0x1018, 0, UNSIGNED8, 4, "count", "ro")] + [var(0x1018, s, UNSIGNED32, v, access="ro") for s, v in ((1, 0x1234), (2, 1), (3, 1), (4, 1))])
    for n, (cob, mapping) in enumerate([(0x181, [0x60070008, 0x60500010, 0x60530010, 0x60550018]), (0x281, [0x60B00120, 0x60800008])]):
        record(0x1800 + n, [var(0x1800 + n, 0, UNSIGNED8, 2, "count", "ro"), var(0x1800 + n, 1, UNSIGNED32, cob), var(0x1800 + n, 2, UNSIGNED8, 254)])
        record(0x1A00 + n, [var(0x1A00 + n, 0, UNSIGNED8, len(mapping), "count")] + [var(0x1A00 + n, i + 1, UNSIGNED32, m) for i, m in enumerate(mapping)])
    for index, dtype in ((0x6007, UNSIGNED8), (0x6050, UNSIGNED16), (0x6053, UNSIGNED16), (0x6055, UNSIGNED24), (0x6080, UNSIGNED8)):
        od.add_object(var(index, 0, dtype, 0))
    record(0x60B0, [var(0x60B0, 0, UNSIGNED8, 1, "count", "ro"), var(0x60B0, 1, UNSIGNED32, 0)], ODArray)
    return od


def test_the_manuals_indications_byte_for_byte(sim):
    """Chapter 8's output as the spec's D examples: node 1 (python-canopen's LocalNode with the
    gateway's dictionary) boots, is scanned and its TPDOs arrive as one D per mapped entry."""
    gateway = canopen.LocalNode(1, gateway_dictionary())
    sim.net.add_node(gateway)
    sim.net.send_message(0x701, [0])
    sim.host.indication(b"D" + bytes([NODE_ID]) + bytes.fromhex("04 5F 01 A0"), timeout=5.0)  # scan complete
    sim.host.indications = []
    sim.net.send_message(0x181, bytes.fromhex("00 00 00 FF FF FF FF FF"))
    sim.net.send_message(0x281, bytes.fromhex("00 00 00 00 E0"))
    sim.net.send_message(0x181, bytes.fromhex("01 00 00 FF FF FF FF FF"))
    examples = [
        "11 06 44 01 07 60 00 00 83 AD", "11 07 44 01 50 60 00 00 00 72 D2", "11 07 44 01 53 60 00 FF FF AF 21",
        "11 08 44 01 55 60 00 FF FF FF 06 90", "11 09 44 01 B0 60 01 00 00 00 00 D6 A6", "11 06 44 01 80 60 00 E0 B8 DC",
        "11 06 44 01 07 60 00 01 A2 BD",
    ]
    want = [bytes.fromhex(e) for e in examples]
    deadline = time.monotonic() + WAIT
    while len([i for i in sim.host.indications if i[1] == 1]) < len(want) and time.monotonic() < deadline:
        sim.host.silent(0.1)
    got = [encode(i) for i in sim.host.indications if i[1] == 1]
    assert got[: len(want)] == want


def test_error_bits_start_byte_options_and_resync(sim):
    host = sim.host
    # No such object; a host write of a read-only status entry; a value of the wrong size.
    assert err_of(host.xfer(b"R\x45\x23\x00")[1], 4) == BIT_NOT_FOUND
    assert err_of(host.xfer(b"W\x00\x5F\x01\x05")[1], 4) == BIT_NOT_SUPPORTED
    assert err_of(host.xfer(b"W\x00\x60\x01\x01\x02")[1], 4) == BIT_LENGTH
    # A command cut short is answered with the invalid-length bit.
    assert err_of(host.xfer(b"R\x00\x10")[1], 4) == BIT_LENGTH
    # The answer takes the form of the command: no CRC; 16-bit length; another network.
    start, payload = host.xfer(b"R\x00\x10\x00", start=0x01)
    assert start == 0x01 and err_of(payload, 4) == 0
    start, payload = host.xfer(b"R\x00\x10\x00", start=0x31)
    assert start == 0x31 and err_of(payload, 4) == 0
    start, payload = host.xfer(b"R\x00\x10\x00", start=0x13)
    assert start == 0x13 and err_of(payload, 4) == BIT_NOT_SUPPORTED
    # Garbage, a bad CRC, a frame cut off by garbage, an unknown letter: no answer. Then the
    # next valid frame is answered.
    bad = bytearray(encode(b"R\x00\x10\x00"))
    bad[-1] ^= 0xFF
    host.send(b"\x00\xc0\xff" + bytes(bad) + encode(b"X\x01\x02"))
    host.silent(0.3)
    assert host.xfer(b"R\x00\x10\x00")[1][4:6] == b"\x00\x00"


def test_remote_operations_busy_and_timeout(sim):
    host = sim.host
    # U of node 3's vendor-ID (the manual's example frame): no node 3 on this bus.
    t0 = time.monotonic()
    host.send(bytes.fromhex("11 05 55 03 18 10 01 28 17"))
    # A second remote operation meanwhile is busy at once; W/R are served meanwhile.
    start, payload = host.xfer(b"S\x04\x17\x10\x00\x64\x00")
    assert payload[:5] == b"S\x04\x17\x10\x00" and err_of(payload, 5) == BIT_BUSY
    assert host.xfer(b"R\x00\x10\x00")[1][:1] == b"R"
    start, payload = host.answer(timeout=SDO_TIMEOUT + WAIT)
    assert payload[:5] == bytes.fromhex("55 03 18 10 01")
    assert err_of(payload, 5) == BIT_ABORTED | BIT_TIMEOUT
    assert time.monotonic() - t0 >= SDO_TIMEOUT * 0.9
    # A node-ID no node can have.
    assert err_of(host.xfer(b"U\x80\x00\x10\x00")[1], 5) == BIT_INVALID
    # Its own node-ID: served from its own dictionary.
    start, payload = host.xfer(bytes([0x55, NODE_ID, 0x00, 0x10, 0x00]))
    assert err_of(payload, 5) == 0 and payload[7:] == (0x000F0191).to_bytes(4, "little")


def test_writes_from_the_bus_and_state_changes_are_indicated(sim):
    sim.start_node()
    # A master writes 6200h.1 by SDO: D with sender 0 (an SDO client is not known).
    sim.node.sdo.download(0x6200, 1, b"\xa5")
    sim.host.indication(bytes.fromhex("44 00 00 62 01 A5"))
    # RPDO1 carries 8 output bytes: one D per mapped entry.
    sim.net.send_message(0x200 + NODE_ID, bytes(range(1, 9)))
    for i in range(1, 9):
        sim.host.indication(bytes([0x44, 0x00, 0x00, 0x62, i, i]))
    # A host write is not indicated back to the host.
    sim.host.xfer(b"W\x00\x62\x01\x07")
    sim.host.silent(0.3)
    assert bytes.fromhex("44 00 00 62 01 07") not in sim.host.indications


# --------------------------------------------------------------------------------------------
# The coprocessor as the manager of a bus: CO401Memory1 (node 3) and CO401GW1 (node 5) boot
# after it, each in a `coforge sim` of its own whose bus is put on the coprocessor's with
# `--connect`. The defaults of 5F01h.04 (087F0017h, erratum COIA-48) scan them, start them and
# monitor their heartbeats; the host sees all of it as indications D.
# --------------------------------------------------------------------------------------------

MEM_ID, GW1_ID = 3, 5


def status(node, code):
    """D of 5F04h.`node` (NODESTATUS `code`), sent with the coprocessor's node-ID."""
    return bytes([0x44, NODE_ID, 0x04, 0x5F, node, code])


@pytest.fixture
def bus():
    ia = Target("sim", None)
    others = []
    try:
        hub = ia.sim_can_url.removeprefix("socket://")

        def boot(args, node):
            proc = SimProcess([COFORGE, "sim", *args, "--node-id", str(node), "--port", "0", "--connect", hub])
            proc.banner(rf"node-ID {node} on slcan (socket://\S+)")
            others.append(proc)
            return proc

        yield ia, boot
    finally:
        for proc in others:
            if proc.proc.poll() is None:
                proc.stop()
        ia.close()


def test_the_manager_scans_starts_and_monitors_the_nodes_that_boot(bus):
    ia, boot = bus
    host = ia.host
    mem = boot(["co401memory1"], MEM_ID)
    # Boot-up, scan started, scan complete, started (KEEP_OP), heartbeat active: in this order
    # (the module also reports its blank banks with emergencies, 80h, during the scan).
    for code in (0x00, 0x9F, 0xA0, 0x05, 0x90):
        host.indication(status(MEM_ID, code), timeout=5.0)
    order = [i[5] for i in host.indications if i[:5] == status(MEM_ID, 0)[:5]]
    assert [c for c in order if c != 0x80][:5] == [0x00, 0x9F, 0xA0, 0x05, 0x90], order
    gw1 = boot(["co401gw1", "--enable-can"], GW1_ID)
    for code in (0x00, 0x9F, 0xA0, 0x05, 0x90):
        host.indication(status(GW1_ID, code), timeout=5.0)

    # U of the gateway's 1000h comes from the scan cache; S of 6200h.1 reaches its outputs.
    start, payload = host.xfer(bytes([0x55, GW1_ID, 0x00, 0x10, 0x00]))
    assert err_of(payload, 5) == 0 and int.from_bytes(payload[7:11], "little") == 0x000F0191
    start, payload = host.xfer(bytes([0x53, GW1_ID, 0x00, 0x62, 0x01, 0x5A]))
    assert err_of(payload, 5) == 0
    assert gw1.console("pins").startswith("outputs 0x5a")

    # TPDO receive all: the gateway's input IN0 arrives as D of its 6000h.1, from node 5.
    gw1.console("in 1")
    host.indication(bytes([0x44, GW1_ID, 0x00, 0x60, 0x01, 0x01]), timeout=5.0)

    # Without KEEP_OP, an NMT stop through 5F0Ah stops the module; its heartbeat says so.
    assert err_of(host.xfer(b"W\x01\x5f\x04" + (0x087F0016).to_bytes(4, "little"))[1], 4) == 0
    assert err_of(host.xfer(bytes([0x57, 0x0A, 0x5F, 0x01, 0x02, MEM_ID]))[1], 4) == 0
    host.indication(status(MEM_ID, 0x04), timeout=3.0)
    # The module goes away: its heartbeat is lost after 1.5 s, and the manager resets it.
    mem.stop()
    host.indication(status(MEM_ID, 0x91), timeout=4.0)
    host.indication(status(MEM_ID, 0xB0), timeout=1.0)
