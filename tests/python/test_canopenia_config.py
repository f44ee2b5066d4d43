"""CANopenIA's configuration loading (manual section 4.2) end to end, with python-canopen as
the CANopen master on the coprocessor's bus and the host on its serial line, against the
simulator and the QEMU image (`test_canopenia.Target`):

- the activation sequence: pre-operational, the serial number (1018h.4) into 1F50h.1, 0 into
  1F51h.1; the coprocessor boots as node 70h;
- the vendor's CiA 401 file downloaded (segmented SDO) into 1F50h.2 of node 70h, 1 into
  1F51h.1: the error-reset emergency from 70h, the boot-up as node 3, the host told of its new
  node-ID, the file's PDOs and values in use, its autostart and event-timer TPDO running;
- a corrupted file refused with abort 0800 0023h, and a download cut by killing the process:
  after the restart the previous configuration runs;
- a file from `coforge beds` (node 5, manager, autostart) loaded the same way.
"""

import pathlib
import subprocess

import canopen
import pytest

from test_canopenia import COFORGE, SPEC, WAIT, Target

ROOT = pathlib.Path(__file__).resolve().parents[2]
VENDOR_401 = (ROOT / "tests" / "vendor-data" / "canopenia" / "CiA401_IO_Node3.bin").read_bytes()
BOOTLOADER = 0x70


def remote(target, node_id):
    """A python-canopen node for `node_id` with the coprocessor's dictionary."""
    node = canopen.RemoteNode(node_id, target.node.object_dictionary)
    node.sdo.RESPONSE_TIMEOUT = 2.0
    target.net.add_node(node)
    return node


def enter_bootloader(target, node):
    """Steps 2..5 of section 4.2; the boot-up of node 70h."""
    node.nmt.send_command(0x80)
    serial = node.sdo.upload(0x1018, 4)
    node.sdo.download(0x1F50, 1, serial)
    mark = target.rec.mark()
    node.sdo.download(0x1F51, 1, b"\x00")
    assert target.rec.wait(0x770, mark, WAIT, lambda f: f.data == b"\x00"), "boot-up of node 70h"
    return remote(target, BOOTLOADER)


def start_application(target, bootloader, node_id):
    """1 to 1F51h.1: the error reset from 70h, the boot-up of `node_id`."""
    mark = target.rec.mark()
    bootloader.sdo.download(0x1F51, 1, b"\x01")
    assert target.rec.wait(0x0F0, mark, WAIT, lambda f: f.data == bytes(8)), "error-reset emergency from node 70h"
    assert target.rec.wait(0x700 + node_id, mark, WAIT, lambda f: f.data == b"\x00"), f"boot-up of node {node_id}"
    return remote(target, node_id)


@pytest.mark.parametrize("kind", ["sim", "qemu"])
def test_the_bootloader_sequence_loads_configurations(kind, tmp_path):
    target = Target(kind, tmp_path, store=True)
    try:
        bootloader = enter_bootloader(target, target.node)
        bootloader.sdo.download(0x1F50, 2, VENDOR_401)
        node3 = start_application(target, bootloader, 3)
        # The host hears of its new node-ID; the file's PDOs and values are in use.
        target.host.indication(b"D\x03" + bytes.fromhex("00 5F 01 03"))
        assert int.from_bytes(node3.sdo.upload(0x1801, 1), "little") == 0x4000_0283
        assert int.from_bytes(node3.sdo.upload(0x1A01, 1), "little") == 0x6401_0110
        start, payload = target.host.xfer(b"R\x01\x64\x01")
        assert payload[4:6] == b"\x00\x00" and payload[6:] == (0x015A).to_bytes(2, "little")
        # Autostart (FUNC bit 1): operational, TPDO2 on its 1000 ms event timer.
        mark = target.rec.mark()
        assert target.rec.wait(0x283, mark, 2.5), "TPDO2 of node 3 on its event timer"

        # A corrupted file is refused; a download cut by a power loss changes nothing either.
        bootloader = enter_bootloader(target, node3)
        bad = bytearray(VENDOR_401)
        bad[700] ^= 0x40
        with pytest.raises(canopen.SdoAbortedError) as refused:
            bootloader.sdo.download(0x1F50, 2, bytes(bad))
        assert refused.value.code == 0x0800_0023
        cut = bootloader.sdo.open(0x1F50, 2, "wb", size=len(VENDOR_401), buffering=0)
        cut.write(VENDOR_401[:1000])
        # The power goes: the process is killed mid-download (the stream must not try to
        # finish the transfer on a closed bus when it is collected).
        cut._done = True
        target.close()
        target = None
    finally:
        if target is not None:
            target.close()

    target = Target(kind, tmp_path, store=True)
    try:
        # The previous file runs again after the restart: node 3, operational.
        start, payload = target.host.xfer(b"R\x00\x5F\x01")
        assert payload[6:] == b"\x03", payload.hex(" ")
        node3 = remote(target, 3)
        assert int.from_bytes(node3.sdo.upload(0x1801, 1), "little") == 0x4000_0283

        # A file from coforge beds: node 5, the manager on, autostart.
        own = tmp_path / "own.bin"
        subprocess.run([COFORGE, "beds", SPEC, "--node-id", "5", "--manager", "--autostart", "-o", own], check=True, timeout=60)
        bootloader = enter_bootloader(target, node3)
        bootloader.sdo.download(0x1F50, 2, own.read_bytes())
        node5 = start_application(target, bootloader, 5)
        target.host.indication(b"D\x05" + bytes.fromhex("00 5F 01 05"))
        assert int.from_bytes(node5.sdo.upload(0x1800, 1), "little") == 0x185
        assert int.from_bytes(node5.sdo.upload(0x1000, 0), "little") == 0x000F_0191
    finally:
        target.close()
