//! Kani harnesses: each calls one `prop_*` function with symbolic inputs up to a bound.
//! Run with `cargo kani -p coforge-verification` (see `.github/workflows/kani.yml`).

use crate::framing::*;
use crate::integrity::*;
use crate::stack::*;
use coforge_link::crc::Crc16;

static TABLES: [Crc16; 3] = [Crc16::new(PARAMS[0]), Crc16::new(PARAMS[1]), Crc16::new(PARAMS[2])];

fn any_table() -> &'static Crc16 {
    let i: usize = kani::any();
    kani::assume(i < TABLES.len());
    &TABLES[i]
}

#[kani::proof]
#[kani::unwind(9)]
fn crc_table_step_equals_bitwise() {
    prop_crc_table_step(any_table(), kani::any(), kani::any());
}

#[kani::proof]
#[kani::unwind(9)]
fn crc_equals_reference_up_to_4_bytes() {
    let data: [u8; 4] = kani::any();
    let len: usize = kani::any();
    kani::assume(len <= data.len());
    prop_crc_matches_reference(any_table(), &data[..len]);
}

#[kani::proof]
#[kani::unwind(17)]
fn crc_detects_bursts_up_to_16_bits_in_4_bytes() {
    let mut data: [u8; 4] = kani::any();
    prop_crc_detects_burst(&TABLES[0], &mut data, kani::any(), kani::any());
}

#[kani::proof]
fn sum32_update_step() {
    prop_sum32_step(kani::any(), kani::any(), kani::any());
}

#[kani::proof]
#[kani::unwind(9)]
fn sum32_update_equals_recompute_8_bytes() {
    let mut data: [u8; 8] = kani::any();
    prop_sum32_update(&mut data, kani::any(), kani::any());
}

#[kani::proof]
#[kani::unwind(17)]
fn nibble_round_trip() {
    let data: [u8; 15] = kani::any();
    let len: usize = kani::any();
    kani::assume(len <= 15);
    prop_nibble_round_trip(kani::any(), &data[..len]);
}

#[kani::proof]
#[kani::unwind(11)]
fn length_byte_round_trip_up_to_8_bytes() {
    let data: [u8; 8] = kani::any();
    let len: usize = kani::any();
    kani::assume(len <= 8);
    let extension: Option<u8> = if kani::any() { Some(kani::any()) } else { None };
    prop_length_byte_round_trip(kani::any(), &data[..len], extension);
}

#[kani::proof]
#[kani::unwind(12)]
fn start_crc_round_trip_up_to_6_bytes() {
    let data: [u8; 6] = kani::any();
    let len: usize = kani::any();
    kani::assume(len <= 6);
    prop_start_crc_round_trip(kani::any(), &data[..len]);
}

#[kani::proof]
#[kani::unwind(9)]
fn decoders_are_total_for_8_bytes() {
    let bytes: [u8; 8] = kani::any();
    let gaps: [u8; 8] = kani::any();
    prop_decoders_total(&bytes, &gaps);
}

#[kani::proof]
#[kani::unwind(14)]
fn resync_after_4_bytes_of_garbage() {
    let garbage: [u8; 4] = kani::any();
    let data: [u8; 2] = kani::any();
    prop_resync_after_garbage(&garbage, kani::any(), &data);
}

#[kani::proof]
#[kani::unwind(7)]
fn emcy_register_follows_active_errors_for_6_operations() {
    let ops: [u8; 6] = kani::any();
    prop_emcy_register(&ops);
}

#[kani::proof]
fn nmt_commands_address_only_this_node() {
    let payload: [u8; 3] = kani::any();
    let len: usize = kani::any();
    kani::assume(len <= payload.len());
    prop_nmt_parse(&payload[..len], kani::any());
}

#[kani::proof]
#[kani::unwind(9)]
fn sdo_first_request_answers_validly() {
    let request: [u8; 8] = kani::any();
    prop_sdo_first_request(&request);
}

/// The mirrored EEPROM banks (`crate::banks`) on the geometry of the state-space search
/// (`tests/banks_model.rs`): 2 blocks of 2 data bytes, 12 bytes per bank (each block is
/// followed by its 4-byte commit record). 2 blocks: a write can span blocks, so the commit
/// order and a cut between blocks are covered; 2 bytes: a write can change part of a block,
/// and a cut can fall between two data bytes. The write protocol (mark, changed data bytes,
/// CRC, begin, end) and the record are the same for any block size, and every cut point is a
/// single byte write. A write of both blocks is at most 2 x 2 x 7 = 28 byte writes, so a
/// symbolic `u32` cut step covers every cut point and "no cut".
///
/// The solver is kissat (part of Kani's bundle): the check-block corruption harness verified
/// in 20 min with it and had not left its first CaDiCaL round after 38 min
/// (verification/README.md).
mod mirrored_banks {
    use crate::banks::*;

    const BLOCKS: usize = 2;
    const BLOCK: usize = KANI_MAX_WRITE;
    const N: usize = BLOCKS * slot_size(BLOCK);

    type Devices<'p> = [CutEeprom<'p, N>; 2];

    /// Both banks holding any data, each block committed with any sequence number.
    fn any_committed(power: &Power) -> Devices<'_> {
        let data: [[u8; BLOCK]; BLOCKS] = kani::any();
        let seqs: [u8; BLOCKS] = kani::any();
        committed_devices::<N, BLOCKS, BLOCK>(power, &data, &seqs)
    }

    fn any_cut() -> CutByte {
        CutByte::select(kani::any(), kani::any())
    }

    /// Any bank contents.
    fn any_devices(power: &Power) -> Devices<'_> {
        [CutEeprom::new(power, kani::any()), CutEeprom::new(power, kani::any())]
    }

    /// (a) A write of `len` bytes of any data at `addr`, cut at any byte write with the byte
    /// old, new or any garbage, then a reboot: every block old or new. With the write's place
    /// and length constants, every address the write touches is a constant, and CBMC does
    /// not carry each byte write at every place a symbolic address could name (one harness
    /// for any place and length did not finish: 2.7 M steps and 16 GB before its solver).
    /// The harnesses below take every in-range place and length in turn (10 of them on 2
    /// blocks of 2 bytes: 4 bytes at 0 by its two one-block pieces, the other 9 each by a
    /// harness); `banks_write_cut_out_of_range_or_empty` takes the rest, so together they
    /// cover any write of 0..=5 bytes at 0..=5.
    fn write_cut(addr: usize, len: usize) {
        let power = Power::new();
        let data: [u8; BLOCKS * BLOCK] = kani::any();
        prop_write_cut::<N, BLOCKS, BLOCK>(any_committed(&power), addr, &data[..len], kani::any(), any_cut());
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_write_cut_of_1_byte_at_0_leaves_old_or_new() {
        write_cut(0, 1);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_write_cut_of_2_bytes_at_0_leaves_old_or_new() {
        write_cut(0, 2);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_write_cut_of_3_bytes_at_0_leaves_old_or_new() {
        write_cut(0, 3);
    }

    /// (a) A write of 4 bytes at 0 is the writes of 2 bytes at 0 and at 2 in turn
    /// (`banks_write_pieces_partition_any_range`). A cut in the first leaves what the 2-byte
    /// write cut at 0 leaves (the write ends there); otherwise the first leaves banks that agree
    /// (the harness below), and the cut falls in a 2-byte write at 2 of such banks. So the two
    /// one-block harnesses prove it; as one harness it took 36 to 46 minutes (stops 37 and 40).
    /// The other writes across blocks are proved both ways.
    ///
    /// The first piece of any write across blocks (the rest of block 0 from 0 or 1), uncut,
    /// leaves banks that agree, committed as a mount of them would find them.
    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_uncut_first_piece_keeps_banks_agreeing() {
        let power = Power::new();
        let data: [[u8; BLOCK]; BLOCKS] = kani::any();
        let seqs: [u8; BLOCKS] = kani::any();
        let bytes: [u8; BLOCK] = kani::any();
        let addr: usize = kani::any();
        kani::assume(addr < BLOCK);
        prop_uncut_first_piece_keeps_banks_agreeing::<N, BLOCKS, BLOCK>(&power, &data, &seqs, addr, &bytes[addr..]);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_write_cut_of_1_byte_at_1_leaves_old_or_new() {
        write_cut(1, 1);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_write_cut_of_2_bytes_at_1_leaves_old_or_new() {
        write_cut(1, 2);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_write_cut_of_3_bytes_at_1_leaves_old_or_new() {
        write_cut(1, 3);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_write_cut_of_1_byte_at_2_leaves_old_or_new() {
        write_cut(2, 1);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_write_cut_of_2_bytes_at_2_leaves_old_or_new() {
        write_cut(2, 2);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_write_cut_of_1_byte_at_3_leaves_old_or_new() {
        write_cut(3, 1);
    }

    /// (a) The rest: an empty write, or one past the data area (0..=5 bytes at 0..=5). It
    /// writes nothing and answers `Ok` or `OutOfRange`, and the banks are as before
    /// (`prop_write_outside`; until stop 36 the whole `prop_write_cut` with its reboot, which
    /// reached 1.6 M steps and 8 GB with the place and length symbolic).
    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_write_cut_out_of_range_or_empty() {
        let power = Power::new();
        let devices = any_committed(&power);
        let data: [u8; BLOCKS * BLOCK + 1] = kani::any();
        let addr: usize = kani::any();
        let len: usize = kani::any();
        kani::assume(addr <= BLOCKS * BLOCK + 1 && len <= data.len());
        kani::assume(len == 0 || addr + len > BLOCKS * BLOCK);
        prop_write_outside::<N, BLOCKS, BLOCK>(devices, addr, &data[..len], kani::any(), any_cut());
    }

    /// (b) Recovery is idempotent (`prop_recovery_idempotent`), in two halves: one harness of
    /// both mounts took 49 to 65 minutes; these two 9 and 12 (verification/README.md). First,
    /// any contents mounted once are left settled, not to be formatted, with lost flags and
    /// status to match (`prop_first_mount_settles`).
    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_first_mount_settles_any_contents() {
        let power = Power::new();
        prop_first_mount_settles::<N, BLOCKS, BLOCK>(any_devices(&power));
    }

    /// (b), second half: any settled banks that a mount does not format mount without a write
    /// or a change, and read back what they hold (`prop_settled_mount_is_quiet`).
    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_settled_banks_mount_quietly() {
        let power = Power::new();
        let images: [[u8; N]; 2] = kani::any();
        kani::assume(is_settled::<N, BLOCKS, BLOCK>(&images) && !settled_mount_formats::<N, BLOCKS, BLOCK>(&images));
        prop_settled_mount_is_quiet::<N, BLOCKS, BLOCK>([CutEeprom::new(&power, images[0]), CutEeprom::new(&power, images[1])]);
    }

    /// (b) Any contents, the recovery cut at any byte write with any byte left: the reboot
    /// ends with the contents and images of an uncut recovery. Proved in parts since stop 42
    /// (as one harness, `banks_recovery_cut_at_any_byte_for_any_contents`, it took 63 minutes
    /// in stop 38). A mount settles each block in turn (the steps of `check_block`: both
    /// copies loaded, then settled), then formats if it must. A cut while it settles block
    /// `b` leaves the blocks before `b` settled, `b` as a cut `check_block` leaves it, and the
    /// rest as they were; the reboot settles each of them as the uncut mount did (the
    /// harnesses per block below: a block settled already is a cut that never fired), so it
    /// takes the same format decision and ends the same. A cut in the format is the recovery
    /// cut of the settled banks the block steps left (`banks_format_cut_of_settled_banks`).
    /// The whole argument: verification/README.md, stop 42.
    fn block_recovery_cut(block: usize) {
        let power = Power::new();
        prop_block_recovery_cut::<N, BLOCKS, BLOCK>(any_devices(&power), block, kani::any(), any_cut());
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_recovery_cut_of_block_0_for_any_contents() {
        block_recovery_cut(0);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_recovery_cut_of_block_1_for_any_contents() {
        block_recovery_cut(1);
    }

    /// (b) Settled banks (each block lost or the same valid copy in both banks), the recovery
    /// cut at any byte write: only a format writes, and the reboot finishes it.
    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_format_cut_of_settled_banks() {
        let power = Power::new();
        let images: [[u8; N]; 2] = kani::any();
        kani::assume(is_settled::<N, BLOCKS, BLOCK>(&images));
        prop_format_cut_of_settled_banks::<N, BLOCKS, BLOCK>([CutEeprom::new(&power, images[0]), CutEeprom::new(&power, images[1])], kani::any(), any_cut());
    }

    /// (b) The format of blank (erased) banks, cut at any byte write.
    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_format_cut_at_any_byte() {
        let power = Power::new();
        let devices = [CutEeprom::erased(&power), CutEeprom::erased(&power)];
        prop_recovery_cut::<N, BLOCKS, BLOCK>(devices, kani::any(), any_cut());
    }

    /// (c) Any byte of either bank set to any other value is found `via` (a reboot, a read or
    /// `check_block`) and repaired from the other bank. One harness per way of looking: each
    /// is a third of the paths, and together they cover what one harness with a symbolic
    /// `Detect` would.
    fn single_corruption(via: Detect) {
        let power = Power::new();
        let banks = Banks::<N, BLOCKS, BLOCK>::mount(any_committed(&power));
        let bank: usize = kani::any();
        let pos: usize = kani::any();
        kani::assume(bank < 2 && pos < N);
        let value: u8 = kani::any();
        kani::assume(value != banks.banks()[bank].as_bytes()[pos]);
        prop_single_corruption(banks, bank, pos, value, via);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_single_corruption_is_found_by_a_reboot_and_repaired() {
        single_corruption(Detect::Mount);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_single_corruption_is_found_by_a_read_and_repaired() {
        single_corruption(Detect::Read);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_single_corruption_is_found_by_check_block_and_repaired() {
        single_corruption(Detect::CheckBlock);
    }

    /// (c) One block corrupted in both banks (any byte of each, any other values) is lost,
    /// never read as data, and a write restarts it; a read that comes first answers `Lost` or
    /// what both banks hold. Precondition of a reboot: the block is not what a format writes
    /// (zeros committed as sequence 0). One harness per way of looking, as for a single
    /// corruption, and per block: with the block a constant, its addresses are constants too,
    /// and CBMC does not carry every read and write at both blocks' places (with a symbolic
    /// block the reboot harness reached 21.8 GB before its solver). The reboot harnesses
    /// corrupt the banks before their first mount (`prop_double_corruption_at_boot`): banks
    /// that agree mount without a write or a status bit, which
    /// `banks_first_mount_settles_any_contents` proves, so a mount before the
    /// corruption would change nothing but the cost. For the same reason the read and
    /// `check_block` harnesses start from `mount_agreeing` (since stop 37): under Kani the
    /// state such a mount leaves, built by `in_state`; in every test a real mount checked
    /// against it.
    fn double_corruption(via: Detect, block: usize) {
        let power = Power::new();
        let data: [[u8; BLOCK]; BLOCKS] = kani::any();
        let seqs: [u8; BLOCKS] = kani::any();
        kani::assume(data[block] != [0; BLOCK] || seqs[block] != 0);
        let devices = committed_devices::<N, BLOCKS, BLOCK>(&power, &data, &seqs);
        let offsets: [usize; 2] = kani::any();
        let values: [u8; 2] = kani::any();
        let slot = slot_size(BLOCK);
        kani::assume(offsets[0] < slot && offsets[1] < slot);
        kani::assume(values[0] != devices[0].as_bytes()[block * slot + offsets[0]]);
        kani::assume(values[1] != devices[1].as_bytes()[block * slot + offsets[1]]);
        if via == Detect::Mount {
            prop_double_corruption_at_boot::<N, BLOCKS, BLOCK>(devices, block, offsets, values);
        } else {
            prop_double_corruption(mount_agreeing::<N, BLOCKS, BLOCK>(devices), block, offsets, values, via);
        }
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_double_corruption_of_block_0_found_by_a_reboot_is_lost() {
        double_corruption(Detect::Mount, 0);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_double_corruption_of_block_1_found_by_a_reboot_is_lost() {
        double_corruption(Detect::Mount, 1);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_double_corruption_of_block_0_found_by_a_read_is_lost() {
        double_corruption(Detect::Read, 0);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_double_corruption_of_block_1_found_by_a_read_is_lost() {
        double_corruption(Detect::Read, 1);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_double_corruption_of_block_0_found_by_check_block_is_lost() {
        double_corruption(Detect::CheckBlock, 0);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_double_corruption_of_block_1_found_by_check_block_is_lost() {
        double_corruption(Detect::CheckBlock, 1);
    }

    /// (d) One operation from any running state (`prop_step`): any images, either bank
    /// silent, any status bits, lost flags and scrub position, the per-block sums right.
    /// Nothing panics, the sums stay right while both banks answer, and a write changes no
    /// byte while one does not. With the reboot harness (a mount of any contents, which also
    /// checks what `prop_banks_total` checks after its mount) this is an induction over any
    /// number of operations. Until stop 36 two harnesses ran 3 and 2 symbolic operations
    /// after a mount (`banks_checksum_matches_after_3_operations`,
    /// `banks_are_total_for_any_contents`) and never ended: every operation could be a reboot.
    /// One harness per kind of operation, with the kind a constant, for the reason the
    /// corruption harnesses are one per way of looking.
    fn step(op: Op) {
        let power = Power::new();
        let unreadable: [bool; 2] = kani::any();
        let scrub_at: usize = kani::any();
        kani::assume(scrub_at < BLOCKS);
        let banks = running_banks::<N, BLOCKS, BLOCK>(any_devices(&power), unreadable, kani::any(), kani::any(), scrub_at);
        prop_step(banks, unreadable, op);
    }

    /// The block CRC the step harnesses run with, in place of `record::block_crc`: any value,
    /// chosen afresh at every call. Every run of the real code is a run of the code with this
    /// stub (the one whose choices happen to be the real CRCs), so what holds for every run
    /// with the stub holds for the real CRC. What `prop_step` asserts (the sums equal the
    /// data bytes, no byte changes while a bank is silent, no panic) never reads a CRC
    /// value, only the branches CRCs choose, and the stub lets every branch happen. The
    /// reboot step keeps the real CRC: it asserts that settled blocks are valid, which a CRC
    /// chosen afresh at every call would not repeat. With no CRC circuits the solver has
    /// less to do (the times before and after: verification/README.md, stop 41).
    fn any_block_crc<const BLOCK: usize>(_data: &[u8; BLOCK], _seq: u8) -> u16 {
        kani::any()
    }

    /// Any place and length `Op::decode` draws: addresses up to one past the data area,
    /// lengths up to two blocks and one byte.
    fn any_range() -> (usize, usize) {
        let (addr, len): (usize, usize) = (kani::any(), kani::any());
        kani::assume(addr <= BLOCKS * BLOCK && len <= 2 * BLOCK + 1);
        (addr, len)
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    #[kani::stub(coforge_storage::record::block_crc, any_block_crc)]
    fn banks_write_step_from_any_state() {
        let (addr, len) = any_range();
        step(Op::Write { addr, len, value: kani::any(), step: kani::any() });
    }

    /// Any place and length of [`any_range`] but those of a write across both blocks: a write
    /// within one block, an empty one, or one past the data area. A write across blocks is
    /// its two one-block writes in turn, the second only after the first answered `Ok`
    /// (`banks_write_pieces_partition_any_range`), and a write the cut stopped never answers
    /// `Ok` (`prop_step`): so the second starts from a running state with the power on and
    /// any cut still ahead, which this harness covers too.
    fn any_range_but_across_blocks() -> (usize, usize) {
        let (addr, len) = any_range();
        kani::assume(len == 0 || addr + len > BLOCKS * BLOCK || addr / BLOCK == (addr + len - 1) / BLOCK);
        (addr, len)
    }

    /// The induction step across the pieces of a write: what the cut-write step proves for
    /// writes within one block holds for every write. Pure arithmetic on `MirroredBanks::piece`.
    #[kani::proof]
    #[kani::unwind(3)]
    fn banks_write_pieces_partition_any_range() {
        let (addr, len): (usize, usize) = (kani::any(), kani::any());
        kani::assume(addr <= BLOCKS * BLOCK && len <= BLOCKS * BLOCK - addr);
        prop_pieces_partition::<N, BLOCKS, BLOCK>(addr, len);
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    #[kani::stub(coforge_storage::record::block_crc, any_block_crc)]
    fn banks_cut_write_step_from_any_state() {
        let (addr, len) = any_range_but_across_blocks();
        step(Op::CutWrite { addr, len, value: kani::any(), cut_at: kani::any(), cut: any_cut() });
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    #[kani::stub(coforge_storage::record::block_crc, any_block_crc)]
    fn banks_corruption_step_from_any_state() {
        let (bank, pos): (usize, usize) = (kani::any(), kani::any());
        kani::assume(bank < 2 && pos < N);
        step(Op::Corrupt { bank, pos, value: kani::any() });
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    #[kani::stub(coforge_storage::record::block_crc, any_block_crc)]
    fn banks_read_step_from_any_state() {
        let (addr, len) = any_range();
        step(Op::Read { addr, len });
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    #[kani::stub(coforge_storage::record::block_crc, any_block_crc)]
    fn banks_check_block_step_from_any_state() {
        let block: usize = kani::any();
        kani::assume(block <= BLOCKS);
        step(Op::CheckBlock(block));
    }

    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    #[kani::stub(coforge_storage::record::block_crc, any_block_crc)]
    fn banks_scrub_step_from_any_state() {
        step(Op::Scrub);
    }

    /// The base of the induction: a reboot mounts any contents (the state before it does not
    /// matter to a mount) with the sums right, every block lost or settled and readable
    /// exactly when not lost.
    #[kani::proof]
    #[kani::unwind(13)]
    #[kani::solver(kissat)]
    fn banks_reboot_step_from_any_state() {
        step(Op::Reboot);
    }
}
