"""A CR3101 memory card as a PC sees it, what the card suites share: `coforge card` makes an
image as a PC formats one (MBR, FAT16 from 1 MiB on), mtools copies its files out, `fsck.fat -n`
checks the partition."""

import os
import shutil
import subprocess

from host import COFORGE

MTOOLS = dict(os.environ, MTOOLS_SKIP_CHECK="1")


def new_card(tmp_path, mib=16):
    for tool in ("mdir", "mcopy", "fsck.fat"):
        assert shutil.which(tool), f"{tool} is missing: cargo xtask test installs mtools and dosfstools"
    card = tmp_path / "card.img"
    subprocess.run([COFORGE, "card", card, "--mib", str(mib), "--label", "CANMEM"], check=True, timeout=60)
    return card


def listing(card):
    return subprocess.run(["mdir", "-b", "-i", f"{card}@@1M", "::"], env=MTOOLS, capture_output=True, text=True, check=True).stdout


def copy_out(card, tmp_path, name):
    out = tmp_path / name
    subprocess.run(["mcopy", "-o", "-n", "-i", f"{card}@@1M", f"::{name}", out], env=MTOOLS, check=True)
    return out.read_bytes()


def fsck_clean(card, tmp_path):
    """Whether `fsck.fat -n` finds the partition clean (copied out: it takes no offset), and
    what it said."""
    partition = tmp_path / "partition.img"
    partition.write_bytes(card.read_bytes()[1 << 20 :])
    fsck = subprocess.run(["fsck.fat", "-n", partition], capture_output=True, text=True)
    return fsck.returncode == 0, fsck.stdout + fsck.stderr
