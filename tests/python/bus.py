"""Every CAN frame on the simulator's bus, with the time it arrived: a python-can listener the
interoperability tests share."""

import threading
import time
from dataclasses import dataclass

import can


@dataclass(frozen=True)
class Frame:
    t: float
    id: int
    rtr: bool
    data: bytes

    def __str__(self):
        return f"{self.id:03X}{' RTR' if self.rtr else ''} [{self.data.hex(' ')}] @{self.t:.3f}"


class Recorder(can.Listener):
    def __init__(self):
        self.frames = []
        self.cond = threading.Condition()

    def on_message_received(self, msg):
        f = Frame(time.monotonic(), msg.arbitration_id, msg.is_remote_frame, bytes(msg.data))
        with self.cond:
            self.frames.append(f)
            self.cond.notify_all()

    def mark(self):
        with self.cond:
            return len(self.frames)

    def since(self, mark, cob=None):
        with self.cond:
            return [f for f in self.frames[mark:] if cob is None or (f.id == cob and not f.rtr)]

    def wait(self, cob, mark, timeout, pred=lambda f: True):
        """The first data frame on `cob` after `mark` that satisfies `pred`, or None."""
        deadline = time.monotonic() + timeout
        with self.cond:
            i = mark
            while True:
                while i < len(self.frames):
                    f = self.frames[i]
                    i += 1
                    if f.id == cob and not f.rtr and pred(f):
                        return f
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self.cond.wait(left)

    def wait_count(self, cob, mark, count, timeout):
        deadline = time.monotonic() + timeout
        with self.cond:
            while True:
                got = [f for f in self.frames[mark:] if f.id == cob and not f.rtr]
                left = deadline - time.monotonic()
                if len(got) >= count or left <= 0:
                    return got
                self.cond.wait(left)
