//! A write across blocks is its one-block pieces written in turn: the induction step the
//! cut-write step harness relies on (`prop_pieces_partition`, harnesses.rs), checked here on
//! whole bank states. On the Kani geometry (2 blocks of 2 bytes): every range across both
//! blocks, from running states of every kind (committed, torn, garbage, a bank silent, any
//! status and lost flags), cut at every byte write with the byte old, new or garbage. The
//! partition itself is checked for every range of two geometries.

use coforge_storage::Error;
use coforge_verification::banks::*;
use coforge_verification::rng::Rng;

const N: usize = 12;
const BLOCKS: usize = 2;
const BLOCK: usize = 2;

/// A running state as `running_banks` builds it: committed banks with up to 3 bytes changed,
/// or garbage, a bank silent now and then, any status, lost flags and scrub position.
struct Start {
    images: [[u8; N]; 2],
    unreadable: [bool; 2],
    status: [u8; 2],
    lost: [bool; BLOCKS],
    scrub_at: usize,
}

impl Start {
    fn draw(rng: &mut Rng) -> Start {
        let mut images = if rng.byte().is_multiple_of(4) {
            core::array::from_fn(|_| core::array::from_fn(|_| rng.byte()))
        } else {
            let data = core::array::from_fn(|_| core::array::from_fn(|_| rng.byte() % 3));
            let seqs = core::array::from_fn(|_| rng.byte());
            let image = committed_image::<N, BLOCKS, BLOCK>(&data, &seqs);
            [image, image]
        };
        for _ in 0..rng.byte() % 4 {
            let (bank, pos) = (usize::from(rng.byte() % 2), usize::from(rng.byte()) % N);
            images[bank][pos] = rng.byte();
        }
        let unreadable = [rng.byte().is_multiple_of(8), rng.byte().is_multiple_of(8)];
        Start {
            images,
            unreadable,
            status: [rng.byte(), rng.byte()],
            lost: [rng.byte().is_multiple_of(2), rng.byte().is_multiple_of(2)],
            scrub_at: usize::from(rng.byte() % 2),
        }
    }

    fn banks<'p>(&self, power: &'p Power) -> Banks<'p, N, BLOCKS, BLOCK> {
        let devices = [CutEeprom::new(power, self.images[0]), CutEeprom::new(power, self.images[1])];
        running_banks::<N, BLOCKS, BLOCK>(devices, self.unreadable, self.status, self.lost, self.scrub_at)
    }
}

#[test]
fn the_pieces_of_every_range_partition_it() {
    let mut ranges = 0;
    for addr in 0..=BLOCKS * BLOCK {
        for len in 0..=BLOCKS * BLOCK - addr {
            prop_pieces_partition::<N, BLOCKS, BLOCK>(addr, len);
            ranges += 1;
        }
    }
    // A wider geometry too: 4 blocks of 8 bytes (4 x 12 bytes per bank).
    for addr in 0..=32 {
        for len in 0..=32 - addr {
            prop_pieces_partition::<48, 4, 8>(addr, len);
            ranges += 1;
        }
    }
    println!("{ranges} ranges partitioned");
    assert_eq!(ranges, 15 + 561);
}

#[test]
fn a_write_across_blocks_is_its_pieces_in_turn() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let (mut cases, mut fired, mut second_piece_ran) = (0_u32, 0_u32, 0_u32);
    for _ in 0..300 {
        let start = Start::draw(&mut rng);
        for (addr, len) in [(1, 2), (0, 3), (1, 3), (0, 4)] {
            let data: Vec<u8> = (0..len).map(|_| rng.byte()).collect();
            let split = BLOCK - addr % BLOCK;
            for cut_at in 0..=30 {
                for cut in [CutByte::Old, CutByte::New, CutByte::Garbage(rng.byte())] {
                    let (p1, p2) = (Power::new(), Power::new());
                    let (mut whole, mut pieces) = (start.banks(&p1), start.banks(&p2));
                    p1.arm(cut_at, cut);
                    let result = whole.write(addr, &data);
                    p2.arm(cut_at, cut);
                    let mut in_turn = pieces.write(addr, &data[..split]);
                    if in_turn.is_ok() {
                        second_piece_ran += 1;
                        in_turn = pieces.write(addr + split, &data[split..]);
                    }
                    assert_eq!(result, in_turn, "{len} bytes at {addr}, cut at {cut_at} ({cut:?})");
                    assert!(!(p1.is_off() && result.is_ok()), "a write the cut stopped answered Ok");
                    assert_eq!((p1.is_off(), p1.steps(), p1.torn_at()), (p2.is_off(), p2.steps(), p2.torn_at()));
                    assert_eq!(observable(&whole), observable(&pieces), "{len} bytes at {addr}, cut at {cut_at} ({cut:?})");
                    fired += u32::from(p1.is_off());
                    cases += 1;
                    if result == Err(Error::OutOfRange) {
                        panic!("a range in the data area answered OutOfRange");
                    }
                }
            }
        }
    }
    println!("{cases} cut writes across blocks, {fired} cut, the second piece written in {second_piece_ran}");
    assert!(fired > cases / 4 && second_piece_ran > cases / 4, "the cases reach both pieces and both outcomes");
}

#[test]
fn an_uncut_first_piece_leaves_banks_that_agree() {
    let mut rng = Rng(0xD1B5_4A32_D192_ED03);
    let mut changed = 0;
    for case in 0..2_000 {
        let power = Power::new();
        // Small data values, so that the written bytes often equal the stored ones.
        let data: [[u8; BLOCK]; BLOCKS] = core::array::from_fn(|_| core::array::from_fn(|_| rng.byte() % 3));
        let seqs: [u8; BLOCKS] = core::array::from_fn(|_| if case % 5 == 0 { 255 } else { rng.byte() });
        let addr = case % BLOCK;
        let bytes: Vec<u8> = (addr..BLOCK).map(|_| rng.byte() % 3).collect();
        changed += usize::from(written(&data, addr, &bytes) != Some(data));
        prop_uncut_first_piece_keeps_banks_agreeing::<N, BLOCKS, BLOCK>(&power, &data, &seqs, addr, &bytes);
    }
    println!("2000 first pieces, {changed} of them changing block 0");
    assert!(changed > 500 && changed < 2_000, "both writes that change block 0 and writes that do not");
}
