"""Interoperability of the coforge CANopen stack with python-canopen as the master.

Every test starts its own simulated device (`coforge sim`, an SLCAN hub over TCP), connects
python-canopen to it and drives it through CiA 301 services: NMT and boot-up, node guarding and
heartbeat, SDO (expedited, segmented, block, aborts), PDO mapping and transmission, EMCY, and
store/restore of parameters. Dictionaries come from the EDS files coforge exports, expected
defaults from `coforge model`.

Devices: co401gw1 (DS401 gateway, dynamic PDO mapping, 1010/1011 on command, 1029), cr3101
(DS301 v3-style logger: no 1017, static PDO mapping, parameters saved autonomously) and
canopenia (heartbeat consumer 1016, no 100C/100D).

Timing: the simulator runs in real time and frames travel over TCP, so every wait has a
timeout and periods are checked with generous tolerances.
"""

import binascii
import json
import re
import selectors
import statistics
import subprocess
import tempfile
import threading
import time
import types
from dataclasses import dataclass, field

from bus import Recorder, connect_attached
import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError
from serial.urlhandler import protocol_socket
from host import COFORGE, ROOT


# Node-IDs differ per device so that nothing works only for one identifier by accident.
NODE_ID = {"co401gw1": 5, "cr3101": 0x22, "canopenia": 0x10}

# NMT commands (CiA 301 7.2.8.3.1) and state codes in heartbeat / guarding answers.
START, STOP, PRE_OP, RESET_NODE, RESET_COMM = 0x01, 0x02, 0x80, 0x81, 0x82
BOOT, STOPPED, OPERATIONAL, PRE_OPERATIONAL = 0x00, 0x04, 0x05, 0x7F

SAVE = int.from_bytes(b"save", "little")  # 0x65766173
LOAD = int.from_bytes(b"load", "little")  # 0x64616F6C


def coforge(*args):
    return subprocess.run([COFORGE, *map(str, args)], check=True, capture_output=True, text=True).stdout


# --------------------------------------------------------------------------------------------
# Spec facts: EDS files and the normalised model, cached for the session.
# --------------------------------------------------------------------------------------------

_INFO = {}


def default_mode(device):
    """The spec's first mode, which the simulator runs when no --mode is given."""
    if device not in _INFO:
        _INFO[device] = json.loads(coforge("info", ROOT / "spec" / f"{device}.yaml"))
    modes = _INFO[device]["modes"]
    return modes[0] if modes else None


@pytest.fixture(scope="session")
def eds_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("eds")


@pytest.fixture(scope="session")
def eds_file(eds_dir):
    cache = {}

    def get(device, mode):
        key = (device, mode)
        if key not in cache:
            path = eds_dir / f"{device}-{mode or 'single'}.eds"
            coforge("eds", ROOT / "spec" / f"{device}.yaml", *(["--mode", mode] if mode else []), "-o", path)
            cache[key] = path
        return cache[key]

    return get


_MODELS = {}


def model(device, mode, node_id):
    """(index, sub) -> entry of `coforge model`, values resolved for node_id."""
    key = (device, mode, node_id)
    if key not in _MODELS:
        mode_args = ["--mode", mode] if mode else []
        m = json.loads(coforge("model", ROOT / "spec" / f"{device}.yaml", "--node-id", node_id, *mode_args))
        _MODELS[key] = {(e["index"], e["sub"]): e for e in m["entries"]}
    return _MODELS[key]


# --------------------------------------------------------------------------------------------
# A simulated device with python-canopen connected as the master.
# --------------------------------------------------------------------------------------------


@dataclass
class Device:
    name: str
    mode: str
    node_id: int
    proc: subprocess.Popen
    net: canopen.Network
    node: canopen.RemoteNode
    rec: Recorder
    stderr: object = field(repr=False, default=None)

    # COB-IDs of the predefined connection set.
    @property
    def emcy_cob(self):
        return 0x80 + self.node_id

    @property
    def nmt_err_cob(self):
        return 0x700 + self.node_id

    @property
    def sdo_tx_cob(self):
        return 0x580 + self.node_id

    def entry(self, index, sub=0):
        return model(self.name, self.mode, self.node_id)[(index, sub)]

    def has(self, index, sub=0):
        return (index, sub) in model(self.name, self.mode, self.node_id)

    def nmt(self, command):
        self.node.nmt.send_command(command)

    def guard(self, timeout=1.0, node_id=None):
        """One node guarding request (RTR on 700h + node-ID); the answer frame."""
        cob = 0x700 + (node_id or self.node_id)
        mark = self.rec.mark()
        self.net.send_message(cob, b"", remote=True)
        # A boot-up message (state 0) is never a guarding answer: it may still be on its way if
        # the node started after the master connected.
        f = self.rec.wait(cob, mark, timeout, lambda f: f.data != b"\x00")
        assert f is not None, "no answer to the node guarding request"
        assert len(f.data) == 1, f"guarding answer {f}"
        return f

    def guarded_state(self, node_id=None):
        return self.guard(node_id=node_id).data[0] & 0x7F

    def wait_heartbeat(self, state, timeout=1.0, mark=None):
        mark = self.rec.mark() if mark is None else mark
        return self.rec.wait(self.nmt_err_cob, mark, timeout, lambda f: f.data == bytes([state]))

    def wait_emcy(self, mark, code, timeout=2.0):
        return self.rec.wait(self.emcy_cob, mark, timeout, lambda f: len(f.data) == 8 and int.from_bytes(f.data[:2], "little") == code)

    def read(self, index, sub=0):
        return self.node.sdo.upload(index, sub)

    def write(self, index, sub, data, **kw):
        self.node.sdo.download(index, sub, data, **kw)

    def read_int(self, index, sub=0, signed=False):
        return int.from_bytes(self.read(index, sub), "little", signed=signed)

    def write_int(self, index, sub, value, size):
        self.write(index, sub, value.to_bytes(size, "little", signed=value < 0))


def _banner(proc, timeout=20.0):
    sel = selectors.DefaultSelector()
    sel.register(proc.stdout, selectors.EVENT_READ)
    try:
        if not sel.select(timeout):
            raise RuntimeError("coforge sim printed nothing")
    finally:
        sel.close()
    line = proc.stdout.readline()
    m = re.search(r"(socket://\S+)", line)
    if not m:
        raise RuntimeError(f"unexpected banner {line!r}")
    return m.group(1)


@pytest.fixture
def start(eds_file):
    """start(device, mode=None, node_id=None, store=None, nodes=1) -> Device, with python-canopen
    connected; start.stop(dev) ends one early. Teardown stops the rest and fails the test if a
    simulator died on its own (a panic), showing its stderr."""
    running = []

    def _start(name, mode=None, node_id=None, store=None, nodes=1):
        node_id = NODE_ID[name] if node_id is None else node_id
        mode = mode or default_mode(name)
        args = [COFORGE, "sim", name, "--node-id", str(node_id), "--port", "0"]
        if mode:
            args += ["--mode", mode]
        if store:
            args += ["--store", str(store)]
        if nodes != 1:
            args += ["--nodes", str(nodes)]
        if name == "co401gw1":
            # The chip waits for its serial host to enable CAN; these tests are the bus side only.
            args.append("--enable-can")
        err = tempfile.TemporaryFile()
        proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=err, text=True)
        try:
            url = _banner(proc)
        except Exception:
            proc.kill()
            proc.wait()
            err.seek(0)
            raise RuntimeError(f"coforge sim failed: {err.read().decode(errors='replace')}") from None
        net = canopen.Network()
        net.NOTIFIER_CYCLE = 0.05  # a short receive cycle makes disconnect fast
        # The recorder sees each frame before python-canopen does, so a frame that completed an
        # SDO transfer is recorded by the time the transfer returns.
        rec = Recorder()
        net.listeners.insert(0, rec)
        try:
            connect_attached(net, url, 500000)
        except Exception:
            proc.kill()
            proc.wait()
            raise
        node = canopen.RemoteNode(node_id, str(eds_file(name, mode)))
        net.add_node(node)
        for other in range(node_id + 1, node_id + nodes):
            net.add_node(canopen.RemoteNode(other, str(eds_file(name, mode))))
        dev = Device(name, mode, node_id, proc, net, node, rec, err)
        running.append(dev)
        return dev

    def _stop(dev):
        exited = dev.proc.poll()
        try:
            # pyserial's socket:// close() sleeps 0.3 s "in case of quick reconnects"; every test
            # has its own hub, so that pause only slows the suite down.
            with pytest.MonkeyPatch.context() as mp:
                mp.setattr(protocol_socket, "time", types.SimpleNamespace(sleep=lambda _s: None))
                dev.net.disconnect()
        finally:
            dev.proc.kill()
            dev.proc.wait(timeout=10)
            dev.proc.stdout.close()
            dev.stderr.seek(0)
            stderr = dev.stderr.read().decode(errors="replace")
            dev.stderr.close()
            running.remove(dev)
        assert exited is None, f"coforge sim {dev.name} exited by itself with {exited}: {stderr}"

    _start.stop = _stop
    yield _start
    failures = []
    for dev in list(running):
        try:
            _stop(dev)
        except AssertionError as e:
            failures.append(str(e))
    assert not failures, "; ".join(failures)


def sdo_abort(fn, *args, **kw):
    """Runs an SDO transfer that must be aborted; returns the abort code."""
    with pytest.raises(SdoAbortedError) as e:
        fn(*args, **kw)
    return e.value.code


# ============================================================================================
# 1. Boot-up and NMT
# ============================================================================================


@pytest.mark.parametrize("command", [RESET_NODE, RESET_COMM], ids=["reset_node", "reset_communication"])
@pytest.mark.parametrize("name", ["co401gw1", "cr3101", "canopenia"])
def test_bootup_after_nmt_reset(start, name, command):
    dev = start(name)
    dev.nmt(START)
    assert dev.guarded_state() == OPERATIONAL
    mark = dev.rec.mark()
    dev.nmt(command)
    boot = dev.rec.wait(dev.nmt_err_cob, mark, 2.0)
    assert boot is not None, "no boot-up message after the reset"
    assert boot.data == bytes([BOOT]), f"boot-up message must carry one byte 0: {boot}"
    deadline = time.monotonic() + 1
    while dev.node.nmt.state != "PRE-OPERATIONAL" and time.monotonic() < deadline:
        time.sleep(0.01)
    assert dev.node.nmt.state == "PRE-OPERATIONAL"
    # After boot-up the node is pre-operational and the guarding toggle restarts at 0.
    first = dev.guard()
    assert first.data[0] == PRE_OPERATIONAL, f"first guarding answer after boot-up: {first}"


def test_nmt_bootup_seen_by_wait_for_bootup(start):
    """python-canopen's own wait_for_bootup() sees the boot-up message."""
    dev = start("co401gw1")
    result = {}

    def waiter():
        try:
            dev.node.nmt.wait_for_bootup(3)
            result["ok"] = True
        except Exception as e:  # noqa: BLE001 - reported through the assertion
            result["error"] = e

    t = threading.Thread(target=waiter)
    t.start()
    time.sleep(0.05)  # let the waiter block before the boot-up can arrive
    dev.nmt(RESET_NODE)
    t.join(5)
    assert result.get("ok"), f"wait_for_bootup failed: {result.get('error')}"


def test_reset_communication_keeps_application_values_reset_node_does_not(start):
    """CiA 301: reset communication restores 1000h..1FFFh only, reset node everything."""
    dev = start("co401gw1")
    dev.write_int(0x6200, 1, 0x5A, 1)  # application (device profile) area, RAM
    dev.write_int(0x100C, 0, 321, 2)  # communication area
    remap_tpdo(dev, 1, [(0x6411, 1, 16)], 1, event_timer=500)
    mark = dev.rec.mark()
    dev.nmt(RESET_COMM)
    assert dev.rec.wait(dev.nmt_err_cob, mark, 2.0) is not None
    assert dev.read_int(0x100C) == 0, "reset communication restores the communication area"
    assert (dev.read_int(0x1800, 2), dev.read_int(0x1800, 5)) == (255, 1000), "TPDO parameters restored"
    assert [dev.read_int(0x1A00, s) for s in range(9)] == [8] + [0x60000008 | s << 8 for s in range(1, 9)], "mapping restored"
    assert dev.read_int(0x6200, 1) == 0x5A, "reset communication must not touch 6000h..9FFFh"
    mark = dev.rec.mark()
    dev.nmt(RESET_NODE)
    assert dev.rec.wait(dev.nmt_err_cob, mark, 2.0) is not None
    assert dev.read_int(0x6200, 1) == 0, "reset node restores the application area"


@pytest.mark.parametrize("name", ["co401gw1", "canopenia"])
def test_nmt_states_through_heartbeat(start, name):
    dev = start(name)
    dev.node.sdo[0x1017].raw = 20
    assert dev.wait_heartbeat(PRE_OPERATIONAL) is not None, "heartbeat in pre-operational"
    for command, state, text in [
        (START, OPERATIONAL, "OPERATIONAL"),
        (STOP, STOPPED, "STOPPED"),
        (PRE_OP, PRE_OPERATIONAL, "PRE-OPERATIONAL"),
        (START, OPERATIONAL, "OPERATIONAL"),
        (STOP, STOPPED, "STOPPED"),
        (START, OPERATIONAL, "OPERATIONAL"),
    ]:
        mark = dev.rec.mark()
        dev.nmt(command)
        hb = dev.wait_heartbeat(state, mark=mark)
        assert hb is not None, f"no heartbeat with state {state:#04x} after NMT command {command:#04x}"
        # Every heartbeat after that one keeps the new state. wait_count returns at least two:
        # a loaded host can deliver two 20 ms beats in one batch, so a third may come with them.
        later = dev.rec.wait_count(dev.nmt_err_cob, dev.rec.mark(), 2, 1.0)
        assert len(later) >= 2, f"only {len(later)} heartbeats within 1 s at a 20 ms period"
        assert [f.data for f in later] == [bytes([state])] * len(later), f"heartbeats {later}"
        assert dev.node.nmt.state == text
        if state == STOPPED:
            # CiA 301: no SDO in Stopped; the request goes unanswered.
            dev.node.sdo.RESPONSE_TIMEOUT = 0.2
            with pytest.raises(SdoCommunicationError):
                dev.read(0x1000)
            dev.node.sdo.RESPONSE_TIMEOUT = 0.3
        else:
            assert dev.read_int(0x1017) == 20


@pytest.mark.parametrize("name", ["co401gw1", "cr3101"])
def test_nmt_states_through_node_guarding(start, name):
    dev = start(name)
    answers = [dev.guard()]
    for command, state in [(START, OPERATIONAL), (STOP, STOPPED), (PRE_OP, PRE_OPERATIONAL), (START, OPERATIONAL), (STOP, STOPPED), (START, OPERATIONAL)]:
        dev.nmt(command)
        a = dev.guard()
        answers.append(a)
        assert a.data[0] & 0x7F == state, f"after NMT {command:#04x}: {a}"
    toggles = [a.data[0] >> 7 for a in answers]
    assert toggles == [i % 2 for i in range(len(answers))], f"toggle bits must alternate from 0: {toggles}"
    # Reset communication restarts the toggle bit at 0.
    mark = dev.rec.mark()
    dev.nmt(RESET_COMM)
    assert dev.rec.wait(dev.nmt_err_cob, mark, 2.0, lambda f: f.data == b"\x00") is not None
    assert dev.guard().data[0] == PRE_OPERATIONAL
    assert dev.guard().data[0] == 0x80 | PRE_OPERATIONAL
    # Reset node works from Stopped too.
    dev.nmt(STOP)
    assert dev.guarded_state() == STOPPED
    mark = dev.rec.mark()
    dev.nmt(RESET_NODE)
    assert dev.rec.wait(dev.nmt_err_cob, mark, 2.0, lambda f: f.data == b"\x00") is not None, "no boot-up after reset node in Stopped"
    assert dev.guard().data[0] == PRE_OPERATIONAL


def test_node_guarding_by_python_canopen(start):
    """python-canopen's periodic guarding (start_node_guarding) keeps it informed of the state."""
    dev = start("cr3101")
    dev.nmt(START)
    mark = dev.rec.mark()
    dev.node.nmt.start_node_guarding(0.03)
    try:
        answers = dev.rec.wait_count(dev.nmt_err_cob, mark, 8, 2.0)
    finally:
        dev.node.nmt.stop_node_guarding()
    assert len(answers) >= 8
    assert all(a.data[0] & 0x7F == OPERATIONAL for a in answers)
    toggles = [a.data[0] >> 7 for a in answers]
    assert all(x != y for x, y in zip(toggles, toggles[1:])), f"toggle bits must alternate: {toggles}"
    assert dev.node.nmt.state == "OPERATIONAL"


# ============================================================================================
# 2. SDO transfers
# ============================================================================================


@pytest.mark.parametrize("name,rw", [("co401gw1", (0x100C, 0, 2)), ("cr3101", (0x100C, 0, 2)), ("canopenia", (0x1017, 0, 2))], ids=["co401gw1", "cr3101", "canopenia"])
def test_sdo_expedited(start, name, rw):
    dev = start(name)
    # Read: values from the EDS/spec defaults.
    assert dev.node.sdo[0x1000].raw == dev.entry(0x1000)["default"]
    assert dev.node.sdo[0x1018][1].raw == dev.entry(0x1018, 1)["default"]
    mark = dev.rec.mark()
    dev.read(0x1000)
    resp = dev.rec.wait(dev.sdo_tx_cob, mark, 1.0)
    assert resp.data[0] & 0xE0 == 0x40 and resp.data[0] & 0x02, f"expedited upload response expected: {resp}"
    assert resp.data[0] & 0x01 and (4 - (resp.data[0] >> 2 & 3)) == 4, "size indicated, 4 bytes"
    # Write and read back.
    index, sub, size = rw
    mark = dev.rec.mark()
    dev.write_int(index, sub, 0x1234, size)
    resp = dev.rec.wait(dev.sdo_tx_cob, mark, 1.0)
    assert resp.data[:4] == bytes([0x60, index & 0xFF, index >> 8, sub]), f"download response {resp}"
    assert dev.read_int(index, sub) == 0x1234
    assert dev.node.sdo[index].raw == 0x1234


@pytest.mark.parametrize("name,index", [("co401gw1", 0x1017), ("cr3101", 0x100C)], ids=["co401gw1-1017", "cr3101-100C"])
def test_sdo_expedited_download_without_size(start, name, index):
    """CiA 301 7.2.4.3.3: e = 1, s = 0 means "d contains an unspecified number of bytes"; the
    server takes the bytes its object needs (here 2 of the 4). Some masters send this form."""
    dev = start(name)
    mark = dev.rec.mark()
    dev.net.send_message(0x600 + dev.node_id, bytes([0x22, index & 0xFF, index >> 8, 0, 0x34, 0x12, 0x00, 0x00]))
    resp = dev.rec.wait(dev.sdo_tx_cob, mark, 1.0)
    assert resp is not None
    assert resp.data[:4] == bytes([0x60, index & 0xFF, index >> 8, 0]), f"download response expected, got {resp}"
    assert dev.read_int(index) == 0x1234


@pytest.mark.parametrize("name", ["co401gw1", "cr3101", "canopenia"])
def test_sdo_segmented_upload(start, name):
    dev = start(name)
    expected = dev.entry(0x1008)["default"]
    assert len(expected) > 4
    mark = dev.rec.mark()
    assert dev.node.sdo[0x1008].raw == expected
    responses = dev.rec.since(mark, dev.sdo_tx_cob)
    assert responses[0].data[0] & 0xE3 == 0x41, f"segmented initiate response (size indicated) expected: {responses[0]}"
    assert int.from_bytes(responses[0].data[4:8], "little") == len(expected)
    segments = responses[1:]
    assert len(segments) == -(-len(expected) // 7)
    assert [s.data[0] >> 4 & 1 for s in segments] == [i % 2 for i in range(len(segments))], "toggle bit"
    assert segments[-1].data[0] & 0x01, "last segment has c = 1"


@pytest.mark.parametrize(
    "name,index,sub,data",
    [
        # cr3101 2000h "Name of the memory card": a writable VISIBLE_STRING of 11 characters.
        ("cr3101", 0x2000, 0, b"CARD-4711-X"),
        ("cr3101", 0x3000, 1, b"LOG_TEMP"),
        # co401gw1 has no writable entry longer than 4 bytes: a forced segmented download of
        # the INTEGER32 6424h sub 1 (analog input upper limit) exercises the protocol.
        ("co401gw1", 0x6424, 1, (-123456).to_bytes(4, "little", signed=True)),
    ],
    ids=["cr3101-2000-string11", "cr3101-3000.1-string8", "co401gw1-6424.1-int32"],
)
def test_sdo_segmented_download(start, name, index, sub, data):
    dev = start(name)
    mark = dev.rec.mark()
    dev.write(index, sub, data, force_segment=True)
    responses = dev.rec.since(mark, dev.sdo_tx_cob)
    assert responses[0].data[:4] == bytes([0x60, index & 0xFF, index >> 8, sub]), f"initiate response {responses[0]}"
    segments = responses[1:]
    assert len(segments) == -(-len(data) // 7)
    assert [s.data[0] for s in segments] == [0x20 | (i % 2) << 4 for i in range(len(segments))], "segment responses"
    assert dev.read(index, sub) == data


def test_sdo_segmented_download_of_shorter_string(start):
    """A VISIBLE_STRING written shorter than its maximum reads back with the written length."""
    dev = start("cr3101")
    dev.write(0x2000, 0, b"LONG-NAME-1")
    dev.write(0x2000, 0, b"SHORT")
    assert dev.read(0x2000) == b"SHORT"
    assert dev.node.sdo[0x2000].raw == "SHORT"


@pytest.mark.parametrize("name", ["cr3101", "canopenia"])
def test_sdo_block_upload(start, name):
    dev = start(name)
    expected = dev.entry(0x1008)["default"].encode()
    mark = dev.rec.mark()
    with dev.node.sdo.open(0x1008, 0, "rb", block_transfer=True) as f:
        data = f.read()
    assert data == expected
    first = dev.rec.since(mark, dev.sdo_tx_cob)[0]
    assert first.data[0] & 0xE0 == 0xC0, f"block upload initiate response (scs 6) expected: {first}"


@pytest.mark.parametrize(
    "name,index,sub,data",
    [
        # An 11-byte VISIBLE_STRING (cr3101 2000h): two segments, CRC over all 11 bytes.
        ("cr3101", 0x2000, 0, b"BLOCKXFER11"),
    ],
    ids=["cr3101-2000-string11"],
)
def test_sdo_block_download_and_upload(start, name, index, sub, data):
    dev = start(name)
    mark = dev.rec.mark()
    with dev.node.sdo.open(index, sub, "wb", block_transfer=True, size=len(data)) as f:
        f.write(data)
    responses = dev.rec.since(mark, dev.sdo_tx_cob)
    assert responses[0].data[0] & 0xE3 == 0xA0, f"block download initiate response (scs 5) expected: {responses[0]}"
    assert responses[-1].data[0] & 0xE3 == 0xA1, f"block download end response expected: {responses[-1]}"
    assert dev.read(index, sub) == data
    with dev.node.sdo.open(index, sub, "rb", block_transfer=True) as f:
        assert f.read() == data


def test_co401gw1_refuses_block_transfer(start):
    """GW1-63: no block transfer; a block initiate is aborted with 0504 0001h, and segmented
    transfers still work."""
    dev = start("co401gw1")
    for request in ([0xA0, 0x08, 0x10, 0x00, 0x7F, 0, 0, 0], [0xC6, 0x24, 0x64, 0x01, 4, 0, 0, 0]):
        mark = dev.rec.mark()
        dev.net.send_message(0x600 + dev.node_id, bytes(request))
        answer = dev.rec.wait(dev.sdo_tx_cob, mark, 2.0)
        assert answer is not None and answer.data[0] == 0x80, f"abort expected: {answer}"
        assert int.from_bytes(answer.data[4:8], "little") == 0x05040001
    assert dev.read(0x1008) == dev.entry(0x1008)["default"].encode()


# ============================================================================================
# 3. SDO aborts
# ============================================================================================

UP, DOWN = "upload", "download"
ABORT_CASES = [
    # device, direction, index, sub, data, abort code, what
    ("co401gw1", DOWN, 0x1000, 0, b"\x00\x00\x00\x00", 0x06010002, "read-only object"),
    ("co401gw1", DOWN, 0x1008, 0, b"NAME", 0x06010002, "read-only string"),
    ("co401gw1", UP, 0x2222, 0, None, 0x06020000, "missing object"),
    ("co401gw1", DOWN, 0x2222, 0, b"\x01", 0x06020000, "missing object"),
    ("co401gw1", UP, 0x100B, 0, None, 0x06020000, "access none (not on the bus)"),
    ("co401gw1", UP, 0x1018, 5, None, 0x06090011, "missing sub-index"),
    ("co401gw1", DOWN, 0x1029, 3, b"\x00", 0x06090011, "missing sub-index"),
    ("co401gw1", DOWN, 0x1017, 0, b"\x01", 0x06070013, "length too low"),
    ("co401gw1", DOWN, 0x1017, 0, b"\x01\x00\x00\x00", 0x06070012, "length too high"),
    ("co401gw1", DOWN, 0x1029, 1, b"\x03", 0x06090031, "value too high"),
    ("co401gw1", DOWN, 0x1800, 2, bytes([241]), 0x06090030, "reserved transmission type"),
    ("co401gw1", DOWN, 0x1800, 1, (0x1FE).to_bytes(4, "little"), 0x06090030, "PDO COB-ID change while valid"),
    ("co401gw1", DOWN, 0x1014, 0, (0x0FE).to_bytes(4, "little"), 0x06090030, "EMCY COB-ID change while valid"),
    ("co401gw1", DOWN, 0x1800, 3, (10).to_bytes(2, "little"), 0x06090030, "inhibit time change while valid"),
    ("co401gw1", DOWN, 0x1400, 2, bytes([253]), 0x06090030, "RTR-only transmission type for an RPDO"),
    ("cr3101", DOWN, 0x1000, 0, b"\x00\x00\x00\x00", 0x06010002, "read-only object"),
    ("cr3101", UP, 0x2222, 0, None, 0x06020000, "missing object"),
    ("cr3101", UP, 0x1018, 4, None, 0x06090011, "missing sub-index"),
    ("cr3101", DOWN, 0x100C, 0, b"\x01", 0x06070013, "length too low"),
    ("cr3101", DOWN, 0x2000, 0, b"123456789012", 0x06070012, "string too long"),
    ("cr3101", DOWN, 0x20F0, 0, bytes([128]), 0x06090031, "value too high"),
    ("cr3101", DOWN, 0x20F0, 0, bytes([0]), 0x06090032, "value too low"),
    ("cr3101", DOWN, 0x3003, 1, bytes([4]), 0x06090030, "value not in the allowed list"),
    ("cr3101", DOWN, 0x1404, 1, (0x100 + 0x22).to_bytes(4, "little"), 0x06090030, "restricted COB-ID"),
    ("canopenia", UP, 0x5F01, 1, None, 0x06010001, "write-only object"),
    ("canopenia", DOWN, 0x1008, 0, b"X", 0x06010002, "const object"),
    ("canopenia", DOWN, 0x1F51, 1, bytes([4]), 0x06090031, "value too high"),
    ("canopenia", DOWN, 0x5F01, 1, bytes([128]), 0x06090032, "value too low"),
]


@pytest.mark.parametrize(
    "name,direction,index,sub,data,code",
    [pytest.param(*c[:6], id=f"{c[0]}-{c[1]}-{c[2]:04X}.{c[3]}-{c[6].replace(' ', '_')}") for c in ABORT_CASES],
)
def test_sdo_abort_codes(start, name, direction, index, sub, data, code):
    dev = start(name)
    readable = direction == DOWN and dev.has(index, sub) and dev.entry(index, sub)["access"] in ("ro", "rw", "rww", "rwr", "const")
    before = dev.read(index, sub) if readable else None
    mark = dev.rec.mark()
    if direction == UP:
        got = sdo_abort(dev.read, index, sub)
    else:
        got = sdo_abort(dev.write, index, sub, data)
    assert got == code, f"abort {got:#010x}, expected {code:#010x}"
    abort = dev.rec.wait(dev.sdo_tx_cob, mark, 1.0)
    assert abort.data[:4] == bytes([0x80, index & 0xFF, index >> 8, sub]), f"abort frame {abort}"
    assert int.from_bytes(abort.data[4:], "little") == code
    if before is not None:
        assert dev.read(index, sub) == before, "a refused write leaves the value unchanged"


def test_sdo_protocol_errors(start):
    """Raw SDO frames: unknown command specifier, toggle error, block CRC error."""
    dev = start("cr3101")
    rx, tx = 0x600 + dev.node_id, dev.sdo_tx_cob

    def request(payload, timeout=1.0):
        mark = dev.rec.mark()
        dev.net.send_message(rx, bytes(payload).ljust(8, b"\x00"))
        f = dev.rec.wait(tx, mark, timeout)
        assert f is not None, f"no SDO response to {bytes(payload).hex(' ')}"
        return f.data

    def abort_code(data):
        assert data[0] == 0x80, f"abort expected: {data.hex(' ')}"
        return int.from_bytes(data[4:8], "little")

    before = dev.read(0x2000)
    # Client command specifier 7 does not exist: 0504 0001h.
    assert abort_code(request([0xE0, 0x00, 0x20, 0x00])) == 0x05040001
    # Segmented download whose first segment has toggle bit 1: 0503 0000h.
    assert request([0x21, 0x00, 0x20, 0x00, 11, 0, 0, 0])[:4] == bytes([0x60, 0x00, 0x20, 0x00])
    assert abort_code(request([0x10, *b"TOGGLE!"])) == 0x05030000
    # Block download with a wrong CRC: 0504 0004h.
    data = b"CRC-ERROR!!"
    resp = request([0xC6, 0x00, 0x20, 0x00, len(data), 0, 0, 0])
    assert resp[:4] == bytes([0xA4, 0x00, 0x20, 0x00]), f"block download with CRC support expected: {resp.hex(' ')}"
    blksize = resp[4]
    assert 1 <= blksize <= 127, "block size"
    segments = [data[i : i + 7] for i in range(0, len(data), 7)]
    while segments:
        block, segments = segments[:blksize], segments[blksize:]
        mark = dev.rec.mark()
        for seqno, seg in enumerate(block, 1):
            last = 0x80 if not segments and seqno == len(block) else 0
            dev.net.send_message(rx, bytes([last | seqno, *seg.ljust(7, b"\x00")]))
        ack = dev.rec.wait(tx, mark, 1.0)
        assert ack is not None and ack.data[:2] == bytes([0xA2, len(block)]), f"block acknowledge {ack}"
        blksize = ack.data[2]
    crc = binascii.crc_hqx(data, 0) ^ 0xFFFF
    assert abort_code(request([0xC1 | 3 << 2, crc & 0xFF, crc >> 8])) == 0x05040004
    assert dev.read(0x2000) == before, "aborted transfers leave the value unchanged"
    # Segmented download without size indication (e = 0, s = 0): the last segment ends it.
    assert request([0x20, 0x00, 0x20, 0x00])[:4] == bytes([0x60, 0x00, 0x20, 0x00])
    assert request([0x00, *b"NO-SIZE"])[0] == 0x20
    assert request([0x10 | 4 << 1 | 1, *b"!!!", 0, 0, 0, 0])[0] == 0x30  # n = 4: 3 data bytes
    assert dev.read(0x2000) == b"NO-SIZE!!!"
    # A transfer the client aborts is dropped silently; the next one starts afresh.
    assert request([0x21, 0x00, 0x20, 0x00, 11, 0, 0, 0])[0] == 0x60
    mark = dev.rec.mark()
    dev.net.send_message(rx, bytes([0x80, 0x00, 0x20, 0x00, 0x00, 0x00, 0x04, 0x05]))
    assert dev.rec.wait(tx, mark, 0.1) is None, "a server must not answer an abort"
    assert request([0x00, *b"IGNORED"])[:1] == b"\x80", "a segment after the abort is no transfer"
    assert dev.read(0x2000) == b"NO-SIZE!!!"
    # A transfer the client abandons is aborted by the server's timeout: 0504 0000h.
    assert request([0x21, 0x00, 0x20, 0x00, 11, 0, 0, 0])[0] == 0x60
    mark = dev.rec.mark()
    timeout = dev.rec.wait(tx, mark, 3.0)
    assert timeout is not None, "no abort after the client stopped sending segments"
    assert abort_code(timeout.data) == 0x05040000
    # The server is ready for the next transfer.
    dev.write(0x2000, 0, b"AFTER")
    assert dev.read(0x2000) == b"AFTER"


# ============================================================================================
# 4. PDO mapping and TPDOs
# ============================================================================================

# Per device: TPDO number, the entries to map (index, sub, bits), the entry written to cause
# events with its size, and an RPDO that writes a mapped entry.
TPDO_SETUPS = {
    "co401gw1": dict(tpdo=1, map=[(0x6200, 1, 8), (0x6411, 1, 16), (0x6411, 2, 16)], trigger=(0x6411, 1, 2), rpdo=1),
    "canopenia": dict(tpdo=1, map=[(0x6200, 1, 8), (0x6200, 2, 8), (0x6200, 3, 8)], trigger=(0x6200, 2, 1), rpdo=1),
}


def remap_tpdo(dev, number, entries, trans_type, event_timer=0, inhibit_time=0):
    """Remap a TPDO through python-canopen's PDO API (the CiA 301 procedure)."""
    dev.node.tpdo.read()
    pdo = dev.node.tpdo[number]
    pdo.clear()
    for index, sub, bits in entries:
        pdo.add_variable(index, sub, bits)
    pdo.trans_type = trans_type
    pdo.event_timer = event_timer
    pdo.inhibit_time = inhibit_time
    pdo.enabled = True
    pdo.save()
    return pdo


def packed(entries, values):
    return b"".join(v.to_bytes(bits // 8, "little", signed=v < 0) for (_, _, bits), v in zip(entries, values))


# CO401GW1 sends a TPDO on DS401 events only (its inputs changing through the masks, erratum
# GW1-61; tests/python/test_gw1.py), never on an SDO or RPDO write of an output: the tests of
# "a write of a mapped object is an event" run on CANopenIA.
@pytest.mark.parametrize("name", ["canopenia"])
def test_tpdo_remap_event_driven(start, name):
    dev = start(name)
    setup = TPDO_SETUPS[name]
    n, entries = setup["tpdo"], setup["map"]
    pdo = remap_tpdo(dev, n, entries, 255)
    cob = pdo.cob_id
    # The mapping reads back as written.
    mapping = 0x1A00 + n - 1
    assert dev.read_int(mapping, 0) == len(entries)
    assert [dev.read_int(mapping, i + 1) for i in range(len(entries))] == [i << 16 | s << 8 | b for i, s, b in entries]
    assert dev.read_int(0x1800 + n - 1, 2) == 255
    assert dev.read_int(0x1800 + n - 1, 1) & 0x80000000 == 0, "the PDO is valid again"

    # Pre-operational: an event does not send the PDO.
    index, sub, size = setup["trigger"]
    mark = dev.rec.mark()
    dev.write_int(index, sub, 0x11, size)
    assert dev.rec.wait(cob, mark, 0.15) is None, "no PDO outside Operational"

    dev.nmt(START)
    assert dev.guarded_state() == OPERATIONAL
    # An SDO write of a mapped object is an event.
    mark = dev.rec.mark()
    dev.write_int(index, sub, 0x42, size)
    f = dev.rec.wait(cob, mark, 1.0)
    assert f is not None, "no event-driven TPDO after writing a mapped object"
    values = [dev.read_int(i, s, signed=i == 0x6411) for i, s, _ in entries]
    assert f.data == packed(entries, values)
    assert 0x42 in values
    # python-canopen decodes the received PDO with the mapping it configured.
    deadline = time.monotonic() + 1
    while pdo.data != f.data and time.monotonic() < deadline:
        time.sleep(0.01)
    assert [var.raw for var in pdo.map] == values
    # Event timer 0: no further transmission without an event.
    assert dev.rec.wait(cob, dev.rec.mark(), 0.3) is None, "event timer 0 must not send periodically"

    # An RPDO writing a mapped object is an event as well.
    dev.node.rpdo.read()
    rpdo = dev.node.rpdo[setup["rpdo"]]
    assert any((v.index, v.subindex) == (0x6200, 1) for v in rpdo.map)
    for var in rpdo.map:
        var.raw = 0xA5 if (var.index, var.subindex) == (0x6200, 1) else 0
    mark = dev.rec.mark()
    rpdo.transmit()
    f = dev.rec.wait(cob, mark, 1.0, lambda f: f.data[0] == 0xA5)
    assert f is not None, "no TPDO after an RPDO wrote a mapped object"
    assert dev.read_int(0x6200, 1) == 0xA5


# Type 0 sends after an event: CANopenIA only (see above); the cyclic types on both.
@pytest.mark.parametrize("name,trans_type", [("co401gw1", 1), ("co401gw1", 2), ("canopenia", 0), ("canopenia", 1), ("canopenia", 2)])
def test_tpdo_synchronous(start, name, trans_type):
    dev = start(name)
    setup = TPDO_SETUPS[name]
    n, entries = setup["tpdo"], setup["map"]
    pdo = remap_tpdo(dev, n, entries, trans_type)
    cob = pdo.cob_id
    index, sub, size = setup["trigger"]
    dev.write_int(index, sub, 0x33, size)
    dev.nmt(START)
    assert dev.guarded_state() == OPERATIONAL
    values = [dev.read_int(i, s, signed=i == 0x6411) for i, s, _ in entries]
    expected = packed(entries, values)

    if trans_type == 0:
        # Acyclic synchronous: a SYNC without an event sends nothing...
        mark = dev.rec.mark()
        dev.net.sync.transmit()
        assert dev.rec.wait(cob, mark, 0.15) is None, "type 0 sends only after an event"
        # ... an event alone sends nothing either...
        mark = dev.rec.mark()
        dev.write_int(index, sub, 0x44, size)
        assert dev.rec.wait(cob, mark, 0.15) is None, "type 0 waits for the SYNC"
        # ... the next SYNC does, with the current values.
        values = [dev.read_int(i, s, signed=i == 0x6411) for i, s, _ in entries]
        mark = dev.rec.mark()
        dev.net.sync.transmit()
        f = dev.rec.wait(cob, mark, 1.0)
        assert f is not None and f.data == packed(entries, values)
        mark = dev.rec.mark()
        dev.net.sync.transmit()
        assert dev.rec.wait(cob, mark, 0.15) is None, "one transmission per event"
        return

    # Cyclic synchronous: every n-th SYNC, not on events.
    mark = dev.rec.mark()
    dev.write_int(index, sub, 0x33, size)  # same value: an event, but type 1..240 ignore events
    assert dev.rec.wait(cob, mark, 0.15) is None, "cyclic synchronous PDOs do not send on events"
    sent_after = []
    for i in range(1, 7):
        mark = dev.rec.mark()
        dev.net.sync.transmit(i if i > 3 else None)  # SYNC without, then with the counter byte
        f = dev.rec.wait(cob, mark, 0.5 if i % trans_type == 0 else 0.1)
        if f is not None:
            sent_after.append(i)
            assert f.data == expected
    assert sent_after == [i for i in range(1, 7) if i % trans_type == 0], f"TPDO after SYNCs {sent_after}"
    # python-canopen received them with the mapped values.
    assert [var.raw for var in pdo.map] == values


def test_tpdo_event_timer_and_inhibit_time(start):
    dev = start("co401gw1")
    entries = TPDO_SETUPS["co401gw1"]["map"]
    # Event timer 100 ms, no events: about 10 transmissions per second.
    pdo = remap_tpdo(dev, 1, entries, 254, event_timer=100)
    dev.nmt(START)
    mark = dev.rec.mark()
    time.sleep(1.0)
    frames = dev.rec.since(mark, pdo.cob_id)
    assert 7 <= len(frames) <= 13, f"{len(frames)} TPDOs in 1 s with a 100 ms event timer"
    gaps = [b.t - a.t for a, b in zip(frames, frames[1:])]
    assert 0.07 <= statistics.median(gaps) <= 0.13, f"event timer gaps {gaps}"
    # Leaving Operational stops the PDO.
    dev.nmt(PRE_OP)
    assert dev.guarded_state() == PRE_OPERATIONAL
    mark = dev.rec.mark()
    assert dev.rec.wait(pdo.cob_id, mark, 0.25) is None, "TPDO sent in pre-operational"


def test_tpdo_inhibit_time(start):
    # SDO writes of a mapped object are events on CANopenIA (not on CO401GW1, erratum GW1-61).
    dev = start("canopenia")
    entries = TPDO_SETUPS["canopenia"]["map"]
    # Inhibit time 50 ms (500 x 100 us), event timer off: a burst of events is spaced out and
    # the last value still goes out.
    pdo = remap_tpdo(dev, 1, entries, 255, event_timer=0, inhibit_time=500)
    assert dev.read_int(0x1800, 3) == 500
    dev.nmt(START)
    mark = dev.rec.mark()
    for v in range(1, 21):
        dev.write_int(0x6200, 2, v, 1)
        time.sleep(0.005)
    last = dev.rec.wait(pdo.cob_id, mark, 1.0, lambda f: f.data[1] == 20)
    assert last is not None, "the last value must be sent once the inhibit time has passed"
    frames = dev.rec.since(mark, pdo.cob_id)
    gaps = [b.t - a.t for a, b in zip(frames, frames[1:])]
    assert len(frames) < 20, "events within the inhibit time are merged"
    assert all(g >= 0.04 for g in gaps), f"TPDOs closer than the 50 ms inhibit time: {gaps}"


def test_tpdo_synchronous_rtr(start):
    """Transmission type 252: the data is sampled at SYNC and sent on a remote frame."""
    dev = start("co401gw1")
    entries = [(0x6411, 1, 16)]
    pdo = remap_tpdo(dev, 1, entries, 252)
    dev.nmt(START)
    dev.write_int(0x6411, 1, 1111, 2)
    dev.net.sync.transmit()
    dev.write_int(0x6411, 1, 2222, 2)
    mark = dev.rec.mark()
    assert dev.rec.wait(pdo.cob_id, mark, 0.15) is None, "type 252 sends only on a remote request"
    dev.net.send_message(pdo.cob_id, b"", remote=True)
    f = dev.rec.wait(pdo.cob_id, mark, 1.0)
    assert f is not None, "no TPDO answering the remote request"
    assert f.data == (1111).to_bytes(2, "little"), "the value sampled at the SYNC, not the current one"
    dev.net.sync.transmit()
    mark = dev.rec.mark()
    dev.net.send_message(pdo.cob_id, b"", remote=True)
    f = dev.rec.wait(pdo.cob_id, mark, 1.0)
    assert f is not None and f.data == (2222).to_bytes(2, "little")


def test_tpdo_remote_request(start):
    """Transmission type 253: sent on a remote frame (RTR allowed in the COB-ID)."""
    dev = start("co401gw1")
    entries = TPDO_SETUPS["co401gw1"]["map"]
    pdo = remap_tpdo(dev, 1, entries, 253)
    dev.write_int(0x6411, 2, -2, 2)
    dev.nmt(START)
    mark = dev.rec.mark()
    dev.write_int(0x6411, 1, 7, 2)
    assert dev.rec.wait(pdo.cob_id, mark, 0.15) is None, "type 253 is not event-driven"
    mark = dev.rec.mark()
    pdo.remote_request()
    f = dev.rec.wait(pdo.cob_id, mark, 1.0)
    assert f is not None, "no TPDO answering the remote request"
    assert f.data == packed(entries, [dev.read_int(0x6200, 1), 7, -2])
    # COB-ID bit 30 set: remote requests are not answered.
    dev.nmt(PRE_OP)
    pdo.rtr_allowed = False
    pdo.save()
    assert dev.read_int(0x1800, 1) & 0xC0000000 == 0x40000000
    dev.nmt(START)
    mark = dev.rec.mark()
    dev.net.send_message(pdo.cob_id, b"", remote=True)
    assert dev.rec.wait(pdo.cob_id, mark, 0.2) is None, "TPDO answered a remote request with RTR not allowed"


def test_pdo_mapping_rules(start):
    dev = start("co401gw1")
    # Writing the mapping of a valid PDO: 0800 0022h.
    assert dev.read_int(0x1800, 1) & 0x80000000 == 0
    assert sdo_abort(dev.write_int, 0x1A00, 0, 0, 1) == 0x08000022
    assert sdo_abort(dev.write_int, 0x1A00, 1, 0x64110110, 4) == 0x08000022

    # Through the master's PDO API: a non-mappable object (1000h Device Type)...
    dev.node.tpdo.read()
    pdo = dev.node.tpdo[1]
    pdo.clear()
    pdo.add_variable(0x1000, 0, 32)
    with pytest.raises(SdoAbortedError) as e:
        pdo.save()
    assert e.value.code == 0x06040041
    # ... and more than 64 bits (5 x 16).
    pdo.clear()
    for index, sub in [(0x6411, 1), (0x6411, 2), (0x6411, 3), (0x6411, 4), (0x6300, 1)]:
        pdo.add_variable(index, sub, 16)
    with pytest.raises(SdoAbortedError) as e:
        pdo.save()
    assert e.value.code == 0x06040042
    # A TPDO cannot map a write-only-for-the-bus RPDO object the other way round: an RPDO
    # cannot map a read-only input (6000h).
    dev.write_int(0x1400, 1, 0x80000000 | 0x205, 4)
    dev.write_int(0x1600, 0, 0, 1)
    assert sdo_abort(dev.write_int, 0x1600, 1, 0x60000108, 4) == 0x06040041


def test_cr3101_has_static_pdo_mapping(start):
    dev = start("cr3101")
    assert dev.read_int(0x1600, 0) == 4
    assert sdo_abort(dev.write_int, 0x1600, 0, 0, 1) == 0x06010002
    assert sdo_abort(dev.write_int, 0x1600, 1, 0x50000910, 4) == 0x06010002


# ============================================================================================
# 5. RPDOs
# ============================================================================================

RPDO_CASES = [
    # device, RPDO number, mapped entries (index, sub, bytes), payload
    ("co401gw1", 1, [(0x6200, s, 1) for s in range(1, 9)], bytes(range(0x11, 0x19))),
    ("co401gw1", 2, [(0x6411, s, 2) for s in range(1, 5)], bytes.fromhex("3412 FFFF 0080 7856")),
    # CR3101's RPDOs feed its files, not its dictionary: test_cr3101.py.
    ("canopenia", 1, [(0x6200, s, 1) for s in range(1, 9)], bytes.fromhex("0102040810204080")),
]


@pytest.mark.parametrize("name,number,entries,payload", RPDO_CASES, ids=[f"{c[0]}-rpdo{c[1]}" for c in RPDO_CASES])
def test_rpdo_writes_dictionary(start, name, number, entries, payload):
    dev = start(name)
    cob = dev.read_int(0x1400 + number - 1, 1)
    assert cob & 0x80000000 == 0 and cob & 0x7FF == [0x200, 0x300, 0x400, 0x500][number - 1] + dev.node_id
    before = [dev.read(i, s) for i, s, _ in entries]
    # Pre-operational: RPDOs are not processed.
    dev.net.send_message(cob & 0x7FF, payload)
    assert [dev.read(i, s) for i, s, _ in entries] == before, "RPDO processed outside Operational"
    dev.nmt(START)
    dev.net.send_message(cob & 0x7FF, payload)
    at = 0
    for index, sub, size in entries:
        assert dev.read(index, sub) == payload[at : at + size], f"{index:04X}.{sub}"
        at += size


def test_rpdo_by_master_pdo_api(start):
    dev = start("co401gw1")
    dev.node.rpdo.read()
    rpdo = dev.node.rpdo[2]
    assert [(v.index, v.subindex) for v in rpdo.map] == [(0x6411, s) for s in range(1, 5)]
    dev.nmt(START)
    for var, value in zip(rpdo.map, [-1, 2, -30000, 32767]):
        var.raw = value
    rpdo.transmit()
    assert [dev.node.sdo[0x6411][s].raw for s in range(1, 5)] == [-1, 2, -30000, 32767]


def test_rpdo_synchronous_applies_at_sync(start):
    dev = start("co401gw1")
    dev.write_int(0x1400, 2, 1, 1)  # RPDO1 synchronous
    dev.nmt(START)
    dev.net.send_message(0x200 + dev.node_id, bytes([0x99] * 8))
    assert dev.read_int(0x6200, 1) == 0, "a synchronous RPDO waits for the SYNC"
    dev.net.sync.transmit()
    assert dev.read_int(0x6200, 1) == 0x99


def test_rpdo_remap_by_master(start):
    """RPDO remapping through python-canopen; the new layout is applied."""
    dev = start("canopenia")
    dev.node.rpdo.read()
    rpdo = dev.node.rpdo[1]
    rpdo.clear()
    rpdo.add_variable(0x6200, 8, 8)
    rpdo.add_variable(0x6200, 7, 8)
    rpdo.trans_type = 255
    rpdo.enabled = True
    rpdo.save()
    assert dev.read_int(0x1600, 0) == 2
    dev.nmt(START)
    rpdo.map[0].raw = 0x88
    rpdo.map[1].raw = 0x77
    rpdo.transmit()
    assert dev.read_int(0x6200, 8) == 0x88
    assert dev.read_int(0x6200, 7) == 0x77
    assert dev.read_int(0x6200, 1) == 0
    # CiA 301: of an RPDO longer than its mapping the first bytes are used.
    dev.net.send_message(rpdo.cob_id, bytes([0x18, 0x17, 1, 2, 3, 4, 5, 6]))
    assert (dev.read_int(0x6200, 8), dev.read_int(0x6200, 7)) == (0x18, 0x17)
    assert [dev.read_int(0x6200, s) for s in range(1, 7)] == [0] * 6


# ============================================================================================
# 6. Heartbeat producer
# ============================================================================================


@pytest.mark.parametrize("name", ["co401gw1", "canopenia"])
def test_heartbeat_period(start, name):
    dev = start(name)
    mark = dev.rec.mark()
    # (The boot-up message may still arrive if the node started after the master connected.)
    assert dev.rec.wait(dev.nmt_err_cob, mark, 0.2, lambda f: f.data != b"\x00") is None, "1017h = 0: no heartbeat"
    dev.node.sdo[0x1017].raw = 50
    mark = dev.rec.mark()
    time.sleep(1.0)
    beats = dev.rec.since(mark, dev.nmt_err_cob)
    assert 14 <= len(beats) <= 26, f"{len(beats)} heartbeats in 1 s at 50 ms"
    assert all(b.data == bytes([PRE_OPERATIONAL]) for b in beats)
    gaps = [b.t - a.t for a, b in zip(beats, beats[1:])]
    assert 0.035 <= statistics.median(gaps) <= 0.065, f"heartbeat gaps {gaps}"
    assert min(gaps) >= 0.015, f"heartbeats must not burst: {gaps}"
    # 1017h = 0 stops the heartbeat.
    dev.node.sdo[0x1017].raw = 0
    time.sleep(0.06)
    mark = dev.rec.mark()
    assert dev.rec.wait(dev.nmt_err_cob, mark, 0.2) is None, "heartbeat after 1017h = 0"


def test_heartbeat_replaces_node_guarding(start):
    """With a heartbeat producer time the node uses heartbeat, not guarding (CiA 301 7.2.8.3.2)."""
    dev = start("co401gw1")
    assert dev.guard().data[0] == PRE_OPERATIONAL
    dev.node.sdo[0x1017].raw = 500
    mark = dev.rec.mark()
    dev.net.send_message(dev.nmt_err_cob, b"", remote=True)
    assert dev.rec.wait(dev.nmt_err_cob, mark, 0.2, lambda f: f.data != b"\x00") is None, "guarding answered with 1017h != 0"
    assert dev.wait_heartbeat(PRE_OPERATIONAL, timeout=1.0, mark=mark) is not None
    assert dev.node.nmt.wait_for_heartbeat(1.0) == "PRE-OPERATIONAL"


# ============================================================================================
# 7. Emergencies
# ============================================================================================

LIFE_GUARDING = {
    # device: EMCY payload, NMT state after the life guarding error (1029h sub 1 default 0 on
    # co401gw1: Operational -> Pre-operational; cr3101 has no 1029h and its EMCY no reaction).
    "co401gw1": (bytes.fromhex("30 81 01 00 00 00 00 30"), PRE_OPERATIONAL),
    "cr3101": (bytes.fromhex("30 81 11 00 00 00 00 00"), OPERATIONAL),
}


@pytest.mark.parametrize("name", ["co401gw1", "cr3101"])
def test_life_guarding_emcy(start, name):
    payload, state_after = LIFE_GUARDING[name]
    dev = start(name)
    dev.node.sdo[0x100C].raw = 50  # guard time 50 ms
    dev.node.sdo[0x100D].raw = 3  # life time 150 ms
    dev.nmt(START)
    mark = dev.rec.mark()
    dev.node.nmt.start_node_guarding(0.04)
    try:
        answers = dev.rec.wait_count(dev.nmt_err_cob, mark, 10, 2.0)
    finally:
        dev.node.nmt.stop_node_guarding()
    assert len(answers) >= 10 and all(a.data[0] & 0x7F == OPERATIONAL for a in answers)
    assert dev.rec.since(mark, dev.emcy_cob) == [], "no EMCY while the master guards in time"
    emcy = dev.wait_emcy(mark, 0x8130, 2.0)
    assert emcy is not None, "no life guarding EMCY after the master stopped guarding"
    assert emcy.data == payload, f"life guarding EMCY {emcy}"
    late = emcy.t - dev.rec.since(mark, dev.nmt_err_cob)[-1].t
    assert 0.10 <= late <= 1.0, f"EMCY {late:.3f} s after the last guarding answer (life time 0.15 s)"
    # python-canopen's EMCY consumer decoded it.
    assert any(e.code == 0x8130 and e.register == payload[2] for e in dev.node.emcy.log)
    assert dev.node.sdo[0x1001].raw == payload[2], "1001h mirrors the active error"
    if dev.has(0x1003):
        assert dev.read_int(0x1003, 0) == 1, "1003h counts the error"
        assert dev.read_int(0x1003, 1) & 0xFFFF == 0x8130, "1003h sub 1 holds the newest error code"
    # The next guarding request shows the 1029h reaction and ends the error: error reset EMCY.
    mark = dev.rec.mark()
    assert dev.guard().data[0] & 0x7F == state_after
    reset = dev.wait_emcy(mark, 0x0000, 1.0)
    assert reset is not None, "no error reset EMCY after guarding resumed"
    assert reset.data == bytes(8), f"error reset {reset}"
    assert dev.node.emcy.active == []
    assert dev.node.sdo[0x1001].raw == 0


def test_guarding_warning_emcy(start):
    """co401gw1 2103h = 1: the guard-time warning EMCY (manufacturer code 2000 0000)."""
    dev = start("co401gw1")
    dev.node.sdo[0x2103].raw = 1
    dev.node.sdo[0x100C].raw = 60
    dev.node.sdo[0x100D].raw = 10  # life time 600 ms: the warning comes first
    dev.nmt(START)
    mark = dev.rec.mark()
    dev.guard()
    warning = dev.wait_emcy(mark, 0x8130, 1.0)
    assert warning is not None and warning.data == bytes.fromhex("30 81 01 00 00 00 00 20"), f"{warning}"
    assert dev.guarded_state() == OPERATIONAL, "the warning changes no NMT state"


# CR3101's RPDOs feed its files at their configured layout: its length check is in
# firmware/sim/tests/cr3101_device.rs.
@pytest.mark.parametrize("name", ["co401gw1", "canopenia"])
def test_rpdo_too_short_emcy(start, name):
    dev = start(name)
    cob = dev.read_int(0x1400, 1) & 0x7FF
    mapped = [dev.read_int(0x1600, s) for s in range(1, dev.read_int(0x1600, 0) + 1)]
    first = (mapped[0] >> 16, mapped[0] >> 8 & 0xFF)
    length = sum(m & 0xFF for m in mapped) // 8
    assert length > 3
    dev.nmt(START)
    before = dev.read(*first)
    mark = dev.rec.mark()
    dev.net.send_message(cob, bytes([0x5A] * 3))
    emcy = dev.wait_emcy(mark, 0x8210, 1.0)
    if name == "co401gw1":
        # Only the datasheet's emergencies go out (erratum GW1-59); the RPDO is still refused.
        assert emcy is None, f"CO401GW1 sent the CiA 301 emergency 8210h: {emcy}"
        assert dev.read(*first) == before
        return
    assert emcy is not None, "no EMCY 8210h for an RPDO shorter than its mapping"
    assert emcy.data[2] == 0x11, f"error register {emcy}"
    assert any(e.code == 0x8210 and e.register == 0x11 for e in dev.node.emcy.log)
    assert dev.read(*first) == before, "a too short RPDO must not be processed"
    assert dev.read_int(0x1001) == 0x11
    # A correct RPDO ends the length error: error reset EMCY, 1001h clear.
    mark = dev.rec.mark()
    dev.net.send_message(cob, bytes([0x5A] * length))
    assert dev.read(*first)[0] == 0x5A
    reset = dev.wait_emcy(mark, 0x0000, 1.0)
    assert reset is not None, "no error reset EMCY after a correct RPDO ended the length error"
    assert reset.data[2] == 0x00
    assert dev.read_int(0x1001) == 0


@pytest.mark.parametrize("behaviour,state_after", [(0, PRE_OPERATIONAL), (1, OPERATIONAL), (2, STOPPED)], ids=["preop", "no_change", "stopped"])
def test_heartbeat_consumer_timeout_emcy(start, behaviour, state_after):
    dev = start("canopenia")
    producer = 0x33
    dev.node.sdo[0x1029][1].raw = behaviour
    dev.node.sdo[0x1016][1].raw = producer << 16 | 150  # 150 ms
    dev.node.sdo[0x1017].raw = 30  # to watch the state
    dev.nmt(START)
    assert dev.wait_heartbeat(OPERATIONAL) is not None
    mark = dev.rec.mark()
    # Monitoring starts with the first heartbeat: no EMCY while the producer is silent.
    time.sleep(0.3)
    assert dev.rec.since(mark, dev.emcy_cob) == [], "heartbeat consumer must wait for the first heartbeat"
    task = dev.net.send_periodic(0x700 + producer, bytes([OPERATIONAL]), 0.05)
    try:
        time.sleep(0.4)
        assert dev.rec.since(mark, dev.emcy_cob) == [], "EMCY while the producer is on time"
    finally:
        task.stop()
    stopped = time.monotonic()
    # 1029h sub 1 decides the NMT state after the loss.
    assert dev.wait_heartbeat(state_after, timeout=1.0, mark=mark) is not None, f"expected state {state_after:#04x} after the heartbeat loss"
    assert dev.wait_heartbeat(state_after).data == bytes([state_after])
    # The EMCY reports the loss when it happens, also when 1029h then stops the node (the
    # error occurred in Operational, where EMCY is allowed; in Stopped no EMCY can follow).
    emcy = dev.wait_emcy(mark, 0x8130, 0.5)
    assert emcy is not None, "no heartbeat consumer EMCY at the heartbeat loss"
    assert emcy.data == bytes.fromhex("30 81 11 00 00 00 00 00"), f"{emcy}"
    assert 0.08 <= emcy.t - stopped <= 1.0
    if behaviour == 2:
        dev.nmt(PRE_OP)  # EMCY and SDO need a state other than Stopped
    assert dev.node.sdo[0x1001].raw == 0x11
    # The producer is back: error reset.
    mark = dev.rec.mark()
    dev.net.send_message(0x700 + producer, bytes([OPERATIONAL]))
    reset = dev.wait_emcy(mark, 0x0000, 1.0)
    assert reset is not None, "no error reset EMCY after the producer came back"
    assert reset.data == bytes(8)
    assert dev.node.sdo[0x1001].raw == 0


def test_emcy_inhibit_time_and_cob_id(start):
    # CO401GW1 (the device with 1015h) sends only its datasheet's emergencies (GW1-59): the
    # life guarding error 8130h, raised 100 ms after the last guarding RTR, reset by the next.
    dev = start("co401gw1")
    dev.write_int(0x1015, 0, 1000, 2)  # 100 ms between EMCYs
    dev.write_int(0x100C, 0, 50, 2)  # guard time 50 ms
    dev.write_int(0x100D, 0, 2, 1)  # life time 100 ms
    rtr = lambda: dev.net.send_message(dev.nmt_err_cob, b"", remote=True)  # noqa: E731
    mark = dev.rec.mark()
    rtr()  # guarding starts
    raised = dev.wait_emcy(mark, 0x8130, 1.0)
    assert raised is not None and raised.data[7] == 0x30, f"life guarding error: {raised}"
    rtr()  # the error ends at once; its reset waits for the inhibit time
    reset = dev.wait_emcy(mark, 0x0000, 1.0)
    assert reset is not None
    assert reset.t - raised.t >= 0.08, f"EMCYs {reset.t - raised.t:.3f} s apart, inhibit time 100 ms"
    # A new EMCY COB-ID: invalidate, then set the new identifier.
    dev.write_int(0x1014, 0, 0x80000000 | 0x85, 4)
    dev.write_int(0x1014, 0, 0x0FE, 4)
    mark = dev.rec.mark()
    rtr()
    f = dev.rec.wait(0x0FE, mark, 1.0, lambda f: f.data[:2] == bytes([0x30, 0x81]))
    assert f is not None and f.data[:3] == bytes([0x30, 0x81, 0x01]), f"EMCY on the new COB-ID: {f}"
    assert dev.rec.since(mark, dev.emcy_cob) == []


def test_heartbeat_consumer_rejects_duplicate_producer(start):
    dev = start("canopenia")
    dev.write_int(0x1016, 1, 0x33 << 16 | 100, 4)
    assert sdo_abort(dev.write_int, 0x1016, 2, 0x33 << 16 | 200, 4) == 0x06040043
    dev.write_int(0x1016, 2, 0x34 << 16 | 200, 4)
    assert dev.read_int(0x1016, 2) == 0x34 << 16 | 200


def test_broadcast_nmt_with_several_nodes(start):
    dev = start("co401gw1", nodes=3)
    ids = [dev.node_id, dev.node_id + 1, dev.node_id + 2]
    assert [dev.guarded_state(n) for n in ids] == [PRE_OPERATIONAL] * 3
    dev.net.nmt.send_command(START)  # node-ID 0: every node
    assert [dev.guarded_state(n) for n in ids] == [OPERATIONAL] * 3
    dev.net[ids[1]].nmt.send_command(STOP)
    assert [dev.guarded_state(n) for n in ids] == [OPERATIONAL, STOPPED, OPERATIONAL]
    # SDO reaches only the addressed node.
    mark = dev.rec.mark()
    assert dev.net[ids[2]].sdo[0x1008].raw == "CO401GW1"
    sdo_cobs = {f.id for f in dev.rec.since(mark) if 0x580 <= f.id <= 0x5FF}
    assert sdo_cobs == {0x580 + ids[2]}
    mark = dev.rec.mark()
    dev.net.nmt.send_command(RESET_COMM)
    deadline = time.monotonic() + 2
    while time.monotonic() < deadline:
        boots = {f.id for f in dev.rec.since(mark) if f.data == b"\x00" and 0x700 < f.id < 0x780}
        if len(boots) == 3:
            break
        time.sleep(0.01)
    assert boots == {0x700 + n for n in ids}, "one boot-up message per node"
    assert [dev.guarded_state(n) for n in ids] == [PRE_OPERATIONAL] * 3


# ============================================================================================
# 8. Store and restore (1010h / 1011h)
# ============================================================================================

STORE_CASES = {
    # device: a persistent entry (index, sub, bytes) and two values that are not its default
    "co401gw1": ((0x2180, 0, 2), 1234, 4321),
    "cr3101": ((0x100C, 0, 2), 1234, 4321),
}


def reset_node(dev):
    mark = dev.rec.mark()
    dev.nmt(RESET_NODE)
    assert dev.rec.wait(dev.nmt_err_cob, mark, 2.0, lambda f: f.data == b"\x00") is not None


@pytest.mark.parametrize("name", ["co401gw1", "cr3101"])
def test_store_and_restore_parameters(start, name):
    (index, sub, size), stored, changed = STORE_CASES[name]
    dev = start(name)
    default = dev.entry(index, sub)["default"]
    assert dev.read_int(index, sub) == default
    # 1010h sub 1 reads the storage capability: bit 0 on command, bit 1 autonomously.
    capability = dev.read_int(0x1010, 1)
    assert capability & 0x03, f"1010h sub 1 = {capability:#x}"
    dev.write_int(index, sub, stored, size)
    dev.node.store()  # python-canopen: 1010h sub 1 = "save"
    reset_node(dev)
    assert dev.read_int(index, sub) == stored, "stored value lost at reset node"
    # A later change without "save" is lost at reset unless the device saves by itself.
    dev.write_int(index, sub, changed, size)
    reset_node(dev)
    after = dev.read_int(index, sub)
    assert after == (changed if capability & 0x02 else stored)
    # Restore defaults: valid after the next reset.
    dev.node.restore()  # 1011h sub 1 = "load"
    assert dev.read_int(index, sub) == after, "restored defaults take effect at the next reset"
    reset_node(dev)
    assert dev.read_int(index, sub) == default
    reset_node(dev)
    assert dev.read_int(index, sub) == default


@pytest.mark.parametrize("name", ["co401gw1", "cr3101"])
def test_store_restore_wrong_signature(start, name):
    dev = start(name)
    assert sdo_abort(dev.write_int, 0x1010, 1, LOAD, 4) == 0x08000020
    assert sdo_abort(dev.write_int, 0x1010, 1, 0x12345678, 4) == 0x08000020
    assert sdo_abort(dev.write_int, 0x1011, 1, SAVE, 4) == 0x08000020
    assert sdo_abort(dev.write, 0x1010, 1, b"sav") == 0x06070013


def test_co401gw1_stores_only_in_pre_operational(start):
    """The spec restricts 1010h/1011h writes to pre-operational (writable_in)."""
    dev = start("co401gw1")
    dev.nmt(START)
    assert sdo_abort(dev.write_int, 0x1010, 1, SAVE, 4) == 0x08000022
    assert sdo_abort(dev.write_int, 0x1011, 1, LOAD, 4) == 0x08000022
    dev.nmt(PRE_OP)
    dev.write_int(0x1010, 1, SAVE, 4)


def test_stored_parameters_survive_a_restart(start, tmp_path):
    """--store FILE: stored parameters (here heartbeat time and a PDO mapping) survive a new process."""
    store = tmp_path / "gw1.store"
    dev = start("co401gw1", store=store)
    dev.node.sdo[0x1017].raw = 40
    remap_tpdo(dev, 1, [(0x6411, 1, 16)], 255)
    # Storing to a file takes the simulator about 0.2 s (the file is rewritten for every entry),
    # close to python-canopen's default SDO timeout of 0.3 s; real devices storing to flash are
    # slower still, so the master waits longer for this confirmation.
    dev.node.sdo.RESPONSE_TIMEOUT = 3.0
    dev.write_int(0x1010, 1, SAVE, 4)
    start.stop(dev)
    assert store.exists()
    dev = start("co401gw1", store=store)
    assert dev.node.sdo[0x1017].raw == 40
    assert dev.read_int(0x1A00, 0) == 1 and dev.read_int(0x1A00, 1) == 0x64110110
    beat = dev.wait_heartbeat(PRE_OPERATIONAL)
    assert beat is not None, "the stored heartbeat time is in effect after the restart"
