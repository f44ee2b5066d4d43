//! Configuration loading (manual section 4.2): a binary EDS downloaded into 1F50h.2 in
//! bootloader mode, kept in one of two slots, checked against this firmware's dictionary and
//! applied after every initialisation.
//!
//! - [`slots`]: the two slots on the configuration memory; a download never touches the
//!   active file, and a cut download leaves it active;
//! - [`check`]: whether a file fits the dictionary, and the abort code of each refusal;
//! - [`apply`]: a checked file as writes into the dictionary;
//! - [`program`]: 1F50h/1F51h, the activation sequence and the download.

pub mod apply;
pub mod check;
pub mod program;
pub mod slots;

/// The settings a loaded file gives the coprocessor besides its dictionary values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Settings {
    /// The node-ID; `None` when the file leaves it to the hardware (FUNC bit 5).
    pub node_id: Option<u8>,
    /// The CAN bit rate in kbit/s; `None` when the file leaves it to the hardware.
    pub bitrate_kbit: Option<u16>,
    /// FUNC bit 1: start operational without a master.
    pub autostart: bool,
    /// FUNC bit 2: the boot-up manager (NMT master) starts every node after boot-up.
    pub nmt_master: bool,
    /// FUNC bit 3: the CANopen manager runs (scans, monitoring, S and U).
    pub manager: bool,
}

impl Settings {
    /// Without a loaded file: the firmware's own (the manager firmware: the manager runs).
    pub const FIRMWARE: Settings = Settings { node_id: None, bitrate_kbit: None, autostart: false, nmt_master: false, manager: true };

    pub fn of(header: &coforge_beds::Header<'_>) -> Settings {
        use coforge_beds::layout::func;
        let hardware = header.func & func::SETTINGS_FROM_HARDWARE != 0;
        Settings {
            node_id: (!hardware).then_some(header.node_id),
            bitrate_kbit: (!hardware).then_some(header.bitrate_kbit),
            autostart: header.func & func::AUTOSTART != 0,
            nmt_master: header.func & func::BOOTUP_MANAGER != 0,
            manager: header.func & func::MANAGER != 0,
        }
    }
}
