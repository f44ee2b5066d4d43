//! Expedited and segmented transfer (CiA 301 7.2.4.3.3 to 7.2.4.3.8).

use super::command::{self, InitDownload, Mux, SEGMENT_DATA, Segment};
use super::{SdoTarget, Started, State, Step, too_long};
use crate::od::{ReadLen, SdoAbort};

/// A segmented download in progress; the value collects in the server's buffer and reaches
/// the target only after the last segment, unless it streams.
#[derive(Debug)]
pub(super) struct Download {
    pub(super) mux: Mux,
    /// The toggle bit the next segment must carry (the first carries 0).
    toggle: bool,
    /// Each segment goes to the target at once ([`SdoTarget::write_part`]), not to the buffer.
    pub(super) stream: bool,
    /// The size the client indicated, if it did.
    size: Option<usize>,
    /// Bytes received so far.
    len: usize,
}

/// Initiate download: an expedited one is written at once, a segmented one starts.
///
/// Expedited with `s = 0` carries "an unspecified number of bytes": the entry's own size if
/// it has a fixed one of at most 4 bytes, otherwise all four bytes, and the dictionary's
/// length check decides.
pub(super) fn initiate_download<T: SdoTarget>(init: &InitDownload, capacity: usize, target: &mut T) -> Started {
    let mux = init.mux;
    if init.expedited {
        let len = if init.sized { 4 - usize::from(init.n) } else { target.fixed_size(mux.index, mux.sub).filter(|&n| n <= 4).unwrap_or(4) };
        let data = init.data.get(..len).ok_or(SdoAbort::General)?;
        target.check_download(mux.index, mux.sub, Some(len))?;
        target.write(mux.index, mux.sub, data)?;
        return Ok((State::Idle, command::download_initiate_frame(mux)));
    }
    let size = if init.sized { Some(usize::try_from(u32::from_le_bytes(init.data)).map_err(|_| SdoAbort::LengthTooHigh)?) } else { None };
    target.check_download(mux.index, mux.sub, size)?;
    let stream = T::STREAMING && target.streams(mux.index, mux.sub);
    // The dictionary would take it, but the buffer cannot hold it.
    if !stream && size.is_some_and(|size| size > capacity) {
        return Err(SdoAbort::OutOfMemory);
    }
    Ok((State::Download(Download { mux, toggle: false, stream, size, len: 0 }), command::download_initiate_frame(mux)))
}

impl Download {
    /// A download segment. More data than indicated aborts at once (`LengthTooHigh`), less
    /// after the last segment (`LengthTooLow`): the more specific codes rather than the
    /// generic `LengthMismatch`.
    pub(super) fn segment<T: SdoTarget>(&mut self, seg: &Segment, buf: &mut [u8], target: &mut T) -> Result<Step, SdoAbort> {
        if seg.toggle != self.toggle {
            return Err(SdoAbort::ToggleBit);
        }
        let end = self.len.saturating_add(seg.len());
        if self.size.is_some_and(|size| end > size) {
            return Err(SdoAbort::LengthTooHigh);
        }
        if T::STREAMING && self.stream {
            return self.stream_segment(seg, end, target);
        }
        let Some(dst) = buf.get_mut(self.len..end) else { return Err(too_long(target, self.mux, end)) };
        dst.copy_from_slice(seg.data.get(..seg.len()).unwrap_or_default());
        self.len = end;
        self.toggle = !self.toggle;
        let response = command::download_segment_frame(seg.toggle);
        if !seg.last {
            return Ok(Step::Continue(Some(response)));
        }
        if self.size.is_some_and(|size| end < size) {
            return Err(SdoAbort::LengthTooLow);
        }
        target.write(self.mux.index, self.mux.sub, buf.get(..end).unwrap_or_default())?;
        Ok(Step::Finish(Some(response)))
    }

    /// A segment of a streamed download, ending at `end`: checked as above, then handed to
    /// the target, the last one with `last` once the length is known to be right.
    fn stream_segment(&mut self, seg: &Segment, end: usize, target: &mut impl SdoTarget) -> Result<Step, SdoAbort> {
        if seg.last && self.size.is_some_and(|size| end < size) {
            return Err(SdoAbort::LengthTooLow);
        }
        target.write_part(self.mux.index, self.mux.sub, self.len, seg.data.get(..seg.len()).unwrap_or_default(), seg.last)?;
        self.len = end;
        self.toggle = !self.toggle;
        let response = command::download_segment_frame(seg.toggle);
        Ok(if seg.last { Step::Finish(Some(response)) } else { Step::Continue(Some(response)) })
    }
}

/// A segmented upload in progress: each segment is read from the target at its offset.
#[derive(Debug)]
pub(super) struct Upload {
    pub(super) mux: Mux,
    toggle: bool,
    offset: usize,
    /// The size announced in the initiate response.
    total: usize,
}

/// Initiate upload.
pub(super) fn initiate_upload(mux: Mux, target: &mut impl SdoTarget) -> Started {
    let mut first = [0; 4];
    let len = target.read(mux.index, mux.sub, 0, &mut first)?;
    start_upload(mux, len, first)
}

/// Answers an upload initiation once the first (up to 4) bytes are read: expedited when the
/// value fits, segmented with the size indicated otherwise. An empty value goes segmented
/// (size 0, one empty last segment): an expedited response with size cannot say 0 bytes.
pub(super) fn start_upload(mux: Mux, first: ReadLen, bytes: [u8; 4]) -> Started {
    if (1..=4).contains(&first.total) {
        // A target that copies less than the value it reports is a local fault.
        let data = bytes.get(..first.total).filter(|_| first.copied == first.total).ok_or(SdoAbort::General)?;
        return Ok((State::Idle, command::upload_expedited_frame(mux, data)));
    }
    let size = u32::try_from(first.total).map_err(|_| SdoAbort::LengthTooHigh)?;
    Ok((State::Upload(Upload { mux, toggle: false, offset: 0, total: first.total }), command::upload_initiate_frame(mux, size)))
}

impl Upload {
    /// An upload segment request.
    pub(super) fn segment(&mut self, toggle: bool, target: &mut impl SdoTarget) -> Result<Step, SdoAbort> {
        if toggle != self.toggle {
            return Err(SdoAbort::ToggleBit);
        }
        let (data, len) = read_segment(target, self.mux, self.offset, self.total)?;
        self.offset = self.offset.saturating_add(len);
        self.toggle = !self.toggle;
        let last = self.offset >= self.total;
        let response = command::upload_segment_frame(toggle, data, len, last);
        Ok(if last { Step::Finish(Some(response)) } else { Step::Continue(Some(response)) })
    }
}

/// Reads the segment at `offset` of a value of `total` bytes: its 7 bytes (zero padded) and
/// how many are data. A value that shrank since the size was announced aborts with
/// `General`: the announced size can no longer be kept.
pub(super) fn read_segment(target: &mut impl SdoTarget, mux: Mux, offset: usize, total: usize) -> Result<([u8; SEGMENT_DATA], usize), SdoAbort> {
    let want = total.saturating_sub(offset).min(SEGMENT_DATA);
    let mut data = [0; SEGMENT_DATA];
    let dst = data.get_mut(..want).ok_or(SdoAbort::General)?;
    let got = target.read(mux.index, mux.sub, offset, dst)?;
    if got.copied != want {
        return Err(SdoAbort::General);
    }
    Ok((data, want))
}
