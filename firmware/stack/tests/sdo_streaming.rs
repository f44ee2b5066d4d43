//! Streamed SDO downloads: a value much larger than the server's buffer handed to the target
//! in parts (CANopenIA's 2,217-byte configuration file into 1F50h.2 through an 8-byte
//! buffer), every way such a transfer can fail ending it with exactly one `abort_stream`,
//! and the objects that do not stream behaving as in a server without streaming.

use coforge_link::crc::{Crc16, XMODEM};
mod common;

use coforge_stack::od::{ReadLen, SdoAbort};
use coforge_stack::sdo::{SdoServer, SdoTarget};
use common::{DOMAIN, Dict};

/// The streaming entry: 1F50h.2, up to 4000 bytes.
const PROGRAM: u16 = 0x1F50;
const SUB: u8 = 2;
const PROGRAM_MAX: usize = 4000;
/// The server's download buffer: smaller than a segment.
const N: usize = 8;

/// [`Dict`]'s objects as they are, plus 1F50h.2, which streams while `streaming` is set.
#[derive(Debug)]
struct Streamer {
    dict: Dict,
    streaming: bool,
    /// The parts of the download in progress.
    incoming: Vec<u8>,
    /// Every part as `(offset, len, last)`.
    parts: Vec<(usize, usize, bool)>,
    /// The value of the last completed download, whole or streamed.
    program: Vec<u8>,
    /// Completed streamed downloads and whole writes of 1F50h.2.
    streamed: usize,
    whole: usize,
    aborts: usize,
    /// A part that reaches this offset is refused with `Hardware`.
    refuse_at: Option<usize>,
}

impl Streamer {
    fn new() -> Streamer {
        Streamer {
            dict: Dict::new(),
            streaming: true,
            incoming: Vec::new(),
            parts: Vec::new(),
            program: Vec::new(),
            streamed: 0,
            whole: 0,
            aborts: 0,
            refuse_at: None,
        }
    }
}

impl SdoTarget for Streamer {
    const STREAMING: bool = true;

    fn read(&mut self, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        self.dict.read(index, sub, offset, buf)
    }

    fn check_download(&mut self, index: u16, sub: u8, size: Option<usize>) -> Result<(), SdoAbort> {
        match (index, sub) {
            (PROGRAM, SUB) if size.is_some_and(|size| size > PROGRAM_MAX) => Err(SdoAbort::LengthTooHigh),
            (PROGRAM, SUB) => Ok(()),
            _ => self.dict.check_download(index, sub, size),
        }
    }

    fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        if (index, sub) != (PROGRAM, SUB) {
            return self.dict.write(index, sub, data);
        }
        self.program = data.to_vec();
        self.whole += 1;
        Ok(())
    }

    fn streams(&mut self, index: u16, sub: u8) -> bool {
        (index, sub) == (PROGRAM, SUB) && self.streaming
    }

    fn write_part(&mut self, index: u16, sub: u8, offset: usize, data: &[u8], last: bool) -> Result<(), SdoAbort> {
        assert_eq!((index, sub), (PROGRAM, SUB), "only 1F50h.2 streams");
        assert_eq!(offset, self.incoming.len(), "parts in order, without gaps");
        self.parts.push((offset, data.len(), last));
        if self.refuse_at.is_some_and(|at| offset + data.len() >= at) {
            return Err(SdoAbort::Hardware);
        }
        self.incoming.extend_from_slice(data);
        if last {
            self.program = std::mem::take(&mut self.incoming);
            self.streamed += 1;
        }
        Ok(())
    }

    fn abort_stream(&mut self, index: u16, sub: u8) {
        assert_eq!((index, sub), (PROGRAM, SUB));
        self.incoming.clear();
        self.aborts += 1;
    }
}

struct Bench {
    server: SdoServer<N>,
    t: Streamer,
    now: u64,
}

impl Bench {
    fn new() -> Bench {
        Bench { server: SdoServer::new(), t: Streamer::new(), now: 0 }
    }

    fn req(&mut self, frame: &[u8; 8]) -> Option<[u8; 8]> {
        self.server.on_request(frame, self.now, &mut self.t)
    }
}

fn with_mux(command: u8, index: u16, sub: u8, data: [u8; 4]) -> [u8; 8] {
    let [lo, hi] = index.to_le_bytes();
    [command, lo, hi, sub, data[0], data[1], data[2], data[3]]
}

fn abort(index: u16, sub: u8, code: SdoAbort) -> [u8; 8] {
    with_mux(0x80, index, sub, code.code().to_le_bytes())
}

/// The configuration file: 2,217 bytes that differ from segment to segment.
fn file() -> Vec<u8> {
    (0..2217_u32).map(|i| (i * 31 + i / 7) as u8).collect()
}

/// Segment `i` of a download (toggle from `i`).
fn segment(i: usize, chunk: &[u8], last: bool) -> [u8; 8] {
    let mut f = [0; 8];
    f[0] = (i as u8 & 1) << 4 | (7 - chunk.len() as u8) << 1 | u8::from(last);
    f[1..1 + chunk.len()].copy_from_slice(chunk);
    f
}

/// Initiates a segmented download (size indicated if `size` is given).
fn initiate(b: &mut Bench, index: u16, sub: u8, size: Option<usize>) -> Option<[u8; 8]> {
    let init = match size {
        Some(size) => with_mux(0x21, index, sub, (size as u32).to_le_bytes()),
        None => with_mux(0x20, index, sub, [0; 4]),
    };
    b.req(&init)
}

/// Sends the first `count` segments of `data` (the last flagged if it is the data's last),
/// checking each response.
fn send_segments(b: &mut Bench, data: &[u8], count: usize) {
    let chunks: Vec<&[u8]> = data.chunks(7).collect();
    for (i, chunk) in chunks.iter().enumerate().take(count) {
        let toggle = (i as u8 & 1) << 4;
        assert_eq!(b.req(&segment(i, chunk, i + 1 == chunks.len())), Some([0x20 | toggle, 0, 0, 0, 0, 0, 0, 0]), "segment {i}");
    }
}

/// A whole segmented download of `data` into 1F50h.2.
fn download(b: &mut Bench, data: &[u8], sized: bool) {
    assert_eq!(initiate(b, PROGRAM, SUB, sized.then_some(data.len())), Some(with_mux(0x60, PROGRAM, SUB, [0; 4])));
    send_segments(b, data, usize::MAX);
    assert!(b.server.is_idle());
}

/// After a failed transfer: exactly one abort so far, nothing completed, and the next
/// download goes through.
fn recovers(b: &mut Bench, what: &str) {
    assert_eq!((b.t.aborts, b.t.streamed), (1, 0), "{what}: one abort_stream, no completed download");
    assert!(b.server.is_idle(), "{what}");
    b.t.refuse_at = None;
    let data = file();
    download(b, &data, true);
    assert_eq!((b.t.aborts, b.t.streamed), (1, 1), "{what}: the next download completes");
    assert_eq!(b.t.program, data, "{what}");
}

#[test]
fn a_2217_byte_segmented_download_streams_through_an_8_byte_buffer() {
    for sized in [true, false] {
        let mut b = Bench::new();
        let data = file();
        download(&mut b, &data, sized);
        assert_eq!(b.t.program, data, "complete and in order");
        assert_eq!((b.t.streamed, b.t.whole, b.t.aborts), (1, 0, 0));
        let expected: Vec<(usize, usize, bool)> = (0..317).map(|i| (i * 7, if i == 316 { 5 } else { 7 }, i == 316)).collect();
        assert_eq!(b.t.parts, expected, "one part per segment, sized {sized}");
    }
}

#[test]
fn a_toggle_error_aborts_the_stream_once() {
    let mut b = Bench::new();
    let data = file();
    initiate(&mut b, PROGRAM, SUB, Some(data.len()));
    send_segments(&mut b, &data, 10);
    // Segment 10 must carry toggle 0: segment 11's (1) is wrong.
    assert_eq!(b.req(&segment(11, &data[70..77], false)), Some(abort(PROGRAM, SUB, SdoAbort::ToggleBit)));
    recovers(&mut b, "toggle error");
}

#[test]
fn a_client_abort_aborts_the_stream_once() {
    let mut b = Bench::new();
    let data = file();
    initiate(&mut b, PROGRAM, SUB, Some(data.len()));
    send_segments(&mut b, &data, 100);
    assert_eq!(b.req(&abort(PROGRAM, SUB, SdoAbort::General)), None, "nothing answers a client abort");
    assert_eq!(b.server.poll(10_000_000, &mut b.t), None, "and no timeout follows");
    recovers(&mut b, "client abort");
}

#[test]
fn a_timeout_aborts_the_stream_once() {
    let mut b = Bench::new();
    let data = file();
    initiate(&mut b, PROGRAM, SUB, Some(data.len()));
    send_segments(&mut b, &data, 3);
    assert_eq!(b.server.poll(999_999, &mut b.t), None);
    assert_eq!(b.t.aborts, 0, "still waiting");
    assert_eq!(b.server.poll(1_000_000, &mut b.t), Some(abort(PROGRAM, SUB, SdoAbort::Timeout)));
    assert_eq!(b.server.poll(2_000_000, &mut b.t), None);
    b.now = 2_000_000;
    recovers(&mut b, "timeout");
}

#[test]
fn a_length_mismatch_aborts_the_stream_once() {
    // The client ends 3 bytes early.
    let mut b = Bench::new();
    let data = file();
    initiate(&mut b, PROGRAM, SUB, Some(data.len() + 3));
    send_segments(&mut b, &data, 316);
    assert_eq!(b.req(&segment(316, &data[2212..], true)), Some(abort(PROGRAM, SUB, SdoAbort::LengthTooLow)));
    assert!(b.t.parts.iter().all(|&(_, _, last)| !last), "the short value was never complete");
    recovers(&mut b, "too little data");
    // More data than indicated.
    let mut b = Bench::new();
    initiate(&mut b, PROGRAM, SUB, Some(20));
    send_segments(&mut b, &data, 2);
    assert_eq!(b.req(&segment(2, &data[14..21], false)), Some(abort(PROGRAM, SUB, SdoAbort::LengthTooHigh)));
    recovers(&mut b, "too much data");
}

#[test]
fn other_ends_abort_the_stream_once() {
    let data = file();
    // A new initiate replaces the transfer.
    let mut b = Bench::new();
    initiate(&mut b, PROGRAM, SUB, Some(data.len()));
    send_segments(&mut b, &data, 5);
    assert_eq!(initiate(&mut b, PROGRAM, SUB, Some(data.len())), Some(with_mux(0x60, PROGRAM, SUB, [0; 4])));
    assert_eq!(b.t.aborts, 1, "the old transfer ended before the new one started");
    assert_eq!(b.req(&abort(PROGRAM, SUB, SdoAbort::General)), None);
    assert_eq!(b.t.aborts, 2, "and the new one is a stream of its own");
    // An NMT reset or stop.
    let mut b = Bench::new();
    initiate(&mut b, PROGRAM, SUB, None);
    send_segments(&mut b, &data, 5);
    b.server.reset(&mut b.t);
    b.server.reset(&mut b.t);
    recovers(&mut b, "reset, twice");
    // The target refuses a part.
    let mut b = Bench::new();
    b.t.refuse_at = Some(100);
    initiate(&mut b, PROGRAM, SUB, Some(data.len()));
    send_segments(&mut b, &data, 14);
    assert_eq!(b.req(&segment(14, &data[98..105], false)), Some(abort(PROGRAM, SUB, SdoAbort::Hardware)));
    recovers(&mut b, "a part refused");
    // A stray command.
    let mut b = Bench::new();
    initiate(&mut b, PROGRAM, SUB, Some(data.len()));
    assert_eq!(b.req(&[0xE0, 0, 0, 0, 0, 0, 0, 0]), Some(abort(PROGRAM, SUB, SdoAbort::UnknownCommand)));
    recovers(&mut b, "an unknown command");
}

#[test]
fn the_indicated_size_is_checked_against_the_entry_not_the_buffer() {
    let mut b = Bench::new();
    assert_eq!(initiate(&mut b, PROGRAM, SUB, Some(PROGRAM_MAX + 1)), Some(abort(PROGRAM, SUB, SdoAbort::LengthTooHigh)));
    assert_eq!(initiate(&mut b, PROGRAM, SUB, Some(PROGRAM_MAX)), Some(with_mux(0x60, PROGRAM, SUB, [0; 4])));
    assert_eq!(b.t.aborts, 0, "a refused initiate starts no stream");
    b.t.streaming = false;
    assert_eq!(initiate(&mut b, PROGRAM, SUB, Some(9)), Some(abort(PROGRAM, SUB, SdoAbort::OutOfMemory)), "not streaming: the buffer decides");
    assert_eq!(b.t.aborts, 1, "the replaced stream was aborted");
}

#[test]
fn entries_that_do_not_stream_are_collected_in_the_buffer_as_before() {
    let mut b = Bench::new();
    // DOMAIN takes up to 200 bytes, more than the buffer: refused as without streaming.
    assert_eq!(initiate(&mut b, DOMAIN, 0, Some(9)), Some(abort(DOMAIN, 0, SdoAbort::OutOfMemory)));
    assert_eq!(initiate(&mut b, DOMAIN, 0, Some(201)), Some(abort(DOMAIN, 0, SdoAbort::LengthTooHigh)));
    assert_eq!(initiate(&mut b, DOMAIN, 0, Some(8)), Some(with_mux(0x60, DOMAIN, 0, [0; 4])));
    send_segments(&mut b, b"8 bytes!", 2);
    assert_eq!(b.t.dict.value(DOMAIN), b"8 bytes!");
    assert_eq!(initiate(&mut b, DOMAIN, 0, None), Some(with_mux(0x60, DOMAIN, 0, [0; 4])));
    assert_eq!(b.req(&segment(0, b"1234567", false)), Some([0x20, 0, 0, 0, 0, 0, 0, 0]));
    assert_eq!(b.req(&segment(1, b"89", true)), Some(abort(DOMAIN, 0, SdoAbort::OutOfMemory)), "past the buffer");
    assert_eq!(b.t.dict.value(DOMAIN), b"8 bytes!", "nothing written");
    // An expedited download of the streaming entry comes whole.
    assert_eq!(b.req(&with_mux(0x2B, PROGRAM, SUB, [1, 2, 0, 0])), Some(with_mux(0x60, PROGRAM, SUB, [0; 4])));
    assert_eq!((b.t.program.as_slice(), b.t.whole, b.t.parts.len()), (&[1_u8, 2][..], 1, 0));
    assert_eq!(b.t.aborts, 0, "no stream was involved");
}

fn crc16(data: &[u8]) -> u16 {
    Crc16::new(XMODEM).checksum(data)
}

/// Block download of `data` into 1F50h.2 with the size indicated, up to the end request:
/// segments in `lose` are not sent the first time (never a sub-block's last). Returns the
/// block size of each sub-block.
fn block_segments(b: &mut Bench, data: &[u8], lose: &[usize]) -> Vec<u8> {
    let r = b.req(&with_mux(0xC6, PROGRAM, SUB, (data.len() as u32).to_le_bytes())).expect("a response");
    assert_eq!(r[..4], with_mux(0xA4, PROGRAM, SUB, [0; 4])[..4]);
    let mut blksizes = vec![r[4]];
    let segments: Vec<&[u8]> = data.chunks(7).collect();
    let mut lose = lose.to_vec();
    let mut next = 0;
    while next < segments.len() {
        let count = usize::from(*blksizes.last().expect("a block size")).min(segments.len() - next);
        let mut ack = None;
        for k in 0..count {
            let i = next + k;
            let last = i + 1 == segments.len();
            let mut f = [0; 8];
            f[0] = (k as u8 + 1) | if last { 0x80 } else { 0 };
            f[1..1 + segments[i].len()].copy_from_slice(segments[i]);
            if let Some(p) = lose.iter().position(|&l| l == i) {
                lose.remove(p);
                continue;
            }
            ack = b.req(&f);
        }
        let ack = ack.expect("the sub-block is acknowledged");
        assert_eq!(ack[0], 0xA2);
        next += usize::from(ack[1]);
        blksizes.push(ack[2]);
    }
    blksizes
}

/// The block download end request: `n` bytes of the last segment are padding.
fn block_end(b: &mut Bench, n: u8, crc: u16) -> Option<[u8; 8]> {
    b.req(&[0xC1 | n << 2, crc as u8, (crc >> 8) as u8, 0, 0, 0, 0, 0])
}

#[test]
fn a_block_download_streams_with_its_size_indicated() {
    let mut b = Bench::new();
    let data = file();
    // Segments 3 and 130 are lost once: the server acknowledges what came in order and the
    // client resends from there.
    let blksizes = block_segments(&mut b, &data, &[3, 130]);
    assert!(blksizes.iter().all(|&s| s == 127), "no buffer limits the sub-blocks: {blksizes:?}");
    assert!(b.t.parts.iter().all(|&(_, _, last)| !last), "not complete before the end request");
    assert_eq!(block_end(&mut b, 2, crc16(&data)), Some([0xA1, 0, 0, 0, 0, 0, 0, 0]));
    assert_eq!(b.t.program, data, "complete and in order, nothing written twice");
    assert_eq!((b.t.streamed, b.t.aborts), (1, 0));
    assert_eq!(b.t.parts.last(), Some(&(2217, 0, true)), "the last part follows the end request's checks");
    assert_eq!(b.t.parts[b.t.parts.len() - 2], (2212, 5, false), "the last segment's padding is not data");
    assert!(b.server.is_idle());
}

#[test]
fn a_block_crc_error_aborts_the_stream_once() {
    let mut b = Bench::new();
    let data = file();
    block_segments(&mut b, &data, &[]);
    assert_eq!(block_end(&mut b, 2, crc16(&data) ^ 1), Some(abort(PROGRAM, SUB, SdoAbort::BlockCrc)));
    assert!(b.t.parts.iter().all(|&(_, _, last)| !last));
    recovers(&mut b, "CRC error");
}

#[test]
fn a_block_length_mismatch_aborts_the_stream_once() {
    // The end request's n says one byte more than the indicated size.
    let mut b = Bench::new();
    let data = file();
    block_segments(&mut b, &data, &[]);
    assert_eq!(block_end(&mut b, 1, crc16(&data)), Some(abort(PROGRAM, SUB, SdoAbort::LengthTooHigh)));
    recovers(&mut b, "block length");
    // A segment past the indicated size.
    let mut b = Bench::new();
    assert!(b.req(&with_mux(0xC6, PROGRAM, SUB, 10_u32.to_le_bytes())).is_some());
    assert_eq!(b.req(&[0x01, 1, 2, 3, 4, 5, 6, 7]), None);
    assert_eq!(b.req(&[0x02, 8, 9, 10, 11, 12, 13, 14]), Some(abort(PROGRAM, SUB, SdoAbort::LengthTooHigh)));
    assert_eq!(b.t.parts, [(0, 7, false)], "the full segment past the size was not handed over");
    recovers(&mut b, "block segment past the size");
}

#[test]
fn a_block_download_without_size_is_collected_in_the_buffer() {
    let mut b = Bench::new();
    let r = b.req(&with_mux(0xC4, PROGRAM, SUB, [0; 4])).expect("a response");
    assert_eq!(r[4], 1, "the block size the 8-byte buffer allows");
    assert_eq!(b.req(&[0x81, 1, 2, 3, 0, 0, 0, 0]), Some([0xA2, 1, 1, 0, 0, 0, 0, 0]));
    assert_eq!(b.req(&[0xC1 | 4 << 2, 0x00, 0x00, 0, 0, 0, 0, 0]).map(|r| r[0]), Some(0x80), "CRC of [1, 2, 3] is not 0");
    assert_eq!((b.t.aborts, b.t.parts.len()), (0, 0), "not a stream");
    let crc = crc16(&[1, 2, 3]);
    b.req(&with_mux(0xC4, PROGRAM, SUB, [0; 4]));
    b.req(&[0x81, 1, 2, 3, 0, 0, 0, 0]);
    assert_eq!(b.req(&[0xC1 | 4 << 2, crc as u8, (crc >> 8) as u8, 0, 0, 0, 0, 0]), Some([0xA1, 0, 0, 0, 0, 0, 0, 0]));
    assert_eq!((b.t.program.as_slice(), b.t.whole), (&[1_u8, 2, 3][..], 1));
}
