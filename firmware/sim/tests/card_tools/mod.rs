//! Tools we did not write, on a card image: mtools reads its files, `fsck.fat -n` checks its
//! file system. Shared by the card tests (`cr3101_card.rs`, `cr3101_device.rs`).
#![allow(dead_code)]

use coforge_sim::card::CardImage;
use std::path::{Path, PathBuf};
use std::process::Command;

pub const MIB: u64 = 1 << 20;

/// A card image file in a scratch directory that is removed when the test ends, pass or fail
/// (16 MiB per card, dozens of cards per run: leaving them would fill the disk).
pub struct Card {
    path: PathBuf,
    _dir: tempfile::TempDir,
}

impl std::ops::Deref for Card {
    type Target = Path;

    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for Card {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

/// A new 16 MiB card image in a directory of its own, named after the test.
pub fn image(name: &str) -> Card {
    let dir = tempfile::Builder::new().prefix(&format!("coforge-card-{name}-")).tempdir().unwrap();
    let path = dir.path().join("card.img");
    CardImage::create(&path, 16 * MIB, "CANMEM").unwrap();
    Card { path, _dir: dir }
}

/// mtools on the card's first partition (it starts at 1 MiB).
pub fn mtools(tool: &str, path: &Path, args: &[&str]) -> std::process::Output {
    let out = Command::new(tool).arg("-i").arg(format!("{}@@1M", path.display())).args(args).env("MTOOLS_SKIP_CHECK", "1").output();
    let out = out.unwrap_or_else(|e| panic!("{tool}: {e} (cargo xtask test installs mtools)"));
    assert!(out.status.success(), "{tool} {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    out
}

/// The names in the card's root directory, as `mdir -b` lists them.
pub fn listing(path: &Path) -> String {
    String::from_utf8(mtools("mdir", path, &["-b", "::"]).stdout).unwrap()
}

/// A file from the card, as a PC copies it.
pub fn copy_out(path: &Path, name: &str) -> Vec<u8> {
    let to = path.with_file_name(name);
    mtools("mcopy", path, &["-n", &format!("::{name}"), to.to_str().unwrap()]);
    std::fs::read(to).unwrap()
}

/// `fsck.fat -n` on the partition (copied out: fsck.fat takes no offset): clean or not.
pub fn fsck_clean(path: &Path) -> bool {
    let bytes = std::fs::read(path).unwrap();
    let part = path.with_file_name("partition.img");
    std::fs::write(&part, &bytes[MIB as usize..]).unwrap();
    let out = Command::new("fsck.fat").arg("-n").arg(&part).output().expect("fsck.fat (cargo xtask test installs dosfstools)");
    out.status.success()
}
