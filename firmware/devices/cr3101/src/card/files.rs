//! The card's files: an MBR-partitioned FAT16/FAT32 volume through `embedded-sdmmc`, with one
//! data file per configured file, named by 3x00h (8.3) and pre-allocated at its 2002h size.
//!
//! Laying out a file writes its clusters, then its directory entry with the whole size.
//! Logging then rewrites the bytes of the pre-allocated file in place: the clusters, and so the
//! FAT, never change while logging, and the files stay open, so their directory entries are
//! not rewritten either (`embedded-sdmmc` writes an entry when its file is flushed or closed).
//! A power loss while logging can only cut the sector being written. Files on the card that
//! are not the device's are left alone.

use embedded_sdmmc::{BlockDevice, Mode, RawDirectory, RawFile, TimeSource, VolumeIdx, VolumeManager};

/// Data files (3000h..3700h).
pub const FILES: usize = 8;
/// Files the device keeps open: the data files, then the configuration file.
pub const SLOTS: usize = FILES + 1;
/// The configuration file's slot ([`super::settings`]).
pub const SETTINGS_SLOT: usize = FILES;
/// Bytes written at a time to pre-allocate a file.
const FILL: usize = 512;

/// Why the card refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CardError {
    /// The card does not answer, or a block could not be read or written.
    Device,
    /// No FAT volume in the first partition, or a damaged one.
    NoVolume,
    /// The card is full: a file of that size does not fit.
    Full,
    /// 3x00h is not a valid 8.3 name.
    Name,
    /// Outside the file, or a file that is not laid out.
    Range,
}

impl<E: core::error::Error> From<embedded_sdmmc::Error<E>> for CardError {
    fn from(e: embedded_sdmmc::Error<E>) -> Self {
        use embedded_sdmmc::Error as E;
        match e {
            E::DeviceError(_) => CardError::Device,
            E::FormatError(_) | E::NoSuchVolume | E::Unsupported => CardError::NoVolume,
            E::DiskFull | E::NotEnoughSpace => CardError::Full,
            E::FilenameError(_) => CardError::Name,
            _ => CardError::Range,
        }
    }
}

/// The mounted card.
pub struct Card<D: BlockDevice, T: TimeSource> {
    volumes: VolumeManager<D, T, 1, SLOTS, 1>,
    root: RawDirectory,
    files: [Option<(RawFile, u32)>; SLOTS],
}

impl<D: BlockDevice, T: TimeSource> core::fmt::Debug for Card<D, T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Card").field("files", &self.files).finish_non_exhaustive()
    }
}

impl<D: BlockDevice, T: TimeSource> Card<D, T> {
    /// Mounts the FAT volume of the card's first partition; a card that has none is handed
    /// back with the reason.
    pub fn mount(device: D, time: T) -> Result<Self, (CardError, D)> {
        let volumes = VolumeManager::new_with_limits(device, time, 0);
        let root = volumes.open_raw_volume(VolumeIdx(0)).and_then(|volume| volumes.open_root_dir(volume));
        match root {
            Ok(root) => Ok(Card { volumes, root, files: [None; SLOTS] }),
            Err(e) => Err((e.into(), volumes.free().0)),
        }
    }

    /// The card's size in bytes.
    pub fn capacity(&self) -> Result<u64, CardError> {
        let blocks = self.volumes.device(|d| d.num_blocks()).map_err(|_| CardError::Device)?;
        Ok(u64::from(blocks.0) * 512)
    }

    /// File `n` (0-based; [`SETTINGS_SLOT`] the configuration file) named `name` (8.3, such as `OIL_TEMP.DAT`) with `size` bytes: made
    /// if the card lacks it, grown with zeros if shorter, cut to nothing and grown again if
    /// longer, and kept open. Size 0: the file is not used, and stays on the card as it is.
    /// Files are never deleted: embedded-sdmmc 0.10 leaves a deleted file's clusters
    /// allocated, and a file emptied by truncation keeps one, which `fsck.fat` reports.
    ///
    /// With `erase`, what the file keeps of its old contents is overwritten with zeros too
    /// (in place: the FAT does not change).
    pub fn lay_out(&mut self, n: usize, name: &str, size: u32, erase: bool) -> Result<(), CardError> {
        self.close(n)?;
        let slot = self.files.get(n).ok_or(CardError::Range)?;
        debug_assert!(slot.is_none());
        if size == 0 {
            return Ok(());
        }
        // A file longer than wanted is cut to nothing and grown again (embedded-sdmmc frees a
        // truncated file's clusters but its first; deleting a file would leave them all).
        let mode = match self.volumes.find_directory_entry(self.root, name).map(|e| e.size) {
            Ok(len) if len > size => Mode::ReadWriteTruncate,
            Ok(_) => Mode::ReadWriteAppend,
            Err(embedded_sdmmc::Error::NotFound) => Mode::ReadWriteCreate,
            Err(e) => return Err(e.into()),
        };
        let file = self.volumes.open_file_in_dir(self.root, name, mode)?;
        let kept = if erase { self.volumes.file_length(file)? } else { 0 };
        // Its directory entry is written now, with the whole size: the FAT and the directory
        // agree from here on, whenever the power goes.
        let laid_out = self.grow(file, size).and_then(|()| self.zero(file, kept)).and_then(|()| Ok(self.volumes.flush_file(file)?));
        if let Err(e) = laid_out {
            // What fit stays, a file a PC can delete; the device does not use it. A write
            // that ran out of clusters may have linked one more than the file's length
            // covers: it is filled, so that length and clusters agree again.
            if e == CardError::Full {
                let zeros = [0_u8; FILL];
                while self.volumes.write(file, &zeros).is_ok() {}
            }
            let _ = self.volumes.close_file(file);
            return Err(e);
        }
        if let Some(slot) = self.files.get_mut(n) {
            *slot = Some((file, size));
        }
        Ok(())
    }

    fn grow(&mut self, file: RawFile, size: u32) -> Result<(), CardError> {
        let zeros = [0_u8; FILL];
        let mut len = self.volumes.file_length(file)?;
        self.volumes.file_seek_from_end(file, 0)?;
        while len < size {
            let n = (size - len).min(FILL as u32);
            self.volumes.write(file, zeros.get(..n as usize).unwrap_or(&zeros))?;
            len += n;
        }
        Ok(())
    }

    /// Overwrites the first `len` bytes of `file` with zeros.
    fn zero(&mut self, file: RawFile, len: u32) -> Result<(), CardError> {
        let zeros = [0_u8; FILL];
        self.volumes.file_seek_from_start(file, 0)?;
        let mut at = 0;
        while at < len {
            let n = (len - at).min(FILL as u32);
            self.volumes.write(file, zeros.get(..n as usize).unwrap_or(&zeros))?;
            at += n;
        }
        Ok(())
    }

    /// Opens file `n` named `name` as it is, for reading only (a write-protected card); its
    /// size.
    pub fn open_read_only(&mut self, n: usize, name: &str) -> Result<u32, CardError> {
        self.close(n)?;
        let slot = self.files.get(n).ok_or(CardError::Range)?;
        debug_assert!(slot.is_none());
        let file = self.volumes.open_file_in_dir(self.root, name, Mode::ReadOnly)?;
        let size = self.volumes.file_length(file)?;
        if let Some(slot) = self.files.get_mut(n) {
            *slot = Some((file, size));
        }
        Ok(size)
    }

    /// Closes file `n` (its directory entry is written now).
    pub fn close(&mut self, n: usize) -> Result<(), CardError> {
        if let Some((file, _)) = self.files.get_mut(n).and_then(Option::take) {
            self.volumes.close_file(file)?;
        }
        Ok(())
    }

    /// Bytes of file `n`, if laid out.
    pub fn size(&self, n: usize) -> Option<u32> {
        self.files.get(n).copied().flatten().map(|(_, size)| size)
    }

    fn open(&self, n: usize, offset: u32, len: usize) -> Result<RawFile, CardError> {
        let (file, size) = self.files.get(n).copied().flatten().ok_or(CardError::Range)?;
        let end = offset.checked_add(u32::try_from(len).map_err(|_| CardError::Range)?).ok_or(CardError::Range)?;
        if end > size {
            return Err(CardError::Range);
        }
        self.volumes.file_seek_from_start(file, offset)?;
        Ok(file)
    }

    /// Writes `bytes` at `offset` of file `n`, inside its size: in place.
    pub fn write_at(&mut self, n: usize, offset: u32, bytes: &[u8]) -> Result<(), CardError> {
        let file = self.open(n, offset, bytes.len())?;
        self.volumes.write(file, bytes)?;
        Ok(())
    }

    /// Reads `buf.len()` bytes at `offset` of file `n`.
    pub fn read_at(&mut self, n: usize, offset: u32, buf: &mut [u8]) -> Result<(), CardError> {
        let file = self.open(n, offset, buf.len())?;
        let mut at = 0;
        while at < buf.len() {
            let got = self.volumes.read(file, buf.get_mut(at..).unwrap_or_default())?;
            if got == 0 {
                return Err(CardError::Range);
            }
            at += got;
        }
        Ok(())
    }

    /// Closes every file (their directory entries written) and gives the device back.
    pub fn unmount(mut self) -> D {
        for n in 0..SLOTS {
            let _ = self.close(n);
        }
        let _ = self.volumes.close_dir(self.root);
        self.volumes.free().0
    }
}
