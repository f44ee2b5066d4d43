//! The STM32F042K6 board (Cortex-M0, 48 MHz, 32 KiB flash, 6 KiB RAM, LQFP32/UFQFPN32) for
//! CO401Memory1: bxCAN, the serial host on USART2, the two memory banks in two 24C128 EEPROMs
//! on I2C1, the 16 configuration pins through two 74HC165 shift registers, the supply on the
//! ADC, the status outputs and the CANopen LEDs on GPIOs.
//!
//! The chip has 25 I/O pins (23 without SWD); the datasheet's 16 configuration pins, CAN, the
//! host UART, the EEPROM bus, the supply input, four status outputs and two LEDs would need 30.
//! The configuration pins therefore go through a 16-bit 74HC165 chain on three pins, read
//! once at power-on (the module reads them only then).
//!
//! | Signal (datasheet) | STM32F042K6 pin (LQFP32 no.) | Use |
//! |---|---|---|
//! | CRX / CTX (TTL, to the transceiver) | PA11 (21) / PA12 (22) | CAN_RX / CAN_TX, AF4 |
//! | RSRX / RSTX (through an RS232 transceiver) | PA3 (9) / PA2 (8) | USART2_RX / USART2_TX, AF1 |
//! | EEPROM bus SCL / SDA | PB6 (29) / PB7 (30) | I2C1, AF1, open drain, 4.7 kOhm pull-ups to 3.3 V |
//! | bank 1 / bank 2 | - | 24C128 at A2..A0 = 000 (0x50) / 001 (0x51) |
//! | supply (behind the input diodes) | PA0 (6) | ADC_IN0, 110 kOhm / 10 kOhm divider (1/12, 39.6 V full scale) |
//! | MEM1ERR# | PA4 (10) | push-pull output, active low |
//! | MEM2ERR# | PA5 (11) | push-pull output, active low |
//! | STATE4# (new CAN monitoring data) | PA6 (12) | push-pull output, active low |
//! | STATE7# (voltage low) | PA7 (13) | push-pull output, active low |
//! | CANLEDR# (green) | PB0 (14) | push-pull output, active low, CiA 303-3 run LED |
//! | CANLEDE# (red) | PB1 (15) | push-pull output, active low, CiA 303-3 error LED |
//! | 74HC165 CLK | PB3 (26) | push-pull output |
//! | 74HC165 SH/LD# | PB4 (27) | push-pull output |
//! | 74HC165 QH (U1) | PB5 (28) | input with pull-up |
//! | ID0..ID6, CFG2 | U1 inputs A..H | 10 kOhm pull-ups, switches to ground |
//! | BD0..BD2, RSBD0..RSBD2, CFG0, CFG1 | U2 inputs A..H (U2 QH to U1 SER) | 10 kOhm pull-ups, switches to ground |
//! | 8 MHz crystal | PF0 (2) / PF1 (3) | HSE, PLL x6 = 48 MHz (feature `hsi48`: none) |
//! | SWDIO / SWCLK | PA13 (23) / PA14 (24) | debug, flashing |
//! | FU# | BOOT0 (31) | high = ROM bootloader; not read by the firmware |
//! | RES# | NRST (4) | reset |
//! | spare | PA1, PA8, PA9, PA10, PA15 | reserved STATE2#, STATE3#, STATE5#, STATE6# are not driven |
//!
//! The datasheet's inversions (ID, BD, RSBD and CFG active low) are applied by the device
//! crate's decoders: [`board::ConfigWord`] hands over raw levels.
//!
//! # CO401GW1 on the STM32F042C6 (LQFP48)
//!
//! The same die in 48 pins (`src/bin/co401gw1.rs`, [`gw1`]; `PINS-co401gw1.md` has the
//! reasons, the straps and the parameter store). Its 40 signals need 7 more pins than the
//! 33 left after SWD, the crystal and BOOT0, so ID, BD and RSBD (read only at reset) go
//! through the same two 74HC165 as above; CFG0..CFG2 are read at reset and then drive the
//! LEDs and the watchdog. 1010h/1011h store into a 24C128 at 0x50.
//!
//! | Signal (datasheet) | STM32F042C6 pin (LQFP48 no.) | Use |
//! |---|---|---|
//! | CANRX / CANTX | PA11 (32) / PA12 (33) | CAN_RX / CAN_TX, AF4 |
//! | RSRXD / RSTXD | PA3 (13) / PA2 (12) | USART2_RX / USART2_TX, AF1 |
//! | EEPROM SCL / SDA | PB6 (42) / PB7 (43) | I2C1, AF1, open drain; 24C128 at 0x50 |
//! | IN0..IN7 | PA0 (10), PA1 (11), PA4..PA9 (14..17, 29, 30) | inputs with pull-up, active low |
//! | EMY0# / EMY1# | PA10 (31) / PA15 (38) | inputs with pull-up, active low |
//! | OUT0..OUT7 | PB8 (45), PB9 (46), PB10 (21), PB11 (22), PB12..PB15 (25..28) | push-pull, active low |
//! | CFG0/R, CFG1/E, CFG2/WD | PB0 (18), PB1 (19), PB2 (20) | strap inputs at reset, then push-pull outputs: run LED, error LED, watchdog |
//! | 74HC165 CLK, SH/LD#, QH | PB3 (39), PB4 (40), PB5 (41) | ID0..ID6 on U1 A..G; BD0..BD2, RSBD0..RSBD2 on U2 A..F |
//! | 8 MHz crystal | PF0 (5) / PF1 (6) | HSE, PLL x6 = 48 MHz |
//! | SWDIO / SWCLK | PA13 (34) / PA14 (37) | debug, flashing |
//! | spare | PC13 (2), PC14 (3), PC15 (4) | |
//!
//! # CANopenIA on the STM32F091RC and the STM32F042K6
//!
//! `coprocessor::run` (feature `canopenia`) is the whole CANopenIA image for either chip (pins
//! in `firmware/boards/stm32f091/PINS.md`): `firmware/boards/stm32f091` builds this library
//! with the features `stm32f091` and `canopenia` for its image; this crate's `canopenia` is the
//! STM32F042K6 image, which does not fit the chip yet (feature `canopenia-image`, pending in
//! `dist`).
//!
//! # CR3101 on the STM32F072CB
//!
//! [`cr3101::run`] (feature `cr3101`) is the CR3101 CANmem image of
//! `firmware/boards/stm32f072`, which builds this library with the features `stm32f072` and
//! `cr3101`: the SD card on SPI1, the RTC, five status LEDs, the parameters in a 24C128 (pins
//! in `firmware/boards/stm32f072/PINS.md`).
//!
//! # CO401GW1 on the STM32F042C6 and the STM32F072CB
//!
//! [`gw1::run`] is the whole CO401GW1 image on the gateway's board (`PINS-co401gw1.md`): this
//! crate's `co401gw1` for the STM32F042C6, and `firmware/boards/stm32f072`'s for the
//! pin-compatible STM32F072CB.
#![no_std]
// One read of a status register (`serve::esr`), the GW1 board's port registers (`gw1::Ports`),
// the F091's configuration flash (`config_flash`: programming and reading it in place) and the
// chip's unique ID (`coprocessor::serial_number`) and the RTC's calendar writes
// (`cr3101::rtc`: registers svd2rust cannot range-check) are the only `unsafe`.
#![deny(unsafe_code)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]

pub mod board;
pub mod can;
pub mod clock;
#[cfg(all(feature = "stm32f091", feature = "canopenia"))]
pub mod config_flash;
#[cfg(feature = "canopenia")]
pub mod coprocessor;
#[cfg(feature = "cr3101")]
pub mod cr3101;
pub mod gw1;
pub mod i2c;
pub mod serve;

// The small memory functions (`firmware/boards/mem`): 1.5 KB less flash than compiler-builtins'.
use coforge_board_mem as _;

/// Stops for good: the peripherals were taken twice, or the board's pins name no valid
/// setting (the images' start-up).
pub(crate) fn halt() -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}
