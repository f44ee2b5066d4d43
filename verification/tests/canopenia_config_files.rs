//! CANopenIA's configuration loading under arbitrary files (`coforge_verification::
//! canopenia_files`): the vendor's CiA 401 file and coforge's own export with random bytes
//! changed and cut short, most with their CRC made right again so that the checks behind it
//! run too; and both files unchanged load with every value taken.

use coforge_verification::canopenia_files::{Files, VENDOR_401, download, prop_config_file, start};
use proptest::prelude::*;
use std::sync::OnceLock;

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

#[test]
fn the_vendors_file_and_coforges_own_export_load_with_every_value_taken() {
    for (file, node) in [(VENDOR_401, 3), (own_export(), 5)] {
        let (result, files) = download(Files::default(), file);
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
        let mut file = if own { own_export() } else { VENDOR_401 }.to_vec();
        for (at, byte) in changes {
            let len = file.len();
            file[at % len] = byte;
        }
        if cut {
            file.truncate(keep % file.len());
        }
        let mut input = vec![u8::from(fix_crc)];
        input.extend(file);
        prop_config_file(&input);
    }
}
