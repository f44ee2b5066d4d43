#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! The reader against the vendor's own files (copies of `../shared/vendor-data/canopenia/`,
//! kept byte for byte in `tests/vendor-data/`), and against every kind of damage.

use coforge_beds::layout::{self, func};
use coforge_beds::{BinaryEds, Dsat, Error, Table};
use proptest::prelude::*;

fn vendor(name: &str) -> Vec<u8> {
    let path = format!("{}/../../tests/vendor-data/canopenia/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

const IO: &str = "CiA401_IO_Node3.bin";
const STEPPER: &str = "CiA402_Stepper_Node8.bin";

#[test]
fn the_vendor_files_are_valid_and_read_as_the_fact_sheet_lists_them() {
    let io = vendor(IO);
    let eds = BinaryEds::parse(&io).unwrap();
    let h = eds.header();
    assert_eq!((io.len(), h.node_id, h.bitrate_kbit, h.func, h.rpdos, h.tpdos), (2486, 3, 125, func::AUTOSTART | func::LIMIT_TABLES, 4, 4));
    assert!(h.ident.starts_with(b"'CiA401_IO_Node3'"));
    let st = vendor(STEPPER);
    let eds8 = BinaryEds::parse(&st).unwrap();
    let h8 = eds8.header();
    assert_eq!((st.len(), h8.node_id, h8.bitrate_kbit, h8.func, h8.rpdos, h8.tpdos), (2442, 8, 125, 0x12, 6, 2));

    // 1000h of the I/O node: device type 0x000F0191 (CiA 401, digital in and out, analogue).
    let r1000 = eds.sdo_replies().find(|r| r.index == 0x1000).unwrap();
    assert_eq!((r1000.command, r1000.value()), (0x43, &0x000F_0191_u32.to_le_bytes()[..]));
    // 6200h.1 (write outputs 1..8) is in the process image, writable and RPDO-mappable.
    let out1 = eds.od_entries().find(|e| (e.index, e.sub) == (0x6200, 1)).unwrap();
    assert_eq!(out1.dsat, Dsat::new(1, Dsat::READ | Dsat::WRITE | Dsat::RPDO));
    // 1008h (device name) is a generic entry, its default the string.
    let name = eds.generic_entries().find(|e| e.index == 0x1008).unwrap();
    assert_eq!(eds.image_value(Table::Defaults, name.offset, name.size), b"CANopenIA CiA401 Demo");
    // TPDO2: COB-ID 0x40000283 (no RTR), event timer 1000 ms.
    let t2 = eds.pdos(Table::Tpdos).nth(1).unwrap();
    assert_eq!((t2.cob_id, t2.event_time, t2.length), (0x4000_0283, 1000, 8));
}

fn with_crc(mut body: Vec<u8>) -> Vec<u8> {
    let crc = layout::crc(&body);
    body.extend_from_slice(&crc.to_le_bytes());
    body
}

fn body(file: &[u8]) -> Vec<u8> {
    file[..file.len() - 2].to_vec()
}

#[test]
fn damage_is_named() {
    let io = vendor(IO);
    assert_eq!(BinaryEds::parse(&io[..100]).unwrap_err(), Error::TooShort { len: 100 });
    let mut flipped = io.clone();
    flipped[500] ^= 1;
    assert!(matches!(BinaryEds::parse(&flipped), Err(Error::Crc { .. })));
    let mut b = body(&io);
    b[4] = b'X';
    assert_eq!(BinaryEds::parse(&with_crc(b)).unwrap_err(), Error::Magic);
    let mut b = body(&io);
    b[0] = 3;
    assert_eq!(BinaryEds::parse(&with_crc(b)).unwrap_err(), Error::Version { major: 3, minor: 0 });
    let mut b = body(&io);
    b[11] = 0x80;
    assert!(matches!(BinaryEds::parse(&with_crc(b)), Err(Error::ReservedFunc { .. })));
    // A table offset past the end of the file.
    let mut b = body(&io);
    b[layout::OFFSETS_AT + 4..layout::OFFSETS_AT + 8].copy_from_slice(&9999_u32.to_le_bytes());
    assert_eq!(BinaryEds::parse(&with_crc(b)).unwrap_err(), Error::TableOutOfFile { table: Table::OdEntries, offset: 9999 });
    // The header counts one TPDO more than the table holds.
    let mut b = body(&io);
    b[layout::header::TPDOS] = 5;
    assert_eq!(BinaryEds::parse(&with_crc(b)).unwrap_err(), Error::PdoCount { table: Table::Tpdos, header: 5, records: 4 });
    // A process image too small for its entries.
    let mut b = body(&io);
    b[layout::header::IMAGE_SIZE..layout::header::IMAGE_SIZE + 4].copy_from_slice(&100_u32.to_le_bytes());
    assert!(matches!(BinaryEds::parse(&with_crc(b)), Err(Error::BadEntry { .. })));
    // An SDO reply whose command byte is a download response.
    let mut b = body(&io);
    let first_reply = u32::from_le_bytes(b[layout::OFFSETS_AT..layout::OFFSETS_AT + 4].try_into().unwrap()) as usize;
    b[first_reply] = 0x60;
    assert_eq!(BinaryEds::parse(&with_crc(b)).unwrap_err(), Error::BadReply { index: 0x0005, sub: 0, command: 0x60 });
    // Every error explains itself.
    assert!(Error::PdoCount { table: Table::Tpdos, header: 5, records: 4 }.to_string().contains("TPDO configuration"));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    /// Arbitrary bytes with a correct CRC (the hard case: everything past the CRC check).
    #[test]
    fn any_bytes_are_read_or_refused_without_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let file = with_crc(bytes);
        if let Ok(eds) = BinaryEds::parse(&file) {
            // What parsed is inside the file and the image.
            let image = eds.header().image_size;
            prop_assert!(eds.od_entries().all(|e| u32::from(e.offset) + u32::from(e.size()) <= image));
            prop_assert!(eds.sdo_replies().all(|r| r.size().is_some()));
        }
    }

    /// The vendor file with a few bytes changed and the CRC fixed up: never a panic, and a
    /// change in the table offsets or the header either still reads or is refused.
    #[test]
    fn a_damaged_vendor_file_never_panics(changes in proptest::collection::vec((0..2484_usize, any::<u8>()), 1..6)) {
        let mut b = body(&vendor(IO));
        for (at, v) in changes {
            b[at] = v;
        }
        let file = with_crc(b);
        if let Ok(eds) = BinaryEds::parse(&file) {
            let image = eds.image(Table::Defaults);
            prop_assert_eq!(image.len() as u32, eds.header().image_size);
            prop_assert!(eds.generic_entries().all(|e| eds.image_value(Table::Defaults, e.offset, e.size).len() == usize::from(e.size)));
        }
    }
}
