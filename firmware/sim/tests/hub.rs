//! The SLCAN codec and the hub: in-process ports and TCP SLCAN clients on one virtual bus.

use coforge_sim::hub::{Hub, PORT_QUEUE_CAPACITY, Port};
use coforge_sim::slcan::{self, Command, Decoder, MAX_LINE};
use coforge_stack::frame::CanFrame;
use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

const WAIT: Duration = Duration::from_secs(5);
/// How long to wait for a frame that must not arrive.
const QUIET: Duration = Duration::from_millis(150);

fn data(id: u16, bytes: &[u8]) -> CanFrame {
    CanFrame::data(id, bytes).expect("valid frame")
}

fn decode_all(bytes: &[u8]) -> Vec<Command> {
    let mut decoder = Decoder::new();
    decoder.push(bytes);
    decoder.collect()
}

fn encoded(frame: &CanFrame) -> Vec<u8> {
    let mut out = Vec::new();
    slcan::encode(frame, &mut out);
    out
}

fn wait_until(what: &str, mut cond: impl FnMut() -> bool) {
    let start = Instant::now();
    while !cond() {
        assert!(start.elapsed() < WAIT, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn hub() -> Hub {
    Hub::bind("127.0.0.1:0").expect("bind a loopback port")
}

/// A TCP SLCAN client, read the way python-can reads: lines end at `\r` or at a BELL.
struct Client {
    stream: TcpStream,
    buf: Vec<u8>,
}

impl Client {
    /// Connects and waits until the hub has made it a node (`nodes` in all, counting it).
    fn connect(hub: &Hub, nodes: usize) -> Client {
        let stream = TcpStream::connect(hub.local_addr()).expect("connect to the hub");
        stream.set_read_timeout(Some(Duration::from_millis(20))).expect("set a read timeout");
        wait_until("the client to join", || hub.node_count() == nodes);
        Client { stream, buf: Vec::new() }
    }

    fn send(&mut self, text: &str) {
        self.stream.write_all(text.as_bytes()).expect("write to the hub");
    }

    /// The next line, terminator included, or `None` if none completes within `timeout`.
    fn line(&mut self, timeout: Duration) -> Option<String> {
        let start = Instant::now();
        loop {
            if let Some(end) = self.buf.iter().position(|&b| b == b'\r' || b == 0x07) {
                let line: Vec<u8> = self.buf.drain(..=end).collect();
                return Some(String::from_utf8(line).expect("ASCII from the hub"));
            }
            if start.elapsed() > timeout {
                return None;
            }
            let mut chunk = [0u8; 1024];
            match self.stream.read(&mut chunk) {
                Ok(0) => return None,
                Ok(n) => self.buf.extend_from_slice(&chunk[..n]),
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted) => {}
                Err(e) => panic!("read from the hub: {e}"),
            }
        }
    }

    /// Lines until one satisfies `until` (returned last); panics after [`WAIT`].
    fn lines_until(&mut self, until: impl Fn(&str) -> bool) -> Vec<String> {
        let start = Instant::now();
        let mut lines = Vec::new();
        while start.elapsed() < WAIT {
            if let Some(line) = self.line(QUIET) {
                let done = until(&line);
                lines.push(line);
                if done {
                    return lines;
                }
            }
        }
        panic!("timed out; got {lines:?}");
    }

    /// Frame lines (`t`/`r`) received within [`QUIET`]; answers are skipped as python-can does.
    fn frames_within_quiet(&mut self) -> Vec<String> {
        let mut frames = Vec::new();
        while let Some(line) = self.line(QUIET) {
            if line.starts_with(['t', 'r']) {
                frames.push(line);
            }
        }
        frames
    }
}

// --- SLCAN codec ---------------------------------------------------------------------------

#[test]
fn data_frames_of_every_length_round_trip() {
    for dlc in 0..=8u8 {
        let bytes: Vec<u8> = (0..dlc).map(|i| i.wrapping_mul(0x37).wrapping_add(0xA5)).collect();
        let frame = data(0x700 + u16::from(dlc) * 0x0F, &bytes);
        let line = encoded(&frame);
        assert_eq!(line.len(), 6 + 2 * usize::from(dlc), "{line:?}");
        assert_eq!(decode_all(&line), [Command::Frame(frame)], "{}", String::from_utf8_lossy(&line));
        // Lower-case hex, as some tools write it, decodes to the same frame.
        assert_eq!(decode_all(&line.to_ascii_lowercase()), [Command::Frame(frame)]);
    }
    assert_eq!(encoded(&data(0x601, &[0x40, 0x00, 0x10, 0xAB])), b"t6014400010AB\r");
    assert_eq!(encoded(&data(0x000, &[])), b"t0000\r");
}

#[test]
fn remote_frames_round_trip() {
    for dlc in 0..=8u8 {
        let frame = CanFrame::remote(0x700 + u16::from(dlc), dlc).expect("valid remote frame");
        let line = encoded(&frame);
        assert_eq!(line, format!("r{:03X}{dlc}\r", 0x700 + u16::from(dlc)).into_bytes());
        assert_eq!(decode_all(&line), [Command::Frame(frame)]);
    }
}

#[test]
fn encode_never_writes_an_unparseable_line() {
    // Public fields allow out-of-range values; the line stays well-formed.
    let odd = CanFrame { id: 0xFFFF, rtr: false, dlc: 12, data: [0xFF; 8] };
    let line = encoded(&odd);
    assert_eq!(line, b"t7FF8FFFFFFFFFFFFFFFF\r");
    assert!(matches!(decode_all(&line).as_slice(), [Command::Frame(f)] if f.id == 0x7FF && f.dlc == 8));
}

#[test]
fn host_commands_decode_and_get_lawicel_answers() {
    let cmds = decode_all(b"C\rS6\r\rO\rV\rN\rF\rZ1\rs031C\rM00000000\rmFFFFFFFF\rL\rT1234567821122\rR1FFFFFFF0\rX1\r");
    let expected = [
        Command::Close,
        Command::Bitrate(6),
        Command::Open,
        Command::Version,
        Command::SerialNumber,
        Command::Status,
        Command::Other(b'Z'),
        Command::Other(b's'),
        Command::Other(b'M'),
        Command::Other(b'm'),
        Command::Other(b'L'),
        Command::Extended,
        Command::Extended,
        Command::Other(b'X'),
    ];
    assert_eq!(cmds, expected);
    assert_eq!(slcan::bitrate(6), Some(500_000));
    assert_eq!(slcan::bitrate(10), None);
    let answers: Vec<&[u8]> = expected.iter().map(slcan::reply).collect();
    assert_eq!(answers[..6], [&b"\r"[..], b"\r", b"\r", b"V1013\r", b"NC0F0\r", b"F00\r"]);
    assert_eq!(slcan::reply(&Command::Extended), b"Z\r");
    assert_eq!(slcan::reply(&Command::Frame(data(1, &[]))), b"z\r");
    assert_eq!(slcan::reply(&Command::Invalid), b"\x07");
}

#[test]
fn malformed_lines_are_invalid() {
    let bad: &[&str] = &[
        "t12",         // too short for id + DLC
        "t1239",       // DLC above 8
        "t123A",       // DLC not a decimal digit
        "t12G0",       // bad hex in the id
        "t1232AAB",    // one data digit short
        "t1231AABB",   // one data byte too many
        "t1231ZZ",     // bad hex in the data
        "t8000",       // id above 0x7FF
        "t+120",       // sign is not a hex digit
        "r123",        // remote without DLC
        "r1239",       // remote DLC above 8
        "r1231AA",     // remote frame with data
        "T1234567",    // extended id too short
        "T2000000000", // extended id above 29 bits
        "T1234567811", // extended data missing
        "R12345678",   // extended remote without DLC
        "S",           // bitrate without code
        "SA",          // bitrate code not a digit
        "S10",         // bitrate code too long
        "Ox",          // open with garbage
        "V1",          // version with argument
        "Z2",          // timestamps neither on nor off
        "s03",         // BTR too short
        "M0000",       // acceptance code too short
        "d1230",       // CAN FD is not classic CAN
        "q",           // unknown command
        "\u{7f}",      // control byte
        "t12\u{e9}0",  // non-ASCII
    ];
    for line in bad {
        let cmds = decode_all(format!("{line}\r").as_bytes());
        assert_eq!(cmds, [Command::Invalid], "{line:?}");
        assert_eq!(slcan::reply(&cmds[0]), b"\x07");
    }
}

#[test]
fn streaming_is_byte_at_a_time_and_tolerates_newlines() {
    let stream = b"O\r\nt1232AABB\r\n\n\rr7FF0\nC\r";
    let whole = decode_all(stream);
    assert_eq!(whole, [Command::Open, Command::Frame(data(0x123, &[0xAA, 0xBB])), Command::Frame(CanFrame::remote(0x7FF, 0).expect("remote")), Command::Close]);
    let mut decoder = Decoder::new();
    let mut one_by_one = Vec::new();
    for byte in stream {
        decoder.push(std::slice::from_ref(byte));
        one_by_one.extend(decoder.by_ref());
    }
    assert_eq!(one_by_one, whole);
    // A line split across pushes is held back until its end arrives.
    let mut decoder = Decoder::new();
    decoder.push(b"t12");
    assert_eq!(decoder.next(), None);
    assert_eq!(decoder.partial_len(), 3);
    decoder.push(b"30\r");
    assert_eq!(decoder.next(), Some(Command::Frame(data(0x123, &[]))));
}

#[test]
fn an_endless_line_is_reported_once_and_memory_stays_bounded() {
    let mut decoder = Decoder::new();
    for _ in 0..1000 {
        decoder.push(&[b'7'; 97]);
        assert!(decoder.partial_len() <= MAX_LINE);
    }
    assert_eq!(decoder.by_ref().collect::<Vec<_>>(), [Command::Invalid]);
    // The line's end resynchronises: the next line decodes.
    decoder.push(b"777\rt0011FF\r");
    assert_eq!(decoder.by_ref().collect::<Vec<_>>(), [Command::Frame(data(0x001, &[0xFF]))]);
    // A line of exactly MAX_LINE bytes is still parsed (and is invalid), not discarded.
    let mut line = vec![b't'; MAX_LINE];
    line.push(b'\r');
    assert_eq!(decode_all(&line), [Command::Invalid]);
}

#[test]
fn random_bytes_never_panic() {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut decoder = Decoder::new();
    let mut alphabet = b"tTrRSOCVNFZsMmLX0123456789abcdefABCDEFG\r\n\x07 ".to_vec();
    alphabet.extend(0..=255u8);
    let mut lines = 0usize;
    let mut commands = 0usize;
    for _ in 0..200_000 {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        let r = state.wrapping_mul(0x2545_F491_4F6C_DD1D);
        let byte = alphabet[(r >> 33) as usize % alphabet.len()];
        lines += usize::from(byte == b'\r' || byte == b'\n');
        decoder.push(&[byte]);
        commands += decoder.by_ref().count();
        assert!(decoder.partial_len() <= MAX_LINE);
    }
    assert!(commands > 0 && commands <= lines, "{commands} commands from {lines} lines");
}

// --- the hub --------------------------------------------------------------------------------

#[test]
fn tcp_client_and_port_exchange_frames_both_ways() {
    let hub = hub();
    let port = hub.attach();
    let mut client = Client::connect(&hub, 2);
    client.send("O\rt1232AABB\r");
    assert_eq!(port.recv_timeout(WAIT), Some(data(0x123, &[0xAA, 0xBB])));
    let answers = client.lines_until(|l| l == "z\r");
    assert_eq!(answers, ["\r", "z\r"]);

    port.send(data(0x581, &[0x43, 0x00, 0x10, 0x00, 0x91, 0x01, 0x0F, 0x00]));
    port.send(CanFrame::remote(0x701, 1).expect("remote"));
    assert_eq!(client.line(WAIT).as_deref(), Some("t58184300100091010F00\r"));
    assert_eq!(client.line(WAIT).as_deref(), Some("r7011\r"));
    assert_eq!(hub.frames_routed(), 3);
    assert_eq!(port.try_recv(), None);
}

#[test]
fn a_frame_reaches_everyone_but_its_sender() {
    let hub = hub();
    let (a, b) = (hub.attach(), hub.attach());
    let mut c = Client::connect(&hub, 3);

    let f1 = data(0x181, &[1, 2, 3]);
    a.send(f1);
    assert_eq!(b.recv_timeout(WAIT), Some(f1));
    assert_eq!(c.line(WAIT).as_deref(), Some("t1813010203\r"));
    assert_eq!(a.recv_timeout(QUIET), None, "the sender must not hear itself");

    c.send("t2820\r");
    let f2 = data(0x282, &[]);
    assert_eq!(a.recv_timeout(WAIT), Some(f2));
    assert_eq!(b.recv_timeout(WAIT), Some(f2));
    assert_eq!(c.lines_until(|l| l == "z\r"), ["z\r"]);
    assert!(c.frames_within_quiet().is_empty(), "the client must not hear itself");
    assert_eq!((hub.frames_routed(), hub.frames_delivered(), hub.frames_dropped()), (2, 4, 0));
}

#[test]
fn invalid_and_extended_lines_are_answered_but_not_routed() {
    let hub = hub();
    let port = hub.attach();
    let mut client = Client::connect(&hub, 2);
    client.send("t12\rT123456781FF\rV\rN\rF\r");
    assert_eq!(client.lines_until(|l| l == "F00\r"), ["\x07", "Z\r", "V1013\r", "NC0F0\r", "F00\r"]);
    assert_eq!(port.recv_timeout(QUIET), None);
    assert_eq!(hub.frames_routed(), 0);
}

#[test]
fn a_client_disconnect_leaves_the_others_undisturbed() {
    let hub = hub();
    let (a, b) = (hub.attach(), hub.attach());
    let mut c = Client::connect(&hub, 3);
    let mut d = Client::connect(&hub, 4);
    // C leaves mid-line.
    c.send("t12");
    drop(c);
    wait_until("the client to leave", || hub.node_count() == 3);

    a.send(data(0x100, &[7]));
    assert_eq!(b.recv_timeout(WAIT), Some(data(0x100, &[7])));
    assert_eq!(d.line(WAIT).as_deref(), Some("t100107\r"));
    d.send("t2001FE\r");
    assert_eq!(a.recv_timeout(WAIT), Some(data(0x200, &[0xFE])));
    assert_eq!(b.recv_timeout(WAIT), Some(data(0x200, &[0xFE])));

    // A dropped port detaches too.
    drop(b);
    assert_eq!(hub.node_count(), 2);
    a.send(data(0x101, &[]));
    let lines = d.lines_until(|l| l.starts_with('t'));
    assert_eq!(lines.last().map(String::as_str), Some("t1010\r"), "{lines:?}");
    assert_eq!(hub.frames_dropped(), 0);
}

fn numbered(n: u16) -> CanFrame {
    data(0x100 + n % 0x600, &n.to_be_bytes())
}

#[test]
fn a_thousand_frames_keep_their_order() {
    let hub = hub();
    let (a, b) = (hub.attach(), hub.attach());
    let mut client = Client::connect(&hub, 3);

    // Port to port and port to client.
    for n in 0..1000 {
        a.send(numbered(n));
    }
    for n in 0..1000 {
        assert_eq!(b.recv_timeout(WAIT), Some(numbered(n)), "frame {n}");
    }
    for n in 0..1000 {
        assert_eq!(client.line(WAIT).map(String::into_bytes), Some(encoded(&numbered(n))), "frame {n}");
    }

    // Client to port, all lines in one write.
    let text: Vec<u8> = (1000..2000).flat_map(|n| encoded(&numbered(n))).collect();
    client.stream.write_all(&text).expect("write to the hub");
    for n in 1000..2000 {
        assert_eq!(a.recv_timeout(WAIT), Some(numbered(n)), "frame {n}");
        assert_eq!(b.recv_timeout(WAIT), Some(numbered(n)), "frame {n}");
    }
    assert_eq!(hub.frames_routed(), 2000);
}

#[test]
fn a_port_that_never_reads_overflows_without_stalling_the_bus() {
    let hub = hub();
    let (sender, reader, sleeper): (Port, Port, Port) = (hub.attach(), hub.attach(), hub.attach());
    for n in 0..PORT_QUEUE_CAPACITY + 10 {
        sender.send(numbered(n as u16));
        // `reader` keeps up; `sleeper` never reads.
        assert_eq!(reader.try_recv(), Some(numbered(n as u16)));
    }
    assert_eq!(sleeper.pending(), PORT_QUEUE_CAPACITY);
    assert_eq!(hub.frames_dropped(), 10);
    // Once it reads, it gets the oldest frames, then new ones again.
    assert_eq!(sleeper.try_recv(), Some(numbered(0)));
    sender.send(data(0x7FF, &[]));
    let rest: Vec<CanFrame> = std::iter::from_fn(|| sleeper.try_recv()).collect();
    assert_eq!(rest.len(), PORT_QUEUE_CAPACITY);
    assert_eq!(rest.last(), Some(&data(0x7FF, &[])));
}

#[test]
fn dropping_the_hub_disconnects_clients_and_keeps_ports_working() {
    let hub = hub();
    let (a, b) = (hub.attach(), hub.attach());
    let mut client = Client::connect(&hub, 3);
    let start = Instant::now();
    drop(hub);
    assert!(start.elapsed() < WAIT);
    // The client sees end of stream.
    let mut byte = [0u8; 1];
    client.stream.set_read_timeout(Some(WAIT)).expect("set a read timeout");
    assert_eq!(client.stream.read(&mut byte).ok(), Some(0));
    a.send(data(0x080, &[]));
    assert_eq!(b.recv_timeout(WAIT), Some(data(0x080, &[])));
}

#[test]
fn the_hub_connects_to_an_slcan_adapter_as_its_host() {
    let hub = hub();
    let adapter = std::net::TcpListener::bind("127.0.0.1:0").expect("bind an adapter port");
    hub.connect(adapter.local_addr().expect("adapter address")).expect("connect to the adapter");
    let (mut line, _) = adapter.accept().expect("the hub connects");
    line.set_read_timeout(Some(WAIT)).expect("socket");
    let port = hub.attach();
    // A frame on the hub reaches the adapter as an SLCAN line.
    port.send(data(0x605, &[0x40, 0x00, 0x10, 0x00]));
    let mut got = vec![0; encoded(&data(0x605, &[0x40, 0x00, 0x10, 0x00])).len()];
    line.read_exact(&mut got).expect("socket");
    assert_eq!(got, encoded(&data(0x605, &[0x40, 0x00, 0x10, 0x00])));
    // The adapter's acknowledge is taken silently; its frame line goes on the hub.
    line.write_all(b"z\rt58580000000000000000\r").expect("socket");
    let frame = port.recv_timeout(WAIT).expect("the adapter's frame on the hub");
    assert_eq!(frame, data(0x585, &[0; 8]));
    // An error answer (a lone BELL: a line reached the adapter garbled) does not swallow the
    // frame line after it.
    line.write_all(b"\x07t705100\r").expect("socket");
    assert_eq!(port.recv_timeout(WAIT), Some(data(0x705, &[0])), "the frame after an error answer");
    line.set_read_timeout(Some(QUIET)).expect("socket");
    let mut answer = [0_u8; 8];
    assert!(matches!(line.read(&mut answer), Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut)), "the host answers nothing");
}
