//! CiA 301 rules for writes to communication objects, beyond what the dictionary checks:
//! PDO parameters and the remapping procedure, COB-ID changes, heartbeat consumers.
//!
//! Abort codes where CiA 301 leaves the choice to the device:
//! - changing a PDO's COB-ID, inhibit time or SYNC start while it is valid, a reserved
//!   transmission type, or a reserved identifier: 0609 0030h (invalid value);
//! - writing a mapping while the PDO is valid, or a mapping entry while sub 0 is not 0:
//!   0800 0022h (not in the present device state), since the same write succeeds once the
//!   master has followed the remapping procedure;
//! - writing a mapping while the remapping object (`remapping_object`) reads 0: 0800 0021h
//!   (local control), from any side: the device, not the master, disabled remapping;
//! - two consumer entries for one producer: 0604 0043h (general parameter incompatibility);
//!   more producers than the node can monitor: 0604 0047h.

use super::le_u32;
use super::{Core, read_u32};
use crate::heartbeat::{Consumer, MAX_CONSUMED};
use crate::od::{NodeDictionary, SdoAbort, Side};
use crate::pdo::slot::mapping_words;
use crate::pdo::{COB_EXTENDED, COB_INVALID, Dir, Mapping, mapping::check_entry, restricted_cob_id};
use crate::store::ParamStore;

impl<D: NodeDictionary, S: ParamStore, const P: usize> Core<D, S, P> {
    pub(super) fn check_communication(&mut self, index: u16, sub: u8, data: &[u8], side: Side) -> Result<(), SdoAbort> {
        // Values of the wrong length are the dictionary's to refuse.
        let value = le_u32(data);
        match (index, sub) {
            (0x1003, 0) if value != 0 => Err(SdoAbort::InvalidValue),
            (0x1005, 0) if value & (1 << 30 | COB_EXTENDED) != 0 => Err(SdoAbort::InvalidValue),
            (0x1014, 0) => self.check_cob_change(0x1014, 0, value),
            (0x1016, 1..) if D::COMM.heartbeat_consumer => self.check_consumer(sub, value),
            _ => match Dir::of_index(index) {
                Some((dir, false, _)) => self.check_pdo_comm(dir, index, sub, value, side),
                Some((dir, true, _)) => self.check_pdo_mapping(dir, index, sub, value, side),
                None => Ok(()),
            },
        }
    }

    /// A valid COB-ID may only be replaced by an invalid one, or by itself.
    fn check_cob_change(&mut self, index: u16, sub: u8, new: u32) -> Result<(), SdoAbort> {
        let old = self.current(index, sub);
        if new & COB_EXTENDED != 0 {
            return Err(SdoAbort::InvalidValue);
        }
        let (old_valid, new_valid) = (old & COB_INVALID == 0, new & COB_INVALID == 0);
        if old_valid && new_valid && old & 0x7FF != new & 0x7FF {
            return Err(SdoAbort::InvalidValue);
        }
        Ok(())
    }

    /// CiA 301 PDO communication rules. The restricted identifiers only bind the bus: device
    /// code may put a PDO on one where its datasheet says so (CO401Memory1 monitors any ID).
    fn check_pdo_comm(&mut self, dir: Dir, index: u16, sub: u8, value: u32, side: Side) -> Result<(), SdoAbort> {
        let valid = self.current(index, 1) & COB_INVALID == 0;
        match sub {
            1 => {
                self.check_cob_change(index, 1, value)?;
                if value & COB_INVALID == 0 && side != Side::Device && restricted_cob_id((value & 0x7FF) as u16) {
                    return Err(SdoAbort::InvalidValue);
                }
                Ok(())
            }
            2 => match (dir, value) {
                (_, 241..=251) | (Dir::Rx, 252 | 253) => Err(SdoAbort::InvalidValue),
                _ => Ok(()),
            },
            3 | 6 if valid => Err(SdoAbort::InvalidValue),
            _ => Ok(()),
        }
    }

    /// The CiA 301 remapping procedure: invalidate the PDO, set sub 0 to 0, write the
    /// entries, set sub 0 to their number.
    fn check_pdo_mapping(&mut self, dir: Dir, index: u16, sub: u8, value: u32, side: Side) -> Result<(), SdoAbort> {
        self.check_remapping_enabled()?;
        if side == Side::Device {
            return Ok(());
        }
        let comm = index - 0x200;
        if self.current(comm, 1) & COB_INVALID == 0 {
            return Err(SdoAbort::DataTransferState);
        }
        if sub == 0 {
            let (words, n) = mapping_words(&mut self.od, index, value)?;
            Mapping::check(&self.od, words.get(..n).unwrap_or(&[]), dir)?;
            return Ok(());
        }
        if self.current(index, 0) != 0 {
            return Err(SdoAbort::DataTransferState);
        }
        if value != 0 {
            check_entry(&self.od, value, dir)?;
        }
        Ok(())
    }

    /// Whether any side may write a mapping now: not while the remapping object reads 0.
    fn check_remapping_enabled(&mut self) -> Result<(), SdoAbort> {
        match self.cfg.remapping_object {
            Some(index) if read_u32(&mut self.od, index, 0) == Some(0) => Err(SdoAbort::DataTransferLocal),
            _ => Ok(()),
        }
    }

    fn check_consumer(&mut self, sub: u8, value: u32) -> Result<(), SdoAbort> {
        let Some((node, _)) = Consumer::decode(value) else { return Ok(()) };
        let count = self.current(0x1016, 0).min(127) as u8;
        let mut active = 1;
        for s in (1..=count).filter(|&s| s != sub) {
            if let Some((other, _)) = Consumer::decode(self.current(0x1016, s)) {
                if other == node {
                    return Err(SdoAbort::IncompatibleParameter);
                }
                active += 1;
            }
        }
        if active > MAX_CONSUMED { Err(SdoAbort::IncompatibleInternal) } else { Ok(()) }
    }
}
