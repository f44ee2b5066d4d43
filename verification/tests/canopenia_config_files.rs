//! CANopenIA's configuration loading under arbitrary files: a binary EDS comes from the bus
//! (1F50h.2), so no file may panic the coprocessor, a refused file must leave the active one in
//! place, and an accepted one must start. Files are the vendor's CiA 401 file and coforge's own
//! export with random bytes changed and cut short, most with their CRC made right again so that
//! the checks behind it run too.

use canopenia::Canopenia;
use canopenia::config::program::Program;
use canopenia::config::slots::{ConfigMemory, ConfigSlots};
use coforge_stack::device::Device;
use coforge_stack::store::NoStore;
use embedded_storage::{ReadStorage, Storage};
use proptest::prelude::*;
use std::sync::OnceLock;

const VENDOR_401: &[u8] = include_bytes!("../../tests/vendor-data/canopenia/CiA401_IO_Node3.bin");

/// Configuration memory in RAM (erased: 0xFF).
#[derive(Debug, Clone)]
struct RamFiles(Vec<u8>);

impl RamFiles {
    fn new() -> Self {
        RamFiles(vec![0xFF; ConfigSlots::<RamFiles>::CAPACITY])
    }
}

impl ReadStorage for RamFiles {
    type Error = ();
    fn read(&mut self, offset: u32, out: &mut [u8]) -> Result<(), ()> {
        out.copy_from_slice(self.0.get(offset as usize..offset as usize + out.len()).ok_or(())?);
        Ok(())
    }
    fn capacity(&self) -> usize {
        self.0.len()
    }
}

impl Storage for RamFiles {
    fn write(&mut self, offset: u32, data: &[u8]) -> Result<(), ()> {
        self.0.get_mut(offset as usize..offset as usize + data.len()).ok_or(())?.copy_from_slice(data);
        Ok(())
    }
}

impl ConfigMemory for RamFiles {
    fn mapped(&self) -> &[u8] {
        &self.0
    }
    fn erase(&mut self, offset: u32, len: u32) -> Result<(), ()> {
        self.0.get_mut(offset as usize..(offset + len) as usize).ok_or(())?.fill(0xFF);
        Ok(())
    }
}

fn own_export() -> &'static [u8] {
    static FILE: OnceLock<Vec<u8>> = OnceLock::new();
    FILE.get_or_init(|| {
        let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../spec/canopenia.yaml")).unwrap();
        let device = coforge_spec::load_str("canopenia.yaml", &text).into_device().unwrap();
        let func = coforge_beds::layout::func::MANAGER | coforge_beds::layout::func::AUTOSTART;
        let settings = coforge_spec::beds::Settings { node_id: 5, bitrate_kbit: 250, func, ident: "proptest".into() };
        coforge_spec::beds::export(&device, None, settings).unwrap()
    })
}

/// `file` downloaded in 7-byte segments into the configuration memory `files` in bootloader
/// mode: the download's result and the memory afterwards.
fn download(files: RamFiles, file: &[u8]) -> (Result<(), u32>, RamFiles) {
    let mut program = Program::new(files, canopenia::od::entries(canopenia::Mode::Default));
    program.entered(true);
    let mut result = Ok(());
    let chunks: Vec<&[u8]> = file.chunks(7).collect();
    for (i, chunk) in chunks.iter().enumerate() {
        if let Err(abort) = program.write_part(i * 7, chunk, i + 1 == chunks.len()) {
            result = Err(abort.code());
            break;
        }
    }
    let memory = program.lend().map(|s| s.memory().clone()).unwrap();
    (result, memory)
}

/// The coprocessor started on `files`: its node-ID, and the values its file had refused.
fn start(files: RamFiles) -> (u8, u32) {
    let mut ia = Canopenia::with_configuration(2, NoStore, files);
    ia.start(0);
    for t in 0..50 {
        while ia.poll(t * 1000).is_some() {}
    }
    (ia.node().node_id(), ia.config_write_errors)
}

/// A file with `changes` (position, byte), cut to `keep` bytes, and its CRC made right again.
fn mutate(base: &[u8], changes: &[(usize, u8)], keep: usize, fix_crc: bool) -> Vec<u8> {
    let mut f = base.to_vec();
    for &(at, byte) in changes {
        let len = f.len();
        f[at % len] = byte;
    }
    f.truncate(keep.clamp(2, f.len()));
    if fix_crc {
        let n = f.len() - 2;
        let crc = coforge_beds::layout::crc(&f[..n]);
        f[n..].copy_from_slice(&crc.to_le_bytes());
    }
    f
}

#[test]
fn the_vendors_file_and_coforges_own_export_load_with_every_value_taken() {
    for (file, node) in [(VENDOR_401, 3), (own_export(), 5)] {
        let (result, files) = download(RamFiles::new(), file);
        assert_eq!(result, Ok(()));
        assert_eq!(start(files), (node, 0), "node-ID from the file, no value refused");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn any_file_is_refused_or_runs_and_a_refused_one_changes_nothing(
        own in any::<bool>(),
        changes in prop::collection::vec((any::<usize>(), any::<u8>()), 1..6),
        keep in any::<usize>(),
        cut in prop::bool::weighted(0.2),
        fix_crc in prop::bool::weighted(0.8),
    ) {
        let base = if own { own_export() } else { VENDOR_401 };
        let file = mutate(base, &changes, if cut { keep } else { usize::MAX }, fix_crc);
        // The vendor's file is active; then the mutated one is downloaded.
        let (first, files) = download(RamFiles::new(), VENDOR_401);
        prop_assert_eq!(first, Ok(()));
        let (result, files) = download(files, &file);
        let (node, _refused_values) = start(files);
        match result {
            // The previous file still runs: node 3.
            Err(code) => {
                prop_assert!(code >> 24 == 0x06 || code >> 24 == 0x08, "an SDO abort code: {code:08X}");
                prop_assert_eq!(node, 3);
            }
            // The new one runs with a node-ID a file may give.
            Ok(()) => prop_assert!((1..=127).contains(&node)),
        }
    }
}
