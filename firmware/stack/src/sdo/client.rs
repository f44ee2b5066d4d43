//! SDO client (CiA 301 7.2.4): expedited and segmented upload and download against a node's
//! default SDO server (requests on 600h + node-ID, responses on 580h + node-ID).
//!
//! One [`SdoClient`] is one client channel: one transfer at a time, and a second request while
//! one runs gets [`StartError::Busy`]. The client owns no data buffer: the caller passes the
//! value to download, or the buffer an upload fills, with every call that may need it, so a
//! large upload costs no fixed RAM. Like the server it is poll-driven: [`SdoClient::on_frame`]
//! takes each received frame and returns the next request, [`SdoClient::poll`] sends the
//! timeout abort, and the outcome waits in [`SdoClient::take_result`].
//!
//! Choices where CiA 301 leaves room, so a caller can rely on them:
//!
//! - **Values up to 4 bytes** go expedited with the size indicated; longer ones, and the
//!   empty value (which an expedited frame cannot say), segmented with the size indicated.
//! - **Frames shorter than 8 bytes** on the response COB-ID are not SDO frames: they are
//!   ignored (as CANopenNode does), the transfer goes on and times out if nothing valid comes.
//!   Remote frames are ignored too.
//! - **A response for another object** (initiate responses name it) aborts with
//!   `IncompatibleParameter` (0604 0043h), as CANopenNode does; a response of the wrong kind
//!   (a download response to an upload, a block response, scs = 7) aborts with
//!   `UnknownCommand` (0504 0001h); a segment with the wrong toggle bit with `ToggleBit`.
//! - **Upload size**: more data than the server indicated aborts with `LengthTooHigh`, less
//!   with `LengthTooLow`; more than the caller's buffer holds with `OutOfMemory`
//!   (0504 0005h). A size indicated in the initiate response that exceeds the buffer aborts
//!   at once, before any segment.
//! - **Faults found after the server's last frame** (a short last segment, an expedited
//!   value larger than the buffer) end the transfer on the server's side already: the client
//!   reports [`SdoResult::Aborted`] by [`AbortSource::Client`] and sends nothing.
//! - **The server's abort** ends the transfer with its code unchanged, even one CiA 301 does
//!   not list; nothing is sent back.
//! - **Timeout**: no valid response for the timeout (elapsed >= timeout; 1 s by default,
//!   counted from the last request sent) aborts with `Timeout` (0504 0000h).
//! - **Block transfer** is not offered: a client that needs it for speed uses segmented
//!   transfer, which every server supports.

pub use super::{request_id, response_id};

use super::DEFAULT_TIMEOUT_US;
use super::command::{self, Mux, Response, SEGMENT_DATA, Segment};
use crate::frame::CanFrame;
use crate::od::SdoAbort;

/// Which side ended a transfer with an abort.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AbortSource {
    /// The server sent an abort frame.
    Server,
    /// The client aborted (a timeout, a malformed response, a value too large).
    Client,
}

/// How a transfer ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoResult {
    /// The upload is complete: the value is the first `len` bytes of the caller's buffer.
    Uploaded {
        len: usize,
    },
    Downloaded,
    /// The transfer was aborted with `code` (the server's code as it sent it).
    Aborted {
        code: u32,
        by: AbortSource,
    },
}

impl SdoResult {
    /// The abort code as a CiA 301 abort, if it is one the table lists.
    pub fn abort(&self) -> Option<SdoAbort> {
        match *self {
            SdoResult::Aborted { code, .. } => SdoAbort::from_code(code),
            _ => None,
        }
    }
}

/// Why a transfer could not start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StartError {
    /// A transfer is in progress on this channel.
    Busy,
    /// The node-ID is outside 1..=127.
    NodeId,
    /// The value is longer than a size field can say.
    TooLong,
}

/// Where a transfer is.
#[derive(Debug, Clone, Copy)]
enum Phase {
    Idle,
    /// Initiate upload sent.
    UploadInitiated,
    /// Segments requested; `len` bytes received so far.
    Uploading {
        toggle: bool,
        len: usize,
        size: Option<usize>,
    },
    /// Initiate download sent (the data with it if expedited).
    DownloadInitiated {
        expedited: bool,
        len: usize,
    },
    /// A segment carrying `toggle` sent; `sent` bytes sent so far, including it.
    Downloading {
        toggle: bool,
        sent: usize,
        len: usize,
    },
}

/// One SDO client channel.
#[derive(Debug)]
pub struct SdoClient {
    phase: Phase,
    node: u8,
    mux: Mux,
    timeout_us: u64,
    /// When the last request went out: the timeout runs from here.
    last_us: u64,
    result: Option<SdoResult>,
}

impl Default for SdoClient {
    fn default() -> Self {
        Self::new()
    }
}

impl SdoClient {
    /// An idle client with the default timeout of 1 s.
    pub const fn new() -> Self {
        SdoClient { phase: Phase::Idle, node: 0, mux: Mux { index: 0, sub: 0 }, timeout_us: DEFAULT_TIMEOUT_US, last_us: 0, result: None }
    }

    /// How long the client waits for each response before it aborts.
    pub fn set_timeout_us(&mut self, us: u64) {
        self.timeout_us = us;
    }

    /// Whether no transfer is in progress.
    pub fn is_idle(&self) -> bool {
        matches!(self.phase, Phase::Idle)
    }

    /// The node of the transfer in progress.
    pub fn server(&self) -> Option<u8> {
        (!self.is_idle()).then_some(self.node)
    }

    /// Starts reading `index`/`sub` of `node`: the initiate request to send.
    pub fn upload(&mut self, node: u8, index: u16, sub: u8, now_us: u64) -> Result<CanFrame, StartError> {
        self.begin(node, index, sub, now_us)?;
        self.phase = Phase::UploadInitiated;
        Ok(self.request(command::upload_initiate_request(self.mux)))
    }

    /// Starts writing `data` to `index`/`sub` of `node`: the initiate request to send. The same
    /// `data` must be passed to [`on_frame`](Self::on_frame) until the transfer ends.
    pub fn download(&mut self, node: u8, index: u16, sub: u8, data: &[u8], now_us: u64) -> Result<CanFrame, StartError> {
        let size = u32::try_from(data.len()).map_err(|_| StartError::TooLong)?;
        self.begin(node, index, sub, now_us)?;
        let expedited = (1..=4).contains(&data.len());
        self.phase = Phase::DownloadInitiated { expedited, len: data.len() };
        let request = if expedited { command::download_expedited_request(self.mux, data) } else { command::download_initiate_request(self.mux, size) };
        Ok(self.request(request))
    }

    fn begin(&mut self, node: u8, index: u16, sub: u8, now_us: u64) -> Result<(), StartError> {
        if !self.is_idle() {
            return Err(StartError::Busy);
        }
        if !(1..=127).contains(&node) {
            return Err(StartError::NodeId);
        }
        self.node = node;
        self.mux = Mux { index, sub };
        self.last_us = now_us;
        self.result = None;
        Ok(())
    }

    /// A received frame. If it is this transfer's response, the transfer moves on: the next
    /// request to send, if one is due. `buf` is the transfer's data: the value being
    /// downloaded, or where an upload puts the value.
    pub fn on_frame(&mut self, frame: &CanFrame, now_us: u64, buf: &mut [u8]) -> Option<CanFrame> {
        if self.is_idle() || frame.rtr || frame.id != response_id(self.node) {
            return None;
        }
        let bytes: &[u8; 8] = frame.payload().try_into().ok()?;
        self.last_us = now_us;
        match self.step(Response::parse(bytes), buf) {
            Ok(Some(request)) => Some(self.request(request)),
            Ok(None) => None,
            Err(Fault::Send(code)) => {
                self.finish(SdoResult::Aborted { code: code.code(), by: AbortSource::Client });
                Some(self.request(command::abort_frame(self.mux, code)))
            }
            Err(Fault::Local(code)) => {
                self.finish(SdoResult::Aborted { code: code.code(), by: AbortSource::Client });
                None
            }
        }
    }

    /// Called every poll: the `Timeout` abort of a transfer the server left waiting.
    pub fn poll(&mut self, now_us: u64) -> Option<CanFrame> {
        if self.is_idle() || now_us.saturating_sub(self.last_us) < self.timeout_us {
            return None;
        }
        self.finish(SdoResult::Aborted { code: SdoAbort::Timeout.code(), by: AbortSource::Client });
        Some(self.request(command::abort_frame(self.mux, SdoAbort::Timeout)))
    }

    /// How the last transfer ended, once.
    pub fn take_result(&mut self) -> Option<SdoResult> {
        self.result.take()
    }

    /// Ends the transfer in progress without a word to the server (the caller gave up, or the
    /// server's node was reset): no result.
    pub fn cancel(&mut self) {
        self.phase = Phase::Idle;
    }

    fn step(&mut self, response: Response, buf: &mut [u8]) -> Result<Option<[u8; 8]>, Fault> {
        match (response, self.phase) {
            (Response::Abort { code, .. }, _) => {
                self.finish(SdoResult::Aborted { code, by: AbortSource::Server });
                Ok(None)
            }
            (Response::UploadInitiate { mux, .. } | Response::DownloadInitiate { mux }, Phase::UploadInitiated | Phase::DownloadInitiated { .. })
                if mux != self.mux =>
            {
                Err(Fault::Send(SdoAbort::IncompatibleParameter))
            }
            (Response::UploadInitiate { expedited: true, sized, n, data, .. }, Phase::UploadInitiated) => {
                // Without a size, all four bytes are the value ("unspecified number of bytes").
                let len = if sized { 4 - usize::from(n) } else { 4 };
                let dst = buf.get_mut(..len).ok_or(Fault::Local(SdoAbort::OutOfMemory))?;
                dst.copy_from_slice(data.get(..len).unwrap_or_default());
                self.finish(SdoResult::Uploaded { len });
                Ok(None)
            }
            (Response::UploadInitiate { expedited: false, sized, data, .. }, Phase::UploadInitiated) => {
                let size = sized.then(|| usize::try_from(u32::from_le_bytes(data)).unwrap_or(usize::MAX));
                if size.is_some_and(|size| size > buf.len()) {
                    return Err(Fault::Send(SdoAbort::OutOfMemory));
                }
                self.phase = Phase::Uploading { toggle: false, len: 0, size };
                Ok(Some(command::upload_segment_request(false)))
            }
            (Response::UploadSegment(segment), Phase::Uploading { toggle, len, size }) => self.upload_segment(&segment, toggle, len, size, buf),
            (Response::DownloadInitiate { .. }, Phase::DownloadInitiated { expedited: true, .. }) => {
                self.finish(SdoResult::Downloaded);
                Ok(None)
            }
            (Response::DownloadInitiate { .. }, Phase::DownloadInitiated { expedited: false, len }) => Ok(Some(self.next_segment(false, 0, len, buf))),
            (Response::DownloadSegment { toggle }, Phase::Downloading { toggle: sent_toggle, .. }) if toggle != sent_toggle => {
                Err(Fault::Send(SdoAbort::ToggleBit))
            }
            (Response::DownloadSegment { toggle }, Phase::Downloading { sent, len, .. }) => {
                if sent >= len {
                    self.finish(SdoResult::Downloaded);
                    return Ok(None);
                }
                Ok(Some(self.next_segment(!toggle, sent, len, buf)))
            }
            _ => Err(Fault::Send(SdoAbort::UnknownCommand)),
        }
    }

    /// A received upload segment; `toggle` is the one requested, `len` bytes are in so far.
    fn upload_segment(&mut self, segment: &Segment, toggle: bool, len: usize, size: Option<usize>, buf: &mut [u8]) -> Result<Option<[u8; 8]>, Fault> {
        // After the last segment the server has finished: faults are only reported.
        let fault = |code| if segment.last { Fault::Local(code) } else { Fault::Send(code) };
        if segment.toggle != toggle {
            return Err(fault(SdoAbort::ToggleBit));
        }
        let end = len.saturating_add(segment.len());
        if size.is_some_and(|size| end > size) {
            return Err(fault(SdoAbort::LengthTooHigh));
        }
        let dst = buf.get_mut(len..end).ok_or(fault(SdoAbort::OutOfMemory))?;
        dst.copy_from_slice(segment.data.get(..segment.len()).unwrap_or_default());
        if !segment.last {
            self.phase = Phase::Uploading { toggle: !toggle, len: end, size };
            return Ok(Some(command::upload_segment_request(!toggle)));
        }
        if size.is_some_and(|size| end < size) {
            return Err(Fault::Local(SdoAbort::LengthTooLow));
        }
        self.finish(SdoResult::Uploaded { len: end });
        Ok(None)
    }

    /// The download segment after the first `sent` bytes of the `len`-byte value in `buf`. A
    /// caller that passes less data than it started with gets zeros in the missing bytes:
    /// the announced size is kept.
    fn next_segment(&mut self, toggle: bool, sent: usize, len: usize, buf: &[u8]) -> [u8; 8] {
        let n = len.saturating_sub(sent).min(SEGMENT_DATA);
        let mut data = [0; SEGMENT_DATA];
        let src = buf.get(sent..).unwrap_or_default();
        data.iter_mut().take(n).zip(src).for_each(|(dst, src)| *dst = *src);
        let sent = sent + n;
        self.phase = Phase::Downloading { toggle, sent, len };
        command::download_segment_request(toggle, data, n, sent >= len)
    }

    fn finish(&mut self, result: SdoResult) {
        self.phase = Phase::Idle;
        self.result = Some(result);
    }

    /// A request frame to the server.
    fn request(&mut self, payload: [u8; 8]) -> CanFrame {
        CanFrame { id: request_id(self.node), rtr: false, dlc: 8, data: payload }
    }
}

/// A fault in a response.
enum Fault {
    /// The server still waits: tell it with an abort frame.
    Send(SdoAbort),
    /// The server has finished: only the caller is told.
    Local(SdoAbort),
}
