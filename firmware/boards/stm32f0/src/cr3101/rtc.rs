//! The STM32F0's RTC on the 32.768 kHz crystal (LSE, PC14/PC15), kept running by the backup
//! battery on VBAT: CR3101's clock at power-on (2010h), and kept in step with 2010h after.
//!
//! - [`start_backup_domain`], before the HAL takes the RCC: the PWR clock, write access to the
//!   backup domain (DBP), and on a backup domain that is new (battery or VBAT just connected:
//!   RTCEN clear) the LSE switched on (medium-high drive) as the RTC clock. A domain that runs
//!   already is left as it is (RTCSEL can only be chosen once per backup-domain reset).
//! - [`Rtc::at_power_on`]: the calendar if it was ever set (ISR.INITS: year not 0) and its
//!   shadow registers come (RSF), else [`UNSET`], 2000-01-01 00:00:00.000.
//! - [`Rtc::keep`], once a second from the main loop: when the device's clock (2010h, set over
//!   SDO) and the calendar differ by more than a second (a calendar never set runs from
//!   2000-01-01 since the battery came, and differs), the calendar is set to the device's
//!   time. A crystal that is just starting (up to 2 s) or missing does not let the calendar
//!   enter initialisation mode: the write gives up after about 0.4 ms and is tried again
//!   [`RETRY_MS`] later.
//!
//! Calendar values are BCD in the 24-hour format (CR.FMT = 0, the reset value), years 2000..2099;
//! the prescalers are the 32.768 kHz values (PREDIV_A 127, PREDIV_S 255: 1 Hz).

use cr3101::card::record::TimeStamp;
use cr3101::clock::ms_since_2000;
use stm32f0xx_hal::pac::{PWR, RCC, RTC};

/// The clock when the calendar was never set: the RTC's own start, 2000-01-01 00:00.
pub const UNSET: TimeStamp = TimeStamp { millisecond: 0, second: 0, minute: 0, hour: 0, day: 1, month: 1, year: 0 };
/// Status polls before a wait gives up: INITF and RSF come within two RTC clocks (61 us) of a
/// running crystal; some 2,000 polls of about 10 core clocks each are 0.4 ms at 48 MHz.
const POLLS: u32 = 2_000;
/// How long after a failed calendar write the next is tried.
pub const RETRY_MS: u32 = 60_000;
/// Synchronous prescaler: 32,768 Hz / (127 + 1) / (255 + 1) = 1 Hz.
const PREDIV_S: u32 = 255;
const PREDIV_A: u32 = 127;

/// Switches on the PWR clock and backup-domain write access, and on a new backup domain the
/// LSE as the RTC's clock. Before `clock::start_core`, which gives the RCC to the HAL (whose
/// clock set-up leaves APB1ENR's PWREN and BDCR alone).
pub fn start_backup_domain(rcc: &RCC, pwr: &PWR) {
    rcc.apb1enr.modify(|_, w| w.pwren().set_bit());
    pwr.cr.modify(|_, w| w.dbp().set_bit());
    if rcc.bdcr.read().rtcen().bit_is_clear() {
        // Medium-high drive: starts the usual 6..12.5 pF watch crystals (AN2867); the LSE
        // runs from VBAT from here on, as long as the battery lasts.
        rcc.bdcr.modify(|_, w| w.lsedrv().medium_high());
        rcc.bdcr.modify(|_, w| w.lseon().set_bit());
        rcc.bdcr.modify(|_, w| w.rtcsel().lse().rtcen().set_bit());
    }
}

/// The RTC peripheral.
pub struct Rtc {
    regs: RTC,
    /// After a calendar write that failed: when (the low 32 bits of the milliseconds) the next
    /// may be tried.
    retry_at_ms: Option<u32>,
}

impl Rtc {
    pub fn new(regs: RTC) -> Self {
        Rtc { regs, retry_at_ms: None }
    }

    /// The calendar's date and time, or [`UNSET`] when it was never set, does not run, or
    /// holds no valid date.
    pub fn at_power_on(&mut self) -> TimeStamp {
        if self.regs.isr.read().inits().bit_is_clear() {
            return UNSET;
        }
        self.read().unwrap_or(UNSET)
    }

    /// Sets the calendar to `now` (the device's clock) if it is more than a second off (or
    /// unreadable); `ms`: the loop's milliseconds (low 32 bits), for the retry delay.
    pub fn keep(&mut self, now: &TimeStamp, ms: u32) {
        let off = match self.read() {
            Some(t) => (ms_since_2000(&t) / 1000).abs_diff(ms_since_2000(now) / 1000) > 1,
            None => true,
        };
        if !off {
            self.retry_at_ms = None;
            return;
        }
        // A wrapping comparison: a retry time is at most RETRY_MS ahead.
        if self.retry_at_ms.is_some_and(|at| (ms.wrapping_sub(at) as i32) < 0) {
            return;
        }
        self.retry_at_ms = (!self.write(now)).then_some(ms.wrapping_add(RETRY_MS));
    }

    /// Polls until `done` or [`POLLS`] run out.
    fn wait(&self, done: impl Fn(&stm32f0xx_hal::pac::rtc::isr::R) -> bool) -> bool {
        (0..POLLS).any(|_| done(&self.regs.isr.read()))
    }

    /// The calendar, once its shadow registers are up to date (RSF: after a reset or a write,
    /// within two RTC clocks of a running crystal), if it holds a valid date.
    fn read(&mut self) -> Option<TimeStamp> {
        if !self.wait(|isr| isr.rsf().bit_is_set()) {
            return None;
        }
        // SSR first: reading it freezes TR and DR until DR is read (RM0091, 26.4.8).
        let ss = self.regs.ssr.read().ss().bits();
        let tr = self.regs.tr.read();
        let dr = self.regs.dr.read();
        // SS counts down from PREDIV_S once a second.
        let ms = (PREDIV_S.saturating_sub(u32::from(ss)) * 1000 / (PREDIV_S + 1)) as u16;
        let bcd = |tens: u8, units: u8| tens * 10 + units;
        let t = TimeStamp {
            millisecond: ms,
            second: bcd(tr.st().bits(), tr.su().bits()),
            minute: bcd(tr.mnt().bits(), tr.mnu().bits()),
            hour: bcd(tr.ht().bits(), tr.hu().bits()),
            day: bcd(dr.dt().bits(), dr.du().bits()),
            month: bcd(u8::from(dr.mt().bit()), dr.mu().bits()),
            year: bcd(dr.yt().bits(), dr.yu().bits()),
        };
        cr3101::clock::is_valid(&t).then_some(t)
    }

    /// Sets the calendar to `t` (to the second; years 2000..2099); `false` if the RTC did not
    /// enter initialisation mode (its clock does not run yet).
    fn write(&mut self, t: &TimeStamp) -> bool {
        if !cr3101::clock::is_valid(t) || t.year > 99 {
            return false;
        }
        let bcd = |v: u8| u32::from(v / 10) << 4 | u32::from(v % 10);
        let tr = bcd(t.hour) << 16 | bcd(t.minute) << 8 | bcd(t.second);
        // Day of the week, 1 = Monday .. 7 = Sunday: 2000-01-01 was a Saturday.
        let weekday = u32::from(cr3101::clock::weekday(t));
        let dr = bcd(t.year) << 16 | weekday << 13 | bcd(t.month) << 8 | bcd(t.day);
        self.unlock(true);
        self.regs.isr.modify(|_, w| w.init().set_bit());
        let entered = self.wait(|isr| isr.initf().bit_is_set());
        if entered {
            // SAFETY: `bits` writes whole registers that svd2rust cannot range-check: PRER
            // with the prescalers above (each within its field), TR and DR with BCD digits
            // built from a valid date and time (each within its field, reserved bits 0). They
            // are written in initialisation mode only, as RM0091 requires; PRER in two
            // accesses, synchronous first (as ST's HAL does).
            #[allow(unsafe_code)]
            unsafe {
                self.regs.prer.write(|w| w.bits(PREDIV_S));
                self.regs.prer.write(|w| w.bits(PREDIV_A << 16 | PREDIV_S));
                self.regs.tr.write(|w| w.bits(tr));
                self.regs.dr.write(|w| w.bits(dr));
            }
        }
        // Leaving initialisation mode starts the calendar at the values written; RSF is
        // cleared so that the next read waits for shadow registers holding them.
        self.regs.isr.modify(|_, w| w.init().clear_bit().rsf().clear_bit());
        self.unlock(false);
        entered
    }

    /// Opens (the two keys CAh, 53h) or closes (any other key) the RTC's write protection.
    fn unlock(&mut self, open: bool) {
        let keys: &[u8] = if open { &[0xCA, 0x53] } else { &[0xFF] };
        for &key in keys {
            // SAFETY: the key field is the whole register; every value is allowed (a wrong
            // key closes the protection again).
            #[allow(unsafe_code)]
            self.regs.wpr.write(|w| unsafe { w.key().bits(key) });
        }
    }
}
