//! CANopenIA's configuration loading under any file: a binary EDS comes from the bus
//! (1F50h.2), so no file may panic the coprocessor, a refused file must leave the active one
//! in place, and an accepted one must start with a node-ID a file may give. The proptest
//! (`tests/canopenia_config_files.rs`) and the cargo-fuzz target `canopenia_config_file` check
//! [`prop_config_file`].

use canopenia::Canopenia;
use canopenia::config::program::Program;
use canopenia::config::slots::{FILE_MAX, SLOT};
use coforge_stack::device::Device;
use coforge_stack::store::NoStore;
use coforge_storage::ram::RamEeprom;

/// The vendor's CiA 401 configuration (node-ID 3).
pub const VENDOR_401: &[u8] = include_bytes!("../../tests/vendor-data/canopenia/CiA401_IO_Node3.bin");

/// Configuration memory: two slots in RAM.
pub type Files = RamEeprom<[u8; 2 * SLOT]>;

/// `file` downloaded in 7-byte segments (as a segmented SDO download brings it) into `files`
/// in bootloader mode: the download's abort code, if refused, and the memory afterwards.
pub fn download(files: Files, file: &[u8]) -> (Result<(), u32>, Files) {
    let mut program = Program::new(files, canopenia::od::entries(canopenia::Mode::Default));
    program.entered(true);
    let mut result = Ok(());
    let parts = file.len().div_ceil(7).max(1);
    for (i, part) in file.chunks(7).enumerate() {
        if let Err(abort) = program.write_part(i * 7, part, i + 1 == parts) {
            result = Err(abort.code());
            break;
        }
    }
    let files = program.lend().map(|slots| slots.into_memory()).unwrap_or_default();
    (result, files)
}

/// The coprocessor (runtime node-ID 2) started on `files` and run for 50 ms: its node-ID, and
/// the values its file gave that the dictionary refused.
pub fn start(files: Files) -> (u8, u32) {
    let mut ia = Canopenia::with_configuration(2, NoStore, files);
    ia.start(0);
    for ms in 0..50 {
        while ia.poll(ms * 1000).is_some() {}
    }
    (ia.node().node_id(), ia.config_write_errors)
}

/// Byte 0 of `input` says whether the file's CRC is made right (bit 0) so that the checks
/// behind it run; the rest is the file. With the vendor's file active, the file is downloaded:
/// a refusal is an SDO abort code and the vendor's file (node 3) still runs; an accepted file
/// runs with a node-ID from 1 to 127.
pub fn prop_config_file(input: &[u8]) {
    let Some((&mode, bytes)) = input.split_first() else { return };
    let mut file = [0_u8; FILE_MAX + 16];
    let len = bytes.len().min(file.len());
    let (Some(dst), Some(src)) = (file.get_mut(..len), bytes.get(..len)) else { return };
    dst.copy_from_slice(src);
    if mode & 1 == 1
        && let Some(n) = len.checked_sub(2)
    {
        let crc = coforge_beds::layout::crc(file.get(..n).unwrap_or_default()).to_le_bytes();
        if let Some(tail) = file.get_mut(n..len) {
            tail.copy_from_slice(&crc);
        }
    }
    let (first, files) = download(Files::default(), VENDOR_401);
    assert_eq!(first, Ok(()), "the vendor's file loads");
    let (result, files) = download(files, file.get(..len).unwrap_or_default());
    let (node, _refused_values) = start(files);
    match result {
        Err(code) => {
            assert!(matches!(code >> 24, 0x06 | 0x08), "an SDO abort code: {code:08X}");
            assert_eq!(node, 3, "a refused file leaves the vendor's running");
        }
        Ok(()) => assert!((1..=127).contains(&node), "node-ID {node}"),
    }
}
