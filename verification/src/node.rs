//! The CANopen node under arbitrary bus traffic: any identifier, DLC 0..8, data or remote,
//! at any time steps, in every NMT state and SDO transfer phase the traffic reaches.
//!
//! Invariants ([`prop_node_frames`]):
//! - nothing panics;
//! - no read-only or const entry changes (except the ones the stack itself maintains:
//!   1001h error register, 1003h error history);
//! - every SDO answer is a valid server response or an abort with a CiA 301 code.

use coforge_stack::device::{Assemble, NodeAccess};
use coforge_stack::frame::CanFrame;
use coforge_stack::node::Node;
use coforge_stack::od::{Access, NoAppObjects, NodeDictionary, SdoAbort, Side, Table};
use coforge_stack::store::{BlockStore, ParamStore};
use coforge_storage::ram::RamEeprom;

const NODE_ID: u8 = 5;
const STORE: usize = 2048;
/// The parameter store of the nodes under test: a block on an EEPROM image in RAM.
pub type Store = BlockStore<RamEeprom<[u8; STORE]>>;
/// Entries the stack writes itself although the bus may not.
const STACK_MAINTAINED: [u16; 2] = [0x1001, 0x1003];
/// Bytes of a read-only value kept for comparison.
const VALUE: usize = 32;
const MAX_WATCHED: usize = 600;

/// Identifiers the traffic is steered towards, so short inputs reach the services.
const IDS: [u16; 8] = [0x000, 0x080, 0x605, 0x705, 0x205, 0x305, 0x185, 0x285];

/// One frame from 12 input bytes: time step, identifier choice, flags, data.
fn frame_of(chunk: &[u8]) -> (u64, Option<CanFrame>) {
    let b = |i: usize| chunk.get(i).copied().unwrap_or(0);
    let step_us = u64::from(b(0)) * 997;
    let id = match b(1) {
        s @ 0..=199 => IDS.get(usize::from(s % 8)).copied().unwrap_or(0),
        _ => u16::from_le_bytes([b(2), b(3)]) & 0x7FF,
    };
    let dlc = b(3) >> 4 & 0x0F;
    let rtr = b(3) & 0x08 != 0;
    let data = [b(4), b(5), b(6), b(7), b(8), b(9), b(10), b(11)];
    let frame = if rtr { CanFrame::remote(id, dlc.min(8)) } else { CanFrame::data(id, data.get(..usize::from(dlc.min(8))).unwrap_or(&[])) };
    (step_us, frame)
}

/// A valid SDO server frame (CiA 301 7.2.4.3). During a block upload the server's segments
/// start with any sequence number, so only an abort (seqno 0 is never valid) is checked.
fn valid_sdo_answer(data: &[u8; 8], block_upload: bool) -> bool {
    let abort_ok = || SdoAbort::from_code(u32::from_le_bytes([data[4], data[5], data[6], data[7]])).is_some();
    if block_upload {
        return data[0] != 0x80 || abort_ok();
    }
    match data[0] >> 5 {
        // Upload segment, download response, upload initiate, download segment response.
        0..=3 => true,
        4 => data[0] == 0x80 && abort_ok(),
        // Block download / upload server frames.
        5 | 6 => true,
        _ => false,
    }
}

/// Checks the invariants for one input; the first byte picks the device.
pub fn prop_node_frames(input: &[u8]) {
    let Some((&pick, rest)) = input.split_first() else { return };
    match pick % 3 {
        0 => drive(assembled::<co401gw1::Node<NoAppObjects, Store>>(), rest),
        1 => drive(assembled::<cr3101::Node<NoAppObjects, Store>>(), rest),
        _ => drive(assembled::<canopenia::Node<NoAppObjects, Store>>(), rest),
    }
}

/// A device in its default mode at [`NODE_ID`] on an erased EEPROM, as a runtime builds it.
fn assembled<T: Assemble<RamEeprom<[u8; STORE]>>>() -> T {
    T::assemble(None, NODE_ID, &mut |_| Some(RamEeprom::new())).unwrap_or_else(|e| panic!("cannot assemble: {e:?}"))
}

type Snapshot = ([(u16, u8, usize, [u8; VALUE]); MAX_WATCHED], usize);

fn snapshot(node: &mut dyn NodeAccess, entries: Table<'_>) -> Snapshot {
    let mut out = ([(0, 0, 0, [0; VALUE]); MAX_WATCHED], 0);
    let watched = entries.iter().filter(|e| matches!(e.access(), Access::Ro | Access::Const) && !STACK_MAINTAINED.contains(&e.index));
    for e in watched {
        for sub in e.sub..=e.last_sub {
            let mut buf = [0; VALUE];
            if let Ok(n) = node.read(e.index, sub, 0, &mut buf, Side::Device).map(|r| r.copied)
                && let Some(slot) = out.0.get_mut(out.1)
            {
                *slot = (e.index, sub, n, buf);
                out.1 += 1;
            }
        }
    }
    out
}

fn drive<D: NodeDictionary, S: ParamStore, const N: usize, const P: usize>(mut node: Node<D, S, N, P>, input: &[u8]) {
    let entries = node.od().entries();
    node.start(0);
    let before = snapshot(&mut node, entries);
    let mut now = 0_u64;
    let mut block_upload = false;
    for chunk in input.chunks(12) {
        let (step, frame) = frame_of(chunk);
        now += step;
        if let Some(f) = frame {
            // A block upload continues only with block-upload client frames (ccs 5); the
            // server ignores remote frames.
            if f.id == 0x600 + u16::from(NODE_ID) && !f.rtr && f.data[0] >> 5 != 5 {
                block_upload = false;
            }
            node.on_frame(&f, now);
        }
        // A bounded drain: a node never has more than a few frames per event.
        for _ in 0..256 {
            let Some(out) = node.poll(now) else { break };
            if out.id == 0x580 + u16::from(NODE_ID) {
                assert!(valid_sdo_answer(&out.data, block_upload), "invalid SDO answer {:02X?}", out.data);
                if out.data[0] == 0x80 {
                    block_upload = false;
                } else if out.data[0] >> 5 == 6 && out.data[0] & 0x01 == 0 && !block_upload {
                    block_upload = true;
                }
            }
        }
    }
    let after = snapshot(&mut node, entries);
    assert_eq!(before.1, after.1, "read-only entries appeared or vanished");
    for (b, a) in before.0.iter().zip(after.0.iter()).take(before.1) {
        assert_eq!(b, a, "read-only entry {:04X}h.{} changed", b.0, b.1);
    }
}

/// The requests the performance figures are taken for, on a CO401GW1 node (node-ID 5) in
/// Operational with TPDO1 and TPDO2 valid. Shared by the criterion bench and the callgrind
/// example so both measure the same work.
pub mod requests {
    use super::{BlockStore, CanFrame, NODE_ID, RamEeprom, Store};
    use co401gw1::IoImage;
    use co401gw1::app::Typed;
    use coforge_stack::od::Side;

    /// The chip's node over its process image (the PDOs map 6000h and 6200h, which it owns).
    pub type GwNode = co401gw1::Node<Typed<IoImage>, Store>;

    /// A started node; TPDO1 and TPDO2 use `transmission_type`.
    pub fn node(transmission_type: u8) -> GwNode {
        let mut node = GwNode::of_dictionary(co401gw1::Mode::Mixed, NODE_ID, Typed(IoImage::default()), BlockStore::new(RamEeprom::new(), 0));
        node.start(0);
        for index in [0x1800_u16, 0x1801] {
            let _ = node.write(index, 2, &[transmission_type], Side::Device);
        }
        node.on_frame(&frame(0x000, &[0x01, 0]), 0);
        drain(&mut node, 0);
        node
    }

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::data(id, data).unwrap_or(CanFrame { id: 0, rtr: false, dlc: 0, data: [0; 8] })
    }

    /// Polls until the node is quiet; returns the frames sent.
    pub fn drain(node: &mut GwNode, now: u64) -> usize {
        let mut n = 0;
        while node.poll(now).is_some() {
            n += 1;
        }
        n
    }

    pub fn sdo_upload(node: &mut GwNode) -> usize {
        node.on_frame(&frame(0x605, &[0x40, 0x17, 0x10, 0, 0, 0, 0, 0]), 1);
        drain(node, 1)
    }

    pub fn sdo_download(node: &mut GwNode) -> usize {
        node.on_frame(&frame(0x605, &[0x2B, 0x17, 0x10, 0, 0xE8, 0x03, 0, 0]), 1);
        drain(node, 1)
    }

    pub fn rpdo(node: &mut GwNode) -> usize {
        node.on_frame(&frame(0x205, &[1, 2, 3, 4, 5, 6, 7, 8]), 1);
        drain(node, 1)
    }

    pub fn tpdo_event(node: &mut GwNode, now: u64) -> usize {
        node.trigger_tpdo(1);
        drain(node, now)
    }

    pub fn sync(node: &mut GwNode) -> usize {
        node.on_frame(&frame(0x080, &[]), 1);
        drain(node, 1)
    }
}
