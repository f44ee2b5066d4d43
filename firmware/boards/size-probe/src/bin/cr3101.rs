//! cr3101: the whole logger (dictionary, stack, the logger over a FAT card through
//! embedded-sdmmc, the modes, RPDO logging and the PDO read mode) on a Cortex-M0, with a
//! stand-in board whose card answers what the optimiser cannot predict, so that the size
//! report shows the device's code and its static RAM (see `src/probe.rs`). No parameter store:
//! its driver is the board's.
#![no_std]
#![no_main]

use coforge_stack::store::NoStore;
use core::hint::black_box;
use cr3101::card::record::TimeStamp;
use cr3101::{Board, CardSense, Cr3101, StatusLeds};
use embedded_sdmmc::{Block, BlockCount, BlockDevice, BlockIdx};
use panic_halt as _;

/// A card whose blocks come from nowhere the compiler can see.
struct ProbeCard;

/// The card's one error.
#[derive(Debug)]
struct CardFault;

impl core::fmt::Display for CardFault {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("card fault")
    }
}

impl core::error::Error for CardFault {}

impl BlockDevice for ProbeCard {
    type Error = CardFault;
    fn read(&self, blocks: &mut [Block], start: BlockIdx) -> Result<(), CardFault> {
        for b in blocks {
            b.contents = black_box([start.0 as u8; 512]);
        }
        black_box(Ok(()))
    }
    fn write(&self, blocks: &[Block], start: BlockIdx) -> Result<(), CardFault> {
        black_box((blocks.len(), start.0));
        black_box(Ok(()))
    }
    fn num_blocks(&self) -> Result<BlockCount, CardFault> {
        Ok(BlockCount(black_box(32768)))
    }
}

struct ProbeBoard;

impl Board for ProbeBoard {
    type Card = ProbeCard;
    fn sense_card(&mut self) -> Option<CardSense> {
        black_box(Some(CardSense { write_protected: black_box(false) }))
    }
    fn take_card(&mut self) -> Option<ProbeCard> {
        black_box(Some(ProbeCard))
    }
    fn return_card(&mut self, card: ProbeCard) {
        black_box(card);
    }
    fn battery_ok(&mut self) -> bool {
        black_box(true)
    }
    fn clock_at_power_on(&mut self) -> TimeStamp {
        black_box(TimeStamp::default())
    }
    fn set_leds(&mut self, leds: StatusLeds) {
        black_box(leds);
    }
}

#[cortex_m_rt::entry]
fn main() -> ! {
    let logger = Cr3101::new(ProbeBoard, NoStore, black_box(0x20));
    // The device lives in .bss, so the size report shows its static RAM.
    let Some(logger) = cortex_m::singleton!(: Cr3101<ProbeBoard, NoStore> = logger) else {
        loop {
            cortex_m::asm::wfi()
        }
    };
    probe::run(logger)
}
