"""The same end-to-end test against two targets that run the same CO401Memory1 firmware logic:
the host simulator (`coforge sim`) and the Cortex-M3 image in QEMU (lm3s6965evb, built by
`cargo xtask test` from firmware/boards/qemu; its path comes in COFORGE_QEMU_IMAGE).

python-canopen is the master over SLCAN on a hub: the simulator's own, or `coforge hub`
connected to the image's UART1, where the image is an SLCAN adapter whose bus is its own node. A serial host talks to
the module's RS232 protocol: the simulator's --serial port, or the image's UART0.

Checks: boot-up (after NMT reset node: an image that booted before anyone connected has sent
its first boot-up into the void), SDO reads of 1000/1018/1008, SDO write and read of memory
bytes and the bank sums, the status TPDO, the heartbeat, and the datasheet's serial examples.
"""

import os
import pathlib
import re
import socket
import subprocess
import time

import canopen
import pytest

from bus import Recorder, connect_attached
from host import COFORGE, ROOT, connect
from qemu import QemuProcess

QEMU_IMAGE = os.environ.get("COFORGE_QEMU_IMAGE", str(ROOT / "firmware/boards/qemu/target/thumbv7m-none-eabi/release/co401memory1"))
# The image that keeps its banks in host files (semihosting), beside the plain one.
FILES_IMAGE = str(pathlib.Path(QEMU_IMAGE).resolve().with_name(pathlib.Path(QEMU_IMAGE).name.replace("co401memory1", "co401memory1-files", 1)))
NODE_ID = 5  # the QEMU board's ID pins; the simulator derives its pins from --node-id
SDO_TIMEOUT = 2.0
WAIT = 10.0


class Target:
    """A running CO401Memory1: `can_url` for python-can, `serial` a connected socket."""

    def __init__(self, kind, image=QEMU_IMAGE, cwd=None):
        self.kind = kind
        if kind == "sim":
            self.proc = subprocess.Popen(
                [COFORGE, "sim", "co401memory1", "--node-id", str(NODE_ID), "--port", "0", "--serial", "0"],
                stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
            )
            serial = re.search(r"serial host on socket://[\d.]+:(\d+)", self.proc.stdout.readline())
            can = re.search(r"on slcan (socket://\S+)", self.proc.stdout.readline())
            assert serial and can, "coforge sim banner"
            self.can_url = can.group(1)
            self.serial = connect(int(serial.group(1)))
        else:
            # UART0 is the serial host line; the hub on UART1 is the bus.
            self.qemu = QemuProcess(image, cwd)
            self.can_url = self.qemu.can_url
            self.serial = self.qemu.connect(self.qemu.ports[0])
        self.serial.settimeout(2.0)
        self.serial.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def close(self):
        self.serial.close()
        if self.kind == "sim":
            self.proc.kill()
            self.proc.wait(timeout=10)
        else:
            self.qemu.stop()


@pytest.fixture(params=["sim", "qemu"])
def target(request):
    t = Target(request.param)
    net = canopen.Network()
    rec = Recorder()
    net.listeners.insert(0, rec)
    try:
        connect_attached(net, t.can_url, 1000000)
        node = canopen.RemoteNode(NODE_ID, canopen.ObjectDictionary())
        node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT
        net.add_node(node)
        t.net, t.node, t.rec = net, node, rec
        if t.kind == "qemu":
            wait_serving(t)
        yield t
    finally:
        net.disconnect()
        t.close()


def wait_serving(t, timeout=20.0):
    """Waits until the image answers an SDO read of 1000h, as a master waits for a node that
    is starting: QEMU starts an image slowly on a busy machine, and the node's boot-up went
    out before anyone listened."""
    deadline = time.monotonic() + timeout
    t.node.sdo.RESPONSE_TIMEOUT = 0.5
    try:
        while True:
            try:
                t.node.sdo.upload(0x1000, 0)
                return
            except canopen.SdoCommunicationError:
                assert time.monotonic() < deadline, f"the image did not answer SDO within {timeout} s"
    finally:
        t.node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT


def upload(t, index, sub=0):
    return t.node.sdo.upload(index, sub)


def download(t, index, sub, data):
    t.node.sdo.download(index, sub, data)


def exchange(t, request_hex, answer_len):
    t.serial.sendall(bytes.fromhex(request_hex))
    got = b""
    deadline = time.monotonic() + WAIT
    while len(got) < answer_len and time.monotonic() < deadline:
        # The socket's own timeout (2 s) only bounds one wait: a busy machine may take longer.
        try:
            got += t.serial.recv(answer_len - len(got))
        except TimeoutError:
            continue
    return got.hex(" ").upper()


def read_frame(t, request_hex):
    """Sends a request and reads one whole answer frame: CMD/LEN byte, then LEN bytes."""
    t.serial.sendall(bytes.fromhex(request_hex))
    head = exchange(t, "", 1)
    length = int(head, 16) & 0x0F
    return (head + " " + exchange(t, "", length)).strip() if length else head


def test_bootup_identity_and_device_name(target):
    mark = target.rec.mark()
    target.net.send_message(0x000, bytes([0x81, NODE_ID]))
    assert target.rec.wait(0x700 + NODE_ID, mark, WAIT, lambda f: f.data == b"\x00"), "boot-up after reset node"
    assert int.from_bytes(upload(target, 0x1000), "little") == 0x00030191
    assert int.from_bytes(upload(target, 0x1018, 1), "little") == 0x58
    assert int.from_bytes(upload(target, 0x1018, 2), "little") == 0x01401FFE
    assert upload(target, 0x1008) == b"CO401Memory1"


def test_memory_bytes_and_bank_sums(target):
    written = {(0x5000, 1): 0x11, (0x5012, 4): 0x23, (0x503F, 0x80): 0xA5}
    for (index, sub), value in written.items():
        download(target, index, sub, bytes([value]))
    for (index, sub), value in written.items():
        assert upload(target, index, sub) == bytes([value])
    total = sum(written.values())
    assert int.from_bytes(upload(target, 0x5C00, 1), "little") == total
    assert int.from_bytes(upload(target, 0x5C00, 2), "little") == total


def test_status_tpdo_and_heartbeat(target):
    for bank in (1, 2):
        download(target, 0x6200, bank, b"\x91")
    download(target, 0x1017, 0, (100).to_bytes(2, "little"))
    mark = target.rec.mark()
    target.net.send_message(0x000, bytes([0x01, NODE_ID]))
    tpdo = target.rec.wait(0x180 + NODE_ID, mark, 3.0)
    assert tpdo is not None and tpdo.data == b"\x00\x00", "TPDO1 carries 6000h.1/.2"
    time.sleep(1.0)
    beats = [f.t for f in target.rec.since(mark, 0x700 + NODE_ID) if f.data == b"\x05"]
    assert len(beats) >= 6, f"{len(beats)} operational heartbeats in over 1 s at 100 ms"
    gaps = sorted(b - a for a, b in zip(beats, beats[1:]))
    assert 0.07 <= gaps[len(gaps) // 2] <= 0.13, f"median heartbeat period {gaps[len(gaps) // 2]:.3f} s"


def test_serial_datasheet_examples(target):
    assert exchange(target, "00", 5) == "04 40 40 03 00"
    assert exchange(target, "12 01 91", 2) == "11 01"
    assert exchange(target, "44 12 50 04 23", 2) == "41 01"
    assert exchange(target, "33 12 50 04", 3) == "32 01 23"
    assert upload(target, 0x5012, 4) == b"\x23", "written over serial, read over SDO"
    assert exchange(target, "83 00 23 01", 2) == "81 01"
    target.net.send_message(0x123, bytes.fromhex("B1 B2 B3 B4 B5"))
    deadline = time.monotonic() + WAIT
    while (answer := read_frame(target, "C0")) == "C1 00" and time.monotonic() < deadline:
        time.sleep(0.05)
    assert answer == "C6 01 B1 B2 B3 B4 B5"
    mark = target.rec.mark()
    assert exchange(target, "D5 23 01 B1 B2 B3", 2) == "D1 01"
    assert target.rec.wait(0x123, mark, WAIT, lambda f: f.data == bytes.fromhex("B1 B2 B3")), "transmitted"


def test_banks_in_host_files_survive_a_restart_of_the_image(tmp_path):
    """The `-files` image keeps its banks in `co401memory1.bank1`/`.bank2` in QEMU's working
    directory: a byte written over the serial line is there after QEMU is stopped and started
    again, and the files mount clean (status 0) instead of as new blank banks (0x40)."""
    first = Target("qemu", image=FILES_IMAGE, cwd=tmp_path)
    try:
        assert exchange(first, "00", 5) == "04 40 40 03 00", "new files: blank banks, cleared"
        assert exchange(first, "44 12 50 04 23", 2) == "41 01"
        assert exchange(first, "33 12 50 04", 3) == "32 01 23"
    finally:
        first.close()
    sizes = {f.name: f.stat().st_size for f in tmp_path.iterdir()}
    assert sizes == {"co401memory1.bank1": 8448, "co401memory1.bank2": 8448}
    second = Target("qemu", image=FILES_IMAGE, cwd=tmp_path)
    try:
        assert exchange(second, "33 12 50 04", 3) == "32 01 23", "the byte survived the restart"
        assert exchange(second, "00", 5) == "04 00 00 00 00", "both banks mounted clean"
    finally:
        second.close()
