//! Block transfer (CiA 301 7.2.4.3.9 to 7.2.4.3.16), with the optional CRC.
//!
//! Download collects the value in the server's buffer and writes it after the end request,
//! or, streaming, hands each in-order segment to the target and checks the CRC as it goes;
//! upload reads each segment from the target by offset, so it needs no buffer at all and
//! can resend any segment the client did not acknowledge.

// CRC-16-CCITT, polynomial 0x1021, initial value 0 (CiA 301 7.2.4.3.16): XMODEM.
use coforge_link::crc::CCITT as CRC;

use super::command::{self, BlockSegment, Mux, SEGMENT_DATA};
use super::segmented::{read_segment, start_upload};
use super::{SdoTarget, Started, State, Step, too_long};
use crate::od::SdoAbort;

/// The largest sub-block CiA 301 allows.
const MAX_BLKSIZE: u8 = 127;

/// `n / SEGMENT_DATA` (7) without a division instruction, which a Cortex-M0 lacks: these
/// are the server's only divisions by a number that is not a power of two, and a libcall
/// would link the 400-byte software divider.
fn whole_segments(n: usize) -> usize {
    const _: () = assert!(SEGMENT_DATA == 7);
    match u32::try_from(n) {
        // Multiply-high by 2^32/7 rounded up, then the add-back step that makes it exact for
        // every u32 (Hacker's Delight 10-8).
        Ok(n) => {
            let high = ((u64::from(n) * 0x2492_4925) >> 32) as u32;
            ((((n - high) >> 1) + high) >> 2) as usize
        }
        Err(_) => n / SEGMENT_DATA,
    }
}

/// Segments that `n` bytes take: `n.div_ceil(SEGMENT_DATA)`.
fn segments_for(n: usize) -> usize {
    let whole = whole_segments(n);
    if whole * SEGMENT_DATA == n { whole } else { whole + 1 }
}

/// Segments per sub-block the server can take with `free` bytes of buffer left: what fits,
/// at least 1 (the last segment may be short) and at most 127.
fn blksize_for(free: usize) -> u8 {
    u8::try_from(whole_segments(free)).unwrap_or(MAX_BLKSIZE).clamp(1, MAX_BLKSIZE)
}

/// A client's block size: 1..=127, else `InvalidBlockSize`.
fn check_blksize(blksize: u8) -> Result<u8, SdoAbort> {
    if (1..=MAX_BLKSIZE).contains(&blksize) { Ok(blksize) } else { Err(SdoAbort::InvalidBlockSize) }
}

/// A block download in progress.
#[derive(Debug)]
pub(super) struct Download {
    pub(super) mux: Mux,
    size: Option<usize>,
    /// Both sides support CRC: the client said so, the server always does.
    crc: bool,
    /// Each in-order segment goes to the target at once ([`SdoTarget::write_part`]).
    pub(super) stream: bool,
    /// Streaming: the CRC of the bytes handed over so far.
    crc_so_far: u16,
    /// Segments in the current sub-block, as last announced.
    blksize: u8,
    /// Segments of the current sub-block received in order.
    in_order: u8,
    /// A segment was lost or repeated: the rest of the sub-block is ignored.
    skipping: bool,
    /// Bytes received in order, counting the padding of the last segment.
    received: usize,
    /// The last segment is in: only the end request may follow.
    ended: bool,
}

/// Initiate block download. It streams only with its size indicated: the padding of the
/// last segment is known only from the end request, and the buffer may be too small to hold
/// that segment back until then.
pub(super) fn initiate_download<T: SdoTarget>(mux: Mux, crc: bool, size: Option<u32>, capacity: usize, target: &mut T) -> Started {
    let size = size.map(usize::try_from).transpose().map_err(|_| SdoAbort::LengthTooHigh)?;
    target.check_download(mux.index, mux.sub, size)?;
    let stream = T::STREAMING && size.is_some() && target.streams(mux.index, mux.sub);
    if !stream && size.is_some_and(|size| size > capacity) {
        return Err(SdoAbort::OutOfMemory);
    }
    let blksize = blksize_for(if stream { usize::MAX } else { capacity });
    let download = Download { mux, size, crc, stream, crc_so_far: CRC.start(), blksize, in_order: 0, skipping: false, received: 0, ended: false };
    Ok((State::BlockDownload(download), command::block_download_initiate_frame(mux, blksize)))
}

impl Download {
    /// Whether a sub-block is being received: every frame is then a segment.
    pub(super) fn receiving(&self) -> bool {
        !self.ended
    }

    /// A segment of the current sub-block. Sequence number 0 aborts; any other number out
    /// of order (a lost or repeated segment) makes the server ignore the rest of the
    /// sub-block and acknowledge the last in-order segment when the sub-block ends, so the
    /// client resends from there.
    pub(super) fn segment<T: SdoTarget>(&mut self, seg: &BlockSegment, buf: &mut [u8], target: &mut T) -> Result<Step, SdoAbort> {
        if seg.seq == 0 {
            return Err(SdoAbort::InvalidSequence);
        }
        // A streamed download keeps nothing: sub-blocks are as large as CiA 301 allows.
        let capacity = if T::STREAMING && self.stream { usize::MAX } else { buf.len() };
        let sub_block_over = seg.last || seg.seq >= self.blksize;
        if self.skipping || seg.seq != self.in_order.saturating_add(1) {
            self.skipping = true;
            return Ok(Step::Continue(sub_block_over.then(|| self.acknowledge(capacity))));
        }
        let start = self.received;
        self.received = start.saturating_add(SEGMENT_DATA);
        if T::STREAMING && self.stream {
            self.stream_segment(seg, start, target)?;
        } else {
            if !seg.last && self.received > buf.len() {
                return Err(too_long(target, self.mux, self.received));
            }
            // The last segment may carry padding past the buffer: only the end request says how much.
            let fits = buf.len().saturating_sub(start).min(SEGMENT_DATA);
            if let (Some(dst), Some(src)) = (buf.get_mut(start..start.saturating_add(fits)), seg.data.get(..fits)) {
                dst.copy_from_slice(src);
            }
        }
        self.in_order = seg.seq;
        self.ended = seg.last;
        Ok(Step::Continue(sub_block_over.then(|| self.acknowledge(capacity))))
    }

    /// An in-order segment of a streamed download, from byte `start`: its bytes up to the
    /// indicated size go to the target (the rest of the last segment is padding), never as
    /// the last part: that waits for the end request's length and CRC.
    fn stream_segment(&mut self, seg: &BlockSegment, start: usize, target: &mut impl SdoTarget) -> Result<(), SdoAbort> {
        let size = self.size.unwrap_or_default();
        // Data past the indicated size: a segment that is not the last must be full, and
        // only an empty value has a segment starting at its size.
        if !seg.last && self.received > size || start > 0 && start >= size {
            return Err(SdoAbort::LengthTooHigh);
        }
        let data = seg.data.get(..size.saturating_sub(start).min(SEGMENT_DATA)).unwrap_or_default();
        if self.crc {
            self.crc_so_far = CRC.update(self.crc_so_far, data);
        }
        target.write_part(self.mux.index, self.mux.sub, start, data, false)
    }

    /// Acknowledges the in-order segments of the sub-block and announces the next one's size.
    fn acknowledge(&mut self, capacity: usize) -> [u8; 8] {
        let ackseq = self.in_order;
        self.blksize = blksize_for(capacity.saturating_sub(self.received));
        self.in_order = 0;
        self.skipping = false;
        command::block_download_ack_frame(ackseq, self.blksize)
    }

    /// The end request: `n` bytes of the last segment carried no data. Checks the length
    /// (buffer, then the indicated size) and the CRC if negotiated, then writes.
    pub(super) fn end<T: SdoTarget>(&self, n: u8, crc: u16, buf: &[u8], target: &mut T) -> Result<Step, SdoAbort> {
        let len = self.received.saturating_sub(usize::from(n));
        if T::STREAMING && self.stream {
            return self.end_stream(len, crc, target);
        }
        let Some(data) = buf.get(..len) else { return Err(too_long(target, self.mux, len)) };
        self.check_size(len)?;
        if self.crc && CRC.checksum(data) != crc {
            return Err(SdoAbort::BlockCrc);
        }
        target.write(self.mux.index, self.mux.sub, data)?;
        Ok(Step::Finish(Some(command::block_download_end_frame())))
    }

    /// The end of a streamed download of `len` bytes: the same checks on what was handed
    /// over, then the target's last (empty) part.
    fn end_stream(&self, len: usize, crc: u16, target: &mut impl SdoTarget) -> Result<Step, SdoAbort> {
        self.check_size(len)?;
        if self.crc && CRC.finish(self.crc_so_far) != crc {
            return Err(SdoAbort::BlockCrc);
        }
        target.write_part(self.mux.index, self.mux.sub, len, &[], true)?;
        Ok(Step::Finish(Some(command::block_download_end_frame())))
    }

    /// The received length against the indicated size.
    fn check_size(&self, len: usize) -> Result<(), SdoAbort> {
        match self.size {
            Some(size) if len > size => Err(SdoAbort::LengthTooHigh),
            Some(size) if len < size => Err(SdoAbort::LengthTooLow),
            _ => Ok(()),
        }
    }
}

/// Where a block upload stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Initiate answered; waiting for the client's start.
    Initiated,
    /// Sending a sub-block of `count` segments, `sent` of them so far (one per poll), then
    /// waiting for the acknowledgement.
    SubBlock { sent: u8, count: u8 },
    /// End request sent; waiting for the client's end response.
    End,
}

/// A block upload in progress.
#[derive(Debug)]
pub(super) struct Upload {
    pub(super) mux: Mux,
    total: usize,
    /// The running CRC if both sides support it.
    crc: Option<u16>,
    /// Bytes the CRC covers: segments are added the first time they are sent, in order.
    crc_len: usize,
    /// The client's block size for the next sub-block.
    blksize: u8,
    /// Segments the client acknowledged.
    acked: usize,
    phase: Phase,
}

/// Initiate block upload. With a protocol switch threshold (`pst != 0`) and a value of at
/// most `pst` bytes, CiA 301 lets the server answer with a normal upload (expedited or
/// segmented) instead.
pub(super) fn initiate_upload(mux: Mux, crc: bool, blksize: u8, pst: u8, target: &mut impl SdoTarget) -> Started {
    let blksize = check_blksize(blksize)?;
    let mut first = [0; 4];
    let len = target.read(mux.index, mux.sub, 0, &mut first)?;
    if pst != 0 && len.total <= usize::from(pst) {
        return start_upload(mux, len, first);
    }
    let size = u32::try_from(len.total).map_err(|_| SdoAbort::LengthTooHigh)?;
    let upload = Upload { mux, total: len.total, crc: crc.then(|| CRC.start()), crc_len: 0, blksize, acked: 0, phase: Phase::Initiated };
    Ok((State::BlockUpload(upload), command::block_upload_initiate_frame(mux, size)))
}

impl Upload {
    /// Segments the value takes; an empty value still sends one (empty, last) segment.
    fn segments(&self) -> usize {
        segments_for(self.total).max(1)
    }

    /// The first sub-block from where the client acknowledged.
    fn sub_block(&self) -> Phase {
        let left = self.segments().saturating_sub(self.acked);
        Phase::SubBlock { sent: 0, count: u8::try_from(left).unwrap_or(MAX_BLKSIZE).min(self.blksize) }
    }

    /// The client's start: the first sub-block goes out through `poll`.
    pub(super) fn start(&mut self) -> Result<Step, SdoAbort> {
        if self.phase != Phase::Initiated {
            return Err(SdoAbort::UnknownCommand);
        }
        self.phase = self.sub_block();
        Ok(Step::Continue(None))
    }

    /// The next segment of the sub-block being sent, if any.
    pub(super) fn next_segment(&mut self, target: &mut impl SdoTarget) -> Result<Option<[u8; 8]>, SdoAbort> {
        let Phase::SubBlock { sent, count } = self.phase else { return Ok(None) };
        if sent >= count {
            return Ok(None);
        }
        let segment = self.acked.saturating_add(usize::from(sent));
        let offset = segment.saturating_mul(SEGMENT_DATA);
        let (data, len) = read_segment(target, self.mux, offset, self.total)?;
        if let Some(crc) = self.crc
            && offset == self.crc_len
        {
            self.crc = Some(CRC.update(crc, data.get(..len).unwrap_or_default()));
            self.crc_len = offset.saturating_add(len);
        }
        let seq = sent.saturating_add(1);
        self.phase = Phase::SubBlock { sent: seq, count };
        Ok(Some(command::block_segment_frame(seq, segment.saturating_add(1) >= self.segments(), data)))
    }

    /// The client's acknowledgement: `ackseq` segments of the sub-block arrived. Resends
    /// from the first one missing, or ends with `n` and the CRC once all are in.
    pub(super) fn ack(&mut self, ackseq: u8, blksize: u8) -> Result<Step, SdoAbort> {
        let Phase::SubBlock { sent, .. } = self.phase else { return Err(SdoAbort::UnknownCommand) };
        if ackseq > sent {
            return Err(SdoAbort::InvalidSequence);
        }
        self.blksize = check_blksize(blksize)?;
        self.acked = self.acked.saturating_add(usize::from(ackseq));
        if self.acked < self.segments() {
            self.phase = self.sub_block();
            return Ok(Step::Continue(None));
        }
        self.phase = Phase::End;
        let padding = self.segments().saturating_mul(SEGMENT_DATA).saturating_sub(self.total);
        let n = u8::try_from(padding).unwrap_or(0);
        let crc = self.crc.map_or(0, |crc| CRC.finish(crc));
        Ok(Step::Continue(Some(command::block_upload_end_frame(n, crc))))
    }

    /// The client's end response closes the transfer.
    pub(super) fn end(&mut self) -> Result<Step, SdoAbort> {
        if self.phase != Phase::End {
            return Err(SdoAbort::UnknownCommand);
        }
        Ok(Step::Finish(None))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_is_ccitt_xmodem() {
        assert_eq!(CRC.checksum(b"123456789"), 0x31C3);
        assert_eq!(CRC.checksum(b""), 0);
    }

    #[test]
    fn block_size_fits_the_free_buffer() {
        assert_eq!(blksize_for(0), 1);
        assert_eq!(blksize_for(6), 1);
        assert_eq!(blksize_for(14), 2);
        assert_eq!(blksize_for(200), 28);
        assert_eq!(blksize_for(127 * 7), 127);
        assert_eq!(blksize_for(usize::MAX), 127);
        assert_eq!(check_blksize(0), Err(SdoAbort::InvalidBlockSize));
        assert_eq!(check_blksize(128), Err(SdoAbort::InvalidBlockSize));
        assert_eq!(check_blksize(127), Ok(127));
    }

    #[test]
    fn segment_counts_equal_the_divisions() {
        let check = |n: usize| {
            assert_eq!(whole_segments(n), n / 7, "{n}");
            assert_eq!(segments_for(n), n.div_ceil(7), "{n}");
        };
        (0..200_000).for_each(check);
        // Near every power of two, the ends of u32 and, on 64-bit hosts, beyond.
        for bit in 3..usize::BITS {
            let p = 1_usize << bit;
            (p - 8..=p + 8).for_each(check);
        }
        (u32::MAX as usize - 100_000..=u32::MAX as usize).for_each(check);
        (usize::MAX - 8..=usize::MAX).for_each(check);
        // A spread of other values (a fixed LCG).
        let mut x = 1_u32;
        for _ in 0..1_000_000 {
            x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            check(x as usize);
        }
    }
}
