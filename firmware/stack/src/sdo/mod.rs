//! SDO server (CiA 301 7.2.4): expedited, segmented and block transfer, both directions.
//!
//! The server sees the dictionary only through [`SdoTarget`]; the node implements it over the
//! generated dictionary plus its communication-object hooks, so every abort code the
//! dictionary produces reaches the client unchanged.
//!
//! [`SdoServer`] is poll-driven like the rest of the stack: the node hands it each request
//! (COB-ID 600h + node ID) with [`SdoServer::on_request`] and sends the response it returns
//! (on 580h + node ID), and calls [`SdoServer::poll`] every cycle for what the server sends on
//! its own: block upload segments, one per call, and the abort of a timed-out transfer.
//!
//! A download is collected in the server's `N`-byte buffer and written to the target in one
//! call once complete, so a refused or aborted download changes nothing. An upload reads the
//! value by offset, a segment at a time, and needs no buffer. A target whose objects are
//! larger than any buffer it can afford (CANopenIA's 2,217-byte configuration file into
//! 1F50h.2) may have their downloads *streamed* instead: handed over in parts as they
//! arrive ([`SdoTarget::streams`], [`SdoTarget::write_part`]), the target voiding them if the
//! transfer fails ([`SdoTarget::abort_stream`]). The code for it is in the image only if
//! [`SdoTarget::STREAMING`] says so.
//!
//! Choices where CiA 301 leaves room, so a client can rely on them:
//!
//! - **Short requests**: a request of fewer than 8 bytes is read as if the missing bytes
//!   were 0; bytes past the eighth are ignored.
//! - **Expedited download without size** (`e = 1, s = 0`): the size is unspecified, so all
//!   four data bytes are written and the dictionary's length check decides.
//! - **Indicated size versus data** (segmented and block download): more data than
//!   indicated aborts with `LengthTooHigh` (0607 0012h), less with `LengthTooLow`
//!   (0607 0013h), rather than the generic `LengthMismatch`. Segmented download aborts as
//!   soon as a segment goes past the indicated size; block download checks at its end.
//! - **More than `N` bytes**: the target is asked whether it would take that many; its own
//!   code (typically `LengthTooHigh`) is sent if it refuses, `OutOfMemory` (0504 0005h)
//!   otherwise. An expedited download carries its data in the frame and needs no buffer.
//! - **Out-of-context commands**: a segment, block sub-command or end when no transfer (or
//!   a different one) is in progress, or after the last segment, aborts with
//!   `UnknownCommand` (0504 0001h), as does ccs = 7. The abort names the transfer's object,
//!   or with no transfer the request's bytes 1..=3 for ccs = 7 and 0000h.00 for a stray
//!   segment (whose bytes 1..=3 are data, not a multiplexer). A transfer in progress ends.
//! - **New initiate during a transfer**: the old transfer is dropped silently (nothing
//!   written) and the new one starts, as CANopenNode does: the client evidently gave up on
//!   the old one. The exception is a block download's sub-block, where every frame is a
//!   segment by definition.
//! - **Client abort** (ccs = 4): the transfer is dropped, nothing is sent. During a block
//!   download sub-block, byte 0 = 80h is read as the client's abort: as a segment it would
//!   be sequence number 0, which no valid segment carries.
//! - **Block sizes**: the download block size is what fits the free buffer (`free / 7`),
//!   1..=127, announced again in every acknowledgement. A client block size of 0 or above
//!   127 aborts with `InvalidBlockSize` (0504 0002h).
//! - **Lost block download segments**: sequence number 0 aborts with `InvalidSequence`
//!   (0504 0003h); any other out-of-order number makes the server ignore the rest of the
//!   sub-block and, when the sub-block ends (its last number or `c = 1`), acknowledge the
//!   last in-order segment so the client resends from there.
//!   If the sub-block's last segment itself is lost, no acknowledgement is due and the
//!   transfer ends by timeout.
//! - **Block upload acknowledgement** of more segments than were sent aborts with
//!   `InvalidSequence`. The end request follows an acknowledgement of the last segment
//!   directly as its response.
//! - **CRC**: the server always offers CRC; it is checked and sent only if the client
//!   offers it too. The upload CRC is accumulated as each segment is first sent.
//! - **Empty upload**: a value of 0 bytes is uploaded segmented (size 0, one empty last
//!   segment), since an expedited response with size indicated cannot say 0 bytes.
//! - **A value that changes length during an upload** so that the announced size cannot be
//!   kept aborts with `General` (0800 0000h).
//! - **Timeout**: a transfer with no client frame for the timeout (elapsed >= timeout; 1 s
//!   by default) is aborted by `poll` with `Timeout` (0504 0000h). While the server sends a
//!   block upload sub-block it is not waiting, so each segment sent restarts the clock.
//!
//! Streamed downloads (CiA 301 does not know them: what the client sees is unchanged, only
//! the limits differ):
//!
//! - **Which**: the target is asked at each segmented or block download initiation, after
//!   its own checks; the size indicated is still checked against the object's maximum
//!   (`check_download`), but a size beyond the buffer is no longer `OutOfMemory`.
//! - **Expedited downloads** of a streaming object are written whole, as before: the data is
//!   in the frame, so there is nothing to stream, and the target keeps a single path for
//!   every value that arrives whole (host and device writes too).
//! - **Segmented download**: each segment is a part, handed over once its toggle and length
//!   checks pass; the last segment is the last part, after the `LengthTooLow` check.
//! - **Block download** streams only with its size indicated (without, it is collected in
//!   the buffer as before): the last segment's padding is known only from the end request,
//!   and a buffer of a few bytes cannot hold that segment back. In-order segments become
//!   parts once received (a resent segment never twice: only in-order ones are taken), the
//!   last one cut at the indicated size; the CRC is accumulated over the parts. The end
//!   request checks the length and the CRC, then hands over an empty last part. Sub-blocks
//!   are 127 segments, as no buffer limits them.
//! - **Failure**: every way a streamed download ends without its last part accepted (abort
//!   from either side, timeout, toggle, length or CRC error, a refused part, NMT reset or
//!   stop through [`SdoServer::reset`], a new initiate) calls `abort_stream` exactly once;
//!   for a new initiate, before the target is asked anything about the new transfer.

mod block;
pub mod client;
mod command;
mod segmented;

use crate::od::{ReadLen, SdoAbort};
use command::{BlockSegment, Mux, Request};

/// What the SDO server reads and writes.
pub trait SdoTarget {
    /// Whether block transfers are served. If not, a block request is refused with
    /// `UnknownCommand` and, the constant being false, the block code is not in the image.
    const BLOCK_TRANSFER: bool = true;

    /// Reads the value of `index`/`sub` from byte `offset` into `buf`; `total` is the
    /// value's full length. Includes the read access check.
    fn read(&mut self, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort>;

    /// Whether a download of `size` bytes (if the client indicated one) could be written:
    /// the object exists, is writable now, and `size` does not exceed its maximum. Lets the
    /// server refuse at initiation instead of after the last segment.
    fn check_download(&mut self, index: u16, sub: u8, size: Option<usize>) -> Result<(), SdoAbort>;

    /// Writes the whole value; a refused write changes nothing.
    fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort>;

    /// The fixed size of the entry's value, if it has one (not a string or domain): an
    /// expedited download that gives no size carries that many bytes (CiA 301 7.2.4.3.3).
    fn fixed_size(&mut self, _index: u16, _sub: u8) -> Option<usize> {
        None
    }

    /// Whether any download may stream (below). If not, the constant being false, the
    /// streaming code is not in the image.
    const STREAMING: bool = false;

    /// Whether a segmented or block download of `index`/`sub`, just initiated and checked,
    /// is handed over in parts ([`SdoTarget::write_part`]) instead of collected in the
    /// server's buffer. Asked only if [`SdoTarget::STREAMING`].
    fn streams(&mut self, _index: u16, _sub: u8) -> bool {
        false
    }

    /// The next part of a streamed download: `data` belongs at byte `offset` of the value;
    /// parts come in order without gaps. `last`: the download is complete and checked (the
    /// last part may be empty). An error aborts the transfer with that code.
    fn write_part(&mut self, _index: u16, _sub: u8, _offset: usize, _data: &[u8], _last: bool) -> Result<(), SdoAbort> {
        Err(SdoAbort::UnsupportedAccess)
    }

    /// A streamed download ended without success (abort from either side, timeout, NMT
    /// reset or stop, a new initiate, an error of `write_part` itself): what its parts wrote
    /// is void. Called exactly once for every streamed download that does not end with
    /// `write_part(.., last = true)` succeeding.
    fn abort_stream(&mut self, _index: u16, _sub: u8) {}
}

/// The COB-ID a node's default SDO server receives on (CiA 301 predefined connection set).
pub const fn request_id(node: u8) -> u16 {
    0x600 + node as u16
}

/// The COB-ID a node's default SDO server answers on.
pub const fn response_id(node: u8) -> u16 {
    0x580 + node as u16
}

/// The default SDO timeout: 1 s.
pub const DEFAULT_TIMEOUT_US: u64 = 1_000_000;

/// The transfer in progress, if any.
#[derive(Debug)]
enum State {
    Idle,
    Download(segmented::Download),
    Upload(segmented::Upload),
    BlockDownload(block::Download),
    BlockUpload(block::Upload),
}

impl State {
    /// The object of a streamed download in progress.
    fn streamed(&self) -> Option<Mux> {
        match self {
            State::Download(t) if t.stream => Some(t.mux),
            State::BlockDownload(t) if t.stream => Some(t.mux),
            _ => None,
        }
    }

    /// The object of the transfer in progress.
    fn mux(&self) -> Option<Mux> {
        match self {
            State::Idle => None,
            State::Download(t) => Some(t.mux),
            State::Upload(t) => Some(t.mux),
            State::BlockDownload(t) => Some(t.mux),
            State::BlockUpload(t) => Some(t.mux),
        }
    }
}

/// What a request within a transfer leads to.
#[derive(Debug)]
enum Step {
    /// Send this frame, if any; the transfer goes on.
    Continue(Option<[u8; 8]>),
    /// Send this frame, if any; the transfer is complete.
    Finish(Option<[u8; 8]>),
}

/// An initiation: the new state and the initiate response, or the abort code.
type Started = Result<(State, [u8; 8]), SdoAbort>;

/// The abort for a download that outgrows the buffer: the dictionary's own code if the object
/// could not take that many bytes either, `OutOfMemory` if only the buffer is too small.
fn too_long(target: &mut impl SdoTarget, mux: Mux, len: usize) -> SdoAbort {
    match target.check_download(mux.index, mux.sub, Some(len)) {
        Err(code) => code,
        Ok(()) => SdoAbort::OutOfMemory,
    }
}

/// A CiA 301 SDO server with an `N`-byte download buffer (the largest value a client can
/// write with a segmented or block download, streamed downloads aside).
#[derive(Debug)]
pub struct SdoServer<const N: usize> {
    state: State,
    timeout_us: u64,
    /// When the client last sent a frame, or the server a block segment: the timeout runs
    /// from here.
    last_us: u64,
    /// A download collects here and reaches the target only once complete.
    buf: [u8; N],
}

impl<const N: usize> Default for SdoServer<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> SdoServer<N> {
    /// An idle server with the default timeout of 1 s.
    pub const fn new() -> Self {
        SdoServer { state: State::Idle, timeout_us: DEFAULT_TIMEOUT_US, last_us: 0, buf: [0; N] }
    }

    /// How long a transfer may wait for the client before `poll` aborts it.
    pub fn set_timeout_us(&mut self, us: u64) {
        self.timeout_us = us;
    }

    /// Whether no transfer is in progress.
    pub fn is_idle(&self) -> bool {
        matches!(self.state, State::Idle)
    }

    /// Drops any transfer silently (NMT reset or stop): nothing is written or sent; the
    /// target of a streamed download hears of it ([`SdoTarget::abort_stream`]).
    pub fn reset<T: SdoTarget>(&mut self, target: &mut T) {
        self.drop_transfer(target);
    }

    /// A received request (the payload of a CAN frame on COB-ID 600h + node ID). Returns the
    /// response payload if one is due: always 8 bytes, a valid SDO response or an abort.
    pub fn on_request<T: SdoTarget>(&mut self, data: &[u8], now_us: u64, target: &mut T) -> Option<[u8; 8]> {
        let frame = command::pad(data);
        self.last_us = now_us;
        if T::BLOCK_TRANSFER
            && let State::BlockDownload(down) = &mut self.state
            && down.receiving()
            && !command::is_abort(&frame)
        {
            let mux = down.mux;
            let step = down.segment(&BlockSegment::parse(&frame), &mut self.buf, target);
            return self.step(mux, step, target);
        }
        let current = self.state.mux();
        let request = Request::parse(&frame);
        // A streamed download that a new initiate replaces ends before the new one asks.
        if T::STREAMING && request.initiates() {
            self.drop_transfer(target);
        }
        match (request, &mut self.state) {
            (Request::Abort, _) => {
                self.drop_transfer(target);
                None
            }
            (Request::InitiateDownload(init), _) => {
                let started = segmented::initiate_download(&init, N, target);
                self.start(init.mux, started, target)
            }
            (Request::InitiateUpload { mux }, _) => {
                let started = segmented::initiate_upload(mux, target);
                self.start(mux, started, target)
            }
            (Request::BlockDownloadInitiate { mux, .. } | Request::BlockUploadInitiate { mux, .. }, _) if !T::BLOCK_TRANSFER => {
                self.abort(current.unwrap_or(mux), SdoAbort::UnknownCommand, target)
            }
            (Request::BlockDownloadInitiate { mux, crc, size }, _) => {
                let started = block::initiate_download(mux, crc, size, N, target);
                self.start(mux, started, target)
            }
            (Request::BlockUploadInitiate { mux, crc, blksize, pst }, _) => {
                let started = block::initiate_upload(mux, crc, blksize, pst, target);
                self.start(mux, started, target)
            }
            (Request::DownloadSegment(seg), State::Download(down)) => {
                let (mux, step) = (down.mux, down.segment(&seg, &mut self.buf, target));
                self.step(mux, step, target)
            }
            (Request::UploadSegment { toggle }, State::Upload(up)) => {
                let (mux, step) = (up.mux, up.segment(toggle, target));
                self.step(mux, step, target)
            }
            (Request::BlockDownloadEnd { n, crc }, State::BlockDownload(down)) if T::BLOCK_TRANSFER => {
                let (mux, step) = (down.mux, down.end(n, crc, &self.buf, target));
                self.step(mux, step, target)
            }
            (Request::BlockUploadStart, State::BlockUpload(up)) if T::BLOCK_TRANSFER => {
                let (mux, step) = (up.mux, up.start());
                self.step(mux, step, target)
            }
            (Request::BlockUploadAck { ackseq, blksize }, State::BlockUpload(up)) if T::BLOCK_TRANSFER => {
                let (mux, step) = (up.mux, up.ack(ackseq, blksize));
                self.step(mux, step, target)
            }
            (Request::BlockUploadEnd, State::BlockUpload(up)) if T::BLOCK_TRANSFER => {
                let (mux, step) = (up.mux, up.end());
                self.step(mux, step, target)
            }
            (Request::Unknown { mux }, _) => self.abort(current.unwrap_or(mux), SdoAbort::UnknownCommand, target),
            // A segment or block sub-command that does not belong to the transfer in progress.
            _ => self.abort(current.unwrap_or_default(), SdoAbort::UnknownCommand, target),
        }
    }

    /// Called every poll: the next frame the server sends on its own (a block upload
    /// segment, one per call; the `Timeout` abort of a transfer the client left waiting).
    pub fn poll<T: SdoTarget>(&mut self, now_us: u64, target: &mut T) -> Option<[u8; 8]> {
        let mux = self.state.mux()?;
        if T::BLOCK_TRANSFER
            && let State::BlockUpload(up) = &mut self.state
        {
            match up.next_segment(target) {
                Ok(Some(frame)) => {
                    self.last_us = now_us;
                    return Some(frame);
                }
                Ok(None) => {}
                Err(code) => return self.abort(mux, code, target),
            }
        }
        if now_us.saturating_sub(self.last_us) >= self.timeout_us {
            return self.abort(mux, SdoAbort::Timeout, target);
        }
        None
    }

    fn start<T: SdoTarget>(&mut self, mux: Mux, started: Started, target: &mut T) -> Option<[u8; 8]> {
        match started {
            Ok((state, response)) => {
                self.state = state;
                Some(response)
            }
            Err(code) => self.abort(mux, code, target),
        }
    }

    fn step<T: SdoTarget>(&mut self, mux: Mux, step: Result<Step, SdoAbort>, target: &mut T) -> Option<[u8; 8]> {
        match step {
            Ok(Step::Continue(response)) => response,
            Ok(Step::Finish(response)) => {
                self.state = State::Idle;
                response
            }
            Err(code) => self.abort(mux, code, target),
        }
    }

    /// Ends the transfer with an abort frame, telling a streamed download's target. Inlined:
    /// without streaming it is the plain `send_abort`, as before streaming existed.
    #[inline(always)]
    fn abort<T: SdoTarget>(&mut self, mux: Mux, code: SdoAbort, target: &mut T) -> Option<[u8; 8]> {
        self.end_stream(target);
        self.send_abort(mux, code)
    }

    fn send_abort(&mut self, mux: Mux, code: SdoAbort) -> Option<[u8; 8]> {
        self.state = State::Idle;
        Some(command::abort_frame(mux, code))
    }

    /// Ends the transfer in progress without success (nothing is sent).
    fn drop_transfer<T: SdoTarget>(&mut self, target: &mut T) {
        self.end_stream(target);
        self.state = State::Idle;
    }

    /// The one place a streamed download's target hears that it failed: called as any
    /// transfer ends without success, it tells a streamed download's target once.
    fn end_stream<T: SdoTarget>(&mut self, target: &mut T) {
        if T::STREAMING
            && let Some(mux) = self.state.streamed()
        {
            self.state = State::Idle;
            target.abort_stream(mux.index, mux.sub);
        }
    }
}
