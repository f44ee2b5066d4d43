//! Every default of every mode of every spec reads back from the generated dictionary as the
//! spec says (`$NODEID` resolved), whether the dictionary was built in that mode or switched
//! to it at run time (`set_mode`, as CO401GW1's enable command does).

use coforge_spec::model::{Device, Entry, Value, in_mode};
use coforge_spec::types::Storage;
use coforge_stack::od::{NoAppObjects, NodeDictionary, Side};
use std::path::PathBuf;

const NODE_ID: u8 = 0x22;

fn spec(name: &str) -> Device {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../spec").join(name);
    coforge_spec::load_file(&path).into_device().unwrap_or_else(|| panic!("{name} loads"))
}

/// The bytes a read of `e` must give in its spec default.
fn expected(e: &Entry) -> Vec<u8> {
    let size = e.data_type.bits().map(|b| b.div_ceil(8) as usize);
    match (&e.default, size) {
        (Some(Value::Str(s)), _) => s.as_bytes().to_vec(),
        (Some(Value::Real(x)), Some(4)) => (*x as f32).to_le_bytes().to_vec(),
        (Some(Value::Real(x)), Some(_)) => x.to_le_bytes().to_vec(),
        (Some(v @ Value::Int(_)), Some(n)) if e.data_type.is_real() => {
            let x = v.int_for(NODE_ID).expect("evaluates") as f64;
            if n == 4 { (x as f32).to_le_bytes().to_vec() } else { x.to_le_bytes().to_vec() }
        }
        (Some(v @ Value::Int(_)), Some(n)) => v.int_for(NODE_ID).expect("evaluates").to_le_bytes()[..n].to_vec(),
        (None, Some(n)) => vec![0; n],
        (_, None) => Vec::new(),
    }
}

/// Checks every stored entry of every mode; returns how many values were compared.
fn check<D: NodeDictionary<App = NoAppObjects>>(file: &str) -> usize {
    let d = spec(file);
    let mut compared = 0;
    for &mode in D::MODES {
        let name = D::mode_name(mode);
        let spec_mode = if d.modes.is_empty() { None } else { Some(name) };
        let built = D::new(mode, NODE_ID, NoAppObjects);
        // Every other mode switched to this one at run time.
        let mut dictionaries = vec![("built", built)];
        for &from in D::MODES.iter().filter(|&&m| m != mode) {
            let mut switched = D::new(from, NODE_ID, NoAppObjects);
            switched.set_mode(mode, NODE_ID);
            assert_eq!(switched.mode(), mode);
            dictionaries.push((D::mode_name(from), switched));
        }
        for (how, od) in &mut dictionaries {
            for o in d.objects.iter().filter(|o| in_mode(&o.modes, spec_mode)) {
                for e in o.entries.iter().filter(|e| in_mode(&e.modes, spec_mode) && e.storage != Storage::App) {
                    let mut buf = [0_u8; 256];
                    let got = od.read(o.index, e.sub, 0, &mut buf, Side::Device).map(|n| buf[..n.copied].to_vec());
                    assert_eq!(got, Ok(expected(e)), "{file} mode {name} ({how}): {:04X}.{} {}", o.index, e.sub, e.name);
                    compared += 1;
                }
            }
        }
    }
    compared
}

#[test]
fn co401gw1_defaults_in_every_mode() {
    // About 1,970 values: the process image views (6000h, 6100h, 6120h, 6200h, 6300h,
    // 6320h) belong to the chip's app, whose sub 0 per mode the device tests check.
    let n = check::<co401gw1::Od<NoAppObjects>>("co401gw1.yaml");
    assert!(n > 1900, "{n}");
}

#[test]
fn co401gw1_mode_dependent_defaults_are_the_datasheets() {
    use co401gw1::{Mode, Od, index};
    let read = |od: &mut Od<NoAppObjects>, i, s| coforge_stack::node::read_u32(od, i, s);
    let mut mixed = Od::new(Mode::Mixed, 5, NoAppObjects);
    assert_eq!(read(&mut mixed, index::POLARITY_INPUT_8_BIT, 0), Some(8), "6002h sub 0: 8 digital input bytes in mixed mode");
    let mut alt = Od::new(Mode::Digital, 5, NoAppObjects);
    assert_eq!(read(&mut alt, 0x1404, 1), Some(0x8000_0000), "RPDO5 off in digital mode");
    alt.set_mode(Mode::DigitalAlt, 5);
    assert_eq!(read(&mut alt, 0x1404, 1), Some(0x305), "RPDO5 at 300h + node-ID in digital_alt");
    assert_eq!(read(&mut alt, 0x1804, 1), Some(0x285), "TPDO5 at 280h + node-ID in digital_alt");
    assert_eq!(read(&mut alt, index::POLARITY_INPUT_8_BIT, 0), Some(16));
}

#[test]
fn cr3101_canopenia_and_co401memory1_defaults_in_every_mode() {
    assert!(check::<cr3101::Od<NoAppObjects>>("cr3101.yaml") > 500);
    assert!(check::<canopenia::Od<NoAppObjects>>("canopenia.yaml") > 200);
    assert!(check::<co401memory1::Od<NoAppObjects>>("co401memory1.yaml") > 100);
}
