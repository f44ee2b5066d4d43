//! CR3101's memory card in the simulator: an image file of 512-byte blocks (what
//! `embedded-sdmmc` reads and writes, and what QEMU's `-drive if=sd` takes), made as a PC
//! would make a card: an MBR with one FAT16 partition from 1 MiB on, formatted by `fatfs`.

use embedded_sdmmc::{Block, BlockCount, BlockDevice, BlockIdx};
use std::cell::RefCell;
use std::fs::{File, OpenOptions};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::Path;

const BLOCK: u64 = 512;
/// The partition's first block: 1 MiB, as partitioning tools align it.
const PARTITION_START: u64 = 2048;
/// MBR partition type: FAT16 with LBA addressing.
const FAT16_LBA: u8 = 0x0E;

/// A card image file.
#[derive(Debug)]
pub struct CardImage {
    file: RefCell<File>,
    blocks: u32,
}

impl CardImage {
    /// Opens an existing image.
    pub fn open(path: &Path) -> io::Result<CardImage> {
        let file = OpenOptions::new().read(true).write(true).open(path)?;
        let blocks = u32::try_from(file.metadata()?.len() / BLOCK).map_err(io::Error::other)?;
        Ok(CardImage { file: RefCell::new(file), blocks })
    }

    /// Makes a new image of `bytes` (a power of two from 16 MiB up: QEMU's SD card needs a
    /// power of two, FAT16 enough clusters), partitioned and formatted, labelled `label`.
    pub fn create(path: &Path, bytes: u64, label: &str) -> io::Result<CardImage> {
        if !bytes.is_power_of_two() || !(16 << 20..=2 << 30).contains(&bytes) {
            return Err(io::Error::other(format!("a card of {bytes} bytes: 16 MiB to 2 GiB, a power of two")));
        }
        let mut file = OpenOptions::new().read(true).write(true).create(true).truncate(true).open(path)?;
        file.set_len(bytes)?;
        let sectors = u32::try_from(bytes / BLOCK - PARTITION_START).map_err(io::Error::other)?;
        file.seek(SeekFrom::Start(0))?;
        file.write_all(&mbr(PARTITION_START as u32, sectors))?;
        let mut name = [b' '; 11];
        name.iter_mut().zip(label.bytes()).for_each(|(d, s)| *d = s.to_ascii_uppercase());
        let options = fatfs::FormatVolumeOptions::new().fat_type(fatfs::FatType::Fat16).volume_label(name);
        fatfs::format_volume(Partition { file: &mut file, start: PARTITION_START * BLOCK, len: u64::from(sectors) * BLOCK, at: 0 }, options)?;
        file.sync_all()?;
        drop(file);
        CardImage::open(path)
    }
}

/// A master boot record with one partition.
fn mbr(start: u32, sectors: u32) -> [u8; 512] {
    let [s0, s1, s2, s3] = start.to_le_bytes();
    let [n0, n1, n2, n3] = sectors.to_le_bytes();
    // Not bootable; the CHS fields unused (FE FF FF: "use the LBA fields").
    let entry = [0x00, 0xFE, 0xFF, 0xFF, FAT16_LBA, 0xFE, 0xFF, 0xFF, s0, s1, s2, s3, n0, n1, n2, n3];
    let mut b = [0_u8; 512];
    b.iter_mut().skip(446).zip(entry).for_each(|(d, s)| *d = s);
    b.iter_mut().skip(510).zip([0x55, 0xAA]).for_each(|(d, s)| *d = s);
    b
}

/// The partition as a stream of its own, for `fatfs`.
struct Partition<'f> {
    file: &'f mut File,
    start: u64,
    len: u64,
    at: u64,
}

impl Read for Partition<'_> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = buf.len().min(usize::try_from(self.len.saturating_sub(self.at)).unwrap_or(usize::MAX));
        self.file.seek(SeekFrom::Start(self.start + self.at))?;
        let got = self.file.read(buf.get_mut(..n).unwrap_or_default())?;
        self.at += got as u64;
        Ok(got)
    }
}

impl Write for Partition<'_> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = buf.len().min(usize::try_from(self.len.saturating_sub(self.at)).unwrap_or(usize::MAX));
        self.file.seek(SeekFrom::Start(self.start + self.at))?;
        let put = self.file.write(buf.get(..n).unwrap_or_default())?;
        self.at += put as u64;
        Ok(put)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.file.flush()
    }
}

impl Seek for Partition<'_> {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        let at = match to {
            SeekFrom::Start(n) => Some(n),
            SeekFrom::End(d) => self.len.checked_add_signed(d),
            SeekFrom::Current(d) => self.at.checked_add_signed(d),
        };
        self.at = at.filter(|&a| a <= self.len).ok_or_else(|| io::Error::other("seek outside the partition"))?;
        Ok(self.at)
    }
}

impl BlockDevice for CardImage {
    type Error = io::Error;

    fn read(&self, blocks: &mut [Block], start: BlockIdx) -> io::Result<()> {
        let mut file = self.file.borrow_mut();
        file.seek(SeekFrom::Start(u64::from(start.0) * BLOCK))?;
        for block in blocks {
            file.read_exact(&mut block.contents)?;
        }
        Ok(())
    }

    fn write(&self, blocks: &[Block], start: BlockIdx) -> io::Result<()> {
        let mut file = self.file.borrow_mut();
        file.seek(SeekFrom::Start(u64::from(start.0) * BLOCK))?;
        for block in blocks {
            file.write_all(&block.contents)?;
        }
        Ok(())
    }

    fn num_blocks(&self) -> io::Result<BlockCount> {
        Ok(BlockCount(self.blocks))
    }
}
