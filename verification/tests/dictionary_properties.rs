//! The dictionary properties (`coforge_stack::od::properties`) of every device in every mode,
//! on bounded random accesses: the same properties the generated `od::proofs` harnesses give
//! Kani symbolic ones. Indices are drawn mostly from each dictionary's own entries (with
//! neighbours and sub-indices beyond them), data of every length around the entry's size, by
//! each side in each NMT state.

use coforge_stack::od::properties::{prop_read_is_checked, prop_write_is_checked};
use coforge_stack::od::{AccessContext, NmtState, NoAppObjects, NodeDictionary, Side};

/// xorshift64*: reproducible.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

const CASES: usize = 60_000;

fn check<D: NodeDictionary>(make: impl Fn(D::Mode) -> D, seed: u64) -> usize {
    let mut rng = Rng(seed | 1);
    let mut n = 0;
    for &mode in D::MODES {
        let mut od = make(mode);
        let table = od.entries();
        for _ in 0..CASES / D::MODES.len() {
            let run = &table[rng.below(table.len() as u64) as usize];
            let (index, sub) = match rng.below(8) {
                // Now and then anywhere: missing objects and sub-indices.
                0 => (rng.next() as u16, rng.next() as u8),
                1 => (run.index, run.last_sub.wrapping_add(1 + rng.below(3) as u8)),
                _ => (run.index + rng.below(u64::from(run.copies()) + 1) as u16, run.sub + rng.below(u64::from(run.last_sub - run.sub) + 1) as u8),
            };
            let size = od.entry(index, sub).map_or(4, |e| usize::from(e.size));
            let len = (size + 2).min(32).saturating_sub(rng.below(4) as usize).min(if rng.below(4) == 0 { rng.below(33) as usize } else { usize::MAX });
            let data: Vec<u8> = (0..len).map(|_| if rng.below(3) == 0 { 0 } else { rng.next() as u8 }).collect();
            let side = [Side::Bus, Side::Bus, Side::Host, Side::Device][rng.below(4) as usize];
            let nmt = [NmtState::PreOperational, NmtState::Operational, NmtState::Stopped][rng.below(3) as usize];
            let ctx = AccessContext { nmt, can_enabled: rng.below(2) == 0 };
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
