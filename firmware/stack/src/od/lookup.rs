//! Finding an entry's run in a generated table, and copying a value out of it.

use super::{EntryInfo, ReadLen, SdoAbort};

/// Copies `value[offset..]` into `buf` (segmented and partial reads).
pub fn read_slice(value: &[u8], offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
    let rest = value.get(offset..).ok_or(SdoAbort::LengthTooHigh)?;
    let n = rest.len().min(buf.len());
    if let (Some(dst), Some(src)) = (buf.get_mut(..n), rest.get(..n)) {
        dst.copy_from_slice(src);
    }
    Ok(ReadLen { copied: n, total: value.len() })
}

/// Finds the description of `index`/`sub` in a table sorted by `(index, sub)` whose runs do
/// not overlap (the runs of repeated objects are listed once, under the first index):
/// `NoObject` if the index is absent, `NoSubIndex` if only the sub-index is.
pub fn find(entries: &[EntryInfo], index: u16, sub: u8) -> Result<&EntryInfo, SdoAbort> {
    find_run(entries, index, sub).and_then(|run| entries.get(run).ok_or(SdoAbort::NoObject))
}

/// Like [`find`], but the position of the run in the table (PDO mappings keep it).
pub fn find_run(entries: &[EntryInfo], index: u16, sub: u8) -> Result<usize, SdoAbort> {
    // The object: the last run listed at or before `index` must describe it.
    let listed = entries.partition_point(|e| e.index <= index);
    let last = listed.checked_sub(1).ok_or(SdoAbort::NoObject)?;
    let first = match entries.get(last) {
        Some(e) if e.covers_index(index) => {
            // The object's last run: most accesses end here (single-run objects, and the
            // subs of the last run), without the second search.
            if e.sub <= sub {
                return if e.covers(sub) { Ok(last) } else { Err(SdoAbort::NoSubIndex) };
            }
            e.index
        }
        _ => return Err(SdoAbort::NoObject),
    };
    // The sub-index: only the object's last run starting at or before `sub` can cover it. A
    // second binary search rather than a scan back over the object's runs: its steps depend
    // on the table's length alone, so Kani unrolls it a fixed number of times even for a
    // symbolic index.
    let run = entries.partition_point(|e| (e.index, e.sub) <= (first, sub)).checked_sub(1).ok_or(SdoAbort::NoSubIndex)?;
    match entries.get(run) {
        Some(e) if e.index == first && e.covers(sub) => Ok(run),
        _ => Err(SdoAbort::NoSubIndex),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coforge_types::{Access, DataType, HostAccess};

    const fn info(data_type: DataType, access: Access, host_access: HostAccess, size: u16) -> EntryInfo {
        super::super::entry::test_entry(data_type, access, host_access, size)
    }

    #[test]
    fn find_distinguishes_missing_objects_from_missing_subs() {
        let at = |index, sub, last_sub| EntryInfo { index, sub, last_sub, ..info(DataType::Unsigned8, Access::Ro, HostAccess::Ro, 1) };
        // 1000; 1018 subs 0, 1, 4; a memory block 5000 with sub 0 and the run 1..=128.
        let table = [at(0x1000, 0, 0), at(0x1018, 0, 0), at(0x1018, 1, 1), at(0x1018, 4, 4), at(0x5000, 0, 0), at(0x5000, 1, 128)];
        assert_eq!(find(&table, 0x1018, 4).map(|e| e.sub), Ok(4));
        assert_eq!(find(&table, 0x1018, 2), Err(SdoAbort::NoSubIndex));
        assert_eq!(find(&table, 0x1018, 9), Err(SdoAbort::NoSubIndex));
        assert_eq!(find(&table, 0x5000, 77).map(|e| (e.sub, e.last_sub)), Ok((1, 128)));
        assert_eq!(find(&table, 0x5000, 128).map(|e| e.sub), Ok(1));
        assert_eq!(find(&table, 0x5000, 129), Err(SdoAbort::NoSubIndex));
        assert_eq!(find(&table, 0x1001, 0), Err(SdoAbort::NoObject));
        assert_eq!(find(&table, 0x0FFF, 0), Err(SdoAbort::NoObject));
        assert_eq!(find(&table, 0x6000, 0), Err(SdoAbort::NoObject));
        let no_sub0 = [at(0x6000, 1, 8)];
        assert_eq!(find(&no_sub0, 0x6000, 0), Err(SdoAbort::NoSubIndex));
        // Every sub-index of every present index resolves as the table says.
        for index in [0x1000_u16, 0x1018, 0x5000] {
            for sub in 0..=255_u8 {
                let want = table.iter().find(|e| e.index == index && e.covers(sub));
                assert_eq!(find(&table, index, sub).ok(), want, "{index:04X}.{sub}");
            }
        }
    }

    #[test]
    fn repeated_objects_resolve_through_their_first_index() {
        let at = |index, sub, last_sub, copies| {
            let e = info(DataType::Unsigned8, Access::Ro, HostAccess::Ro, 1);
            EntryInfo { index, sub, last_sub, flags: e.flags.copies(copies), ..e }
        };
        // 5000..5003 alike (sub 0 and 1..=128), then 5C00 with subs 0..=2.
        let table = [at(0x1000, 0, 0, 0), at(0x5000, 0, 0, 3), at(0x5000, 1, 128, 3), at(0x5C00, 0, 2, 0)];
        for index in 0x5000..=0x5003 {
            assert_eq!(find_run(&table, index, 0), Ok(1), "{index:04X}.0");
            assert_eq!(find_run(&table, index, 1), Ok(2), "{index:04X}.1");
            assert_eq!(find_run(&table, index, 128), Ok(2), "{index:04X}.128");
            assert_eq!(find_run(&table, index, 129), Err(SdoAbort::NoSubIndex), "{index:04X}.129");
        }
        assert_eq!(find_run(&table, 0x5004, 0), Err(SdoAbort::NoObject));
        assert_eq!(find_run(&table, 0x4FFF, 0), Err(SdoAbort::NoObject));
        assert_eq!(find_run(&table, 0x5C00, 2), Ok(3));
        assert_eq!(find_run(&table, 0x5C00, 3), Err(SdoAbort::NoSubIndex));
        assert_eq!(find_run(&table, 0x5BFF, 0), Err(SdoAbort::NoObject));
        assert!(at(0x5000, 0, 0, 3).covers_index(0x5003) && !at(0x5000, 0, 0, 3).covers_index(0x5004));
        assert!(!at(0xFFFF, 0, 0, 0).covers_index(0xFFFE));
    }

    #[test]
    fn partial_reads_copy_what_fits() {
        let mut buf = [0_u8; 4];
        assert_eq!(read_slice(b"CO401Memory1", 0, &mut buf), Ok(ReadLen { copied: 4, total: 12 }));
        assert_eq!(&buf, b"CO40");
        assert_eq!(read_slice(b"CO401Memory1", 8, &mut buf), Ok(ReadLen { copied: 4, total: 12 }));
        assert_eq!(&buf, b"ory1");
        assert_eq!(read_slice(b"CO401Memory1", 12, &mut buf), Ok(ReadLen { copied: 0, total: 12 }));
        assert_eq!(read_slice(b"CO401Memory1", 13, &mut buf), Err(SdoAbort::LengthTooHigh));
    }
}
