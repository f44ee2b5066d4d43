//! The layout of every CiA 301 SDO frame (7.2.4.3): what the client sends, decoded into a
//! [`Request`], and what the server answers, built by the `*_frame` functions.
//!
//! Byte 0 carries the command specifier in bits 7..5 (`ccs` from the client, `scs` from the
//! server) and per-command flags below it; bytes 1..=3 the multiplexer (index LE, sub-index).
//! Block segments are the exception: byte 0 is `c` (bit 7) and the sequence number.

use crate::od::SdoAbort;

/// The object a transfer addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(super) struct Mux {
    pub(super) index: u16,
    pub(super) sub: u8,
}

impl Mux {
    fn bytes(self) -> [u8; 3] {
        let [lo, hi] = self.index.to_le_bytes();
        [lo, hi, self.sub]
    }
}

// Client command specifiers (byte 0, bits 7..5).
const CCS_DOWNLOAD_SEGMENT: u8 = 0;
const CCS_INITIATE_DOWNLOAD: u8 = 1;
const CCS_INITIATE_UPLOAD: u8 = 2;
const CCS_UPLOAD_SEGMENT: u8 = 3;
const CCS_ABORT: u8 = 4;
const CCS_BLOCK_UPLOAD: u8 = 5;
const CCS_BLOCK_DOWNLOAD: u8 = 6;

// Block upload client sub-commands (`cs`, bits 1..0).
const BLOCK_UPLOAD_INITIATE: u8 = 0;
const BLOCK_UPLOAD_END: u8 = 1;
const BLOCK_UPLOAD_ACK: u8 = 2;
const BLOCK_UPLOAD_START: u8 = 3;

// Server command bytes (scs in bits 7..5).
const SCS_UPLOAD_SEGMENT: u8 = 0x00;
const SCS_DOWNLOAD_SEGMENT: u8 = 0x20;
const SCS_INITIATE_UPLOAD: u8 = 0x40;
const SCS_INITIATE_DOWNLOAD: u8 = 0x60;
/// Also the client's: `ccs = 4`, the only frame with byte 0 = 0x80 outside block segments.
pub(super) const ABORT: u8 = 0x80;
const SCS_BLOCK_DOWNLOAD: u8 = 0xA0;
const SCS_BLOCK_UPLOAD: u8 = 0xC0;

// Flags.
const TOGGLE: u8 = 0x10;
/// `c` of a segment: no more segments follow.
const LAST: u8 = 0x01;
/// `e` of an initiate: expedited.
const EXPEDITED: u8 = 0x02;
/// `s` of an initiate: size indicated.
const SIZED: u8 = 0x01;
/// `cc`/`sc` of a block initiate: CRC supported.
const BLOCK_CRC: u8 = 0x04;
/// `s` of a block initiate.
const BLOCK_SIZED: u8 = 0x02;
/// `c` of a block segment.
const BLOCK_LAST: u8 = 0x80;
// Block sub-commands the server sends (`ss`).
const SS_ACK: u8 = 0x02;
const SS_END: u8 = 0x01;

/// Bytes a segment carries.
pub(super) const SEGMENT_DATA: usize = 7;

/// The request padded to 8 bytes: a short frame's missing bytes count as 0, bytes past the
/// eighth are ignored.
pub(super) fn pad(data: &[u8]) -> [u8; 8] {
    // SDO frames are 8 bytes long: a fixed-size copy, not a call of `memcpy`.
    if let Some(whole) = data.first_chunk::<8>() {
        return *whole;
    }
    let mut frame = [0; 8];
    frame.iter_mut().zip(data).for_each(|(dst, src)| *dst = *src);
    frame
}

/// Initiate download (ccs = 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct InitDownload {
    pub(super) mux: Mux,
    pub(super) expedited: bool,
    pub(super) sized: bool,
    /// Expedited and sized: bytes of `data` that carry no data.
    pub(super) n: u8,
    /// The data (expedited) or the size (segmented, sized).
    pub(super) data: [u8; 4],
}

/// A download segment (ccs = 0) or an upload segment request (ccs = 3, data unused).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Segment {
    pub(super) toggle: bool,
    /// Bytes of `data` that carry no data.
    pub(super) n: u8,
    pub(super) last: bool,
    pub(super) data: [u8; SEGMENT_DATA],
}

impl Segment {
    /// How many bytes of `data` are data.
    pub(super) fn len(&self) -> usize {
        SEGMENT_DATA.saturating_sub(usize::from(self.n))
    }
}

/// A block download segment: any byte 0 while a sub-block is being received.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct BlockSegment {
    pub(super) seq: u8,
    pub(super) last: bool,
    pub(super) data: [u8; SEGMENT_DATA],
}

impl BlockSegment {
    pub(super) fn parse(frame: &[u8; 8]) -> BlockSegment {
        let [b0, data @ ..] = *frame;
        BlockSegment { seq: b0 & !BLOCK_LAST, last: b0 & BLOCK_LAST != 0, data }
    }
}

/// A client request, decoded from its command byte alone (the server's state decides
/// whether it fits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Request {
    DownloadSegment(Segment),
    InitiateDownload(InitDownload),
    InitiateUpload {
        mux: Mux,
    },
    UploadSegment {
        toggle: bool,
    },
    Abort,
    BlockUploadInitiate {
        mux: Mux,
        crc: bool,
        blksize: u8,
        pst: u8,
    },
    BlockUploadStart,
    BlockUploadAck {
        ackseq: u8,
        blksize: u8,
    },
    BlockUploadEnd,
    BlockDownloadInitiate {
        mux: Mux,
        crc: bool,
        size: Option<u32>,
    },
    BlockDownloadEnd {
        n: u8,
        crc: u16,
    },
    /// ccs = 7: no such command; `mux` is bytes 1..=3 taken at face value.
    Unknown {
        mux: Mux,
    },
}

impl Request {
    /// Whether the request starts a transfer.
    pub(super) fn initiates(&self) -> bool {
        matches!(
            self,
            Request::InitiateDownload(_) | Request::InitiateUpload { .. } | Request::BlockDownloadInitiate { .. } | Request::BlockUploadInitiate { .. }
        )
    }

    pub(super) fn parse(frame: &[u8; 8]) -> Request {
        let [b0, i0, i1, sub, d0, d1, d2, d3] = *frame;
        let mux = Mux { index: u16::from_le_bytes([i0, i1]), sub };
        let data = [d0, d1, d2, d3];
        let toggle = b0 & TOGGLE != 0;
        match b0 >> 5 {
            CCS_DOWNLOAD_SEGMENT => {
                Request::DownloadSegment(Segment { toggle, n: (b0 >> 1) & 0x07, last: b0 & LAST != 0, data: [i0, i1, sub, d0, d1, d2, d3] })
            }
            CCS_INITIATE_DOWNLOAD => {
                Request::InitiateDownload(InitDownload { mux, expedited: b0 & EXPEDITED != 0, sized: b0 & SIZED != 0, n: (b0 >> 2) & 0x03, data })
            }
            CCS_INITIATE_UPLOAD => Request::InitiateUpload { mux },
            CCS_UPLOAD_SEGMENT => Request::UploadSegment { toggle },
            CCS_ABORT => Request::Abort,
            CCS_BLOCK_UPLOAD => match b0 & 0x03 {
                BLOCK_UPLOAD_INITIATE => Request::BlockUploadInitiate { mux, crc: b0 & BLOCK_CRC != 0, blksize: d0, pst: d1 },
                BLOCK_UPLOAD_END => Request::BlockUploadEnd,
                BLOCK_UPLOAD_ACK => Request::BlockUploadAck { ackseq: i0, blksize: i1 },
                // `cs` is two bits: start is the only value left.
                BLOCK_UPLOAD_START | 4..=u8::MAX => Request::BlockUploadStart,
            },
            CCS_BLOCK_DOWNLOAD if b0 & 0x01 == 0 => {
                let size = (b0 & BLOCK_SIZED != 0).then_some(u32::from_le_bytes(data));
                Request::BlockDownloadInitiate { mux, crc: b0 & BLOCK_CRC != 0, size }
            }
            CCS_BLOCK_DOWNLOAD => Request::BlockDownloadEnd { n: (b0 >> 2) & 0x07, crc: u16::from_le_bytes([i0, i1]) },
            _ => Request::Unknown { mux },
        }
    }
}

fn with_mux(command: u8, mux: Mux, data: [u8; 4]) -> [u8; 8] {
    let [m0, m1, m2] = mux.bytes();
    let [d0, d1, d2, d3] = data;
    [command, m0, m1, m2, d0, d1, d2, d3]
}

fn with_bytes(command: u8, data: [u8; 7]) -> [u8; 8] {
    let [d0, d1, d2, d3, d4, d5, d6] = data;
    [command, d0, d1, d2, d3, d4, d5, d6]
}

/// Abort transfer: [0x80, index LE, sub, code LE].
pub(super) fn abort_frame(mux: Mux, code: SdoAbort) -> [u8; 8] {
    with_mux(ABORT, mux, code.code().to_le_bytes())
}

/// Whether a frame is an abort (client or server).
pub(super) fn is_abort(frame: &[u8; 8]) -> bool {
    frame.first() == Some(&ABORT)
}

/// Initiate download response.
pub(super) fn download_initiate_frame(mux: Mux) -> [u8; 8] {
    with_mux(SCS_INITIATE_DOWNLOAD, mux, [0; 4])
}

/// Download segment response, echoing the segment's toggle bit.
pub(super) fn download_segment_frame(toggle: bool) -> [u8; 8] {
    with_bytes(SCS_DOWNLOAD_SEGMENT | if toggle { TOGGLE } else { 0 }, [0; 7])
}

/// Expedited initiate upload response with size indicated; `data` holds 1..=4 bytes.
pub(super) fn upload_expedited_frame(mux: Mux, data: &[u8]) -> [u8; 8] {
    let mut bytes = [0; 4];
    bytes.iter_mut().zip(data).for_each(|(dst, src)| *dst = *src);
    let n = 4_usize.saturating_sub(data.len()).min(3) as u8;
    with_mux(SCS_INITIATE_UPLOAD | n << 2 | EXPEDITED | SIZED, mux, bytes)
}

/// Segmented initiate upload response with the size indicated.
pub(super) fn upload_initiate_frame(mux: Mux, size: u32) -> [u8; 8] {
    with_mux(SCS_INITIATE_UPLOAD | SIZED, mux, size.to_le_bytes())
}

/// Upload segment response: the first `len` bytes of `data` are data.
pub(super) fn upload_segment_frame(toggle: bool, data: [u8; 7], len: usize, last: bool) -> [u8; 8] {
    let n = SEGMENT_DATA.saturating_sub(len) as u8;
    let command = SCS_UPLOAD_SEGMENT | if toggle { TOGGLE } else { 0 } | n << 1 | if last { LAST } else { 0 };
    with_bytes(command, data)
}

/// Block download initiate response: the server always offers CRC (`sc = 1`).
pub(super) fn block_download_initiate_frame(mux: Mux, blksize: u8) -> [u8; 8] {
    with_mux(SCS_BLOCK_DOWNLOAD | BLOCK_CRC, mux, [blksize, 0, 0, 0])
}

/// Block download sub-block acknowledgement.
pub(super) fn block_download_ack_frame(ackseq: u8, blksize: u8) -> [u8; 8] {
    with_bytes(SCS_BLOCK_DOWNLOAD | SS_ACK, [ackseq, blksize, 0, 0, 0, 0, 0])
}

/// Block download end response.
pub(super) fn block_download_end_frame() -> [u8; 8] {
    with_bytes(SCS_BLOCK_DOWNLOAD | SS_END, [0; 7])
}

/// Block upload initiate response: CRC offered (`sc = 1`), size indicated.
pub(super) fn block_upload_initiate_frame(mux: Mux, size: u32) -> [u8; 8] {
    with_mux(SCS_BLOCK_UPLOAD | BLOCK_CRC | BLOCK_SIZED, mux, size.to_le_bytes())
}

/// A block upload segment; `seq` is 1..=127.
pub(super) fn block_segment_frame(seq: u8, last: bool, data: [u8; 7]) -> [u8; 8] {
    with_bytes(seq & !BLOCK_LAST | if last { BLOCK_LAST } else { 0 }, data)
}

/// Block upload end request: `n` bytes of the last segment carried no data.
pub(super) fn block_upload_end_frame(n: u8, crc: u16) -> [u8; 8] {
    let [c0, c1] = crc.to_le_bytes();
    with_bytes(SCS_BLOCK_UPLOAD | (n & 0x07) << 2 | SS_END, [c0, c1, 0, 0, 0, 0, 0])
}

// The client side: what a client sends (built by the `*_request` functions) and what it
// reads from the server, decoded into a [`Response`].

/// A server response, decoded from its command byte alone (the client's state decides
/// whether it fits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Response {
    /// scs = 2: expedited (the data in `data`, `4 - n` bytes if sized) or segmented (the size
    /// in `data` if sized).
    UploadInitiate { mux: Mux, expedited: bool, sized: bool, n: u8, data: [u8; 4] },
    /// scs = 0.
    UploadSegment(Segment),
    /// scs = 3.
    DownloadInitiate { mux: Mux },
    /// scs = 1.
    DownloadSegment { toggle: bool },
    /// scs = 4: the server's code, unchanged (it may be one CiA 301 does not list).
    Abort { mux: Mux, code: u32 },
    /// scs = 5, 6 or 7: block transfer responses and undefined specifiers, which no
    /// expedited or segmented transfer expects.
    Other,
}

impl Response {
    pub(super) fn parse(frame: &[u8; 8]) -> Response {
        let [b0, i0, i1, sub, d0, d1, d2, d3] = *frame;
        let mux = Mux { index: u16::from_le_bytes([i0, i1]), sub };
        let data = [d0, d1, d2, d3];
        match b0 & 0xE0 {
            SCS_UPLOAD_SEGMENT => {
                Response::UploadSegment(Segment { toggle: b0 & TOGGLE != 0, n: (b0 >> 1) & 0x07, last: b0 & LAST != 0, data: [i0, i1, sub, d0, d1, d2, d3] })
            }
            SCS_DOWNLOAD_SEGMENT => Response::DownloadSegment { toggle: b0 & TOGGLE != 0 },
            SCS_INITIATE_UPLOAD => Response::UploadInitiate { mux, expedited: b0 & EXPEDITED != 0, sized: b0 & SIZED != 0, n: (b0 >> 2) & 0x03, data },
            SCS_INITIATE_DOWNLOAD => Response::DownloadInitiate { mux },
            ABORT => Response::Abort { mux, code: u32::from_le_bytes(data) },
            _ => Response::Other,
        }
    }
}

/// Initiate upload request.
pub(super) fn upload_initiate_request(mux: Mux) -> [u8; 8] {
    with_mux(CCS_INITIATE_UPLOAD << 5, mux, [0; 4])
}

/// Upload segment request.
pub(super) fn upload_segment_request(toggle: bool) -> [u8; 8] {
    with_bytes(CCS_UPLOAD_SEGMENT << 5 | if toggle { TOGGLE } else { 0 }, [0; 7])
}

/// Expedited initiate download request with size indicated; `data` holds 1..=4 bytes.
pub(super) fn download_expedited_request(mux: Mux, data: &[u8]) -> [u8; 8] {
    let mut bytes = [0; 4];
    bytes.iter_mut().zip(data).for_each(|(dst, src)| *dst = *src);
    let n = 4_usize.saturating_sub(data.len()).min(3) as u8;
    with_mux(CCS_INITIATE_DOWNLOAD << 5 | n << 2 | EXPEDITED | SIZED, mux, bytes)
}

/// Segmented initiate download request with the size indicated.
pub(super) fn download_initiate_request(mux: Mux, size: u32) -> [u8; 8] {
    with_mux(CCS_INITIATE_DOWNLOAD << 5 | SIZED, mux, size.to_le_bytes())
}

/// Download segment request: the same layout as the server's upload segment (ccs = scs = 0).
pub(super) fn download_segment_request(toggle: bool, data: [u8; 7], len: usize, last: bool) -> [u8; 8] {
    upload_segment_frame(toggle, data, len, last)
}

#[cfg(test)]
mod tests {
    use super::*;

    const MUX: Mux = Mux { index: 0x1018, sub: 2 };

    #[test]
    fn short_requests_are_zero_padded() {
        assert_eq!(pad(&[0x40, 0x18, 0x10]), [0x40, 0x18, 0x10, 0, 0, 0, 0, 0]);
        assert_eq!(pad(&[1; 12]), [1; 8]);
        assert_eq!(pad(&[]), [0; 8]);
    }

    #[test]
    fn client_commands_decode() {
        let expedited = Request::parse(&[0x2B, 0x18, 0x10, 0x02, 0x34, 0x12, 0, 0]);
        assert_eq!(expedited, Request::InitiateDownload(InitDownload { mux: MUX, expedited: true, sized: true, n: 2, data: [0x34, 0x12, 0, 0] }));
        assert_eq!(Request::parse(&[0x40, 0x18, 0x10, 0x02, 0, 0, 0, 0]), Request::InitiateUpload { mux: MUX });
        let segment = Request::parse(&[0x1B, 1, 2, 3, 4, 5, 6, 7]);
        assert_eq!(segment, Request::DownloadSegment(Segment { toggle: true, n: 5, last: true, data: [1, 2, 3, 4, 5, 6, 7] }));
        assert_eq!(Request::parse(&[0x70, 0, 0, 0, 0, 0, 0, 0]), Request::UploadSegment { toggle: true });
        assert_eq!(Request::parse(&[0x80, 0, 0, 0, 0, 0, 0, 0]), Request::Abort);
        assert_eq!(Request::parse(&[0xA4, 0x18, 0x10, 0x02, 33, 9, 0, 0]), Request::BlockUploadInitiate { mux: MUX, crc: true, blksize: 33, pst: 9 });
        assert_eq!(Request::parse(&[0xA3, 0, 0, 0, 0, 0, 0, 0]), Request::BlockUploadStart);
        assert_eq!(Request::parse(&[0xA2, 5, 10, 0, 0, 0, 0, 0]), Request::BlockUploadAck { ackseq: 5, blksize: 10 });
        assert_eq!(Request::parse(&[0xA1, 0, 0, 0, 0, 0, 0, 0]), Request::BlockUploadEnd);
        let block = Request::parse(&[0xC6, 0x18, 0x10, 0x02, 200, 0, 0, 0]);
        assert_eq!(block, Request::BlockDownloadInitiate { mux: MUX, crc: true, size: Some(200) });
        assert_eq!(Request::parse(&[0xC0, 0x18, 0x10, 0x02, 200, 0, 0, 0]), Request::BlockDownloadInitiate { mux: MUX, crc: false, size: None });
        assert_eq!(Request::parse(&[0xD5, 0xC3, 0x31, 0, 0, 0, 0, 0]), Request::BlockDownloadEnd { n: 5, crc: 0x31C3 });
        assert_eq!(Request::parse(&[0xE0, 0x18, 0x10, 0x02, 0, 0, 0, 0]), Request::Unknown { mux: MUX });
        assert_eq!(BlockSegment::parse(&[0x85, 1, 2, 3, 4, 5, 6, 7]), BlockSegment { seq: 5, last: true, data: [1, 2, 3, 4, 5, 6, 7] });
    }

    #[test]
    fn client_requests_encode_and_server_responses_decode() {
        assert_eq!(upload_initiate_request(MUX), [0x40, 0x18, 0x10, 0x02, 0, 0, 0, 0]);
        assert_eq!(upload_segment_request(true), [0x70, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(upload_segment_request(false), [0x60, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(download_expedited_request(MUX, &[0x34, 0x12]), [0x2B, 0x18, 0x10, 0x02, 0x34, 0x12, 0, 0]);
        assert_eq!(download_expedited_request(MUX, &[1, 2, 3, 4]), [0x23, 0x18, 0x10, 0x02, 1, 2, 3, 4]);
        assert_eq!(download_initiate_request(MUX, 300), [0x21, 0x18, 0x10, 0x02, 0x2C, 0x01, 0, 0]);
        assert_eq!(download_segment_request(true, [5; 7], 3, true), [0x19, 5, 5, 5, 5, 5, 5, 5]);
        // What the client sends is what the server reads, and the other way round.
        assert_eq!(Request::parse(&download_expedited_request(MUX, &[0x34, 0x12])), Request::parse(&[0x2B, 0x18, 0x10, 0x02, 0x34, 0x12, 0, 0]));
        assert_eq!(Request::parse(&upload_segment_request(true)), Request::UploadSegment { toggle: true });
        assert_eq!(
            Response::parse(&upload_expedited_frame(MUX, &[0xAA])),
            Response::UploadInitiate { mux: MUX, expedited: true, sized: true, n: 3, data: [0xAA, 0, 0, 0] }
        );
        assert_eq!(
            Response::parse(&upload_initiate_frame(MUX, 300)),
            Response::UploadInitiate { mux: MUX, expedited: false, sized: true, n: 0, data: [0x2C, 0x01, 0, 0] }
        );
        let segment = Response::parse(&upload_segment_frame(true, [9, 8, 0, 0, 0, 0, 0], 2, true));
        assert_eq!(segment, Response::UploadSegment(Segment { toggle: true, n: 5, last: true, data: [9, 8, 0, 0, 0, 0, 0] }));
        assert_eq!(Response::parse(&download_initiate_frame(MUX)), Response::DownloadInitiate { mux: MUX });
        assert_eq!(Response::parse(&download_segment_frame(true)), Response::DownloadSegment { toggle: true });
        assert_eq!(Response::parse(&abort_frame(MUX, SdoAbort::ToggleBit)), Response::Abort { mux: MUX, code: 0x0503_0000 });
        assert_eq!(Response::parse(&[0xAB, 0x18, 0x10, 0x02, 0, 0, 0, 0]), Response::Other);
        assert_eq!(Response::parse(&block_download_ack_frame(1, 2)), Response::Other);
    }

    #[test]
    fn server_frames_encode() {
        assert_eq!(abort_frame(MUX, SdoAbort::ToggleBit), [0x80, 0x18, 0x10, 0x02, 0x00, 0x00, 0x03, 0x05]);
        assert_eq!(download_initiate_frame(MUX), [0x60, 0x18, 0x10, 0x02, 0, 0, 0, 0]);
        assert_eq!(download_segment_frame(true), [0x30, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(upload_expedited_frame(MUX, &[0xAA]), [0x4F, 0x18, 0x10, 0x02, 0xAA, 0, 0, 0]);
        assert_eq!(upload_expedited_frame(MUX, &[1, 2, 3, 4]), [0x43, 0x18, 0x10, 0x02, 1, 2, 3, 4]);
        assert_eq!(upload_initiate_frame(MUX, 300), [0x41, 0x18, 0x10, 0x02, 0x2C, 0x01, 0, 0]);
        assert_eq!(upload_segment_frame(true, [9, 8, 0, 0, 0, 0, 0], 2, true), [0x1B, 9, 8, 0, 0, 0, 0, 0]);
        assert_eq!(upload_segment_frame(false, [1; 7], 7, false), [0x00, 1, 1, 1, 1, 1, 1, 1]);
        assert_eq!(block_download_initiate_frame(MUX, 127), [0xA4, 0x18, 0x10, 0x02, 127, 0, 0, 0]);
        assert_eq!(block_download_ack_frame(3, 20), [0xA2, 3, 20, 0, 0, 0, 0, 0]);
        assert_eq!(block_download_end_frame(), [0xA1, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(block_upload_initiate_frame(MUX, 200), [0xC6, 0x18, 0x10, 0x02, 200, 0, 0, 0]);
        assert_eq!(block_segment_frame(3, true, [1; 7]), [0x83, 1, 1, 1, 1, 1, 1, 1]);
        assert_eq!(block_upload_end_frame(5, 0x31C3), [0xD5, 0xC3, 0x31, 0, 0, 0, 0, 0]);
    }
}
