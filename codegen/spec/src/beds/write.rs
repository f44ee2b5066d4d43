//! Writes [`Tables`] out as a file: header, table offsets, each table at a multiple of 4
//! (0x00 padding) and ended by its all-0xFF sentinel, 4 bytes of 0x00 after the last table
//! (the vendor's tool writes them; readers ignore them), then the CRC.

use super::dictionary::Settings;
use super::layout::Tables;
use coforge_beds::layout::{self, func, header};
use coforge_beds::{GenericEntry, OdEntry, PdoRecord, SdoReply};

/// Bytes the vendor's tool leaves between the last table and the CRC.
const TRAILER: usize = 4;
const ALIGN: usize = 4;

fn put(file: &mut [u8], at: usize, bytes: &[u8]) {
    file[at..at + bytes.len()].copy_from_slice(bytes);
}

fn record_table<const N: usize>(records: impl Iterator<Item = [u8; N]>) -> Vec<u8> {
    let mut bytes: Vec<u8> = records.flatten().collect();
    bytes.extend([layout::SENTINEL; N]);
    bytes
}

/// The whole file. Maximum and minimum tables are always written (FUNC bit 4 set).
pub fn file(settings: &Settings, t: &Tables) -> Vec<u8> {
    let tables: [Vec<u8>; 8] = [
        record_table(t.replies.iter().map(SdoReply::encode)),
        record_table(t.od.iter().map(OdEntry::encode)),
        record_table(t.generic.iter().map(GenericEntry::encode)),
        t.defaults.clone(),
        t.maximums.clone(),
        t.minimums.clone(),
        record_table(t.rpdos.iter().map(PdoRecord::encode_rpdo)),
        record_table(t.tpdos.iter().map(PdoRecord::encode_tpdo)),
    ];
    let mut file = vec![0_u8; layout::TABLES_AT];
    for (n, table) in tables.iter().enumerate() {
        file.resize(file.len().next_multiple_of(ALIGN), 0);
        let offset = file.len() as u32;
        put(&mut file, layout::OFFSETS_AT + 4 * n, &offset.to_le_bytes());
        file.extend_from_slice(table);
    }
    file.extend([0; TRAILER]);
    put(&mut file, header::MAJOR, &layout::VERSION.0.to_le_bytes());
    put(&mut file, header::MINOR, &layout::VERSION.1.to_le_bytes());
    put(&mut file, header::MAGIC, &layout::MAGIC);
    put(&mut file, header::FUNC, &((settings.func & func::DEFINED) | func::LIMIT_TABLES).to_le_bytes());
    put(&mut file, header::BITRATE_KBIT, &settings.bitrate_kbit.to_le_bytes());
    file[header::NODE_ID] = settings.node_id;
    put(&mut file, header::RPDOS, &(t.rpdos.len() as u16).to_le_bytes());
    put(&mut file, header::TPDOS, &(t.tpdos.len() as u16).to_le_bytes());
    put(&mut file, header::IMAGE_SIZE, &(t.defaults.len() as u32).to_le_bytes());
    let ident: Vec<u8> = settings.ident.chars().map(|c| u8::try_from(u32::from(c)).unwrap_or(b'?')).take(header::IDENT_LEN).collect();
    put(&mut file, header::IDENT, &ident);
    let crc = layout::crc(&file);
    file.extend_from_slice(&crc.to_le_bytes());
    file
}
