"""The same CO401GW1 end-to-end tests against two targets that run the same chip code: the
host simulator (`coforge sim co401gw1`) and the Cortex-M3 image in QEMU (lm3s6965evb, built
by `cargo xtask dist` from firmware/boards/qemu; its path comes in COFORGE_GW1_QEMU_IMAGE).

Each target is test_gw1's `Sim` (python-canopen, the recorder of the bus, the serial host and
its helpers) over a different process:
- `sim`: `coforge sim co401gw1 --node-id 5 --port 0 --serial 0 --store DIR/co401gw1.params`,
  the pin console on its standard input;
- `qemu`: the image with three UARTs as TCP servers: UART0 the serial host, UART1 an SLCAN
  adapter whose bus is the chip's own node (`coforge hub --connect` puts it on a hub that
  python-canopen joins), UART2 the pin console (`ok <answer>` / `error <why>` lines); its
  parameter file `co401gw1.params` in QEMU's working directory.
Both pin consoles are the chip crate's `co401gw1::console`: the same commands, the same answers.

Checks: the boot phase (`01 00` every 250 ms, CAN silent) and enable, the boot-up frame, SDO
reads of 1000h/1008h/1018h, a host write of TPDO1 (`30`) on CAN, an RPDO as the unsolicited
`40` telegram (2E01h.1), an input pin as the digital TPDO and 6000h, EMY0# as the datasheet's
EMCY with the outputs in their error state, the console's answers, and a parameter saved with
1010h surviving a restart of the target with the same parameter file.
"""

import os
import pathlib
import re
import socket
import time

import pytest
from canopen.sdo.exceptions import SdoCommunicationError

from bus import Recorder, connect_attached
import qemu
from host import ROOT
from test_gw1 import EMY0_EMCY, NODE_ID, PRE_OPERATIONAL, SDO_TIMEOUT, WAIT, Host, Sim, X, dictionary, eventually, h
import canopen

# Absolute: QEMU runs in a test's own directory, where it keeps the parameter file.
GW1_IMAGE = str(pathlib.Path(os.environ.get("COFORGE_GW1_QEMU_IMAGE", ROOT / "target" / "dist" / "images" / "co401gw1-qemu.bin")).resolve())
PARAMS = "co401gw1.params"  # the image's parameter file; the simulator's --store file
SAVE = 0x65766173  # "save", 1010h.1
BOOTUP_FRAME = b"\x00"


class QemuProcess(qemu.QemuProcess):
    """The GW1 image in QEMU and a `coforge hub` on its UART1, with the interface of
    simproc.SimProcess that `Sim` uses (`console`, `stop`): the console is UART2's."""

    def __init__(self, workdir):
        self.pins = None
        self.pending = b""
        super().__init__(GW1_IMAGE, workdir, uarts=3)
        try:
            self.pins = self.connect(self.ports[2])
            self.pins.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        except BaseException:
            self.stop()
            raise

    def answer(self, command, timeout=5.0):
        """Sends a console line; the answer line, without its "\\n"."""
        self.pins.sendall(command.encode() + b"\n")
        deadline = time.monotonic() + timeout
        while b"\n" not in self.pending:
            left = deadline - time.monotonic()
            assert left > 0, f"no console answer to {command!r} within {timeout} s{self.output_note()}"
            self.pins.settimeout(left)
            try:
                chunk = self.pins.recv(256)
            except socket.timeout:
                continue
            assert chunk, f"the console closed{self.output_note()}"
            self.pending += chunk
        line, _, self.pending = self.pending.partition(b"\n")
        return line.decode()

    def console(self, command, timeout=5.0):
        """Runs a console command; returns the text after 'ok '."""
        line = self.answer(command, timeout)
        assert line.startswith("ok "), f"console {command!r}: {line!r}"
        return line[len("ok ") :]

    def stop(self):
        if self.pins is not None:
            self.pins.close()
        super().stop()


class Target(Sim):
    """A running CO401GW1, `kind` "sim" or "qemu", keeping its parameters in
    `workdir/co401gw1.params`, with python-canopen and the serial host connected (test_gw1's
    `Sim`: `host`, `rec`, `node`, `console`, `pins`, the SDO helpers)."""

    def __init__(self, kind, workdir):
        self.kind = kind
        if kind == "sim":
            super().__init__("mixed", ["--store", str(workdir / PARAMS)])
            return
        # As Sim.__init__, over QEMU and the hub (the image's ID pins select NODE_ID).
        self.mode = "mixed"
        self.node_id = NODE_ID
        od = dictionary(self.mode)
        self.net = self.host = None
        self.sim = QemuProcess(workdir)
        try:
            self.net = canopen.Network()
            self.net.NOTIFIER_CYCLE = 0.05
            self.rec = Recorder()
            self.net.listeners.insert(0, self.rec)
            connect_attached(self.net, self.sim.can_url, 500000)
            self.node = canopen.RemoteNode(self.node_id, od)
            self.node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT
            self.net.add_node(self.node)
            self.host = Host(self.sim.serial_url)
            # QEMU starts the image under load slowly: until it runs its loop, the bytes of a
            # telegram may come further apart than the chip's 10 ms and be dropped. The chip
            # says it is ready with its first boot-up telegram.
            assert self.host.wait_bootup(5.0), f"no boot-up telegram from the image{self.sim.output_note()}"
        except BaseException:
            self.close()
            raise

    def console_answer(self, command, timeout=5.0):
        """A console line's outcome: ("ok" or "error", the text)."""
        if self.kind == "sim":
            self.sim.proc.stdin.write(command + "\n")
            self.sim.proc.stdin.flush()
            line = self.sim.line(timeout).removeprefix("coforge sim: ")
        else:
            line = self.sim.answer(command, timeout)
        outcome, _, text = line.partition(" ")
        return outcome, text

    def enable(self):
        """The host enables CAN (`02 00`); the boot-up frame follows."""
        mark = self.rec.mark()
        self.host.enable()
        assert self.rec.wait(self.cob(0x700), mark, WAIT, lambda f: f.data == BOOTUP_FRAME) is not None, "no CAN boot-up after 02 00"


@pytest.fixture(params=["sim", "qemu"])
def kind(request):
    return request.param


@pytest.fixture
def gw1(kind, tmp_path):
    t = Target(kind, tmp_path)
    try:
        yield t
    finally:
        t.close()


def test_boot_phase_enable_and_identity(gw1):
    host = gw1.host
    # 01 00 every 250 ms, nothing else.
    assert host.silent(0.9) is True, "nothing but 01 00 before enable"
    times = host.bootups
    assert len(times) >= 3, f"boot-up telegrams in 0.9 s: {len(times)}"
    # Each is due 250 ms after the last was sent: on a busy machine a late pass of the
    # image's loop delays the rest too, hence the upper bound's margin.
    mean = (times[-1] - times[0]) / (len(times) - 1)
    assert 0.2 < mean < 0.35, f"boot-up telegram period {mean:.3f} s"
    # CAN is off: no SDO answer, no frame.
    mark = gw1.rec.mark()
    gw1.node.sdo.RESPONSE_TIMEOUT = 0.3
    with pytest.raises(SdoCommunicationError):
        gw1.read(0x1000)
    gw1.node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT
    assert [str(f) for f in gw1.rec.since(mark)] == [], "the node sent frames before enable"
    assert host.xfer(h("50 00")) == X("50 01 00")
    # Enable: 02 00 answered, the boot-up frame, the boot-up telegrams stop.
    gw1.enable()
    assert host.silent(0.6) is True, "telegrams after enable"
    assert gw1.read_int(0x1000) == 0x000F0191, "mixed mode: digital and analog I/O"
    assert gw1.node.sdo[0x1008].raw == "CO401GW1"
    assert [gw1.read_int(0x1018, sub) for sub in (0, 1, 2)] == [4, 0x58, 0x01401FFF]
    assert gw1.guarded_state() == PRE_OPERATIONAL
    assert host.xfer(h("50 00")) == X("50 01 7F")


def test_host_and_can_process_data(gw1):
    host = gw1.host
    gw1.enable()
    gw1.quiet_tpdo_timers(1)
    # 2E01h.1 bit 0: RPDO1's data goes to the host unasked.
    assert host.xfer(h("20 05 01 2E 01 01 00")) == X("20 00")
    gw1.start()
    time.sleep(0.1)  # whatever entering operational sends
    # 30: the host's bytes into TPDO1 (6000h.1..8; byte 0 stays the hardware input byte).
    mark = gw1.rec.mark()
    assert host.xfer(h("30 03 12 34 56")) == X("30 00")
    tpdo = h("00 34 56 00 00 00 00 00")
    assert gw1.rec.wait(gw1.cob(0x180), mark, WAIT, lambda f: f.data == tpdo) is not None, f"TPDO1 after 30: {gw1.frames(0x180, mark)}"
    # RPDO1 from the master: 6200h, the output pins (active low), and 40 to the host.
    gw1.net.send_message(gw1.cob(0x200), h("0F 00 00 00 00 00 00 A5"))
    assert X(host.answer(WAIT)) == X("40 08 0F 00 00 00 00 00 00 A5")
    assert gw1.read_int(0x6200, 1) == 0x0F
    assert eventually(lambda: gw1.pins()[:2] == (0x0F, 0xF0)), f"pins: {gw1.console('pins')}"
    # The same data again is not sent again.
    gw1.net.send_message(gw1.cob(0x200), h("0F 00 00 00 00 00 00 A5"))
    assert host.silent() is True, "unchanged RPDO1 data sent again"


def test_input_pin_and_emergency_pin(gw1):
    gw1.enable()
    gw1.quiet_tpdo_timers(1)
    gw1.start()
    gw1.net.send_message(gw1.cob(0x200), h("3C 00 00 00 00 00 00 00"))
    assert eventually(lambda: gw1.pins()[:2] == (0x3C, 0xC3)), f"pins: {gw1.console('pins')}"
    assert gw1.pins()[3] is False, "error LED lit without an error"
    # IN0 active: a DS401 event, TPDO1 with 6000h.1 = 01.
    mark = gw1.rec.mark()
    assert gw1.console("in 0x01") == "inputs 0x01 (pins 0xfe)"
    tpdo = h("01 00 00 00 00 00 00 00")
    assert gw1.rec.wait(gw1.cob(0x180), mark, WAIT, lambda f: f.data == tpdo) is not None, f"TPDO1 after IN0: {gw1.frames(0x180, mark)}"
    assert gw1.read_int(0x6000, 1) == 0x01
    # EMY0# low: the datasheet's EMCY, the outputs in their error state (5200h = 1: 6200h
    # overwritten with 6207h's 0), pre-operational (1029h.2 = 0).
    mark = gw1.rec.mark()
    assert gw1.console("emy0 on") == "emy0 on"
    f = gw1.rec.wait(gw1.cob(0x80), mark, WAIT)
    assert f is not None, "no EMCY after EMY0# went low"
    assert f.data == EMY0_EMCY, f"EMCY {f}"
    assert eventually(lambda: gw1.pins()[:2] == (0x00, 0xFF)), f"pins in the error state: {gw1.console('pins')}"
    assert gw1.read_int(0x6200, 1) == 0x00
    assert gw1.read_int(0x1001) & 0x01 and gw1.read_int(0x1002) == 0x01
    assert gw1.guarded_state() == PRE_OPERATIONAL
    # EMY0# high again: the error reset EMCY.
    mark = gw1.rec.mark()
    assert gw1.console("emy0 off") == "emy0 off"
    f = gw1.rec.wait(gw1.cob(0x80), mark, WAIT)
    assert f is not None and f.data[:2] == h("00 00"), f"error reset expected: {f}"


def test_console_answers_alike(gw1):
    """The pin console's answers, refusals included, and its enable (no 02 00 on the host's
    line, the boot-up frame on CAN)."""
    text = gw1.console("pins")
    assert re.fullmatch(r"outputs 0x00 \(pins 0xff\), run LED dark, error LED dark, watchdog (high|low)", text), text
    assert gw1.console_answer("in 0x100") == ("error", "`0x100` is not a byte")
    assert gw1.console_answer("emy1 maybe") == ("error", "`maybe`: say on (pin low) or off (pin high)")
    assert gw1.console_answer("frob") == ("error", "unknown command `frob`; commands: in <bits>, emy0 on|off, emy1 on|off, enable [alt], pins")
    assert gw1.console_answer("enable alt") == ("error", "enable refused: enabled already, no valid node-ID, or `alt` in mixed mode")
    mark = gw1.rec.mark()
    assert gw1.console("enable") == "CAN enabled in mode mixed"
    assert gw1.rec.wait(gw1.cob(0x700), mark, WAIT, lambda f: f.data == BOOTUP_FRAME) is not None, "no CAN boot-up after the console's enable"
    # A boot-up telegram sent just before the enable may still be on its way on the host's
    # line (the console's UART is another): taken as one for 0.1 s, then none may come.
    assert gw1.host.silent(0.1) is True
    gw1.host.enabled = True
    assert gw1.host.silent(0.6) is True, "telegrams after the console's enable"
    assert gw1.host.xfer(h("50 00")) == X("50 01 7F")
    assert gw1.console_answer("enable") == ("error", "enable refused: enabled already, no valid node-ID, or `alt` in mixed mode")


def test_saved_parameter_survives_a_restart(kind, tmp_path):
    """1017h saved with 1010h.1 is there after the target is stopped and started again with
    the same parameter file; 100Ch, written after the save, is not."""
    params = tmp_path / PARAMS
    first = Target(kind, tmp_path)
    try:
        first.enable()
        assert b"CFG1" not in params.read_bytes(), "a parameter block before any save"
        assert first.read_int(0x1017) == 0
        first.write_int(0x1017, 0, 150, 2)
        first.write_int(0x1010, 1, SAVE, 4)
        first.write_int(0x100C, 0, 40, 2)
        assert (first.read_int(0x1017), first.read_int(0x100C)) == (150, 40)
    finally:
        first.close()
    assert b"CFG1" in params.read_bytes(), "no parameter block in the file after the save"
    second = Target(kind, tmp_path)
    try:
        second.enable()
        mark = second.rec.mark()
        assert second.read_int(0x1017) == 150, "1017h after the restart"
        assert second.read_int(0x100C) == 0, "100Ch was not saved"
        beats = second.rec.wait_count(second.cob(0x700), mark, 4, 2.0)
        assert len(beats) >= 4 and all(f.data == b"\x7f" for f in beats), f"heartbeats at 150 ms: {[str(f) for f in beats]}"
        gaps = sorted(b.t - a.t for a, b in zip(beats, beats[1:]))
        assert 0.1 <= gaps[len(gaps) // 2] <= 0.2, f"median heartbeat period {gaps[len(gaps) // 2]:.3f} s"
    finally:
        second.close()
