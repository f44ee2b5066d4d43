//! The real-time clock (2010h): a calendar date and time, running on the runtime's
//! microseconds, that stamps the records and the FAT directory entries.
//!
//! The clock keeps the milliseconds since 2000-01-01 00:00 at one instant of the runtime's
//! time base, and converts with the proleptic Gregorian calendar (leap years included), so
//! that a record stamped at 23:59:59.999 on 28 February 2028 is followed by one on the 29th.
//! A field written over 2010h changes that field only; a date that does not exist (31 April)
//! is refused (erratum CR-46).

use crate::card::record::TimeStamp;
use coforge_stack::od::SdoAbort;

const MS_PER_DAY: u64 = 86_400_000;
/// Days from 0000-03-01 to 2000-01-01 in the era arithmetic below.
const DAYS_TO_2000: i64 = 730_425;

/// The clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Clock {
    /// Milliseconds since 2000-01-01 00:00:00.000 at `at_us`.
    base_ms: u64,
    at_us: u64,
}

/// 2010h's fields, 1..=7.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    Millisecond,
    Second,
    Minute,
    Hour,
    Day,
    Month,
    Year,
}

impl Field {
    /// The field of 2010h sub-index `sub` (and of 5x00h subs 1..7).
    pub const fn of_sub(sub: u8) -> Option<Field> {
        Some(match sub {
            1 => Field::Millisecond,
            2 => Field::Second,
            3 => Field::Minute,
            4 => Field::Hour,
            5 => Field::Day,
            6 => Field::Month,
            7 => Field::Year,
            _ => return None,
        })
    }

    /// The field's value in `t`, and its size in bytes (the milliseconds take two).
    pub fn get(self, t: &TimeStamp) -> (u16, usize) {
        match self {
            Field::Millisecond => (t.millisecond, 2),
            Field::Second => (t.second.into(), 1),
            Field::Minute => (t.minute.into(), 1),
            Field::Hour => (t.hour.into(), 1),
            Field::Day => (t.day.into(), 1),
            Field::Month => (t.month.into(), 1),
            Field::Year => (t.year.into(), 1),
        }
    }

    fn set(self, t: &mut TimeStamp, value: u16) {
        let byte = value as u8;
        match self {
            Field::Millisecond => t.millisecond = value,
            Field::Second => t.second = byte,
            Field::Minute => t.minute = byte,
            Field::Hour => t.hour = byte,
            Field::Day => t.day = byte,
            Field::Month => t.month = byte,
            Field::Year => t.year = byte,
        }
    }
}

/// Days in `month` (1..=12) of year 2000 + `year`.
pub const fn days_in_month(year: u8, month: u8) -> u8 {
    match month {
        4 | 6 | 9 | 11 => 30,
        2 if is_leap(2000 + year as u32) => 29,
        2 => 28,
        _ => 31,
    }
}

const fn is_leap(y: u32) -> bool {
    y.is_multiple_of(4) && (!y.is_multiple_of(100) || y.is_multiple_of(400))
}

/// Whether `t` is a moment of the calendar.
pub fn is_valid(t: &TimeStamp) -> bool {
    t.millisecond <= 999
        && t.second <= 59
        && t.minute <= 59
        && t.hour <= 23
        && (1..=12).contains(&t.month)
        && (1..=days_in_month(t.year, t.month)).contains(&t.day)
}

/// Days since 2000-01-01 of a valid date (H. Hinnant's days-from-civil).
fn days_since_2000(year: u8, month: u8, day: u8) -> i64 {
    let m = i64::from(month);
    let y = 2000 + i64::from(year) - i64::from(m <= 2);
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + i64::from(day) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - DAYS_TO_2000
}

/// The date `days` after 2000-01-01 (civil-from-days): year since 2000, month, day.
fn date_of(days: i64) -> (u8, u8, u8) {
    let z = days + DAYS_TO_2000;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2) - 2000;
    (year as u8, month as u8, day as u8)
}

fn to_ms(t: &TimeStamp) -> u64 {
    let days = days_since_2000(t.year, t.month, t.day).max(0) as u64;
    let secs = u64::from(t.hour) * 3600 + u64::from(t.minute) * 60 + u64::from(t.second);
    days * MS_PER_DAY + secs * 1000 + u64::from(t.millisecond)
}

/// The date and time `ms` milliseconds after 2000-01-01 00:00 (a host's clock, for a
/// simulated board's RTC).
pub fn at_ms_since_2000(ms: u64) -> TimeStamp {
    of_ms(ms)
}

/// Milliseconds from 2000-01-01 00:00 to a valid `t` (a board's RTC compares with it).
pub fn ms_since_2000(t: &TimeStamp) -> u64 {
    to_ms(t)
}

/// The day of the week of a valid `t`, ISO 8601: 1 = Monday .. 7 = Sunday (2000-01-01 was a
/// Saturday).
pub fn weekday(t: &TimeStamp) -> u8 {
    (days_since_2000(t.year, t.month, t.day).rem_euclid(7) as u8 + 5) % 7 + 1
}

fn of_ms(ms: u64) -> TimeStamp {
    let (year, month, day) = date_of((ms / MS_PER_DAY) as i64);
    let in_day = ms % MS_PER_DAY;
    let secs = in_day / 1000;
    TimeStamp { millisecond: (in_day % 1000) as u16, second: (secs % 60) as u8, minute: (secs / 60 % 60) as u8, hour: (secs / 3600) as u8, day, month, year }
}

impl Clock {
    /// A clock showing `t` at `now_us` (a board's RTC at power-on); an invalid `t` starts at
    /// 2000-01-01 00:00.
    pub fn new(t: &TimeStamp, now_us: u64) -> Clock {
        let base_ms = if is_valid(t) { to_ms(t) } else { 0 };
        Clock { base_ms, at_us: now_us }
    }

    /// The date and time at `now_us`.
    pub fn now(&self, now_us: u64) -> TimeStamp {
        of_ms(self.base_ms + now_us.saturating_sub(self.at_us) / 1000)
    }

    /// Writes one field (2010h sub `field`) at `now_us`; a date that does not exist is
    /// refused, and the clock keeps running as it was.
    pub fn set(&mut self, field: Field, value: u16, now_us: u64) -> Result<(), SdoAbort> {
        let mut t = self.now(now_us);
        field.set(&mut t, value);
        if !is_valid(&t) {
            return Err(SdoAbort::InvalidValue);
        }
        *self = Clock { base_ms: to_ms(&t), at_us: now_us };
        Ok(())
    }

    /// The time FAT directory entries take at `now_us`.
    pub fn fat_time(&self, now_us: u64) -> embedded_sdmmc::Timestamp {
        fat_time_of(&self.now(now_us))
    }
}

/// `t` as FAT directory entries keep it (two-second resolution on the card).
pub fn fat_time_of(t: &TimeStamp) -> embedded_sdmmc::Timestamp {
    embedded_sdmmc::Timestamp {
        year_since_1970: t.year.saturating_add(30),
        zero_indexed_month: t.month.saturating_sub(1),
        zero_indexed_day: t.day.saturating_sub(1),
        hours: t.hour,
        minutes: t.minute,
        seconds: t.second,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ts(year: u8, month: u8, day: u8, hour: u8, minute: u8, second: u8, millisecond: u16) -> TimeStamp {
        TimeStamp { millisecond, second, minute, hour, day, month, year }
    }

    #[test]
    fn every_day_the_year_byte_holds_round_trips() {
        let mut previous: Option<(u16, u8, u8)> = None;
        let mut days = 0;
        loop {
            let (y, m, d) = date_of(days);
            assert_eq!(days_since_2000(y, m, d), days);
            assert!(is_valid(&ts(y, m, d, 0, 0, 0, 0)), "{y} {m} {d}");
            let y = u16::from(y);
            if let Some((py, pm, pd)) = previous {
                let next_day = (py, pm, pd + 1);
                let next_month = if pm == 12 { (py + 1, 1, 1) } else { (py, pm + 1, 1) };
                let last = days_in_month(py as u8, pm);
                assert!((pd < last && (y, m, d) == next_day) || (pd == last && (y, m, d) == next_month), "{previous:?} -> {y} {m} {d}");
            }
            if (y, m, d) == (255, 12, 31) {
                break;
            }
            previous = Some((y, m, d));
            days += 1;
        }
        assert_eq!(days, 93_501, "2000-01-01 to 2255-12-31, as Python's datetime counts them");
    }

    #[test]
    fn the_clock_runs_across_a_leap_day_and_a_year_end() {
        let c = Clock::new(&ts(28, 2, 28, 23, 59, 59, 999), 5_000_000);
        assert_eq!(c.now(5_000_999), ts(28, 2, 28, 23, 59, 59, 999), "under a millisecond");
        assert_eq!(c.now(5_001_000), ts(28, 2, 29, 0, 0, 0, 0));
        let c = Clock::new(&ts(26, 12, 31, 23, 59, 59, 500), 0);
        assert_eq!(c.now(1_500_000), ts(27, 1, 1, 0, 0, 1, 0));
        assert_eq!(Clock::new(&ts(25, 2, 28, 23, 59, 59, 999), 0).now(1000), ts(25, 3, 1, 0, 0, 0, 0), "2025 is no leap year");
        assert_eq!(Clock::new(&ts(100, 2, 28, 12, 0, 0, 0), 0).now(MS_PER_DAY * 1000), ts(100, 3, 1, 12, 0, 0, 0), "2100 is none either");
    }

    #[test]
    fn a_field_write_changes_that_field_and_refuses_dates_that_do_not_exist() {
        let mut c = Clock::new(&ts(26, 1, 31, 10, 0, 0, 0), 0);
        c.set(Field::Hour, 8, 2_000_000).unwrap();
        assert_eq!(c.now(2_000_000), ts(26, 1, 31, 8, 0, 2, 0));
        assert_eq!(c.set(Field::Month, 4, 2_000_000), Err(SdoAbort::InvalidValue), "31 April");
        assert_eq!(c.set(Field::Month, 2, 2_000_000), Err(SdoAbort::InvalidValue), "31 February");
        assert_eq!(c.now(3_000_000), ts(26, 1, 31, 8, 0, 3, 0), "refused: still running as it was");
        c.set(Field::Day, 30, 3_000_000).unwrap();
        c.set(Field::Month, 4, 3_000_000).unwrap();
        assert_eq!(c.now(3_000_000), ts(26, 4, 30, 8, 0, 3, 0));
        assert_eq!(c.fat_time(3_000_000).year_since_1970, 56);
        assert_eq!((c.fat_time(3_000_000).zero_indexed_month, c.fat_time(3_000_000).zero_indexed_day), (3, 29));
    }

    #[test]
    fn weekdays_follow_the_calendar() {
        assert_eq!(weekday(&ts(0, 1, 1, 0, 0, 0, 0)), 6, "2000-01-01, a Saturday");
        assert_eq!(weekday(&ts(26, 12, 3, 0, 0, 0, 0)), 4, "2026-12-03, a Thursday");
        assert_eq!(weekday(&ts(28, 2, 29, 0, 0, 0, 0)), 2, "2028-02-29, a Tuesday");
        assert_eq!(ms_since_2000(&ts(0, 1, 2, 0, 0, 1, 5)), MS_PER_DAY + 1005);
    }

    #[test]
    fn an_invalid_start_time_starts_at_2000() {
        assert_eq!(Clock::new(&ts(26, 13, 1, 0, 0, 0, 0), 0).now(0), ts(0, 1, 1, 0, 0, 0, 0));
    }
}
