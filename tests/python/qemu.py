"""A firmware image in QEMU's lm3s6965evb with its UARTs as TCP servers, and a `coforge hub`
on UART1 (the image's SLCAN adapter) that python-canopen joins: what the end-to-end suites
share. UART0 is the device's serial host line; further UARTs are the suite's (a pin console)."""

import pathlib
import re
import subprocess
import tempfile

from test_e2e_memory1 import COFORGE, free_port


class QemuProcess:
    """`image` run in `workdir` (where semihosting keeps its files) with `uarts` UARTs and the
    QEMU arguments `extra` (a drive); `serial_url` is UART0, `can_url` the hub on UART1, `ports`
    every UART's TCP port; with `monitor`, the QEMU monitor listens on `monitor_port`."""

    def __init__(self, image, workdir, uarts=2, extra=(), monitor=False):
        assert pathlib.Path(image).exists(), f"no QEMU image at {image}: run `cargo xtask dist`"
        self.ports = [free_port() for _ in range(uarts)]
        self.monitor_port = free_port() if monitor else None
        self.output = tempfile.TemporaryFile()
        self.hub = None
        self.cut = False
        monitor_arg = f"tcp:127.0.0.1:{self.monitor_port},server=on,wait=off" if monitor else "none"
        self.qemu = subprocess.Popen(
            ["qemu-system-arm", "-machine", "lm3s6965evb", "-nographic", "-monitor", monitor_arg,
             "-semihosting-config", "enable=on,target=native", "-kernel", image, *extra,
             *(arg for port in self.ports for arg in ("-serial", f"tcp:127.0.0.1:{port},server=on,wait=off,nodelay=on"))],
            stdin=subprocess.DEVNULL, stdout=self.output, stderr=subprocess.STDOUT, cwd=workdir,
        )
        try:
            self.hub = subprocess.Popen([COFORGE, "hub", "--port", "0", "--connect", f"127.0.0.1:{self.ports[1]}"], stdout=subprocess.PIPE, text=True)
            hub = re.search(r"on slcan (socket://\S+)", self.hub.stdout.readline())
            assert hub, f"coforge hub banner{self.output_note()}"
            self.can_url = hub.group(1)
            self.serial_url = f"socket://127.0.0.1:{self.ports[0]}"
        except BaseException:
            self.stop()
            raise

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
        for proc in (self.hub, self.qemu):
            if proc is not None:
                proc.kill()
                proc.wait(timeout=10)
        if self.hub is not None:
            self.hub.stdout.close()
        note = self.output_note()
        self.output.close()
        assert exited is None, f"QEMU exited by itself with {exited}{note}"
