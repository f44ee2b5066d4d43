"""A `coforge sim` process as the device suites drive it: its stdout read by a thread (banner
lines and console answers arrive in one queue), console commands on stdin, and its stderr kept
for failure messages. The suites build their own CANopen and serial clients on top."""

import queue
import re
import subprocess
import tempfile
import threading


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
