//! Default PDO configuration, as the spec gives it and `device!` emits it.

/// A default COB-ID: `base`, plus the node ID when the spec writes `$NODEID + base`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CobIdDefault {
    pub base: u32,
    pub plus_node_id: bool,
}

impl CobIdDefault {
    /// The COB-ID for a node (bit 31 set means the PDO starts disabled).
    pub const fn resolve(self, node_id: u8) -> u32 {
        if self.plus_node_id { self.base.wrapping_add(node_id as u32) } else { self.base }
    }

    pub const fn enabled(self) -> bool {
        self.base & 0x8000_0000 == 0
    }
}

/// One default PDO: communication parameters and mapping.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdoDefault {
    /// 1-based PDO number (RPDO1 is 1 and lives at 1400h/1600h).
    pub number: u16,
    pub cob_id: CobIdDefault,
    pub transmission_type: u8,
    /// Multiples of 100 us.
    pub inhibit_time: u16,
    /// Milliseconds.
    pub event_timer: u16,
    pub sync_start: u8,
    /// Mapping entries as stored in 16xxh/1Axxh: index << 16 | sub << 8 | bits.
    pub mapping: &'static [u32],
}

impl PdoDefault {
    /// Total mapped length in bits.
    pub fn mapped_bits(&self) -> u32 {
        self.mapping.iter().map(|m| m & 0xFF).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_relative_cob_ids_resolve() {
        let tpdo1 = CobIdDefault { base: 0x180, plus_node_id: true };
        assert_eq!(tpdo1.resolve(0x22), 0x1A2);
        assert!(tpdo1.enabled());
        let off = CobIdDefault { base: 0x8000_0280, plus_node_id: true };
        assert_eq!(off.resolve(5), 0x8000_0285);
        assert!(!off.enabled());
        let pdo = PdoDefault {
            number: 1,
            cob_id: tpdo1,
            transmission_type: 255,
            inhibit_time: 0,
            event_timer: 0,
            sync_start: 0,
            mapping: &[0x6000_0108, 0x6000_0208],
        };
        assert_eq!(pdo.mapped_bits(), 16);
    }
}
