//! The lm3s6965's device registers, read and written by address: the one place the board's
//! drivers (`uart`, `sd`) touch memory-mapped I/O.

/// Reads the register at `address`.
pub fn read(address: usize) -> u32 {
    // SAFETY: the drivers pass only the aligned addresses of the lm3s6965's peripheral
    // registers (SYSCTL, UARTs, SSI0, GPIO D), which are always mapped and have no side effects
    // on read but the ones the drivers mean (a data register's next byte).
    unsafe { core::ptr::read_volatile(address as *const u32) }
}

/// Writes `value` to the register at `address`.
pub fn write(address: usize, value: u32) {
    // SAFETY: as in `read`.
    unsafe { core::ptr::write_volatile(address as *mut u32, value) }
}
