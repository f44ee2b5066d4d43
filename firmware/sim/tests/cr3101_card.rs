#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! CR3101's memory card as a PC reads it: files laid out and records written through the
//! firmware's card layer (`cr3101::card`, embedded-sdmmc) on an image the simulator formats,
//! then read back with mtools and checked with `fsck.fat -n`, tools we did not write.

use coforge_sim::card::CardImage;
use cr3101::card::files::{Card, CardError};
use cr3101::card::record::Record;
use cr3101::card::sample::{layout, record};
use embedded_sdmmc::{TimeSource, Timestamp};
use std::path::Path;

mod card_tools;
use card_tools::{MIB, copy_out, fsck_clean, image, mtools};

/// The clock the FAT directory entries take their times from.
struct Clock;

impl TimeSource for Clock {
    fn get_timestamp(&self) -> Timestamp {
        Timestamp { year_since_1970: 56, zero_indexed_month: 11, zero_indexed_day: 2, hours: 6, minutes: 30, seconds: 0 }
    }
}

fn mount(path: &Path) -> Card<CardImage, Clock> {
    Card::mount(CardImage::open(path).unwrap(), Clock).map_err(|(e, _)| e).unwrap()
}

#[test]
fn records_written_in_place_read_back_with_mtools_and_the_card_stays_clean() {
    let path = image("records");
    let len = layout().len();
    assert_eq!(len, 9 + 2 + 4 + 1);
    // A PC has put a file of its own on the card; it must survive.
    let foreign = path.with_file_name("NOTES.TXT");
    std::fs::write(&foreign, b"not the device's").unwrap();
    mtools("mcopy", &path, &[foreign.to_str().unwrap(), "::NOTES.TXT"]);

    let mut card = mount(&path);
    card.lay_out(0, "OIL_TEMP.DAT", (len * 100) as u32, false).unwrap();
    card.lay_out(2, "PRESS.DAT", 4096, false).unwrap();
    let mut expected = vec![0_u8; len * 100];
    for n in 0..100_u32 {
        let r = record(n);
        card.write_at(0, n * len as u32, r.as_bytes()).unwrap();
        expected[n as usize * len..(n as usize + 1) * len].copy_from_slice(r.as_bytes());
    }
    // Nothing outside a file, and a record read back as written.
    assert_eq!(card.write_at(0, (len * 100 - 1) as u32, &[0, 0]), Err(CardError::Range));
    assert_eq!(card.write_at(1, 0, &[0]), Err(CardError::Range), "file 2 is not laid out");
    let mut back = vec![0_u8; len];
    card.read_at(0, 42 * len as u32, &mut back).unwrap();
    assert_eq!(Record::from_bytes(&layout(), &back), Some(record(42)));
    let _ = card.unmount();

    let listing = String::from_utf8(mtools("mdir", &path, &["-b", "::"]).stdout).unwrap();
    for name in ["OIL_TEMP.DAT", "PRESS.DAT", "NOTES.TXT"] {
        assert!(listing.contains(name), "{name} in {listing}");
    }
    assert_eq!(copy_out(&path, "OIL_TEMP.DAT"), expected, "every record byte for byte");
    assert_eq!(copy_out(&path, "PRESS.DAT"), vec![0; 4096], "pre-allocated with zeros");
    assert_eq!(copy_out(&path, "NOTES.TXT"), b"not the device's");
    assert!(fsck_clean(&path), "fsck.fat -n finds the card clean");
}

#[test]
fn laying_out_again_keeps_a_file_of_the_same_size_and_remakes_a_smaller_one() {
    let path = image("relayout");
    let mut card = mount(&path);
    card.lay_out(0, "A.DAT", 3000, false).unwrap();
    card.write_at(0, 2990, b"0123456789").unwrap();
    let _ = card.unmount();

    let mut card = mount(&path);
    card.lay_out(0, "A.DAT", 3000, false).unwrap();
    let mut tail = [0_u8; 10];
    card.read_at(0, 2990, &mut tail).unwrap();
    assert_eq!(&tail, b"0123456789", "the same size: kept as it is");
    card.lay_out(0, "A.DAT", 5000, false).unwrap();
    card.read_at(0, 2990, &mut tail).unwrap();
    assert_eq!(&tail, b"0123456789", "grown: kept, zeros after it");
    card.lay_out(0, "A.DAT", 1000, false).unwrap();
    assert_eq!(card.size(0), Some(1000));
    let mut head = [0_u8; 10];
    card.read_at(0, 0, &mut head).unwrap();
    assert_eq!(head, [0; 10], "made again: zeros");
    card.lay_out(0, "A.DAT", 0, false).unwrap();
    assert_eq!(card.size(0), None);
    assert_eq!(card.lay_out(1, "BAD NAME.DATA", 10, false), Err(CardError::Name));
    let _ = card.unmount();
    assert_eq!(copy_out(&path, "A.DAT").len(), 1000, "size 0: not used, left as it was");
    assert!(fsck_clean(&path));
}

#[test]
fn a_full_card_refuses_the_file_that_does_not_fit_and_keeps_the_others() {
    let path = image("full");
    let mut card = mount(&path);
    card.lay_out(0, "BIG.DAT", 10 * MIB as u32, false).unwrap();
    assert_eq!(card.lay_out(1, "HUGE.DAT", 8 * MIB as u32, false), Err(CardError::Full));
    assert_eq!(card.size(1), None);
    card.write_at(0, 0, b"still here").unwrap();
    let _ = card.unmount();
    let listing = String::from_utf8(mtools("mdir", &path, &["-b", "::"]).stdout).unwrap();
    assert!(listing.contains("BIG.DAT"), "{listing}");
    assert!(copy_out(&path, "HUGE.DAT").len() < 8 << 20, "what fit is left, shorter");
    assert_eq!(&copy_out(&path, "BIG.DAT")[..10], b"still here");
    assert!(fsck_clean(&path));
}

#[test]
fn the_files_take_the_names_their_configuration_gives() {
    let path = image("names");
    let mut card = mount(&path);
    for n in 0..8 {
        let mut config = cr3101::logger::file_config::FileConfig::factory(n);
        if n == 7 {
            config.set_name(b"oil_temp").unwrap();
        }
        let mut name = [0_u8; 12];
        let len = config.file_name(&mut name);
        card.lay_out(n, std::str::from_utf8(&name[..len]).unwrap(), 512, false).unwrap();
    }
    let _ = card.unmount();
    let listing = String::from_utf8(mtools("mdir", &path, &["-b", "::"]).stdout).unwrap();
    for name in ["DATEI1.DAT", "DATEI7.DAT", "OIL_TEMP.DAT"] {
        assert!(listing.contains(name), "{name} in {listing}");
    }
    assert!(fsck_clean(&path));
}
