"""The QEMU launcher the end-to-end suites share (qemu.py): a port that another process bound
between `free_port` and QEMU's own bind (CI saw it once) costs a second start, not a failed
test; a QEMU that exits for another reason fails at once, with its output."""

import socket

import pytest

import qemu
from host import free_port
from test_e2e_memory1 import QEMU_IMAGE


def ports_starting_with(taken):
    handed = iter([taken])
    return lambda: next(handed, None) or free_port()


def test_a_port_taken_before_qemu_binds_it_costs_a_second_start(monkeypatch, tmp_path):
    with socket.socket() as squatter:
        squatter.bind(("127.0.0.1", 0))
        squatter.listen()
        taken = squatter.getsockname()[1]
        monkeypatch.setattr(qemu, "free_port", ports_starting_with(taken))
        proc = qemu.QemuProcess(QEMU_IMAGE, tmp_path)
        try:
            assert taken not in proc.ports, "started again on other ports"
            assert "Address already in use" not in proc.output_note(), "the first start's complaint is not kept"
            with proc.connect(proc.ports[0]):
                pass
        finally:
            proc.stop()


def test_a_qemu_that_cannot_start_fails_with_its_output(tmp_path):
    # An option QEMU rejects before it opens any port: it exits, and is not started again.
    with pytest.raises(AssertionError, match="QEMU exited with 1 at start; QEMU printed: .*no-such-option"):
        qemu.QemuProcess(QEMU_IMAGE, tmp_path, extra=["-no-such-option"])
