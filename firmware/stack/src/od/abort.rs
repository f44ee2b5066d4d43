//! CiA 301 SDO abort codes: the one answer every refused access gets.

/// CiA 301 SDO abort codes (table 22).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum SdoAbort {
    ToggleBit = 0x0503_0000,
    Timeout = 0x0504_0000,
    UnknownCommand = 0x0504_0001,
    InvalidBlockSize = 0x0504_0002,
    InvalidSequence = 0x0504_0003,
    BlockCrc = 0x0504_0004,
    OutOfMemory = 0x0504_0005,
    UnsupportedAccess = 0x0601_0000,
    WriteOnly = 0x0601_0001,
    ReadOnly = 0x0601_0002,
    NoObject = 0x0602_0000,
    NotMappable = 0x0604_0041,
    PdoTooLong = 0x0604_0042,
    IncompatibleParameter = 0x0604_0043,
    IncompatibleInternal = 0x0604_0047,
    Hardware = 0x0606_0000,
    LengthMismatch = 0x0607_0010,
    LengthTooHigh = 0x0607_0012,
    LengthTooLow = 0x0607_0013,
    NoSubIndex = 0x0609_0011,
    InvalidValue = 0x0609_0030,
    ValueTooHigh = 0x0609_0031,
    ValueTooLow = 0x0609_0032,
    MaxBelowMin = 0x0609_0036,
    NoResource = 0x060A_0023,
    General = 0x0800_0000,
    DataTransfer = 0x0800_0020,
    DataTransferLocal = 0x0800_0021,
    DataTransferState = 0x0800_0022,
    NoDictionary = 0x0800_0023,
    NoData = 0x0800_0024,
}

impl SdoAbort {
    pub const ALL: [SdoAbort; 31] = [
        SdoAbort::ToggleBit,
        SdoAbort::Timeout,
        SdoAbort::UnknownCommand,
        SdoAbort::InvalidBlockSize,
        SdoAbort::InvalidSequence,
        SdoAbort::BlockCrc,
        SdoAbort::OutOfMemory,
        SdoAbort::UnsupportedAccess,
        SdoAbort::WriteOnly,
        SdoAbort::ReadOnly,
        SdoAbort::NoObject,
        SdoAbort::NotMappable,
        SdoAbort::PdoTooLong,
        SdoAbort::IncompatibleParameter,
        SdoAbort::IncompatibleInternal,
        SdoAbort::Hardware,
        SdoAbort::LengthMismatch,
        SdoAbort::LengthTooHigh,
        SdoAbort::LengthTooLow,
        SdoAbort::NoSubIndex,
        SdoAbort::InvalidValue,
        SdoAbort::ValueTooHigh,
        SdoAbort::ValueTooLow,
        SdoAbort::MaxBelowMin,
        SdoAbort::NoResource,
        SdoAbort::General,
        SdoAbort::DataTransfer,
        SdoAbort::DataTransferLocal,
        SdoAbort::DataTransferState,
        SdoAbort::NoDictionary,
        SdoAbort::NoData,
    ];

    /// The 32-bit code sent in an SDO abort frame.
    pub const fn code(self) -> u32 {
        self as u32
    }

    /// The abort of a code; `None` for a code CiA 301 does not list. A `match`, not a search
    /// of [`ALL`](Self::ALL): no loop for a model checker to unwind (Kani needed a bound of
    /// 32 for the search).
    pub const fn from_code(code: u32) -> Option<SdoAbort> {
        Some(match code {
            0x0503_0000 => SdoAbort::ToggleBit,
            0x0504_0000 => SdoAbort::Timeout,
            0x0504_0001 => SdoAbort::UnknownCommand,
            0x0504_0002 => SdoAbort::InvalidBlockSize,
            0x0504_0003 => SdoAbort::InvalidSequence,
            0x0504_0004 => SdoAbort::BlockCrc,
            0x0504_0005 => SdoAbort::OutOfMemory,
            0x0601_0000 => SdoAbort::UnsupportedAccess,
            0x0601_0001 => SdoAbort::WriteOnly,
            0x0601_0002 => SdoAbort::ReadOnly,
            0x0602_0000 => SdoAbort::NoObject,
            0x0604_0041 => SdoAbort::NotMappable,
            0x0604_0042 => SdoAbort::PdoTooLong,
            0x0604_0043 => SdoAbort::IncompatibleParameter,
            0x0604_0047 => SdoAbort::IncompatibleInternal,
            0x0606_0000 => SdoAbort::Hardware,
            0x0607_0010 => SdoAbort::LengthMismatch,
            0x0607_0012 => SdoAbort::LengthTooHigh,
            0x0607_0013 => SdoAbort::LengthTooLow,
            0x0609_0011 => SdoAbort::NoSubIndex,
            0x0609_0030 => SdoAbort::InvalidValue,
            0x0609_0031 => SdoAbort::ValueTooHigh,
            0x0609_0032 => SdoAbort::ValueTooLow,
            0x0609_0036 => SdoAbort::MaxBelowMin,
            0x060A_0023 => SdoAbort::NoResource,
            0x0800_0000 => SdoAbort::General,
            0x0800_0020 => SdoAbort::DataTransfer,
            0x0800_0021 => SdoAbort::DataTransferLocal,
            0x0800_0022 => SdoAbort::DataTransferState,
            0x0800_0023 => SdoAbort::NoDictionary,
            0x0800_0024 => SdoAbort::NoData,
            _ => return None,
        })
    }

    /// The meaning CiA 301 (table 22) gives the code, for people reading an abort.
    pub const fn description(self) -> &'static str {
        match self {
            SdoAbort::ToggleBit => "toggle bit not alternated",
            SdoAbort::Timeout => "SDO protocol timed out",
            SdoAbort::UnknownCommand => "client/server command specifier not valid or unknown",
            SdoAbort::InvalidBlockSize => "invalid block size (block mode only)",
            SdoAbort::InvalidSequence => "invalid sequence number (block mode only)",
            SdoAbort::BlockCrc => "CRC error (block mode only)",
            SdoAbort::OutOfMemory => "out of memory",
            SdoAbort::UnsupportedAccess => "unsupported access to an object",
            SdoAbort::WriteOnly => "attempt to read a write only object",
            SdoAbort::ReadOnly => "attempt to write a read only object",
            SdoAbort::NoObject => "object does not exist in the object dictionary",
            SdoAbort::NotMappable => "object cannot be mapped to the PDO",
            SdoAbort::PdoTooLong => "the number and length of the objects to be mapped would exceed the PDO length",
            SdoAbort::IncompatibleParameter => "general parameter incompatibility reason",
            SdoAbort::IncompatibleInternal => "general internal incompatibility in the device",
            SdoAbort::Hardware => "access failed due to a hardware error",
            SdoAbort::LengthMismatch => "data type does not match, length of service parameter does not match",
            SdoAbort::LengthTooHigh => "data type does not match, length of service parameter too high",
            SdoAbort::LengthTooLow => "data type does not match, length of service parameter too low",
            SdoAbort::NoSubIndex => "sub-index does not exist",
            SdoAbort::InvalidValue => "invalid value for parameter (download only)",
            SdoAbort::ValueTooHigh => "value of parameter written too high (download only)",
            SdoAbort::ValueTooLow => "value of parameter written too low (download only)",
            SdoAbort::MaxBelowMin => "maximum value is less than minimum value",
            SdoAbort::NoResource => "resource not available: SDO connection",
            SdoAbort::General => "general error",
            SdoAbort::DataTransfer => "data cannot be transferred or stored to the application",
            SdoAbort::DataTransferLocal => "data cannot be transferred or stored to the application because of local control",
            SdoAbort::DataTransferState => "data cannot be transferred or stored to the application because of the present device state",
            SdoAbort::NoDictionary => "object dictionary dynamic generation fails or no object dictionary is present",
            SdoAbort::NoData => "no data available",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn abort_codes_are_the_cia_301_values() {
        assert_eq!(SdoAbort::WriteOnly.code(), 0x0601_0001);
        assert_eq!(SdoAbort::ReadOnly.code(), 0x0601_0002);
        assert_eq!(SdoAbort::NoObject.code(), 0x0602_0000);
        assert_eq!(SdoAbort::NoSubIndex.code(), 0x0609_0011);
        assert_eq!(SdoAbort::LengthMismatch.code(), 0x0607_0010);
        assert_eq!(SdoAbort::LengthTooHigh.code(), 0x0607_0012);
        assert_eq!(SdoAbort::LengthTooLow.code(), 0x0607_0013);
        assert_eq!(SdoAbort::InvalidValue.code(), 0x0609_0030);
        assert_eq!(SdoAbort::ValueTooHigh.code(), 0x0609_0031);
        assert_eq!(SdoAbort::ValueTooLow.code(), 0x0609_0032);
        assert_eq!(SdoAbort::NotMappable.code(), 0x0604_0041);
        assert_eq!(SdoAbort::DataTransfer.code(), 0x0800_0020);
        assert_eq!(SdoAbort::DataTransferState.code(), 0x0800_0022);
        for a in SdoAbort::ALL {
            assert_eq!(SdoAbort::from_code(a.code()), Some(a));
        }
        assert_eq!(SdoAbort::from_code(0x1234_5678), None);
        assert_eq!(SdoAbort::NoObject.description(), "object does not exist in the object dictionary");
        // Every code has its own text.
        for (i, a) in SdoAbort::ALL.iter().enumerate() {
            assert!(SdoAbort::ALL[..i].iter().all(|b| b.description() != a.description()), "{a:?}");
        }
    }
}
