//! The four transcribed datasheets: they check clean, are canonically formatted, and hold
//! the facts the firmware depends on. Golden EDS/docs output of the fixture device.

mod common;

use coforge_spec::model::{Device, Framing, NodeSettings, PdoDir};
use coforge_spec::types::{Access, DataType, HostAccess, Storage, WriteWhen};
use coforge_spec::{eds, fmt, load_str};
use common::{crate_dir, files, golden, repo_dir};

fn load(name: &str) -> Device {
    let path = repo_dir().join("spec").join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let loaded = load_str(name, &text);
    assert!(loaded.diagnostics.items.is_empty(), "{name}:\n{}", loaded.render_diagnostics());
    loaded.into_device().expect("loads")
}

#[test]
fn all_specs_check_clean_with_reasoned_errata() {
    let specs = files(&repo_dir().join("spec"), "yaml");
    let names: Vec<String> = specs.iter().filter_map(|p| p.file_name()?.to_str().map(String::from)).collect();
    assert_eq!(names, ["canopenia.yaml", "co401gw1.yaml", "co401memory1.yaml", "cr3101.yaml"]);
    for name in &names {
        let d = load(name);
        assert!(d.errata.len() >= 10, "{name}: only {} errata", d.errata.len());
        assert!(d.errata.iter().all(|e| e.reason.len() > 20), "{name}: every erratum gives a real reason");
        assert!(!d.emergencies.is_empty(), "{name}: emergencies transcribed");
        assert!(!d.pdo.pdos.is_empty(), "{name}: default PDOs transcribed");
    }
}

#[test]
fn specs_are_canonically_formatted_and_formatting_keeps_their_meaning() {
    let mut paths = files(&repo_dir().join("spec"), "yaml");
    paths.push(crate_dir().join("tests/fixtures/valid/minimal.yaml"));
    for path in paths {
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        let formatted = fmt::format(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(formatted == text, "{} is not canonical:\n{}", path.display(), fmt::first_difference(&text, &formatted));
        // Formatting a differently laid out copy restores the same data.
        let squashed: String = text.lines().map(|l| l.trim_end()).collect::<Vec<_>>().join("\n") + "\n";
        let a: serde_json::Value = serde_saphyr::from_str(&text).expect("parses");
        let b: serde_json::Value = serde_saphyr::from_str(&fmt::format(&squashed).expect("formats")).expect("parses");
        assert_eq!(a, b, "{}", path.display());
    }
}

#[test]
fn co401memory1_has_64_mirrored_blocks_and_its_protocol() {
    let d = load("co401memory1.yaml");
    let blocks: Vec<_> = d.objects.iter().filter(|o| (0x5000..=0x503F).contains(&o.index)).collect();
    assert_eq!(blocks.len(), 64);
    for b in &blocks {
        assert_eq!(b.entries.len(), 129, "{:04X}: sub 0 + 128 bytes", b.index);
        assert!(b.entries.iter().skip(1).all(|e| e.data_type == DataType::Unsigned8 && e.access == Access::Rw && e.storage == Storage::App));
    }
    let checksum = d.object(0x5C00, None).expect("5C00");
    assert_eq!(checksum.entries.iter().filter(|e| e.sub > 0 && e.data_type == DataType::Unsigned32).count(), 2);
    let serial = d.serial.as_ref().expect("serial protocol");
    assert!(matches!(serial.framing, Framing::NibbleLength { resync_pause_ms: 100 }));
    assert!(serial.commands.iter().all(|c| c.code <= 0xF));
    assert!(serial.commands.iter().any(|c| !c.examples.is_empty()));
}

#[test]
fn co401gw1_modes_and_side_dependent_access() {
    let d = load("co401gw1.yaml");
    let modes: Vec<&str> = d.modes.iter().map(|m| m.name.as_str()).collect();
    assert!(modes.contains(&"mixed") && modes.contains(&"digital"), "{modes:?}");
    for index in [0x2E00, 0x2E01] {
        let o = d.object(index, Some("mixed")).expect("2E00/2E01");
        for e in o.entries.iter().filter(|e| e.sub > 0) {
            assert!(!e.access.writable(), "{index:04X}.{} is read-only from CAN", e.sub);
            assert_eq!(e.host_access, HostAccess::Rw, "{index:04X}.{} is writable by the host", e.sub);
        }
    }
    let node_id = d.object(0x100B, Some("mixed")).and_then(|o| o.entry(0)).expect("100B");
    assert!(node_id.host_access.writable());
    assert_eq!(node_id.host_write_when, WriteWhen::BeforeCanEnabled);
    let device_type = d.object(0x1000, Some("mixed")).and_then(|o| o.entry(0)).expect("1000");
    assert!(!device_type.host_access.writable(), "below 0x3000 the host may not write");
    // The digital-only mode doubles the digital I/O bytes.
    let inputs = |m| d.object(0x6000, Some(m)).map(|o| o.entries.len());
    assert!(inputs("digital") > inputs("mixed"));
    assert!(matches!(
        d.serial.as_ref().map(|s| &s.framing),
        Some(Framing::LengthByte { inter_byte_timeout_ms: 10, resync_pause_ms: 50, extension_threshold: 0x80 })
    ));
    assert_eq!(node_id.access, Access::None, "100B is not reachable from CAN");
    for mode in ["mixed", "digital"] {
        let text = eds::export(&d, Some(mode)).expect("exports");
        assert!(!text.contains("[100B]") && !text.contains("[100E]"), "CAN-inaccessible objects stay out of the EDS");
    }
    assert!(eds::export(&d, None).is_err(), "a device with modes needs --mode");
}

#[test]
fn cr3101_files_records_and_redundant_pairs() {
    let d = load("cr3101.yaml");
    for f in 0..8_u16 {
        let base = 0x3000 + 0x100 * f;
        assert!(d.object(base, None).is_some(), "file {f} designation");
        for c in 0..8 {
            assert!(d.object(base + 0x10 + c, None).is_some(), "file {f} component {c}");
        }
        assert!(d.object(0x5000 + 0x100 * f, None).is_some(), "file {f} data record");
    }
    let mut pairs: Vec<(u16, u16)> = d.redundant_pairs.iter().map(|p| (p.primary, p.shadow)).collect();
    pairs.sort_unstable();
    assert_eq!(pairs, [(0x2002, 0x2003), (0x20F0, 0x20F1), (0x20F2, 0x20F3)]);
    assert!(d.pdo.pdos.iter().filter(|p| p.dir == PdoDir::Rx).count() >= 8);
    let selectors: Vec<_> = d.modes.iter().map(|m| m.object).collect();
    assert_eq!(selectors, [Some((0x20F5, 0, 0)), Some((0x20F5, 0, 1))], "PDO operating mode 20F5 selects the mode");
    for f in 0..8_u16 {
        let op_mode = d.object(0x3003 + 0x100 * f, None).and_then(|o| o.entry(1)).expect("3x03.1");
        assert_eq!(op_mode.values.as_deref(), Some(&[0x01, 0x02, 0x03, 0x10][..]));
    }
}

#[test]
fn canopenia_crc_is_xmodem_and_node_table_has_127_nodes() {
    let d = load("canopenia.yaml");
    let Some(Framing::StartLengthCrc { start_byte, crc, max_payload, .. }) = d.serial.as_ref().map(|s| &s.framing) else { panic!("start_length_crc framing") };
    assert_eq!(*start_byte, 0x11);
    assert_eq!((crc.width, crc.poly, crc.init, crc.reflect_in, crc.xor_out), (16, 0x1021, 0, false, 0));
    assert_eq!(crc.compute(b"123456789"), 0x31C3);
    assert!(crc.little_endian && crc.covers_length && crc.covers_payload && !crc.covers_start);
    assert!(*max_payload >= 28);
    let table = d.object(0x5F04, None).expect("5F04");
    let subs: Vec<u8> = table.entries.iter().map(|e| e.sub).filter(|&s| s > 0).collect();
    assert_eq!(subs, (1..=127).collect::<Vec<u8>>());
    let codes: Vec<u32> = d.serial.as_ref().map(|s| s.commands.iter().map(|c| c.code).collect()).unwrap_or_default();
    for letter in ['W', 'R', 'S', 'U', 'D'] {
        assert!(codes.contains(&u32::from(letter)), "command {letter}");
    }
    assert!(d.errata.iter().any(|e| e.datasheet.contains("x^16") || e.datasheet.contains("x16")), "CRC polynomial conflict recorded");
}

#[test]
fn node_settings_are_what_each_firmware_needs() {
    let cia301 = NodeSettings::default();
    assert_eq!(
        cia301,
        NodeSettings {
            restart_time_object: None,
            bootup_object: None,
            startup_object: None,
            rpdo_deadline_monitoring: true,
            combine_emcy_codes: false,
            auto_save: false,
            listed_emergencies_only: false,
            tpdo_on_write: true,
            remapping_object: None,
        }
    );
    let expected = [
        // frenzel+berg CAN restart time 2180h; CO40xx codes ORed; DS301 4.0 without RPDO deadlines (MEM-27).
        (
            "co401memory1.yaml",
            NodeSettings { restart_time_object: Some(0x2180), combine_emcy_codes: true, rpdo_deadline_monitoring: false, ..NodeSettings::default() },
        ),
        // CAN restart time 2180h, boot-up message switch 2110h; no RPDO deadlines (GW1-13); CO40xx
        // codes ORed; only the datasheet's emergencies (GW1-59); DS401 events (GW1-61); 2102h
        // gates remapping (GW1-60).
        (
            "co401gw1.yaml",
            NodeSettings {
                restart_time_object: Some(0x2180),
                bootup_object: Some(0x2110),
                rpdo_deadline_monitoring: false,
                combine_emcy_codes: true,
                listed_emergencies_only: true,
                tpdo_on_write: false,
                remapping_object: Some(0x2102),
                ..NodeSettings::default()
            },
        ),
        // 20F4h "CANopen StartUp mode"; all parameters are saved automatically.
        ("cr3101.yaml", NodeSettings { startup_object: Some(0x20F4), auto_save: true, ..NodeSettings::default() }),
        ("canopenia.yaml", NodeSettings::default()),
    ];
    for (name, want) in expected {
        let d = load(name);
        assert_eq!(d.node, want, "{name}");
        for (key, index) in d.node.objects() {
            let Some(index) = index else { continue };
            for mode in d.mode_names() {
                let e = d.object(index, mode).and_then(|o| o.entry(0)).unwrap_or_else(|| panic!("{name}: node.{key} {index:04X} in {mode:?}"));
                if key == "remapping_object" {
                    // The switch may be local (CO401GW1 2102h: read-only from CAN, the host sets it).
                    let settable = e.access.writable() || e.host_access.writable();
                    assert!(e.access.readable() && settable, "{name}: node.{key} {index:04X} is read over CAN and set by someone");
                } else {
                    assert!(e.access.readable() && e.access.writable(), "{name}: node.{key} {index:04X} is configurable over CAN");
                }
            }
        }
    }
    let gw1 = load("co401gw1.yaml");
    assert!(gw1.errata.iter().any(|e| e.id == "GW1-13" && e.choice.contains("node.rpdo_deadline_monitoring")));
    let mem = load("co401memory1.yaml");
    assert!(mem.errata.iter().any(|e| e.id == "MEM-27" && e.choice.contains("node.rpdo_deadline_monitoring")));
}

#[test]
fn fixture_eds_and_docs_match_golden_files() {
    let text = std::fs::read_to_string(crate_dir().join("tests/fixtures/valid/minimal.yaml")).unwrap_or_default();
    let d = load_str("minimal.yaml", &text).into_device().expect("loads");
    let mut failures = Vec::new();
    for mode in ["mixed", "digital"] {
        let out = eds::export(&d, Some(mode)).expect("exports");
        failures.extend(golden(&crate_dir().join(format!("tests/golden/minimal-{mode}.eds")), &out));
    }
    failures.extend(golden(&crate_dir().join("tests/golden/minimal.md"), &coforge_spec::docs::markdown(&d)));
    failures.extend(golden(&crate_dir().join("tests/golden/minimal-digital.json"), &eds::model_json(&d, Some("digital"), 5).expect("json")));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_fixture_node_section_is_read_whole() {
    let text = std::fs::read_to_string(crate_dir().join("tests/fixtures/valid/minimal.yaml")).unwrap_or_default();
    let d = load_str("minimal.yaml", &text).into_device().expect("loads");
    let want = NodeSettings {
        restart_time_object: Some(0x2000),
        rpdo_deadline_monitoring: false,
        listed_emergencies_only: true,
        tpdo_on_write: false,
        remapping_object: Some(0x2004),
        ..NodeSettings::default()
    };
    assert_eq!(d.node, want);
}
