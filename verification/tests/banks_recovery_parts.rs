//! The two parts the recovery-cut proof is made of (verification/README.md, stop 42), on the
//! Kani geometry (2 blocks of 2 bytes): a block's check cut at every byte write, then checked
//! again (`prop_block_recovery_cut`), and the recovery cut of settled banks
//! (`prop_format_cut_of_settled_banks`). The whole property they make up,
//! `prop_recovery_cut` for any contents, is tested directly in `banks_exhaustive.rs` and
//! `random.rs`.

use coforge_storage::record::Record;
use coforge_verification::banks::*;
use coforge_verification::rng::Rng;

const N: usize = 12;
const BLOCKS: usize = 2;
const BLOCK: usize = 2;
const SLOT: usize = BLOCK + 4;

/// A committed slot: `data`, then its record with `seq`.
fn committed(data: [u8; BLOCK], seq: u8) -> [u8; SLOT] {
    let mut slot = [0; SLOT];
    slot[..BLOCK].copy_from_slice(&data);
    slot[BLOCK..].copy_from_slice(&Record::committed(&data, seq).to_bytes());
    slot
}

/// One copy of a block, of the kinds a device meets: committed (data from a 3-value alphabet,
/// so that copies often agree), committed one step ahead, one byte changed, staged zeros as a
/// format cut leaves them, erased, or garbage.
fn copy(rng: &mut Rng, data: [u8; BLOCK], seq: u8) -> [u8; SLOT] {
    match rng.byte() % 7 {
        0 | 1 => committed(data, seq),
        2 => committed([rng.byte() % 3, rng.byte() % 3], seq.wrapping_add(1)),
        3 => {
            let mut slot = committed(data, seq);
            slot[usize::from(rng.byte()) % SLOT] ^= 1 << (rng.byte() % 8);
            slot
        }
        4 => {
            let mut slot = committed([0; BLOCK], 0);
            slot[BLOCK] = rng.byte() | 1;
            slot
        }
        5 => [0xFF; SLOT],
        _ => core::array::from_fn(|_| rng.byte()),
    }
}

fn any_images(rng: &mut Rng) -> [[u8; N]; 2] {
    let mut images = [[0; N]; 2];
    for block in 0..BLOCKS {
        let (data, seq) = ([rng.byte() % 3, rng.byte() % 3], rng.byte());
        for image in &mut images {
            image[block * SLOT..(block + 1) * SLOT].copy_from_slice(&copy(rng, data, seq));
        }
    }
    images
}

/// Settled images: each block the same committed copy in both banks (zeros as sequence 0 now
/// and then, what a format writes), or lost with both copies invalid (staged zeros now and
/// then, what a format cut leaves).
fn settled_images(rng: &mut Rng) -> [[u8; N]; 2] {
    let mut images = [[0; N]; 2];
    for block in 0..BLOCKS {
        let kind = rng.byte() % 4;
        let shared = match kind {
            0 => committed([0; BLOCK], 0),
            1 => committed([rng.byte() % 3, rng.byte() % 3], rng.byte()),
            _ => [0; SLOT],
        };
        for image in &mut images {
            let slot = match kind {
                0 | 1 => shared,
                _ => loop {
                    let c = copy(rng, [0; BLOCK], 0);
                    if !Record::from_bytes([c[BLOCK], c[BLOCK + 1], c[BLOCK + 2], c[BLOCK + 3]]).is_valid_for(&[c[0], c[1]]) {
                        break c;
                    }
                },
            };
            image[block * SLOT..(block + 1) * SLOT].copy_from_slice(&slot);
        }
    }
    images
}

fn cuts(rng: &mut Rng) -> [CutByte; 3] {
    [CutByte::Old, CutByte::New, CutByte::Garbage(rng.byte())]
}

#[test]
fn a_block_check_cut_at_every_byte_then_checked_again_ends_as_an_uncut_one() {
    let mut rng = Rng(0x0BAD_5EED_1234_5678);
    let (mut cases, mut written) = (0_u32, 0_u32);
    for _ in 0..3_000 {
        let images = any_images(&mut rng);
        for block in 0..BLOCKS {
            let power = Power::new();
            let steps = {
                let mut banks: Banks<'_, N, BLOCKS, BLOCK> =
                    running_banks([CutEeprom::new(&power, images[0]), CutEeprom::new(&power, images[1])], [false; 2], [0; 2], [false; BLOCKS], 0);
                power.reset_steps();
                let _ = banks.check_block(block);
                power.steps()
            };
            written += u32::from(steps > 0);
            for cut_at in 0..=steps {
                for cut in cuts(&mut rng) {
                    prop_block_recovery_cut::<N, BLOCKS, BLOCK>([CutEeprom::new(&power, images[0]), CutEeprom::new(&power, images[1])], block, cut_at, cut);
                    cases += 1;
                }
            }
        }
    }
    println!("{cases} block checks cut, {written} of 6000 blocks repaired");
    assert!(written > 1_500, "most contents need a repair");
}

#[test]
fn a_format_cut_at_every_byte_of_settled_banks_changes_nothing() {
    let mut rng = Rng(0x05EE_D0FF_04A7);
    let (mut cases, mut formatted) = (0_u32, 0_u32);
    for _ in 0..3_000 {
        let images = settled_images(&mut rng);
        assert!(is_settled::<N, BLOCKS, BLOCK>(&images));
        let power = Power::new();
        let steps = recovery_steps::<N, BLOCKS, BLOCK>(&[CutEeprom::new(&power, images[0]), CutEeprom::new(&power, images[1])]);
        assert_eq!(steps > 0, settled_mount_formats::<N, BLOCKS, BLOCK>(&images), "settled banks are written exactly when formatted");
        formatted += u32::from(steps > 0);
        for cut_at in 0..=steps {
            for cut in cuts(&mut rng) {
                prop_format_cut_of_settled_banks::<N, BLOCKS, BLOCK>([CutEeprom::new(&power, images[0]), CutEeprom::new(&power, images[1])], cut_at, cut);
                cases += 1;
            }
        }
    }
    println!("{cases} recovery cuts of settled banks, {formatted} of 3000 formatted");
    assert!(formatted > 300, "the formats are reached");
}
