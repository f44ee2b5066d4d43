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

/// The entry table of a dictionary in one mode: the runs (entry descriptions) of every mode
/// at once, and which of them this mode has. A device whose modes differ in a few objects
/// keeps each run once, not once per mode (CR3101's two modes share 209 of their 214 runs).
///
/// A run's *position* is its place in all the runs: what [`find_run`] gives, what a PDO
/// mapping keeps, what [`Table::get`] takes. The mode's runs are sorted by `(index, sub)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Table<'t> {
    runs: &'t [EntryInfo],
    /// This mode's runs as positions in `runs`, in order; `None`: all of them.
    pick: Option<&'t [u8]>,
}

impl<'t> Table<'t> {
    /// Every run, in order: a device with one mode, or one table per mode.
    pub const fn new(runs: &'t [EntryInfo]) -> Self {
        Table { runs, pick: None }
    }

    /// The runs of `pick`, in its order.
    pub const fn picked(runs: &'t [EntryInfo], pick: &'t [u8]) -> Self {
        Table { runs, pick: Some(pick) }
    }

    /// How many runs the mode has.
    pub fn len(&self) -> usize {
        self.pick.map_or(self.runs.len(), <[u8]>::len)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The run at `position` (see [`Table`]).
    pub fn get(&self, position: usize) -> Option<&'t EntryInfo> {
        self.runs.get(position)
    }

    /// The position of the mode's `n`th run.
    fn position(&self, n: usize) -> Option<usize> {
        match self.pick {
            None => (n < self.runs.len()).then_some(n),
            Some(pick) => pick.get(n).map(|&p| usize::from(p)),
        }
    }

    /// The mode's runs, in order.
    pub fn iter(self) -> impl Iterator<Item = &'t EntryInfo> {
        (0..self.len()).filter_map(move |n| self.position(n).and_then(|p| self.runs.get(p)))
    }

    /// How many of the mode's runs, from the first, `pred` holds for (it holds for a prefix):
    /// a binary search, as `slice::partition_point`.
    fn partition_point(&self, pred: impl Fn(&EntryInfo) -> bool) -> usize {
        let (mut low, mut high) = (0, self.len());
        while low < high {
            let mid = low + (high - low) / 2;
            match self.position(mid).and_then(|p| self.runs.get(p)) {
                Some(e) if pred(e) => low = mid + 1,
                _ => high = mid,
            }
        }
        low
    }
}

/// Finds the description of `index`/`sub` in a table sorted by `(index, sub)` whose runs do
/// not overlap (the runs of repeated objects are listed once, under the first index):
/// `NoObject` if the index is absent, `NoSubIndex` if only the sub-index is.
pub fn find<'t>(entries: Table<'t>, index: u16, sub: u8) -> Result<&'t EntryInfo, SdoAbort> {
    find_run(entries, index, sub).and_then(|run| entries.get(run).ok_or(SdoAbort::NoObject))
}

/// Like [`find`], but the run's position (PDO mappings keep it).
pub fn find_run(entries: Table<'_>, index: u16, sub: u8) -> Result<usize, SdoAbort> {
    let at = |n: usize| entries.position(n).and_then(|p| Some((p, entries.get(p)?)));
    // The object: the last run listed at or before `index` must describe it.
    let listed = entries.partition_point(|e| e.index <= index);
    let last = listed.checked_sub(1).ok_or(SdoAbort::NoObject)?;
    let first = match at(last) {
        Some((position, e)) if e.covers_index(index) => {
            // The object's last run: most accesses end here (single-run objects, and the
            // subs of the last run), without the second search.
            if e.sub <= sub {
                return if e.covers(sub) { Ok(position) } else { Err(SdoAbort::NoSubIndex) };
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
    match at(run) {
        Some((position, e)) if e.index == first && e.covers(sub) => Ok(position),
        _ => Err(SdoAbort::NoSubIndex),
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
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
        assert_eq!(find(Table::new(&table), 0x1018, 4).map(|e| e.sub), Ok(4));
        assert_eq!(find(Table::new(&table), 0x1018, 2), Err(SdoAbort::NoSubIndex));
        assert_eq!(find(Table::new(&table), 0x1018, 9), Err(SdoAbort::NoSubIndex));
        assert_eq!(find(Table::new(&table), 0x5000, 77).map(|e| (e.sub, e.last_sub)), Ok((1, 128)));
        assert_eq!(find(Table::new(&table), 0x5000, 128).map(|e| e.sub), Ok(1));
        assert_eq!(find(Table::new(&table), 0x5000, 129), Err(SdoAbort::NoSubIndex));
        assert_eq!(find(Table::new(&table), 0x1001, 0), Err(SdoAbort::NoObject));
        assert_eq!(find(Table::new(&table), 0x0FFF, 0), Err(SdoAbort::NoObject));
        assert_eq!(find(Table::new(&table), 0x6000, 0), Err(SdoAbort::NoObject));
        let no_sub0 = [at(0x6000, 1, 8)];
        assert_eq!(find(Table::new(&no_sub0), 0x6000, 0), Err(SdoAbort::NoSubIndex));
        // Every sub-index of every present index resolves as the table says.
        for index in [0x1000_u16, 0x1018, 0x5000] {
            for sub in 0..=255_u8 {
                let want = table.iter().find(|e| e.index == index && e.covers(sub));
                assert_eq!(find(Table::new(&table), index, sub).ok(), want, "{index:04X}.{sub}");
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
            assert_eq!(find_run(Table::new(&table), index, 0), Ok(1), "{index:04X}.0");
            assert_eq!(find_run(Table::new(&table), index, 1), Ok(2), "{index:04X}.1");
            assert_eq!(find_run(Table::new(&table), index, 128), Ok(2), "{index:04X}.128");
            assert_eq!(find_run(Table::new(&table), index, 129), Err(SdoAbort::NoSubIndex), "{index:04X}.129");
        }
        assert_eq!(find_run(Table::new(&table), 0x5004, 0), Err(SdoAbort::NoObject));
        assert_eq!(find_run(Table::new(&table), 0x4FFF, 0), Err(SdoAbort::NoObject));
        assert_eq!(find_run(Table::new(&table), 0x5C00, 2), Ok(3));
        assert_eq!(find_run(Table::new(&table), 0x5C00, 3), Err(SdoAbort::NoSubIndex));
        assert_eq!(find_run(Table::new(&table), 0x5BFF, 0), Err(SdoAbort::NoObject));
        assert!(at(0x5000, 0, 0, 3).covers_index(0x5003) && !at(0x5000, 0, 0, 3).covers_index(0x5004));
        assert!(!at(0xFFFF, 0, 0, 0).covers_index(0xFFFE));
    }

    /// Two modes over one set of runs, as the generator emits them for CO401GW1: 6000h has
    /// subs 1..=8 in one mode and 1..=16 in the other, 6401h only in the first.
    #[test]
    fn each_mode_finds_its_own_runs_among_all() {
        let at = |index, sub, last_sub| EntryInfo { index, sub, last_sub, ..info(DataType::Unsigned8, Access::Ro, HostAccess::Ro, 1) };
        let runs = [at(0x1000, 0, 0), at(0x6000, 0, 0), at(0x6000, 1, 8), at(0x6000, 1, 16), at(0x6200, 0, 0), at(0x6401, 0, 0)];
        let (mixed, digital) = (Table::picked(&runs, &[0, 1, 2, 4, 5]), Table::picked(&runs, &[0, 1, 3, 4]));
        assert_eq!((mixed.len(), digital.len()), (5, 4));
        assert_eq!(find_run(mixed, 0x6000, 8), Ok(2));
        assert_eq!(find_run(mixed, 0x6000, 9), Err(SdoAbort::NoSubIndex));
        assert_eq!(find_run(digital, 0x6000, 9), Ok(3), "the position among all runs");
        assert_eq!(find_run(digital, 0x6000, 16), Ok(3));
        assert_eq!(find_run(digital, 0x6000, 17), Err(SdoAbort::NoSubIndex));
        assert_eq!(find_run(mixed, 0x6401, 0), Ok(5));
        assert_eq!(find_run(digital, 0x6401, 0), Err(SdoAbort::NoObject));
        assert_eq!(find_run(digital, 0x6200, 0), Ok(4));
        // Each mode's iteration is its own runs, in order; `get` takes a position.
        assert_eq!(digital.iter().map(|e| (e.index, e.last_sub)).collect::<std::vec::Vec<_>>(), [(0x1000, 0), (0x6000, 0), (0x6000, 16), (0x6200, 0)]);
        assert_eq!(digital.get(3).map(|e| e.last_sub), Some(16));
        // Every index and sub-index resolves in each mode as its own runs say.
        for (table, pick) in [(mixed, &[0_usize, 1, 2, 4, 5][..]), (digital, &[0, 1, 3, 4][..])] {
            for index in [0x1000_u16, 0x6000, 0x6200, 0x6401, 0x6402] {
                for sub in 0..=20_u8 {
                    let want = pick.iter().copied().find(|&p| runs[p].index == index && runs[p].covers(sub));
                    assert_eq!(find_run(table, index, sub).ok(), want, "{index:04X}.{sub}");
                }
            }
        }
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
