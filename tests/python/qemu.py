"""A firmware image in QEMU's lm3s6965evb with its UARTs as TCP servers, and a `coforge hub`
on UART1 (the image's SLCAN adapter) that python-canopen joins: what the end-to-end suites
share. UART0 is the device's serial host line; further UARTs are the suite's (a pin console)."""

import pathlib
import re
import subprocess
import tempfile
import time

from host import COFORGE, connect, free_port, listening

# QEMU exits at once if another process bound one of its ports first: it is started again on
# new ports, at most this many times in all.
LAUNCHES = 3


class QemuProcess:
    """`image` run in `workdir` (where semihosting keeps its files) with `uarts` UARTs and the
    QEMU arguments `extra` (a drive); `serial_url` is UART0, `can_url` the hub on UART1, `ports`
    every UART's TCP port; with `monitor`, the QEMU monitor listens on `monitor_port`."""

    def __init__(self, image, workdir, uarts=2, extra=(), monitor=False):
        assert pathlib.Path(image).exists(), f"no QEMU image at {image}: run `cargo xtask dist`"
        self.output = tempfile.TemporaryFile()
        self.hub = None
        self.cut = False
        try:
            self._launch(image, workdir, uarts, extra, monitor)
            self.hub = subprocess.Popen([COFORGE, "hub", "--port", "0", "--connect", f"127.0.0.1:{self.ports[1]}"], stdout=subprocess.PIPE, text=True)
            hub = re.search(r"on slcan (socket://\S+)", self.hub.stdout.readline())
            assert hub, f"coforge hub banner{self.output_note()}"
            self.can_url = hub.group(1)
            self.serial_url = f"socket://127.0.0.1:{self.ports[0]}"
        except BaseException:
            self._end()
            raise

    def _launch(self, image, workdir, uarts, extra, monitor):
        self.qemu = None
        for launch in range(1, LAUNCHES + 1):
            self.ports = [free_port() for _ in range(uarts)]
            self.monitor_port = free_port() if monitor else None
            monitor_arg = f"tcp:127.0.0.1:{self.monitor_port},server=on,wait=off" if monitor else "none"
            self.qemu = subprocess.Popen(
                ["qemu-system-arm", "-machine", "lm3s6965evb", "-nographic", "-monitor", monitor_arg,
                 "-semihosting-config", "enable=on,target=native", "-kernel", image, *extra,
                 *(arg for port in self.ports for arg in ("-serial", f"tcp:127.0.0.1:{port},server=on,wait=off,nodelay=on"))],
                stdin=subprocess.DEVNULL, stdout=self.output, stderr=subprocess.STDOUT, cwd=workdir,
            )
            if self._listens_or_exits():
                return
            note = self.output_note()
            assert "Address already in use" in note and launch < LAUNCHES, f"QEMU exited with {self.qemu.returncode} at start{note}"
            self.output.seek(0)
            self.output.truncate()

    def _listens_or_exits(self, timeout=20.0):
        """True once QEMU listens on all its ports, False if it exits first."""
        ports = [*self.ports, *([self.monitor_port] if self.monitor_port else [])]
        deadline = time.monotonic() + timeout
        while not listening(ports):
            if self.qemu.poll() is not None:
                return False
            assert time.monotonic() < deadline, f"QEMU did not listen on {ports} within {timeout} s{self.output_note()}"
            time.sleep(0.02)
        return True

    def connect(self, port):
        """A connection to one of QEMU's ports (it listens on all of them by now)."""
        try:
            return connect(port, timeout=5.0)
        except OSError as e:
            raise AssertionError(f"QEMU does not accept on port {port}: {e}{self.output_note()}") from e

    def output_note(self):
        self.output.seek(0)
        text = self.output.read().decode(errors="replace")
        return f"; QEMU printed: {text}" if text else ""

    def power_cut(self):
        """QEMU killed: nothing is closed or flushed."""
        self.cut = True
        self.qemu.kill()
        self.qemu.wait(timeout=10)

    def stop(self):
        """Stops QEMU and the hub; fails if QEMU had exited by itself (a panic), with its output."""
        exited = None if self.cut else self.qemu.poll()
        note = self._end()
        assert exited is None, f"QEMU exited by itself with {exited}{note}"

    def _end(self):
        """Kills the hub and QEMU; returns QEMU's output note."""
        for proc in (self.hub, self.qemu):
            if proc is not None:
                proc.kill()
                proc.wait(timeout=10)
        if self.hub is not None:
            self.hub.stdout.close()
        note = self.output_note()
        self.output.close()
        return note
