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
