//! coforge-stack's manager under any traffic and any caller: no panic, only valid frames
//! sent, and a transfer completes only on a response that may complete it.
//!
//! Checked by proptest (`tests/manager_inputs.rs`, [`check`] on generated inputs) and by
//! cargo fuzz (`fuzz/fuzz_targets/manager_inputs.rs`, [`prop_manager_inputs`] on raw bytes).

use coforge_stack::frame::CanFrame;
use coforge_stack::manager::scan::{ScanConfig, ScanEvent};
use coforge_stack::manager::{Manager, ManagerEvent};
use coforge_stack::sdo::client::SdoResult;

/// The node the caller's transfers go to.
pub const SERVER: u8 = 5;

/// One thing that happens to the manager.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Input {
    /// A received frame.
    Frame { id: u16, rtr: bool, data: [u8; 8], len: u8 },
    /// The caller asks to read `index`/`sub` of [`SERVER`].
    Upload { index: u16, sub: u8 },
    /// The caller asks to write `len` bytes of its buffer to `index`/`sub` of [`SERVER`].
    Download { index: u16, sub: u8, len: u8 },
    /// A scan of `node` is asked for.
    Scan { node: u8 },
    /// Time passes.
    Time { ms: u32 },
}

/// Whether `frame` may end an SDO transfer with its node successfully: an initiate response
/// (expedited upload, or download) or a segment (response) marked last, 8 bytes long.
fn may_complete(frame: &CanFrame) -> bool {
    let b0 = frame.data[0];
    !frame.rtr
        && frame.dlc == 8
        && match b0 >> 5 {
            2 => b0 & 0x02 != 0,
            0 => b0 & 0x01 != 0,
            1 | 3 => true,
            _ => false,
        }
}

/// A frame the manager may send: an SDO request to a node 1..=127 or an NMT command, always
/// 8 or 2 bytes.
fn valid_request(frame: &CanFrame) -> bool {
    !frame.rtr && ((0x601..=0x67F).contains(&frame.id) && frame.dlc == 8 || frame.id == 0 && frame.dlc == 2)
}

/// How the caller's transfers and the scans ended in a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Outcomes {
    pub completed: usize,
    pub aborted: usize,
    pub scans_complete: usize,
}

/// Runs `inputs`; panics if an invariant breaks.
pub fn check(inputs: impl IntoIterator<Item = Input>) -> Outcomes {
    let mut outcomes = Outcomes::default();
    let mut m: Manager<4, 2> = Manager::new(ScanConfig { pdos: 2, heartbeat_ms: Some(100) });
    m.monitor_mut().set_consumer_ms(None, 300);
    let mut buf = [0x11_u8; 16];
    let mut now_us = 0_u64;
    for input in inputs {
        let received = match input {
            Input::Frame { id, rtr, data, len } => {
                let frame = if rtr { CanFrame::remote(id & 0x7FF, len.min(8)) } else { CanFrame::from_payload(id & 0x7FF, data, len.min(8)) };
                if let Some(frame) = frame {
                    m.on_frame(&frame, now_us, &mut buf);
                }
                frame
            }
            Input::Upload { index, sub } => {
                let _ = m.upload(SERVER, index, sub);
                None
            }
            Input::Download { index, sub, len } => {
                let _ = m.download(SERVER, index, sub, usize::from(len));
                None
            }
            Input::Scan { node } => {
                m.scan(node);
                None
            }
            Input::Time { ms } => {
                now_us += u64::from(ms) * 1000;
                None
            }
        };
        // What the frame did (on_frame), then what polling does.
        while let Some(event) = m.take_event() {
            completes(&event, received.as_ref(), &mut outcomes);
        }
        let mut sent = 0;
        while let Some(frame) = m.poll(now_us, &mut buf) {
            assert!(valid_request(&frame), "sent {frame:02X?}");
            sent += 1;
            assert!(sent < 16, "poll never runs dry");
            while let Some(event) = m.take_event() {
                completes(&event, None, &mut outcomes);
            }
        }
        while let Some(event) = m.take_event() {
            completes(&event, None, &mut outcomes);
        }
    }
    outcomes
}

/// A successful end happens only while a frame that may complete a transfer is taken.
fn completes(event: &ManagerEvent, received: Option<&CanFrame>, outcomes: &mut Outcomes) {
    match event {
        ManagerEvent::Sdo(SdoResult::Aborted { .. }) => outcomes.aborted += 1,
        ManagerEvent::Sdo(_) => outcomes.completed += 1,
        ManagerEvent::Scan(ScanEvent::Complete(_)) => outcomes.scans_complete += 1,
        _ => {}
    }
    let ok = match event {
        ManagerEvent::Sdo(SdoResult::Uploaded { len }) => {
            assert!(*len <= 16, "an upload longer than the caller's buffer");
            received.is_some_and(|f| f.id == 0x580 + u16::from(SERVER) && may_complete(f))
        }
        ManagerEvent::Sdo(SdoResult::Downloaded) => received.is_some_and(|f| f.id == 0x580 + u16::from(SERVER) && may_complete(f)),
        // A scan also ends on a refusal of an object the node may lack (an abort frame).
        ManagerEvent::Scan(ScanEvent::Complete(node)) => {
            received.is_some_and(|f| f.id == 0x580 + u16::from(*node) && (may_complete(f) || f.dlc == 8 && f.data[0] == 0x80))
        }
        _ => true,
    };
    assert!(ok, "{event:?} after {received:02X?}");
}

/// The invariants for raw bytes (cargo fuzz): see [`decode`].
pub fn prop_manager_inputs(input: &[u8]) {
    check(decode(input));
}

/// A caller's upload and download and a node's scan answered correctly: the runs the
/// invariants must let through.
pub fn answered_run() -> impl Iterator<Item = Input> {
    let frame = |id: u16, data: [u8; 8]| Input::Frame { id, rtr: false, data, len: 8 };
    let server = 0x580 + u16::from(SERVER);
    let items = [
        Input::Upload { index: 0x1018, sub: 1 },
        frame(server, [0x43, 0x18, 0x10, 0x01, 0x58, 0, 0, 0]),
        Input::Download { index: 0x1017, sub: 0, len: 2 },
        frame(server, [0x60, 0x17, 0x10, 0x00, 0, 0, 0, 0]),
        // Node 9 boots: its scan reads 1000h and 1018h.1, ...
        Input::Frame { id: 0x709, rtr: false, data: [0; 8], len: 1 },
        Input::Time { ms: 1 },
        frame(0x589, [0x43, 0x00, 0x10, 0x00, 0x91, 0x01, 0, 0]),
        frame(0x589, [0x43, 0x18, 0x10, 0x01, 0x58, 0, 0, 0]),
    ];
    // ... and the node refuses the rest: 3 optional identity entries, the first of each of
    // 2 TPDOs and 2 RPDOs, the 1017h write.
    let refusal = frame(0x589, [0x80, 0, 0, 0, 0x00, 0x00, 0x02, 0x06]);
    items.into_iter().chain(core::iter::repeat_n(refusal, 8))
}

/// Raw bytes as inputs: a tag byte, then what it needs. Tags 0..=3 (mod 8): a frame, one
/// byte picking its identifier (low 3 bits: the server's 580h + 5, a heartbeat 700h + n, an
/// emergency 80h + n, NMT, 580h + n, any; the rest: n) and the length (tag >> 3, up to 8),
/// then its data; 4: an upload, 5: a download of `tag >> 3` bytes, each with two index bytes
/// and a sub-index; 6: a scan of the node in the next byte; 7: `(tag >> 3) * 25` ms pass.
pub fn decode(input: &[u8]) -> impl Iterator<Item = Input> + '_ {
    let mut rest = input;
    core::iter::from_fn(move || {
        let (&tag, tail) = rest.split_first()?;
        rest = tail;
        Some(match tag % 8 {
            0..=3 => {
                let (&pick, tail) = rest.split_first()?;
                let n = u16::from(pick >> 3) % 128;
                let id = match pick % 8 {
                    0 | 1 => 0x580 + u16::from(SERVER),
                    2 => 0x700 + n,
                    3 => 0x080 + n,
                    4 => 0x000,
                    5 => 0x580 + n,
                    _ => u16::from(pick) << 3 | u16::from(tag >> 5),
                };
                let len = usize::from(tag >> 3).min(8);
                let (payload, tail) = tail.split_at(len.min(tail.len()));
                rest = tail;
                let mut data = [0_u8; 8];
                data.iter_mut().zip(payload).for_each(|(d, s)| *d = *s);
                Input::Frame { id, rtr: tag % 8 == 3 && tag & 0x80 != 0, data, len: payload.len() as u8 }
            }
            4 | 5 => {
                let [lo, hi, sub, tail @ ..] = rest else { return None };
                rest = tail;
                let index = u16::from_le_bytes([*lo, *hi]);
                if tag % 8 == 4 { Input::Upload { index, sub: *sub } } else { Input::Download { index, sub: *sub, len: tag >> 3 } }
            }
            6 => {
                let (&node, tail) = rest.split_first()?;
                rest = tail;
                Input::Scan { node }
            }
            _ => Input::Time { ms: u32::from(tag >> 3) * 25 },
        })
    })
}
