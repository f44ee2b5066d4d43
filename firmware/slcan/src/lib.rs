//! SLCAN, the Lawicel CAN232/CANUSB ASCII protocol, as python-can's `slcan` interface speaks it.
//!
//! Every command is one ASCII line ended by `\r` (a `\n` ends a line too, and empty lines are
//! skipped, so a terminal or `nc` works). The frames:
//!
//! | line | frame |
//! | --- | --- |
//! | `tIIILDD..` | standard data frame: 3 hex digits of id, DLC `0`..`8`, DLC bytes as hex |
//! | `TIIIIIIIILDD..` | extended data frame (29-bit id) |
//! | `rIIIL` | standard remote frame requesting L bytes |
//! | `RIIIIIIIIL` | extended remote frame |
//!
//! Hex digits may be upper or lower case; [`encode`] writes upper case, as python-can does.
//! The other commands a host sends: `O` open, `C` close, `S0`..`S8` bitrate (`S9`, python-can's
//! 83.3 kbit/s, is accepted too), `sxxyy` BTR0/BTR1, `V` version, `N` serial number, `F`
//! status flags, `Z0`/`Z1` timestamps, `Mxxxxxxxx`/`mxxxxxxxx` acceptance code/mask, `L`
//! listen-only, `X0`/`X1` auto-poll, `W0`..`W2` filter mode, `Q0`..`Q2` auto-start, `Un` UART
//! speed. CAN FD lines (`d`, `D`, `b`, `B`, `Yn`) are not classic CAN and are rejected as a
//! Lawicel device does, with a BELL.
//!
//! python-can reads the answers line by line, up to a `\r` or a BELL, and takes only lines that
//! start with a frame letter (`t`, `T`, `r`, `R`, ...) as frames: a transmit acknowledge `z\r`,
//! an OK `\r` and a BELL are skipped, so [`reply`] answers every line exactly as Lawicel does.
#![no_std]
#![forbid(unsafe_code)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]
#![cfg_attr(test, allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic))]

use coforge_stack::frame::CanFrame;

/// Longest line the [`Decoder`] buffers; the longest valid one, an extended data frame with
/// 8 bytes and a timestamp, has 30 characters. A longer line is discarded up to its end and
/// reported once as [`Command::Invalid`].
pub const MAX_LINE: usize = 64;

/// One decoded command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    /// `t` or `r`: a standard data or remote frame to transmit.
    Frame(CanFrame),
    /// `T` or `R`: a well-formed extended frame. CANopen uses standard ids only and the bus
    /// carries none; a hub acknowledges and drops it.
    Extended,
    /// `O`: open the channel.
    Open,
    /// `C`: close the channel.
    Close,
    /// `Sn`: set a standard bitrate, `n` in `0..=9` (see [`bitrate`]).
    Bitrate(u8),
    /// `V`: hardware and software version.
    Version,
    /// `N`: serial number.
    SerialNumber,
    /// `F`: status flags.
    Status,
    /// A well-formed command that does not change the simulation; the byte is its letter
    /// (`s`, `Z`, `M`, `m`, `L`, `X`, `W`, `Q`, `U`).
    Other(u8),
    /// A malformed or unknown line: bad hex, DLC above 8, wrong length, a standard id above
    /// 0x7FF, an extended id above 0x1FFF_FFFF, an over-long line, an unknown command.
    Invalid,
}

/// The bit rate in bit/s of an `Sn` command's `n`, as python-can maps them.
pub fn bitrate(code: u8) -> Option<u32> {
    Some(match code {
        0 => 10_000,
        1 => 20_000,
        2 => 50_000,
        3 => 100_000,
        4 => 125_000,
        5 => 250_000,
        6 => 500_000,
        7 => 750_000,
        8 => 1_000_000,
        9 => 83_300,
        _ => return None,
    })
}

const HEX: &[u8; 16] = b"0123456789ABCDEF";

fn hex_digit(nibble: u8) -> u8 {
    HEX.get(usize::from(nibble & 0x0F)).copied().unwrap_or(b'0')
}

/// The longest line [`encode`] writes: `t`, 3 id digits, DLC, 16 data digits, `\r`.
pub const MAX_FRAME_LINE: usize = 22;

/// The SLCAN line of `frame`, `\r` included: `tIIIL` + data as upper-case hex, or `rIIIL`.
/// The id is masked to 11 bits and the DLC capped at 8, so the line always parses.
pub fn encode(frame: &CanFrame, out: &mut [u8; MAX_FRAME_LINE]) -> usize {
    let id = frame.id & 0x7FF;
    let dlc = frame.dlc.min(8);
    let mut n = 0;
    let mut put = |b: u8| {
        if let Some(slot) = out.get_mut(n) {
            *slot = b;
            n += 1;
        }
    };
    put(if frame.rtr { b'r' } else { b't' });
    for shift in [8u16, 4, 0] {
        put(hex_digit(((id >> shift) & 0x0F) as u8));
    }
    put(b'0' + dlc);
    if !frame.rtr {
        for &byte in frame.data.iter().take(usize::from(dlc)) {
            put(hex_digit(byte >> 4));
            put(hex_digit(byte));
        }
    }
    put(b'\r');
    n
}

/// The Lawicel error answer, sent alone (no `\r` follows).
pub const BELL: u8 = 0x07;

/// The Lawicel answer to a command: `\r` for OK, BELL (`\x07`) for an error, `z\r` / `Z\r`
/// for a transmitted standard / extended frame, `V1013\r`, `NC0F0\r` and `F00\r` (no error
/// flags) for the queries.
pub fn reply(cmd: &Command) -> &'static [u8] {
    match cmd {
        Command::Frame(_) => b"z\r",
        Command::Extended => b"Z\r",
        Command::Open | Command::Close | Command::Bitrate(_) | Command::Other(_) => b"\r",
        Command::Version => b"V1013\r",
        Command::SerialNumber => b"NC0F0\r",
        Command::Status => b"F00\r",
        Command::Invalid => &[BELL],
    }
}

/// A streaming line decoder: [`push`](Decoder::push) one byte at a time; a byte that ends a
/// line returns its [`Command`]. Memory is [`MAX_LINE`] bytes. Never panics.
#[derive(Debug, Clone)]
pub struct Decoder {
    line: [u8; MAX_LINE],
    len: usize,
    /// The current line grew past [`MAX_LINE`]: skip to its end (already reported).
    discarding: bool,
}

impl Default for Decoder {
    fn default() -> Self {
        Decoder::new()
    }
}

impl Decoder {
    pub const fn new() -> Decoder {
        Decoder { line: [0; MAX_LINE], len: 0, discarding: false }
    }

    /// Feeds one received byte; the command of the line it completes, if any. An over-long
    /// line is reported once, as [`Command::Invalid`], when it overflows.
    pub fn push(&mut self, byte: u8) -> Option<Command> {
        if byte == b'\r' || byte == b'\n' {
            let cmd = (!self.discarding && self.len > 0).then(|| parse(self.line.get(..self.len).unwrap_or_default()));
            self.len = 0;
            self.discarding = false;
            cmd
        } else if self.discarding {
            None
        } else if let Some(slot) = self.line.get_mut(self.len) {
            *slot = byte;
            self.len += 1;
            None
        } else {
            self.len = 0;
            self.discarding = true;
            Some(Command::Invalid)
        }
    }

    /// As [`push`](Decoder::push), for a host reading what an adapter sends: its error
    /// answer, a lone [`BELL`] without `\r`, ends a line too (python-can reads answers so).
    /// Otherwise the frame line that follows an error answer would be taken as one line
    /// with it, and lost as invalid.
    pub fn push_from_adapter(&mut self, byte: u8) -> Option<Command> {
        self.push(if byte == BELL { b'\r' } else { byte })
    }

    /// Bytes of an unfinished line held back (0 while discarding an over-long line).
    pub fn partial_len(&self) -> usize {
        self.len
    }
}

/// Parses one line without its terminator.
pub fn parse(line: &[u8]) -> Command {
    let Some((&letter, args)) = line.split_first() else { return Command::Invalid };
    let hex_args = |n: usize| args.len() == n && hex(args).is_some();
    let digit_arg = |max: u8| matches!(args, [d] if d.is_ascii_digit() && d - b'0' <= max);
    match letter {
        b't' | b'r' => match frame(args, 3, letter == b'r') {
            Some((id, dlc, data)) if id <= 0x7FF => {
                let id = id as u16;
                let frame = if letter == b'r' { CanFrame::remote(id, dlc) } else { CanFrame::data(id, data.get(..usize::from(dlc)).unwrap_or_default()) };
                frame.map_or(Command::Invalid, Command::Frame)
            }
            _ => Command::Invalid,
        },
        b'T' | b'R' => match frame(args, 8, letter == b'R') {
            Some((id, _, _)) if id <= 0x1FFF_FFFF => Command::Extended,
            _ => Command::Invalid,
        },
        b'O' if args.is_empty() => Command::Open,
        b'C' if args.is_empty() => Command::Close,
        b'V' if args.is_empty() => Command::Version,
        b'N' if args.is_empty() => Command::SerialNumber,
        b'F' if args.is_empty() => Command::Status,
        b'S' => match args {
            [d @ b'0'..=b'9'] => Command::Bitrate(d - b'0'),
            _ => Command::Invalid,
        },
        b'L' if args.is_empty() => Command::Other(letter),
        b's' if hex_args(4) => Command::Other(letter),
        b'M' | b'm' if hex_args(8) => Command::Other(letter),
        b'Z' | b'X' if digit_arg(1) => Command::Other(letter),
        b'W' | b'Q' if digit_arg(2) => Command::Other(letter),
        b'U' if digit_arg(9) => Command::Other(letter),
        _ => Command::Invalid,
    }
}

/// `id_digits` hex digits of id, a decimal DLC `0`..`8`, then exactly DLC data bytes as hex
/// (none for a remote frame).
fn frame(args: &[u8], id_digits: usize, remote: bool) -> Option<(u32, u8, [u8; 8])> {
    let id = hex(args.get(..id_digits)?)?;
    let dlc = match *args.get(id_digits)? {
        d @ b'0'..=b'8' => d - b'0',
        _ => return None,
    };
    let rest = args.get(id_digits + 1..)?;
    let mut data = [0u8; 8];
    if remote {
        return rest.is_empty().then_some((id, dlc, data));
    }
    if rest.len() != 2 * usize::from(dlc) {
        return None;
    }
    for (byte, pair) in data.iter_mut().zip(rest.chunks_exact(2)) {
        *byte = u8::try_from(hex(pair)?).ok()?;
    }
    Some((id, dlc, data))
}

/// Up to 8 hex digits, either case; `None` on any other byte or on no digits.
fn hex(digits: &[u8]) -> Option<u32> {
    if digits.is_empty() || digits.len() > 8 {
        return None;
    }
    digits.iter().try_fold(0u32, |acc, &d| {
        let v = char::from(d).to_digit(16)?;
        Some(acc << 4 | v)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_error_answer_ends_a_line_only_for_the_adapters_host() {
        // An adapter answered a garbled line with BELL, then sent a frame.
        let output = b"\x07t705100\r";
        let frame = CanFrame::data(0x705, &[0]).unwrap();
        let mut host = Decoder::new();
        let got: heapless::Vec<Command, 2> = output.iter().filter_map(|&b| host.push_from_adapter(b)).collect();
        assert_eq!(got.as_slice(), [Command::Frame(frame)]);
        // A device reading its host's commands takes BELL as a character of the line.
        let mut device = Decoder::new();
        let got: heapless::Vec<Command, 2> = output.iter().filter_map(|&b| device.push(b)).collect();
        assert_eq!(got.as_slice(), [Command::Invalid]);
    }

    #[test]
    fn encodes_lines_that_parse_back() {
        let frame = CanFrame::data(0x123, &[0xB1, 0xB2]).unwrap();
        let mut line = [0; MAX_FRAME_LINE];
        let n = encode(&frame, &mut line);
        assert_eq!(&line[..n], b"t1232B1B2\r");
        let mut d = Decoder::new();
        let cmds: heapless::Vec<Command, 2> = line[..n].iter().filter_map(|&b| d.push(b)).collect();
        assert_eq!(cmds.as_slice(), [Command::Frame(frame)]);
    }

    #[test]
    fn parses_what_python_can_writes() {
        assert_eq!(parse(b"t60181234567890ABCDEF"), Command::Frame(CanFrame::data(0x601, &[0x12, 0x34, 0x56, 0x78, 0x90, 0xAB, 0xCD, 0xEF]).unwrap()));
        assert_eq!(parse(b"r7051"), Command::Frame(CanFrame::remote(0x705, 1).unwrap()));
        assert_eq!(parse(b"T1234567820011"), Command::Extended);
        assert_eq!(parse(b"R123456780"), Command::Extended);
        assert_eq!(parse(b"T2000000000"), Command::Invalid);
        assert_eq!(parse(b"t8000"), Command::Invalid);
        assert_eq!(parse(b"S8"), Command::Bitrate(8));
        assert_eq!(parse(b"s031C"), Command::Other(b's'));
        assert_eq!(parse(b"Z2"), Command::Invalid);
        assert_eq!(parse(b"d1230"), Command::Invalid);
    }
}
