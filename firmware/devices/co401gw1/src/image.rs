//! The gateway's process image: 16 bytes each way. 6000h, 6100h and 6120h are byte, word and
//! double-word views of the same input bytes, 6200h, 6300h and 6320h of the same output
//! bytes (DS401): this type owns those bytes and answers every access to the six objects.

use crate::app::Hooks;
use coforge_stack::od::{ReadLen, SdoAbort, read_slice};

/// Bytes each way in the digital-only modes (mixed mode uses the first 8).
pub const IMAGE: usize = 16;

/// The input and output bytes behind the DS401 digital objects.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct IoImage {
    /// 6000h sub n = `inputs[n - 1]`.
    pub inputs: [u8; IMAGE],
    /// 6200h sub n = `outputs[n - 1]`.
    pub outputs: [u8; IMAGE],
    /// Bytes each way in the current mode: 8 (mixed) or 16 (digital only).
    bytes: u8,
}

impl Default for IoImage {
    fn default() -> Self {
        IoImage { inputs: [0; IMAGE], outputs: [0; IMAGE], bytes: 8 }
    }
}

impl IoImage {
    /// Sizes the image for a mode with `bytes` bytes each way (8 or 16).
    pub fn set_bytes(&mut self, bytes: u8) {
        self.bytes = bytes.min(IMAGE as u8);
    }

    pub fn bytes(&self) -> u8 {
        self.bytes
    }
}

/// Reads sub-index `sub` of a view whose elements are `width` bytes of `image`: sub 0 is the
/// number of elements.
fn read_view(image: &[u8; IMAGE], bytes: u8, width: u8, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
    match sub.checked_sub(1) {
        None => read_slice(&[bytes / width], offset, buf),
        Some(n) => read_slice(element(image, width, n)?, offset, buf),
    }
}

/// Writes element `sub` of a view (the dictionary has checked the length and the access).
fn write_view(image: &mut [u8; IMAGE], width: u8, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
    let n = sub.checked_sub(1).ok_or(SdoAbort::ReadOnly)?;
    let at = usize::from(n) * usize::from(width);
    let dst = image.get_mut(at..at + usize::from(width)).ok_or(SdoAbort::NoSubIndex)?;
    if data.len() != dst.len() {
        return Err(SdoAbort::LengthMismatch);
    }
    dst.copy_from_slice(data);
    Ok(())
}

fn element(image: &[u8; IMAGE], width: u8, n: u8) -> Result<&[u8], SdoAbort> {
    let at = usize::from(n) * usize::from(width);
    image.get(at..at + usize::from(width)).ok_or(SdoAbort::NoSubIndex)
}

/// Each view's reads and writes, as the generated hooks name them.
impl Hooks for IoImage {
    fn read_digital_input_8_bit(&mut self, sub: u8) -> Result<u8, SdoAbort> {
        match sub.checked_sub(1) {
            None => Ok(self.bytes),
            Some(n) => self.inputs.get(usize::from(n)).copied().ok_or(SdoAbort::NoSubIndex),
        }
    }

    fn write_digital_input_8_bit(&mut self, sub: u8, value: u8) -> Result<(), SdoAbort> {
        write_view(&mut self.inputs, 1, sub, &[value])
    }

    fn read_read_digital_input_16_bit(&mut self, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        read_view(&self.inputs, self.bytes, 2, sub, offset, buf)
    }

    fn write_read_digital_input_16_bit(&mut self, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        write_view(&mut self.inputs, 2, sub, data)
    }

    fn read_read_digital_input_32_bit(&mut self, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        read_view(&self.inputs, self.bytes, 4, sub, offset, buf)
    }

    fn write_read_digital_input_32_bit(&mut self, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        write_view(&mut self.inputs, 4, sub, data)
    }

    fn read_write_to_digital_output(&mut self, sub: u8) -> Result<u8, SdoAbort> {
        match sub.checked_sub(1) {
            None => Ok(self.bytes),
            Some(n) => self.outputs.get(usize::from(n)).copied().ok_or(SdoAbort::NoSubIndex),
        }
    }

    fn write_write_to_digital_output(&mut self, sub: u8, value: u8) -> Result<(), SdoAbort> {
        write_view(&mut self.outputs, 1, sub, &[value])
    }

    fn read_write_digital_output_16_bit(&mut self, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        read_view(&self.outputs, self.bytes, 2, sub, offset, buf)
    }

    fn write_write_digital_output_16_bit(&mut self, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        write_view(&mut self.outputs, 2, sub, data)
    }

    fn read_write_digital_output_32_bit(&mut self, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        read_view(&self.outputs, self.bytes, 4, sub, offset, buf)
    }

    fn write_write_digital_output_32_bit(&mut self, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        write_view(&mut self.outputs, 4, sub, data)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_and_double_words_are_views_of_the_same_bytes() {
        let mut image = IoImage::default();
        image.set_bytes(16);
        image.write_read_digital_input_16_bit(2, &[0x34, 0x12]).unwrap();
        assert_eq!(image.inputs[2..4], [0x34, 0x12]);
        assert_eq!(image.read_digital_input_8_bit(3), Ok(0x34));
        let mut buf = [0; 4];
        assert_eq!(image.read_read_digital_input_32_bit(1, 0, &mut buf), Ok(ReadLen { copied: 4, total: 4 }));
        assert_eq!(buf, [0, 0, 0x34, 0x12]);
        image.write_write_digital_output_32_bit(4, &[1, 2, 3, 4]).unwrap();
        assert_eq!(image.outputs[12..16], [1, 2, 3, 4]);
        assert_eq!(image.read_write_to_digital_output(16), Ok(4));
    }

    #[test]
    fn sub_zero_counts_the_elements_of_the_mode() {
        let mut image = IoImage::default();
        let mut buf = [0; 1];
        assert_eq!(image.read_digital_input_8_bit(0), Ok(8));
        image.read_read_digital_input_16_bit(0, 0, &mut buf).unwrap();
        assert_eq!(buf, [4]);
        image.set_bytes(16);
        image.read_write_digital_output_32_bit(0, 0, &mut buf).unwrap();
        assert_eq!(buf, [4]);
        assert_eq!(image.write_write_to_digital_output(0, 3), Err(SdoAbort::ReadOnly));
        assert_eq!(image.write_digital_input_8_bit(17, 3), Err(SdoAbort::NoSubIndex));
    }
}
