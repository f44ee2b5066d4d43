//! The two mirrored banks over any two `embedded-storage` devices.

use core::ops::Range;

use crate::record::{RECORD, Record, block_crc, offset};
use crate::resolve::{CopyState, Verdict, resolve};
use crate::status::BankStatus;
use embedded_storage::Storage;

/// Why a read or write of the banks failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Error {
    /// The address range is outside the data area.
    OutOfRange,
    /// Neither bank holds a valid copy of this block.
    Lost { block: usize },
    /// A bank did not answer. Reads fall back to the other bank; writes are refused, because
    /// a write with a single bank could tear the only copy.
    Access,
}

/// One copy of a block as read from a bank.
#[derive(Debug, Clone, Copy)]
struct Copy<const BLOCK: usize> {
    data: [u8; BLOCK],
    record: Record,
    state: CopyState,
}

impl<const BLOCK: usize> Copy<BLOCK> {
    /// What a bank holds after committing `data` as `seq`.
    fn committed(data: [u8; BLOCK], seq: u8) -> Self {
        Copy { data, record: Record::committed(&data, seq), state: CopyState::Valid(seq) }
    }

    /// What a format cut short leaves of a copy: zeros and their CRC with sequence 0, not yet
    /// committed by both markers.
    fn is_format_staged(&self) -> bool {
        self.data.iter().all(|&b| b == 0) && self.record.crc == block_crc(&self.data, 0) && (self.record.begin, self.record.end) != (0, 0)
    }

    /// Both copies of a lost block are as a format cut short leaves them. Staging opens every
    /// copy (`begin != end`) and the commit phase finishes bank 1 before it touches bank 2, so
    /// a cut leaves at least one copy open. A corrupted byte in each copy of a committed block
    /// leaves both markers equal: zeros committed as sequence 89h, say, whose CRC differs from
    /// that of sequence 0 in one byte, become two staged-looking copies, and that block is
    /// lost, not a format to finish.
    fn left_by_a_format_cut(copies: &[Self; 2]) -> bool {
        copies.iter().all(Self::is_format_staged) && copies.iter().any(|c| c.record.begin != c.record.end)
    }
}

/// A block's contents once both banks agree on them.
#[derive(Debug, Clone, Copy)]
struct Settled<const BLOCK: usize> {
    data: [u8; BLOCK],
    seq: u8,
    /// Both banks now hold this copy committed (a repair, if one was needed, completed).
    mirrored: bool,
}

/// `BLOCKS` blocks of `BLOCK` bytes, mirrored in two banks (index 0 = bank 1, written first).
#[derive(Debug)]
pub struct MirroredBanks<S, const BLOCKS: usize, const BLOCK: usize> {
    banks: [S; 2],
    status: [BankStatus; 2],
    /// The sum of each block's data bytes in each bank as last read or written: 5C00h
    /// without rereading the EEPROM, and corrected whenever a load finds other bytes.
    block_sums: [[u16; BLOCKS]; 2],
    lost: [bool; BLOCKS],
    scrub_at: usize,
}

impl<S: Storage, const BLOCKS: usize, const BLOCK: usize> MirroredBanks<S, BLOCKS, BLOCK> {
    /// Bytes of one block's slot in a bank: data, then the commit record.
    pub const SLOT: usize = BLOCK + RECORD;
    /// Bytes each bank's EEPROM must provide.
    pub const BANK_SIZE: usize = crate::bank_size(BLOCKS, BLOCK);
    /// The user-visible data bytes.
    pub const DATA_SIZE: usize = BLOCKS * BLOCK;
    /// Per-block sums are 16-bit: a block may hold at most 257 bytes of 0xFF.
    const SUM_FITS: () = assert!(BLOCK * 255 <= u16::MAX as usize, "blocks above 257 bytes need wider block sums");

    /// Start-up: checks every block in both banks, repairs what a power cut or corruption
    /// left behind, and formats the banks if they are blank: no valid copy anywhere (blank
    /// EEPROMs, or a format cut in its first phase), or every block either holds what a
    /// format writes or is lost with only staged copies (a format cut in its second phase;
    /// see `format`). Never fails: what cannot be repaired shows in the status and
    /// lost blocks.
    pub fn mount(banks: [S; 2]) -> Self {
        let () = Self::SUM_FITS;
        let mut me = MirroredBanks { banks, status: [BankStatus::default(); 2], block_sums: [[0; BLOCKS]; 2], lost: [false; BLOCKS], scrub_at: 0 };
        let mut blank = true;
        let mut format_cut = true;
        for block in 0..BLOCKS {
            let copies = [me.load(0, block), me.load(1, block)];
            blank &= copies.iter().all(|c| c.state == CopyState::Invalid);
            // Decided on the settled contents, not on the losing copy: a repair cut short
            // must not change the decision at the next mount.
            format_cut &= match me.settle(block, &copies) {
                Ok(settled) => settled.seq == 0 && settled.data.iter().all(|&b| b == 0),
                Err(_) => Copy::left_by_a_format_cut(&copies),
            };
        }
        if (blank || format_cut) && me.lost.iter().any(|&l| l) {
            me.format();
        }
        me
    }

    /// Banks in any state a running device can hold, without a mount: any devices, status,
    /// per-block sums, lost flags and scrub position. For proofs that go one operation at a
    /// time from any state (`coforge-verification`); a device always starts with [`Self::mount`].
    #[cfg(feature = "proof-states")]
    pub fn in_state(banks: [S; 2], status: [BankStatus; 2], block_sums: [[u16; BLOCKS]; 2], lost: [bool; BLOCKS], scrub_at: usize) -> Self {
        MirroredBanks { banks, status, block_sums, lost, scrub_at }
    }

    /// Each block's sum in each bank, as [`Self::in_state`] takes them: for proofs that a state
    /// is one `in_state` builds.
    #[cfg(feature = "proof-states")]
    pub fn block_sums(&self) -> [[u16; BLOCKS]; 2] {
        self.block_sums
    }

    /// Writes zeros, committed as sequence 0, to both banks of every lost block (in blank
    /// banks the others are formatted already, or were just repaired from a formatted copy).
    /// Two phases, so that a power cut leaves banks the next mount formats again: first every
    /// copy is staged (zeros and their CRC behind the invalidating mark), then every copy is
    /// committed. A cut in the first phase leaves no valid copy anywhere; one in the second
    /// leaves formatted blocks and lost ones with staged copies, all of them zeros.
    fn format(&mut self) {
        self.status = [BankStatus(BankStatus::CLEARED); 2];
        let mut markers = [[None; 2]; BLOCKS];
        for (block, markers) in markers.iter_mut().enumerate() {
            if !self.is_lost(block) {
                continue;
            }
            for (bank, staged) in markers.iter_mut().enumerate() {
                let current = self.load(bank, block);
                let result = self.stage(bank, block, &current, &[0; BLOCK], 0);
                self.count_written(bank, block, &[0; BLOCK], result.is_ok());
                *staged = result.ok();
            }
        }
        for (block, markers) in markers.iter().enumerate() {
            for (bank, staged) in markers.iter().enumerate() {
                if let Some(staged) = *staged
                    && self.finish(bank, block, staged, 0).is_ok()
                {
                    self.set_lost(block, false);
                }
            }
        }
    }

    pub fn banks(&self) -> &[S; 2] {
        &self.banks
    }

    /// The raw devices, for fault injection in tests.
    pub fn banks_mut(&mut self) -> &mut [S; 2] {
        &mut self.banks
    }

    pub fn into_banks(self) -> [S; 2] {
        self.banks
    }

    /// Status of bank `bank` (0 or 1).
    pub fn status(&self, bank: usize) -> BankStatus {
        self.status.get(bank).copied().unwrap_or_default()
    }

    /// Command 0x91: forget the bank's error flags. Stored data is not touched.
    pub fn clear_status(&mut self, bank: usize) {
        if let Some(s) = self.status.get_mut(bank) {
            *s = BankStatus::default();
        }
    }

    /// The 32-bit sum of bank `bank`'s data bytes (5C00h), without reading the EEPROM.
    pub fn checksum(&self, bank: usize) -> u32 {
        let Some(sums) = self.block_sums.get(bank) else { return 0 };
        // Loops, not `fold` or `sum` over slices: Kani (CBMC 6.6) never reduces those to
        // constants, so a proof would treat every sum as unknown.
        let mut total = 0;
        for &s in sums {
            total += u32::from(s);
        }
        total
    }

    /// Neither bank holds a valid copy of `block`.
    pub fn is_lost(&self, block: usize) -> bool {
        self.lost.get(block).copied().unwrap_or(false)
    }

    /// Reads `out.len()` data bytes from `addr`, comparing both banks; a block whose copies
    /// differ is resolved and repaired before its bytes are returned.
    pub fn read(&mut self, addr: usize, out: &mut [u8]) -> Result<(), Error> {
        let end = Self::end(addr, out.len())?;
        for k in 0..BLOCKS {
            let Some((block, at, range)) = Self::piece(addr, end, k) else { break };
            self.read_in_block(block, at, out.get_mut(range).ok_or(Error::OutOfRange)?)?;
        }
        Ok(())
    }

    /// Writes `data` at `addr` to both banks, bank 1 first. Each block commits atomically;
    /// a write spanning blocks may be cut between them. Writing what is already stored
    /// costs no EEPROM write.
    pub fn write(&mut self, addr: usize, data: &[u8]) -> Result<(), Error> {
        let end = Self::end(addr, data.len())?;
        for k in 0..BLOCKS {
            let Some((block, at, range)) = Self::piece(addr, end, k) else { break };
            self.write_in_block(block, at, data.get(range).ok_or(Error::OutOfRange)?)?;
        }
        Ok(())
    }

    /// Checks and repairs one block; call it periodically so corruption in rarely read
    /// blocks is found while the other bank still holds them.
    pub fn check_block(&mut self, block: usize) -> Result<(), Error> {
        if block >= BLOCKS {
            return Err(Error::OutOfRange);
        }
        let copies = [self.load(0, block), self.load(1, block)];
        self.settle(block, &copies).map(|_| ())
    }

    /// Checks the next block in turn (a background scrub).
    pub fn scrub_next(&mut self) -> Result<(), Error> {
        let block = self.scrub_at;
        self.scrub_at = if block + 1 >= BLOCKS { 0 } else { block + 1 };
        self.check_block(block)
    }

    /// The end of `len` bytes from `addr`, if they lie in the data area.
    fn end(addr: usize, len: usize) -> Result<usize, Error> {
        addr.checked_add(len).filter(|&e| e <= Self::DATA_SIZE).ok_or(Error::OutOfRange)
    }

    /// Piece `k` of the data range `addr..end` (at most one per block, in block order): its
    /// block, its offset in the block and its place in the range; `None` past the last one.
    /// Callers loop `k` over `0..BLOCKS`, a constant bound: Kani (CBMC) unrolled a loop over an
    /// iterator of the pieces to the harness's bound when `addr` was symbolic. Public for the
    /// proofs (`coforge-verification`): a read or write across blocks is its pieces in turn.
    pub fn piece(addr: usize, end: usize, k: usize) -> Option<(usize, usize, Range<usize>)> {
        let block = addr.checked_div(BLOCK)?.checked_add(k)?;
        let start = block.checked_mul(BLOCK)?;
        let (from, to) = (start.max(addr), start.checked_add(BLOCK)?.min(end));
        (from < to).then(|| (block, from - start, from - addr..to - addr))
    }

    fn read_in_block(&mut self, block: usize, at: usize, dst: &mut [u8]) -> Result<(), Error> {
        if !self.is_lost(block) {
            // Both reads land in whole-block buffers that start equal, so the comparison has a
            // constant length: Kani (CBMC) unrolls a compare of `dst.len()` bytes to its bound.
            let n = dst.len();
            let (mut mine, mut other) = ([0_u8; BLOCK], [0_u8; BLOCK]);
            let base = Self::slot(block) + at;
            let a = self.get(0, base, mine.get_mut(..n).ok_or(Error::OutOfRange)?);
            let b = self.get(1, base, other.get_mut(..n).ok_or(Error::OutOfRange)?);
            if a.is_ok() && b.is_ok() && mine == other {
                dst.copy_from_slice(mine.get(..n).ok_or(Error::OutOfRange)?);
                return Ok(());
            }
        }
        let copies = [self.load(0, block), self.load(1, block)];
        let settled = self.settle(block, &copies)?;
        let src = settled.data.get(at..at + dst.len()).ok_or(Error::OutOfRange)?;
        dst.copy_from_slice(src);
        Ok(())
    }

    fn write_in_block(&mut self, block: usize, at: usize, src: &[u8]) -> Result<(), Error> {
        let copies = [self.load(0, block), self.load(1, block)];
        if copies.iter().any(|c| c.state == CopyState::Unreadable) {
            return Err(Error::Access);
        }
        let (old, seq, current) = match self.settle(block, &copies) {
            // A repair that failed leaves the loser holding unknown bytes: writing over it as if
            // it were the committed copy could commit them, so the write waits for a repair.
            Ok(s) if !s.mirrored => return Err(Error::Access),
            Ok(s) => (Some(s.data), s.seq.wrapping_add(1), [Copy::committed(s.data, s.seq); 2]),
            // Both copies lost: the block starts again from zeros, and the banks say so.
            Err(Error::Lost { .. }) => {
                for s in &mut self.status {
                    s.set(BankStatus::CLEARED);
                }
                (None, 0, copies)
            }
            Err(e) => return Err(e),
        };
        let mut new = old.unwrap_or([0; BLOCK]);
        new.get_mut(at..at + src.len()).ok_or(Error::OutOfRange)?.copy_from_slice(src);
        if old == Some(new) {
            return Ok(());
        }
        let [first, second] = current;
        self.write_copy(0, block, &first, &new, seq)?;
        self.write_copy(1, block, &second, &new, seq)?;
        self.set_lost(block, false);
        Ok(())
    }

    /// Decides a block from its two copies, repairs the losing bank and records why.
    fn settle(&mut self, block: usize, copies: &[Copy<BLOCK>; 2]) -> Result<Settled<BLOCK>, Error> {
        let [a, b] = copies;
        match resolve(a.state, b.state, a.data == b.data) {
            Verdict::Agree => {
                self.set_lost(block, false);
                Ok(Settled { data: a.data, seq: a.record.seq(), mirrored: true })
            }
            Verdict::Use { winner, repair, flags } => {
                let loser = winner ^ 1;
                // Indexed, not picked with `if winner == 0 { (a, b) } else { (b, a) }`: Kani
                // (CBMC 6.6) read the winner's data through such a reference as the loser's,
                // a false counterexample (verification/README.md). `resolve` names bank 0 or
                // 1, so the `else` is never taken.
                let (Some(w), Some(l)) = (copies.get(winner), copies.get(loser)) else {
                    return Err(Error::OutOfRange);
                };
                if let Some(s) = self.status.get_mut(loser) {
                    s.set(flags);
                }
                let seq = w.record.seq();
                // A failed repair leaves the loser invalid; the winner is still intact.
                let mirrored = repair && self.write_copy(loser, block, l, &w.data, seq).is_ok();
                self.set_lost(block, false);
                Ok(Settled { data: w.data, seq, mirrored })
            }
            Verdict::Lost => {
                // Indexed, not `zip`: Kani cannot bound a `zip` loop by its length.
                for (bank, c) in copies.iter().enumerate() {
                    if c.state == CopyState::Invalid
                        && let Some(s) = self.status.get_mut(bank)
                    {
                        s.set(BankStatus::CHECKSUM_ERROR);
                    }
                }
                self.set_lost(block, true);
                Err(Error::Lost { block })
            }
        }
    }

    /// Turns `current` (what `bank` holds for `block`) into `new` committed as `seq`, in the
    /// order of [`crate::record`], writing only bytes that change.
    fn write_copy(&mut self, bank: usize, block: usize, current: &Copy<BLOCK>, new: &[u8; BLOCK], seq: u8) -> Result<(), Error> {
        let result = self.stage(bank, block, current, new, seq).and_then(|markers| self.finish(bank, block, markers, seq));
        self.count_written(bank, block, new, result.is_ok());
        result
    }

    /// The block sum after writing `new` into `bank`: `new` if the write completed.
    fn count_written(&mut self, bank: usize, block: usize, new: &[u8; BLOCK], done: bool) {
        if done {
            self.set_block_sum(bank, block, new);
        } else {
            // Some bytes may be written: count what the bank now holds, if it answers.
            let mut now = [0_u8; BLOCK];
            if self.get(bank, Self::slot(block), &mut now).is_ok() {
                self.set_block_sum(bank, block, &now);
            }
        }
    }

    /// Steps 1 and 2 of [`crate::record`]: the invalidating mark, the changed data bytes and
    /// the CRC. Returns the markers `(begin, end)` the copy then holds, for [`Self::finish`].
    fn stage(&mut self, bank: usize, block: usize, current: &Copy<BLOCK>, new: &[u8; BLOCK], seq: u8) -> Result<(u8, u8), Error> {
        let base = Self::slot(block);
        let (begin, end) = (current.record.begin, current.record.end);
        // Markers that differ already make the copy invalid; a mark written over them could
        // make it valid again, if the cut left the stored `end` in `begin`.
        let begin = if begin == end {
            let mark = current.record.invalidating_mark(seq);
            self.put(bank, base + offset::begin(BLOCK), &[mark])?;
            mark
        } else {
            begin
        };
        let mut run: Option<usize> = None;
        for i in 0..=BLOCK {
            let changed = i < BLOCK && new.get(i) != current.data.get(i);
            match (run, changed) {
                (None, true) => run = Some(i),
                (Some(start), false) => {
                    self.put(bank, base + start, new.get(start..i).unwrap_or(&[]))?;
                    run = None;
                }
                _ => {}
            }
        }
        let record = Record::committed(new, seq);
        if current.record.crc != record.crc {
            self.put(bank, base + offset::crc(BLOCK), &record.crc.to_le_bytes())?;
        }
        Ok((begin, end))
    }

    /// Step 3, the commit: each marker that does not yet say `seq`, `begin` first; the last
    /// one written commits the copy.
    fn finish(&mut self, bank: usize, block: usize, (begin, end): (u8, u8), seq: u8) -> Result<(), Error> {
        let base = Self::slot(block);
        if begin != seq {
            self.put(bank, base + offset::begin(BLOCK), &[seq])?;
        }
        if end != seq {
            self.put(bank, base + offset::end(BLOCK), &[seq])?;
        }
        Ok(())
    }

    fn load(&mut self, bank: usize, block: usize) -> Copy<BLOCK> {
        let mut data = [0_u8; BLOCK];
        let mut record = [0_u8; RECORD];
        let base = Self::slot(block);
        let read = self.get(bank, base, &mut data).and_then(|()| self.get(bank, base + BLOCK, &mut record));
        let record = Record::from_bytes(record);
        if read.is_ok() {
            self.set_block_sum(bank, block, &data);
        }
        let state = match read {
            Err(_) => CopyState::Unreadable,
            Ok(()) if record.is_valid_for(&data) => CopyState::Valid(record.seq()),
            Ok(()) => CopyState::Invalid,
        };
        Copy { data, record, state }
    }

    fn set_block_sum(&mut self, bank: usize, block: usize, data: &[u8; BLOCK]) {
        if let Some(sum) = self.block_sums.get_mut(bank).and_then(|sums| sums.get_mut(block)) {
            // At most 255 * BLOCK; blocks beyond 257 bytes would need a wider sum.
            // Indexed, not `for &b in data`: see `Crc16::update`.
            *sum = 0;
            for i in 0..BLOCK {
                *sum = sum.wrapping_add(data.get(i).copied().map_or(0, u16::from));
            }
        }
    }

    fn slot(block: usize) -> usize {
        block * Self::SLOT
    }

    fn set_lost(&mut self, block: usize, lost: bool) {
        if let Some(l) = self.lost.get_mut(block) {
            *l = lost;
        }
    }

    fn get(&mut self, bank: usize, offset: usize, buf: &mut [u8]) -> Result<(), Error> {
        let offset = u32::try_from(offset).map_err(|_| Error::OutOfRange)?;
        let ok = match self.banks.get_mut(bank) {
            Some(s) => s.read(offset, buf).is_ok(),
            None => return Err(Error::OutOfRange),
        };
        self.checked(bank, ok)
    }

    fn put(&mut self, bank: usize, offset: usize, bytes: &[u8]) -> Result<(), Error> {
        let offset = u32::try_from(offset).map_err(|_| Error::OutOfRange)?;
        let ok = match self.banks.get_mut(bank) {
            Some(s) => s.write(offset, bytes).is_ok(),
            None => return Err(Error::OutOfRange),
        };
        self.checked(bank, ok)
    }

    /// An EEPROM error sets the bank's access time-out bit.
    fn checked(&mut self, bank: usize, ok: bool) -> Result<(), Error> {
        if ok {
            return Ok(());
        }
        if let Some(s) = self.status.get_mut(bank) {
            s.set(BankStatus::ACCESS_TIMEOUT);
        }
        Err(Error::Access)
    }
}
