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

/// Where an image's blocks are: a file, or memory (a card that lasts as long as the
/// simulator).
#[derive(Debug)]
enum Backing {
    File(File),
    Memory(io::Cursor<Vec<u8>>),
}

impl Read for Backing {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        match self {
            Backing::File(f) => f.read(buf),
            Backing::Memory(m) => m.read(buf),
        }
    }
}

impl Write for Backing {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match self {
            Backing::File(f) => f.write(buf),
            Backing::Memory(m) => m.write(buf),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match self {
            Backing::File(f) => f.flush(),
            Backing::Memory(_) => Ok(()),
        }
    }
}

impl Seek for Backing {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        match self {
            Backing::File(f) => f.seek(to),
            Backing::Memory(m) => m.seek(to),
        }
    }
}

/// A card image.
#[derive(Debug)]
pub struct CardImage {
    file: RefCell<Backing>,
    blocks: u32,
}

impl CardImage {
    /// Opens an existing image.
    pub fn open(path: &Path) -> io::Result<CardImage> {
        let file = OpenOptions::new().read(true).write(true).open(path)?;
        let blocks = u32::try_from(file.metadata()?.len() / BLOCK).map_err(io::Error::other)?;
        Ok(CardImage { file: RefCell::new(Backing::File(file)), blocks })
    }

    /// Makes a new image of `bytes` (a power of two from 16 MiB up: QEMU's SD card needs a
    /// power of two, FAT16 enough clusters), partitioned and formatted, labelled `label`.
    pub fn create(path: &Path, bytes: u64, label: &str) -> io::Result<CardImage> {
        let mut file = OpenOptions::new().read(true).write(true).create(true).truncate(true).open(path)?;
        file.set_len(bytes)?;
        format(&mut file, bytes, label)?;
        file.sync_all()?;
        drop(file);
        CardImage::open(path)
    }

    /// A new image of `bytes` in memory, as [`CardImage::create`] makes one.
    pub fn in_memory(bytes: u64, label: &str) -> io::Result<CardImage> {
        let mut memory = io::Cursor::new(vec![0; usize::try_from(bytes).map_err(io::Error::other)?]);
        format(&mut memory, bytes, label)?;
        let blocks = u32::try_from(bytes / BLOCK).map_err(io::Error::other)?;
        Ok(CardImage { file: RefCell::new(Backing::Memory(memory)), blocks })
    }
}

/// Partitions and formats `bytes` of `disk`.
fn format(disk: &mut (impl Read + Write + Seek), bytes: u64, label: &str) -> io::Result<()> {
    if !bytes.is_power_of_two() || !(16 << 20..=2 << 30).contains(&bytes) {
        return Err(io::Error::other(format!("a card of {bytes} bytes: 16 MiB to 2 GiB, a power of two")));
    }
    let sectors = u32::try_from(bytes / BLOCK - PARTITION_START).map_err(io::Error::other)?;
    disk.seek(SeekFrom::Start(0))?;
    disk.write_all(&mbr(PARTITION_START as u32, sectors))?;
    let mut name = [b' '; 11];
    name.iter_mut().zip(label.bytes()).for_each(|(d, s)| *d = s.to_ascii_uppercase());
    let options = fatfs::FormatVolumeOptions::new().fat_type(fatfs::FatType::Fat16).volume_label(name);
    fatfs::format_volume(Partition { file: disk, start: PARTITION_START * BLOCK, len: u64::from(sectors) * BLOCK, at: 0 }, options)
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
struct Partition<'f, F> {
    file: &'f mut F,
    start: u64,
    len: u64,
    at: u64,
}

impl<F: Read + Seek> Read for Partition<'_, F> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = buf.len().min(usize::try_from(self.len.saturating_sub(self.at)).unwrap_or(usize::MAX));
        self.file.seek(SeekFrom::Start(self.start + self.at))?;
        let got = self.file.read(buf.get_mut(..n).unwrap_or_default())?;
        self.at += got as u64;
        Ok(got)
    }
}

impl<F: Write + Seek> Write for Partition<'_, F> {
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

impl<F> Seek for Partition<'_, F> {
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
