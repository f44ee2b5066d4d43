//! Properties every generated serial protocol must have, generic over its [`SerialCodec`]:
//! the harnesses the generator emits for each device under `cfg(kani)` call them with
//! symbolic inputs, and the verification crate's random tests call them with random ones.
//! Each returns normally when the property holds and panics (an assertion) when it does not.

use crate::{Deframer, Frame, Message, SerialCodec};

/// Which of a protocol's two command sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    HostToDevice,
    DeviceToHost,
}

/// `decode(encode(x)) == x` for the command `x` that (`code`, `length_code`, `data`) decodes
/// to in `direction`, if it decodes at all: `x` encodes into `out`, the protocol's decoder
/// takes those bytes (1 ms apart) as exactly one frame, completed by the last byte, and that
/// frame decodes to `x` again. `copy` receives the decoded frame's data, so it must be as
/// long as the longest command; `out` as long as its whole frame.
pub fn prop_round_trip<C: SerialCodec>(direction: Direction, code: u8, length_code: Option<u8>, data: &[u8], out: &mut [u8], copy: &mut [u8]) {
    let frame = Frame { code, length_code, network: None, data };
    match direction {
        Direction::HostToDevice => {
            if let Ok(x) = C::HostToDevice::decode(&frame) {
                assert!(redecode::<C, _>(&x, out, copy) == Some(x), "decode(encode(x)) != x");
            }
        }
        Direction::DeviceToHost => {
            if let Ok(x) = C::DeviceToHost::decode(&frame) {
                assert!(redecode::<C, _>(&x, out, copy) == Some(x), "decode(encode(x)) != x");
            }
        }
    }
}

/// Encodes `x`, deframes the bytes with `C`'s decoder into `copy` and decodes that frame;
/// asserts that the encoding and the deframing succeed.
fn redecode<'a, C: SerialCodec, M: Message<'a>>(x: &M, out: &mut [u8], copy: &'a mut [u8]) -> Option<M> {
    let encoded = x.encode(out);
    assert!(encoded.is_ok(), "a decoded command encodes");
    let n = encoded.unwrap_or(0);
    let mut decoder = C::decoder();
    let mut got = None;
    for (i, &byte) in out.iter().take(n).enumerate() {
        assert!(got.is_none(), "the frame ended before its last byte");
        let pushed = decoder.push(byte, i as u32);
        assert!(!matches!(pushed, Some(Err(_))), "the decoder rejects what the encoder wrote");
        if let Some(Ok(f)) = pushed {
            let room = copy.get_mut(..f.data.len());
            assert!(room.is_some(), "the copy buffer is shorter than the frame's data");
            if let Some(room) = room {
                room.copy_from_slice(f.data);
            }
            got = Some((f.code, f.length_code, f.data.len()));
        }
    }
    assert!(got.is_some(), "the encoded bytes make no frame");
    let (code, length_code, len) = got?;
    let copy: &'a [u8] = copy;
    M::decode(&Frame { code, length_code, network: None, data: copy.get(..len).unwrap_or(&[]) }).ok()
}

/// The protocol's decoder takes any `bytes` (the `i`-th arriving `gaps[i % gaps.len()]` ms
/// after the one before; 1 ms without gaps) without panicking, and every frame it completes
/// decodes in both directions without panicking; a command decoded from it encodes again.
pub fn prop_decoder_total<C: SerialCodec>(bytes: &[u8], gaps: &[u8], out: &mut [u8]) {
    let mut decoder = C::decoder();
    let mut now: u32 = 0;
    for (i, &byte) in bytes.iter().enumerate() {
        let gap = if gaps.is_empty() { 1 } else { gaps.get(i % gaps.len()).copied().unwrap_or(1) };
        now = now.wrapping_add(u32::from(gap));
        if let Some(Ok(frame)) = decoder.push(byte, now) {
            if let Ok(x) = C::HostToDevice::decode(&frame) {
                assert!(x.encode(out).is_ok(), "a decoded command encodes");
            }
            if let Ok(x) = C::DeviceToHost::decode(&frame) {
                assert!(x.encode(out).is_ok(), "a decoded command encodes");
            }
        }
    }
}
