//! bxCAN at 48 MHz: the bit timing of every CO401Memory1 and CR3101 bit rate (1000, 800, 500,
//! 250, 125, 100, 50, 20 and 10 kbit/s, all exact), frame conversion to and from
//! the stack's [`CanFrame`], and the controller's error state.

use coforge_stack::frame::CanFrame;
use coforge_stack::node::BusState;
use stm32f0xx_hal::can::bxcan::{Data, Frame, Id, StandardId};

/// The CAN kernel clock: APB = HCLK = SYSCLK = 48 MHz.
const CAN_HZ: u32 = 48_000_000;

/// A BTR value from prescaler, time segment 1 (propagation + phase 1) and phase segment 2, in
/// time quanta, with a resynchronisation jump width of 2 tq. BTR holds each value minus one:
/// SJW[25:24], TS2[22:20], TS1[19:16], BRP[9:0].
const fn btr(brp: u32, ts1: u32, ts2: u32) -> u32 {
    (2 - 1) << 24 | (ts2 - 1) << 20 | (ts1 - 1) << 16 | (brp - 1)
}

/// Bit rate in kbit/s, prescaler, TS1, TS2. 16 tq per bit (1 + 13 + 2) samples at 87.5 %,
/// CiA 301's recommended point for every rate up to 1 Mbit/s; 800 kbit/s has 60 clocks per bit
/// and uses 15 tq (1 + 12 + 2): 86.7 %.
#[rustfmt::skip]
const TIMINGS: [(u32, u32, u32, u32); 9] = [
    // kbit/s, BRP, TS1, TS2      tq/bit  sample point  BTR
    (1000,   3, 13, 2),        // 16      87.5 %        0x011C_0002
    (800,    4, 12, 2),        // 15      86.7 %        0x011B_0003
    (500,    6, 13, 2),        // 16      87.5 %        0x011C_0005
    (250,   12, 13, 2),        // 16      87.5 %        0x011C_000B
    (125,   24, 13, 2),        // 16      87.5 %        0x011C_0017
    (100,   30, 13, 2),        // 16      87.5 %        0x011C_001D
    (50,    60, 13, 2),        // 16      87.5 %        0x011C_003B
    (20,   150, 13, 2),        // 16      87.5 %        0x011C_0095
    (10,   300, 13, 2),        // 16      87.5 %        0x011C_012B
];

// Every entry gives its bit rate exactly, within the BTR field ranges (TS1 <= 16, TS2 <= 8,
// BRP <= 1024). (Evaluated by the compiler: an index out of range fails the build.)
#[allow(clippy::indexing_slicing)]
const _: () = {
    let mut i = 0;
    while i < TIMINGS.len() {
        let (kbit, brp, ts1, ts2) = TIMINGS[i];
        assert!(CAN_HZ == kbit * 1000 * brp * (1 + ts1 + ts2));
        assert!(ts1 <= 16 && ts2 <= 8 && ts2 >= 2 && brp <= 1024);
        i += 1;
    }
};

/// The BTR value for `kbit` (the BD pins' bit rates, CR3101's 20F2h codes); 1 Mbit/s, the
/// unconnected default, for anything else.
pub fn bit_timing(kbit: u32) -> u32 {
    let (_, brp, ts1, ts2) = TIMINGS.iter().copied().find(|t| t.0 == kbit).unwrap_or(TIMINGS[0]);
    btr(brp, ts1, ts2)
}

/// A received frame for the stack; `None` for extended identifiers (not CANopen traffic) and
/// for a DLC of 9..15. (CAN 2.0 allows those codes for 8 bytes, but bxcan 0.6 keeps the raw
/// DLC as the payload length and would slice 8 bytes by it: such a frame is dropped before its
/// data is touched. CANopen never sends them.)
pub fn from_bxcan(frame: &Frame) -> Option<CanFrame> {
    let Id::Standard(id) = frame.id() else { return None };
    if frame.dlc() > 8 {
        return None;
    }
    match frame.data() {
        Some(data) => CanFrame::data(id.as_raw(), data),
        None => CanFrame::remote(id.as_raw(), frame.dlc()),
    }
}

/// A frame of the stack for the controller (its identifier and length are valid by
/// construction; `None` otherwise).
pub fn to_bxcan(frame: &CanFrame) -> Option<Frame> {
    let id = StandardId::new(frame.id)?;
    if frame.rtr {
        // `new_remote` asserts the DLC: check it first.
        (frame.dlc <= 8).then(|| Frame::new_remote(id, frame.dlc))
    } else {
        Some(Frame::new_data(id, Data::new(frame.payload())?))
    }
}

/// The error state in CAN_ESR: bus-off (BOFF), error passive (EPVF), warning (EWGF).
pub fn bus_state(esr: u32) -> BusState {
    if esr & 0b100 != 0 {
        BusState::BusOff
    } else if esr & 0b010 != 0 {
        BusState::Passive
    } else if esr & 0b001 != 0 {
        BusState::Warning
    } else {
        BusState::Active
    }
}
