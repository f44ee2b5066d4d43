//! One mount, two outcomes: what an uncut start-up recovery leaves and what the same recovery
//! cut at a chosen byte write leaves.
//!
//! A [`TwinEeprom`] holds two images of one device. Every write lands in full in the uncut
//! image, and through a [`CutEeprom`] in the cut one, which stops at the cut armed on the shared
//! [`Power`]. Reads come from the uncut image, so the mount runs exactly as an uncut mount. Up
//! to the cut both images are equal, so until then it also runs exactly as the cut mount, and
//! nothing a cut mount would do after the cut reaches its EEPROM: the cut image is what that
//! mount leaves. The recovery-cut property then needs two mounts of symbolic banks (this one
//! and the reboot), not three. The native tests check both images against real mounts.

use super::{CutEeprom, EepromError, KANI_MAX_WRITE, Power};
use embedded_storage::{ReadStorage, Storage};

/// A device seen by an uncut and a cut run of the same operations at once.
#[derive(Clone)]
pub struct TwinEeprom<'p, const N: usize> {
    uncut: [u8; N],
    cut: CutEeprom<'p, N>,
}

impl<'p, const N: usize> TwinEeprom<'p, N> {
    /// Both images start as `device` holds it, on the same supply.
    pub fn new(device: &CutEeprom<'p, N>) -> Self {
        let mut cut = CutEeprom::new(device.power(), *device.as_bytes());
        cut.set_unreadable(device.unreadable);
        TwinEeprom { uncut: *device.as_bytes(), cut }
    }

    pub fn power(&self) -> &'p Power {
        self.cut.power()
    }

    /// What the device holds after the uncut run.
    pub fn uncut(&self) -> &[u8; N] {
        &self.uncut
    }

    /// What the device holds after the cut run.
    pub fn cut(&self) -> &[u8; N] {
        self.cut.as_bytes()
    }
}

impl<const N: usize> ReadStorage for TwinEeprom<'_, N> {
    type Error = EepromError;

    /// From the uncut image: the run goes on as if the power had stayed on.
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), EepromError> {
        if self.cut.unreadable {
            return Err(EepromError::NoAnswer);
        }
        let src = self.uncut.get(CutEeprom::<N>::range(offset, bytes.len())?).ok_or(EepromError::OutOfBounds)?;
        bytes.copy_from_slice(src);
        Ok(())
    }

    fn capacity(&self) -> usize {
        N
    }
}

impl<const N: usize> Storage for TwinEeprom<'_, N> {
    /// In full to the uncut image; byte by byte to the cut one, which keeps what it held once
    /// the cut has fired. Succeeds whenever an uncut write would.
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), EepromError> {
        if self.cut.unreadable {
            return Err(EepromError::NoAnswer);
        }
        let start = CutEeprom::<N>::range(offset, bytes.len())?.start;
        // A failure here is the cut: from then on the cut image keeps what it holds. (Under
        // Kani it also asserts the write's length is at most `KANI_MAX_WRITE`.)
        let _ = self.cut.write(offset, bytes);
        // Byte by byte with a constant bound under Kani, as `CutEeprom::write`: a slice copy
        // of symbolic place and length into the image made kissat's formula too large for
        // this machine (8.7 GB beside CBMC's 13.6 GB, against 3 GB without the twins).
        let most = if cfg!(kani) { KANI_MAX_WRITE } else { usize::MAX };
        for (k, &new) in bytes.iter().enumerate().take(most) {
            let cell = self.uncut.get_mut(start + k).ok_or(EepromError::OutOfBounds)?;
            *cell = new;
        }
        Ok(())
    }
}
