//! The error-code field of W, R, S and U (manual section 6.2): which bits every local refusal
//! and every remote SDO result sets. One table each way, so a host can rely on them.
//!
//! | cause | bits |
//! |---|---|
//! | no such object or sub-index (0602 0000h, 0609 0011h) | 0 entry not found |
//! | wrong length (0607 0010h/0012h/0013h), a command of the wrong length | 1 invalid command length |
//! | a node-ID outside 1..=127 | 2 invalid command |
//! | a remote operation while one runs | 3 busy |
//! | out of memory, no resource (0504 0005h, 060A 0023h) | 4 no resources |
//! | a value longer than the 28 bytes an answer holds | 7 receive buffer too small |
//! | toggle bit (0503 0000h) | 8 SDO toggle error |
//! | timeout (0504 0000h) | 9 SDO timeout |
//! | read-only, write-only, unsupported access (0601 000xh), another network | 11 not supported |
//! | a local hardware error (0606 0000h): the parameter store failed | 13 non-volatile memory write failure |
//! | any other abort (value range, PDO mapping, device state, general) | 10 unknown error |
//!
//! A remote operation that ends in an abort also sets bit 6 (transfer aborted), whoever
//! aborted, besides the bit of its code; the abort code itself is not in the protocol.

use crate::serial::errors::*;
use coforge_stack::od::SdoAbort;
use coforge_stack::sdo::client::{AbortSource, SdoResult};

/// The bits of an abort code, local or remote.
pub fn of_abort(abort: SdoAbort) -> u16 {
    use SdoAbort::*;
    match abort {
        NoObject | NoSubIndex => OD_ENTRY_NOT_FOUND,
        LengthMismatch | LengthTooHigh | LengthTooLow => INVALID_COMMAND_LENGTH,
        OutOfMemory | NoResource => NO_RESOURCES,
        ToggleBit => SDO_TOGGLE_ERROR,
        Timeout => SDO_TIMEOUT,
        UnsupportedAccess | WriteOnly | ReadOnly => NOT_SUPPORTED,
        Hardware => NVM_WRITE_FAILURE,
        _ => UNKNOWN_ERROR,
    }
}

/// The error code of a remote operation's end.
pub fn of_remote(result: &SdoResult) -> u16 {
    match *result {
        SdoResult::Uploaded { .. } | SdoResult::Downloaded => 0,
        // The client stopped an upload longer than the answer's 28 bytes.
        SdoResult::Aborted { code, by: AbortSource::Client } if code == SdoAbort::OutOfMemory.code() => TRANSFER_ABORTED | RECEIVE_BUFFER_TOO_SMALL,
        SdoResult::Aborted { code, .. } => TRANSFER_ABORTED | SdoAbort::from_code(code).map_or(UNKNOWN_ERROR, of_abort),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_abort_has_exactly_one_bit() {
        for abort in SdoAbort::ALL {
            assert_eq!(of_abort(abort).count_ones(), 1, "{abort:?}");
        }
        assert_eq!(of_abort(SdoAbort::NoSubIndex), 1);
        assert_eq!(of_abort(SdoAbort::ReadOnly), 1 << 11);
        assert_eq!(of_abort(SdoAbort::ValueTooHigh), 1 << 10);
    }

    #[test]
    fn remote_aborts_say_so_besides_their_cause() {
        let server = |a: SdoAbort| SdoResult::Aborted { code: a.code(), by: AbortSource::Server };
        assert_eq!(of_remote(&SdoResult::Downloaded), 0);
        assert_eq!(of_remote(&server(SdoAbort::NoObject)), 1 << 6 | 1);
        assert_eq!(of_remote(&SdoResult::Aborted { code: SdoAbort::Timeout.code(), by: AbortSource::Client }), 1 << 6 | 1 << 9);
        assert_eq!(of_remote(&SdoResult::Aborted { code: SdoAbort::OutOfMemory.code(), by: AbortSource::Client }), 1 << 6 | 1 << 7);
        // A code CiA 301 does not list, sent by a server.
        assert_eq!(of_remote(&SdoResult::Aborted { code: 0x1234_5678, by: AbortSource::Server }), 1 << 6 | 1 << 10);
    }
}
