//! The lm3s6965's PL011-style UARTs, polled: a byte in when one is waiting, a byte out when
//! the FIFO has room.

use crate::mmio;

/// UART0 (the first `-serial` of QEMU).
pub const UART0: usize = 0x4000_C000;
/// UART1 (the second `-serial`).
pub const UART1: usize = 0x4000_D000;
/// UART2 (the third `-serial`).
pub const UART2: usize = 0x4000_E000;

const DR: usize = 0x000;
const FR: usize = 0x018;
const LCRH: usize = 0x02C;
const CTL: usize = 0x030;
const FR_RXFE: u32 = 1 << 4;
const FR_TXFF: u32 = 1 << 5;
const LCRH_FEN: u32 = 1 << 4;
const LCRH_WLEN_8: u32 = 0b11 << 5;

/// One UART by its base address.
#[derive(Debug)]
pub struct Uart {
    base: usize,
    /// A byte that arrived before [`Uart::new`] switched the FIFO on (see there).
    early: Option<u8>,
}

impl Uart {
    /// Enables `base` for 8N1 with its FIFOs, transmit and receive. With the receive FIFO
    /// QEMU queues up to 16 received bytes without waiting for the program to read each one;
    /// without it QEMU hands over the next byte only after the data register was read, and a
    /// busy host can stretch the gap between two bytes of a telegram past a protocol's
    /// inter-byte timeout (CO401GW1's 10 ms).
    ///
    /// QEMU empties the receive buffer when the FIFO is switched on or off. A host may connect
    /// and send while the image is still starting (mounting its banks from host files takes a
    /// while): the first byte then waits in the one-byte holding register (the next ones wait
    /// in QEMU, since the register is full), and is taken out here before the switch instead
    /// of being lost.
    pub fn new(base: usize) -> Uart {
        let mut uart = Uart { base, early: None };
        uart.early = uart.take_waiting();
        uart.write_reg(LCRH, LCRH_WLEN_8 | LCRH_FEN);
        uart.write_reg(CTL, 0x301);
        uart
    }

    fn read_reg(&self, offset: usize) -> u32 {
        mmio::read(self.base + offset)
    }

    fn write_reg(&self, offset: usize, value: u32) {
        mmio::write(self.base + offset, value)
    }

    /// A received byte, if one is waiting.
    pub fn read(&mut self) -> Option<u8> {
        self.early.take().or_else(|| self.take_waiting())
    }

    fn take_waiting(&self) -> Option<u8> {
        (self.read_reg(FR) & FR_RXFE == 0).then(|| self.read_reg(DR) as u8)
    }

    /// Sends `bytes`, waiting for FIFO room.
    pub fn write(&self, bytes: &[u8]) {
        for &b in bytes {
            while self.read_reg(FR) & FR_TXFF != 0 {}
            self.write_reg(DR, u32::from(b));
        }
    }
}
