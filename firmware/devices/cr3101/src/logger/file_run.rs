//! One file's operating mode at run time (3x03h): the record being filled, the autoincrement
//! window, the cyclic timer and the end of a linear file. A small engine: values come in with
//! [`FileRun::set`], [`FileRun::due`] says when a record is to be written, and
//! [`FileRun::commit`] hands out the record and where it goes.

use super::file_config::{FileConfig, Mode};
use crate::card::record::{Record, RecordLayout, TimeStamp};

/// 3x03h.3's unit.
const INTERVAL_US: u64 = 10_000;

/// A record to write at record address `at`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Commit {
    pub record: Record,
    pub at: u32,
}

/// One file's run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileRun {
    /// The values written since the last record, with their modification bits.
    pending: Record,
    /// Something was written since the last record.
    input: bool,
    /// Autoincrement writing: when the open window closes.
    window_ends: Option<u64>,
    /// Cyclic writing: when the next record is due.
    next_cycle: Option<u64>,
    /// What 5x00h shows: the last record written or read, and its address in the direct modes.
    shown: Option<(Record, Option<u32>)>,
    /// A linear file at its end: no more records until its pointers are set back.
    stopped: bool,
}

fn interval_us(file: &FileConfig) -> u64 {
    u64::from(file.interval()) * INTERVAL_US
}

impl FileRun {
    pub fn new(layout: RecordLayout) -> FileRun {
        FileRun { pending: Record::new(&layout), input: false, window_ends: None, next_cycle: None, shown: None, stopped: false }
    }

    /// The mode (or the NMT state) starts now: a cyclic file's first record is due one
    /// interval from `now_us`; an open window is forgotten.
    pub fn restart(&mut self, file: &FileConfig, now_us: u64) {
        self.window_ends = None;
        self.next_cycle = (file.mode() == Mode::Cyclic).then(|| now_us.saturating_add(interval_us(file)));
    }

    /// Value `value` of component `c` (checked against `layout` by the caller), written at
    /// `now_us`: autoincrement writing opens its window with the first value.
    pub fn set(&mut self, layout: &RecordLayout, c: usize, value: &[u8], file: &FileConfig, now_us: u64) {
        self.pending.set(layout, c, value);
        self.input = true;
        if file.mode() == Mode::Autoincrement && file.interval() > 0 && self.window_ends.is_none() {
            self.window_ends = Some(now_us.saturating_add(interval_us(file)));
        }
    }

    pub fn has_input(&self) -> bool {
        self.input
    }

    /// When the next record is due: the cyclic timer (in operational state only) or the
    /// closing of the autoincrement window.
    pub fn due(&self, file: &FileConfig, operational: bool) -> Option<u64> {
        match file.mode() {
            _ if self.stopped => None,
            Mode::Cyclic if operational => self.next_cycle,
            Mode::Autoincrement => self.window_ends,
            _ => None,
        }
    }

    /// The record to write now, stamped `stamp`, for a file of `records` records: at the
    /// write pointer, or at record 0 for a ring file whose pointer was set past its end.
    /// `None` when the file takes no record (no records, or a linear file at its end).
    pub fn commit(&mut self, file: &FileConfig, records: u32, stamp: &TimeStamp, now_us: u64) -> Option<Commit> {
        self.window_ends = None;
        if let Some(next) = self.next_cycle {
            // The next cycle one interval on; a late check does not make a burst of records.
            let following = next.saturating_add(interval_us(file));
            self.next_cycle = Some(if following <= now_us { now_us.saturating_add(interval_us(file)) } else { following });
        }
        let at = match file.write_pointer() {
            _ if self.stopped || records == 0 => return None,
            at if at < records => at,
            _ if file.ring => 0,
            _ => {
                self.stopped = true;
                return None;
            }
        };
        self.pending.stamp(stamp);
        let record = self.pending;
        self.shown = Some((record, None));
        // Cyclic writing keeps the last values for the next record; the modification status
        // says what was written within each record's interval.
        self.pending.clear_modified();
        self.input = false;
        Some(Commit { record, at })
    }

    /// The file reached its end in linear mode.
    pub fn stop(&mut self) {
        self.stopped = true;
    }

    /// Its pointers were set back: it takes records again.
    pub fn reopen(&mut self) {
        self.stopped = false;
    }

    pub fn is_stopped(&self) -> bool {
        self.stopped
    }

    /// Shows `record`, read from or written to record address `at` in a direct mode.
    pub fn show(&mut self, record: Record, at: u32) {
        self.shown = Some((record, Some(at)));
    }

    /// The address of the record shown, if a direct mode put it there.
    pub fn shown_record(&self) -> Option<u32> {
        self.shown.and_then(|(_, at)| at)
    }

    /// What 5x00h shows: the last record written or read, or before any, the values written
    /// so far.
    pub fn shown(&self) -> Record {
        self.shown.map_or(self.pending, |(r, _)| r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(mode: u8, interval: u32, ring: bool) -> FileConfig {
        let mut f = FileConfig::factory(0);
        f.relevant = 0b1;
        f.set_mode(0x03).unwrap();
        f.set_interval(interval).unwrap();
        f.set_mode(mode).unwrap();
        f.ring = ring;
        f
    }

    const T: TimeStamp = TimeStamp { millisecond: 5, second: 1, minute: 2, hour: 3, day: 4, month: 5, year: 26 };

    #[test]
    fn an_autoincrement_window_opens_with_the_first_value_and_collects_until_it_closes() {
        let f = file(0x03, 5, false);
        let l = f.layout();
        let mut run = FileRun::new(l);
        run.restart(&f, 0);
        assert_eq!(run.due(&f, true), None, "no window before a value");
        run.set(&l, 0, &[1, 0], &f, 1_000);
        run.set(&l, 0, &[2, 0], &f, 30_000);
        assert_eq!(run.due(&f, false), Some(51_000), "5 x 10 ms from the first value, in any state");
        let c = run.commit(&f, 10, &T, 51_000).unwrap();
        assert_eq!((c.at, c.record.get(&l, 0), c.record.time_stamp(), c.record.modified()), (0, Some(&[2, 0][..]), T, 1));
        assert_eq!((run.due(&f, true), run.has_input()), (None, false));
        assert_eq!(run.shown(), c.record);
    }

    #[test]
    fn cyclic_writing_runs_in_operational_only_and_keeps_the_last_values() {
        let f = file(0x02, 2, false);
        let l = f.layout();
        let mut run = FileRun::new(l);
        run.restart(&f, 100);
        assert_eq!((run.due(&f, true), run.due(&f, false)), (Some(20_100), None));
        run.set(&l, 0, &[7, 0], &f, 150);
        let first = run.commit(&f, 10, &T, 20_100).unwrap();
        assert_eq!(first.record.modified(), 1);
        assert_eq!(run.due(&f, true), Some(40_100));
        let second = run.commit(&f, 10, &T, 40_100).unwrap();
        assert_eq!((second.record.get(&l, 0), second.record.modified()), (Some(&[7, 0][..]), 0), "same value, not written again");
        run.commit(&f, 10, &T, 200_000).unwrap();
        assert_eq!(run.due(&f, true), Some(220_000), "late: the next cycle from now, not a burst");
    }

    #[test]
    fn a_linear_file_stops_at_its_end_and_a_ring_file_goes_on_at_record_0() {
        let mut f = file(0x03, 0, false);
        f.set_progress(3, 3);
        let l = f.layout();
        let mut run = FileRun::new(l);
        run.set(&l, 0, &[1, 0], &f, 0);
        assert_eq!(run.commit(&f, 3, &T, 0), None);
        assert!(run.is_stopped());
        run.reopen();
        f.ring = true;
        assert_eq!(run.commit(&f, 3, &T, 0).map(|c| c.at), Some(0));
        assert_eq!(run.commit(&f, 0, &T, 0), None, "a file without records");
    }
}
