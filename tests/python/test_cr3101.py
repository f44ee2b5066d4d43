"""CR3101 end to end, with python-canopen as the master, against two targets that run the same
device code:
- `sim`: `coforge sim cr3101`, the card an image file (`--card FILE`), the clock the host's;
- `qemu`: the Cortex-M3 image (lm3s6965evb, built by `cargo xtask dist`, path in
  COFORGE_CR3101_QEMU_IMAGE) run in the test's own directory (where it keeps its parameter
  file `cr3101.params`), the card image QEMU's SD card (`-drive if=sd`), taken out and put
  back through the QEMU monitor (`eject -f sd0`, `change sd0 FILE raw`); UART1 is its SLCAN
  adapter, which `coforge hub --connect` puts on a hub python-canopen joins. Its clock starts
  at a fixed date (the board has no RTC), so its time stamps are compared with the host's
  clock relative to the first record.

Files configured over SDO, process data logged from RPDOs in real time, the card taken out and
read with mtools record by record (time stamps included), `fsck.fat -n` clean; presets put on
the card by mtools read back over SDO and through the PDO read mode; a card pulled while
logging and no card. For the image only: the power cut (QEMU killed) while it logs, at several
points: the card stays clean and every record the device reported written reads back. A
write-protected card is not tried on the image: QEMU's SPI-mode SD card has no write-protect
switch, and QEMU refuses a read-only drive as an SD card.
"""

import datetime
import os
import pathlib
import struct
import subprocess
import threading
import time

import canopen
import pytest

from bus import Recorder, connect_attached
from card import MTOOLS, copy_out, fsck_clean, listing, new_card
from qemu import QemuProcess
from simproc import SimProcess
from host import COFORGE, ROOT

# Absolute: QEMU runs in a test's own directory, where it keeps the parameter file.
IMAGE = str(pathlib.Path(os.environ.get("COFORGE_CR3101_QEMU_IMAGE", ROOT / "target" / "dist" / "images" / "cr3101-qemu.bin")).resolve())
KINDS = ["sim", "qemu"]
NODE = 0x20
# Component 1 WORD, 2 DINT, 4 BYTE: 9 + 2 + 4 + 1 = 16-byte records.
RELEVANT, RECORD = 0b1011, 16
# Records of the power-cut test's file, and frames its sender sends at most (one each 2 ms).
FRAMES = 1000


class QemuCr3101(QemuProcess):
    """The image in QEMU, run in `workdir`, with the card image `card` in its SD slot: UART0
    unused, UART1 (SLCAN) on a `coforge hub` (`can_url`), UART2 its console, the monitor on a
    TCP port."""

    def __init__(self, workdir, card):
        self.monitor_sock = self.console_sock = None
        super().__init__(IMAGE, workdir, uarts=3, extra=["-drive", f"if=sd,format=raw,file={card}"], monitor=True)

    def _until(self, sock, done, timeout=10.0):
        """What `sock` sends until `done(text so far)`."""
        data = b""
        deadline = time.monotonic() + timeout
        while not done(data):
            assert time.monotonic() < deadline, f"no answer; got {data!r}"
            sock.settimeout(max(deadline - time.monotonic(), 0.01))
            more = sock.recv(4096)
            assert more, f"connection closed; got {data!r}{self.output_note()}"
            data += more
        return data

    def monitor(self, command):
        """Runs a QEMU monitor command; returns what it printed (its echo line removed)."""
        def prompt(d):
            return d.endswith(b"(qemu) ")

        if self.monitor_sock is None:
            self.monitor_sock = self.connect(self.monitor_port)
            self._until(self.monitor_sock, prompt)
        self.monitor_sock.sendall(command.encode() + b"\n")
        out = self._until(self.monitor_sock, lambda d: b"\r\n" in d and prompt(d))
        return out.split(b"\r\n", 1)[1][: -len(b"(qemu) ")].decode(errors="replace").strip()

    def console(self, command):
        """Runs a console command on UART2; returns the text after 'ok '."""
        if self.console_sock is None:
            self.console_sock = self.connect(self.ports[2])
        self.console_sock.sendall(command.encode() + b"\n")
        line = self._until(self.console_sock, lambda d: d.endswith(b"\n")).decode().strip()
        assert line.startswith("ok "), f"console {command!r}: {line!r}"
        return line[len("ok ") :]

    def stop(self):
        for sock in (self.monitor_sock, self.console_sock):
            if sock is not None:
                sock.close()
        super().stop()


class Logger:
    """A running CR3101 (`kind` "sim" or "qemu") with its card image, and python-canopen on its
    bus."""

    def __init__(self, workdir, card, kind="sim", store=True):
        self.kind, self.card = kind, card
        if kind == "sim":
            keep = ["--store", str(pathlib.Path(workdir) / "cr3101.params")] if store else []
            self.sim = SimProcess([COFORGE, "sim", "cr3101", "--node-id", str(NODE), "--port", "0", "--card", str(card), *keep])
        else:
            # The image keeps its parameters in its working directory whatever `store` says.
            self.sim = QemuCr3101(workdir, card)
        self.net = None
        try:
            url = self.sim.banner(rf"cr3101 node-ID {NODE} on slcan (socket://\S+)") if kind == "sim" else self.sim.can_url
            self.net = canopen.Network()
            self.rec = Recorder()
            self.net.listeners.insert(0, self.rec)
            connect_attached(self.net, url, 125000)
            self.node = canopen.RemoteNode(NODE, canopen.ObjectDictionary())
            self.node.sdo.RESPONSE_TIMEOUT = 2.0
            self.net.add_node(self.node)
            if kind == "qemu":
                self.ready()
        except BaseException:
            self.close()
            raise

    def ready(self, timeout=20.0):
        """Until the node answers an SDO read of 1000h (an image in QEMU starts slowly: it
        mounts the card before its loop runs)."""
        deadline = time.monotonic() + timeout
        self.node.sdo.RESPONSE_TIMEOUT = 0.5
        try:
            while True:
                try:
                    self.node.sdo.upload(0x1000, 0)
                    return
                except canopen.SdoCommunicationError:
                    assert time.monotonic() < deadline, f"the image does not answer SDO{self.sim.output_note()}"
        finally:
            self.node.sdo.RESPONSE_TIMEOUT = 2.0

    def pull_card(self):
        """The card taken out of the slot (the device sees it at its next poll)."""
        if self.kind == "sim":
            self.sim.console("card remove")
        else:
            out = self.sim.monitor("eject -f sd0")
            assert not out, out

    def put_back_card(self):
        if self.kind == "sim":
            self.sim.console("card insert")
        else:
            out = self.sim.monitor(f"change sd0 {self.card} raw")
            assert not out, out

    def write(self, index, sub, value, fmt=None):
        data = value if isinstance(value, bytes) else struct.pack(fmt, value)
        self.node.sdo.download(index, sub, data)

    def read(self, index, sub, fmt=None):
        data = self.node.sdo.upload(index, sub)
        return struct.unpack(fmt, data)[0] if fmt else data

    def configure(self, f, name, mode, interval, records):
        """File f (0-based): components 1 WORD, 2 DINT, 4 BYTE; `records` records long."""
        base = 0x3000 + 0x100 * f
        self.write(base, 1, name)
        self.write(base + 1, 0, RELEVANT, "<H")
        self.write(base + 0x11, 2, 4, "<H")
        self.write(base + 0x13, 2, 5, "<H")
        self.write(base + 3, 1, 0x03, "<B")
        self.write(base + 3, 3, interval, "<I")
        self.write(base + 3, 1, mode, "<B")
        for pair in (0x2002, 0x2003):
            self.write(pair, f + 1, records * RECORD, "<I")

    def close(self):
        try:
            if self.net is not None:
                self.net.disconnect()
        finally:
            self.sim.stop()


def values(n):
    return struct.pack("<HiB", n & 0xFFFF, -1000 * n, n % 251)


# The image's clock at power-on.
POWER_ON = datetime.datetime(2026, 1, 1, tzinfo=datetime.timezone.utc)


def stamp_of(record):
    ms, s, mi, h, d, mo, y = struct.unpack("<HBBBBBB", record[:8])
    return datetime.datetime(2000 + y, mo, d, h, mi, s, ms * 1000, tzinfo=datetime.timezone.utc)


def remove_card(dev):
    dev.pull_card()
    time.sleep(0.3)  # the slot is polled every 100 ms
    assert dev.read(0x2001, 1) == b"\x00"


@pytest.mark.parametrize("kind", KINDS)
def test_a_logging_session_reads_back_record_by_record_with_mtools(tmp_path, kind):
    card = new_card(tmp_path)
    dev = Logger(tmp_path, card, kind)
    try:
        dev.configure(0, b"OIL_TEMP", 0x03, 0, 200)
        dev.node.nmt.state = "OPERATIONAL"
        sent = []
        for n in range(100):
            dev.net.send_message(0x200 + NODE, values(n))
            sent.append(datetime.datetime.now(datetime.timezone.utc))
            time.sleep(0.005)
        time.sleep(0.2)
        assert dev.read(0x3005, 0, "<I") == 100, "one record per frame (window 0)"
        assert dev.read(0x5000, 9, "<i") == -99_000, "5000h shows the last record, its DINT in 4 bytes"
        assert {"on", "can"} <= set(dev.sim.console("leds").split()[2:]), "ON and CAN (operational) lit"
        remove_card(dev)
    finally:
        dev.close()
    names = listing(card)
    assert "OIL_TEMP.DAT" in names and "CANMEM.CFG" in names, names
    data = copy_out(card, tmp_path, "OIL_TEMP.DAT")
    assert len(data) == 200 * RECORD
    previous = None
    # The simulator's clock is the host's; the image's starts at 2026-01-01 00:00 at power-on
    # (no RTC): its stamps are compared with the host's clock from the first record on.
    first = stamp_of(data[:RECORD])
    if kind == "qemu":
        assert POWER_ON <= first < POWER_ON + datetime.timedelta(minutes=1), f"record 0 stamped {first}"
    for n in range(100):
        record = data[n * RECORD : (n + 1) * RECORD]
        assert record[8] == RELEVANT, f"record {n}: every component written"
        assert record[9:] == values(n), f"record {n}"
        t = stamp_of(record)
        if kind == "sim":
            assert abs((t - sent[n]).total_seconds()) < 0.25, f"record {n} stamped {t}, sent {sent[n]}"
        else:
            assert abs(((t - first) - (sent[n] - sent[0])).total_seconds()) < 0.25, f"record {n} stamped {t}, sent {sent[n] - sent[0]} after record 0"
        assert previous is None or t >= previous
        previous = t
    assert data[100 * RECORD :] == bytes(100 * RECORD), "the rest of the file still zeros"
    clean, report = fsck_clean(card, tmp_path)
    assert clean, report


@pytest.mark.parametrize("kind", KINDS)
def test_presets_put_on_the_card_by_a_pc_read_back_over_sdo_and_the_pdo_read_mode(tmp_path, kind):
    card = new_card(tmp_path)
    dev = Logger(tmp_path, card, kind)
    try:
        dev.configure(1, b"PRESETS", 0x10, 1, 4)
        remove_card(dev)
    finally:
        dev.close()
    # The PC writes a preset table of the same size over the file.
    table = b"".join(struct.pack("<HBBBBBB", 100 + n, n, 0, 12, 1, 6, 26) + bytes([RELEVANT]) + values(1000 + n) for n in range(4))
    presets = tmp_path / "PRESETS.DAT"
    presets.write_bytes(table)
    subprocess.run(["mcopy", "-o", "-i", f"{card}@@1M", presets, "::PRESETS.DAT"], env=MTOOLS, check=True)

    dev = Logger(tmp_path, card, kind)
    try:
        dev.write(0x3104, 0, 2, "<I")
        assert dev.read(0x5100, 1, "<H") == 102, "the time stamp's milliseconds"
        assert dev.read(0x5100, 8, "<H") == 1002 and dev.read(0x5100, 9, "<i") == -1_002_000 and dev.read(0x5100, 11) == bytes([1002 % 251])
        dev.write(0x20F5, 0, 1, "<B")
    finally:
        dev.close()
    # PDO read mode from the next power-on (20F5h is kept in --store, or the image's
    # parameter file in the test's directory).
    dev = Logger(tmp_path, card, kind)
    try:
        dev.node.nmt.state = "OPERATIONAL"
        time.sleep(0.1)
        mark = dev.rec.mark()
        dev.net.send_message(0x200 + NODE, bytes([1]) + struct.pack("<I", 3) + b"\x00\x00\x00")
        answer = dev.rec.wait(0x180 + NODE, mark, 2.0)
        assert answer and bytes(answer.data) == table[3 * RECORD + 9 : 4 * RECORD] + b"\x00", "record 3's 7 data bytes, then a zero"
        mark = dev.rec.mark()
        dev.net.send_message(0x200 + NODE, bytes([1]) + struct.pack("<I", 3) + b"\x01\x00\x00")
        answer = dev.rec.wait(0x180 + NODE, mark, 2.0)
        assert answer and bytes(answer.data) == bytes([0, 103, 3, 0, 12, 1, 6, 26]), "the time stamp, milliseconds MSB first"
    finally:
        dev.close()
    clean, report = fsck_clean(card, tmp_path)
    assert clean, report


@pytest.mark.parametrize("kind", KINDS)
def test_a_card_pulled_while_logging_and_put_back(tmp_path, kind):
    card = new_card(tmp_path)
    dev = Logger(tmp_path, card, kind)
    try:
        dev.configure(0, b"PULLED", 0x03, 0, 100)
        dev.node.nmt.state = "OPERATIONAL"
        for n in range(10):
            dev.net.send_message(0x200 + NODE, values(n))
            time.sleep(0.01)
        time.sleep(0.1)
        dev.pull_card()
        time.sleep(0.3)
        mark = dev.rec.mark()
        dev.net.send_message(0x200 + NODE, values(99))
        emcy = dev.rec.wait(0x80 + NODE, mark, 2.0)
        assert emcy and bytes(emcy.data[:3]) == bytes([0x01, 0x50, 0x81]), "EMCY 5001h: no memory card"
        with pytest.raises(canopen.SdoAbortedError) as refused:
            dev.read(0x3004, 0)
        assert refused.value.code == 0x0800_0020
        mark = dev.rec.mark()
        dev.put_back_card()
        reset = dev.rec.wait(0x80 + NODE, mark, 2.0)
        assert reset and bytes(reset.data) == bytes(8), "the card is back: error reset"
        for n in range(10, 20):
            dev.net.send_message(0x200 + NODE, values(n))
            time.sleep(0.01)
        time.sleep(0.2)
        assert dev.read(0x3005, 0, "<I") == 20, "logging went on where it was"
        remove_card(dev)
    finally:
        dev.close()
    data = copy_out(card, tmp_path, "PULLED.DAT")
    assert [data[n * RECORD + 9 :][: RECORD - 9] for n in range(20)] == [values(n) for n in range(20)]
    clean, report = fsck_clean(card, tmp_path)
    assert clean, report


# 600: after the pointers' delayed save to CANMEM.CFG (1 s after the first record).
@pytest.mark.parametrize("cut_after", [0, 37, 120, 600])
def test_a_power_cut_while_logging_leaves_the_card_clean_and_every_record_written(tmp_path, cut_after):
    """The image only (a power cut is QEMU killed): frames keep coming while QEMU is killed,
    just after the device said over SDO how many records it had written (3005h) once
    `cut_after` frames were sent. The card is `fsck.fat` clean, every record reported written
    reads back byte for byte, what came after them is whole records or nothing, and at the
    next power-on the device finds every record on the card."""
    card = new_card(tmp_path)
    dev = Logger(tmp_path, card, "qemu")
    stop, sent = threading.Event(), []

    def send():
        for n in range(FRAMES):
            if stop.is_set():
                return
            dev.net.send_message(0x200 + NODE, values(n))
            sent.append(n)
            time.sleep(0.002)

    sender = threading.Thread(target=send, daemon=True)
    try:
        dev.configure(0, b"CUT", 0x03, 0, FRAMES)
        dev.node.nmt.state = "OPERATIONAL"
        time.sleep(0.1)
        sender.start()
        deadline = time.monotonic() + 10
        while len(sent) < cut_after:
            assert time.monotonic() < deadline, "the frames do not go out"
            time.sleep(0.001)
        written = dev.read(0x3005, 0, "<I")
        dev.sim.power_cut()
        stop.set()
        sender.join(timeout=5)
    finally:
        stop.set()
        dev.close()
    assert written <= len(sent)
    clean, report = fsck_clean(card, tmp_path)
    assert clean, report
    data = copy_out(card, tmp_path, "CUT.DAT")
    assert len(data) == FRAMES * RECORD, "the file keeps its pre-allocated size"
    records = [data[n * RECORD : (n + 1) * RECORD] for n in range(FRAMES)]
    for n in range(written):
        assert records[n][8] == RELEVANT and records[n][9:] == values(n), f"record {n}, reported written, reads back"
    stamps = [stamp_of(r) for r in records[:written]]
    assert stamps == sorted(stamps), "time stamps in order"
    # What came after the SDO answer: whole records, then nothing (a block is written whole).
    intact = written
    while intact < FRAMES and records[intact][8] == RELEVANT and records[intact][9:] == values(intact):
        intact += 1
    assert all(r == bytes(RECORD) for r in records[intact:]), f"records {intact}.. are empty"
    print(f"power cut after {len(sent)} frames: {written} records reported written, {intact} on the card")

    # Power again: logging goes on after the last record on the card (CR-48).
    dev = Logger(tmp_path, card, "qemu")
    try:
        assert dev.read(0x3005, 0, "<I") == intact, "the records on the card are found again"
    finally:
        dev.close()
    clean, report = fsck_clean(card, tmp_path)
    assert clean, report


def emcy_codes(dev, mark):
    """(code, byte 3) of every emergency since `mark`."""
    return [(struct.unpack_from("<H", bytes(f.data))[0], f.data[3]) for f in dev.rec.since(mark, 0x80 + NODE)]


@pytest.mark.parametrize("kind", KINDS)
def test_cyclic_ring_and_direct_writing_files(tmp_path, kind):
    """Cyclic writing into a ring of 4 records every 50 ms (the wrap an emergency event), direct
    writing at 3x04h, and a linear autoincrement file whose end switches it to direct reading."""
    card = new_card(tmp_path)
    dev = Logger(tmp_path, card, kind)
    try:
        dev.configure(0, b"CYCLE", 0x02, 5, 4)
        dev.write(0x3003, 2, 0x55, "<B")  # ring
        dev.configure(1, b"DIRECT", 0x01, 1, 8)
        dev.configure(2, b"LINEAR", 0x03, 0, 3)
        dev.write(0x5000, 8, 4711, "<H")
        mark = dev.rec.mark()
        dev.node.nmt.state = "OPERATIONAL"
        time.sleep(0.6)  # some 12 cycles: three times round the ring
        dev.node.nmt.state = "PRE-OPERATIONAL"
        assert dev.read(0x3006, 0, "<I") == 4, "a ring holds 4 records"
        wraps = [c for c in emcy_codes(dev, mark) if c == (0x6200, 1)]
        assert len(wraps) >= 2, f"6200h with file 1 at each wrap: {emcy_codes(dev, mark)}"
        # Direct writing: record 5, each write stamped.
        dev.write(0x3104, 0, 5, "<I")
        dev.write(0x5100, 8, 0xBEEF, "<H")
        dev.write(0x5100, 9, -5, "<i")
        with pytest.raises(canopen.SdoAbortedError) as refused:
            dev.write(0x5100, 9, 7, "<H")
        assert refused.value.code == 0x0607_0010, "a DINT takes 4 bytes"
        # Linear autoincrement: 3 records, then the file is full and reads directly.
        dev.node.nmt.state = "OPERATIONAL"
        mark = dev.rec.mark()
        for n in range(5):
            dev.net.send_message(0x400 + NODE, values(n))
            time.sleep(0.02)
        time.sleep(0.2)
        assert (0x6200, 3) in emcy_codes(dev, mark), "file 3 reached its end"
        assert dev.read(0x3203, 1, "<B") == 0x10, "switched to direct reading"
        assert dev.read(0x3205, 0, "<I") == 3
        remove_card(dev)
    finally:
        dev.close()
    cycle = copy_out(card, tmp_path, "CYCLE.DAT")
    records = [cycle[i * RECORD : (i + 1) * RECORD] for i in range(4)]
    assert all(r[9:11] == struct.pack("<H", 4711) for r in records), "every cycle records the last value"
    direct = copy_out(card, tmp_path, "DIRECT.DAT")
    assert direct[5 * RECORD + 8] == 0b11 and direct[5 * RECORD + 9 : 5 * RECORD + 15] == struct.pack("<Hi", 0xBEEF, -5)
    assert direct[: 5 * RECORD] == bytes(5 * RECORD), "only record 5 written"
    linear = copy_out(card, tmp_path, "LINEAR.DAT")
    assert [linear[i * RECORD + 9 : (i + 1) * RECORD] for i in range(3)] == [values(n) for n in range(3)], "frames after the end refused"
    clean, report = fsck_clean(card, tmp_path)
    assert clean, report


def test_pairs_no_card_and_a_full_card(tmp_path):
    """The node-ID pair takes effect at the next power-on only when both halves agree; without a
    card, card data is refused with 0800 0020h and EMCY 5001h; an allocation the card cannot
    hold is refused and leaves the card clean."""
    card = new_card(tmp_path)
    dev = Logger(tmp_path, card)
    try:
        dev.write(0x20F0, 0, 0x25, "<B")
        # 16 MiB card: two halves of 20 MiB agree, and the card refuses.
        dev.write(0x2002, 1, 20 << 20, "<I")
        with pytest.raises(canopen.SdoAbortedError) as full:
            dev.write(0x2003, 1, 20 << 20, "<I")
        assert full.value.code == 0x0800_0020
        mark = dev.rec.mark()
        remove_card(dev)
        with pytest.raises(canopen.SdoAbortedError) as none:
            dev.read(0x3000, 1)
        assert none.value.code == 0x0800_0020
        assert dev.rec.wait(0x80 + NODE, mark, 2.0, lambda f: bytes(f.data[:2]) == b"\x01\x50"), "EMCY 5001h"
        assert dev.read(0x1002, 0, "<I") & 1 == 0
    finally:
        dev.close()
    clean, report = fsck_clean(card, tmp_path)
    assert clean, report
    # Only 20F0h was written: the next power-on keeps node-ID 20h (CR-47). Then both halves.
    dev = Logger(tmp_path, card)
    try:
        assert dev.read(0x100B, 0, "<I") == NODE
        dev.write(0x20F1, 0, 0x25, "<B")
    finally:
        dev.close()
    dev = Logger(tmp_path, card)
    try:
        moved = canopen.RemoteNode(0x25, canopen.ObjectDictionary())
        moved.sdo.RESPONSE_TIMEOUT = 2.0
        dev.net.add_node(moved)
        assert struct.unpack("<I", moved.sdo.upload(0x100B, 0))[0] == 0x25, "both halves agree: node-ID 25h"
    finally:
        dev.close()
