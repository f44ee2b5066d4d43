//! CR3101's board on QEMU's lm3s6965evb: the card slot is QEMU's SD card on SSI0 (`sd`), the
//! status LEDs are kept in RAM and shown on a line console (UART2), the clock starts at a
//! fixed date.
//!
//! **Card detection.** The board has no card-detect pin, so the slot is probed whenever the
//! device polls it (every 100 ms), with one SPI-mode command whose R1 answer comes within NCR
//! (at most [`R1_POLLS`] bytes); a slot without a card answers nothing (MISO stays high: FFh
//! only, on a real board as in QEMU 7.2 with its drive empty):
//! - while no card is up: CMD0 (GO_IDLE_STATE). Any card answers it; only then is the card
//!   initialised by the driver (CMD0, CMD8, ACMD41, CMD58, and the CSD for its size), which
//!   with no card would spend half a second in its retries at every poll;
//! - while a card is up (initialised, and every probe answered since): CMD13 (SEND_STATUS),
//!   which must answer R1 without the idle and illegal-command bits. A card pulled (monitor
//!   `eject -f sd0`) answers nothing; one pulled and put back between two polls (`change sd0
//!   FILE raw`: QEMU resets the card when a medium comes) is in its idle state again, where
//!   CMD13 is illegal. Either way the card is no longer up: the device lets it go and mounts
//!   whatever is in the slot at a later poll.
//!
//! The probe runs between the device's card accesses, on its own handle of SSI0 while the
//! device holds the driver. A card that is no longer up fails every block access at once
//! ([`QemuCard`]), as a pulled card does, instead of the driver's timeouts (what the device
//! tries to save as it lets the card go would otherwise stall the node for seconds).
//!
//! **Write protection.** QEMU's SPI-mode card has no write-protect switch (and QEMU refuses a
//! read-only drive as an SD card): a card is never write-protected here.
//!
//! **Clock.** QEMU's lm3s6965evb has no battery-backed RTC: the device's clock (2010h) starts
//! at [`POWER_ON_TIME`] at every power-on, until it is set over SDO.

use crate::sd::{SdSpi, SpinDelay};
use coforge_stack::store::ParamStore;
use core::fmt::Write as _;
use core::sync::atomic::{AtomicBool, Ordering};
use cr3101::card::record::TimeStamp;
use cr3101::{Board, CardSense, Cr3101, StatusLeds};
use embedded_hal::spi::{Operation, SpiDevice};
use embedded_sdmmc::{Block, BlockCount, BlockDevice, BlockIdx, SdCard, SdCardError};

/// The card in the slot was initialised and has answered every probe since (the board's one
/// slot; shared with the driver the device holds).
static CARD_UP: AtomicBool = AtomicBool::new(false);

/// The card's block device: embedded-sdmmc's SPI-mode driver over SSI0, failing at once
/// (`CardNotFound`) once the card is no longer up.
pub struct QemuCard {
    sd: SdCard<SdSpi, SpinDelay>,
}

impl QemuCard {
    fn check_up() -> Result<(), SdCardError> {
        if CARD_UP.load(Ordering::Relaxed) { Ok(()) } else { Err(SdCardError::CardNotFound) }
    }
}

impl BlockDevice for QemuCard {
    type Error = SdCardError;

    fn read(&self, blocks: &mut [Block], start: BlockIdx) -> Result<(), SdCardError> {
        Self::check_up()?;
        self.sd.read(blocks, start)
    }

    fn write(&self, blocks: &[Block], start: BlockIdx) -> Result<(), SdCardError> {
        Self::check_up()?;
        self.sd.write(blocks, start)
    }

    fn num_blocks(&self) -> Result<BlockCount, SdCardError> {
        Self::check_up()?;
        self.sd.num_blocks()
    }
}

/// What the clock shows at power-on: 2026-01-01 00:00:00.000.
pub const POWER_ON_TIME: TimeStamp = TimeStamp { millisecond: 0, second: 0, minute: 0, hour: 0, day: 1, month: 1, year: 26 };

/// A command with argument 0, its CRC7 and end bit (CMD0 is sent while the card still
/// checks CRCs; the driver switches CRC checking on for the rest).
const fn command(index: u8) -> [u8; 6] {
    let token = 0x40 | index;
    [token, 0, 0, 0, 0, (crc7(&[token, 0, 0, 0, 0]) << 1) | 1]
}
const CMD0: [u8; 6] = command(0);
const CMD13: [u8; 6] = command(13);
/// Bytes read for R1 after a command before the card counts as silent (NCR is at most 8).
const R1_POLLS: usize = 8;
/// R1 bits CMD13 must not answer: in idle state (reset: a card put back), illegal command (a
/// card in a state where CMD13 is not allowed).
const R1_IDLE: u8 = 0x01;
const R1_ILLEGAL: u8 = 0x04;

/// CRC7 of an SD command (polynomial x^7 + x^3 + 1).
const fn crc7(bytes: &[u8]) -> u8 {
    let mut crc = 0_u8;
    let mut i = 0;
    while i < bytes.len() {
        let mut byte = bytes[i];
        let mut bit = 0;
        while bit < 8 {
            crc <<= 1;
            if (byte ^ crc) & 0x80 != 0 {
                crc ^= 0x09;
            }
            byte <<= 1;
            bit += 1;
        }
        i += 1;
    }
    crc & 0x7F
}

/// The board.
pub struct QemuBoard {
    /// The card driver while the device does not hold it.
    card: Option<QemuCard>,
    /// SSI0 for the probes.
    probe: SdSpi,
    leds: StatusLeds,
    battery_ok: bool,
}

impl core::fmt::Debug for QemuBoard {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("QemuBoard")
            .field("card_up", &CARD_UP.load(Ordering::Relaxed))
            .field("leds", &self.leds)
            .field("battery_ok", &self.battery_ok)
            .finish_non_exhaustive()
    }
}

impl QemuBoard {
    /// The board with its slot (the card is looked for at the device's first poll).
    pub fn new() -> Self {
        CARD_UP.store(false, Ordering::Relaxed);
        QemuBoard { card: Some(QemuCard { sd: SdCard::new(SdSpi::new(), SpinDelay) }), probe: SdSpi::new(), leds: StatusLeds::default(), battery_ok: true }
    }

    pub fn leds(&self) -> StatusLeds {
        self.leds
    }

    /// Sends `cmd` on SSI0: the card's R1, if it answered within NCR.
    fn r1(&mut self, cmd: &[u8; 6]) -> Option<u8> {
        // Ready (FFh), the command, then R1 within R1_POLLS bytes, R2's second byte (CMD13)
        // and FFh, after which QEMU's adapter waits for a command again. `SdSpi` cannot fail.
        let mut answer = [0xFF_u8; R1_POLLS + 2];
        let _ = self.probe.transaction(&mut [Operation::Write(&[0xFF]), Operation::Write(cmd), Operation::TransferInPlace(&mut answer)]);
        answer.iter().take(R1_POLLS).copied().find(|b| b & 0x80 == 0)
    }
}

impl Default for QemuBoard {
    fn default() -> Self {
        QemuBoard::new()
    }
}

impl Board for QemuBoard {
    type Card = QemuCard;

    fn sense_card(&mut self) -> Option<CardSense> {
        let up = if CARD_UP.load(Ordering::Relaxed) {
            self.r1(&CMD13).is_some_and(|r1| r1 & (R1_IDLE | R1_ILLEGAL) == 0)
        } else if self.r1(&CMD0).is_some()
            && let Some(card) = &self.card
        {
            // A card answered: the driver initialises it.
            card.sd.mark_card_uninit();
            card.sd.num_bytes().is_ok()
        } else {
            false
        };
        // A card that is no longer up fails the device's accesses at once; the device lets it
        // go, and gives its driver back.
        CARD_UP.store(up, Ordering::Relaxed);
        up.then_some(CardSense { write_protected: false })
    }

    fn take_card(&mut self) -> Option<QemuCard> {
        if CARD_UP.load(Ordering::Relaxed) { self.card.take() } else { None }
    }

    fn return_card(&mut self, card: QemuCard) {
        self.card = Some(card);
    }

    fn battery_ok(&mut self) -> bool {
        self.battery_ok
    }

    fn clock_at_power_on(&mut self) -> TimeStamp {
        POWER_ON_TIME
    }

    fn set_leds(&mut self, leds: StatusLeds) {
        self.leds = leds;
    }
}

/// An answer line of the console.
pub struct Answer<const N: usize> {
    bytes: [u8; N],
    len: usize,
}

impl<const N: usize> Answer<N> {
    pub fn new() -> Self {
        Answer { bytes: [0; N], len: 0 }
    }
}

impl<const N: usize> Default for Answer<N> {
    fn default() -> Self {
        Answer::new()
    }
}

impl<const N: usize> AsRef<[u8]> for Answer<N> {
    fn as_ref(&self) -> &[u8] {
        self.bytes.get(..self.len).unwrap_or_default()
    }
}

impl<const N: usize> core::fmt::Write for Answer<N> {
    /// Keeps what fits.
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        for &b in s.as_bytes() {
            let Some(slot) = self.bytes.get_mut(self.len) else { return Err(core::fmt::Error) };
            *slot = b;
            self.len += 1;
        }
        Ok(())
    }
}

/// The console's commands (the simulator's, but for the card, which QEMU's monitor takes out
/// and puts back).
pub const COMMANDS: &str = "battery low|ok, leds";

/// Runs one console line (`battery low|ok`, `leds`): whether it was carried out, and the
/// answer, as the simulator's console words it.
pub fn console<S: ParamStore, const N: usize>(device: &mut Cr3101<QemuBoard, S>, line: &[u8]) -> (bool, Answer<N>) {
    let mut answer = Answer::new();
    let text = core::str::from_utf8(line).unwrap_or("");
    let mut words = text.split_ascii_whitespace();
    let ok = match (words.next(), words.next(), words.next()) {
        (Some("battery"), Some(state @ ("low" | "ok")), None) => {
            device.board_mut().battery_ok = state == "ok";
            let _ = write!(answer, "battery {state}");
            true
        }
        (Some("leds"), None, None) => {
            let l = device.board_mut().leds;
            let _ = answer.write_str("leds lit:");
            let lit = [("card-error", l.card_error), ("card-access", l.card_access), ("on", l.on), ("error", l.error), ("can", l.can)];
            for (name, _) in lit.iter().filter(|(_, on)| *on) {
                let _ = write!(answer, " {name}");
            }
            true
        }
        _ => {
            let _ = write!(answer, "unknown command `{text}`; commands: {COMMANDS}");
            false
        }
    };
    (ok, answer)
}
