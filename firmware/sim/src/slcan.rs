//! SLCAN for the simulator: the `no_std` codec of [`coforge_slcan`] (which boards use
//! too), with a decoder that queues the commands of many bytes and an encoder into a `Vec`.

pub use coforge_slcan::{Command, MAX_LINE, bitrate, parse, reply};
use coforge_stack::frame::CanFrame;
use std::collections::VecDeque;

/// Appends the SLCAN line of `frame`, `\r` included (see [`coforge_slcan::encode`]).
pub fn encode(frame: &CanFrame, out: &mut Vec<u8>) {
    let mut line = [0; coforge_slcan::MAX_FRAME_LINE];
    let n = coforge_slcan::encode(frame, &mut line);
    out.extend_from_slice(line.get(..n).unwrap_or_default());
}

/// A streaming decoder: [`push`](Decoder::push) any bytes, then take the [`Command`]s of the
/// completed lines through the [`Iterator`] implementation.
#[derive(Debug, Clone, Default)]
pub struct Decoder {
    lines: coforge_slcan::Decoder,
    ready: VecDeque<Command>,
}

impl Decoder {
    pub fn new() -> Decoder {
        Decoder::default()
    }

    /// Feeds received bytes; complete lines become commands.
    pub fn push(&mut self, bytes: &[u8]) {
        self.ready.extend(bytes.iter().filter_map(|&b| self.lines.push(b)));
    }

    /// As [`push`](Decoder::push), for a host reading an adapter's output (see
    /// [`coforge_slcan::Decoder::push_from_adapter`]).
    pub fn push_from_adapter(&mut self, bytes: &[u8]) {
        self.ready.extend(bytes.iter().filter_map(|&b| self.lines.push_from_adapter(b)));
    }

    /// Bytes of an unfinished line held back (0 while discarding an over-long line).
    pub fn partial_len(&self) -> usize {
        self.lines.partial_len()
    }
}

impl Iterator for Decoder {
    type Item = Command;

    fn next(&mut self) -> Option<Command> {
        self.ready.pop_front()
    }
}
