//! The pin console: one text line drives the pins of a chip on a [`FixedBoard`] as a test
//! bench would, and shows what its outputs do. The simulator (`coforge sim co401gw1`, on
//! standard input) and the QEMU image (on its third UART) share it, so both take the same
//! commands and give the same answers:
//!
//! - `in <bits>`: the inputs IN0..IN7, bit n set = INn active (pin low); hex `0x..` or decimal;
//! - `emy0 on|off`, `emy1 on|off`: EMY0#/EMY1# active (pin low) or not (`low`/`high` too);
//! - `enable`, `enable alt`: enables CAN as the host's `02 00` / `02 81` does;
//! - `pins`: the outputs, the LEDs and the watchdog pin.
//!
//! No heap and no panic: an answer is written to any [`core::fmt::Write`] (a [`Answer`]
//! buffer on the target, a `String` in the simulator), every bad line gets an error text.

use crate::board::FixedBoard;
use crate::device::Gw1;
use coforge_stack::device::NodeAccess;
use coforge_stack::store::ParamStore;
use core::fmt::{self, Write};

/// The emergency inputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EmergencyPin {
    /// EMY0#, the critical one.
    Emy0,
    /// EMY1#, the uncritical one.
    Emy1,
}

impl EmergencyPin {
    /// Its bit in [`FixedBoard::emergency_levels`].
    const fn bit(self) -> u8 {
        match self {
            EmergencyPin::Emy0 => 0b01,
            EmergencyPin::Emy1 => 0b10,
        }
    }

    const fn name(self) -> &'static str {
        match self {
            EmergencyPin::Emy0 => "emy0",
            EmergencyPin::Emy1 => "emy1",
        }
    }
}

/// One console command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command<'a> {
    /// `in <bits>`: bit n set = INn active (pin low).
    Inputs(u8),
    /// `emy0|emy1 on|off`; `state` is the word as typed (`on`, `off`, `low`, `high`), echoed
    /// in the answer.
    Emergency { pin: EmergencyPin, active: bool, state: &'a str },
    /// `enable` or `enable alt`.
    Enable { alternate: bool },
    /// `pins`.
    Pins,
}

/// Why a line was not carried out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConsoleError<'a> {
    /// The line is not UTF-8.
    NotText,
    /// The bits of `in` are not a byte.
    NotAByte(&'a str),
    /// The state of `emy0`/`emy1` is not on/off/low/high.
    NotAState(&'a str),
    /// Not a command (the whole line, trimmed).
    Unknown(&'a str),
    /// The chip refused to enable CAN.
    EnableRefused,
}

impl fmt::Display for ConsoleError<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConsoleError::NotText => f.write_str("the line is not text (UTF-8)"),
            ConsoleError::NotAByte(s) => write!(f, "`{s}` is not a byte"),
            ConsoleError::NotAState(s) => write!(f, "`{s}`: say on (pin low) or off (pin high)"),
            ConsoleError::Unknown(line) => {
                write!(f, "unknown command `{line}`; commands: in <bits>, emy0 on|off, emy1 on|off, enable [alt], pins")
            }
            ConsoleError::EnableRefused => f.write_str("enable refused: enabled already, no valid node-ID, or `alt` in mixed mode"),
        }
    }
}

/// A byte in hex (`0x..`) or decimal.
fn byte(s: &str) -> Result<u8, ConsoleError<'_>> {
    let parsed = match s.strip_prefix("0x") {
        Some(hex) => u8::from_str_radix(hex, 16),
        None => s.parse(),
    };
    parsed.map_err(|_| ConsoleError::NotAByte(s))
}

/// `on`/`low`: active; `off`/`high`: not.
fn active(s: &str) -> Result<bool, ConsoleError<'_>> {
    match s {
        "on" | "low" => Ok(true),
        "off" | "high" => Ok(false),
        _ => Err(ConsoleError::NotAState(s)),
    }
}

impl<'a> Command<'a> {
    /// Parses one line (its line end, if any, is whitespace like any other).
    pub fn parse(line: &'a [u8]) -> Result<Self, ConsoleError<'a>> {
        Self::parse_str(core::str::from_utf8(line).map_err(|_| ConsoleError::NotText)?)
    }

    /// Parses one line of text.
    pub fn parse_str(line: &'a str) -> Result<Self, ConsoleError<'a>> {
        let mut words = line.split_whitespace();
        let (first, second, rest) = (words.next(), words.next(), words.next());
        let unknown = ConsoleError::Unknown(line.trim());
        if rest.is_some() {
            return Err(unknown);
        }
        match (first, second) {
            (Some("in"), Some(bits)) => Ok(Command::Inputs(byte(bits)?)),
            (Some(pin @ ("emy0" | "emy1")), Some(state)) => {
                let pin = if pin == "emy0" { EmergencyPin::Emy0 } else { EmergencyPin::Emy1 };
                Ok(Command::Emergency { pin, active: active(state)?, state })
            }
            (Some("enable"), None) => Ok(Command::Enable { alternate: false }),
            (Some("enable"), Some("alt")) => Ok(Command::Enable { alternate: true }),
            (Some("pins"), None) => Ok(Command::Pins),
            _ => Err(unknown),
        }
    }

    /// Carries the command out on `chip` and writes what it did to `out`. The pins take
    /// effect at the chip's next input or poll, as a level change on a real pin does.
    pub fn apply<S: ParamStore>(self, chip: &mut Gw1<FixedBoard, S>, out: &mut impl Write) -> Result<(), ConsoleError<'a>> {
        // A full answer buffer cuts the answer short; the command is done all the same.
        let _ = match self {
            Command::Inputs(bits) => {
                chip.board_mut().input_levels = !bits;
                write!(out, "inputs {bits:#04x} (pins {:#04x})", !bits)
            }
            Command::Emergency { pin, active, state } => {
                let levels = &mut chip.board_mut().emergency_levels;
                *levels = if active { *levels & !pin.bit() } else { *levels | pin.bit() };
                write!(out, "{} {state}", pin.name())
            }
            Command::Enable { alternate } => {
                let now = chip.now_us();
                if !chip.enable(alternate, now) {
                    return Err(ConsoleError::EnableRefused);
                }
                write!(out, "CAN enabled in mode {}", NodeAccess::mode_name(chip.node()))
            }
            Command::Pins => {
                let b = chip.board();
                let lit = |on: bool| if on { "lit" } else { "dark" };
                write!(
                    out,
                    "outputs {:#04x} (pins {:#04x}), run LED {}, error LED {}, watchdog {}",
                    !b.output_levels,
                    b.output_levels,
                    lit(b.run_lit),
                    lit(b.error_lit),
                    if b.watchdog { "high" } else { "low" }
                )
            }
        };
        Ok(())
    }
}

/// Parses `line`, carries it out on `chip` and writes the answer to `out`: what the command
/// did (`true`), or why it was not carried out (`false`).
pub fn run<S: ParamStore>(chip: &mut Gw1<FixedBoard, S>, line: &[u8], out: &mut impl Write) -> bool {
    match Command::parse(line).and_then(|command| command.apply(chip, out)) {
        Ok(()) => true,
        Err(why) => {
            let _ = write!(out, "{why}");
            false
        }
    }
}

/// A fixed answer buffer of `N` bytes: what does not fit is cut off (at a character
/// boundary) and the write reports [`fmt::Error`], so the answer is always a prefix of the
/// whole one.
#[derive(Debug, Clone)]
pub struct Answer<const N: usize> {
    buf: [u8; N],
    len: usize,
    cut: bool,
}

impl<const N: usize> Answer<N> {
    pub const fn new() -> Self {
        Answer { buf: [0; N], len: 0, cut: false }
    }

    pub fn as_str(&self) -> &str {
        // Only whole characters are ever copied in: this never fails.
        core::str::from_utf8(self.as_bytes()).unwrap_or_default()
    }

    pub fn as_bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or_default()
    }

    /// Whether something did not fit.
    pub fn is_cut(&self) -> bool {
        self.cut
    }

    pub fn clear(&mut self) {
        (self.len, self.cut) = (0, false);
    }
}

impl<const N: usize> Default for Answer<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> AsRef<[u8]> for Answer<N> {
    fn as_ref(&self) -> &[u8] {
        self.as_bytes()
    }
}

impl<const N: usize> Write for Answer<N> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let room = N.saturating_sub(self.len);
        let mut take = s.len().min(room);
        while !s.is_char_boundary(take) {
            take -= 1;
        }
        let (Some(dst), Some(src)) = (self.buf.get_mut(self.len..self.len + take), s.as_bytes().get(..take)) else {
            self.cut = true;
            return Err(fmt::Error);
        };
        dst.copy_from_slice(src);
        self.len += take;
        if take < s.len() {
            self.cut = true;
            return Err(fmt::Error);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coforge_stack::device::Device;
    use coforge_stack::store::NoStore;
    use std::string::String;

    fn chip() -> Gw1<FixedBoard, NoStore> {
        let mut chip = Gw1::new(FixedBoard::new(5, true), NoStore);
        chip.start(0);
        chip
    }

    /// Runs `line` on `chip`: the outcome and the answer.
    fn console(chip: &mut Gw1<FixedBoard, NoStore>, line: &str) -> (bool, String) {
        let mut out = String::new();
        let ok = run(chip, line.as_bytes(), &mut out);
        (ok, out)
    }

    #[test]
    fn every_command_parses() {
        assert_eq!(Command::parse(b"in 0x81"), Ok(Command::Inputs(0x81)));
        assert_eq!(Command::parse(b"in 129\r\n"), Ok(Command::Inputs(129)));
        assert_eq!(Command::parse_str("  in\t0  "), Ok(Command::Inputs(0)));
        assert_eq!(Command::parse_str("emy0 on"), Ok(Command::Emergency { pin: EmergencyPin::Emy0, active: true, state: "on" }));
        assert_eq!(Command::parse_str("emy1 off"), Ok(Command::Emergency { pin: EmergencyPin::Emy1, active: false, state: "off" }));
        assert_eq!(Command::parse_str("emy1 low"), Ok(Command::Emergency { pin: EmergencyPin::Emy1, active: true, state: "low" }));
        assert_eq!(Command::parse_str("emy0 high"), Ok(Command::Emergency { pin: EmergencyPin::Emy0, active: false, state: "high" }));
        assert_eq!(Command::parse_str("enable"), Ok(Command::Enable { alternate: false }));
        assert_eq!(Command::parse_str("enable alt"), Ok(Command::Enable { alternate: true }));
        assert_eq!(Command::parse_str("pins"), Ok(Command::Pins));
    }

    #[test]
    fn byte_bounds() {
        assert_eq!(Command::parse_str("in 255"), Ok(Command::Inputs(0xFF)));
        assert_eq!(Command::parse_str("in 0xff"), Ok(Command::Inputs(0xFF)));
        assert_eq!(Command::parse_str("in 0x00"), Ok(Command::Inputs(0)));
        for bad in ["256", "0x100", "-1", "0x", "0xg1", "", "1.0", "0b1", "99999999999999999999999"] {
            let line = std::format!("in {bad}");
            let expected = if bad.is_empty() { ConsoleError::Unknown("in") } else { ConsoleError::NotAByte(bad) };
            assert_eq!(Command::parse_str(&line), Err(expected), "{line:?}");
        }
    }

    #[test]
    fn bad_lines_are_errors() {
        assert_eq!(Command::parse(b"in \xFF"), Err(ConsoleError::NotText));
        assert_eq!(Command::parse_str("emy0 maybe"), Err(ConsoleError::NotAState("maybe")));
        for bad in ["", "   ", "in", "in 1 2", "emy2 on", "emy0", "emy0 on now", "enable now", "enable alt alt", "pins 1", "PINS", "outputs"] {
            assert_eq!(Command::parse_str(bad), Err(ConsoleError::Unknown(bad.trim())), "{bad:?}");
        }
    }

    #[test]
    fn inputs_and_emergency_pins_drive_the_board() {
        let mut chip = chip();
        assert_eq!(console(&mut chip, "in 0x81"), (true, "inputs 0x81 (pins 0x7e)".into()));
        assert_eq!(chip.board().input_levels, 0x7E);
        assert_eq!(console(&mut chip, "emy1 on"), (true, "emy1 on".into()));
        assert_eq!(chip.board().emergency_levels, 0b01);
        assert_eq!(console(&mut chip, "emy0 low"), (true, "emy0 low".into()));
        assert_eq!(chip.board().emergency_levels, 0b00);
        assert_eq!(console(&mut chip, "emy1 off"), (true, "emy1 off".into()));
        assert_eq!(chip.board().emergency_levels, 0b10);
        assert_eq!(console(&mut chip, "emy0 high"), (true, "emy0 high".into()));
        assert_eq!(chip.board().emergency_levels, 0b11);
        // A refused line changes nothing.
        assert_eq!(console(&mut chip, "in 0x100"), (false, "`0x100` is not a byte".into()));
        assert_eq!(chip.board().input_levels, 0x7E);
        assert_eq!(console(&mut chip, "emy0 maybe"), (false, "`maybe`: say on (pin low) or off (pin high)".into()));
        assert_eq!(chip.board().emergency_levels, 0b11);
    }

    #[test]
    fn enable_and_pins() {
        let mut chip = chip();
        assert_eq!(console(&mut chip, "pins"), (true, "outputs 0x00 (pins 0xff), run LED dark, error LED dark, watchdog high".into()));
        // The alternate enable does not exist in mixed mode.
        assert_eq!(console(&mut chip, "enable alt"), (false, "enable refused: enabled already, no valid node-ID, or `alt` in mixed mode".into()));
        assert!(!chip.node().can_enabled());
        assert_eq!(console(&mut chip, "enable"), (true, "CAN enabled in mode mixed".into()));
        assert!(chip.node().can_enabled());
        assert!(!console(&mut chip, "enable").0, "enabled already");
        // Digital only: the alternate enable chooses digital_alt.
        let mut chip = Gw1::new(FixedBoard::new(5, false), NoStore);
        chip.start(0);
        assert_eq!(console(&mut chip, "enable alt"), (true, "CAN enabled in mode digital_alt".into()));
    }

    #[test]
    fn unknown_lines_name_the_commands() {
        let mut chip = chip();
        let (ok, answer) = console(&mut chip, " frobnicate 3 ");
        assert!(!ok);
        assert_eq!(answer, "unknown command `frobnicate 3`; commands: in <bits>, emy0 on|off, emy1 on|off, enable [alt], pins");
        let mut out = String::new();
        assert!(!run(&mut chip, b"\xC3\x28", &mut out));
        assert_eq!(out, "the line is not text (UTF-8)");
    }

    #[test]
    fn answers_are_cut_to_the_buffer_without_panic() {
        let mut chip = chip();
        let mut out = Answer::<16>::new();
        assert!(run(&mut chip, b"pins", &mut out));
        assert_eq!(out.as_str(), "outputs 0x00 (pi");
        assert!(out.is_cut());
        out.clear();
        assert_eq!((out.as_str(), out.is_cut()), ("", false));
        // A long bad line: the answer is a prefix of the whole one.
        let long = [b'x'; 300];
        let mut out = Answer::<64>::new();
        assert!(!run(&mut chip, &long, &mut out));
        assert_eq!(out.as_bytes().len(), 64);
        assert!(out.as_str().starts_with("unknown command `xxx"));
        // No room at all, and a cut inside a character.
        let mut none = Answer::<0>::new();
        assert!(run(&mut chip, b"in 1", &mut none));
        assert_eq!((none.as_bytes(), none.is_cut()), (&[][..], true));
        let mut two = Answer::<2>::new();
        assert!(two.write_str("aé").is_err());
        assert_eq!(two.as_str(), "a");
        let mut exact = Answer::<3>::new();
        assert!(exact.write_str("aé").is_ok());
        assert_eq!((exact.as_str(), exact.is_cut()), ("aé", false));
    }

    #[test]
    fn every_short_line_is_answered_without_panic() {
        // Every line of up to two bytes from a small alphabet, and prefixes of the commands.
        let alphabet = b" \t\r\nin0x1emyonfabl\xFF";
        let mut chip = chip();
        for &a in alphabet {
            for &b in alphabet {
                let mut out = Answer::<128>::new();
                let ok = run(&mut chip, &[a, b], &mut out);
                assert!(ok || !out.as_bytes().is_empty(), "{:?}", [a, b]);
            }
        }
        for command in ["in 0x81", "emy0 on", "emy1 off", "enable alt", "pins"] {
            for end in 0..=command.len() {
                let mut out = Answer::<128>::new();
                let _ = run(&mut chip, command.as_bytes().get(..end).unwrap_or_default(), &mut out);
                assert!(!out.as_bytes().is_empty(), "{:?}", &command[..end]);
            }
        }
    }
}
