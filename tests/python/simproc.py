"""What the device suites share: a `coforge sim` process (its stdout read by a thread, banner
lines and console answers arriving in one queue; console commands on stdin; its stderr kept for
failure messages) and the host end of a device's serial line. The suites add their CANopen
clients and their protocol's framing on top."""

import queue
import re
import socket
import subprocess
import tempfile
import threading
import time

import serial


class SimProcess:
    def __init__(self, args):
        self.stderr = tempfile.TemporaryFile()
        self.proc = subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self.stderr, text=True, bufsize=1)
        self.lines = queue.Queue()
        self.reader = threading.Thread(target=self._read_stdout, daemon=True)
        self.reader.start()

    def _read_stdout(self):
        for line in self.proc.stdout:
            self.lines.put(line.rstrip("\n"))

    def line(self, timeout):
        try:
            return self.lines.get(timeout=timeout)
        except queue.Empty:
            raise AssertionError(f"coforge sim printed nothing within {timeout} s{self.stderr_note()}") from None

    def banner(self, pattern, timeout=20.0):
        """The next stdout line, which must match `pattern`: its first group."""
        line = self.line(timeout)
        m = re.search(pattern, line)
        assert m, f"unexpected banner line {line!r} (wanted {pattern!r}){self.stderr_note()}"
        return m.group(1)

    def stderr_note(self):
        self.stderr.seek(0)
        err = self.stderr.read().decode(errors="replace")
        return f"; stderr: {err}" if err else ""

    def console(self, command, timeout=5.0):
        """Runs a console command; returns the text after 'coforge sim: ok '."""
        self.proc.stdin.write(command + "\n")
        self.proc.stdin.flush()
        line = self.line(timeout)
        assert line.startswith("coforge sim: ok "), f"console {command!r}: {line!r}"
        return line[len("coforge sim: ok ") :]

    def stop(self):
        """Kills the process; fails if it had exited by itself (a panic), with its stderr."""
        exited = self.proc.poll()
        self.proc.kill()
        self.proc.wait(timeout=10)
        self.reader.join(timeout=5)
        for f in (self.proc.stdin, self.proc.stdout):
            try:
                f.close()
            except OSError:
                pass
        note = self.stderr_note()
        self.stderr.close()
        assert exited is None, f"coforge sim exited by itself with {exited}{note}"


class SerialLine:
    """The host end of a simulated device's serial line (`--serial`): a pyserial `socket://`
    port, each write sent at once, reads bounded by a deadline. The suites add their
    protocol's framing on top."""

    def __init__(self, url):
        self.port = serial.serial_for_url(url, timeout=0.1)
        sock = getattr(self.port, "_socket", None)
        if sock is not None:
            # Each write goes out at once: pauses on the line are the ones the test makes.
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def close(self):
        self.port.close()

    def send(self, data):
        self.port.write(data)
        self.port.flush()

    def _read(self, n, deadline):
        """Up to `n` bytes, whatever arrived by `deadline` (time.monotonic())."""
        buf = b""
        while len(buf) < n:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            self.port.timeout = left
            buf += self.port.read(n - len(buf))
        return buf
