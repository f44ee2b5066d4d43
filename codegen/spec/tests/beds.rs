//! `coforge beds` against the vendor's own tool: its two EDS files, exported by us, give its
//! two binary files back, compared field by field and then byte for byte. And every spec
//! exports to a file the shared reader accepts, equal to the export of its own EDS.
#![allow(clippy::unwrap_used)]

use coforge_beds::{BinaryEds, Table};
use coforge_spec::beds::{self, Conventions, Settings, eds_import};

fn vendor(name: &str) -> Vec<u8> {
    let path = format!("{}/../../tests/vendor-data/canopenia/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The settings the vendor's tool was given: node-ID, bit rate and FUNC are its options, and
/// the date in the identification string is the time of its run, which no EDS field holds.
fn vendor_settings(eds: &str, node_id: u8, stamp: &str) -> Settings {
    Settings { node_id, bitrate_kbit: 125, func: coforge_beds::layout::func::AUTOSTART, ident: eds_import::vendor_ident(eds, Some(stamp)) }
}

/// Every field of two files, named, so a difference says where it is.
fn assert_same_fields(ours: &BinaryEds, theirs: &BinaryEds) {
    assert_eq!(ours.header(), theirs.header(), "header");
    assert_eq!(ours.sdo_replies().collect::<Vec<_>>(), theirs.sdo_replies().collect::<Vec<_>>(), "SDO replies");
    assert_eq!(ours.od_entries().collect::<Vec<_>>(), theirs.od_entries().collect::<Vec<_>>(), "OD entries");
    assert_eq!(ours.generic_entries().collect::<Vec<_>>(), theirs.generic_entries().collect::<Vec<_>>(), "generic entries");
    for table in [Table::Defaults, Table::Maximums, Table::Minimums] {
        assert_eq!(ours.image(table), theirs.image(table), "{}", table.name());
    }
    for table in [Table::Rpdos, Table::Tpdos] {
        assert_eq!(ours.pdos(table).collect::<Vec<_>>(), theirs.pdos(table).collect::<Vec<_>>(), "{}", table.name());
    }
    for table in Table::ALL {
        assert_eq!(ours.range(table), theirs.range(table), "where the {} is", table.name());
    }
}

fn reproduces(base: &str, node_id: u8, stamp: &str) {
    let eds = String::from_utf8(vendor(&format!("{base}.eds"))).unwrap();
    let theirs_bytes = vendor(&format!("{base}.bin"));
    let ours_bytes = beds::export_eds(&eds, vendor_settings(&eds, node_id, stamp), &Conventions::canopenia()).unwrap();
    let ours = BinaryEds::parse(&ours_bytes).unwrap();
    let theirs = BinaryEds::parse(&theirs_bytes).unwrap();
    assert_same_fields(&ours, &theirs);
    assert_eq!(ours_bytes, theirs_bytes, "{base}: every field agrees, so only padding or the trailer can differ");
}

#[test]
fn the_cia401_io_example_is_reproduced_byte_for_byte() {
    reproduces("CiA401_IO_Node3", 3, "02-11-2015 12:43PM");
}

#[test]
fn the_cia402_stepper_example_is_reproduced_byte_for_byte() {
    reproduces("CiA402_Stepper_Node8", 8, "04-08-2005 08:29AM");
}

#[test]
fn without_the_vendor_conventions_only_their_objects_differ() {
    // 5FF5h takes process-image space like any other object, and the chip ID (a DOMAIN with
    // no default) has no size, so it is left to the firmware: the rest is still placed.
    let eds = String::from_utf8(vendor("CiA401_IO_Node3.eds")).unwrap();
    let bytes = beds::export_eds(&eds, vendor_settings(&eds, 3, "x"), &Conventions::default()).unwrap();
    let file = BinaryEds::parse(&bytes).unwrap();
    assert!(file.generic_entries().all(|e| (e.index, e.sub) != (0x5F00, 5)));
    assert!(file.od_entries().filter(|e| e.index == 0x5FF5).all(|e| e.offset > 0));
    let theirs = vendor("CiA401_IO_Node3.bin");
    let theirs = BinaryEds::parse(&theirs).unwrap();
    let mapped = |f: &BinaryEds| f.od_entries().take(44).collect::<Vec<_>>();
    assert_eq!(mapped(&file), mapped(&theirs), "the mapped entries come first and do not move");
}

#[test]
fn the_vendor_ident_names_the_file_its_stamp_and_who_modified_it() {
    let eds = String::from_utf8(vendor("CiA402_Stepper_Node8.eds")).unwrap();
    // ModifiedBy, not CreatedBy: the vendor's file carries ModifiedBy's misspelling.
    assert_eq!(eds_import::vendor_ident(&eds, Some("04-08-2005 08:29AM")), "'CiA402_Stepper_Node8' 04-08-2005 08:29AM by EScademy");
    assert_eq!(eds_import::vendor_ident(&eds, None), "'CiA402_Stepper_Node8' 04-29-2019 08:53AM by EScademy");
}

fn specs() -> Vec<coforge_spec::Device> {
    let dir = format!("{}/../../spec", env!("CARGO_MANIFEST_DIR"));
    ["co401memory1", "co401gw1", "cr3101", "canopenia"]
        .iter()
        .map(|name| coforge_spec::load_file(format!("{dir}/{name}.yaml").as_ref()).device().cloned().unwrap())
        .collect()
}

fn our_settings(node_id: u8) -> Settings {
    Settings { node_id, bitrate_kbit: 250, func: 0, ident: "coforge test".into() }
}

#[test]
fn every_spec_and_mode_exports_a_file_the_reader_accepts_and_its_own_eds_gives_the_same() {
    for d in specs() {
        for mode in d.mode_names() {
            let what = format!("{} {mode:?}", d.identity.name);
            let bytes = beds::export(&d, mode, our_settings(5)).unwrap_or_else(|e| panic!("{what}: {e}"));
            let file = BinaryEds::parse(&bytes).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!((file.header().node_id, file.header().bitrate_kbit), (5, 250), "{what}");
            // 1000h (const in every spec) answers with the device type.
            let in_mode = |set| coforge_spec::model::in_mode(set, mode);
            let device_type = d
                .objects
                .iter()
                .filter(|o| o.index == 0x1000 && in_mode(&o.modes))
                .flat_map(|o| o.entries.iter().filter(|e| in_mode(&e.modes)))
                .find_map(|e| e.default.as_ref()?.int_for(5));
            let reply = file.sdo_replies().find(|r| (r.index, r.sub) == (0x1000, 0));
            let in_image = file.od_entries().find(|e| (e.index, e.sub) == (0x1000, 0)).map(|e| file.image_value(Table::Defaults, e.offset, 4).to_vec());
            let stored = reply.map(|r| r.value().to_vec()).or(in_image).unwrap_or_else(|| panic!("{what}: no 1000h"));
            assert_eq!(u32::from_le_bytes(stored.try_into().unwrap()), device_type.unwrap() as u32, "{what}: 1000h");
            // The TPDO records carry the spec's default PDOs, COB-IDs resolved for node 5.
            let tpdos = d.pdo.pdos.iter().filter(|p| p.dir == coforge_spec::model::PdoDir::Tx && coforge_spec::model::in_mode(&p.modes, mode)).count();
            assert_eq!(usize::from(file.header().tpdos), tpdos, "{what}: TPDOs");
            // The same dictionary through the EDS coforge writes for it: the same file.
            let eds = coforge_spec::eds::export(&d, mode).unwrap();
            let via_eds = beds::export_eds(&eds, our_settings(5), &Conventions::default()).unwrap();
            // An EDS cannot say the length of a string or domain, only its default: where the spec
            // declares another, that entry's size (and the offsets after it) differ, or, with no
            // default at all, the entry is left to the firmware. Nothing else may differ.
            let lengths_only_in_spec: Vec<(u16, u8)> = d
                .objects
                .iter()
                .flat_map(|o| o.entries.iter().map(move |e| (o.index, e)))
                .filter(|(_, e)| {
                    let text = match &e.default {
                        Some(coforge_spec::model::Value::Str(s)) => s.len(),
                        _ => 0,
                    };
                    (e.data_type.is_string() || e.data_type == coforge_spec::types::DataType::Domain) && e.length.is_some_and(|l| l as usize != text)
                })
                .map(|(index, e)| (index, e.sub))
                .collect();
            let via = BinaryEds::parse(&via_eds).unwrap();
            if !lengths_only_in_spec.is_empty() {
                assert_eq!(via.sdo_replies().collect::<Vec<_>>(), file.sdo_replies().collect::<Vec<_>>(), "{what}");
                let keys = |f: &BinaryEds| {
                    let od = f.od_entries().map(|e| (e.index, e.sub, e.dsat));
                    od.filter(|(i, s, _)| !lengths_only_in_spec.contains(&(*i, *s))).collect::<Vec<_>>()
                };
                assert_eq!(keys(&via), keys(&file), "{what}");
            } else {
                assert_same_fields(&via, &file);
                assert_eq!(via_eds, bytes, "{what}");
            }
        }
    }
}
