//! The lm3s6965evb board as QEMU emulates it: a millisecond clock from SysTick, the UARTs
//! the images use, banks kept in host files through semihosting, the main loop every image
//! runs its device in (`serve`, generic over the device contract), a line console for a
//! third UART, the SD card on SSI0 (`sd`), CR3101's board around that card (`cr3101_board`),
//! and what the bench images share (`bench`). The devices are the device crates';
//! each image builds its own.
#![no_std]

pub mod bench;
pub mod clock;
pub mod cr3101_board;
pub mod host_file;
pub mod line_console;
pub mod mmio;
pub mod sd;
pub mod serve;
pub mod uart;

// The memory functions of the STM32F0 images (`firmware/boards/mem`), in place of
// compiler-builtins' ones.
use coforge_board_mem as _;
