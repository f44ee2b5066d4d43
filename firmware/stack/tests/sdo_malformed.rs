//! Malformed and out-of-order SDO traffic: a table of cases, each ending in one abort with
//! a known code, none of which may change the dictionary; and every command byte in every
//! server state, which must never panic and only ever abort with a CiA 301 code.

use coforge_link::crc::{Crc16, XMODEM};
mod common;

use coforge_stack::od::SdoAbort;
use coforge_stack::sdo::SdoServer;
use common::{DOMAIN, Dict, STRING, U8_RO, U32};

/// The server's buffer: smaller than the domain, so oversized downloads can be tried.
const N: usize = 64;

/// What a case does, in order.
#[derive(Debug, Clone)]
enum Op {
    /// A request (any length).
    Req(Vec<u8>),
    Poll,
    /// Time passes (µs).
    Wait(u64),
}

fn req(frame: &[u8]) -> Op {
    Op::Req(frame.to_vec())
}

fn with_mux(command: u8, index: u16, data: [u8; 4]) -> Op {
    let [lo, hi] = index.to_le_bytes();
    Op::Req(vec![command, lo, hi, 0, data[0], data[1], data[2], data[3]])
}

/// A segment-like frame: `command`, then up to 7 bytes.
fn seg(command: u8, data: &[u8]) -> Op {
    let mut f = vec![command];
    f.extend_from_slice(data);
    f.resize(8, 0);
    Op::Req(f)
}

fn size(len: u32) -> [u8; 4] {
    len.to_le_bytes()
}

/// `count` segments of a download without size indication, toggling, none last.
fn segments(count: usize) -> Vec<Op> {
    (0..count).map(|i| seg(((i & 1) as u8) << 4, b"0123456")).collect()
}

/// `count` block segments numbered from 1, none last.
fn block_segments(count: u8) -> Vec<Op> {
    (1..=count).map(|seq| seg(seq, b"0123456")).collect()
}

/// The first `count` polls of a block upload.
fn polls(count: usize) -> Vec<Op> {
    vec![Op::Poll; count]
}

struct Case {
    name: &'static str,
    ops: Vec<Op>,
    /// The abort the last op must produce: object and code.
    abort: (u16, u8, SdoAbort),
    /// An earlier transfer of the case completed and wrote (the abort itself still must not).
    wrote_before: bool,
}

fn case(name: &'static str, ops: Vec<Op>, index: u16, sub: u8, code: SdoAbort) -> Case {
    Case { name, ops, abort: (index, sub, code), wrote_before: false }
}

fn cases() -> Vec<Case> {
    let crc_123 = Crc16::new(XMODEM).checksum(&[1, 2, 3]);
    let bad_crc = (crc_123 ^ 0x0101).to_le_bytes();
    let block_up = |blksize: u8| with_mux(0xA4, DOMAIN, [blksize, 0, 0, 0]);
    let start = req(&[0xA3]);
    let seg_download = || with_mux(0x21, STRING, size(10));
    let seg_upload = || with_mux(0x40, STRING, [0; 4]);
    use SdoAbort::*;
    vec![
        // Command specifiers.
        case("unknown command specifier, idle", vec![with_mux(0xE0, U32, [0; 4])], U32, 0, UnknownCommand),
        case("unknown command specifier during a download", vec![seg_download(), with_mux(0xE0, U32, [0; 4])], STRING, 0, UnknownCommand),
        case("upload segment during a download", vec![seg_download(), req(&[0x60])], STRING, 0, UnknownCommand),
        case("download segment during an upload", vec![seg_upload(), seg(0x00, b"x")], STRING, 0, UnknownCommand),
        case("block upload start twice", vec![block_up(5), start.clone(), start.clone()], DOMAIN, 0, UnknownCommand),
        case("block upload ack before the start", vec![block_up(5), req(&[0xA2, 0, 5])], DOMAIN, 0, UnknownCommand),
        case("block upload end before the last ack", [vec![block_up(5), start.clone()], polls(2), vec![req(&[0xA1])]].concat(), DOMAIN, 0, UnknownCommand),
        case("block download end during an upload", vec![seg_upload(), req(&[0xC1])], STRING, 0, UnknownCommand),
        // Toggle bits.
        case("download: first segment toggled", vec![seg_download(), seg(0x10, b"0123456")], STRING, 0, ToggleBit),
        case("download: toggle not alternated", vec![seg_download(), seg(0x00, b"0123456"), seg(0x00, b"0123456")], STRING, 0, ToggleBit),
        case("upload: first segment toggled", vec![seg_upload(), req(&[0x70])], STRING, 0, ToggleBit),
        case("upload: toggle not alternated", vec![seg_upload(), req(&[0x60]), req(&[0x60])], STRING, 0, ToggleBit),
        // Segments outside a transfer.
        case("download segment, no transfer", vec![seg(0x00, b"0123456")], 0, 0, UnknownCommand),
        case("upload segment, no transfer", vec![req(&[0x60])], 0, 0, UnknownCommand),
        case("block upload ack, no transfer", vec![req(&[0xA2, 1, 10])], 0, 0, UnknownCommand),
        case("block download end, no transfer", vec![req(&[0xC1, 0, 0])], 0, 0, UnknownCommand),
        case("upload segment after the last", vec![seg_upload(), req(&[0x60]), req(&[0x70]), req(&[0x60]), req(&[0x70])], 0, 0, UnknownCommand),
        Case {
            wrote_before: true,
            ..case("download segment after the last", vec![with_mux(0x21, STRING, size(3)), seg(0x09, b"abc"), seg(0x10, b"def")], 0, 0, UnknownCommand)
        },
        Case {
            wrote_before: true,
            ..case("block segment after the end", vec![with_mux(0xC2, DOMAIN, size(3)), seg(0x81, b"abc"), req(&[0xD1]), seg(0x01, b"x")], 0, 0, UnknownCommand)
        },
        // Block transfer.
        case(
            "block download CRC mismatch",
            vec![with_mux(0xC6, DOMAIN, size(3)), seg(0x81, &[1, 2, 3]), req(&[0xD1, bad_crc[0], bad_crc[1]])],
            DOMAIN,
            0,
            BlockCrc,
        ),
        case("block upload block size 0", vec![block_up(0)], DOMAIN, 0, InvalidBlockSize),
        case("block upload block size 128", vec![block_up(128)], DOMAIN, 0, InvalidBlockSize),
        case(
            "block upload ack with block size 0",
            [vec![block_up(5), start.clone()], polls(5), vec![req(&[0xA2, 5, 0])]].concat(),
            DOMAIN,
            0,
            InvalidBlockSize,
        ),
        case(
            "block upload ack with block size 128",
            [vec![block_up(5), start.clone()], polls(5), vec![req(&[0xA2, 5, 128])]].concat(),
            DOMAIN,
            0,
            InvalidBlockSize,
        ),
        case("block download sequence number 0", vec![with_mux(0xC2, DOMAIN, size(14)), seg(0x00, b"0123456")], DOMAIN, 0, InvalidSequence),
        case(
            "block download sequence number 0 later",
            [vec![with_mux(0xC2, DOMAIN, size(14))], block_segments(1), vec![seg(0x00, b"x")]].concat(),
            DOMAIN,
            0,
            InvalidSequence,
        ),
        case(
            "block upload ack beyond what was sent",
            [vec![block_up(5), start.clone()], polls(5), vec![req(&[0xA2, 6, 5])]].concat(),
            DOMAIN,
            0,
            InvalidSequence,
        ),
        // Size indication against the data.
        case("expedited n says 2 bytes for a u32", vec![with_mux(0x2B, U32, [1, 2, 0, 0])], U32, 0, LengthTooLow),
        case("expedited n says 1 byte for a u32", vec![with_mux(0x2F, U32, [1, 0, 0, 0])], U32, 0, LengthTooLow),
        case("segmented: more data than indicated", vec![seg_download(), seg(0x00, b"0123456"), seg(0x11, b"789ABCD")], STRING, 0, LengthTooHigh),
        case("segmented: less data than indicated", vec![seg_download(), seg(0x01, b"0123456")], STRING, 0, LengthTooLow),
        case("segmented: size too small for a u32", vec![with_mux(0x21, U32, size(3))], U32, 0, LengthTooLow),
        case("block: less data than indicated", vec![with_mux(0xC2, DOMAIN, size(20)), seg(0x81, b"0123456"), req(&[0xC1])], DOMAIN, 0, LengthTooLow),
        case("block: more data than indicated", vec![with_mux(0xC2, DOMAIN, size(3)), seg(0x81, b"0123456"), req(&[0xC1])], DOMAIN, 0, LengthTooHigh),
        // Timeouts.
        case("timeout: segmented download", vec![seg_download(), Op::Wait(1_000_000), Op::Poll], STRING, 0, Timeout),
        case("timeout: segmented upload", vec![seg_upload(), req(&[0x60]), Op::Wait(1_000_000), Op::Poll], STRING, 0, Timeout),
        case(
            "timeout: block download sub-block",
            [vec![with_mux(0xC2, DOMAIN, size(30))], block_segments(2), vec![Op::Wait(1_000_000), Op::Poll]].concat(),
            DOMAIN,
            0,
            Timeout,
        ),
        case(
            "timeout: block upload waiting for the ack",
            [vec![block_up(2), start.clone()], polls(3), vec![Op::Wait(1_000_000), Op::Poll]].concat(),
            DOMAIN,
            0,
            Timeout,
        ),
        case("timeout: block upload waiting for the start", vec![block_up(2), Op::Wait(1_000_000), Op::Poll], DOMAIN, 0, Timeout),
        // The dictionary's own codes.
        case("expedited download to read-only", vec![with_mux(0x2F, U8_RO, [7, 0, 0, 0])], U8_RO, 0, ReadOnly),
        case("segmented download to read-only", vec![with_mux(0x21, U8_RO, size(1))], U8_RO, 0, ReadOnly),
        case("block download to read-only", vec![with_mux(0xC2, U8_RO, size(1))], U8_RO, 0, ReadOnly),
        case("download to a missing object", vec![with_mux(0x23, 0x2099, [0; 4])], 0x2099, 0, NoObject),
        case("upload of a missing sub-index", vec![req(&[0x40, 0x00, 0x20, 5])], U32, 5, NoSubIndex),
        // Larger than the buffer (64 bytes) or the object.
        case("segmented, size indicated, larger than N", vec![with_mux(0x21, DOMAIN, size(100))], DOMAIN, 0, OutOfMemory),
        case("segmented, size indicated, larger than the object", vec![with_mux(0x21, DOMAIN, size(300))], DOMAIN, 0, LengthTooHigh),
        case("segmented, no size, larger than N", [vec![with_mux(0x20, DOMAIN, [0; 4])], segments(10)].concat(), DOMAIN, 0, OutOfMemory),
        case(
            "segmented, no size, larger than the object",
            [vec![with_mux(0x20, STRING, [0; 4])], segments(6), vec![seg(0x01, b"0")]].concat(),
            STRING,
            0,
            LengthTooHigh,
        ),
        case("segmented, no size, larger than N and the object", [vec![with_mux(0x20, STRING, [0; 4])], segments(10)].concat(), STRING, 0, LengthTooHigh),
        case("block, size indicated, larger than N", vec![with_mux(0xC2, DOMAIN, size(100))], DOMAIN, 0, OutOfMemory),
        case("block, no size, larger than N", [vec![with_mux(0xC0, DOMAIN, [0; 4])], block_segments(9), block_segments(1)].concat(), DOMAIN, 0, OutOfMemory),
    ]
}

fn abort_frame(index: u16, sub: u8, code: SdoAbort) -> [u8; 8] {
    let [lo, hi] = index.to_le_bytes();
    let c = code.code().to_le_bytes();
    [0x80, lo, hi, sub, c[0], c[1], c[2], c[3]]
}

/// Runs `ops` on a fresh server and dictionary: every frame the server sent (with the op that
/// sent it), and the dictionary afterwards.
fn run(ops: &[Op]) -> (Vec<(usize, [u8; 8])>, Dict, SdoServer<N>) {
    let mut server = SdoServer::<N>::new();
    let mut dict = Dict::new();
    let mut now = 0;
    let mut sent = Vec::new();
    for (i, op) in ops.iter().enumerate() {
        let out = match op {
            Op::Req(frame) => server.on_request(frame, now, &mut dict),
            Op::Poll => server.poll(now, &mut dict),
            Op::Wait(us) => {
                now += us;
                None
            }
        };
        sent.extend(out.map(|f| (i, f)));
    }
    (sent, dict, server)
}

#[test]
fn malformed_requests_abort_with_the_cia_code() {
    let cases = cases();
    for c in &cases {
        let (sent, _, mut server) = run(&c.ops);
        let (index, sub, code) = c.abort;
        let last = c.ops.len() - 1;
        assert_eq!(sent.last(), Some(&(last, abort_frame(index, sub, code))), "{}: {sent:02X?}", c.name);
        assert!(sent[..sent.len() - 1].iter().all(|(_, f)| f[0] != 0x80), "{}: only one abort: {sent:02X?}", c.name);
        assert!(server.is_idle(), "{}: idle after the abort", c.name);
        assert_eq!(server.poll(u64::MAX, &mut Dict::new()), None, "{}: nothing more to send", c.name);
    }
    assert!(cases.len() >= 50, "{}", cases.len());
}

#[test]
fn aborts_leave_the_dictionary_unchanged() {
    for c in cases() {
        let (_, after_abort, _) = run(&c.ops);
        // The same case without its aborting op: whatever completed before it.
        let (_, before_abort, _) = run(&c.ops[..c.ops.len() - 1]);
        assert_eq!(after_abort, before_abort, "{}", c.name);
        if c.wrote_before {
            assert_eq!(after_abort.writes, 1, "{}", c.name);
        } else {
            assert_eq!(after_abort, Dict::new(), "{}: nothing written, nothing changed", c.name);
        }
    }
}

/// What brings the server into each of its states.
fn states() -> Vec<(&'static str, Vec<Op>)> {
    vec![
        ("idle", vec![]),
        ("segmented download", vec![with_mux(0x21, STRING, size(20)), seg(0x00, b"0123456")]),
        ("segmented upload", vec![with_mux(0x40, STRING, [0; 4]), req(&[0x60])]),
        ("block download sub-block", vec![with_mux(0xC6, DOMAIN, size(30)), seg(0x01, b"0123456")]),
        ("block download end", vec![with_mux(0xC6, DOMAIN, size(3)), seg(0x81, b"abc")]),
        ("block upload initiated", vec![with_mux(0xA4, DOMAIN, [5, 0, 0, 0])]),
        ("block upload sub-block", vec![with_mux(0xA4, DOMAIN, [5, 0, 0, 0]), req(&[0xA3]), Op::Poll]),
        ("block upload end", vec![with_mux(0xA4, U32, [5, 0, 0, 0]), req(&[0xA3]), Op::Poll, req(&[0xA2, 1, 5])]),
    ]
}

/// Every server frame is well formed: an abort carries a CiA 301 code.
fn check_frame(context: &str, frame: &[u8; 8]) {
    if frame[0] == 0x80 {
        let code = u32::from_le_bytes([frame[4], frame[5], frame[6], frame[7]]);
        assert!(SdoAbort::from_code(code).is_some(), "{context}: abort code {code:08X}");
    }
}

#[test]
fn every_command_byte_in_every_state_is_handled() {
    let fills: [&[u8]; 4] = [&[0; 7], &[0xFF; 7], &[0x03, 0x20, 0x00, 0x07, 0x00, 0x00, 0x00], &[0x02, 0x20, 0x00, 0x80, 0x7F, 0x01, 0xFE]];
    let mut runs = 0;
    for (state, setup) in states() {
        for b0 in 0..=255_u8 {
            for fill in fills {
                for len in [0, 1, 4, 8] {
                    let mut frame = vec![b0];
                    frame.extend_from_slice(fill);
                    frame.truncate(len);
                    let mut ops = setup.clone();
                    ops.push(Op::Req(frame.clone()));
                    // Send a whole block upload sub-block (at most 127 segments), then let it time out.
                    ops.extend([Op::Poll, Op::Poll, Op::Wait(2_000_000)]);
                    ops.extend(polls(130));
                    ops.extend([Op::Wait(2_000_000), Op::Poll]);
                    let (sent, _, server) = run(&ops);
                    let context = format!("{state}, request {frame:02X?}");
                    sent.iter().for_each(|(_, f)| check_frame(&context, f));
                    assert!(server.is_idle(), "{context}: every transfer ends (completed, aborted or timed out)");
                    runs += 1;
                }
            }
        }
    }
    assert_eq!(runs, 8 * 256 * 4 * 4);
}

#[test]
fn random_traffic_never_panics() {
    // xorshift64: deterministic, no dependency.
    let mut x = 0x9E37_79B9_7F4A_7C15_u64;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    // Command bytes the protocol uses, so that random traffic gets deep into transfers.
    const COMMANDS: [u8; 16] = [0x00, 0x10, 0x21, 0x20, 0x23, 0x40, 0x60, 0x70, 0x80, 0xA0, 0xA4, 0xA3, 0xA2, 0xA1, 0xC6, 0xC1];
    let mut server = SdoServer::<N>::new();
    let mut dict = Dict::new();
    let mut now = 0_u64;
    for _ in 0..200_000 {
        let r = next();
        let mut frame = r.to_le_bytes();
        frame[0] = if r & 0x100 != 0 { COMMANDS[(r >> 60) as usize] } else { frame[0] };
        // Mostly the four test objects, sub-index 0.
        if r & 0x200 != 0 {
            frame[1..4].copy_from_slice(&[(r >> 40) as u8 & 0x03, 0x20, 0]);
        }
        let len = if r & 0x400 != 0 { 8 } else { (r >> 56) as usize % 9 };
        if let Some(f) = server.on_request(&frame[..len], now, &mut dict) {
            check_frame("random", &f);
        }
        for _ in 0..(r >> 20) % 4 {
            if let Some(f) = server.poll(now, &mut dict) {
                check_frame("random poll", &f);
            }
        }
        now += (r >> 24) % 50_000;
        // A stored value always respects its object.
        assert!(dict.entries.iter().all(|e| e.len <= e.max && (!e.fixed || e.len == e.max)));
        assert_eq!(dict.entries[1].data[..1], [0x5A], "read-only stays");
    }
}
