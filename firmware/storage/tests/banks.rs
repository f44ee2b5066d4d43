#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! The mirrored banks on the CO401Memory1 geometry: basic behaviour. The exhaustive power-cut
//! and corruption searches live in `verification/`.

use coforge_storage::ram::RamEeprom;
use coforge_storage::{BankStatus, Error, MirroredBanks};

type Banks = MirroredBanks<RamEeprom<[u8; 8448]>, 64, 128>;

fn blank() -> Banks {
    Banks::mount([RamEeprom::new(), RamEeprom::new()])
}

#[test]
fn blank_banks_are_formatted_to_zeros_and_say_so() {
    let mut banks = blank();
    assert_eq!(banks.status(0), BankStatus(BankStatus::CLEARED));
    assert_eq!(banks.status(1), BankStatus(BankStatus::CLEARED));
    let mut all = [0xAA_u8; 8192];
    banks.read(0, &mut all).unwrap();
    assert!(all.iter().all(|&b| b == 0));
    assert_eq!(banks.checksum(0), 0);
}

#[test]
fn writes_reach_both_banks_and_survive_a_remount() {
    let mut banks = blank();
    banks.write(130, &[1, 2, 3]).unwrap();
    banks.write(8191, &[0xFF]).unwrap();
    assert_eq!(banks.checksum(0), 6 + 0xFF);
    assert_eq!(banks.checksum(1), 6 + 0xFF);
    let mut again = Banks::mount(banks.into_banks());
    assert_eq!(again.status(0), BankStatus::default());
    let mut out = [0; 4];
    again.read(129, &mut out).unwrap();
    assert_eq!(out, [0, 1, 2, 3]);
    assert_eq!(again.checksum(1), 6 + 0xFF);
}

#[test]
fn out_of_range_accesses_are_refused() {
    let mut banks = blank();
    assert_eq!(banks.write(8191, &[1, 2]), Err(Error::OutOfRange));
    assert_eq!(banks.read(usize::MAX, &mut [0]), Err(Error::OutOfRange));
}

#[test]
fn a_corrupt_byte_in_one_bank_is_repaired_from_the_other() {
    let mut banks = blank();
    banks.write(0, &[7; 128]).unwrap();
    banks.banks_mut()[1].as_bytes_mut()[5] = 9;
    banks.clear_status(1);
    let mut out = [0; 1];
    banks.read(5, &mut out).unwrap();
    assert_eq!(out, [7]);
    assert_eq!(banks.status(1), BankStatus(BankStatus::CHECKSUM_ERROR | BankStatus::OVERWRITTEN));
    assert_eq!(banks.banks()[1].as_bytes()[5], 7);
    assert_eq!(banks.checksum(1), 7 * 128);
}

#[test]
fn a_block_lost_in_both_banks_is_reported_and_a_write_restarts_it_from_zeros() {
    let mut banks = blank();
    banks.write(128, &[5; 128]).unwrap();
    for bank in banks.banks_mut() {
        bank.as_bytes_mut()[132 + 3] ^= 1;
    }
    let mut banks = Banks::mount(banks.into_banks());
    assert!(banks.is_lost(1));
    assert_eq!(banks.read(130, &mut [0]), Err(Error::Lost { block: 1 }));
    banks.write(130, &[1]).unwrap();
    let mut out = [9; 3];
    banks.read(129, &mut out).unwrap();
    assert_eq!(out, [0, 1, 0]);
    assert!(banks.status(0).bits() & BankStatus::CLEARED != 0);
}

#[test]
fn rewriting_stored_bytes_writes_nothing() {
    let mut banks = blank();
    banks.write(0, &[3]).unwrap();
    let before = banks.banks().clone();
    banks.write(0, &[3]).unwrap();
    assert_eq!(banks.banks()[0].as_bytes(), before[0].as_bytes());
}

/// A RAM EEPROM whose writes can be made to fail (an I2C device that stops acknowledging).
#[derive(Debug, Clone, Default)]
struct Flaky {
    ram: RamEeprom<[u8; 8448]>,
    refuse_writes: bool,
}

impl embedded_storage::ReadStorage for Flaky {
    type Error = ();
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), ()> {
        self.ram.read(offset, bytes).map_err(|_| ())
    }
    fn capacity(&self) -> usize {
        8448
    }
}

impl embedded_storage::Storage for Flaky {
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), ()> {
        if self.refuse_writes {
            return Err(());
        }
        self.ram.write(offset, bytes).map_err(|_| ())
    }
}

#[test]
fn a_write_waits_while_the_other_bank_cannot_be_repaired() {
    let mut banks = MirroredBanks::<Flaky, 64, 128>::mount([Flaky::default(), Flaky::default()]);
    banks.write(10, &[1]).unwrap();
    // Bank 2's copy of block 0 goes bad, and bank 2 stops taking writes.
    banks.banks_mut()[1].ram.as_bytes_mut()[3] ^= 0x40;
    banks.banks_mut()[1].refuse_writes = true;
    assert_eq!(banks.write(10, &[2]), Err(Error::Access));
    assert!(banks.status(1).bits() & BankStatus::ACCESS_TIMEOUT != 0);
    let mut out = [0];
    banks.read(10, &mut out).unwrap();
    assert_eq!(out, [1], "the committed byte, from bank 1");
    banks.banks_mut()[1].refuse_writes = false;
    banks.write(10, &[2]).unwrap();
    let mut again = MirroredBanks::<Flaky, 64, 128>::mount(banks.into_banks());
    again.read(10, &mut out).unwrap();
    assert_eq!(out, [2]);
    assert_eq!(again.status(0), BankStatus::default());
    assert_eq!(again.status(1), BankStatus::default());
}
