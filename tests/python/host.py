"""What every suite takes from the host: the `coforge` binary and loopback TCP ports."""

import os
import pathlib
import random
import socket
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
COFORGE = os.environ.get("COFORGE_BIN", str(ROOT / "target" / "debug" / "coforge"))


def _ephemeral_start():
    try:
        return int(pathlib.Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return 32768


# Ports below the kernel's ephemeral range: a port-0 bind (a hub's, a simulator's) or the
# source port of an outgoing connection never takes one of them between `free_port` and the
# server's own bind, which is how QEMU once failed to start in CI.
_PORTS = range(20000, min(_ephemeral_start(), 32768))
_handed_out = set()


def free_port():
    """A loopback port nothing is bound to now, below the ephemeral range, and not handed out
    before in this run (a stopped server's connections may linger on its ports)."""
    for _ in range(1000):
        port = random.choice(_PORTS)
        if port in _handed_out:
            continue
        with socket.socket() as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
        _handed_out.add(port)
        return port
    raise RuntimeError(f"no free loopback port in {_PORTS}")


def listening(ports):
    """Whether every port in `ports` has a listening TCP socket on this host (/proc/net/tcp)."""
    ports = set(ports)
    with open("/proc/net/tcp") as table:
        next(table)
        for row in table:
            local, state = row.split()[1], row.split()[3]
            if state == "0A":  # TCP_LISTEN
                ports.discard(int(local.split(":")[1], 16))
    return not ports


def connect(port, timeout=10.0):
    """A connection to a loopback server that may still be starting."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            return socket.create_connection(("127.0.0.1", port), timeout=1)
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.05)
