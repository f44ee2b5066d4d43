"""CR3101 end to end in the simulator, with python-canopen as the master and the card an image
file (`coforge sim cr3101 --card FILE`): files configured over SDO, process data logged from
RPDOs in real time, the card taken out and read with mtools record by record (time stamps
included, against the host's clock), `fsck.fat -n` clean; presets put on the card by mtools
read back over SDO and through the PDO read mode; a card pulled while logging and no card.
"""

import datetime
import os
import pathlib
import shutil
import struct
import subprocess
import time

import canopen
import pytest

from bus import Recorder
from simproc import SimProcess

ROOT = pathlib.Path(__file__).resolve().parents[2]
COFORGE = os.environ.get("COFORGE_BIN", str(ROOT / "target" / "debug" / "coforge"))
MTOOLS = dict(os.environ, MTOOLS_SKIP_CHECK="1")
NODE = 0x20
# Component 1 WORD, 2 DINT, 4 BYTE: 9 + 2 + 4 + 1 = 16-byte records.
RELEVANT, RECORD = 0b1011, 16


class Logger:
    """A running CR3101 with its card image, and python-canopen on its bus."""

    def __init__(self, workdir, card, store=True):
        keep = ["--store", str(pathlib.Path(workdir) / "cr3101.params")] if store else []
        self.sim = SimProcess([COFORGE, "sim", "cr3101", "--node-id", str(NODE), "--port", "0", "--card", str(card), *keep])
        self.net = None
        try:
            url = self.sim.banner(rf"cr3101 node-ID {NODE} on slcan (socket://\S+)")
            self.net = canopen.Network()
            self.rec = Recorder()
            self.net.listeners.insert(0, self.rec)
            self.net.connect(interface="slcan", channel=url, sleep_after_open=0, bitrate=125000)
            self.node = canopen.RemoteNode(NODE, canopen.ObjectDictionary())
            self.node.sdo.RESPONSE_TIMEOUT = 2.0
            self.net.add_node(self.node)
        except BaseException:
            self.close()
            raise

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


def new_card(tmp_path):
    for tool in ("mdir", "mcopy", "fsck.fat"):
        assert shutil.which(tool), f"{tool} is missing: cargo xtask test installs mtools and dosfstools"
    card = tmp_path / "card.img"
    subprocess.run([COFORGE, "card", card, "--mib", "16", "--label", "CANMEM"], check=True, timeout=60)
    return card


def copy_out(card, tmp_path, name):
    out = tmp_path / name
    subprocess.run(["mcopy", "-o", "-n", "-i", f"{card}@@1M", f"::{name}", out], env=MTOOLS, check=True)
    return out.read_bytes()


def fsck_clean(card, tmp_path):
    partition = tmp_path / "partition.img"
    partition.write_bytes(card.read_bytes()[1 << 20 :])
    fsck = subprocess.run(["fsck.fat", "-n", partition], capture_output=True, text=True)
    return fsck.returncode == 0, fsck.stdout + fsck.stderr


def stamp_of(record):
    ms, s, mi, h, d, mo, y = struct.unpack("<HBBBBBB", record[:8])
    return datetime.datetime(2000 + y, mo, d, h, mi, s, ms * 1000, tzinfo=datetime.timezone.utc)


def remove_card(dev):
    dev.sim.console("card remove")
    time.sleep(0.3)  # the slot is polled every 100 ms
    assert dev.read(0x2001, 1) == b"\x00"


def test_a_logging_session_reads_back_record_by_record_with_mtools(tmp_path):
    card = new_card(tmp_path)
    dev = Logger(tmp_path, card)
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
        remove_card(dev)
    finally:
        dev.close()
    listing = subprocess.run(["mdir", "-b", "-i", f"{card}@@1M", "::"], env=MTOOLS, capture_output=True, text=True, check=True).stdout
    assert "OIL_TEMP.DAT" in listing and "CANMEM.CFG" in listing, listing
    data = copy_out(card, tmp_path, "OIL_TEMP.DAT")
    assert len(data) == 200 * RECORD
    previous = None
    for n in range(100):
        record = data[n * RECORD : (n + 1) * RECORD]
        assert record[8] == RELEVANT, f"record {n}: every component written"
        assert record[9:] == values(n), f"record {n}"
        t = stamp_of(record)
        assert abs((t - sent[n]).total_seconds()) < 0.25, f"record {n} stamped {t}, sent {sent[n]}"
        assert previous is None or t >= previous
        previous = t
    assert data[100 * RECORD :] == bytes(100 * RECORD), "the rest of the file still zeros"
    clean, report = fsck_clean(card, tmp_path)
    assert clean, report


def test_presets_put_on_the_card_by_a_pc_read_back_over_sdo_and_the_pdo_read_mode(tmp_path):
    card = new_card(tmp_path)
    dev = Logger(tmp_path, card)
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

    dev = Logger(tmp_path, card)
    try:
        dev.write(0x3104, 0, 2, "<I")
        assert dev.read(0x5100, 1, "<H") == 102, "the time stamp's milliseconds"
        assert dev.read(0x5100, 8, "<H") == 1002 and dev.read(0x5100, 9, "<i") == -1_002_000 and dev.read(0x5100, 11) == bytes([1002 % 251])
        dev.write(0x20F5, 0, 1, "<B")
    finally:
        dev.close()
    # PDO read mode from the next power-on (20F5h is kept in --store).
    dev = Logger(tmp_path, card)
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


def test_a_card_pulled_while_logging_and_put_back(tmp_path):
    card = new_card(tmp_path)
    dev = Logger(tmp_path, card)
    try:
        dev.configure(0, b"PULLED", 0x03, 0, 100)
        dev.node.nmt.state = "OPERATIONAL"
        for n in range(10):
            dev.net.send_message(0x200 + NODE, values(n))
            time.sleep(0.01)
        time.sleep(0.1)
        dev.sim.console("card remove")
        time.sleep(0.3)
        mark = dev.rec.mark()
        dev.net.send_message(0x200 + NODE, values(99))
        emcy = dev.rec.wait(0x80 + NODE, mark, 2.0)
        assert emcy and bytes(emcy.data[:3]) == bytes([0x01, 0x50, 0x81]), "EMCY 5001h: no memory card"
        with pytest.raises(canopen.SdoAbortedError) as refused:
            dev.read(0x3004, 0)
        assert refused.value.code == 0x0800_0020
        mark = dev.rec.mark()
        dev.sim.console("card insert")
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
