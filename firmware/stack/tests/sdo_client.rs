//! The SDO client against coforge's own SDO server: every transfer kind both ways, the
//! server's aborts reported unchanged; a table of malformed or missing answers with the result
//! each gets; and mutated answers, which may end a transfer with an abort but never with a
//! value other than the one the server holds.

mod common;

use coforge_stack::frame::CanFrame;
use coforge_stack::od::SdoAbort;
use coforge_stack::sdo::SdoServer;
use coforge_stack::sdo::client::{AbortSource, SdoClient, SdoResult, StartError, request_id, response_id};
use common::{DOMAIN, Dict, STRING, U8_RO, U32};

const NODE: u8 = 5;

/// A client and a server with its dictionary, connected frame by frame.
struct Link<const N: usize> {
    client: SdoClient,
    server: SdoServer<N>,
    dict: Dict,
    now: u64,
    /// Requests the server received.
    requests: Vec<[u8; 8]>,
}

impl<const N: usize> Link<N> {
    fn new() -> Self {
        Link { client: SdoClient::new(), server: SdoServer::new(), dict: Dict::new(), now: 0, requests: Vec::new() }
    }

    /// Runs a transfer that `start` began to its end: each request to the server, each
    /// response through `edit` (which may change or drop it) back to the client.
    fn run(&mut self, first: CanFrame, buf: &mut [u8], mut edit: impl FnMut(usize, CanFrame) -> Option<CanFrame>) -> SdoResult {
        let mut next = Some(first);
        let mut responses = 0;
        for _ in 0..1000 {
            if let Some(request) = next.take() {
                assert_eq!(request.id, request_id(NODE));
                assert_eq!(request.dlc, 8, "client requests are 8 bytes");
                self.requests.push(request.data);
                if let Some(response) = self.server.on_request(&request.data, self.now, &mut self.dict) {
                    let frame = CanFrame::data(response_id(NODE), &response).expect("a valid frame");
                    if let Some(frame) = edit(responses, frame) {
                        next = self.client.on_frame(&frame, self.now, buf);
                    }
                    responses += 1;
                }
            }
            if let Some(result) = self.client.take_result() {
                assert!(self.client.is_idle());
                // An abort the client sends reaches the server too.
                if let Some(request) = next {
                    self.requests.push(request.data);
                    self.server.on_request(&request.data, self.now, &mut self.dict);
                }
                return result;
            }
            if next.is_none() {
                self.now += 100_000;
                next = self.client.poll(self.now);
            }
        }
        panic!("the transfer never ended");
    }

    fn upload(&mut self, index: u16, buf: &mut [u8]) -> SdoResult {
        let first = self.client.upload(NODE, index, 0, self.now).expect("an idle client");
        self.run(first, buf, |_, f| Some(f))
    }

    fn download(&mut self, index: u16, data: &[u8]) -> SdoResult {
        let first = self.client.download(NODE, index, 0, data, self.now).expect("an idle client");
        self.run(first, &mut data.to_vec(), |_, f| Some(f))
    }
}

fn aborted(code: SdoAbort, by: AbortSource) -> SdoResult {
    SdoResult::Aborted { code: code.code(), by }
}

#[test]
fn uploads_of_every_size_arrive_whole() {
    let mut link = Link::<64>::new();
    for (index, value) in [(U32, 0x1234_5678_u32.to_le_bytes().to_vec()), (U8_RO, vec![0x5A]), (STRING, b"coforge sdo string!".to_vec())] {
        let mut buf = [0; 200];
        assert_eq!(link.upload(index, &mut buf), SdoResult::Uploaded { len: value.len() }, "{index:04X}");
        assert_eq!(&buf[..value.len()], &value[..]);
    }
    let mut buf = [0; 200];
    assert_eq!(link.upload(DOMAIN, &mut buf), SdoResult::Uploaded { len: 100 });
    assert_eq!(&buf[..100], link.dict.value(DOMAIN));
    // 4 bytes go expedited: one request; 100 bytes segmented: initiate + 15 segments.
    link.requests.clear();
    link.upload(U32, &mut buf);
    assert_eq!(link.requests.len(), 1);
    link.requests.clear();
    link.upload(DOMAIN, &mut buf);
    assert_eq!(link.requests.len(), 1 + 15);
    // An empty value comes segmented: size 0, one empty last segment.
    link.dict.set(STRING, b"");
    assert_eq!(link.upload(STRING, &mut buf), SdoResult::Uploaded { len: 0 });
}

#[test]
fn downloads_of_every_size_are_written_whole() {
    let mut link = Link::<256>::new();
    assert_eq!(link.download(U32, &0xCAFE_F00D_u32.to_le_bytes()), SdoResult::Downloaded);
    assert_eq!(link.dict.value(U32), 0xCAFE_F00D_u32.to_le_bytes());
    for len in [0_usize, 1, 5, 7, 8, 14, 15, 40] {
        let value: Vec<u8> = (0..len).map(|i| b'a' + (i % 26) as u8).collect();
        assert_eq!(link.download(STRING, &value), SdoResult::Downloaded, "{len} bytes");
        assert_eq!(link.dict.value(STRING), &value[..], "{len} bytes");
    }
    let domain: Vec<u8> = (0..200).map(|i| (i * 13) as u8).collect();
    link.requests.clear();
    assert_eq!(link.download(DOMAIN, &domain), SdoResult::Downloaded);
    assert_eq!(link.dict.value(DOMAIN), &domain[..]);
    assert_eq!(link.requests.len(), 1 + 29, "initiate + ceil(200 / 7) segments");
}

#[test]
fn server_aborts_arrive_unchanged_and_change_nothing() {
    let mut link = Link::<64>::new();
    assert_eq!(link.download(U8_RO, &[1]), aborted(SdoAbort::ReadOnly, AbortSource::Server));
    assert_eq!(link.download(0x3000, &[1]), aborted(SdoAbort::NoObject, AbortSource::Server));
    assert_eq!(link.download(DOMAIN, &[0; 201]), aborted(SdoAbort::LengthTooHigh, AbortSource::Server));
    assert_eq!(link.download(DOMAIN, &[0; 100]), aborted(SdoAbort::OutOfMemory, AbortSource::Server), "the server's buffer is 64 bytes");
    let mut buf = [0; 8];
    assert_eq!(link.client.upload(NODE, U32, 1, 0).map(|_| ()), Ok(()));
    link.client.cancel();
    let first = link.client.upload(NODE, U32, 1, 0).expect("an idle client");
    assert_eq!(link.run(first, &mut buf, |_, f| Some(f)), aborted(SdoAbort::NoSubIndex, AbortSource::Server));
    assert_eq!(link.dict.writes, 0);
    // A code CiA 301 does not list is reported as sent.
    let mut client = SdoClient::new();
    client.upload(NODE, 0x2000, 0, 0).expect("an idle client");
    let abort = CanFrame::data(response_id(NODE), &[0x80, 0x00, 0x20, 0x00, 0x78, 0x56, 0x34, 0x12]).expect("a valid frame");
    assert_eq!(client.on_frame(&abort, 0, &mut buf), None, "nothing answers an abort");
    let result = client.take_result().expect("a result");
    assert_eq!(result, SdoResult::Aborted { code: 0x1234_5678, by: AbortSource::Server });
    assert_eq!(result.abort(), None);
}

#[test]
fn an_upload_larger_than_the_buffer_aborts_and_the_server_hears_it() {
    let mut link = Link::<64>::new();
    let mut small = [0; 50];
    assert_eq!(link.upload(DOMAIN, &mut small), aborted(SdoAbort::OutOfMemory, AbortSource::Client));
    assert!(link.server.is_idle(), "the abort reached the server");
    assert_eq!(link.requests.last().expect("a request")[0], 0x80);
    // Expedited: the server has finished, so only the caller learns of it.
    let mut tiny = [0; 2];
    link.requests.clear();
    assert_eq!(link.upload(U32, &mut tiny), aborted(SdoAbort::OutOfMemory, AbortSource::Client));
    assert_eq!(link.requests.len(), 1, "no abort after the server's last frame");
}

#[test]
fn one_transfer_per_channel() {
    let mut client = SdoClient::new();
    client.upload(NODE, U32, 0, 0).expect("an idle client");
    assert_eq!(client.server(), Some(NODE));
    assert_eq!(client.upload(6, U32, 0, 0), Err(StartError::Busy));
    assert_eq!(client.download(NODE, U32, 0, &[1], 0), Err(StartError::Busy));
    let mut idle = SdoClient::new();
    assert_eq!(idle.upload(0, U32, 0, 0), Err(StartError::NodeId));
    assert_eq!(idle.upload(128, U32, 0, 0), Err(StartError::NodeId));
    assert!(idle.is_idle());
}

/// A case: the transfer, which response (0-based) to change and how, and the result.
struct Case {
    name: &'static str,
    upload: bool,
    index: u16,
    at: usize,
    edit: fn(CanFrame) -> Option<CanFrame>,
    result: SdoResult,
    /// Whether the client's last request is an abort frame the server received.
    abort_sent: bool,
}

fn with_byte0(mut f: CanFrame, b0: u8) -> Option<CanFrame> {
    f.data[0] = b0;
    Some(f)
}

#[test]
fn malformed_or_missing_answers() {
    let cases = [
        Case {
            name: "wrong toggle in an upload segment",
            upload: true,
            index: DOMAIN,
            at: 1,
            edit: |f| with_byte0(f, f.data[0] ^ 0x10),
            result: aborted(SdoAbort::ToggleBit, AbortSource::Client),
            abort_sent: true,
        },
        Case {
            name: "wrong toggle in a download segment response",
            upload: false,
            index: DOMAIN,
            at: 2,
            edit: |f| with_byte0(f, f.data[0] ^ 0x10),
            result: aborted(SdoAbort::ToggleBit, AbortSource::Client),
            abort_sent: true,
        },
        Case {
            name: "download response to an upload",
            upload: true,
            index: DOMAIN,
            at: 0,
            edit: |f| with_byte0(f, 0x60),
            result: aborted(SdoAbort::UnknownCommand, AbortSource::Client),
            abort_sent: true,
        },
        Case {
            name: "upload response to a download",
            upload: false,
            index: U32,
            at: 0,
            edit: |f| with_byte0(f, 0x43),
            result: aborted(SdoAbort::UnknownCommand, AbortSource::Client),
            abort_sent: true,
        },
        Case {
            name: "block response",
            upload: true,
            index: STRING,
            at: 1,
            edit: |f| with_byte0(f, 0xC1),
            result: aborted(SdoAbort::UnknownCommand, AbortSource::Client),
            abort_sent: true,
        },
        Case {
            name: "scs 7",
            upload: true,
            index: U32,
            at: 0,
            edit: |f| with_byte0(f, 0xE0),
            result: aborted(SdoAbort::UnknownCommand, AbortSource::Client),
            abort_sent: true,
        },
        Case {
            name: "initiate response for another object",
            upload: true,
            index: U32,
            at: 0,
            edit: |mut f| {
                f.data[3] = 9;
                Some(f)
            },
            result: aborted(SdoAbort::IncompatibleParameter, AbortSource::Client),
            abort_sent: true,
        },
        Case {
            name: "a short (7-byte) segment is no SDO frame: ignored, then silence",
            upload: true,
            index: DOMAIN,
            at: 1,
            edit: |f| CanFrame::data(f.id, &f.data[..7]),
            result: aborted(SdoAbort::Timeout, AbortSource::Client),
            abort_sent: true,
        },
        Case {
            name: "silence after the initiate",
            upload: true,
            index: STRING,
            at: 0,
            edit: |_| None,
            result: aborted(SdoAbort::Timeout, AbortSource::Client),
            abort_sent: true,
        },
        Case {
            name: "silence mid-download",
            upload: false,
            index: DOMAIN,
            at: 3,
            edit: |_| None,
            result: aborted(SdoAbort::Timeout, AbortSource::Client),
            abort_sent: true,
        },
        Case {
            name: "the server aborts mid-upload",
            upload: true,
            index: DOMAIN,
            at: 2,
            edit: |f| CanFrame::data(f.id, &[0x80, 0x03, 0x20, 0x00, 0x21, 0x00, 0x00, 0x08]),
            result: aborted(SdoAbort::DataTransferLocal, AbortSource::Server),
            abort_sent: false,
        },
        Case {
            name: "more upload data than indicated",
            upload: true,
            index: STRING,
            at: 0,
            edit: |mut f| {
                f.data[4] = 3;
                Some(f)
            },
            result: aborted(SdoAbort::LengthTooHigh, AbortSource::Client),
            abort_sent: true,
        },
        Case {
            name: "less upload data than indicated",
            upload: true,
            index: STRING,
            at: 0,
            edit: |mut f| {
                f.data[4] = 30;
                Some(f)
            },
            result: aborted(SdoAbort::LengthTooLow, AbortSource::Client),
            abort_sent: false,
        },
        Case {
            name: "a remote frame on the response COB-ID",
            upload: true,
            index: U32,
            at: 0,
            edit: |f| CanFrame::remote(f.id, 8),
            result: aborted(SdoAbort::Timeout, AbortSource::Client),
            abort_sent: true,
        },
        Case {
            name: "the answer on another node's COB-ID",
            upload: true,
            index: U32,
            at: 0,
            edit: |f| CanFrame::data(response_id(NODE + 1), &f.data),
            result: aborted(SdoAbort::Timeout, AbortSource::Client),
            abort_sent: true,
        },
    ];
    for case in cases {
        let mut link = Link::<256>::new();
        let before = link.dict.clone();
        let mut buf = [0_u8; 256];
        let first = if case.upload {
            link.client.upload(NODE, case.index, 0, 0).expect("an idle client")
        } else {
            buf[..200].fill(0xEE);
            link.client.download(NODE, case.index, 0, if case.index == U32 { &buf[..4] } else { &buf[..200] }, 0).expect("an idle client")
        };
        let result = link.run(first, &mut buf, |i, f| if i == case.at { (case.edit)(f) } else { Some(f) });
        assert_eq!(result, case.result, "{}", case.name);
        assert_eq!(link.requests.last().expect("a request")[0] == 0x80, case.abort_sent, "{}: abort frame sent", case.name);
        if case.abort_sent {
            let code = u32::from_le_bytes(link.requests.last().expect("a request")[4..].try_into().expect("4 bytes"));
            assert_eq!(SdoResult::Aborted { code, by: AbortSource::Client }, case.result, "{}: the code sent", case.name);
        }
        assert!(link.server.is_idle() || !case.abort_sent, "{}: the server heard the abort", case.name);
        // An expedited download is written when the server reads it, whatever its response
        // suffers on the way back; a segmented one only after the last segment.
        if !case.upload && case.index != U32 {
            assert_eq!(link.dict, before, "{}: nothing written", case.name);
        }
    }
}

/// A small xorshift generator: the same cases on every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// Whether `frame` is a response that may end the transfer successfully: an expedited upload
/// or download initiate response for the object, or a segment (response) marked last.
fn may_complete(frame: &CanFrame, upload: bool) -> bool {
    let [b0, lo, hi, sub, ..] = frame.data;
    let for_object = [lo, hi, sub] == [0x00, 0x20, 0x00];
    match (upload, b0 >> 5) {
        (true, 2) => for_object && b0 & 0x02 != 0,
        (true, 0) => b0 & 0x01 != 0,
        (false, 3) => for_object,
        (false, 1) => true,
        _ => false,
    }
}

#[test]
fn arbitrary_frames_never_panic_and_complete_only_on_a_valid_answer() {
    let mut rng = Rng(0x5EED_C0F0_12AB_34CD);
    let mut client = SdoClient::new();
    let (mut completed, mut aborted_count, mut requests) = (0, 0, 0);
    let value = [0x11_u8; 20];
    let mut upload = true;
    let mut now = 0;
    for _ in 0..200_000 {
        if client.is_idle() {
            upload = rng.next().is_multiple_of(2);
            let len = (rng.next() % 21) as usize;
            let started = if upload { client.upload(NODE, 0x2000, 0, now) } else { client.download(NODE, 0x2000, 0, &value[..len], now) };
            assert!(started.is_ok());
        }
        let r = rng.next();
        // Mostly on the response COB-ID, with the object's multiplexer half the time.
        let id = if r.is_multiple_of(16) { (r >> 8) as u16 & 0x7FF } else { response_id(NODE) };
        let mut data = rng.next().to_le_bytes();
        if r & 0x10 != 0 {
            data[1..4].copy_from_slice(&[0x00, 0x20, 0x00]);
        }
        let len = if r & 0x60 == 0 { (r >> 16) as usize % 9 } else { 8 };
        let frame = if r & 0x380 == 0 { CanFrame::remote(id, 8).expect("a valid frame") } else { CanFrame::data(id, &data[..len]).expect("a valid frame") };
        now += 1000;
        let mut buf = [0_u8; 64];
        buf[..20].copy_from_slice(&value);
        let request = client.on_frame(&frame, now, &mut buf);
        let counts = frame.id == response_id(NODE) && !frame.rtr && frame.dlc == 8;
        if !counts {
            assert_eq!(request, None, "only the server's 8-byte frames move a transfer");
        }
        if let Some(request) = request {
            assert_eq!((request.id, request.dlc), (request_id(NODE), 8));
            requests += 1;
        }
        match client.take_result() {
            Some(SdoResult::Uploaded { len }) => {
                assert!(upload && counts && may_complete(&frame, true), "completed on {frame:02X?}");
                if frame.data[0] >> 5 == 2 {
                    assert_eq!(&buf[..len], &frame.data[4..4 + len], "an expedited value is the frame's data");
                }
                completed += 1;
            }
            Some(SdoResult::Downloaded) => {
                assert!(!upload && counts && may_complete(&frame, false), "completed on {frame:02X?}");
                completed += 1;
            }
            Some(SdoResult::Aborted { .. }) => aborted_count += 1,
            None => {}
        }
    }
    assert!(completed > 100 && aborted_count > 1000 && requests > 1000, "completed {completed}, aborted {aborted_count}, requests {requests}");
}
