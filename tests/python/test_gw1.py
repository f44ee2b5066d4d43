"""CO401GW1 end to end: python-canopen as the CANopen master and a serial host on the chip's
UART, both against `coforge sim co401gw1`.

Every test starts its own simulator (`--node-id 5 --port 0 --serial 0`, with `--mode` where the
test needs a digital mode) and drives its board through the console on stdin (`in <bits>`,
`emy0 on|off`, `emy1 on|off`, `enable [alt]`, `pins`). The CANopen side uses the EDS file
`coforge eds --mode <mode>` exports; the serial side is a pyserial `socket://` port, the byte
stream of the RS232 line. Expected bytes are the datasheet's examples (spec
`serial.commands[].examples`) and the decisions of errata GW1-44..GW1-61.

Facts about a fresh simulator the tests rely on: the ID pins select node-ID 5 (so the host may
not write 100Bh, GW1-48); CFG0 is high (hardware input byte 0 = IN0..IN7, enabled in 2E00h.1);
CFG1 is high in mode mixed and low in the digital modes; all inputs are inactive, so 6000h.1
reads 0. After power-on the CAN side is off and the chip sends `01 00` to its host every 250 ms
until the host enables CAN with `02 00` (or `02 81`).

The protocol (datasheet "Serial Protocol"): a telegram is command byte, DataLen byte, data; a
pause of more than 10 ms inside a telegram invalidates it and the chip then waits for a pause of
50 ms. Each telegram is sent in one write (TCP_NODELAY, so no segment waits for an ACK), and a
refused telegram gets no answer at all (GW1-46): refusals are asserted as silence.

Timing: the simulator runs in real time; every wait has a timeout, and only the protocol's own
pauses are fixed sleeps. Console commands take effect at the chip's next step, so tests wait
for their consequence (a frame, a telegram), not for the console's answer.
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
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError
from serial.urlhandler import protocol_socket
from host import COFORGE, ROOT

SPEC = ROOT / "spec" / "co401gw1.yaml"

NODE_ID = 5

START, STOP, PRE_OP, RESET_NODE, RESET_COMM = 0x01, 0x02, 0x80, 0x81, 0x82
OPERATIONAL, PRE_OPERATIONAL, STOPPED = 0x05, 0x7F, 0x04

# CiA 301 SDO abort codes
ABORT_LOCAL_CONTROL = 0x08000021  # data cannot be stored because of local control (GW1-60)
ABORT_READ_ONLY = 0x06010002

BOOTUP = bytes.fromhex("01 00")
GAP = 0.02  # > the 10 ms inter-byte timeout: invalidates a telegram
SHORT = 0.02  # < the 50 ms resync pause
RESYNC = 0.06  # > the 50 ms resync pause
SILENCE = 0.3  # how long a refused telegram is listened to
SDO_TIMEOUT = 1.0
WAIT = 2.0  # for something that must come (returns as soon as it does)

EMY0_EMCY = bytes.fromhex("10 23 01 00 01 00 00 00")  # datasheet: Application Emergency 0
EMY1_EMCY = bytes.fromhex("00 10 01 00 10 00 00 00")  # datasheet: Application Emergency 1


def coforge(*args):
    return subprocess.run([COFORGE, *map(str, args)], check=True, capture_output=True, text=True, timeout=60).stdout


def h(text):
    """'20 07 18' -> bytes."""
    return bytes.fromhex(text)


def X(data):
    """Canonical hex text of a telegram ('' for none)."""
    if data is None:
        return ""
    if isinstance(data, str):
        return bytes.fromhex(data).hex(" ").upper()
    return data.hex(" ").upper()


def eventually(fn, timeout=WAIT):
    deadline = time.monotonic() + timeout
    while True:
        got = fn()
        if got or time.monotonic() > deadline:
            return got
        time.sleep(0.01)


# --------------------------------------------------------------------------------------------
# The serial host: a pyserial port on the chip's UART.
# --------------------------------------------------------------------------------------------


class Host(SerialLine):
    """The host side of the gateway protocol. Until the host has enabled CAN the chip sends
    `01 00` every 250 ms; those telegrams are collected in `bootups` (with their arrival time)
    and skipped by `answer`/`silent`. After `enabled = True` a `01 00` is an unexpected
    telegram like any other."""

    def __init__(self, url):
        super().__init__(url)
        self.enabled = False
        self.bootups = []

    def telegram(self, timeout):
        """One telegram from the chip (command, DataLen, data), or None."""
        deadline = time.monotonic() + timeout
        head = self._read(2, deadline)
        if not head:
            return None
        # A telegram's bytes are written together: the rest follows at once.
        deadline = max(deadline, time.monotonic() + 0.5)
        if len(head) < 2:
            head += self._read(1, deadline)
        assert len(head) == 2, f"telegram cut short: {head.hex(' ')}"
        n = head[1] if head[1] < 0x80 else 0
        data = self._read(n, deadline)
        assert len(data) == n, f"telegram cut short: {(head + data).hex(' ')}"
        return head + data

    def wait_bootup(self, timeout=WAIT):
        """Waits for a boot-up telegram of the boot phase, as a host does before it talks to
        a chip that is starting (a starting chip may miss bytes); False if none came."""
        t = self.telegram(timeout)
        if t is None:
            return False
        assert t == BOOTUP, f"unexpected telegram in the boot phase: {X(t)}"
        self.bootups.append(time.monotonic())
        return True

    def answer(self, timeout=WAIT):
        """The next telegram that is not a boot-up telegram of the boot phase, or None."""
        deadline = time.monotonic() + timeout
        while True:
            t = self.telegram(max(0.0, deadline - time.monotonic()))
            if t is None:
                return None
            if t == BOOTUP and not self.enabled:
                self.bootups.append(time.monotonic())
                continue
            return t

    def drain(self):
        """Telegrams already waiting (other than boot-up telegrams of the boot phase)."""
        got = []
        while self.port.in_waiting:
            t = self.answer(0.2)
            if t is None:
                break
            got.append(X(t))
        return got

    def xfer(self, request, timeout=WAIT):
        """Sends one telegram and returns the chip's answer as hex text ('' for none)."""
        stale = self.drain()
        assert not stale, f"unexpected telegrams before {X(request)}: {stale}"
        self.send(request)
        return X(self.answer(timeout))

    def silent(self, timeout=SILENCE):
        """Nothing (but boot-up telegrams before enable) arrives within `timeout`; else the
        telegrams that did."""
        got = []
        deadline = time.monotonic() + timeout
        while True:
            t = self.answer(max(0.0, deadline - time.monotonic()))
            if t is None:
                return got == [] or got
            got.append(X(t))

    def refused(self, request, timeout=SILENCE):
        """Sends `request` and checks that no answer comes (GW1-46)."""
        stale = self.drain()
        assert not stale, f"unexpected telegrams before {X(request)}: {stale}"
        self.send(request)
        got = self.silent(timeout)
        assert got is True, f"{X(request)} was answered: {got}"

    def enable(self, request=h("02 00")):
        answer = self.xfer(request)
        assert answer == X("02 00"), f"enable {X(request)} answered {answer!r}"
        self.enabled = True


# --------------------------------------------------------------------------------------------
# A simulator with python-canopen and the serial host connected.
# --------------------------------------------------------------------------------------------

_ODS = {}


def dictionary(mode):
    """The dictionary python-canopen builds from our EDS file for `mode`, imported once."""
    if mode not in _ODS:
        with tempfile.TemporaryDirectory() as d:
            eds = pathlib.Path(d) / f"co401gw1-{mode}.eds"
            coforge("eds", SPEC, "--mode", mode, "-o", eds)
            _ODS[mode] = canopen.import_od(str(eds), NODE_ID)
    return _ODS[mode]


class Sim:
    """`pins`: the node-ID the ID pins select (0: all high, the host programs 100Bh);
    `node_id`: the one python-canopen addresses (the pins' unless given)."""

    def __init__(self, mode="mixed", extra=(), pins=NODE_ID, node_id=None):
        self.mode = mode
        self.node_id = pins if node_id is None else node_id
        args = [COFORGE, "sim", "co401gw1", "--node-id", str(pins), "--port", "0", "--serial", "0"]
        if mode != "mixed":
            args += ["--mode", mode]
        args += list(extra)
        od = dictionary(mode)
        self.sim = SimProcess(args)
        self.net = self.host = None
        try:
            serial_url = self.sim.banner(r"serial host on (socket://\S+)")
            can_url = self.sim.banner(rf"co401gw1 node-ID {pins} on slcan (socket://\S+)")
            self.net = canopen.Network()
            self.net.NOTIFIER_CYCLE = 0.05
            self.rec = Recorder()
            self.net.listeners.insert(0, self.rec)  # sees each frame before python-canopen does
            connect_attached(self.net, can_url, 500000)
            self.node = canopen.RemoteNode(self.node_id, od)
            self.node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT
            self.net.add_node(self.node)
            self.host = Host(serial_url)
        except BaseException:
            self.close()
            raise

    def console(self, command, timeout=5.0):
        return self.sim.console(command, timeout)

    def pins(self):
        """`pins`: (outputs, pin levels, run LED lit, error LED lit)."""
        text = self.console("pins")
        m = re.match(r"outputs (0x[0-9a-fA-F]+) \(pins (0x[0-9a-fA-F]+)\), run LED (lit|dark), error LED (lit|dark), watchdog (high|low)$", text)
        assert m, f"unexpected `pins` answer {text!r}"
        return int(m.group(1), 16), int(m.group(2), 16), m.group(3) == "lit", m.group(4) == "lit"

    def close(self):
        try:
            with pytest.MonkeyPatch.context() as mp:
                # pyserial's socket:// close() sleeps 0.3 s "in case of quick reconnects".
                mp.setattr(protocol_socket, "time", types.SimpleNamespace(sleep=lambda _s: None))
                if self.host is not None:
                    self.host.close()
                if self.net is not None:
                    self.net.disconnect()
        finally:
            self.sim.stop()

    # CANopen helpers -------------------------------------------------------------------------

    def cob(self, base):
        return base + self.node_id

    def nmt(self, command):
        self.node.nmt.send_command(command)

    def guarded_state(self, timeout=WAIT):
        """The NMT state from a node guarding answer (also proves earlier frames were handled)."""
        cob = 0x700 + self.node_id
        mark = self.rec.mark()
        self.net.send_message(cob, b"", remote=True)
        f = self.rec.wait(cob, mark, timeout, lambda f: len(f.data) == 1 and f.data != b"\x00")
        assert f is not None, "no answer to the node guarding request"
        return f.data[0] & 0x7F

    def start(self):
        self.nmt(START)
        assert self.guarded_state() == OPERATIONAL

    def read(self, index, sub=0):
        return self.node.sdo.upload(index, sub)

    def read_int(self, index, sub=0, signed=False):
        return int.from_bytes(self.read(index, sub), "little", signed=signed)

    def write_int(self, index, sub, value, size=1):
        self.node.sdo.download(index, sub, value.to_bytes(size, "little"))

    def abort_code(self, fn, *args):
        with pytest.raises(SdoAbortedError) as e:
            fn(*args)
        return e.value.code

    def frames(self, base, mark):
        return [f.data.hex(" ") for f in self.rec.since(mark, self.cob(base))]

    def quiet_tpdo_timers(self, *numbers):
        """Event timer 0 for the given TPDOs (pre-operational), so that a TPDO on the bus is a
        DS401 event and nothing else."""
        for n in numbers:
            self.write_int(0x1800 + n - 1, 5, 0, 2)
            assert self.read_int(0x1800 + n - 1, 5) == 0

    def remap(self, comm, mapping, entries):
        """CiA 301 remapping in pre-operational: PDO invalid, count 0, entries, count, valid."""
        cob = self.read_int(comm, 1)
        self.write_int(comm, 1, cob | 0x80000000, 4)
        self.write_int(mapping, 0, 0)
        for i, e in enumerate(entries, 1):
            self.write_int(mapping, i, e, 4)
        self.write_int(mapping, 0, len(entries))
        self.write_int(comm, 1, cob & ~0x80000000, 4)


@pytest.fixture
def sim():
    s = Sim("mixed")
    try:
        yield s
    finally:
        s.close()


@pytest.fixture
def enabled(sim):
    """A mixed-mode chip whose host has enabled CAN (`02 00`), pre-operational."""
    mark = sim.rec.mark()
    sim.host.enable()
    assert sim.rec.wait(sim.cob(0x700), mark, WAIT, lambda f: f.data == b"\x00") is not None, "no CAN boot-up after 02 00"
    return sim


# ============================================================================================
# 1. Boot phase and enable
# ============================================================================================


def test_boot_phase_bootup_telegrams_and_can_silent(sim):
    host = sim.host
    # 01 00 repeated every 250 ms (collected while listening for anything else).
    assert host.silent(0.9) is True, "nothing but 01 00 before enable"
    times = host.bootups
    assert len(times) >= 3, f"boot-up telegrams in 0.9 s: {len(times)}"
    gaps = [b - a for a, b in zip(times, times[1:])]
    mean = (times[-1] - times[0]) / (len(times) - 1)
    assert 0.2 < mean < 0.3 and all(0.1 < g < 0.45 for g in gaps), f"boot-up telegram periods {gaps}"
    # CAN is off: an SDO request gets no answer, an NMT start does nothing.
    mark = sim.rec.mark()
    sim.node.sdo.RESPONSE_TIMEOUT = 0.3
    with pytest.raises(SdoCommunicationError):
        sim.read(0x1000)
    sim.nmt(START)
    sim.net.send_message(sim.cob(0x700), b"", remote=True)
    time.sleep(0.2)
    # (The recorder sees the other clients' frames only: python-canopen's own are not echoed.)
    assert [str(f) for f in sim.rec.since(mark)] == [], "the node sent frames before enable"
    # 50 00 answers 00 (boot-up) until enable; the boot-up telegrams go on.
    assert host.xfer(h("50 00")) == X("50 01 00")
    n = len(host.bootups)
    assert host.silent(0.6) is True
    assert len(host.bootups) >= n + 2, "the boot-up telegram stopped without enable"
    # The LEDs are dark until CAN is enabled (GW1-57).
    _, _, run, error = sim.pins()
    assert (run, error) == (False, False)


def test_enable_starts_can(sim):
    sim.node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT
    mark = sim.rec.mark()
    assert sim.host.xfer(h("02 00")) == X("02 00")
    sim.host.enabled = True
    boot = sim.rec.wait(sim.cob(0x700), mark, WAIT, lambda f: f.data == b"\x00")
    assert boot is not None, f"no CAN boot-up after 02 00: {[str(f) for f in sim.rec.since(mark)]}"
    assert sim.read_int(0x1000) == 0x000F0191, "mixed mode: digital and analog I/O (GW1-44)"
    assert sim.node.sdo[0x1008].raw == "CO401GW1"
    assert sim.guarded_state() == PRE_OPERATIONAL
    # The boot-up telegram stops with enable (> 2 periods of silence).
    assert sim.host.silent(0.6) is True, "telegrams after enable"
    # The datasheet's 50 00 example: pre-operational.
    assert sim.host.xfer(h("50 00")) == X("50 01 7F")
    # A repeated enable is confirmed again and changes nothing (GW1-49): no second boot-up.
    mark = sim.rec.mark()
    assert sim.host.xfer(h("02 00")) == X("02 00")
    assert sim.guarded_state() == PRE_OPERATIONAL
    assert sim.rec.wait(sim.cob(0x700), mark, 0.2, lambda f: f.data == b"\x00") is None, "a second CAN boot-up"


def test_programmable_node_id_set_by_the_host_before_enable():
    """ID pins all high (`--node-id 0`): no node-ID, so enable is refused (no answer) until
    the host writes 100Bh; then CAN starts at that node-ID, and 100Bh is refused after."""
    s = Sim(pins=0, node_id=7)
    try:
        host = s.host
        host.refused(h("02 00"))
        assert host.xfer(h("20 04 0B 10 00 07")) == X("20 00")
        mark = s.rec.mark()
        host.enable()
        assert s.rec.wait(0x707, mark, WAIT, lambda f: f.data == b"\x00") is not None, "boot-up at the programmed node-ID 7"
        # 100Bh is not on the CAN side (access none); the host reads it.
        assert host.xfer(h("21 03 0B 10 00")) == X("21 04 0B 10 00 07")
        assert s.read_int(0x1018, 1) == 0x58, "SDO at 0x607/0x587"
        host.refused(h("20 04 0B 10 00 09"))
        assert host.xfer(h("21 03 0B 10 00")) == X("21 04 0B 10 00 07")
    finally:
        s.close()


def test_enable_digital_mode_pdo5_disabled():
    s = Sim("digital")
    try:
        s.host.enable(h("02 00"))
        assert s.read_int(0x1000) == 0x00030191, "digital modes: digital I/O only (GW1-44)"
        assert s.read_int(0x6000, 0) == 16
        assert s.read_int(0x1804, 1) == 0x80000000, "TPDO5 disabled until the master gives it a COB-ID"
        assert s.read_int(0x1404, 1) == 0x80000000, "RPDO5 disabled until the master gives it a COB-ID"
        # 34: TPDO5 data into 6000h.9..; 31 does not exist in the digital modes.
        assert s.host.xfer(h("34 02 AA BB")) == X("34 00")
        assert (s.read_int(0x6000, 9), s.read_int(0x6000, 10)) == (0xAA, 0xBB)
        s.host.refused(h("31 02 01 00"))
        s.host.refused(h("41 00"))
    finally:
        s.close()


def test_enable_alternate_digital_alt_pdo5_identifiers():
    s = Sim("digital_alt")
    try:
        mark = s.rec.mark()
        assert s.host.xfer(h("02 81")) == X("02 00"), "02 81 is answered 02 00"
        s.host.enabled = True
        assert s.rec.wait(s.cob(0x700), mark, WAIT, lambda f: f.data == b"\x00") is not None, "no CAN boot-up after 02 81"
        assert s.read_int(0x1804, 1) == 0x280 + NODE_ID, "TPDO5 COB-ID"
        assert s.read_int(0x1404, 1) == 0x300 + NODE_ID, "RPDO5 COB-ID"
        assert s.read_int(0x1000) == 0x00030191
        # PDO5 works on those identifiers: RPDO5 -> 44, 34 -> TPDO5.
        s.start()
        s.net.send_message(0x300 + NODE_ID, h("01 02 03 04 05 06 07 08"))
        assert eventually(lambda: s.read_int(0x6200, 9) == 0x01), "RPDO5 on 305h did not write 6200h.9"
        assert s.host.xfer(h("44 00")) == X("44 08 01 02 03 04 05 06 07 08")
        mark = s.rec.mark()
        assert s.host.xfer(h("34 08 11 22 33 44 55 66 77 88")) == X("34 00")
        f = s.rec.wait(0x280 + NODE_ID, mark, WAIT, lambda f: f.data == h("11 22 33 44 55 66 77 88"))
        assert f is not None, f"no TPDO5 on 285h: {s.frames(0x280, mark)}"
    finally:
        s.close()


def test_enable_can_option_starts_enabled():
    """`coforge sim --enable-can` does what the host's 02 81 does in mode digital_alt."""
    s = Sim("digital_alt", ["--enable-can"])
    try:
        # The simulator may hand a host that connects a boot-up telegram the chip sent at
        # power-on, before --enable-can enabled it (the UART had it before the host was
        # there): at most one, at once.
        time.sleep(0.1)
        early = s.host.drain()
        assert early == [] and len(s.host.bootups) <= 1, f"telegrams at connect: {early}, {len(s.host.bootups)} x 01 00"
        s.host.enabled = True
        assert s.read_int(0x1804, 1) == 0x280 + NODE_ID
        assert s.host.xfer(h("50 00")) == X("50 01 7F")
        assert s.host.silent(0.6) is True, "boot-up telegrams although CAN is enabled"
    finally:
        s.close()


# ============================================================================================
# 2. The datasheet's example exchanges
# ============================================================================================


def test_datasheet_examples(sim):
    host = sim.host
    # Write then read the serial number 1018h.4 before enable.
    assert host.xfer(h("20 07 18 10 04 78 56 34 12")) == X("20 00")
    assert host.xfer(h("21 03 18 10 04")) == X("21 07 18 10 04 78 56 34 12")
    assert host.xfer(h("50 00")) == X("50 01 00")
    host.enable()
    assert sim.rec.wait(sim.cob(0x700), 0, WAIT, lambda f: f.data == b"\x00") is not None
    assert sim.read_int(0x1018, 4) == 0x12345678, "the host's serial number on CAN"
    assert host.xfer(h("50 00")) == X("50 01 7F")
    # Three single bytes into TPDO1 (default mapping 6000h.1..8). Byte 0 is the hardware
    # input byte (2E00h.1 bit 0): it keeps IN0..IN7 (GW1-50); bytes 1 and 2 are the host's.
    assert host.xfer(h("30 03 12 34 56")) == X("30 00")
    assert [sim.read_int(0x6000, s) for s in (1, 2, 3, 4)] == [0x00, 0x34, 0x56, 0x00]
    assert host.xfer(h("21 03 00 60 03")) == X("21 04 00 60 03 56")
    # 40 00 after the master sent RPDO1 (default mapping: 8 bytes of 6200h).
    sim.start()
    sim.net.send_message(sim.cob(0x200), h("12 34 56 78 00 00 00 00"))
    assert eventually(lambda: sim.read_int(0x6200, 1) == 0x12), "RPDO1 did not write 6200h.1"
    assert host.xfer(h("40 00")) == X("40 08 12 34 56 78 00 00 00 00")
    assert host.xfer(h("50 00")) == X("50 01 05")


def test_datasheet_examples_with_remapped_pdos(enabled):
    """The datasheet's examples for 4 bytes mapped in RPDO1 and "one byte and two integers"
    mapped in TPDO1, with the master's mappings."""
    sim, host = enabled, enabled.host
    sim.quiet_tpdo_timers(1)
    sim.remap(0x1400, 0x1600, [0x62000108, 0x62000208, 0x62000308, 0x62000408])
    # Byte 1 (not the hardware byte), then words 1 and 2 (bytes 2..5) of the same area.
    sim.remap(0x1800, 0x1A00, [0x60000208, 0x61000210, 0x61000310])
    assert sim.read_int(0x1600, 0) == 4 and sim.read_int(0x1A00, 0) == 3
    sim.start()
    mark = sim.rec.mark()
    assert host.xfer(h("30 05 12 56 34 90 78")) == X("30 00")
    assert (sim.read_int(0x6000, 2), sim.read_int(0x6100, 2), sim.read_int(0x6100, 3)) == (0x12, 0x3456, 0x7890)
    # The bytes are arranged as in the PDO: the input change is an event, TPDO1 carries them.
    f = sim.rec.wait(sim.cob(0x180), mark, WAIT, lambda f: f.data == h("12 56 34 90 78"))
    assert f is not None, f"TPDO1: {sim.frames(0x180, mark)}"
    sim.net.send_message(sim.cob(0x200), h("12 34 56 78"))
    assert eventually(lambda: sim.read_int(0x6200, 4) == 0x78), "RPDO1 (4 bytes) did not write 6200h.4"
    assert host.xfer(h("40 00")) == X("40 04 12 34 56 78")


# ============================================================================================
# 3. The host write rule and refusals
# ============================================================================================


def test_refused_telegrams_get_no_answer(sim):
    host = sim.host
    # Before enable: the alternate enable does not exist in mixed mode, the ID pins decide the
    # node-ID (GW1-48, GW1-49); the chip stays in its boot phase.
    host.refused(h("02 81"))
    host.refused(h("20 04 0B 10 00 22"))
    assert host.xfer(h("50 00")) == X("50 01 00")
    host.enable()
    assert host.xfer(h("50 00")) == X("50 01 7F")
    # 1018h.4 only before enable.
    host.refused(h("20 07 18 10 04 01 02 03 04"))
    assert sim.read_int(0x1018, 4) == 0
    # Below 3000h: 1017h (heartbeat) is the master's.
    host.refused(h("20 05 17 10 00 64 00"))
    assert sim.read_int(0x1017) == 0
    # A read of a missing object, of a missing sub-index.
    host.refused(h("21 03 22 22 00"))
    host.refused(h("21 03 00 60 09"))
    # PDO3 is no command, PDO5 does not exist in mixed mode, 02 81 not after enable either.
    host.refused(h("32 00"))
    host.refused(h("34 01 00"))
    host.refused(h("44 00"))
    host.refused(h("02 81"))
    # An unknown command.
    host.refused(h("77 00"))
    # The chip still answers.
    assert host.xfer(h("21 03 17 10 00")) == X("21 05 17 10 00 00 00")
    assert host.xfer(h("50 00")) == X("50 01 7F")


def test_allowed_host_writes(enabled):
    sim, host = enabled, enabled.host
    # 2102h (read-only on CAN).
    assert host.xfer(h("20 04 02 21 00 00")) == X("20 00")
    assert sim.read_int(0x2102) == 0
    assert host.xfer(h("21 03 02 21 00")) == X("21 04 02 21 00 00")
    assert sim.abort_code(sim.write_int, 0x2102, 0, 1) == ABORT_READ_ONLY
    # 2E01h.1..3 (read-only on CAN).
    assert host.xfer(h("20 05 01 2E 01 03 00")) == X("20 00")
    assert host.xfer(h("20 04 01 2E 02 01")) == X("20 00")
    assert host.xfer(h("20 04 01 2E 03 01")) == X("20 00")
    assert (sim.read_int(0x2E01, 1), sim.read_int(0x2E01, 2), sim.read_int(0x2E01, 3)) == (3, 1, 1)
    assert sim.abort_code(sim.write_int, 0x2E01, 2, 0) == ABORT_READ_ONLY
    # Above 3000h: 6002h.1, the polarity of the hardware input byte (pins inactive: 6000h.1
    # reads the polarity mask).
    assert host.xfer(h("20 04 02 60 01 0F")) == X("20 00")
    assert sim.read_int(0x6002, 1) == 0x0F
    assert eventually(lambda: sim.read_int(0x6000, 1) == 0x0F), f"6000h.1 = {sim.read_int(0x6000, 1):#x} with 6002h.1 = 0Fh"


# ============================================================================================
# 4. Unsolicited telegrams (2E01h)
# ============================================================================================


def test_auto_send_received_pdo(enabled):
    sim, host = enabled, enabled.host
    sim.start()
    # 2E01h.1 = 0: nothing unsolicited.
    sim.net.send_message(sim.cob(0x200), h("12 34 56 78 00 00 00 00"))
    assert host.silent() is True, "RPDO1 data sent although 2E01h.1 = 0"
    assert sim.read_int(0x6200, 1) == 0x12
    # Bit 0: RPDO1.
    assert host.xfer(h("20 05 01 2E 01 01 00")) == X("20 00")
    sim.net.send_message(sim.cob(0x200), h("99 00 00 00 00 00 00 01"))
    assert X(host.answer(WAIT)) == X("40 08 99 00 00 00 00 00 00 01")
    # The same data again: nothing.
    sim.net.send_message(sim.cob(0x200), h("99 00 00 00 00 00 00 01"))
    assert host.silent() is True, "unchanged RPDO1 data sent again"
    # New data again: sent.
    sim.net.send_message(sim.cob(0x200), h("55 00 00 00 00 00 00 01"))
    assert X(host.answer(WAIT)) == X("40 08 55 00 00 00 00 00 00 01")
    # RPDO2 (bit 1) is not enabled.
    sim.net.send_message(sim.cob(0x300), h("01 00 02 00 03 00 04 00"))
    assert host.silent() is True, "RPDO2 data sent although 2E01h.1 bit 1 = 0"
    assert sim.read_int(0x6411, 2) == 2
    assert host.xfer(h("41 00")) == X("41 08 01 00 02 00 03 00 04 00")


def test_auto_send_nmt_state(enabled):
    sim, host = enabled, enabled.host
    # 2E01h.2 = 0: nothing unsolicited.
    sim.start()
    assert host.silent() is True, "NMT state sent although 2E01h.2 = 0"
    sim.nmt(PRE_OP)
    assert sim.guarded_state() == PRE_OPERATIONAL
    assert host.silent() is True
    assert host.xfer(h("20 04 01 2E 02 01")) == X("20 00")
    # One telegram per NMT message (GW1-52).
    sim.nmt(START)
    assert X(host.answer(WAIT)) == X("50 01 05")
    assert host.silent() is True, "more than one telegram for one NMT start"
    # A received NMT message without a state change is reported too.
    sim.nmt(START)
    assert X(host.answer(WAIT)) == X("50 01 05")
    assert host.silent() is True
    sim.nmt(STOP)
    assert X(host.answer(WAIT)) == X("50 01 04")
    assert sim.guarded_state() == STOPPED
    sim.nmt(PRE_OP)
    assert X(host.answer(WAIT)) == X("50 01 7F")
    assert host.silent() is True
    assert host.xfer(h("50 00")) == X("50 01 7F")


def test_report_emergencies(enabled):
    sim, host = enabled, enabled.host
    # 2E01h.3 = 0: the EMCY goes to the bus only.
    mark = sim.rec.mark()
    sim.console("emy1 on")
    assert sim.rec.wait(sim.cob(0x80), mark, WAIT, lambda f: f.data == EMY1_EMCY) is not None, sim.frames(0x80, mark)
    assert host.silent() is True, "emergency reported although 2E01h.3 = 0"
    mark = sim.rec.mark()
    sim.console("emy1 off")
    assert sim.rec.wait(sim.cob(0x80), mark, WAIT) is not None, "no EMCY when EMY1# ends"
    assert host.silent() is True
    # 2E01h.3 = 1: EMY0# low, the critical emergency, on the bus and to the host.
    assert host.xfer(h("20 04 01 2E 03 01")) == X("20 00")
    mark = sim.rec.mark()
    sim.console("emy0 on")
    assert X(host.answer(WAIT)) == X("51 08 10 23 01 00 01 00 00 00")
    f = sim.rec.wait(sim.cob(0x80), mark, WAIT)
    assert f is not None and f.data == EMY0_EMCY, f"EMCY on 85h: {sim.frames(0x80, mark)}"
    assert sim.read_int(0x1001) & 0x01 and sim.read_int(0x1002) == 0x01
    # The host's answer needs no answer.
    host.refused(h("51 00"))
    # Resetting is reported too, with exactly the frame's bytes.
    mark = sim.rec.mark()
    sim.console("emy0 off")
    f = sim.rec.wait(sim.cob(0x80), mark, WAIT)
    assert f is not None, "no EMCY when EMY0# ends"
    assert f.data[:2] == h("00 00"), f"error reset expected: {f}"
    assert X(host.answer(WAIT)) == X(b"\x51\x08" + f.data)
    # EMY1#, the uncritical one.
    mark = sim.rec.mark()
    sim.console("emy1 on")
    assert X(host.answer(WAIT)) == X("51 08 00 10 01 00 10 00 00 00")
    assert sim.rec.wait(sim.cob(0x80), mark, WAIT, lambda f: f.data == EMY1_EMCY) is not None
    assert sim.read_int(0x1002) == 0x10


# ============================================================================================
# 5. Outputs, DS401 events, process image
# ============================================================================================


def test_output_error_state_overwrites_6200(enabled):
    """5200h = 1 (default), 6206h.1 = FFh, 6207h.1 = 0: a critical error writes 0 into 6200h."""
    sim = enabled
    assert sim.read_int(0x5200) == 1
    sim.start()
    sim.net.send_message(sim.cob(0x200), h("0F 00 00 00 00 00 00 00"))
    assert eventually(lambda: sim.read_int(0x6200, 1) == 0x0F)
    assert eventually(lambda: sim.pins()[:2] == (0x0F, 0xF0)), f"pins: {sim.console('pins')}"
    assert sim.pins()[3] is False, "error LED lit without an error"
    mark = sim.rec.mark()
    sim.console("emy0 on")
    assert sim.rec.wait(sim.cob(0x80), mark, WAIT, lambda f: f.data == EMY0_EMCY) is not None
    assert eventually(lambda: sim.pins()[:2] == (0x00, 0xFF)), f"pins in the error state: {sim.console('pins')}"
    assert sim.read_int(0x6200, 1) == 0x00, "5200h = 1: 6200h overwritten with the error state"
    # 1029h.2 = 0: an operational node goes pre-operational.
    assert sim.guarded_state() == PRE_OPERATIONAL
    # The error ends: 6200h keeps the error value.
    sim.console("emy0 off")
    assert eventually(lambda: sim.read_int(0x1002) == 0)
    assert sim.pins()[:2] == (0x00, 0xFF)
    assert sim.read_int(0x6200, 1) == 0x00


def test_output_error_state_with_5200_zero(enabled):
    """5200h = 0: 6200h keeps its data, the pins show 6207h while the error lasts."""
    sim = enabled
    sim.write_int(0x5200, 0, 0)
    sim.write_int(0x6207, 1, 0xF0)
    sim.start()
    sim.net.send_message(sim.cob(0x200), h("0F 00 00 00 00 00 00 00"))
    assert eventually(lambda: sim.pins()[:2] == (0x0F, 0xF0)), f"pins: {sim.console('pins')}"
    mark = sim.rec.mark()
    sim.console("emy0 on")
    assert sim.rec.wait(sim.cob(0x80), mark, WAIT, lambda f: f.data == EMY0_EMCY) is not None
    assert eventually(lambda: sim.pins()[:2] == (0xF0, 0x0F)), f"pins in the error state: {sim.console('pins')}"
    assert sim.read_int(0x6200, 1) == 0x0F, "5200h = 0: 6200h unchanged"
    sim.console("emy0 off")
    assert eventually(lambda: sim.pins()[:2] == (0x0F, 0xF0)), f"pins after the error: {sim.console('pins')}"


def test_digital_input_events_send_tpdo1(enabled):
    sim = enabled
    sim.quiet_tpdo_timers(1)
    sim.start()
    time.sleep(0.1)  # whatever entering operational sends
    mark = sim.rec.mark()
    sim.console("in 1")
    f = sim.rec.wait(sim.cob(0x180), mark, WAIT)
    assert f is not None, "no TPDO1 after IN0 went active"
    assert f.data[0] == 0x01, f"TPDO1 {f}"
    assert sim.read_int(0x6000, 1) == 0x01
    # The same value again: no event.
    mark = sim.rec.mark()
    sim.console("in 1")
    time.sleep(SILENCE)
    assert sim.frames(0x180, mark) == [], "TPDO1 without an input change"
    # The other edge (6006h.1 = FFh, any change).
    mark = sim.rec.mark()
    sim.console("in 0")
    f = sim.rec.wait(sim.cob(0x180), mark, WAIT)
    assert f is not None and f.data[0] == 0x00, f"TPDO1 after IN0 went inactive: {sim.frames(0x180, mark)}"
    # 6005h = 0: no events.
    sim.write_int(0x6005, 0, 0)
    mark = sim.rec.mark()
    sim.console("in 0x80")
    assert eventually(lambda: sim.read_int(0x6000, 1) == 0x80)
    time.sleep(0.1)
    assert sim.frames(0x180, mark) == [], "TPDO1 with 6005h = 0"


def test_analog_inputs_wait_for_6423(enabled):
    sim, host = enabled, enabled.host
    sim.quiet_tpdo_timers(2)
    assert sim.read_int(0x6423) == 0
    sim.start()
    time.sleep(0.1)
    mark = sim.rec.mark()
    assert host.xfer(h("31 08 10 00 00 00 00 00 00 00")) == X("31 00")
    assert sim.read_int(0x6401, 1, signed=True) == 0x10
    time.sleep(SILENCE)
    assert sim.frames(0x280, mark) == [], "TPDO2 with 6423h = 0"
    sim.write_int(0x6423, 0, 1)
    mark = sim.rec.mark()
    assert host.xfer(h("31 08 20 00 00 00 00 00 FF FF")) == X("31 00")
    f = sim.rec.wait(sim.cob(0x280), mark, WAIT)
    assert f is not None, "no TPDO2 with 6423h = 1"
    assert f.data == h("20 00 00 00 00 00 FF FF"), f"TPDO2 {f}"
    assert sim.read_int(0x6401, 4, signed=True) == -1


def test_2102_zero_refuses_remapping(sim):
    host = sim.host
    assert host.xfer(h("20 04 02 21 00 00")) == X("20 00")
    host.enable()
    assert sim.rec.wait(sim.cob(0x700), 0, WAIT, lambda f: f.data == b"\x00") is not None
    assert sim.read_int(0x2102) == 0
    assert sim.abort_code(sim.write_int, 0x1A00, 0, 0) == ABORT_LOCAL_CONTROL
    assert sim.abort_code(sim.write_int, 0x1600, 0, 0) == ABORT_LOCAL_CONTROL
    assert sim.read_int(0x1A00, 0) == 8 and sim.read_int(0x1600, 0) == 8, "the mappings are unchanged"


def test_input_views_share_the_bytes(enabled):
    sim, host = enabled, enabled.host
    # Hardware input byte enabled: byte 0 is IN0..IN7, the host's byte 0 is ignored.
    assert host.xfer(h("30 08 AA 11 22 33 44 55 66 77")) == X("30 00")
    assert sim.read_int(0x6000, 1) == 0x00
    assert sim.read_int(0x6100, 1) == 0x1100
    assert sim.read_int(0x6100, 2) == 0x3322
    assert sim.read_int(0x6100, 4) == 0x7766
    assert sim.read_int(0x6120, 1) == 0x33221100
    assert sim.read_int(0x6120, 2) == 0x77665544
    sim.console("in 0x81")
    assert eventually(lambda: sim.read_int(0x6120, 1) == 0x33221181), f"6120h.1 = {sim.read_int(0x6120, 1):#x}"
    assert host.xfer(h("21 03 20 61 01")) == X("21 07 20 61 01 81 11 22 33")
    # 2E00h.1 bit 0 off: byte 0 is the host's.
    assert host.xfer(h("20 04 00 2E 01 FE")) == X("20 00")
    assert host.xfer(h("30 08 AA 11 22 33 44 55 66 77")) == X("30 00")
    assert sim.read_int(0x6000, 1) == 0xAA
    assert sim.read_int(0x6100, 1) == 0x11AA
    assert sim.read_int(0x6120, 1) == 0x332211AA
    assert host.xfer(h("21 03 00 61 01")) == X("21 05 00 61 01 AA 11")


# ============================================================================================
# 6. Framing: gaps and resynchronisation
# ============================================================================================


def test_gap_invalidates_and_resync_after_pause(enabled):
    host = enabled.host
    # A 20 ms pause inside a telegram: no answer.
    host.send(h("21 03 18"))
    time.sleep(GAP)
    host.send(h("10 04"))
    assert host.silent() is True, "a telegram with a 20 ms pause inside was answered"
    # The next telegram after the pause is answered.
    assert host.xfer(h("21 03 18 10 04")) == X("21 07 18 10 04 00 00 00 00")
    # A whole telegram 20 ms after a broken one: still waiting for the 50 ms pause.
    host.send(h("50"))
    time.sleep(GAP)
    host.send(h("00"))
    time.sleep(SHORT)
    host.send(h("50 00"))
    assert host.silent() is True, "answered before the 50 ms resync pause"
    # Broken, then a 60 ms pause: the next telegram is answered (once).
    host.send(h("50"))
    time.sleep(GAP)
    host.send(h("00"))
    time.sleep(RESYNC)
    host.send(h("50 00"))
    assert X(host.answer(WAIT)) == X("50 01 7F")
    assert host.silent() is True
    # Bytes of one telegram a little apart (< 10 ms) still make one telegram.
    host.send(h("21 03"))
    time.sleep(0.003)
    host.send(h("18 10 04"))
    assert X(host.answer(WAIT)) == X("21 07 18 10 04 00 00 00 00")


# ============================================================================================
# 7. NMT resets keep the host's configuration (GW1-53)
# ============================================================================================


RESETS = pytest.mark.parametrize("command", [RESET_NODE, RESET_COMM], ids=["reset_node", "reset_communication"])


@RESETS
def test_host_configuration_survives_nmt_reset(sim, command):
    """What the host wrote before enable (1018h.4, 2E01h.2) is written again after an NMT
    reset (GW1-53): the host cannot write 1018h.4 any more."""
    host = sim.host
    assert host.xfer(h("20 07 18 10 04 78 56 34 12")) == X("20 00")
    assert host.xfer(h("20 04 01 2E 03 01")) == X("20 00")
    host.enable()
    assert sim.rec.wait(sim.cob(0x700), 0, WAIT, lambda f: f.data == b"\x00") is not None
    assert sim.read_int(0x1018, 4) == 0x12345678
    mark = sim.rec.mark()
    sim.nmt(command)
    assert sim.rec.wait(sim.cob(0x700), mark, WAIT, lambda f: f.data == b"\x00") is not None, "no boot-up after the NMT reset"
    assert sim.guarded_state() == PRE_OPERATIONAL
    assert sim.read_int(0x1018, 4) == 0x12345678, "1018h.4 after the NMT reset"
    assert sim.read_int(0x2E01, 3) == 1, "2E01h.3 after the NMT reset"
    assert host.xfer(h("21 03 18 10 04")) == X("21 07 18 10 04 78 56 34 12")
    # Still the host's only before enable.
    host.refused(h("20 07 18 10 04 01 02 03 04"))
    # No boot-up telegram after an NMT reset: CAN stays enabled.
    assert host.silent(0.6) is True


@RESETS
def test_nmt_reset_is_reported_to_the_host(sim, command):
    """2E01h.2, written before enable, holds through an NMT reset (GW1-53), and the reset is
    an NMT message the chip receives: reported with 50 01 <state> (7F, the state it resets
    into, or 00 for the boot-up it passes through)."""
    host = sim.host
    assert host.xfer(h("20 04 01 2E 02 01")) == X("20 00")
    host.enable()
    assert sim.rec.wait(sim.cob(0x700), 0, WAIT, lambda f: f.data == b"\x00") is not None
    mark = sim.rec.mark()
    sim.nmt(command)
    assert sim.rec.wait(sim.cob(0x700), mark, WAIT, lambda f: f.data == b"\x00") is not None, "no boot-up after the NMT reset"
    assert sim.guarded_state() == PRE_OPERATIONAL
    assert sim.read_int(0x2E01, 2) == 1, "2E01h.2 after the NMT reset"
    got = []
    while (t := host.answer(0.3)) is not None:
        got.append(X(t))
    assert got and set(got) <= {X("50 01 7F"), X("50 01 00")}, f"telegrams after NMT reset {command:#04x} with 2E01h.2 = 1: {got}"
    # The next NMT message is reported.
    sim.nmt(START)
    assert X(host.answer(WAIT)) == X("50 01 05")
