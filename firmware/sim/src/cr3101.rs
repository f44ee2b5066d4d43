//! CR3101 in the simulator: a board whose slot holds a card image (a file given with
//! `coforge sim cr3101 --card FILE`, formatted if new, or one in memory), whose clock starts at
//! the host's time, and whose console removes and inserts the card, sets its write
//! protection and the backup battery, and shows the status LEDs.

use crate::card::CardImage;
use crate::devices::Console;
use crate::storage::Eeprom;
use coforge_stack::store::BlockStore;
use cr3101::card::record::TimeStamp;
use cr3101::{Board, CardSense, Cr3101, StatusLeds};
use embedded_sdmmc::{Block, BlockCount, BlockDevice, BlockIdx};
use std::io;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// The size of a card the simulator makes.
pub const NEW_CARD_BYTES: u64 = 64 << 20;

/// The simulated CR3101.
pub type SimCr3101 = Cr3101<SimBoard, BlockStore<Eeprom>>;

/// A card in the simulated slot: its image; it stops answering the moment it leaves the
/// slot, as a pulled card does, and refuses writes when its write-protect tab is set (the
/// device should not write then; the card makes sure).
#[derive(Debug)]
pub struct SimCard {
    image: CardImage,
    read_only: bool,
    in_slot: Arc<AtomicBool>,
}

impl SimCard {
    fn check_in_slot(&self) -> io::Result<()> {
        if self.in_slot.load(Ordering::Relaxed) { Ok(()) } else { Err(io::Error::new(io::ErrorKind::NotConnected, "the card was pulled")) }
    }
}

impl BlockDevice for SimCard {
    type Error = io::Error;

    fn read(&self, blocks: &mut [Block], start: BlockIdx) -> io::Result<()> {
        self.check_in_slot()?;
        self.image.read(blocks, start)
    }

    fn write(&self, blocks: &[Block], start: BlockIdx) -> io::Result<()> {
        self.check_in_slot()?;
        if self.read_only {
            return Err(io::Error::new(io::ErrorKind::PermissionDenied, "the card is write-protected"));
        }
        self.image.write(blocks, start)
    }

    fn num_blocks(&self) -> io::Result<BlockCount> {
        self.image.num_blocks()
    }
}

/// Where the slot's card image is.
#[derive(Debug)]
enum Image {
    /// A file, opened at each insertion.
    File(PathBuf),
    /// In memory: here while the card is out of the device's use.
    Memory(Option<CardImage>),
}

/// The simulated board.
#[derive(Debug)]
pub struct SimBoard {
    image: Image,
    /// Shared with the card handed out, which fails once it is pulled.
    in_slot: Arc<AtomicBool>,
    write_protected: bool,
    battery_ok: bool,
    leds: StatusLeds,
}

impl SimBoard {
    /// A board with the card image at `path` (made and formatted if there is none), or with
    /// a new card in memory.
    pub fn new(path: Option<PathBuf>) -> io::Result<SimBoard> {
        let image = match path {
            Some(path) => {
                if !path.exists() {
                    CardImage::create(&path, NEW_CARD_BYTES, "CANMEM")?;
                }
                Image::File(path)
            }
            None => Image::Memory(Some(CardImage::in_memory(NEW_CARD_BYTES, "CANMEM")?)),
        };
        Ok(SimBoard { image, in_slot: Arc::new(AtomicBool::new(true)), write_protected: false, battery_ok: true, leds: StatusLeds::default() })
    }

    pub fn leds(&self) -> StatusLeds {
        self.leds
    }
}

impl Board for SimBoard {
    type Card = SimCard;

    fn sense_card(&mut self) -> Option<CardSense> {
        self.in_slot.load(Ordering::Relaxed).then_some(CardSense { write_protected: self.write_protected })
    }

    fn take_card(&mut self) -> Option<SimCard> {
        let image = match &mut self.image {
            Image::File(path) => CardImage::open(path).ok()?,
            Image::Memory(image) => image.take()?,
        };
        Some(SimCard { image, read_only: self.write_protected, in_slot: self.in_slot.clone() })
    }

    fn return_card(&mut self, card: SimCard) {
        if let Image::Memory(slot) = &mut self.image {
            *slot = Some(card.image);
        }
    }

    fn battery_ok(&mut self) -> bool {
        self.battery_ok
    }

    /// The host's clock (UTC).
    fn clock_at_power_on(&mut self) -> TimeStamp {
        const UNIX_TO_2000_MS: u64 = 946_684_800_000;
        let unix_ms = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_millis() as u64);
        cr3101::clock::at_ms_since_2000(unix_ms.saturating_sub(UNIX_TO_2000_MS))
    }

    fn set_leds(&mut self, leds: StatusLeds) {
        self.leds = leds;
    }
}

/// The console's commands, for `coforge sim --help` and error answers.
pub const COMMANDS: &str = "card remove, card insert [protected], battery low|ok, leds";

impl Console for SimCr3101 {
    fn console(&mut self, command: &str) -> Result<String, String> {
        let words: Vec<&str> = command.split_whitespace().collect();
        let board = self.board_mut();
        match words.as_slice() {
            ["card", "remove"] => {
                board.in_slot.store(false, Ordering::Relaxed);
                Ok("card removed".into())
            }
            ["card", "insert", rest @ ..] if rest.is_empty() || rest == ["protected"] => {
                board.in_slot.store(true, Ordering::Relaxed);
                board.write_protected = !rest.is_empty();
                Ok(format!("card inserted{}", if rest.is_empty() { "" } else { ", write-protected" }))
            }
            ["battery", state @ ("low" | "ok")] => {
                board.battery_ok = *state == "ok";
                Ok(format!("battery {state}"))
            }
            ["leds"] => {
                let l = board.leds;
                let lit = |name: &'static str, lit: bool| if lit { name } else { "" };
                let names = [lit("card-error", l.card_error), lit("card-access", l.card_access), lit("on", l.on), lit("error", l.error), lit("can", l.can)];
                let lit: Vec<&str> = names.into_iter().filter(|n| !n.is_empty()).collect();
                Ok(format!("leds lit: {}", lit.join(" ")))
            }
            _ => Err(format!("unknown command `{command}`; commands: {COMMANDS}")),
        }
    }
}
