//! The lm3s6965evb board as QEMU emulates it: a millisecond clock from SysTick, the two UARTs
//! the images use, banks kept in host files through semihosting, and the main loop the
//! CO401Memory1 images share. The module itself is the device crate's.
#![no_std]

pub mod clock;
pub mod host_file;
pub mod serve;
pub mod uart;
