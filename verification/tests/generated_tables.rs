//! The tables `device!` generates say exactly what the specs say: every entry of every mode
//! is found with its type, access on both sides, mappability, storage and size; nothing else
//! is in the tables; the default PDOs match.

use coforge_spec::model::{Device, PdoDir, in_mode};
use coforge_spec::types::WriteWhen;
use coforge_stack::od::{Table, find};
use coforge_stack::pdo::PdoDefault;
use std::path::PathBuf;

fn spec(name: &str) -> Device {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../spec").join(name);
    coforge_spec::load_file(&path).into_device().unwrap_or_else(|| panic!("{name} loads"))
}

fn check(d: &Device, mode: Option<&str>, table: Table<'_>, rpdos: &[PdoDefault], tpdos: &[PdoDefault]) {
    let ctx = format!("{} {:?}", d.identity.name, mode);
    // Sorted, non-overlapping runs.
    let runs: Vec<_> = table.iter().collect();
    assert!(runs.windows(2).all(|w| (w[0].index, w[0].last_sub) < (w[1].index, w[1].sub)), "{ctx}: table order");
    let mut covered = 0_usize;
    for o in d.objects.iter().filter(|o| in_mode(&o.modes, mode)) {
        for e in o.entries.iter().filter(|e| in_mode(&e.modes, mode)) {
            let info = find(table, o.index, e.sub).unwrap_or_else(|a| panic!("{ctx}: {:04X}.{} missing ({a:?})", o.index, e.sub));
            let what = format!("{ctx}: {:04X}.{}", o.index, e.sub);
            assert_eq!(info.data_type(), e.data_type, "{what}");
            assert_eq!(info.access(), e.access, "{what}");
            assert_eq!(info.host_access(), e.host_access, "{what}");
            assert_eq!(info.host_write_before_can_enabled(), e.host_write_when == WriteWhen::BeforeCanEnabled, "{what}");
            assert_eq!(info.pdo_mappable(), e.pdo_mapping, "{what}");
            assert_eq!(info.storage(), e.storage, "{what}");
            if let Some(bits) = e.data_type.bits() {
                assert_eq!(u32::from(info.size), bits.div_ceil(8), "{what}");
            }
            covered += 1;
        }
    }
    assert!(table.iter().all(|r| r.copies() <= coforge_stack::pdo::mapping::MAX_COPIES), "{ctx}: copies fit the PDO mapping cache");
    let in_table: usize = table.iter().map(|r| (usize::from(r.last_sub - r.sub) + 1) * (usize::from(r.copies()) + 1)).sum();
    assert_eq!(in_table, covered, "{ctx}: the table holds exactly the spec's entries");
    for (dir, generated) in [(PdoDir::Rx, rpdos), (PdoDir::Tx, tpdos)] {
        let want: Vec<_> = d.pdo.pdos.iter().filter(|p| p.dir == dir && in_mode(&p.modes, mode)).collect();
        assert_eq!(generated.len(), want.len(), "{ctx}: {} count", dir.name());
        for (g, p) in generated.iter().zip(want) {
            assert_eq!(g.number, p.number);
            for node in [1_u8, 0x22, 127] {
                let spec_cob = p.cob_id.eval(&Default::default(), Some(i64::from(node))).unwrap_or(-1);
                assert_eq!(i64::from(g.cob_id.resolve(node)), spec_cob, "{ctx}: {}{} COB-ID for node {node}", dir.name(), p.number);
            }
            assert_eq!((g.transmission_type, g.inhibit_time, g.event_timer, g.sync_start), (p.transmission_type, p.inhibit_time, p.event_timer, p.sync_start));
            assert_eq!(g.mapping, p.map.iter().map(|m| m.encoded()).collect::<Vec<_>>().as_slice());
        }
    }
}

#[test]
fn co401memory1_tables_match_the_spec() {
    use co401memory1::{Mode, od, pdo};
    let d = spec("co401memory1.yaml");
    check(&d, None, od::entries(Mode::Default), pdo::rpdos(Mode::Default), pdo::tpdos(Mode::Default));
    assert_eq!((co401memory1::VENDOR_ID, co401memory1::PRODUCT_CODE), (d.identity.vendor_id, d.identity.product_code));
    // 8 KiB of memory objects cost two table rows per block.
    assert!(od::entries(Mode::Default).len() < 250, "{} rows", od::entries(Mode::Default).len());
}

#[test]
fn co401gw1_tables_match_the_spec_in_every_mode() {
    use co401gw1::{Mode, od, pdo};
    let d = spec("co401gw1.yaml");
    for mode in Mode::ALL {
        check(&d, Some(mode.name()), od::entries(mode), pdo::rpdos(mode), pdo::tpdos(mode));
    }
}

#[test]
fn cr3101_tables_match_the_spec_in_every_mode() {
    use cr3101::{Mode, od, pdo};
    let d = spec("cr3101.yaml");
    for mode in Mode::ALL {
        check(&d, Some(mode.name()), od::entries(mode), pdo::rpdos(mode), pdo::tpdos(mode));
    }
}

#[test]
fn canopenia_tables_match_the_spec() {
    use canopenia::{Mode, od, pdo};
    let d = spec("canopenia.yaml");
    check(&d, None, od::entries(Mode::Default), pdo::rpdos(Mode::Default), pdo::tpdos(Mode::Default));
}

/// The host-only name lookup: every spec emergency of every mode is found by its name, and
/// names nothing else.
#[test]
fn emergencies_are_found_by_their_spec_names() {
    macro_rules! check_names {
        ($krate:ident, $spec:literal) => {{
            use $krate::{Mode, emcy};
            let d = spec($spec);
            for mode in Mode::ALL {
                let spec_mode = (Mode::ALL.len() > 1).then(|| mode.name());
                let listed: Vec<_> = d.emergencies.iter().filter(|e| in_mode(&e.modes, spec_mode)).collect();
                assert_eq!(listed.len(), emcy::emergencies(mode).len(), "{} {mode:?}", $spec);
                for (e, generated) in listed.iter().zip(emcy::emergencies(mode)) {
                    let found = emcy::by_name(mode, &e.name).unwrap_or_else(|| panic!("{} {mode:?}: {} not found", $spec, e.name));
                    assert_eq!(found, *generated, "{} {mode:?}: {}", $spec, e.name);
                    assert_eq!((found.code, found.register), (e.code, e.error_register), "{}", e.name);
                    assert_eq!(emcy::name_of(mode, generated), Some(e.name.as_str()));
                }
                assert_eq!(emcy::by_name(mode, "no_such_emergency"), None);
            }
        }};
    }
    check_names!(co401memory1, "co401memory1.yaml");
    check_names!(co401gw1, "co401gw1.yaml");
    check_names!(cr3101, "cr3101.yaml");
    check_names!(canopenia, "canopenia.yaml");
}
