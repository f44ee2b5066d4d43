//! A line console on a UART: text lines in, one answer line out for each, `ok <answer>` or
//! `error <why>` (as the simulator's console prints them after `coforge sim: `), ended by
//! "\n". An image passes each line to its device's console (CO401GW1's pin console) from
//! [`serve_with`](crate::serve::serve_with)'s hook.

use crate::uart::Uart;

/// Lines of up to `N` bytes from a UART.
#[derive(Debug)]
pub struct LineConsole<const N: usize> {
    uart: Uart,
    line: [u8; N],
    len: usize,
    /// The line being read is longer than `N`: it is dropped up to its end.
    too_long: bool,
}

impl<const N: usize> LineConsole<N> {
    /// The console on the UART at `base` (see [`crate::uart`]).
    pub fn new(base: usize) -> Self {
        LineConsole { uart: Uart::new(base), line: [0; N], len: 0, too_long: false }
    }

    /// Reads what the UART has; for every whole line (ended by "\r" or "\n"; empty lines are
    /// skipped) `run(line)` gives whether it was carried out and the answer text, sent as
    /// `ok <text>` or `error <text>` and "\n". A line longer than `N` bytes is answered
    /// `error line too long` without being looked at.
    pub fn poll<A: AsRef<[u8]>>(&mut self, mut run: impl FnMut(&[u8]) -> (bool, A)) {
        while let Some(byte) = self.uart.read() {
            if byte != b'\r' && byte != b'\n' {
                match self.line.get_mut(self.len) {
                    Some(slot) => {
                        *slot = byte;
                        self.len += 1;
                    }
                    None => self.too_long = true,
                }
                continue;
            }
            if self.too_long {
                self.uart.write(b"error line too long\n");
            } else if self.len > 0 {
                let (ok, text) = run(self.line.get(..self.len).unwrap_or_default());
                self.uart.write(if ok { b"ok " } else { b"error " });
                self.uart.write(text.as_ref());
                self.uart.write(b"\n");
            }
            (self.len, self.too_long) = (0, false);
        }
    }
}
