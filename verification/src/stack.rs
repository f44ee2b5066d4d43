//! Proof obligations of the CANopen stack's small state machines, as `prop_*` functions for
//! Kani (symbolic), exhaustive and random checks.

use coforge_stack::emcy::{EmcyDefault, EmcyProducer, Reaction};
use coforge_stack::nmt::NmtCommand;
use coforge_stack::od::{ReadLen, SdoAbort, read_slice};
use coforge_stack::sdo::{SdoServer, SdoTarget};

/// Four emergencies with overlapping register bits; two share a code.
pub const EMERGENCIES: [EmcyDefault; 4] = [
    EmcyDefault { code: 0x2310, register: 0x03, manufacturer: [0; 5], reaction: Reaction::None, event: None, enabled_by: None },
    EmcyDefault { code: 0x8130, register: 0x11, manufacturer: [0; 5], reaction: Reaction::None, event: None, enabled_by: None },
    EmcyDefault { code: 0x1000, register: 0x01, manufacturer: [0, 0, 0, 0, 0x10], reaction: Reaction::None, event: None, enabled_by: None },
    EmcyDefault { code: 0x1000, register: 0x81, manufacturer: [0, 0, 0, 0, 0x20], reaction: Reaction::None, event: None, enabled_by: None },
];

/// Any sequence of raises and clears (op bit 2: clear, bits 0..1: which emergency) keeps the
/// error register equal to the OR of the active errors (plus the generic bit), sends a frame
/// only when the set changes, and an "error reset" frame carries the remaining register.
pub fn prop_emcy_register(ops: &[u8]) {
    let mut p = EmcyProducer::new();
    let mut active = [false; 4];
    for &op in ops {
        let which = usize::from(op & 3);
        let clear = op & 4 != 0;
        let Some(e) = EMERGENCIES.get(which) else { return };
        let changed = if clear { p.clear(e) } else { p.raise(e) };
        let was = active[which];
        active[which] = !clear;
        assert_eq!(changed.is_some(), was == clear, "a frame exactly when the set changes");
        // Not `zip`: Kani unrolls a `zip` loop to its full unwind bound.
        let bits = EMERGENCIES.iter().enumerate().filter(|&(i, _)| active[i]).fold(0_u8, |acc, (_, e)| acc | e.register);
        let expected = if active.iter().any(|&a| a) { bits | 1 } else { 0 };
        assert_eq!(p.register(), expected);
        if let Some(c) = changed {
            assert_eq!(c.register, expected);
            let frame = p.next(0, 0);
            let frame = frame.unwrap_or([0xFF; 8]);
            let code = if clear { 0 } else { e.code };
            assert_eq!(u16::from_le_bytes([frame[0], frame[1]]), code);
            assert_eq!(frame[2], expected);
        }
        assert_eq!(p.next(0, 0), None, "nothing else queued");
    }
}

/// An NMT frame addresses this node only if it has exactly 2 bytes, a known command and the
/// node's ID or 0.
pub fn prop_nmt_parse(payload: &[u8], node_id: u8) {
    let parsed = NmtCommand::parse(payload, node_id);
    let valid = matches!(payload, [0x01 | 0x02 | 0x80 | 0x81 | 0x82, t] if *t == 0 || *t == node_id);
    assert_eq!(parsed.is_some(), valid);
    if let (Some(cmd), Some(&cs)) = (parsed, payload.first()) {
        assert_eq!(cmd.code(), cs);
    }
}

/// A dictionary of two entries: 2000h.0 UNSIGNED32 rw, 2001h.0 a 20-byte string rw.
#[derive(Debug, Default)]
pub struct TwoEntries {
    pub u32_value: [u8; 4],
    pub text: [u8; 20],
    pub text_len: usize,
}

impl SdoTarget for TwoEntries {
    fn read(&mut self, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        match (index, sub) {
            (0x2000, 0) => read_slice(&self.u32_value, offset, buf),
            (0x2001, 0) => read_slice(self.text.get(..self.text_len).unwrap_or(&[]), offset, buf),
            (0x2000 | 0x2001, _) => Err(SdoAbort::NoSubIndex),
            _ => Err(SdoAbort::NoObject),
        }
    }
    fn check_download(&mut self, index: u16, sub: u8, size: Option<usize>) -> Result<(), SdoAbort> {
        let max = match (index, sub) {
            (0x2000, 0) => 4,
            (0x2001, 0) => 20,
            (0x2000 | 0x2001, _) => return Err(SdoAbort::NoSubIndex),
            _ => return Err(SdoAbort::NoObject),
        };
        if size.is_some_and(|n| n > max) { Err(SdoAbort::LengthTooHigh) } else { Ok(()) }
    }
    fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.check_download(index, sub, Some(data.len()))?;
        if index == 0x2000 {
            self.u32_value = data.try_into().map_err(|_| SdoAbort::LengthTooLow)?;
        } else {
            self.text.get_mut(..data.len()).ok_or(SdoAbort::LengthTooHigh)?.copy_from_slice(data);
            self.text_len = data.len();
        }
        Ok(())
    }
}

/// Any first request to an idle SDO server gets at most one answer, which is a valid server
/// frame (abort codes from CiA 301), and changes a value only through a complete download.
pub fn prop_sdo_first_request(request: &[u8]) {
    let mut target = TwoEntries::default();
    let mut server: SdoServer<32> = SdoServer::new();
    let answer = server.on_request(request, 0, &mut target);
    if let Some(a) = answer {
        match a[0] >> 5 {
            4 => {
                assert_eq!(a[0], 0x80);
                assert!(SdoAbort::from_code(u32::from_le_bytes([a[4], a[5], a[6], a[7]])).is_some(), "abort code {a:02X?}");
            }
            // Download initiate response, upload initiate response, block responses.
            2 | 3 | 5 | 6 => {}
            _ => panic!("not an initiate answer: {a:02X?}"),
        }
    }
    let expedited_write = matches!(request.first(), Some(&c) if c >> 5 == 1 && c & 0x02 != 0);
    if !expedited_write {
        assert_eq!(target.u32_value, [0; 4], "only an expedited download writes at once");
        assert_eq!(target.text_len, 0);
    }
}
