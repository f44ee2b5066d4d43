//! SDO transfers end to end, from the client's side, against a small in-test dictionary:
//! expedited, segmented and block transfer in both directions, block retransmission, the
//! protocol switch threshold, restarts, client aborts and timeouts.

use coforge_link::crc::{Crc16, XMODEM};
mod common;

use coforge_stack::od::SdoAbort;
use coforge_stack::sdo::SdoServer;
use common::{DOMAIN, Dict, STRING, U8_RO, U32};

/// A server, its dictionary and the clock.
struct Bench<const N: usize> {
    server: SdoServer<N>,
    dict: Dict,
    now: u64,
}

impl<const N: usize> Bench<N> {
    fn new() -> Self {
        Bench { server: SdoServer::new(), dict: Dict::new(), now: 0 }
    }

    fn req(&mut self, frame: &[u8]) -> Option<[u8; 8]> {
        self.server.on_request(frame, self.now, &mut self.dict)
    }

    fn poll(&mut self) -> Option<[u8; 8]> {
        self.server.poll(self.now, &mut self.dict)
    }
}

fn with_mux(command: u8, index: u16, data: [u8; 4]) -> [u8; 8] {
    let [lo, hi] = index.to_le_bytes();
    [command, lo, hi, 0, data[0], data[1], data[2], data[3]]
}

fn abort(index: u16, sub: u8, code: SdoAbort) -> [u8; 8] {
    let [lo, hi] = index.to_le_bytes();
    let c = code.code().to_le_bytes();
    [0x80, lo, hi, sub, c[0], c[1], c[2], c[3]]
}

fn segment(command: u8, data: &[u8]) -> [u8; 8] {
    let mut f = [0; 8];
    f[0] = command;
    f[1..1 + data.len()].copy_from_slice(data);
    f
}

fn crc16(data: &[u8]) -> u16 {
    Crc16::new(XMODEM).checksum(data)
}

/// Segmented download from the client's side, checking every response.
fn download_segmented<const N: usize>(b: &mut Bench<N>, index: u16, data: &[u8], sized: bool) {
    let init = if sized { with_mux(0x21, index, (data.len() as u32).to_le_bytes()) } else { with_mux(0x20, index, [0; 4]) };
    assert_eq!(b.req(&init), Some(with_mux(0x60, index, [0; 4])));
    let chunks: Vec<&[u8]> = data.chunks(7).collect();
    for (i, chunk) in chunks.iter().enumerate() {
        let toggle = (i as u8 & 1) << 4;
        let last = u8::from(i + 1 == chunks.len());
        let n = (7 - chunk.len() as u8) << 1;
        assert_eq!(b.req(&segment(toggle | n | last, chunk)), Some(segment(0x20 | toggle, &[])), "segment {i}");
    }
}

/// Segmented upload from the client's side: the value, after checking the toggles and `c`.
fn upload_segmented<const N: usize>(b: &mut Bench<N>, index: u16) -> Vec<u8> {
    let r = b.req(&with_mux(0x40, index, [0; 4])).expect("a response");
    assert_eq!(r[..4], with_mux(0x41, index, [0; 4])[..4], "segmented, size indicated");
    let size = u32::from_le_bytes([r[4], r[5], r[6], r[7]]) as usize;
    let mut value = Vec::new();
    for i in 0.. {
        let toggle = (i as u8 & 1) << 4;
        let r = b.req(&[0x60 | toggle, 0, 0, 0, 0, 0, 0, 0]).expect("a response");
        assert_eq!(r[0] & 0xF0, toggle, "segment {i} echoes the toggle");
        let len = 7 - usize::from(r[0] >> 1 & 7);
        value.extend_from_slice(&r[1..1 + len]);
        if r[0] & 1 == 1 {
            break;
        }
    }
    assert_eq!(value.len(), size);
    assert!(b.server.is_idle());
    value
}

/// Block download from the client's side. Segments whose absolute number is in `lose` are
/// not sent the first time (never the last of a sub-block, which the server needs to
/// answer); the client resends from what the server acknowledged. Returns the acks.
fn block_download<const N: usize>(b: &mut Bench<N>, index: u16, data: &[u8], crc: bool, lose: &[usize]) -> Vec<[u8; 8]> {
    let command = 0xC2 | if crc { 0x04 } else { 0 };
    let r = b.req(&with_mux(command, index, (data.len() as u32).to_le_bytes())).expect("a response");
    assert_eq!(r[..4], with_mux(0xA4, index, [0; 4])[..4], "CRC offered");
    assert_eq!(r[5..], [0, 0, 0]);
    let mut blksize = usize::from(r[4]);
    let segments: Vec<&[u8]> = if data.is_empty() { vec![&[]] } else { data.chunks(7).collect() };
    let mut lose = lose.to_vec();
    let mut acks = Vec::new();
    let mut next = 0;
    while next < segments.len() {
        let count = blksize.min(segments.len() - next);
        let mut ack = None;
        for k in 0..count {
            let i = next + k;
            let last = i + 1 == segments.len();
            let frame = segment((k as u8 + 1) | if last { 0x80 } else { 0 }, segments[i]);
            if let Some(p) = lose.iter().position(|&l| l == i) {
                lose.remove(p);
                continue;
            }
            let r = b.req(&frame);
            if k + 1 < count {
                assert_eq!(r, None, "no answer inside a sub-block");
            } else {
                ack = r;
            }
        }
        let ack = ack.expect("the sub-block is acknowledged");
        assert_eq!(ack[0], 0xA2);
        assert!(usize::from(ack[1]) <= count);
        next += usize::from(ack[1]);
        blksize = usize::from(ack[2]);
        assert!((1..=127).contains(&blksize));
        acks.push(ack);
    }
    let n = (segments.len() * 7 - data.len()) as u8;
    let crc = if crc { crc16(data) } else { 0xDEAD };
    assert_eq!(b.req(&[0xC1 | n << 2, crc as u8, (crc >> 8) as u8, 0, 0, 0, 0, 0]), Some([0xA1, 0, 0, 0, 0, 0, 0, 0]));
    assert!(b.server.is_idle());
    acks
}

/// Block upload from the client's side; `ack` chooses the ackseq of each sub-block (its
/// number and how many segments arrived). Returns the value, the CRC the server sent and the
/// sequence numbers of every segment received.
fn block_upload<const N: usize>(b: &mut Bench<N>, index: u16, blksize: u8, crc: bool, mut ack: impl FnMut(usize, u8) -> u8) -> (Vec<u8>, u16, Vec<u8>) {
    let command = 0xA0 | if crc { 0x04 } else { 0 };
    let r = b.req(&[command, index as u8, (index >> 8) as u8, 0, blksize, 0, 0, 0]).expect("a response");
    assert_eq!(r[..4], with_mux(0xC6, index, [0; 4])[..4], "CRC offered, size indicated");
    let size = u32::from_le_bytes([r[4], r[5], r[6], r[7]]) as usize;
    assert_eq!(b.req(&[0xA3, 0, 0, 0, 0, 0, 0, 0]), None, "segments come from poll");
    let mut value = Vec::new();
    let mut seqs = Vec::new();
    for sub_block in 0.. {
        let mut frames = Vec::new();
        while let Some(f) = b.poll() {
            assert_eq!(f[0] & 0x7F, frames.len() as u8 + 1, "in sequence");
            frames.push(f);
            assert!(frames.len() <= usize::from(blksize), "the client's block size is honoured");
        }
        seqs.extend(frames.iter().map(|f| f[0] & 0x7F));
        let ackseq = ack(sub_block, frames.len() as u8);
        let acked = &frames[..usize::from(ackseq)];
        acked.iter().for_each(|f| value.extend_from_slice(&f[1..]));
        let r = b.req(&[0xA2, ackseq, blksize, 0, 0, 0, 0, 0]);
        if acked.last().is_some_and(|f| f[0] & 0x80 != 0) {
            let end = r.expect("the end request answers the last ack");
            assert_eq!(end[0] & 0xE3, 0xC1);
            value.truncate(value.len() - usize::from(end[0] >> 2 & 7));
            assert_eq!(end[3..], [0; 5]);
            assert_eq!(b.req(&[0xA1, 0, 0, 0, 0, 0, 0, 0]), None);
            assert!(b.server.is_idle());
            assert_eq!(value.len(), size);
            return (value, u16::from_le_bytes([end[1], end[2]]), seqs);
        }
        assert_eq!(r, None);
    }
    unreachable!()
}

#[test]
fn expedited_download_and_upload() {
    let mut b = Bench::<64>::new();
    // n = 0, s = 1: four bytes.
    assert_eq!(b.req(&with_mux(0x23, U32, [0xBE, 0xBA, 0xFE, 0xCA])), Some(with_mux(0x60, U32, [0; 4])));
    assert_eq!(b.dict.value(U32), 0xCAFE_BABE_u32.to_le_bytes());
    assert_eq!(b.req(&with_mux(0x40, U32, [0; 4])), Some(with_mux(0x43, U32, [0xBE, 0xBA, 0xFE, 0xCA])));
    // s = 0: size unspecified, all four bytes are written.
    assert_eq!(b.req(&with_mux(0x22, U32, [1, 2, 3, 4])), Some(with_mux(0x60, U32, [0; 4])));
    assert_eq!(b.dict.value(U32), [1, 2, 3, 4]);
    // One byte: n = 3.
    assert_eq!(b.req(&with_mux(0x40, U8_RO, [0; 4])), Some(with_mux(0x4F, U8_RO, [0x5A, 0, 0, 0])));
    // Two bytes of a string: n = 2.
    assert_eq!(b.req(&with_mux(0x2B, STRING, [b'a', b'b', 0xEE, 0xEE])), Some(with_mux(0x60, STRING, [0; 4])));
    assert_eq!(b.dict.value(STRING), b"ab");
    assert_eq!(b.req(&with_mux(0x40, STRING, [0; 4])), Some(with_mux(0x4B, STRING, [b'a', b'b', 0, 0])));
    assert_eq!(b.dict.writes, 3);
    assert!(b.server.is_idle());
}

#[test]
fn segmented_download_and_upload_of_a_string() {
    let mut b = Bench::<64>::new();
    let text = b"forty bytes of visible string, exactly!!";
    assert_eq!(text.len(), 40);
    download_segmented(&mut b, STRING, text, true);
    assert_eq!(b.dict.value(STRING), text);
    assert_eq!(upload_segmented(&mut b, STRING), text);
    // Size not indicated: the last segment's `c` ends it.
    download_segmented(&mut b, STRING, b"twenty bytes of text", false);
    assert_eq!(b.dict.value(STRING), b"twenty bytes of text");
    assert_eq!(b.dict.writes, 2);
}

#[test]
fn segmented_upload_frames_are_exact() {
    let mut b = Bench::<64>::new();
    // 19 bytes: 7 + 7 + 5.
    assert_eq!(b.req(&with_mux(0x40, STRING, [0; 4])), Some(with_mux(0x41, STRING, [19, 0, 0, 0])));
    assert_eq!(b.req(&[0x60]), Some(segment(0x00, b"coforge")));
    assert_eq!(b.req(&[0x70]), Some(segment(0x10, b" sdo st")));
    assert_eq!(b.req(&[0x60]), Some(segment(0x05, b"ring!")), "n = 2, c = 1");
    assert!(b.server.is_idle());
}

#[test]
fn empty_value_uploads_segmented_with_one_empty_segment() {
    let mut b = Bench::<64>::new();
    b.dict.set(STRING, b"");
    assert_eq!(b.req(&with_mux(0x40, STRING, [0; 4])), Some(with_mux(0x41, STRING, [0; 4])));
    assert_eq!(b.req(&[0x60]), Some(segment(0x0F, &[])), "n = 7, c = 1");
    assert!(b.server.is_idle());
    let (value, crc, seqs) = block_upload(&mut b, STRING, 10, true, |_, sent| sent);
    assert_eq!((value.len(), crc, seqs), (0, 0, vec![1]));
}

#[test]
fn the_value_is_written_only_after_the_last_segment() {
    let mut b = Bench::<64>::new();
    let before = b.dict.clone();
    assert_eq!(b.req(&with_mux(0x21, STRING, [10, 0, 0, 0])), Some(with_mux(0x60, STRING, [0; 4])));
    assert_eq!(b.req(&segment(0x00, b"0123456")), Some(segment(0x20, &[])));
    assert_eq!(b.dict, before);
    assert_eq!(b.req(&segment(0x19, b"789")), Some(segment(0x30, &[])));
    assert_eq!(b.dict.value(STRING), b"0123456789");
}

#[test]
fn block_download_with_crc_fills_the_buffer_exactly() {
    let mut b = Bench::<200>::new();
    let data: Vec<u8> = (0..200).map(|i| (i * 13) as u8).collect();
    let acks = block_download(&mut b, DOMAIN, &data, true, &[]);
    // 200 / 7 = 28 segments fit; then 4 bytes left: block size 1.
    assert_eq!(acks, vec![[0xA2, 28, 1, 0, 0, 0, 0, 0], [0xA2, 1, 1, 0, 0, 0, 0, 0]]);
    assert_eq!(b.dict.value(DOMAIN), data);
}

#[test]
fn block_download_without_crc_ignores_the_crc_field() {
    let mut b = Bench::<200>::new();
    block_download(&mut b, DOMAIN, b"no crc negotiated here", false, &[]);
    assert_eq!(b.dict.value(DOMAIN), b"no crc negotiated here");
}

#[test]
fn block_download_announces_at_most_127_segments() {
    let mut b = Bench::<2000>::new();
    let r = b.req(&with_mux(0xC4, DOMAIN, [0; 4])).expect("a response");
    assert_eq!(r, with_mux(0xA4, DOMAIN, [127, 0, 0, 0]));
}

#[test]
fn block_download_resends_after_a_lost_segment() {
    let mut b = Bench::<200>::new();
    let data: Vec<u8> = (0..100).map(|i| 255 - i as u8).collect();
    // 15 segments in one sub-block of 28; segment 5 (index 4) is lost: the server
    // acknowledges 4 when the last one arrives, and the client resends 11 segments.
    let acks = block_download(&mut b, DOMAIN, &data, true, &[4]);
    assert_eq!(acks.iter().map(|a| a[1]).collect::<Vec<_>>(), vec![4, 11]);
    assert_eq!(b.dict.value(DOMAIN), data);
    assert_eq!(b.dict.writes, 1);
    // Two losses across sub-blocks of a longer value.
    let data: Vec<u8> = (0..200).map(|i| i as u8 ^ 0x5A).collect();
    let acks = block_download(&mut b, DOMAIN, &data, true, &[0, 20]);
    assert_eq!(acks[0][1], 0, "the first segment was lost: nothing acknowledged");
    assert_eq!(b.dict.value(DOMAIN), data);
}

#[test]
fn block_download_ignores_a_repeated_segment_until_the_sub_block_ends() {
    let mut b = Bench::<200>::new();
    assert_eq!(b.req(&with_mux(0xC6, DOMAIN, [14, 0, 0, 0])).expect("a response")[4], 28);
    assert_eq!(b.req(&segment(0x01, b"ABCDEFG")), None);
    assert_eq!(b.req(&segment(0x01, b"ABCDEFG")), None, "repeated: the rest is ignored");
    assert_eq!(b.req(&segment(0x82, b"HIJKLMN")), Some([0xA2, 1, 27, 0, 0, 0, 0, 0]), "only the first one counts");
    assert_eq!(b.req(&segment(0x81, b"HIJKLMN")), Some([0xA2, 1, 26, 0, 0, 0, 0, 0]));
    let crc = crc16(b"ABCDEFGHIJKLMN");
    assert_eq!(b.req(&[0xC1, crc as u8, (crc >> 8) as u8]), Some([0xA1, 0, 0, 0, 0, 0, 0, 0]));
    assert_eq!(b.dict.value(DOMAIN), b"ABCDEFGHIJKLMN");
}

#[test]
fn block_upload_with_crc() {
    let mut b = Bench::<8>::new();
    let (value, crc, seqs) = block_upload(&mut b, DOMAIN, 10, true, |_, sent| sent);
    assert_eq!(value, b.dict.value(DOMAIN));
    assert_eq!(crc, crc16(b.dict.value(DOMAIN)));
    // 100 bytes: 15 segments, a sub-block of 10 then one of 5.
    assert_eq!(seqs, [(1..=10).collect::<Vec<u8>>(), (1..=5).collect()].concat());
    // Without CRC the field is 0.
    let (value, crc, _) = block_upload(&mut b, DOMAIN, 127, false, |_, sent| sent);
    assert_eq!((value.as_slice(), crc), (b.dict.value(DOMAIN), 0));
}

#[test]
fn block_upload_frames_are_exact() {
    let mut b = Bench::<8>::new();
    assert_eq!(b.req(&[0xA4, 0x02, 0x20, 0, 2, 0, 0, 0]), Some(with_mux(0xC6, STRING, [19, 0, 0, 0])));
    assert_eq!(b.poll(), None, "nothing before the start");
    assert_eq!(b.req(&[0xA3]), None);
    assert_eq!(b.poll(), Some(segment(0x01, b"coforge")));
    assert_eq!(b.poll(), Some(segment(0x02, b" sdo st")));
    assert_eq!(b.poll(), None, "the client's block size is 2");
    assert_eq!(b.req(&[0xA2, 2, 2]), None);
    assert_eq!(b.poll(), Some(segment(0x81, b"ring!")));
    assert_eq!(b.poll(), None);
    let crc = crc16(b"coforge sdo string!");
    assert_eq!(b.req(&[0xA2, 1, 2]), Some([0xC9, crc as u8, (crc >> 8) as u8, 0, 0, 0, 0, 0]), "n = 2");
    assert_eq!(b.req(&[0xA1]), None);
    assert!(b.server.is_idle());
}

#[test]
fn block_upload_resends_what_the_client_did_not_acknowledge() {
    let mut b = Bench::<8>::new();
    // The first sub-block (10 segments) is acknowledged only up to 3: the next sub-block
    // starts again at segment 4, read again from the target.
    let (value, crc, seqs) = block_upload(&mut b, DOMAIN, 10, true, |sub_block, sent| if sub_block == 0 { 3 } else { sent });
    assert_eq!(value, b.dict.value(DOMAIN));
    assert_eq!(crc, crc16(b.dict.value(DOMAIN)), "resent segments are not counted twice");
    assert_eq!(seqs.len(), 10 + 12, "12 segments left after 3 acknowledged");
    // Nothing acknowledged at all, twice.
    let (value, crc, _) = block_upload(&mut b, DOMAIN, 4, true, |sub_block, sent| if sub_block < 2 { 0 } else { sent });
    assert_eq!((value.as_slice(), crc), (b.dict.value(DOMAIN), crc16(b.dict.value(DOMAIN))));
}

#[test]
fn block_upload_resends_the_same_bytes() {
    let mut b = Bench::<8>::new();
    assert_eq!(b.req(&[0xA0, 0x03, 0x20, 0, 5, 0, 0, 0]).expect("a response")[0], 0xC6);
    b.req(&[0xA3]);
    let first: Vec<[u8; 8]> = std::iter::from_fn(|| b.poll()).collect();
    assert_eq!(first.len(), 5);
    assert_eq!(b.req(&[0xA2, 2, 5]), None);
    let second: Vec<[u8; 8]> = std::iter::from_fn(|| b.poll()).collect();
    assert_eq!(second[0][1..], first[2][1..], "segment 3 resent as sequence number 1");
    assert_eq!(second[0][0], 1);
}

#[test]
fn protocol_switch_threshold_falls_back_to_a_normal_upload() {
    let mut b = Bench::<8>::new();
    // 4 bytes <= pst 4: expedited.
    assert_eq!(b.req(&[0xA4, 0x00, 0x20, 0, 10, 4, 0, 0]), Some(with_mux(0x43, U32, 0x1234_5678_u32.to_le_bytes())));
    assert!(b.server.is_idle());
    // 19 bytes <= pst 19: segmented.
    assert_eq!(b.req(&[0xA4, 0x02, 0x20, 0, 10, 19, 0, 0]), Some(with_mux(0x41, STRING, [19, 0, 0, 0])));
    assert_eq!(b.req(&[0x60]), Some(segment(0x00, b"coforge")));
    b.server.reset(&mut b.dict);
    // 19 bytes > pst 18: block.
    assert_eq!(b.req(&[0xA4, 0x02, 0x20, 0, 10, 18, 0, 0]), Some(with_mux(0xC6, STRING, [19, 0, 0, 0])));
    // pst 0: no switch, even for 4 bytes.
    assert_eq!(b.req(&[0xA4, 0x00, 0x20, 0, 10, 0, 0, 0]), Some(with_mux(0xC6, U32, [4, 0, 0, 0])));
}

#[test]
fn timeouts_abort_once_and_go_idle() {
    let mut b = Bench::<64>::new();
    b.req(&with_mux(0x21, STRING, [10, 0, 0, 0]));
    b.now = 999_999;
    assert_eq!(b.poll(), None);
    b.now = 1_000_000;
    assert_eq!(b.poll(), Some(abort(STRING, 0, SdoAbort::Timeout)));
    assert!(b.server.is_idle());
    b.now += 5_000_000;
    assert_eq!(b.poll(), None, "only once");
    // Every client frame restarts the clock.
    b.server.set_timeout_us(500);
    b.req(&with_mux(0x40, STRING, [0; 4]));
    b.now += 400;
    b.req(&[0x60]);
    b.now += 400;
    assert_eq!(b.poll(), None);
    b.now += 100;
    assert_eq!(b.poll(), Some(abort(STRING, 0, SdoAbort::Timeout)));
    assert_eq!(b.dict, Dict::new());
}

#[test]
fn block_upload_times_out_only_while_waiting_for_the_client() {
    let mut b = Bench::<8>::new();
    b.server.set_timeout_us(1_000);
    b.req(&[0xA0, 0x03, 0x20, 0, 3, 0, 0, 0]);
    b.req(&[0xA3]);
    // Sending takes longer than the timeout: each segment sent restarts the clock.
    for seq in 1..=3 {
        b.now += 2_000;
        assert_eq!(b.poll().expect("a segment")[0], seq);
    }
    b.now += 999;
    assert_eq!(b.poll(), None);
    b.now += 1;
    assert_eq!(b.poll(), Some(abort(DOMAIN, 0, SdoAbort::Timeout)));
}

#[test]
fn a_new_initiate_restarts_and_drops_the_old_transfer() {
    let mut b = Bench::<64>::new();
    b.req(&with_mux(0x21, STRING, [10, 0, 0, 0]));
    assert_eq!(b.req(&segment(0x00, b"0123456")), Some(segment(0x20, &[])));
    // The client starts over with something else.
    assert_eq!(b.req(&with_mux(0x23, U32, [9, 9, 9, 9])), Some(with_mux(0x60, U32, [0; 4])));
    assert_eq!(b.dict.value(STRING), b"coforge sdo string!", "the old download wrote nothing");
    assert_eq!(b.req(&segment(0x19, b"789")), Some(abort(0, 0, SdoAbort::UnknownCommand)), "its segments no longer belong anywhere");
    // An upload restarted by a download initiate.
    b.req(&with_mux(0x40, STRING, [0; 4]));
    download_segmented(&mut b, STRING, b"restarted", true);
    assert_eq!(b.dict.value(STRING), b"restarted");
}

#[test]
fn client_abort_drops_the_transfer_silently() {
    let mut b = Bench::<200>::new();
    b.req(&with_mux(0x21, STRING, [10, 0, 0, 0]));
    b.req(&segment(0x00, b"0123456"));
    assert_eq!(b.req(&abort(STRING, 0, SdoAbort::General)), None);
    assert!(b.server.is_idle());
    // During a block download sub-block, 0x80 is the client's abort, not a segment.
    b.req(&with_mux(0xC6, DOMAIN, [14, 0, 0, 0]));
    assert_eq!(b.req(&segment(0x01, b"ABCDEFG")), None);
    assert_eq!(b.req(&abort(DOMAIN, 0, SdoAbort::General)), None);
    assert!(b.server.is_idle());
    // During a block upload.
    b.req(&[0xA0, 0x03, 0x20, 0, 3, 0, 0, 0]);
    b.req(&[0xA3]);
    b.poll();
    assert_eq!(b.req(&[0x80]), None);
    assert_eq!(b.poll(), None);
    assert_eq!(b.dict, Dict::new());
    // With nothing in progress an abort is ignored too.
    assert_eq!(b.req(&[0x80]), None);
}

#[test]
fn reset_drops_the_transfer() {
    let mut b = Bench::<64>::new();
    b.req(&with_mux(0x20, STRING, [0; 4]));
    assert!(!b.server.is_idle());
    b.server.reset(&mut b.dict);
    assert!(b.server.is_idle());
    b.now = 10_000_000;
    assert_eq!(b.poll(), None, "no timeout for a dropped transfer");
    assert_eq!(b.req(&segment(0x01, b"x")), Some(abort(0, 0, SdoAbort::UnknownCommand)));
}

#[test]
fn short_requests_read_missing_bytes_as_zero() {
    let mut b = Bench::<64>::new();
    // Upload 2000h: the sub-index byte and the rest are missing.
    assert_eq!(b.req(&[0x40, 0x00, 0x20]), Some(with_mux(0x43, U32, 0x1234_5678_u32.to_le_bytes())));
    assert_eq!(b.req(&[]), Some(abort(0, 0, SdoAbort::UnknownCommand)), "an empty frame is a download segment");
    // Expedited download of 2 bytes of 0 with the data missing: the u32 refuses 2 bytes.
    assert_eq!(b.req(&[0x2B, 0x00, 0x20, 0x00]), Some(abort(U32, 0, SdoAbort::LengthTooLow)));
    // Longer than 8 bytes: the rest is ignored.
    assert_eq!(b.req(&[0x23, 0x00, 0x20, 0x00, 1, 2, 3, 4, 5, 6]), Some(with_mux(0x60, U32, [0; 4])));
    assert_eq!(b.dict.value(U32), [1, 2, 3, 4]);
}

#[test]
fn dictionary_codes_pass_through() {
    let mut b = Bench::<64>::new();
    assert_eq!(b.req(&with_mux(0x40, 0x3000, [0; 4])), Some(abort(0x3000, 0, SdoAbort::NoObject)));
    assert_eq!(b.req(&[0x40, 0x00, 0x20, 0x07]), Some(abort(U32, 7, SdoAbort::NoSubIndex)));
    assert_eq!(b.req(&[0xA0, 0x00, 0x20, 0x07, 10]), Some(abort(U32, 7, SdoAbort::NoSubIndex)));
    assert_eq!(b.req(&with_mux(0x2F, U8_RO, [1, 0, 0, 0])), Some(abort(U8_RO, 0, SdoAbort::ReadOnly)));
}
