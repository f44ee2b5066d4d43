"""CR3101's card layer on QEMU's emulated SD card (lm3s6965evb, SSI0, card select on GPIO D0):
`coforge card` makes a card image as a PC formats one, the `cr3101-card` image (path in
COFORGE_CARD_QEMU_IMAGE) mounts it through embedded-sdmmc, lays out two data files and writes
200 records, and then tools we did not write read it: mtools byte for byte, `fsck.fat -n`
clean. The record layout is the README's (time stamp, modification status, components). The
power is also cut (QEMU killed) while it logs, at several points: the card stays clean and every
record written before the cut reads back.
"""

import os
import pathlib
import struct
import subprocess

import pytest

from card import copy_out, fsck_clean, listing, new_card
from host import ROOT

IMAGE = os.environ.get("COFORGE_CARD_QEMU_IMAGE", str(ROOT / "firmware/boards/qemu/target/thumbv7m-none-eabi/release/cr3101-card"))


def record(n):
    """Record n as the image writes it: component 1 WORD, 2 DINT, 4 BYTE (bitmap 0Bh)."""
    stamp = struct.pack("<HBBBBBB", n % 1000, n % 60, 30, 6, 3, 12, 26)
    return stamp + bytes([0b1011]) + struct.pack("<Hi", n & 0xFFFF, -n * 1000) + bytes([n % 251])


def new_card_for_the_image(tmp_path):
    assert pathlib.Path(IMAGE).exists(), f"no card image at {IMAGE}: cargo xtask test builds it"
    return new_card(tmp_path)


def qemu(card):
    return ["qemu-system-arm", "-machine", "lm3s6965evb", "-nographic", "-monitor", "none",
            "-semihosting-config", "enable=on,target=native", "-kernel", IMAGE,
            "-drive", f"if=sd,format=raw,file={card}"]


def test_records_on_the_emulated_sd_card_read_back_with_mtools_and_fsck_clean(tmp_path):
    card = new_card_for_the_image(tmp_path)
    run = subprocess.run(qemu(card), stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, f"the image failed: {run.stdout}{run.stderr}"
    assert "200 records written" in run.stdout

    names = listing(card)
    assert "OIL_TEMP.DAT" in names and "PRESS.DAT" in names, names
    assert copy_out(card, tmp_path, "OIL_TEMP.DAT") == b"".join(record(n) for n in range(200))
    clean, report = fsck_clean(card, tmp_path)
    assert clean, report


@pytest.mark.parametrize("cut_after", [0, 57, 150])
def test_a_power_cut_while_logging_leaves_the_card_clean_and_every_record_before_it(tmp_path, cut_after):
    card = new_card_for_the_image(tmp_path)
    proc = subprocess.Popen(qemu(card), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        for line in proc.stdout:
            if line.strip() == f"record {cut_after}":
                break
        else:
            pytest.fail(f"the image ended before record {cut_after}")
        proc.kill()  # the power goes: nothing is closed or flushed
    finally:
        proc.kill()
        proc.wait(timeout=10)
        proc.stdout.close()
    clean, report = fsck_clean(card, tmp_path)
    assert clean, report
    logged = copy_out(card, tmp_path, "OIL_TEMP.DAT")
    done = b"".join(record(n) for n in range(cut_after + 1))
    assert logged[: len(done)] == done, "every record written before the cut"
    assert len(logged) == 200 * len(record(0)), "the file keeps its pre-allocated size"
