//! The dictionary properties (`coforge_stack::od::properties`) of every device in every mode,
//! on bounded random accesses: the same properties the generated `od::proofs` harnesses give
//! Kani symbolic ones. Indices are drawn mostly from each dictionary's own entries (with
//! neighbours and sub-indices beyond them), data of every length around the entry's size, by
//! each side in each NMT state.

use coforge_stack::od::properties::{prop_read_is_checked, prop_write_is_checked};
use coforge_stack::od::{AccessContext, NmtState, NoAppObjects, NodeDictionary, Side};

const CASES: usize = 60_000;

fn check<D: NodeDictionary>(make: impl Fn(D::Mode) -> D, seed: u64) -> usize {
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut n = 0;
    for &mode in D::MODES {
        let mut od = make(mode);
        let table = od.entries();
        for _ in 0..CASES / D::MODES.len() {
            let run = &table[rng.u64(..table.len() as u64) as usize];
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
            prop_read_is_checked(&mut od, index, sub, side);
            n += 1;
        }
    }
    n
}

#[test]
fn co401memory1_dictionary_keeps_its_rules() {
    assert_eq!(check(|m| co401memory1::Od::new(m, 0x22, NoAppObjects), 1), CASES);
}

#[test]
fn co401gw1_dictionary_keeps_its_rules() {
    assert!(check(|m| co401gw1::Od::new(m, 5, NoAppObjects), 2) >= CASES - 2);
}

#[test]
fn cr3101_dictionary_keeps_its_rules() {
    assert!(check(|m| cr3101::Od::new(m, 0x20, NoAppObjects), 3) >= CASES - 2);
}

#[test]
fn canopenia_dictionary_keeps_its_rules() {
    assert!(check(|m| canopenia::Od::new(m, 3, NoAppObjects), 4) >= CASES - 2);
}
