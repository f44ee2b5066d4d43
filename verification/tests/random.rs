//! Bounded random tests (proptest) of the properties whose domain is too large to enumerate.

use coforge_link::crc::Crc16;
use coforge_verification::framing::*;
use coforge_verification::integrity::*;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn crc_equals_reference(which in 0..3_usize, data in proptest::collection::vec(any::<u8>(), 0..64)) {
        prop_crc_matches_reference(&Crc16::new(PARAMS[which]), &data);
    }

    #[test]
    fn crc_detects_bursts(mut data in proptest::collection::vec(any::<u8>(), 1..64), at in any::<usize>(), burst in 1..=u16::MAX) {
        prop_crc_detects_burst(&Crc16::new(PARAMS[0]), &mut data, at, burst);
    }

    #[test]
    fn nibble_round_trip(code in 0..16_u8, data in proptest::collection::vec(any::<u8>(), 0..=15)) {
        prop_nibble_round_trip(code, &data);
    }

    #[test]
    fn length_byte_round_trip(code in any::<u8>(), data in proptest::collection::vec(any::<u8>(), 0..=127), extension in proptest::option::of(any::<u8>())) {
        prop_length_byte_round_trip(code, &data, extension);
    }

    #[test]
    fn start_crc_round_trip(code in any::<u8>(), data in proptest::collection::vec(any::<u8>(), 0..=40)) {
        prop_start_crc_round_trip(code, &data);
    }

    #[test]
    fn decoders_are_total(bytes in proptest::collection::vec(any::<u8>(), 0..512), gaps in proptest::collection::vec(any::<u8>(), 0..16)) {
        prop_decoders_total(&bytes, &gaps);
    }

    #[test]
    fn resync_after_garbage(garbage in proptest::collection::vec(any::<u8>(), 0..64), code in any::<u8>(), data in proptest::collection::vec(any::<u8>(), 0..8)) {
        prop_resync_after_garbage(&garbage, code, &data);
    }
}

/// The mirrored banks on 2 blocks of 8 bytes (24 bytes per bank; the Kani harnesses use 2
/// blocks of 2 bytes, which `tests/banks_model.rs` searches exhaustively), with structured contents: committed banks, erased or random ones, then a few bytes
/// of either bank overwritten.
mod banks_small {
    use coforge_storage::record::Record;
    use coforge_verification::banks::*;
    use proptest::prelude::*;

    pub type Devices<'p> = [CutEeprom<'p, 24>; 2];

    /// `kind` 0..=3: committed, bank 2 erased, both erased, random; then `mutations`.
    pub fn devices<'p>(
        power: &'p Power,
        kind: u8,
        data: &[[u8; 8]; 2],
        seqs: &[u8; 2],
        random: &[[u8; 24]; 2],
        mutations: &[(usize, usize, u8)],
    ) -> Devices<'p> {
        let mut d = committed_devices::<24, 2, 8>(power, data, seqs);
        match kind % 4 {
            1 => d[1] = CutEeprom::erased(power),
            2 => d = [CutEeprom::erased(power), CutEeprom::erased(power)],
            3 => d = [CutEeprom::new(power, random[0]), CutEeprom::new(power, random[1])],
            _ => {}
        }
        for &(bank, pos, value) in mutations {
            d[bank % 2].as_bytes_mut()[pos % 24] = value;
        }
        d
    }

    /// Settled banks, block by block after `kinds` (mod 5): any data committed with any
    /// sequence number; zeros committed as sequence 0 (what a format writes); lost with
    /// garbage in both copies; lost with both copies staged by a format cut (bank `open` (mod 3)
    /// open: 1, 2 or both); lost with a staged copy and a garbage one.
    pub fn settled(kinds: &[u8; 2], data: &[[u8; 8]; 2], seqs: &[u8; 2], garbage: &[[u8; 12]; 2], open: &[u8; 2]) -> [[u8; 24]; 2] {
        let mut images = [[0_u8; 24]; 2];
        for block in 0..2 {
            let zeros = Record::committed(&[0; 8], 0);
            let staged = |mark: u8| Record { begin: mark, ..zeros }.to_bytes();
            let copies: [[u8; 12]; 2] = match kinds[block] % 5 {
                0 => [committed_slot(&data[block], seqs[block]); 2],
                1 => [committed_slot(&[0; 8], 0); 2],
                2 => garbage_slots(garbage),
                kind => {
                    // An open copy's begin is the format's mark (any value but the end, 0).
                    let mark = seqs[block] | 1;
                    let which = open[block] % 3;
                    let mut copies = [[0_u8; 12]; 2];
                    for (bank, copy) in copies.iter_mut().enumerate() {
                        // A closed staged copy keeps an older sequence number in both markers
                        // (not 0: that would be the formatted copy itself, valid).
                        let record =
                            if which == 2 || usize::from(which) == bank { staged(mark) } else { Record { begin: mark, end: mark, ..zeros }.to_bytes() };
                        copy[8..].copy_from_slice(&record);
                    }
                    if kind == 4 {
                        copies[1] = garbage_slots(garbage)[1];
                    }
                    copies
                }
            };
            for (image, copy) in images.iter_mut().zip(copies) {
                image[block * 12..block * 12 + 12].copy_from_slice(&copy);
            }
        }
        images
    }

    fn committed_slot(data: &[u8; 8], seq: u8) -> [u8; 12] {
        let mut slot = [0; 12];
        slot[..8].copy_from_slice(data);
        slot[8..].copy_from_slice(&Record::committed(data, seq).to_bytes());
        slot
    }

    /// Two invalid copies: any bytes, with `end` made to differ from `begin`.
    fn garbage_slots(garbage: &[[u8; 12]; 2]) -> [[u8; 12]; 2] {
        garbage.map(|mut g| {
            g[11] = g[8].wrapping_add(1);
            g
        })
    }

    pub fn mutations() -> impl Strategy<Value = Vec<(usize, usize, u8)>> {
        proptest::collection::vec((0..2_usize, 0..24_usize, any::<u8>()), 0..5)
    }

    pub fn cut() -> impl Strategy<Value = CutByte> {
        (any::<u8>(), any::<u8>()).prop_map(|(s, g)| CutByte::select(s, g))
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 10_000, ..ProptestConfig::default() })]

    #[test]
    fn banks_write_cut_leaves_old_or_new(data in any::<[[u8; 8]; 2]>(), seqs in any::<[u8; 2]>(), addr in 0..=17_usize, bytes in proptest::collection::vec(any::<u8>(), 0..=16), cut_at in 0..50_u32, cut in banks_small::cut()) {
        use coforge_verification::banks::*;
        let power = Power::new();
        prop_write_cut::<24, 2, 8>(committed_devices::<24, 2, 8>(&power, &data, &seqs), addr, &bytes, cut_at, cut);
    }

    #[test]
    fn banks_write_outside_the_data_area_changes_nothing(data in any::<[[u8; 8]; 2]>(), seqs in any::<[u8; 2]>(), off in 0..=17_usize, len in 0..=17_usize, bytes in any::<[u8; 17]>(), cut_at in 0..50_u32, cut in banks_small::cut()) {
        use coforge_verification::banks::*;
        // Empty anywhere, or ending past the 16 data bytes.
        let addr = if len == 0 { off } else { 17 - len + off % (len + 1) };
        let power = Power::new();
        prop_write_outside::<24, 2, 8>(committed_devices::<24, 2, 8>(&power, &data, &seqs), addr, &bytes[..len], cut_at, cut);
    }

    #[test]
    fn banks_recovery_is_idempotent(kind in any::<u8>(), data in any::<[[u8; 8]; 2]>(), seqs in any::<[u8; 2]>(), random in any::<[[u8; 24]; 2]>(), mutations in banks_small::mutations()) {
        use coforge_verification::banks::*;
        let power = Power::new();
        let devices = banks_small::devices(&power, kind, &data, &seqs, &random, &mutations);
        let after = prop_first_mount_settles::<24, 2, 8>(devices.clone());
        prop_settled_mount_is_quiet::<24, 2, 8>([CutEeprom::new(&power, after[0]), CutEeprom::new(&power, after[1])]);
        prop_recovery_idempotent::<24, 2, 8>(devices);
    }

    /// `settled_mount_formats`, the specification the second half of idempotence assumes, says
    /// exactly when the firmware formats settled banks; those it does not format mount quietly.
    #[test]
    fn settled_banks_format_exactly_when_the_rule_says(kinds in any::<[u8; 2]>(), data in any::<[[u8; 8]; 2]>(), seqs in any::<[u8; 2]>(), garbage in any::<[[u8; 12]; 2]>(), open in any::<[u8; 2]>()) {
        use coforge_verification::banks::*;
        let power = Power::new();
        let images = banks_small::settled(&kinds, &data, &seqs, &garbage, &open);
        prop_assert!(is_settled::<24, 2, 8>(&images));
        let formats = settled_mount_formats::<24, 2, 8>(&images);
        let banks = Banks::<24, 2, 8>::mount([CutEeprom::new(&power, images[0]), CutEeprom::new(&power, images[1])]);
        prop_assert_eq!(writes(&banks) > 0, formats, "kinds {:?}", kinds);
        if !formats {
            prop_settled_mount_is_quiet::<24, 2, 8>([CutEeprom::new(&power, images[0]), CutEeprom::new(&power, images[1])]);
        }
    }

    #[test]
    fn banks_recovery_cut_at_any_byte(kind in any::<u8>(), data in any::<[[u8; 8]; 2]>(), seqs in any::<[u8; 2]>(), random in any::<[[u8; 24]; 2]>(), mutations in banks_small::mutations(), cut_at in 0..60_u32, cut in banks_small::cut()) {
        use coforge_verification::banks::*;
        let power = Power::new();
        prop_recovery_cut::<24, 2, 8>(banks_small::devices(&power, kind, &data, &seqs, &random, &mutations), cut_at, cut);
    }

    #[test]
    fn banks_single_corruption_is_found_and_repaired(data in any::<[[u8; 8]; 2]>(), seqs in any::<[u8; 2]>(), bank in 0..2_usize, pos in 0..24_usize, value in any::<u8>(), via in any::<u8>()) {
        use coforge_verification::banks::*;
        let power = Power::new();
        let banks = Banks::<24, 2, 8>::mount(committed_devices::<24, 2, 8>(&power, &data, &seqs));
        prop_assume!(banks.banks()[bank].as_bytes()[pos] != value);
        prop_single_corruption(banks, bank, pos, value, Detect::select(via));
    }

    #[test]
    fn banks_double_corruption_is_lost(data in any::<[[u8; 8]; 2]>(), seqs in any::<[u8; 2]>(), block in 0..2_usize, offsets in any::<[usize; 2]>(), flips in any::<[u8; 2]>(), via in any::<u8>()) {
        use coforge_verification::banks::*;
        prop_assume!(data[block] != [0; 8] || seqs[block] != 0);
        prop_assume!(flips != [0, 0] && flips[0] != 0 && flips[1] != 0);
        let power = Power::new();
        let banks = Banks::<24, 2, 8>::mount(committed_devices::<24, 2, 8>(&power, &data, &seqs));
        let offsets = offsets.map(|o| o % 12);
        let values = [0, 1].map(|b| banks.banks()[b].as_bytes()[block * 12 + offsets[b]] ^ flips[b]);
        prop_double_corruption(banks, block, offsets, values, Detect::select(via));
    }

    #[test]
    fn banks_double_corruption_before_the_first_mount_is_lost(data in any::<[[u8; 8]; 2]>(), seqs in any::<[u8; 2]>(), block in 0..2_usize, offsets in any::<[usize; 2]>(), flips in any::<[u8; 2]>()) {
        use coforge_verification::banks::*;
        prop_assume!(data[block] != [0; 8] || seqs[block] != 0);
        prop_assume!(flips[0] != 0 && flips[1] != 0);
        let power = Power::new();
        let devices = committed_devices::<24, 2, 8>(&power, &data, &seqs);
        let offsets = offsets.map(|o| o % 12);
        let values = [0, 1].map(|b| devices[b].as_bytes()[block * 12 + offsets[b]] ^ flips[b]);
        prop_double_corruption_at_boot::<24, 2, 8>(devices, block, offsets, values);
    }

    #[test]
    fn banks_checksum_matches_after_operations(kind in any::<u8>(), data in any::<[[u8; 8]; 2]>(), seqs in any::<[u8; 2]>(), random in any::<[[u8; 24]; 2]>(), mutations in banks_small::mutations(), ops in proptest::collection::vec(any::<[u8; 6]>(), 0..16)) {
        use coforge_verification::banks::*;
        let power = Power::new();
        prop_checksum_after_ops::<24, 2, 8>(banks_small::devices(&power, kind, &data, &seqs, &random, &mutations), &ops);
    }

    #[test]
    fn banks_are_total(kind in any::<u8>(), data in any::<[[u8; 8]; 2]>(), seqs in any::<[u8; 2]>(), random in any::<[[u8; 24]; 2]>(), mutations in banks_small::mutations(), unreadable in any::<[bool; 2]>(), ops in proptest::collection::vec(any::<[u8; 6]>(), 0..16)) {
        use coforge_verification::banks::*;
        let power = Power::new();
        prop_banks_total::<24, 2, 8>(banks_small::devices(&power, kind, &data, &seqs, &random, &mutations), unreadable, &ops);
    }

    /// One operation from any running state (any images, status, lost flags, scrub position;
    /// either bank silent): what the Kani step harnesses prove. Both banks answer in 3 of 4
    /// cases, so the sums half is well exercised.
    #[test]
    fn banks_step_from_any_running_state(kind in any::<u8>(), data in any::<[[u8; 8]; 2]>(), seqs in any::<[u8; 2]>(), random in any::<[[u8; 24]; 2]>(), mutations in banks_small::mutations(), silent in any::<u8>(), status in any::<[u8; 2]>(), lost in any::<[bool; 2]>(), scrub_at in 0..2_usize, op in any::<[u8; 6]>()) {
        use coforge_verification::banks::*;
        let power = Power::new();
        let unreadable = [silent % 8 == 1, silent % 8 == 2];
        let banks = running_banks::<24, 2, 8>(banks_small::devices(&power, kind, &data, &seqs, &random, &mutations), unreadable, status, lost, scrub_at);
        prop_step(banks, unreadable, Op::decode::<24, 2, 8>(op));
    }
}
