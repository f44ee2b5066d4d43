"""The simulator's CAN bus for the tests: a connection that is attached before it is used, and
every frame on the bus with the time it arrived (a python-can listener the tests share)."""

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


def connect_attached(net, url, bitrate, timeout=5.0):
    """Connects `net` (its listeners and NOTIFIER_CYCLE already set) to the simulator hub at
    `url`, and returns once the hub has attached this client to the bus.

    The hub attaches a TCP client on its own accept thread, after the connection is made, and a
    frame that a node sends before that reaches no one: an emergency right after a console
    command went missing about once in 65 runs under load, and a boot-up after `enable` could
    go unseen. The hub answers an SLCAN command from the attached client's own queue, so its
    answer to a version query ("V") proves the attachment. Frames that arrive meanwhile stay
    queued for python-can."""
    bus = can.Bus(interface="slcan", channel=url, sleep_after_open=0, bitrate=bitrate)
    try:
        if bus.get_version(timeout) == (None, None):
            raise RuntimeError(f"the CAN hub at {url} did not answer a version query within {timeout} s")
    except BaseException:
        bus.shutdown()
        raise
    net.bus = bus
    net.connect()
