#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! CO401Memory1 under arbitrary input on both of its inputs: random serial bytes at random
//! times and random CAN frames (any identifier, the module's own SDO, RPDO, NMT and guarding
//! identifiers weighted up). Nothing may panic, and input that is not a memory write (serial
//! command 4, an SDO download, an RPDO) must leave every stored byte, both bank images and
//! the bank sums as they were.

use co401memory1::{BANK_SIZE, FixedBoard, Memory1};
use coforge_stack::device::{Device, HostPort};
use coforge_stack::frame::CanFrame;
use coforge_storage::ram::RamEeprom;
use proptest::prelude::*;

const NODE: u16 = 5;

type Dev = Memory1<RamEeprom<[u8; BANK_SIZE]>, FixedBoard>;

/// A module whose memory holds a known pattern, started and operational.
fn device() -> Dev {
    let mut dev = Memory1::new([RamEeprom::new(), RamEeprom::new()], FixedBoard::new(NODE as u8)).unwrap();
    dev.start(0);
    for addr in (0..8192).step_by(97) {
        dev.node_mut().od_mut().app.banks_mut().write(addr, &[(addr % 251) as u8 + 1]).unwrap();
    }
    dev.on_frame(&CanFrame::data(0, &[0x01, NODE as u8]).unwrap(), 0);
    dev
}

#[derive(Debug, Clone)]
enum Input {
    Serial { byte: u8, gap_ms: u32 },
    Can { id: u16, rtr: bool, data: Vec<u8> },
    Time { ms: u32 },
}

fn input() -> impl Strategy<Value = Input> {
    let id = prop_oneof![Just(0x000), Just(0x080), Just(0x600 + NODE), Just(0x200 + NODE), Just(0x300 + NODE), Just(0x700 + NODE), Just(0x123), 0..0x800_u16];
    prop_oneof![
        4 => (any::<u8>(), prop_oneof![Just(0_u32), 0..3_u32, 90..200_u32]).prop_map(|(byte, gap_ms)| Input::Serial { byte, gap_ms }),
        3 => (id, any::<bool>(), prop::collection::vec(any::<u8>(), 0..=8)).prop_map(|(id, rtr, data)| Input::Can { id, rtr, data }),
        1 => (0..1500_u32).prop_map(|ms| Input::Time { ms }),
    ]
}

/// Input that may change stored memory on purpose: a serial Write Memory command, an SDO
/// download request, an RPDO (RPDO1 carries the bank commands, which clear only status).
fn writes_memory(input: &Input) -> bool {
    match input {
        Input::Serial { byte, .. } => byte >> 4 == 0x4,
        Input::Can { id, rtr: false, data } => *id == 0x600 + NODE && data.first().is_some_and(|c| c >> 5 == 1 || c >> 5 == 6),
        _ => false,
    }
}

fn images(dev: &Dev) -> Vec<u8> {
    let banks = dev.node().od().app.banks().banks();
    [banks[0].as_bytes(), banks[1].as_bytes()].concat()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_serial_and_can_input_never_panics_nor_touches_stored_data(inputs in prop::collection::vec(input(), 1..120)) {
        let mut dev = device();
        let before = images(&dev);
        let sums = [dev.node().od().app.banks().checksum(0), dev.node().od().app.banks().checksum(1)];
        let (mut now_ms, mut out) = (1_u32, [0_u8; 16]);
        let only_reads = !inputs.iter().any(writes_memory);
        for input in inputs {
            match input {
                Input::Serial { byte, gap_ms } => {
                    now_ms += gap_ms;
                    dev.on_host_byte(byte, u64::from(now_ms));
                    let n = dev.host_output(u64::from(now_ms), &mut out);
                    prop_assert!(n <= out.len());
                }
                Input::Can { id, rtr, data } => {
                    let frame = if rtr { CanFrame::remote(id, data.len() as u8) } else { CanFrame::data(id, &data) };
                    dev.on_frame(&frame.unwrap(), u64::from(now_ms) * 1000);
                }
                Input::Time { ms } => now_ms += ms,
            }
            while dev.poll(u64::from(now_ms) * 1000).is_some() {}
        }
        if only_reads {
            prop_assert!(images(&dev) == before, "stored data changed without a write");
            prop_assert_eq!([dev.node().od().app.banks().checksum(0), dev.node().od().app.banks().checksum(1)], sums);
        }
        // Whatever happened, every byte still reads (no block lost) and both banks agree.
        let mut all = [0_u8; 8192];
        prop_assert!(dev.node_mut().od_mut().app.banks_mut().read(0, &mut all).is_ok());
        let banks = dev.node().od().app.banks().banks();
        prop_assert!(banks[0].as_bytes() == banks[1].as_bytes());
    }
}
