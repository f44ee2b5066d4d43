//! The host's commands as the engine serves them: a decoded frame becomes a [`Command`]
//! (what was asked, and the start byte its answer copies), then the device matches on it.

use crate::serial::HostToDevice;
use coforge_link::Frame;
use coforge_link::fields::DecodeError;

/// The most data a W, S or an answer carries (manual section 6.1).
pub const MAX_VALUE: usize = 28;

/// The only CAN network this coprocessor has (start byte bits 0..3).
pub const NETWORK: u8 = 1;

/// A value of up to [`MAX_VALUE`] bytes, owned (the frame's buffer is the decoder's).
pub type Value = heapless::Vec<u8, MAX_VALUE>;

/// What the host asked for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Request {
    WriteLocal { index: u16, sub: u8, data: Value },
    ReadLocal { index: u16, sub: u8 },
    WriteRemote { node: u8, index: u16, sub: u8, data: Value },
    ReadRemote { node: u8, index: u16, sub: u8 },
}

impl Request {
    /// The command letter, which its answer repeats.
    pub fn letter(&self) -> u8 {
        match self {
            Request::WriteLocal { .. } => b'W',
            Request::ReadLocal { .. } => b'R',
            Request::WriteRemote { .. } => b'S',
            Request::ReadRemote { .. } => b'U',
        }
    }
}

/// A command the engine answers: well formed, or with an error the answer reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Command {
    Serve(Request),
    /// A known letter with a length its layout cannot have, or a frame for another network:
    /// answered with these error bits, the fields the frame does carry, zeros for the rest.
    Refuse {
        request: Request,
        err: u16,
    },
}

/// The fields a too-short or too-long command of `letter` does carry (little-endian, as its
/// layout places them), so that its answer names what the host sent.
fn partial(letter: u8, data: &[u8]) -> Option<Request> {
    let byte = |i: usize| data.get(i).copied().unwrap_or(0);
    let word = |i: usize| u16::from_le_bytes([byte(i), byte(i + 1)]);
    Some(match letter {
        b'W' => Request::WriteLocal { index: word(0), sub: byte(2), data: Value::new() },
        b'R' => Request::ReadLocal { index: word(0), sub: byte(2) },
        b'S' => Request::WriteRemote { node: byte(0), index: word(1), sub: byte(3), data: Value::new() },
        b'U' => Request::ReadRemote { node: byte(0), index: word(1), sub: byte(3) },
        _ => return None,
    })
}

/// The command a frame carries; `None` for a letter the protocol does not have (it gets no
/// answer: the protocol has no answer without a letter).
pub fn command(frame: &Frame<'_>) -> Option<Command> {
    let request = match HostToDevice::decode(frame) {
        Ok(HostToDevice::WriteLocalRequest { index, sub, data }) => Request::WriteLocal { index, sub, data: Value::from_slice(data).ok()? },
        Ok(HostToDevice::ReadLocalRequest { index, sub }) => Request::ReadLocal { index, sub },
        Ok(HostToDevice::WriteRemoteRequest { node_id, index, sub, data }) => {
            Request::WriteRemote { node: node_id, index, sub, data: Value::from_slice(data).ok()? }
        }
        Ok(HostToDevice::ReadRemoteRequest { node_id, index, sub }) => Request::ReadRemote { node: node_id, index, sub },
        Err(DecodeError::Length { .. }) => {
            let request = partial(frame.code, frame.data)?;
            return Some(Command::Refuse { request, err: crate::serial::errors::INVALID_COMMAND_LENGTH });
        }
        Err(_) => return None,
    };
    if frame.network.is_some_and(|n| n != NETWORK) {
        return Some(Command::Refuse { request, err: crate::serial::errors::NOT_SUPPORTED });
    }
    Some(Command::Serve(request))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(code: u8, network: u8, data: &[u8]) -> Frame<'_> {
        Frame { code, length_code: None, network: Some(network), data }
    }

    #[test]
    fn commands_of_every_letter() {
        let w = command(&frame(b'W', 1, &[0x0A, 0x5F, 1, 1, 0])).unwrap();
        assert_eq!(w, Command::Serve(Request::WriteLocal { index: 0x5F0A, sub: 1, data: Value::from_slice(&[1, 0]).unwrap() }));
        let u = command(&frame(b'U', 1, &[2, 0x00, 0x10, 0])).unwrap();
        assert_eq!(u, Command::Serve(Request::ReadRemote { node: 2, index: 0x1000, sub: 0 }));
        assert_eq!(command(&frame(b'X', 1, &[1, 2, 3])), None, "no such letter: no answer");
    }

    #[test]
    fn wrong_lengths_and_other_networks_are_answered_with_their_error() {
        // R with one byte too many: the answer names 6000h.1 and says the length is wrong.
        let r = command(&frame(b'R', 1, &[0x00, 0x60, 1, 9])).unwrap();
        assert_eq!(r, Command::Refuse { request: Request::ReadLocal { index: 0x6000, sub: 1 }, err: 1 << 1 });
        // U cut after the node-ID.
        let u = command(&frame(b'U', 1, &[5])).unwrap();
        assert_eq!(u, Command::Refuse { request: Request::ReadRemote { node: 5, index: 0, sub: 0 }, err: 1 << 1 });
        let other = command(&frame(b'R', 2, &[0x00, 0x60, 1])).unwrap();
        assert_eq!(other, Command::Refuse { request: Request::ReadLocal { index: 0x6000, sub: 1 }, err: 1 << 11 });
    }
}
