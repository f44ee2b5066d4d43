//! The manager's connection to a bus: a TCP SLCAN client of a `coforge sim` or `coforge hub`
//! hub, frames out as SLCAN lines, bus frames in through the same decoder the firmware uses.

use coforge_slcan::{Command, Decoder, MAX_FRAME_LINE, encode};
use coforge_stack::frame::CanFrame;
use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

pub struct Link {
    stream: TcpStream,
    decoder: Decoder,
    /// Frames decoded but not taken yet.
    pending: std::collections::VecDeque<CanFrame>,
    started: Instant,
}

impl Link {
    /// Connects to the hub at `addr` (HOST:PORT).
    pub fn connect(addr: &str) -> Result<Link, String> {
        let stream = TcpStream::connect(addr).map_err(|e| format!("cannot connect to the bus hub at {addr}: {e}"))?;
        stream.set_nodelay(true).map_err(|e| format!("{addr}: {e}"))?;
        let mut link = Link { stream, decoder: Decoder::new(), pending: Default::default(), started: Instant::now() };
        // Open the channel, as an SLCAN adapter expects (the hub does not insist).
        link.stream.write_all(b"O\r").map_err(|e| format!("{addr}: {e}"))?;
        Ok(link)
    }

    /// Microseconds since the link was opened: the manager's clock.
    pub fn now_us(&self) -> u64 {
        u64::try_from(self.started.elapsed().as_micros()).unwrap_or(u64::MAX)
    }

    pub fn send(&mut self, frame: &CanFrame) -> Result<(), String> {
        let mut line = [0; MAX_FRAME_LINE];
        let len = encode(frame, &mut line);
        self.stream.write_all(line.get(..len).unwrap_or_default()).map_err(|e| format!("the bus hub closed the connection: {e}"))
    }

    /// The next bus frame, waiting at most `timeout`.
    pub fn recv(&mut self, timeout: Duration) -> Result<Option<CanFrame>, String> {
        if let Some(frame) = self.pending.pop_front() {
            return Ok(Some(frame));
        }
        self.stream.set_read_timeout(Some(timeout.max(Duration::from_micros(100)))).map_err(|e| e.to_string())?;
        let mut bytes = [0; 4096];
        let n = match self.stream.read(&mut bytes) {
            Ok(0) => return Err("the bus hub closed the connection".into()),
            Ok(n) => n,
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => return Ok(None),
            Err(e) => return Err(format!("the bus hub connection failed: {e}")),
        };
        for &byte in bytes.get(..n).unwrap_or_default() {
            // The hub's answers to our own lines (`z`) and anything but frames are not traffic.
            if let Some(Command::Frame(frame)) = self.decoder.push(byte) {
                self.pending.push_back(frame);
            }
        }
        Ok(self.pending.pop_front())
    }
}
