//! The dictionary properties (`coforge_stack::od::properties`) of every device in every mode,
//! on bounded random accesses: the same properties the generated `od::proofs` harnesses give
//! Kani symbolic ones. Indices are drawn mostly from each dictionary's own entries (with
//! neighbours and sub-indices beyond them), data of every length around the entry's size, by
//! each side in each NMT state. The write property also runs on `ImageCells`, the table over a
//! value image of any bytes that the Kani write harnesses use, and a test per device shows that
//! the generated dictionary answers writes as those cells do. Every write also changes no byte
//! of the value image outside the entry written.

use coforge_stack::od::properties::{ImageCells, prop_read_is_checked, prop_write_is_checked};
use coforge_stack::od::{AccessContext, EntryAccess, NmtState, NoAppObjects, NodeDictionary, Side, Storage, image};

const CASES: usize = 60_000;

/// A write of `data` to `index`/`sub` that changes the value image outside the entry's place.
fn write_stays_in_place<D: EntryAccess>(od: &mut D, index: u16, sub: u8, data: &[u8], side: Side, ctx: &AccessContext) {
    let before = od.image().to_vec();
    let result = od.write(index, sub, data, side, ctx);
    let after = od.image();
    let place = match od.entry(index, sub) {
        Ok(info) if result.is_ok() && info.storage() != Storage::App => {
            let start = usize::from(info.offset) + usize::from(sub - info.sub) * image::stride(info);
            start..start + image::stride(info)
        }
        _ => 0..0,
    };
    for (at, (b, a)) in before.iter().zip(after).enumerate() {
        assert!(b == a || place.contains(&at), "{index:04X}h.{sub}: byte {at} of the image changed, outside {place:?}");
    }
}

fn check<D: NodeDictionary, const S: usize>(make: impl Fn(D::Mode) -> D, seed: u64) -> usize {
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut n = 0;
    for &mode in D::MODES {
        let mut od = make(mode);
        // The Kani write harnesses' dictionary, on the same accesses, over random bytes.
        let mut cells = ImageCells::<S>::over(&od, std::array::from_fn(|_| rng.u8(..)));
        let table = od.entries();
        for _ in 0..CASES / D::MODES.len() {
            let run = table.iter().nth(rng.u64(..table.len() as u64) as usize).expect("a run of the table");
            let (index, sub) = match rng.u64(..8) {
                // Now and then anywhere: missing objects and sub-indices.
                0 => (rng.u64(..) as u16, rng.u64(..) as u8),
                1 => (run.index, run.last_sub.wrapping_add(1 + rng.u64(..3) as u8)),
                _ => (run.index + rng.u64(..u64::from(run.copies()) + 1) as u16, run.sub + rng.u64(..u64::from(run.last_sub - run.sub) + 1) as u8),
            };
            let size = od.entry(index, sub).map_or(4, |e| usize::from(e.size));
            let len = (size + 2).min(32).saturating_sub(rng.u64(..4) as usize).min(if rng.u64(..4) == 0 { rng.u64(..33) as usize } else { usize::MAX });
            let data: Vec<u8> = (0..len).map(|_| if rng.u64(..3) == 0 { 0 } else { rng.u64(..) as u8 }).collect();
            let side = [Side::Bus, Side::Bus, Side::Host, Side::Device][rng.u64(..4) as usize];
            let nmt = [NmtState::PreOperational, NmtState::Operational, NmtState::Stopped][rng.u64(..3) as usize];
            let ctx = AccessContext { nmt, can_enabled: rng.u64(..2) == 0 };
            prop_write_is_checked(&mut od, index, sub, &data, side, &ctx);
            prop_write_is_checked(&mut cells, index, sub, &data, side, &ctx);
            write_stays_in_place(&mut od, index, sub, &data, side, &ctx);
            prop_read_is_checked(&mut od, index, sub, side);
            n += 1;
        }
    }
    n
}

#[test]
fn co401memory1_dictionary_keeps_its_rules() {
    assert_eq!(check::<_, { size_of::<co401memory1::Values>() }>(|m| co401memory1::Od::new(m, 0x22, NoAppObjects), 1), CASES);
}

#[test]
fn co401gw1_dictionary_keeps_its_rules() {
    assert!(check::<_, { size_of::<co401gw1::Values>() }>(|m| co401gw1::Od::new(m, 5, NoAppObjects), 2) >= CASES - 2);
}

#[test]
fn cr3101_dictionary_keeps_its_rules() {
    assert!(check::<_, { size_of::<cr3101::Values>() }>(|m| cr3101::Od::new(m, 0x20, NoAppObjects), 3) >= CASES - 2);
}

#[test]
fn canopenia_dictionary_keeps_its_rules() {
    assert!(check::<_, { size_of::<canopenia::Values>() }>(|m| canopenia::Od::new(m, 3, NoAppObjects), 4) >= CASES - 2);
}

/// A `len`-byte little-endian test value: zeros, ones, the top bit alone, every bit but the
/// top one, or random (`pattern` 0 to 3, then any).
fn test_value(pattern: usize, len: usize, rng: &mut fastrand::Rng) -> Vec<u8> {
    let mut data = match pattern {
        0 | 2 => vec![0x00; len],
        1 | 3 => vec![0xFF; len],
        _ => (0..len).map(|_| rng.u8(..)).collect(),
    };
    if let Some(top) = data.last_mut() {
        match pattern {
            2 => *top = 0x80,
            3 => *top = 0x7F,
            _ => {}
        }
    }
    data
}

/// The Kani write harnesses prove `prop_write_is_checked` on `ImageCells`, the device's table
/// over a value image without the device's app-backed objects (see verification/README.md).
/// This is the other half of that proof: for every entry of every mode, a write of every length
/// up to the entry's size and one more, with each test pattern, gets the same answer from the
/// generated dictionary as from the cells over its image, reads back the same bytes, and leaves
/// both images alike. A dictionary with its own code for an entry would answer differently.
fn cells_behave_as_fields<D: NodeDictionary, const S: usize>(make: impl Fn(D::Mode) -> D) -> usize {
    let ctx = AccessContext { nmt: NmtState::PreOperational, can_enabled: false };
    let mut rng = fastrand::Rng::with_seed(17);
    let mut compared = 0;
    for &mode in D::MODES {
        let mut od = make(mode);
        let mut cells = ImageCells::<S>::over(&od, od.image().try_into().expect("the image is S bytes"));
        for run in od.entries().iter() {
            for index in (0..=u16::from(run.copies())).map(|k| run.index + k) {
                for sub in run.sub..=run.last_sub {
                    let size = usize::from(run.size);
                    for len in 0..=(size + 1).min(33) {
                        for pattern in 0..6 {
                            let data = test_value(pattern, len, &mut rng);
                            let real = od.write(index, sub, &data, Side::Device, &ctx);
                            let cell = cells.write(index, sub, &data, Side::Device, &ctx);
                            assert_eq!(real, cell, "{index:04X}h.{sub} ({mode:?}): write of {data:02X?}");
                            if real.is_ok() {
                                let (mut a, mut b) = ([0; 64], [0; 64]);
                                let ra = od.read(index, sub, 0, &mut a, Side::Device);
                                let rb = cells.read(index, sub, 0, &mut b, Side::Device);
                                assert_eq!((ra, a), (rb, b), "{index:04X}h.{sub} ({mode:?}): read after writing {data:02X?}");
                            }
                            assert_eq!(od.image(), cells.image(), "{index:04X}h.{sub} ({mode:?}): the images differ");
                            compared += 1;
                        }
                    }
                }
            }
        }
    }
    compared
}

#[test]
fn co401memory1_fields_behave_as_the_proofs_cells() {
    assert!(cells_behave_as_fields::<_, { size_of::<co401memory1::Values>() }>(|m| co401memory1::Od::new(m, 0x22, NoAppObjects)) > 10_000);
}

#[test]
fn co401gw1_fields_behave_as_the_proofs_cells() {
    assert!(cells_behave_as_fields::<_, { size_of::<co401gw1::Values>() }>(|m| co401gw1::Od::new(m, 5, NoAppObjects)) > 10_000);
}

#[test]
fn cr3101_fields_behave_as_the_proofs_cells() {
    assert!(cells_behave_as_fields::<_, { size_of::<cr3101::Values>() }>(|m| cr3101::Od::new(m, 0x20, NoAppObjects)) > 10_000);
}

#[test]
fn canopenia_fields_behave_as_the_proofs_cells() {
    assert!(cells_behave_as_fields::<_, { size_of::<canopenia::Values>() }>(|m| canopenia::Od::new(m, 3, NoAppObjects)) > 10_000);
}
