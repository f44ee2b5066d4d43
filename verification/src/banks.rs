//! Proof obligations of the mirrored EEPROM banks (`coforge-storage`): a power cut
//! at any byte of a write or of start-up recovery, any single-byte corruption of either bank,
//! the incremental bank sums, and totality for arbitrary bank contents.
//!
//! [`CutEeprom`] is a RAM EEPROM whose byte writes are counted on a [`Power`] supply shared by
//! both banks, so a cut can be placed at any byte of an operation, in bank 1's part or in bank
//! 2's. The byte being programmed at the cut keeps its old value, gets the new one or garbage
//! ([`CutByte`]); every later write fails while reads keep working. A reboot is
//! [`Power::restore_power`] and a new [`MirroredBanks::mount`] on the same devices. A recovery
//! cut runs one mount of [`TwinEeprom`]s, which gives both what the cut left and what the
//! uncut recovery leaves.
//!
//! Every `check_*` function returns what it observed, so the exhaustive tests can count
//! failures; the `prop_*` function of the same name asserts that nothing failed.

use coforge_storage::record::{RECORD, Record};
use coforge_storage::{BankStatus, Error, MirroredBanks};
use core::cell::Cell;
use embedded_storage::{ReadStorage, Storage};

mod twin;
pub use twin::TwinEeprom;

/// The banks under test: two [`CutEeprom`]s of `N` bytes, `BLOCKS` blocks of `BLOCK` bytes.
pub type Banks<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize> = MirroredBanks<CutEeprom<'p, N>, BLOCKS, BLOCK>;

/// What the byte being programmed when the power fails ends up holding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CutByte {
    /// The cell was not yet programmed.
    Old,
    /// The cell was programmed; the cut hits right after it.
    New,
    /// The cell holds whatever the interrupted programming left.
    Garbage(u8),
}

impl CutByte {
    /// `selector % 3`: old, new or `garbage` (for symbolic and exhaustive inputs).
    pub fn select(selector: u8, garbage: u8) -> CutByte {
        match selector % 3 {
            0 => CutByte::Old,
            1 => CutByte::New,
            _ => CutByte::Garbage(garbage),
        }
    }
}

/// The supply of both banks' EEPROMs: counts byte writes across both devices and cuts the
/// power at a chosen one.
#[derive(Debug)]
pub struct Power {
    /// Byte writes attempted since the last [`Power::arm`] or [`Power::reset_steps`].
    steps: Cell<u32>,
    /// The step whose byte is torn, when armed.
    cut_at: Cell<Option<u32>>,
    cut_byte: Cell<CutByte>,
    off: Cell<bool>,
    /// Where in its device the byte torn by the last cut is.
    torn_at: Cell<Option<usize>>,
}

impl Default for Power {
    fn default() -> Self {
        Self::new()
    }
}

impl Power {
    pub const fn new() -> Power {
        Power { steps: Cell::new(0), cut_at: Cell::new(None), cut_byte: Cell::new(CutByte::Old), off: Cell::new(false), torn_at: Cell::new(None) }
    }

    /// Cuts the power at byte write `cut_at` from now (0 = the next one), leaving `byte` in it.
    pub fn arm(&self, cut_at: u32, byte: CutByte) {
        self.steps.set(0);
        self.cut_at.set(Some(cut_at));
        self.cut_byte.set(byte);
        self.torn_at.set(None);
    }

    /// The offset, in its device, of the byte the last cut tore.
    pub fn torn_at(&self) -> Option<usize> {
        self.torn_at.get()
    }

    /// Power is back and no cut is armed.
    pub fn restore_power(&self) {
        self.off.set(false);
        self.cut_at.set(None);
    }

    /// The armed cut has happened.
    pub fn is_off(&self) -> bool {
        self.off.get()
    }

    /// Byte writes attempted (on both devices) since the last `arm` or `reset_steps`.
    pub fn steps(&self) -> u32 {
        self.steps.get()
    }

    pub fn reset_steps(&self) {
        self.steps.set(0);
    }

    /// One byte write of `new` over `old` at `offset`: what the cell then holds (`None`:
    /// untouched, the power is off), and whether the write completed.
    fn program(&self, offset: usize, old: u8, new: u8) -> (Option<u8>, bool) {
        if self.off.get() {
            return (None, false);
        }
        let step = self.steps.get();
        self.steps.set(step.saturating_add(1));
        if self.cut_at.get() == Some(step) {
            self.off.set(true);
            self.torn_at.set(Some(offset));
            let left = match self.cut_byte.get() {
                CutByte::Old => old,
                CutByte::New => new,
                CutByte::Garbage(g) => g,
            };
            return (Some(left), false);
        }
        (Some(new), true)
    }
}

/// The longest single write [`MirroredBanks`] makes on the geometry of the Kani harnesses
/// (2 blocks of 2 data bytes): a block's data, or the 2 CRC bytes. Under Kani a
/// [`CutEeprom`] asserts it and bounds its write loop with it.
pub const KANI_MAX_WRITE: usize = 2;

/// Why a [`CutEeprom`] access failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EepromError {
    OutOfBounds,
    /// The device does not answer at all.
    NoAnswer,
    /// The power is off.
    PowerCut,
}

/// `N` bytes of byte-writable memory on a shared [`Power`] supply, counting byte reads, byte
/// writes and writes per cell.
#[derive(Clone)]
pub struct CutEeprom<'p, const N: usize> {
    bytes: [u8; N],
    power: &'p Power,
    unreadable: bool,
    reads: u32,
    writes: u32,
    /// Programming cycles of each cell (saturating).
    cell_writes: [u16; N],
}

/// Only the contents (and whether the device answers): two devices with the same bytes debug
/// the same whatever their counters say. The model search hashes this.
impl<const N: usize> core::fmt::Debug for CutEeprom<'_, N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("CutEeprom").field("bytes", &self.bytes.as_slice()).field("unreadable", &self.unreadable).finish()
    }
}

impl<'p, const N: usize> CutEeprom<'p, N> {
    pub fn new(power: &'p Power, bytes: [u8; N]) -> Self {
        CutEeprom { bytes, power, unreadable: false, reads: 0, writes: 0, cell_writes: [0; N] }
    }

    /// Erased memory (every byte 0xFF).
    pub fn erased(power: &'p Power) -> Self {
        Self::new(power, [0xFF; N])
    }

    pub fn power(&self) -> &'p Power {
        self.power
    }

    pub fn as_bytes(&self) -> &[u8; N] {
        &self.bytes
    }

    /// Direct access, for corrupting a byte (no write is counted).
    pub fn as_bytes_mut(&mut self) -> &mut [u8; N] {
        &mut self.bytes
    }

    /// A device that answers nothing (every read and write fails).
    pub fn set_unreadable(&mut self, unreadable: bool) {
        self.unreadable = unreadable;
    }

    /// Power is back (the supply is shared: this restores it for both devices).
    pub fn restore_power(&self) {
        self.power.restore_power();
    }

    pub fn reads(&self) -> u32 {
        self.reads
    }

    pub fn writes(&self) -> u32 {
        self.writes
    }

    /// Programming cycles of the most-written cell since the last [`CutEeprom::reset_counts`].
    pub fn max_cell_writes(&self) -> u16 {
        self.cell_writes.iter().copied().max().unwrap_or(0)
    }

    pub fn cell_writes(&self, cell: usize) -> u16 {
        self.cell_writes.get(cell).copied().unwrap_or(0)
    }

    pub fn reset_counts(&mut self) {
        self.reads = 0;
        self.writes = 0;
        self.cell_writes = [0; N];
    }

    fn range(offset: u32, len: usize) -> Result<core::ops::Range<usize>, EepromError> {
        let start = usize::try_from(offset).map_err(|_| EepromError::OutOfBounds)?;
        let end = start.checked_add(len).filter(|&e| e <= N).ok_or(EepromError::OutOfBounds)?;
        Ok(start..end)
    }
}

impl<const N: usize> ReadStorage for CutEeprom<'_, N> {
    type Error = EepromError;

    /// Reads work with the power off: the test reads what a cut left before it reboots.
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), EepromError> {
        if self.unreadable {
            return Err(EepromError::NoAnswer);
        }
        let src = self.bytes.get(Self::range(offset, bytes.len())?).ok_or(EepromError::OutOfBounds)?;
        bytes.copy_from_slice(src);
        self.reads = self.reads.saturating_add(u32::try_from(bytes.len()).unwrap_or(u32::MAX));
        Ok(())
    }

    fn capacity(&self) -> usize {
        N
    }
}

impl<const N: usize> Storage for CutEeprom<'_, N> {
    /// Byte by byte, each one a step of the shared supply.
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), EepromError> {
        if self.unreadable {
            return Err(EepromError::NoAnswer);
        }
        let start = Self::range(offset, bytes.len())?.start;
        // Under Kani the loop gets a constant bound (`take` changes nothing after the
        // assertion): CBMC unrolls a loop of symbolic length, such as a run of changed data
        // bytes, to the harness's unwind bound otherwise. Not `zip` either: Kani unrolls a
        // `zip` loop to the unwind bound even when both lengths are constants.
        #[cfg(kani)]
        assert!(bytes.len() <= KANI_MAX_WRITE, "a write longer than the Kani geometry's blocks");
        let most = if cfg!(kani) { KANI_MAX_WRITE } else { usize::MAX };
        for (k, &new) in bytes.iter().enumerate().take(most) {
            let i = start + k;
            let (Some(cell), Some(count)) = (self.bytes.get_mut(i), self.cell_writes.get_mut(i)) else {
                return Err(EepromError::OutOfBounds);
            };
            let (left, done) = self.power.program(i, *cell, new);
            if let Some(left) = left {
                *cell = left;
                // Wear is for the endurance table; no proof reads it, and under Kani the
                // count would double the cost of a write to a symbolic offset.
                if !cfg!(kani) {
                    *count = count.saturating_add(1);
                }
                self.writes = self.writes.saturating_add(1);
            }
            if !done {
                return Err(EepromError::PowerCut);
            }
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// Reading the state of the banks.

/// Bytes of one block's slot in a bank.
pub const fn slot_size(block: usize) -> usize {
    block + RECORD
}

fn assert_geometry<const N: usize, const BLOCKS: usize, const BLOCK: usize>() {
    assert_eq!(N, BLOCKS * slot_size(BLOCK), "an EEPROM of N bytes holds BLOCKS slots of BLOCK + 4 bytes");
}

/// Block `block`'s slot (data and record) in a bank image.
pub fn slot<const BLOCK: usize>(image: &[u8], block: usize) -> &[u8] {
    let start = block * slot_size(BLOCK);
    // Indexing (panics for a block outside the image): the slice has a constant length, so
    // Kani unrolls the loops over it (CRC, comparisons) exactly that often.
    &image[start..start + slot_size(BLOCK)]
}

/// Block `block`'s copy in a bank image is committed: its record matches its data.
pub fn copy_is_valid<const BLOCK: usize>(image: &[u8], block: usize) -> bool {
    match slot::<BLOCK>(image, block).split_at_checked(BLOCK) {
        Some((data, &[begin, lo, hi, end])) => <&[u8; BLOCK]>::try_from(data).is_ok_and(|data| Record::from_bytes([begin, lo, hi, end]).is_valid_for(data)),
        _ => false,
    }
}

/// The sum of a bank image's data bytes, recomputed (what 5C00h must equal).
pub fn data_sum<const BLOCKS: usize, const BLOCK: usize>(image: &[u8]) -> u32 {
    // Loops, not `sum` over slices: Kani (CBMC 6.6) never reduces a slice `fold` to a constant.
    let mut sum = 0;
    for block in 0..BLOCKS {
        for &b in &slot::<BLOCK>(image, block)[..BLOCK] {
            sum += u32::from(b);
        }
    }
    sum
}

/// A bank image holding `data`, each block committed with its sequence number from `seqs`.
pub fn committed_image<const N: usize, const BLOCKS: usize, const BLOCK: usize>(data: &[[u8; BLOCK]; BLOCKS], seqs: &[u8; BLOCKS]) -> [u8; N] {
    assert_geometry::<N, BLOCKS, BLOCK>();
    let mut image = [0xFF; N];
    for (block, d) in data.iter().enumerate() {
        let seq = seqs[block];
        let base = block * slot_size(BLOCK);
        image[base..base + BLOCK].copy_from_slice(d);
        image[base + BLOCK..base + slot_size(BLOCK)].copy_from_slice(&Record::committed(d, seq).to_bytes());
    }
    image
}

/// Two devices on `power` that both hold [`committed_image`]`(data, seqs)`: banks that agree.
pub fn committed_devices<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    power: &'p Power,
    data: &[[u8; BLOCK]; BLOCKS],
    seqs: &[u8; BLOCKS],
) -> [CutEeprom<'p, N>; 2] {
    let image = committed_image::<N, BLOCKS, BLOCK>(data, seqs);
    [CutEeprom::new(power, image), CutEeprom::new(power, image)]
}

/// What reading each block returns (reads repair, as they do in the device).
pub fn contents<const N: usize, const BLOCKS: usize, const BLOCK: usize>(banks: &mut Banks<'_, N, BLOCKS, BLOCK>) -> [Result<[u8; BLOCK], Error>; BLOCKS] {
    core::array::from_fn(|block| {
        let mut out = [0; BLOCK];
        banks.read(block * BLOCK, &mut out).map(|()| out)
    })
}

/// What reading each block returns right after a mount, from the images alone: `Lost` for a
/// block with no valid copy in either bank, else bank 1's data (a mount leaves both banks
/// holding the same valid slot). [`prop_first_mount_settles`] and
/// [`prop_settled_mount_is_quiet`] prove that reads after any mount return exactly this.
pub fn settled_contents<const N: usize, const BLOCKS: usize, const BLOCK: usize>(images: &[[u8; N]; 2]) -> [Result<[u8; BLOCK], Error>; BLOCKS] {
    core::array::from_fn(|block| {
        if settled_lost::<N, BLOCK>(images, block) {
            return Err(Error::Lost { block });
        }
        let mut data = [0; BLOCK];
        data.copy_from_slice(&slot::<BLOCK>(&images[0], block)[..BLOCK]);
        Ok(data)
    })
}

/// What reading each block returns right after a mount. Natively the blocks are read and the
/// reads must equal [`settled_contents`], so every test also checks that lemma. Under Kani
/// the lemma is taken as proved (by the two halves named there), and the contents come from
/// the images: reading symbolic banks costs as much symbolic execution as another mount.
pub fn contents_after_mount<const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    banks: &mut Banks<'_, N, BLOCKS, BLOCK>,
) -> [Result<[u8; BLOCK], Error>; BLOCKS] {
    let settled = settled_contents::<N, BLOCKS, BLOCK>(&images(banks));
    #[cfg(not(kani))]
    assert_eq!(contents(banks), settled, "reads right after a mount return the committed data or Lost");
    settled
}

/// Mounts banks that agree (identical images, every block valid). Natively a real mount, which
/// must leave exactly the state built here with `MirroredBanks::in_state`: no status bit, no
/// lost block, the sums right (and the scrub at block 0, as a mount sets it; no proof that
/// uses this function scrubs). Under Kani the built state is the mount:
/// `prop_first_mount_settles` proves that such a mount writes nothing and sets no status bit
/// and that it flags exactly the blocks with no valid copy, and the reboot step harness proves
/// the sums right after any mount.
pub fn mount_agreeing<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(devices: [CutEeprom<'p, N>; 2]) -> Banks<'p, N, BLOCKS, BLOCK> {
    let before = [*devices[0].as_bytes(), *devices[1].as_bytes()];
    assert!(before[0] == before[1] && (0..BLOCKS).all(|b| copy_is_valid::<BLOCK>(&before[0], b)), "precondition: banks that agree");
    #[cfg(kani)]
    return running_banks::<N, BLOCKS, BLOCK>(devices, [false; 2], [0; 2], [false; BLOCKS], 0);
    #[cfg(not(kani))]
    {
        let built = running_banks::<N, BLOCKS, BLOCK>(devices.clone(), [false; 2], [0; 2], [false; BLOCKS], 0);
        let mounted = Banks::<N, BLOCKS, BLOCK>::mount(devices);
        assert_eq!(observable(&mounted), observable(&built), "a mount of banks that agree leaves the state in_state builds");
        mounted
    }
}

/// Everything a caller can observe of the banks: both images, both status bytes, the lost
/// flags and both bank sums.
#[allow(clippy::type_complexity)]
pub fn observable<const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    banks: &Banks<'_, N, BLOCKS, BLOCK>,
) -> ([[u8; N]; 2], [BankStatus; 2], [bool; BLOCKS], [u32; 2]) {
    (images(banks), [banks.status(0), banks.status(1)], core::array::from_fn(|block| banks.is_lost(block)), [banks.checksum(0), banks.checksum(1)])
}

/// Two [`observable`] states are equal, the images compared bank by bank (see [`same_images`]).
#[allow(clippy::type_complexity)]
pub fn same_observable<const N: usize, const BLOCKS: usize>(
    a: &([[u8; N]; 2], [BankStatus; 2], [bool; BLOCKS], [u32; 2]),
    b: &([[u8; N]; 2], [BankStatus; 2], [bool; BLOCKS], [u32; 2]),
) -> bool {
    same_images(&a.0, &b.0) && a.1 == b.1 && a.2 == b.2 && a.3 == b.3
}

/// Two pairs of bank images are equal (bank by bank: Kani unrolls the comparison of `N`
/// bytes, not `2 N`).
pub fn same_images<const N: usize>(a: &[[u8; N]; 2], b: &[[u8; N]; 2]) -> bool {
    a[0] == b[0] && a[1] == b[1]
}

/// Both bank images.
pub fn images<const N: usize, const BLOCKS: usize, const BLOCK: usize>(banks: &Banks<'_, N, BLOCKS, BLOCK>) -> [[u8; N]; 2] {
    let [a, b] = banks.banks();
    [*a.as_bytes(), *b.as_bytes()]
}

/// Blocks whose slots (data and record) differ between the two banks.
pub fn disagreeing_blocks<const N: usize, const BLOCKS: usize, const BLOCK: usize>(banks: &Banks<'_, N, BLOCKS, BLOCK>) -> usize {
    let [a, b] = banks.banks();
    (0..BLOCKS).filter(|&block| slot::<BLOCK>(a.as_bytes(), block) != slot::<BLOCK>(b.as_bytes(), block)).count()
}

/// Banks whose incremental sum (`checksum`) differs from a recomputation over the device.
pub fn checksum_errors<const N: usize, const BLOCKS: usize, const BLOCK: usize>(banks: &Banks<'_, N, BLOCKS, BLOCK>) -> usize {
    (0..2).filter(|&bank| banks.checksum(bank) != data_sum::<BLOCKS, BLOCK>(banks.banks()[bank].as_bytes())).count()
}

/// Byte writes of both devices since their counters were reset.
pub fn writes<const N: usize, const BLOCKS: usize, const BLOCK: usize>(banks: &Banks<'_, N, BLOCKS, BLOCK>) -> u32 {
    let [a, b] = banks.banks();
    a.writes() + b.writes()
}

/// Byte reads of both devices since their counters were reset.
pub fn reads<const N: usize, const BLOCKS: usize, const BLOCK: usize>(banks: &Banks<'_, N, BLOCKS, BLOCK>) -> u32 {
    let [a, b] = banks.banks();
    a.reads() + b.reads()
}

pub fn reset_counts<const N: usize, const BLOCKS: usize, const BLOCK: usize>(banks: &mut Banks<'_, N, BLOCKS, BLOCK>) {
    for d in banks.banks_mut() {
        d.reset_counts();
    }
}

/// The new contents of every block after writing `data` at `addr` over `old` (`None` when
/// the range is outside the data area).
pub fn written<const BLOCKS: usize, const BLOCK: usize>(old: &[[u8; BLOCK]; BLOCKS], addr: usize, data: &[u8]) -> Option<[[u8; BLOCK]; BLOCKS]> {
    addr.checked_add(data.len()).filter(|&e| e <= BLOCKS * BLOCK)?;
    let mut new = *old;
    for (k, &byte) in data.iter().enumerate() {
        let pos = addr + k;
        *new.get_mut(pos / BLOCK)?.get_mut(pos % BLOCK)? = byte;
    }
    Some(new)
}

/// Byte writes (both devices) that writing `data` at `addr` costs from the state `devices`
/// hold, uncut: the cut points of that write are `0..steps`.
pub fn write_steps<const N: usize, const BLOCKS: usize, const BLOCK: usize>(devices: &[CutEeprom<'_, N>; 2], addr: usize, data: &[u8]) -> u32 {
    let power = devices[0].power();
    power.restore_power();
    let mut banks = Banks::<N, BLOCKS, BLOCK>::mount(devices.clone());
    power.reset_steps();
    let _ = banks.write(addr, data);
    power.steps()
}

/// Byte writes (both devices) of an uncut mount of `devices`: the cut points of the recovery.
pub fn recovery_steps<const N: usize, const BLOCKS: usize, const BLOCK: usize>(devices: &[CutEeprom<'_, N>; 2]) -> u32 {
    let power = devices[0].power();
    power.restore_power();
    power.reset_steps();
    let _ = Banks::<N, BLOCKS, BLOCK>::mount(devices.clone());
    power.steps()
}

// ---------------------------------------------------------------------------------------------
// (a) A power cut at any byte of a write.

/// What a reboot after a write cut at one step found.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CutOutcome {
    /// The cut happened before the write completed.
    pub fired: bool,
    /// Blocks the write changes that read back their old contents after the reboot.
    pub old: usize,
    /// Blocks the write changes that read back their new contents after the reboot.
    pub new: usize,
    /// Blocks that read back neither their old nor their new contents: a mix.
    pub mixed: usize,
    /// Blocks that could not be read (`Lost` or any other error).
    pub lost: usize,
    /// A block reads new although a block before it in the write still reads old: blocks
    /// commit in address order.
    pub out_of_order: usize,
    /// The write returned `Ok` and a block still reads old: committed data lost.
    pub committed_lost: usize,
    /// Blocks whose two copies differ byte for byte after the reboot.
    pub disagree: usize,
    /// Banks whose incremental sum differs from a recomputation, after the cut (before the
    /// reboot) and after the reboot.
    pub checksum_errors: usize,
    /// The write's result contradicts the cut (`Ok` although cut, or an error without a cut).
    pub wrong_result: bool,
}

impl CutOutcome {
    pub fn is_clean(&self) -> bool {
        self.mixed == 0
            && self.lost == 0
            && self.out_of_order == 0
            && self.committed_lost == 0
            && self.disagree == 0
            && self.checksum_errors == 0
            && !self.wrong_result
    }
}

/// Mounts `devices` (banks holding valid blocks), writes `data` at `addr` with the power cut at
/// byte write `cut_at` (leaving `cut` in that byte), reboots, and classifies every block.
pub fn check_write_cut<const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    devices: [CutEeprom<'_, N>; 2],
    addr: usize,
    data: &[u8],
    cut_at: u32,
    cut: CutByte,
) -> CutOutcome {
    assert_geometry::<N, BLOCKS, BLOCK>();
    let power = devices[0].power();
    let mut banks = mount_agreeing::<N, BLOCKS, BLOCK>(devices);
    let mut old = [[0; BLOCK]; BLOCKS];
    let before = contents_after_mount(&mut banks);
    for (block, o) in old.iter_mut().enumerate() {
        *o = before[block].expect("precondition: every block readable before the write");
    }
    let new = written(&old, addr, data);
    power.arm(cut_at, cut);
    let result = banks.write(addr, data);
    let fired = power.is_off();
    let mut out = CutOutcome { fired, ..CutOutcome::default() };
    out.wrong_result = match (fired, new.is_some()) {
        (true, _) => result != Err(Error::Access),
        (false, true) => result.is_err(),
        (false, false) => result != Err(Error::OutOfRange),
    };
    out.checksum_errors += checksum_errors(&banks);
    power.restore_power();
    let mut banks = Banks::<N, BLOCKS, BLOCK>::mount(banks.into_banks());
    let new = new.unwrap_or(old);
    let mut seen_old = false;
    let after = contents_after_mount(&mut banks);
    for (block, now) in after.iter().enumerate() {
        let (o, n) = (&old[block], &new[block]);
        match now {
            Err(_) => out.lost += 1,
            Ok(now) if o == n => out.mixed += usize::from(now != o),
            Ok(now) if now == o => {
                out.old += 1;
                seen_old = true;
                out.committed_lost += usize::from(!fired);
            }
            Ok(now) if now == n => {
                out.new += 1;
                out.out_of_order += usize::from(seen_old);
            }
            Ok(_) => out.mixed += 1,
        }
    }
    out.disagree = disagreeing_blocks(&banks);
    out.checksum_errors += checksum_errors(&banks);
    out
}

/// After a power cut at any byte of a write and a reboot, every block reads back exactly its
/// old or its new contents (blocks in address order), nothing is lost, the banks agree byte
/// for byte and the bank sums equal a recomputation.
pub fn prop_write_cut<const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    devices: [CutEeprom<'_, N>; 2],
    addr: usize,
    data: &[u8],
    cut_at: u32,
    cut: CutByte,
) -> CutOutcome {
    let out = check_write_cut::<N, BLOCKS, BLOCK>(devices, addr, data, cut_at, cut);
    assert!(out.is_clean(), "write of {} bytes at {addr} cut at byte write {cut_at} ({cut:?}): {out:?}", data.len());
    out
}

/// The first piece of a write across blocks, uncut: the rest of a block from `addr`, written
/// to banks that agree (committed with `seqs`, as [`check_write_cut`] starts from). It answers
/// `Ok` and leaves banks that agree again: every block committed in both banks, the written
/// one with its sequence number one up if its data changed, and every block sum, status bit,
/// lost flag and count a mount of those banks would leave. So when a cut spares the first
/// piece of a write across blocks (which is then the writes of its pieces in turn,
/// [`prop_pieces_partition`]), the second piece is a one-block write cut of banks that agree,
/// which the one-block write-cut harnesses take; when it does not, the write ends there, and
/// it is the one-block write cut of the first piece.
pub fn prop_uncut_first_piece_keeps_banks_agreeing<const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    power: &Power,
    data: &[[u8; BLOCK]; BLOCKS],
    seqs: &[u8; BLOCKS],
    addr: usize,
    bytes: &[u8],
) {
    assert!(addr < BLOCK && addr + bytes.len() == BLOCK, "precondition: the rest of block 0 from {addr}");
    let mut banks = mount_agreeing::<N, BLOCKS, BLOCK>(committed_devices::<N, BLOCKS, BLOCK>(power, data, seqs));
    assert_eq!(banks.write(addr, bytes), Ok(()), "an uncut write of {} bytes at {addr}", bytes.len());
    let new = written(data, addr, bytes).expect("a range in the data area");
    let new_seqs: [u8; BLOCKS] = core::array::from_fn(|b| if new[b] == data[b] { seqs[b] } else { seqs[b].wrapping_add(1) });
    let agreeing = mount_agreeing::<N, BLOCKS, BLOCK>(committed_devices::<N, BLOCKS, BLOCK>(power, &new, &new_seqs));
    assert!(same_observable(&observable(&banks), &observable(&agreeing)), "{} bytes at {addr} left banks that do not agree", bytes.len());
    assert!(banks.block_sums() == agreeing.block_sums(), "{} bytes at {addr} left other block sums", bytes.len());
}

/// A write that changes nothing: empty, or reaching past the data area. With a cut armed at
/// any step it attempts no byte write (so the cut never fires), leaves everything a caller
/// can observe as it was, and answers `Ok` when its range lies in the data area (an empty
/// write) and `OutOfRange` otherwise. The reboot after it mounts the same banks that agree,
/// which `prop_first_mount_settles` proves writes nothing, so every block reads its old
/// contents: [`prop_write_cut`]'s property for these writes, without a reboot of symbolic
/// banks.
pub fn prop_write_outside<const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    devices: [CutEeprom<'_, N>; 2],
    addr: usize,
    data: &[u8],
    cut_at: u32,
    cut: CutByte,
) {
    let in_range = addr.checked_add(data.len()).is_some_and(|end| end <= BLOCKS * BLOCK);
    assert!(data.is_empty() || !in_range, "precondition: an empty write or one past the data area");
    let power = devices[0].power();
    let mut banks = mount_agreeing::<N, BLOCKS, BLOCK>(devices);
    let before = observable(&banks);
    power.arm(cut_at, cut);
    let result = banks.write(addr, data);
    assert_eq!(power.steps(), 0, "a write of {} bytes at {addr} attempted a byte write", data.len());
    assert_eq!(result, if in_range { Ok(()) } else { Err(Error::OutOfRange) });
    assert!(same_observable(&observable(&banks), &before), "a write of {} bytes at {addr} changed the banks", data.len());
    power.restore_power();
}

// ---------------------------------------------------------------------------------------------
// (b) Recovery: idempotent, and safe to cut.

/// What two mounts in a row did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Recovery {
    /// Byte writes of the first mount (the repair).
    pub repair_writes: u32,
    /// Byte reads of the first mount.
    pub reads: u32,
    /// Status of both banks after the first mount.
    pub status: [BankStatus; 2],
    /// Blocks lost after the first mount.
    pub lost: usize,
}

/// Mounts any bank contents with the power on and the access counts reset. Banks that agree
/// (identical images, every block valid) are mounted without a single write or status bit.
fn first_mount<const N: usize, const BLOCKS: usize, const BLOCK: usize>(mut devices: [CutEeprom<'_, N>; 2]) -> Banks<'_, N, BLOCKS, BLOCK> {
    assert_geometry::<N, BLOCKS, BLOCK>();
    devices[0].power().restore_power();
    let agreeing = devices[0].as_bytes() == devices[1].as_bytes() && (0..BLOCKS).all(|b| copy_is_valid::<BLOCK>(devices[0].as_bytes(), b));
    for d in &mut devices {
        d.reset_counts();
    }
    let first = Banks::<N, BLOCKS, BLOCK>::mount(devices);
    if agreeing {
        assert_eq!(writes(&first), 0, "banks that agree are mounted without writes");
        assert_eq!([first.status(0), first.status(1)], [BankStatus::default(); 2], "banks that agree are mounted without status bits");
    }
    first
}

/// Mounting any bank contents twice: the second mount writes nothing, finds nothing new and
/// leaves contents and images unchanged; after the first, every block is lost or identical
/// and valid in both banks. Banks that already agree (identical images, every block valid)
/// are mounted without a single write or status bit.
pub fn prop_recovery_idempotent<const N: usize, const BLOCKS: usize, const BLOCK: usize>(devices: [CutEeprom<'_, N>; 2]) -> Recovery {
    let mut first = first_mount::<N, BLOCKS, BLOCK>(devices);
    let recovery = Recovery {
        repair_writes: writes(&first),
        reads: reads(&first),
        status: [first.status(0), first.status(1)],
        lost: (0..BLOCKS).filter(|&b| first.is_lost(b)).count(),
    };
    let after_first = images(&first);
    for block in 0..BLOCKS {
        let valid = copy_is_valid::<BLOCK>(&after_first[0], block);
        assert!(
            first.is_lost(block) || (valid && slot::<BLOCK>(&after_first[0], block) == slot::<BLOCK>(&after_first[1], block)),
            "block {block} is neither lost nor settled"
        );
    }
    let read_first = contents(&mut first);
    assert!(same_images(&images(&first), &after_first), "reads after a mount repair nothing");
    reset_counts(&mut first);
    let mut second = Banks::<N, BLOCKS, BLOCK>::mount(first.into_banks());
    assert_eq!(writes(&second), 0, "a second mount writes nothing");
    for bank in 0..2 {
        let (s1, s2) = (recovery.status[bank].bits(), second.status(bank).bits());
        assert_eq!(s2 & !s1, 0, "the second mount finds nothing new in bank {bank}");
        assert_eq!(s2 & !BankStatus::CHECKSUM_ERROR, 0, "the second mount repairs nothing in bank {bank}");
        assert_eq!(s2 != 0, recovery.lost > 0, "only lost blocks are reported again");
    }
    assert!(same_images(&images(&second), &after_first), "a second mount changes nothing");
    assert_eq!(contents(&mut second), read_first);
    recovery
}

/// The two halves of [`prop_recovery_idempotent`], for Kani: whole, it mounts a symbolic
/// state that is itself the result of a symbolic mount, and took 49 to 65 minutes.
/// [`prop_first_mount_settles`] proves what any first mount leaves (settled banks, not to be
/// formatted, and its status and lost flags), and [`prop_settled_mount_is_quiet`] what a
/// mount of any such banks does. Together they give the whole property: reads depend only on
/// the images and the lost flags (never on the status or the sums), and both halves pin the
/// lost flags to the blocks with no valid copy, so the first mount's reads are the second
/// mount's reads. The exhaustive and random tests run the whole property and both halves.
///
/// Block `block` has no valid copy in either image: a mount finds it lost.
pub fn settled_lost<const N: usize, const BLOCK: usize>(images: &[[u8; N]; 2], block: usize) -> bool {
    !copy_is_valid::<BLOCK>(&images[0], block) && !copy_is_valid::<BLOCK>(&images[1], block)
}

/// Every block is lost, or valid with the same slot (data and record) in both banks: what a
/// first mount leaves when every write succeeds.
pub fn is_settled<const N: usize, const BLOCKS: usize, const BLOCK: usize>(images: &[[u8; N]; 2]) -> bool {
    (0..BLOCKS)
        .all(|b| settled_lost::<N, BLOCK>(images, b) || (copy_is_valid::<BLOCK>(&images[0], b) && slot::<BLOCK>(&images[0], b) == slot::<BLOCK>(&images[1], b)))
}

/// Whether a mount of settled `images` formats the banks: `MirroredBanks::mount`'s rule,
/// restated on images as its specification (the tests check the two agree). Some block is
/// lost, and either every block is (blank banks) or every block holds zeros committed as
/// sequence 0 or is lost with both copies as a format cut leaves them (zeros, the CRC of zeros
/// with sequence 0, markers not both 0, at least one copy open).
pub fn settled_mount_formats<const N: usize, const BLOCKS: usize, const BLOCK: usize>(images: &[[u8; N]; 2]) -> bool {
    let zeros = Record::committed(&[0; BLOCK], 0);
    let staged = |image: &[u8; N], b: usize| {
        let s = slot::<BLOCK>(image, b);
        let (begin, crc, end) = (s[BLOCK], u16::from_le_bytes([s[BLOCK + 1], s[BLOCK + 2]]), s[BLOCK + 3]);
        s[..BLOCK].iter().all(|&x| x == 0) && crc == zeros.crc && (begin, end) != (0, 0)
    };
    let open = |image: &[u8; N], b: usize| slot::<BLOCK>(image, b)[BLOCK] != slot::<BLOCK>(image, b)[BLOCK + 3];
    let formatted = |b: usize| {
        let s = slot::<BLOCK>(&images[0], b);
        s[..BLOCK].iter().all(|&x| x == 0) && s[BLOCK..] == zeros.to_bytes()
    };
    let lost = |b: usize| settled_lost::<N, BLOCK>(images, b);
    let left_by_a_cut = |b: usize| lost(b) && staged(&images[0], b) && staged(&images[1], b) && (open(&images[0], b) || open(&images[1], b));
    (0..BLOCKS).any(lost) && ((0..BLOCKS).all(lost) || (0..BLOCKS).all(|b| (!lost(b) && formatted(b)) || left_by_a_cut(b)))
}

/// A first mount of any contents leaves settled banks that a mount would not format again;
/// its lost flags are exactly the blocks with no valid copy, and a lost block shows
/// `CHECKSUM_ERROR` in both banks. Banks that agree are mounted without a write or a status
/// bit. Returns the images it left.
pub fn prop_first_mount_settles<const N: usize, const BLOCKS: usize, const BLOCK: usize>(devices: [CutEeprom<'_, N>; 2]) -> [[u8; N]; 2] {
    let first = first_mount::<N, BLOCKS, BLOCK>(devices);
    let status = [first.status(0), first.status(1)];
    let after = images(&first);
    assert!(is_settled::<N, BLOCKS, BLOCK>(&after), "every block is lost or settled");
    for block in 0..BLOCKS {
        assert_eq!(first.is_lost(block), settled_lost::<N, BLOCK>(&after, block), "block {block}: lost exactly when no copy is valid");
        if first.is_lost(block) {
            assert!(status.iter().all(|s| s.bits() & BankStatus::CHECKSUM_ERROR != 0), "a lost block shows in both banks");
        }
    }
    assert!(!settled_mount_formats::<N, BLOCKS, BLOCK>(&after), "a first mount leaves nothing a mount would format");
    after
}

/// A mount of settled banks that it does not format writes nothing and changes nothing; it
/// finds exactly the blocks with no valid copy lost and sets `CHECKSUM_ERROR`, and nothing
/// else, in both banks exactly when there is one; reads return each block's committed data
/// or `Lost` and repair nothing. The caller ensures the precondition (settled, not formatted).
pub fn prop_settled_mount_is_quiet<const N: usize, const BLOCKS: usize, const BLOCK: usize>(mut devices: [CutEeprom<'_, N>; 2]) {
    assert_geometry::<N, BLOCKS, BLOCK>();
    devices[0].power().restore_power();
    let before = [*devices[0].as_bytes(), *devices[1].as_bytes()];
    assert!(
        is_settled::<N, BLOCKS, BLOCK>(&before) && !settled_mount_formats::<N, BLOCKS, BLOCK>(&before),
        "precondition: settled banks a mount does not format"
    );
    for d in &mut devices {
        d.reset_counts();
    }
    let mut banks = Banks::<N, BLOCKS, BLOCK>::mount(devices);
    assert_eq!(writes(&banks), 0, "a mount of settled banks writes nothing");
    let any_lost = (0..BLOCKS).any(|b| settled_lost::<N, BLOCK>(&before, b));
    let expected = BankStatus(if any_lost { BankStatus::CHECKSUM_ERROR } else { 0 });
    assert_eq!([banks.status(0), banks.status(1)], [expected; 2], "only lost blocks are reported, in both banks");
    for block in 0..BLOCKS {
        assert_eq!(banks.is_lost(block), settled_lost::<N, BLOCK>(&before, block), "block {block}: lost exactly when no copy is valid");
    }
    for (block, read) in contents(&mut banks).into_iter().enumerate() {
        let stored = &slot::<BLOCK>(&before[0], block)[..BLOCK];
        match read {
            Ok(data) => assert!(!settled_lost::<N, BLOCK>(&before, block) && data[..] == *stored, "block {block} reads its committed data"),
            Err(e) => assert!(settled_lost::<N, BLOCK>(&before, block) && e == Error::Lost { block }, "block {block} is lost"),
        }
    }
    assert!(same_images(&images(&banks), &before), "neither the mount nor the reads change a byte");
}

/// What a recovery cut at one step and the reboot after it found, against an uncut recovery
/// of the same contents.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RecoveryCutOutcome {
    pub fired: bool,
    /// Blocks that read differently from the uncut recovery.
    pub content_differs: usize,
    /// Blocks that an uncut recovery can read and that are lost now.
    pub lost: usize,
    /// The bank images differ from the uncut recovery's.
    pub image_differs: bool,
}

impl RecoveryCutOutcome {
    pub fn is_clean(&self) -> bool {
        self.content_differs == 0 && self.lost == 0 && !self.image_differs
    }
}

/// What an uncut recovery of some bank contents ends with.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Recovered<const N: usize, const BLOCKS: usize, const BLOCK: usize> {
    pub contents: [Result<[u8; BLOCK], Error>; BLOCKS],
    pub images: [[u8; N]; 2],
}

impl<const N: usize, const BLOCKS: usize, const BLOCK: usize> Recovered<N, BLOCKS, BLOCK> {
    /// Mounts a copy of `devices` with the power on.
    pub fn of(devices: &[CutEeprom<'_, N>; 2]) -> Self {
        devices[0].power().restore_power();
        let mut banks = Banks::<N, BLOCKS, BLOCK>::mount(devices.clone());
        Recovered { contents: contents_after_mount(&mut banks), images: images(&banks) }
    }

    /// What a mount left in `images`: reads right after a mount depend on the images alone
    /// ([`settled_contents`], the lemma [`contents_after_mount`] relies on).
    fn settled(images: [[u8; N]; 2]) -> Self {
        Recovered { contents: settled_contents::<N, BLOCKS, BLOCK>(&images), images }
    }
}

/// One mount of [`TwinEeprom`]s with the power cut at byte write `cut_at`: what the cut left,
/// whether it fired, and the images of the same mount uncut.
struct CutRecovery<const N: usize> {
    cut: [[u8; N]; 2],
    fired: bool,
    uncut: [[u8; N]; 2],
}

impl<const N: usize> CutRecovery<N> {
    fn run<const BLOCKS: usize, const BLOCK: usize>(devices: &[CutEeprom<'_, N>; 2], cut_at: u32, cut: CutByte) -> Self {
        let power = devices[0].power();
        power.restore_power();
        power.arm(cut_at, cut);
        let twins = MirroredBanks::<TwinEeprom<'_, N>, BLOCKS, BLOCK>::mount([TwinEeprom::new(&devices[0]), TwinEeprom::new(&devices[1])]);
        let fired = power.is_off();
        power.restore_power();
        let [a, b] = twins.banks();
        CutRecovery { cut: [*a.cut(), *b.cut()], fired, uncut: [*a.uncut(), *b.uncut()] }
    }

    /// The twins' cut images are what a real mount cut at `cut_at` leaves. (Their uncut images
    /// are compared with a real uncut mount by the callers.)
    #[cfg(not(kani))]
    fn assert_cut_is_a_real_cut<const BLOCKS: usize, const BLOCK: usize>(&self, devices: &[CutEeprom<'_, N>; 2], cut_at: u32, cut: CutByte) {
        let power = devices[0].power();
        power.arm(cut_at, cut);
        let cut_short = Banks::<N, BLOCKS, BLOCK>::mount(devices.clone());
        assert_eq!((self.cut, self.fired), (images(&cut_short), power.is_off()), "the twins' cut images are a cut mount's");
        power.restore_power();
    }

    /// Reboots the cut images and compares with `reference`.
    fn reboot<const BLOCKS: usize, const BLOCK: usize>(&self, power: &Power, reference: &Recovered<N, BLOCKS, BLOCK>) -> RecoveryCutOutcome {
        let (expected, expected_images) = (&reference.contents, &reference.images);
        let mut banks = Banks::<N, BLOCKS, BLOCK>::mount([CutEeprom::new(power, self.cut[0]), CutEeprom::new(power, self.cut[1])]);
        let now = contents_after_mount(&mut banks);
        RecoveryCutOutcome {
            fired: self.fired,
            content_differs: (0..BLOCKS).filter(|&b| now[b] != expected[b]).count(),
            lost: (0..BLOCKS).filter(|&b| now[b].is_err() && expected[b].is_ok()).count(),
            image_differs: !same_images(&images(&banks), expected_images),
        }
    }
}

/// Mounts `devices` with the power cut at byte write `cut_at` of the recovery, reboots, and
/// compares with an uncut mount of the same contents: two mounts of the banks, the first of
/// [`TwinEeprom`]s, whose uncut images are the reference.
pub fn check_recovery_cut<const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    devices: [CutEeprom<'_, N>; 2],
    cut_at: u32,
    cut: CutByte,
) -> RecoveryCutOutcome {
    assert_geometry::<N, BLOCKS, BLOCK>();
    let run = CutRecovery::run::<BLOCKS, BLOCK>(&devices, cut_at, cut);
    #[cfg(not(kani))]
    {
        run.assert_cut_is_a_real_cut::<BLOCKS, BLOCK>(&devices, cut_at, cut);
        assert_eq!(run.uncut, Recovered::<N, BLOCKS, BLOCK>::of(&devices).images, "the twins' uncut images are an uncut mount's");
    }
    run.reboot(devices[0].power(), &Recovered::<N, BLOCKS, BLOCK>::settled(run.uncut))
}

/// [`check_recovery_cut`] against a reference recovery computed once (with real mounts).
pub fn check_recovery_cut_against<const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    devices: [CutEeprom<'_, N>; 2],
    reference: &Recovered<N, BLOCKS, BLOCK>,
    cut_at: u32,
    cut: CutByte,
) -> RecoveryCutOutcome {
    assert_geometry::<N, BLOCKS, BLOCK>();
    let run = CutRecovery::run::<BLOCKS, BLOCK>(&devices, cut_at, cut);
    #[cfg(not(kani))]
    run.assert_cut_is_a_real_cut::<BLOCKS, BLOCK>(&devices, cut_at, cut);
    assert!(run.uncut == reference.images, "the twins' uncut images are the reference recovery's");
    run.reboot(devices[0].power(), reference)
}

/// A power cut at any byte of start-up recovery, then a reboot: the same contents and the same
/// bank images as an uncut recovery.
pub fn prop_recovery_cut<const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    devices: [CutEeprom<'_, N>; 2],
    cut_at: u32,
    cut: CutByte,
) -> RecoveryCutOutcome {
    let out = check_recovery_cut::<N, BLOCKS, BLOCK>(devices, cut_at, cut);
    assert!(out.is_clean(), "recovery cut at byte write {cut_at} ({cut:?}): {out:?}");
    out
}

/// Banks on `devices` with no status bit, no lost block and the scrub at block 0. The block
/// sums are 0: a `check_block` sets the ones it reads, and no bank image depends on them.
fn fresh_state<S: Storage, const BLOCKS: usize, const BLOCK: usize>(devices: [S; 2]) -> MirroredBanks<S, BLOCKS, BLOCK> {
    MirroredBanks::in_state(devices, [BankStatus::default(); 2], [[0; BLOCKS]; 2], [false; BLOCKS], 0)
}

/// The recovery cut, one block at a time: `check_block(block)` of any contents (the steps a
/// mount takes for each block: both copies loaded, then settled) cut at byte write `cut_at`,
/// then `check_block(block)` again on what the cut left, uncut. The second leaves the bank
/// images an uncut first one leaves, and the same lost flag; neither touches another block's
/// slots; a block that ends lost is never written; the block's copy that wins keeps a valid
/// copy in place through any cut; and a block that ends not lost holds the same valid copy
/// in both banks. With [`prop_format_cut_of_settled_banks`] this gives
/// [`prop_recovery_cut`] for any contents (the argument: verification/README.md, stop 42).
pub fn prop_block_recovery_cut<const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    devices: [CutEeprom<'_, N>; 2],
    block: usize,
    cut_at: u32,
    cut: CutByte,
) {
    assert_geometry::<N, BLOCKS, BLOCK>();
    let power = devices[0].power();
    power.restore_power();
    let before = [*devices[0].as_bytes(), *devices[1].as_bytes()];
    power.arm(cut_at, cut);
    let mut twins: MirroredBanks<TwinEeprom<'_, N>, BLOCKS, BLOCK> = fresh_state([TwinEeprom::new(&devices[0]), TwinEeprom::new(&devices[1])]);
    let _ = twins.check_block(block);
    let fired = power.is_off();
    power.restore_power();
    let lost = twins.is_lost(block);
    let [a, b] = twins.banks();
    let (cut_images, uncut) = ([*a.cut(), *b.cut()], [*a.uncut(), *b.uncut()]);
    let mut again: Banks<'_, N, BLOCKS, BLOCK> = fresh_state([CutEeprom::new(power, cut_images[0]), CutEeprom::new(power, cut_images[1])]);
    let _ = again.check_block(block);
    assert!(same_images(&images(&again), &uncut), "block {block}, cut at {cut_at} ({cut:?}): checked again, not what an uncut check leaves");
    assert_eq!(again.is_lost(block), lost, "block {block}, cut at {cut_at} ({cut:?}): lost differs");
    if lost {
        assert!(!fired && same_images(&uncut, &before), "block {block}: a lost block was written");
    } else {
        assert!(copy_is_valid::<BLOCK>(&uncut[0], block) && slot::<BLOCK>(&uncut[0], block) == slot::<BLOCK>(&uncut[1], block), "block {block}: not settled");
    }
    if fired {
        assert!(copy_is_valid::<BLOCK>(&cut_images[0], block) || copy_is_valid::<BLOCK>(&cut_images[1], block), "block {block}: a cut left no valid copy");
    }
    for other in 0..BLOCKS {
        for bank in 0..2 {
            let kept = slot::<BLOCK>(&before[bank], other);
            assert!(
                other == block || (slot::<BLOCK>(&uncut[bank], other) == kept && slot::<BLOCK>(&cut_images[bank], other) == kept),
                "block {block}: block {other} changed"
            );
        }
    }
}

/// The recovery cut of settled banks (every block lost or the same valid copy in both banks,
/// what the block steps of any mount leave): [`prop_recovery_cut`] on them. A mount of such
/// banks writes nothing before its format, if it formats, so every cut falls in the format.
pub fn prop_format_cut_of_settled_banks<const N: usize, const BLOCKS: usize, const BLOCK: usize>(devices: [CutEeprom<'_, N>; 2], cut_at: u32, cut: CutByte) {
    let images = [*devices[0].as_bytes(), *devices[1].as_bytes()];
    assert!(is_settled::<N, BLOCKS, BLOCK>(&images), "precondition: settled banks");
    prop_recovery_cut::<N, BLOCKS, BLOCK>(devices, cut_at, cut);
}

// ---------------------------------------------------------------------------------------------
// (c) Corruption.

/// How a corruption is looked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Detect {
    /// A reboot.
    Mount,
    /// A read of the whole affected block.
    Read,
    /// `check_block` of the affected block.
    CheckBlock,
}

impl Detect {
    pub fn select(selector: u8) -> Detect {
        match selector % 3 {
            0 => Detect::Mount,
            1 => Detect::Read,
            _ => Detect::CheckBlock,
        }
    }
}

/// Looks for a corruption in `block`; a `Read` returns what the read of the block returned.
fn detect<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    mut banks: Banks<'p, N, BLOCKS, BLOCK>,
    block: usize,
    via: Detect,
) -> (Banks<'p, N, BLOCKS, BLOCK>, Option<Result<[u8; BLOCK], Error>>) {
    match via {
        Detect::Mount => return (Banks::mount(banks.into_banks()), None),
        Detect::Read => {
            let mut out = [0; BLOCK];
            let read = banks.read(block * BLOCK, &mut out).map(|()| out);
            return (banks, Some(read));
        }
        Detect::CheckBlock => {
            let _ = banks.check_block(block);
        }
    }
    (banks, None)
}

/// What one single-byte corruption led to.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CorruptionOutcome {
    /// The value differed from the stored byte (otherwise nothing was corrupted).
    pub applied: bool,
    /// The corrupted bank's status shows 0x10 or 0x20.
    pub detected: bool,
    /// The intact bank's status shows an error.
    pub blamed_intact: bool,
    /// Both bank images are byte for byte what they were before the corruption.
    pub repaired: bool,
    /// Every block reads back its contents from before the corruption.
    pub content_kept: bool,
    /// The bank sums equal a recomputation.
    pub checksum_ok: bool,
}

impl CorruptionOutcome {
    pub fn is_clean(&self) -> bool {
        !self.applied || (self.detected && !self.blamed_intact && self.repaired && self.content_kept && self.checksum_ok)
    }
}

/// Sets byte `pos` of bank `bank` to `value` in settled banks (identical images, every block
/// valid, status cleared), looks for it `via`, and checks the repair. The banks come back for
/// the next case, with the status cleared.
pub fn check_single_corruption<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    mut banks: Banks<'p, N, BLOCKS, BLOCK>,
    bank: usize,
    pos: usize,
    value: u8,
    via: Detect,
) -> (Banks<'p, N, BLOCKS, BLOCK>, CorruptionOutcome) {
    assert_geometry::<N, BLOCKS, BLOCK>();
    let (bank, pos) = (bank % 2, pos % N);
    let block = pos / slot_size(BLOCK);
    let before = images(&banks);
    assert!(before[0] == before[1] && copy_is_valid::<BLOCK>(&before[0], block), "precondition: settled banks");
    assert_eq!(banks.status(0).bits() | banks.status(1).bits(), 0, "precondition: status cleared");
    let mut expected = [[0; BLOCK]; BLOCKS];
    for (block, e) in expected.iter_mut().enumerate() {
        e.copy_from_slice(slot::<BLOCK>(&before[0], block).get(..BLOCK).unwrap_or(&[0; BLOCK]));
    }
    let mut out = CorruptionOutcome { applied: before[bank][pos] != value, ..CorruptionOutcome::default() };
    banks.banks_mut()[bank].as_bytes_mut()[pos] = value;
    let (mut banks, read) = detect(banks, block, via);
    // A read compares the data bytes of the two banks: it must return the right data whatever
    // was corrupted, but finds only corrupted data bytes. A record byte is left to check_block.
    let read_right = read.is_none_or(|r| r.as_ref() == expected.get(block).ok_or(&Error::OutOfRange));
    if via == Detect::Read && pos % slot_size(BLOCK) >= BLOCK {
        let _ = banks.check_block(block);
    }
    let errors = BankStatus::CHECKSUM_ERROR | BankStatus::OVERWRITTEN;
    out.detected = banks.status(bank).bits() & errors != 0;
    out.blamed_intact = banks.status(1 - bank).is_error();
    out.repaired = same_images(&images(&banks), &before);
    let now = contents(&mut banks);
    out.content_kept = read_right && (0..BLOCKS).all(|b| now[b].as_ref() == Ok(&expected[b]));
    out.checksum_ok = checksum_errors(&banks) == 0;
    banks.clear_status(0);
    banks.clear_status(1);
    (banks, out)
}

/// Any single-byte corruption of either bank (data or record) is detected on the corrupted
/// bank, by a reboot, a read of the block or `check_block`, and repaired from the other bank:
/// contents and both images as before, and a read in between returns the right data.
/// (`Read` compares the data bytes of the two banks, so it finds corrupted data bytes; for a
/// record byte the read is followed by `check_block`.)
pub fn prop_single_corruption<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    banks: Banks<'p, N, BLOCKS, BLOCK>,
    bank: usize,
    pos: usize,
    value: u8,
    via: Detect,
) -> Banks<'p, N, BLOCKS, BLOCK> {
    let (banks, out) = check_single_corruption(banks, bank, pos, value, via);
    assert!(out.is_clean(), "bank {bank} byte {pos} := {value:#04X} via {via:?}: {out:?}");
    banks
}

/// What corrupting one block in both banks led to.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DoubleOutcome {
    /// Both values differed from the stored bytes.
    pub applied: bool,
    /// `is_lost`, `Err(Lost)` for a read of any single byte and for the whole block, and 0x10
    /// in both banks' status.
    pub reported_lost: bool,
    /// A read of some byte of the block returned data.
    pub data_returned: bool,
    /// Every other block reads back its contents from before.
    pub others_kept: bool,
    /// A one-byte write restarts the block from zeros and sets 0x40 in both banks.
    pub restarted: bool,
    /// Found by a read: the read answered `Lost`, or both banks hold the very bytes it
    /// returned. A read compares the banks' data (the datasheet's "different data within the
    /// two memory banks") and checks a block's CRCs only when they differ, so a corruption
    /// that leaves the data of both copies equal (in their records, or the same value at the
    /// same byte) is first seen by `check_block`, the scrub or a reboot.
    pub read_agreed: bool,
}

impl DoubleOutcome {
    pub fn is_clean(&self) -> bool {
        !self.applied || (self.read_agreed && self.reported_lost && !self.data_returned && self.others_kept && self.restarted)
    }
}

/// Corrupts byte `offsets[i]` of block `block`'s slot in bank `i` with `values[i]` in settled
/// banks, looks for it via a reboot, `check_block`, or a read of the block followed by
/// `check_block`, then reads every byte of the block and restarts it with a write.
pub fn check_double_corruption<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    mut banks: Banks<'p, N, BLOCKS, BLOCK>,
    block: usize,
    offsets: [usize; 2],
    values: [u8; 2],
    via: Detect,
) -> (Banks<'p, N, BLOCKS, BLOCK>, DoubleOutcome) {
    let block = block % BLOCKS;
    let (before, applied) = corrupt_both::<N, BLOCKS, BLOCK>(banks.banks_mut(), block, offsets, values);
    let corrupted = images(&banks);
    let (banks, found) = detect(banks, block, via);
    double_outcome(banks, block, &before, &corrupted, applied, found, via)
}

/// The reboot case of [`check_double_corruption`] on banks that are powered off: the
/// corruption is made in the EEPROMs and found by the first mount. Banks that agree mount
/// without a write and with a clean state (`prop_recovery_idempotent`), so this is the same
/// as mounting them, corrupting them and rebooting, with one mount of symbolic banks fewer
/// for Kani.
pub fn check_double_corruption_at_boot<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    mut devices: [CutEeprom<'p, N>; 2],
    block: usize,
    offsets: [usize; 2],
    values: [u8; 2],
) -> (Banks<'p, N, BLOCKS, BLOCK>, DoubleOutcome) {
    let block = block % BLOCKS;
    let (before, applied) = corrupt_both::<N, BLOCKS, BLOCK>(&mut devices, block, offsets, values);
    let corrupted = [*devices[0].as_bytes(), *devices[1].as_bytes()];
    let banks = Banks::mount(devices);
    double_outcome(banks, block, &before, &corrupted, applied, None, Detect::Mount)
}

/// Sets byte `offsets[i]` of `block`'s slot in bank `i` to `values[i]` in banks that agree;
/// returns the images from before and whether both values differed from the stored bytes.
fn corrupt_both<const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    devices: &mut [CutEeprom<'_, N>; 2],
    block: usize,
    offsets: [usize; 2],
    values: [u8; 2],
) -> ([[u8; N]; 2], bool) {
    assert_geometry::<N, BLOCKS, BLOCK>();
    let before = [*devices[0].as_bytes(), *devices[1].as_bytes()];
    assert!(before[0] == before[1], "precondition: settled banks");
    let mut applied = true;
    for (bank, device) in devices.iter_mut().enumerate() {
        let (offset, value) = (offsets[bank], values[bank]);
        let pos = block * slot_size(BLOCK) + offset % slot_size(BLOCK);
        applied &= before[bank][pos] != value;
        device.as_bytes_mut()[pos] = value;
    }
    (before, applied)
}

/// After a double corruption of `block` was looked for (`found`: what a first read of it
/// returned): reads every byte of the block, checks the others and restarts it with a write.
fn double_outcome<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    mut banks: Banks<'p, N, BLOCKS, BLOCK>,
    block: usize,
    before: &[[u8; N]; 2],
    corrupted: &[[u8; N]; 2],
    applied: bool,
    found: Option<Result<[u8; BLOCK], Error>>,
    via: Detect,
) -> (Banks<'p, N, BLOCKS, BLOCK>, DoubleOutcome) {
    let mut expected = [[0; BLOCK]; BLOCKS];
    for (b, e) in expected.iter_mut().enumerate() {
        e.copy_from_slice(slot::<BLOCK>(&before[0], b).get(..BLOCK).unwrap_or(&[0; BLOCK]));
    }
    let lost = Err(Error::Lost { block });
    let held = |bank: usize, data: &[u8; BLOCK]| slot::<BLOCK>(&corrupted[bank], block).get(..BLOCK) == Some(data);
    let read_agreed = match found {
        None => true,
        Some(Ok(data)) => held(0, &data) && held(1, &data),
        Some(Err(e)) => Err(e) == lost,
    };
    if via == Detect::Read {
        // The rest is what `check_block` (or the scrub) finds.
        let _ = banks.check_block(block);
    }
    let mut out = DoubleOutcome { applied, read_agreed, ..DoubleOutcome::default() };
    let mut every_read_lost = banks.read(block * BLOCK, &mut [0; BLOCK]) == lost;
    for at in 0..BLOCK {
        let r = banks.read(block * BLOCK + at, &mut [0]);
        every_read_lost &= r == lost;
        out.data_returned |= r.is_ok();
    }
    let flagged = (0..2).all(|b| banks.status(b).bits() & BankStatus::CHECKSUM_ERROR != 0);
    out.reported_lost = banks.is_lost(block) && every_read_lost && flagged;
    let now = contents(&mut banks);
    out.others_kept = (0..BLOCKS).all(|b| b == block || now[b].as_ref() == Ok(&expected[b]));
    let mut restarted = [0; BLOCK];
    if let Some(first) = restarted.first_mut() {
        *first = 0xA5;
    }
    let write = banks.write(block * BLOCK, &restarted[..BLOCK.min(1)]);
    let mut back = [0xEE; BLOCK];
    let read = banks.read(block * BLOCK, &mut back);
    let cleared = (0..2).all(|b| banks.status(b).bits() & BankStatus::CLEARED != 0);
    out.restarted = write.is_ok() && read.is_ok() && back == restarted && cleared && !banks.is_lost(block);
    (banks, out)
}

/// Corrupting the same block in both banks: the block is reported lost, every read of it
/// fails with `Lost` and never returns data, other blocks are untouched, and a write restarts
/// it from zeros.
pub fn prop_double_corruption<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    banks: Banks<'p, N, BLOCKS, BLOCK>,
    block: usize,
    offsets: [usize; 2],
    values: [u8; 2],
    via: Detect,
) -> Banks<'p, N, BLOCKS, BLOCK> {
    let (banks, out) = check_double_corruption(banks, block, offsets, values, via);
    assert!(out.is_clean(), "block {block} corrupted at {offsets:?} := {values:?} via {via:?}: {out:?}");
    banks
}

/// [`prop_double_corruption`] by a reboot of banks corrupted while powered off.
pub fn prop_double_corruption_at_boot<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    devices: [CutEeprom<'p, N>; 2],
    block: usize,
    offsets: [usize; 2],
    values: [u8; 2],
) -> Banks<'p, N, BLOCKS, BLOCK> {
    let (banks, out) = check_double_corruption_at_boot(devices, block, offsets, values);
    assert!(out.is_clean(), "block {block} corrupted at {offsets:?} := {values:?} at boot: {out:?}");
    banks
}

// ---------------------------------------------------------------------------------------------
// (d) Bank sums and (e) totality: operation sequences.

/// One operation on the banks, decoded from six bytes so that Kani, the exhaustive tests and
/// random tests can draw them: `op[0] % 7` selects it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    /// Write `len` bytes `value, value + step, ...` at `addr` (possibly out of range).
    Write {
        addr: usize,
        len: usize,
        value: u8,
        step: u8,
    },
    /// The same write, with the power cut at byte write `cut_at`, then a reboot.
    CutWrite {
        addr: usize,
        len: usize,
        value: u8,
        cut_at: u32,
        cut: CutByte,
    },
    /// Set byte `pos` of bank `bank` to `value`, then `check_block` of its block.
    Corrupt {
        bank: usize,
        pos: usize,
        value: u8,
    },
    Read {
        addr: usize,
        len: usize,
    },
    CheckBlock(usize),
    Scrub,
    Reboot,
}

/// The longest write or read of an [`Op`].
pub const MAX_OP_LEN: usize = 256;

impl Op {
    pub fn decode<const N: usize, const BLOCKS: usize, const BLOCK: usize>(op: [u8; 6]) -> Op {
        let [kind, a, b, c, d, e] = op;
        let wide = usize::from(u16::from_le_bytes([a, b]));
        // Addresses up to one past the data area, lengths up to two blocks and one byte: the
        // out-of-range cases are drawn too.
        let addr = wide % (BLOCKS * BLOCK + 1);
        let len = usize::from(c) % (2 * BLOCK + 2).min(MAX_OP_LEN + 1);
        match kind % 7 {
            0 => Op::Write { addr, len, value: d, step: e },
            1 => Op::CutWrite { addr, len, value: d, cut_at: u32::from(e), cut: CutByte::select(kind / 7, d ^ e) },
            2 => Op::Corrupt { bank: usize::from(a & 1), pos: usize::from(u16::from_le_bytes([b, c])) % N, value: d },
            3 => Op::Read { addr, len },
            4 => Op::CheckBlock(usize::from(d) % (BLOCKS + 1)),
            5 => Op::Scrub,
            _ => Op::Reboot,
        }
    }
}

fn pattern(len: usize, value: u8, step: u8) -> [u8; MAX_OP_LEN] {
    let mut data = [0; MAX_OP_LEN];
    let mut v = value;
    for d in data.iter_mut().take(len) {
        *d = v;
        v = v.wrapping_add(step);
    }
    data
}

/// A write of `len` bytes of `pattern(value, 1)` at `addr` with the power cut at byte write
/// `cut_at`, leaving `cut`; the power is back afterwards, before any reboot. Returns what the
/// write answered and whether the cut fired.
pub fn cut_write<const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    banks: &mut Banks<'_, N, BLOCKS, BLOCK>,
    addr: usize,
    len: usize,
    value: u8,
    cut_at: u32,
    cut: CutByte,
) -> (Result<(), Error>, bool) {
    let power = banks.banks()[0].power();
    let data = pattern(len, value, 1);
    power.arm(cut_at, cut);
    let result = banks.write(addr, data.get(..len).unwrap_or(&[]));
    let fired = power.is_off();
    power.restore_power();
    (result, fired)
}

/// Runs `op` on the banks (no assertion: [`prop_checksum_after_ops`] and [`prop_banks_total`]
/// say what must hold after it).
pub fn apply<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(mut banks: Banks<'p, N, BLOCKS, BLOCK>, op: Op) -> Banks<'p, N, BLOCKS, BLOCK> {
    match op {
        Op::Write { addr, len, value, step } => {
            let data = pattern(len, value, step);
            let _ = banks.write(addr, data.get(..len).unwrap_or(&[]));
        }
        Op::CutWrite { addr, len, value, cut_at, cut } => {
            let _ = cut_write(&mut banks, addr, len, value, cut_at, cut);
            return Banks::mount(banks.into_banks());
        }
        Op::Corrupt { bank, pos, value } => {
            if let Some(byte) = banks.banks_mut().get_mut(bank).and_then(|d| d.as_bytes_mut().get_mut(pos)) {
                *byte = value;
            }
            let _ = banks.check_block(pos / slot_size(BLOCK));
        }
        Op::Read { addr, len } => {
            let mut out = [0; MAX_OP_LEN];
            let _ = banks.read(addr, out.get_mut(..len).unwrap_or(&mut []));
        }
        Op::CheckBlock(block) => {
            let _ = banks.check_block(block);
        }
        Op::Scrub => {
            let _ = banks.scrub_next();
        }
        Op::Reboot => return Banks::mount(banks.into_banks()),
    }
    banks
}

/// After mounting any contents and after every operation of any sequence (writes, writes cut
/// at any byte and rebooted, corruption then `check_block`, reads, checks, scrubs, reboots),
/// the incremental sum of each bank equals the sum of its data bytes recomputed from the
/// EEPROM. A cut write is also checked before the reboot.
pub fn prop_checksum_after_ops<const N: usize, const BLOCKS: usize, const BLOCK: usize>(devices: [CutEeprom<'_, N>; 2], ops: &[[u8; 6]]) {
    assert_geometry::<N, BLOCKS, BLOCK>();
    let power = devices[0].power();
    power.restore_power();
    let mut banks = Banks::<N, BLOCKS, BLOCK>::mount(devices);
    assert_eq!(checksum_errors(&banks), 0, "after mount");
    for (i, &bytes) in ops.iter().enumerate() {
        let op = Op::decode::<N, BLOCKS, BLOCK>(bytes);
        if let Op::CutWrite { addr, len, value, cut_at, cut } = op {
            // The sums right after the cut, before the reboot.
            let _ = cut_write(&mut banks, addr, len, value, cut_at, cut);
            assert_eq!(checksum_errors(&banks), 0, "right after operation {i} {op:?}");
            banks = Banks::mount(banks.into_banks());
        } else {
            banks = apply(banks, op);
        }
        assert_eq!(checksum_errors(&banks), 0, "after operation {i} {op:?}");
    }
}

/// Any bank contents, either bank possibly not answering, any operations: nothing panics.
/// After the mount every block is lost or identical and valid in both banks (when both
/// answer); a read of a block that is not lost succeeds; writes are refused while a bank does
/// not answer.
pub fn prop_banks_total<const N: usize, const BLOCKS: usize, const BLOCK: usize>(mut devices: [CutEeprom<'_, N>; 2], unreadable: [bool; 2], ops: &[[u8; 6]]) {
    assert_geometry::<N, BLOCKS, BLOCK>();
    devices[0].power().restore_power();
    for (bank, d) in devices.iter_mut().enumerate() {
        d.set_unreadable(unreadable[bank]);
    }
    let mut banks = Banks::<N, BLOCKS, BLOCK>::mount(devices);
    let both = unreadable == [false, false];
    check_mounted(&mut banks, both);
    if !both && BLOCKS * BLOCK > 0 {
        assert_eq!(banks.write(0, &[0]), Err(Error::Access), "no write while a bank does not answer");
    }
    for &bytes in ops {
        banks = apply(banks, Op::decode::<N, BLOCKS, BLOCK>(bytes));
        // Out-of-range queries answer too.
        let _ = (banks.status(2), banks.checksum(2), banks.is_lost(BLOCKS));
        banks.clear_status(2);
    }
}

/// Right after a mount: every block is lost or identical and valid in both banks (when `both`
/// answer), and a read of each block succeeds exactly when it is not lost.
fn check_mounted<const N: usize, const BLOCKS: usize, const BLOCK: usize>(banks: &mut Banks<'_, N, BLOCKS, BLOCK>, both: bool) {
    for block in 0..BLOCKS {
        let [a, b] = images(banks);
        let settled = copy_is_valid::<BLOCK>(&a, block) && slot::<BLOCK>(&a, block) == slot::<BLOCK>(&b, block);
        assert!(!both || banks.is_lost(block) || settled, "block {block} neither lost nor settled");
        let read = banks.read(block * BLOCK, &mut [0; BLOCK]);
        assert_eq!(read.is_ok(), !banks.is_lost(block), "block {block}: {read:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// (d) One operation at a time, from any state a running device can hold.
//
// `prop_checksum_after_ops` and `prop_banks_total` run sequences of operations; Kani cannot
// take many symbolic operations in a row (each may be a reboot, a mount of symbolic banks).
// `prop_step` takes one operation from any running state instead: a state built by
// `MirroredBanks::in_state` with any images, status, lost flags and scrub position, and the
// per-block sums equal to the images'. Nothing panics, and the sums stay right; a reboot
// (`Op::Reboot`, a mount that ignores the state before it) leaves them right from any
// contents. By induction both properties then hold for any number of operations, not only
// for the bounded sequences of the sequence properties.

/// Banks in any running state: `devices` hold any images, a bank answers nothing when
/// `unreadable` says so, and `status`, `lost` and `scrub_at` are anything; each block's sum
/// equals its data bytes in that image, the invariant [`prop_step`] carries forward.
pub fn running_banks<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    mut devices: [CutEeprom<'p, N>; 2],
    unreadable: [bool; 2],
    status: [u8; 2],
    lost: [bool; BLOCKS],
    scrub_at: usize,
) -> Banks<'p, N, BLOCKS, BLOCK> {
    assert_geometry::<N, BLOCKS, BLOCK>();
    devices[0].power().restore_power();
    let mut sums = [[0_u16; BLOCKS]; 2];
    for (bank, d) in devices.iter_mut().enumerate() {
        for (block, sum) in sums[bank].iter_mut().enumerate() {
            for &b in &slot::<BLOCK>(d.as_bytes(), block)[..BLOCK] {
                *sum = sum.wrapping_add(u16::from(b));
            }
        }
        d.set_unreadable(unreadable[bank]);
    }
    Banks::in_state(devices, [BankStatus(status[0]), BankStatus(status[1])], sums, lost, scrub_at)
}

/// One operation on `banks` (a [`running_banks`] state whose banks answer unless
/// `unreadable` says otherwise): nothing panics; while both banks answer, the bank sums still
/// equal a recomputation afterwards; while one does not, a write changes no byte of either
/// bank. A cut write is taken up to the cut, with the power back ([`cut_write`]); the reboot
/// after it is an [`Op::Reboot`] step, which also checks what [`prop_banks_total`] checks
/// after its mount.
pub fn prop_step<const N: usize, const BLOCKS: usize, const BLOCK: usize>(mut banks: Banks<'_, N, BLOCKS, BLOCK>, unreadable: [bool; 2], op: Op) {
    let both = unreadable == [false, false];
    assert_eq!(checksum_errors(&banks), 0, "precondition: the sums are right");
    let before = images(&banks);
    let banks = match op {
        Op::CutWrite { addr, len, value, cut_at, cut } => {
            // A write the cut stopped never answers `Ok`: so a write across blocks, which goes
            // on to its next piece only after an `Ok` (`prop_pieces_partition`), starts that
            // piece with the power on.
            let (result, fired) = cut_write(&mut banks, addr, len, value, cut_at, cut);
            assert!(!(fired && result.is_ok()), "{op:?} answered Ok although the cut stopped it");
            banks
        }
        Op::Reboot => {
            let mut banks = apply(banks, op);
            check_mounted(&mut banks, both);
            banks
        }
        op => apply(banks, op),
    };
    if both {
        assert_eq!(checksum_errors(&banks), 0, "after {op:?}");
    } else if matches!(op, Op::Write { .. } | Op::CutWrite { .. }) {
        assert!(same_images(&images(&banks), &before), "{op:?} changed a byte while a bank does not answer");
    }
}

/// A write across blocks is the writes of its pieces, one block each, in turn.
/// `MirroredBanks::write(addr, data)` checks the range, then calls `write_in_block` for each
/// [`MirroredBanks::piece`] of it (`k` from 0, up to the first `None`), and stops at the first
/// error. For any range `addr..addr + len` in the data area this checks that the pieces are
/// consecutive, cover the range and lie in one block each, and that the bytes of one piece,
/// written alone at their place, have that piece as their only one. So a write calls
/// `write_in_block` with the same arguments, in the same order, as writing its pieces one
/// after another (each only after the one before answered `Ok`): what every write within one
/// block keeps, from any state, every write keeps. The step harness of cut writes relies on
/// it to take writes within one block only (`harnesses.rs`).
pub fn prop_pieces_partition<const N: usize, const BLOCKS: usize, const BLOCK: usize>(addr: usize, len: usize) {
    let end = addr.checked_add(len).filter(|&e| e <= BLOCKS * BLOCK).expect("precondition: a range in the data area");
    let mut covered = 0;
    let mut ended = false;
    for k in 0..BLOCKS {
        let Some((block, at, range)) = Banks::<N, BLOCKS, BLOCK>::piece(addr, end, k) else {
            ended = true;
            continue;
        };
        assert!(!ended, "piece {k} of {len} bytes at {addr} comes after the last one");
        assert!(range.start == covered && range.start < range.end, "piece {k} of {len} bytes at {addr} does not follow the one before");
        let (from, to) = (addr + range.start, addr + range.end);
        assert!(block == from / BLOCK && at == from % BLOCK && at + range.len() <= BLOCK, "piece {k} of {len} bytes at {addr} is not in one block");
        assert!(
            Banks::<N, BLOCKS, BLOCK>::piece(from, to, 0) == Some((block, at, 0..range.len())),
            "piece {k} of {len} bytes at {addr} alone is another piece"
        );
        for j in 1..BLOCKS {
            assert!(Banks::<N, BLOCKS, BLOCK>::piece(from, to, j).is_none(), "piece {k} of {len} bytes at {addr} alone has more pieces");
        }
        covered = range.end;
    }
    assert_eq!(covered, len, "the pieces of {len} bytes at {addr} do not cover them");
}

// ---------------------------------------------------------------------------------------------
// Endurance and start-up cost (counts, not timings: deterministic).

/// What one operation cost the two EEPROMs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cost {
    pub what: &'static str,
    /// User operations measured together (the counts are totals).
    pub operations: u32,
    pub byte_writes: u32,
    pub byte_reads: u32,
    /// Programming cycles of the most-written cell (either bank) over the operations.
    pub max_cell_writes: u16,
}

fn cost<'p, const N: usize, const BLOCKS: usize, const BLOCK: usize>(
    what: &'static str,
    operations: u32,
    devices: &[CutEeprom<'p, N>; 2],
    op: impl FnOnce(&mut Banks<'p, N, BLOCKS, BLOCK>),
) -> Cost {
    devices[0].power().restore_power();
    let mut banks = Banks::<N, BLOCKS, BLOCK>::mount(devices.clone());
    reset_counts(&mut banks);
    op(&mut banks);
    let max_cell_writes = banks.banks().iter().map(|d| d.max_cell_writes()).max().unwrap_or(0);
    Cost { what, operations, byte_writes: writes(&banks), byte_reads: reads(&banks), max_cell_writes }
}

fn mount_cost<const N: usize, const BLOCKS: usize, const BLOCK: usize>(what: &'static str, mut devices: [CutEeprom<'_, N>; 2]) -> Cost {
    devices[0].power().restore_power();
    for d in &mut devices {
        d.reset_counts();
    }
    let banks = Banks::<N, BLOCKS, BLOCK>::mount(devices);
    let max_cell_writes = banks.banks().iter().map(|d| d.max_cell_writes()).max().unwrap_or(0);
    Cost { what, operations: 1, byte_writes: writes(&banks), byte_reads: reads(&banks), max_cell_writes }
}

/// The costs of writes, reads, checks and mounts, from `settled` (banks that agree, every
/// block valid, no byte 0xA5 or 0x5A so that the writes below change every byte they touch)
/// and `garbage` (the contents of a ruined bank). Needs `BLOCKS >= 2`.
pub fn endurance<const N: usize, const BLOCKS: usize, const BLOCK: usize>(settled: &[CutEeprom<'_, N>; 2], garbage: &[u8; N]) -> [Cost; 13] {
    assert_geometry::<N, BLOCKS, BLOCK>();
    let power = settled[0].power();
    let stored = settled[0].as_bytes()[0];
    let changed = |i: usize, round: usize| if (i + round).is_multiple_of(2) { 0xA5 } else { 0x5A };
    let block = core::array::from_fn::<u8, BLOCK, _>(|i| changed(i, 0));
    let mut erased = settled.clone();
    erased[1] = CutEeprom::erased(power);
    let mut ruined = settled.clone();
    *ruined[0].as_bytes_mut() = *garbage;
    [
        cost::<N, BLOCKS, BLOCK>("write 1 byte", 1, settled, |b| b.write(0, &[changed(0, 0)]).expect("write")),
        cost::<N, BLOCKS, BLOCK>("write 1 byte, value already stored", 1, settled, |b| b.write(0, &[stored]).expect("write")),
        cost::<N, BLOCKS, BLOCK>("write 1 block, every byte changed", 1, settled, |b| b.write(0, &block).expect("write")),
        cost::<N, BLOCKS, BLOCK>("write 1 block's length across 2 blocks", 1, settled, |b| b.write(BLOCK / 2, &block).expect("write")),
        cost::<N, BLOCKS, BLOCK>("write every block once, every byte changed", BLOCKS as u32, settled, |b| {
            for blk in 0..BLOCKS {
                b.write(blk * BLOCK, &block).expect("write");
            }
        }),
        cost::<N, BLOCKS, BLOCK>("1000 writes of 1 byte walking through one block", 1000, settled, |b| {
            for round in 0..1000 {
                b.write(round % BLOCK, &[changed(round % BLOCK, round / BLOCK + 1)]).expect("write");
            }
        }),
        cost::<N, BLOCKS, BLOCK>("read 1 byte", 1, settled, |b| b.read(0, &mut [0]).expect("read")),
        cost::<N, BLOCKS, BLOCK>("read 1 block", 1, settled, |b| b.read(0, &mut [0; BLOCK]).expect("read")),
        cost::<N, BLOCKS, BLOCK>("check_block (one scrub step)", 1, settled, |b| b.check_block(0).expect("check")),
        mount_cost::<N, BLOCKS, BLOCK>("mount, banks agree", settled.clone()),
        mount_cost::<N, BLOCKS, BLOCK>("mount, bank 2 erased (repair)", erased),
        mount_cost::<N, BLOCKS, BLOCK>("mount, bank 1 garbage (repair)", ruined),
        mount_cost::<N, BLOCKS, BLOCK>("mount, blank banks (format)", [CutEeprom::erased(power), CutEeprom::erased(power)]),
    ]
}

/// The endurance fixture on CO401Memory1's geometry: settled banks whose data bytes are all
/// below 0x50 (so the writes of [`endurance`] change every byte they touch), and a bank of
/// pseudo-random garbage.
pub fn co401memory1_fixture(power: &Power) -> ([CutEeprom<'_, 8448>; 2], [u8; 8448]) {
    let data: [[u8; 128]; 64] = core::array::from_fn(|b| core::array::from_fn(|i| ((i * 7 + b) % 0x50) as u8));
    let seqs: [u8; 64] = core::array::from_fn(|b| b as u8);
    let mut garbage = [0_u8; 8448];
    let mut x = 0x2545_F491_u32;
    for g in &mut garbage {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        *g = (x >> 24) as u8;
    }
    (committed_devices::<8448, 64, 128>(power, &data, &seqs), garbage)
}
