"""`coforge master`, the command line on coforge-stack's no_std manager, on a bus hub.

Two peers: python-canopen's own SDO server (a `canopen.LocalNode` on a `coforge hub`), which we
did not write, for the SDO client in both directions, expedited and segmented, its aborts and a
timeout once it has gone; and `coforge sim` devices for scan, NMT and monitor.
"""

import re
import subprocess
import time
import types

import canopen
import pytest
from serial.urlhandler import protocol_socket
from bus import connect_attached
from simproc import SimProcess
from host import COFORGE, ROOT


PEER_ID = 0x21


def master(port, *args, check=True, timeout=30):
    """Runs `coforge master --port PORT ARGS...`; its stdout (and the process)."""
    proc = subprocess.run([COFORGE, "master", "--port", str(port), *map(str, args)], capture_output=True, text=True, timeout=timeout)
    if check:
        assert proc.returncode == 0, f"coforge master {' '.join(map(str, args))}: {proc.stderr}"
    return proc


def port_of(url):
    return int(re.search(r":(\d+)$", url).group(1))


def disconnect(net):
    # pyserial's socket:// close() sleeps 0.3 s "in case of quick reconnects"; not needed here.
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(protocol_socket, "time", types.SimpleNamespace(sleep=lambda _s: None))
        net.disconnect()


def peer_dictionary():
    """A small dictionary python-canopen's SDO server serves."""
    od = canopen.ObjectDictionary()
    od.add_object(canopen.objectdictionary.ODVariable("Device type", 0x1000, 0))
    od[0x1000].data_type = canopen.objectdictionary.UNSIGNED32
    od[0x1000].access_type = "ro"
    od[0x1000].default = 0x000F0191
    for index, name, dtype, access, default in [
        (0x2000, "u32", canopen.objectdictionary.UNSIGNED32, "rw", 0x12345678),
        (0x2001, "text", canopen.objectdictionary.VISIBLE_STRING, "rw", "a segmented upload from python-canopen"),
        (0x2002, "constant", canopen.objectdictionary.UNSIGNED16, "ro", 0xBEEF),
        (0x2003, "i16", canopen.objectdictionary.INTEGER16, "rw", -5),
    ]:
        var = canopen.objectdictionary.ODVariable(name, index, 0)
        var.data_type = dtype
        var.access_type = access
        var.default = default
        od.add_object(var)
    return od


@pytest.fixture
def peer():
    """A `coforge hub` with python-canopen's LocalNode on it: (hub port, local node, network)."""
    hub = SimProcess([COFORGE, "hub", "--port", "0"])
    url = hub.banner(r"(socket://\S+)")
    net = canopen.Network()
    net.NOTIFIER_CYCLE = 0.05
    connect_attached(net, url, 500000)
    node = canopen.LocalNode(PEER_ID, peer_dictionary())
    net.add_node(node)
    try:
        yield port_of(url), node, net
    finally:
        if net.bus is not None:
            disconnect(net)
        hub.stop()


def test_sdo_client_against_python_canopen_expedited_both_ways(peer):
    port, node, _ = peer
    assert master(port, "sdo", "read", PEER_ID, "0x1000", 0, "--type", "u32").stdout.strip() == "983441 (0x000F0191)"
    assert master(port, "sdo", "read", PEER_ID, "2003h", 0, "--type", "i16").stdout.strip() == "-5"
    out = master(port, "sdo", "write", PEER_ID, "0x2000", 0, "0xCAFEF00D", "--type", "u32").stdout
    assert "= 3405705229 (0xCAFEF00D)" in out
    assert node.sdo[0x2000].raw == 0xCAFEF00D
    assert master(port, "sdo", "read", PEER_ID, "0x2000", 0).stdout.strip() == "0D F0 FE CA", "no type: hex bytes"


def test_sdo_client_against_python_canopen_segmented_both_ways(peer):
    port, node, _ = peer
    assert master(port, "sdo", "read", PEER_ID, "0x2001", 0, "--type", "str").stdout.strip() == '"a segmented upload from python-canopen"'
    text = "written by coforge master in segments of seven bytes"
    master(port, "sdo", "write", PEER_ID, "0x2001", 0, text, "--type", "str")
    assert node.sdo[0x2001].raw == text
    assert master(port, "sdo", "read", PEER_ID, "0x2001", 0, "--type", "str").stdout.strip() == f'"{text}"'


def test_sdo_client_reports_python_canopens_aborts(peer):
    port, node, _ = peer
    missing = master(port, "sdo", "read", PEER_ID, "0x2FFF", 0, check=False)
    assert missing.returncode == 1
    assert "the node aborted with 0602 0000h: object does not exist in the object dictionary" in missing.stderr
    ro = master(port, "sdo", "write", PEER_ID, "0x2002", 0, "1", "--type", "u16", check=False)
    assert ro.returncode == 1
    assert "the node aborted with 0601 0002h: attempt to write a read only object" in ro.stderr
    assert node.sdo[0x2002].raw == 0xBEEF


def test_sdo_client_times_out_when_the_server_is_gone(peer):
    port, _, net = peer
    disconnect(net)
    started = time.monotonic()
    gone = master(port, "--timeout-ms", "300", "sdo", "read", PEER_ID, "0x1000", 0, check=False)
    assert gone.returncode == 1
    assert f"node {PEER_ID} 1000h sub 0: no answer within 300 ms" in gone.stderr
    assert time.monotonic() - started < 10


def test_bad_arguments_are_explained(peer):
    port, _, _ = peer
    for args, text in [
        (["sdo", "read", "0", "0x1000", "0"], "node-ID 0 addresses no node"),
        (["sdo", "read", "5", "0x10000", "0"], "index `0x10000` is not a number 0..=65535"),
        (["sdo", "write", "5", "0x2000", "0", "70000", "--type", "u16"], "range 0..=65535"),
        (["sdo", "read", "5", "0x2000", "0", "--type", "u17"], "unknown type `u17`"),
        (["nmt", "start", "200"], "node-ID `200` is not a number 0..=127"),
    ]:
        bad = master(port, *args, check=False)
        assert bad.returncode != 0 and text in bad.stderr, (args, bad.stderr)
    nohub = subprocess.run([COFORGE, "master", "--port", "1", "scan"], capture_output=True, text=True, timeout=30)
    assert nohub.returncode == 1 and "cannot connect to the bus hub at 127.0.0.1:1" in nohub.stderr


@pytest.fixture
def sim():
    """Three CO401Memory1 modules, node-IDs 2..4, on one simulated bus: the hub port."""
    proc = SimProcess([COFORGE, "sim", "co401memory1", "--node-id", "2", "--nodes", "3", "--port", "0"])
    url = proc.banner(r"(socket://\S+)")
    try:
        yield port_of(url)
    finally:
        proc.stop()


def test_scan_lists_the_nodes_with_identity(sim):
    out = master(sim, "--timeout-ms", "200", "scan", "--pdos", "1").stdout.splitlines()
    assert out[0].split() == ["node", "device", "type", "vendor-ID", "product", "revision", "serial"]
    rows = [line.split() for line in out if re.match(r"\s+\d+\s+0x", line)]
    assert rows == [[str(n), "0x00030191", "0x00000058", "0x01401FFE", "0x00010078", "0x00000000"] for n in (2, 3, 4)]
    assert f"      TPDO1 COB-ID 0x{0x183:08X} type 255 map 6000h.1/8 6000h.2/8" in out
    assert re.match(r"3 node\(s\) answered; 127 node-IDs scanned in \d+ ms", out[-1])


def test_nmt_and_monitor(sim):
    for n in (2, 3, 4):
        master(sim, "sdo", "write", n, "0x1017", 0, "100", "--type", "u16")
    mon = subprocess.Popen([COFORGE, "master", "--port", str(sim), "monitor", "--consumer-ms", "350", "--seconds", "4"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(0.8)
    assert "sent NMT start to all nodes" in master(sim, "nmt", "start", "all").stdout
    time.sleep(0.5)
    master(sim, "nmt", "stop", 3)
    time.sleep(0.5)
    master(sim, "nmt", "reset", 4)
    time.sleep(0.5)
    master(sim, "sdo", "write", 2, "0x1017", 0, "0", "--type", "u16")
    time.sleep(0.8)
    out, err = mon.communicate(timeout=30)
    events = [re.sub(r"^\s*[\d.]+ s  ", "", line) for line in out.splitlines()[1:]]
    for n in (2, 3, 4):
        assert f"node {n}: heartbeat started, pre-operational" in events, (out, err)
        assert f"node {n}: pre-operational -> operational" in events, out
    assert "node 3: operational -> stopped" in events, out
    # The reset node boots with 1017h back to 0: after a boot-up only a heartbeat starts
    # monitoring again, so it is not reported lost.
    boot = events.index("node 4: boot-up")
    assert events.index("node 3: operational -> stopped") < boot
    assert "node 4: heartbeat lost" not in events, out
    # Node 2's heartbeat switched off: lost after the consumer time.
    assert "node 2: heartbeat lost" in events[boot:], out


def test_sdo_types_from_an_eds(sim, tmp_path):
    eds = tmp_path / "co401memory1.eds"
    subprocess.run([COFORGE, "eds", ROOT / "spec" / "co401memory1.yaml", "-o", eds], check=True, capture_output=True)
    assert master(sim, "sdo", "read", 3, "0x1018", 1, "--eds", eds).stdout.strip() == "88 (0x00000058)"
    assert master(sim, "sdo", "read", 3, "0x1008", 0, "--eds", eds).stdout.strip() == '"CO401Memory1"'
    assert "= 250 (0x00FA)" in master(sim, "sdo", "write", 3, "0x1017", 0, "250", "--eds", eds).stdout
    assert master(sim, "sdo", "read", 3, "0x1017", 0, "--eds", eds).stdout.strip() == "250 (0x00FA)"
    missing = master(sim, "sdo", "read", 3, "0x2999", 0, "--eds", eds, check=False)
    assert missing.returncode == 1 and "has no entry 2999h sub 0" in missing.stderr
