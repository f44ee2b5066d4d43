//! Properties over their whole (small) domain.

use coforge_link::crc::Crc16;
use coforge_verification::integrity::*;

#[test]
fn crc_table_step_for_every_crc_and_byte() {
    for params in PARAMS {
        let table = Crc16::new(params);
        for crc in 0..=u16::MAX {
            for byte in 0..=u8::MAX {
                prop_crc_table_step(&table, crc, byte);
            }
        }
    }
}

#[test]
fn sum32_update_for_every_old_and_new_byte() {
    for sum in [0_u32, 1, 0x7F, 0xFF, 0x1_0000, 0xFFFF_FF80, u32::MAX] {
        for old in 0..=u8::MAX {
            for new in 0..=u8::MAX {
                prop_sum32_step(sum, old, new);
            }
        }
    }
    // And in a full 8 KiB bank, for every position and value of one byte's change.
    let mut bank = [0_u8; 8192];
    for (i, b) in bank.iter_mut().enumerate() {
        *b = (i * 31 % 251) as u8;
    }
    for index in (0..bank.len()).step_by(97) {
        for new in 0..=u8::MAX {
            prop_sum32_update(&mut bank, index, new);
        }
    }
}

#[test]
fn every_single_bit_and_short_burst_error_in_a_16_byte_message_is_detected() {
    let table = Crc16::new(PARAMS[0]);
    let mut data: [u8; 16] = core::array::from_fn(|i| (i as u8).wrapping_mul(37).wrapping_add(5));
    // Every burst pattern that starts and ends with a 1 bit and spans at most 16 bits.
    for span in 1..=16_u32 {
        let patterns: Vec<u16> = if span == 1 {
            vec![0x8000]
        } else {
            (0..1_u32 << (span - 2)).map(|mid| (1 << (span - 1) | mid << 1 | 1) << (16 - span)).map(|p| p as u16).collect()
        };
        for &pattern in &patterns {
            for at in 0..data.len() * 8 {
                prop_crc_detects_burst(&table, &mut data, at, pattern);
            }
        }
    }
}
