//! Writes with their side effects, and the SDO server's view of the node.

use super::{Core, read_u32};
use crate::od::{AppObjects, NodeDictionary, ReadLen, SdoAbort, Side, Storage, WriteSource};
use crate::pdo::Dir;
use crate::sdo::SdoTarget;
use crate::store::ParamStore;

impl<D: NodeDictionary, S: ParamStore, const P: usize> Core<D, S, P> {
    /// A write, then its indication if it took effect: the one place SDO, host and device
    /// writes are indicated (RPDOs write entries directly, see `apply_rpdo`). Inlined, so
    /// with the indication empty each caller is left with the plain `write` call.
    #[inline(always)]
    pub(super) fn write_indicated(&mut self, index: u16, sub: u8, data: &[u8], by: WriteSource) -> Result<(), SdoAbort> {
        self.write(index, sub, data, by.side())?;
        self.od.app().written(index, sub, data, by);
        Ok(())
    }

    /// A write from any side: the communication-object rules first, then the dictionary's
    /// own checks, then whatever the new value changes.
    fn write(&mut self, index: u16, sub: u8, data: &[u8], side: Side) -> Result<(), SdoAbort> {
        let ctx = self.ctx();
        let entry = self.od.entry(index, sub)?;
        if matches!(index, 0x1010 | 0x1011) && sub >= 1 {
            entry.check_write(side, &ctx, data, self.od.limits())?;
            return self.store_command(index, sub, data);
        }
        self.check_communication(index, sub, data, side)?;
        entry.check_write_access(side, &ctx)?;
        self.od.write_entry(entry, index, sub, data)?;
        self.after_write(index, sub);
        if self.cfg.auto_save && entry.storage() == Storage::Persistent && side != Side::Device {
            self.store.save(&self.od, crate::od::Area::ALL).map_err(|_| SdoAbort::Hardware)?;
        }
        Ok(())
    }

    /// 1010h "save" / 1011h "load" (CiA 301 7.5.2.13/14): the signature, then the store.
    fn store_command(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        let signature: &[u8] = if index == 0x1010 { b"save" } else { b"load" };
        if data != signature {
            return Err(SdoAbort::DataTransfer);
        }
        // Manufacturer-specific sub-indices beyond 4 act on everything.
        let area = crate::od::Area::of_store_sub(sub).unwrap_or(crate::od::Area::ALL);
        let result = if index == 0x1010 && self.restore_pending {
            // The dictionary still shows the values the restore discarded (the defaults take
            // effect at the next reset): saving them would undo the restore, so the store
            // stays erased and the node starts with defaults (CO401GW1 1010h).
            self.store.erase(&self.od)
        } else if index == 0x1010 {
            self.store.save(&self.od, area)
        } else if area == crate::od::Area::ALL {
            // Restored defaults take effect at the next reset (CiA 301).
            let erased = self.store.erase(&self.od);
            self.restore_pending = erased.is_ok();
            erased
        } else {
            // One area of a single stored block: store that area's defaults.
            self.od.reset_area(area, self.node_id);
            let saved = self.store.save(&self.od, area);
            self.reload_services(self.now_us);
            saved
        };
        result.map_err(|_| SdoAbort::Hardware)
    }

    /// Re-reads what a written communication object configures, and marks the TPDOs that map
    /// the written entry (unless the device triggers its TPDOs itself: `tpdo_on_write`).
    pub(super) fn after_write(&mut self, index: u16, sub: u8) {
        if index < 0x2000 {
            self.after_communication_write(index);
        }
        if self.cfg.tpdo_on_write {
            self.trigger_mapped(index, sub);
        }
    }

    fn after_communication_write(&mut self, index: u16) {
        let now = self.now_us;
        match index {
            0x1005 | 0x1006 => self.reload_sync(),
            0x100C..=0x100E => self.reload_guarding(),
            0x1014 | 0x1015 => self.reload_emcy(),
            0x1016 => self.reload_consumer(),
            0x1017 => self.reload_heartbeat(now),
            _ => {}
        }
        match Dir::of_index(index) {
            Some((Dir::Rx, _, offset)) => {
                if let Some(r) = self.rpdos.iter_mut().find(|r| r.offset == offset) {
                    *r = crate::pdo::Rpdo::load(&mut self.od, offset);
                }
            }
            Some((Dir::Tx, _, offset)) => {
                if let Some(i) = self.tpdos.iter().position(|t| t.offset == offset) {
                    let t = crate::pdo::Tpdo::load(&mut self.od, offset, now);
                    if let Some(slot) = self.tpdos.get_mut(i) {
                        *slot = t;
                    }
                    self.refresh_tpdo_filter();
                }
            }
            None => {}
        }
    }
}

impl<D: NodeDictionary, S: ParamStore, const P: usize> SdoTarget for Core<D, S, P> {
    const BLOCK_TRANSFER: bool = D::SDO_BLOCK_TRANSFER;

    fn read(&mut self, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        self.od.read(index, sub, offset, buf, Side::Bus)
    }

    fn check_download(&mut self, index: u16, sub: u8, size: Option<usize>) -> Result<(), SdoAbort> {
        let ctx = self.ctx();
        let entry = self.od.entry(index, sub)?;
        entry.check_write_access(Side::Bus, &ctx)?;
        match size {
            Some(n) if n > usize::from(entry.size) => Err(SdoAbort::LengthTooHigh),
            _ => Ok(()),
        }
    }

    fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.write_indicated(index, sub, data, WriteSource::Sdo)
    }

    fn fixed_size(&mut self, index: u16, sub: u8) -> Option<usize> {
        let e = self.od.entry(index, sub).ok()?;
        e.data_type().bits().map(|_| usize::from(e.size))
    }

    const STREAMING: bool = <D::App as AppObjects>::STREAMING;

    fn streams(&mut self, index: u16, sub: u8) -> bool {
        match self.od.entry(index, sub) {
            Ok(entry) if entry.storage() == Storage::App => self.od.app().streams(entry, index, sub),
            _ => false,
        }
    }

    /// Checked again for every part, as a whole write would be at its end: the NMT state may
    /// have changed since the initiation, and without an indicated size only the parts show
    /// the length. The completed download has a whole write's side effects and indication.
    fn write_part(&mut self, index: u16, sub: u8, offset: usize, data: &[u8], last: bool) -> Result<(), SdoAbort> {
        let ctx = self.ctx();
        let entry = self.od.entry(index, sub)?;
        entry.check_write_access(Side::Bus, &ctx)?;
        if offset.saturating_add(data.len()) > usize::from(entry.size) {
            return Err(SdoAbort::LengthTooHigh);
        }
        self.od.app().write_part(entry, index, sub, offset, data, last)?;
        if last {
            self.after_write(index, sub);
            self.od.app().written(index, sub, &[], WriteSource::Sdo);
        }
        Ok(())
    }

    fn abort_stream(&mut self, index: u16, sub: u8) {
        if let Ok(entry) = self.od.entry(index, sub) {
            self.od.app().abort_stream(entry, index, sub);
        }
    }
}

impl<D: NodeDictionary, S: ParamStore, const P: usize> Core<D, S, P> {
    pub(super) fn current(&mut self, index: u16, sub: u8) -> u32 {
        read_u32(&mut self.od, index, sub).unwrap_or(0)
    }
}
