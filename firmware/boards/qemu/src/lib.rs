//! The lm3s6965evb board as QEMU emulates it: a millisecond clock from SysTick and the two
//! UARTs the images use. Everything device-specific is in the device crates.
#![no_std]

pub mod clock;
pub mod uart;
