//! DS401's rules, as pure functions: when an input change is an event for its TPDO, and what
//! the outputs show while a critical error lasts.

/// The interrupt masks of one digital input byte (6006h, 6007h, 6008h).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DigitalMasks {
    pub any_change: u8,
    /// Rising edge of the 6000h bit (a falling edge of the active-low pin).
    pub low_to_high: u8,
    pub high_to_low: u8,
}

/// Whether input byte `was` -> `now` is an event: a change of a bit whose mask says so,
/// while 6005h (global interrupt enable) is set. Unchanged data is never an event.
pub const fn digital_event(global_enable: bool, masks: DigitalMasks, was: u8, now: u8) -> bool {
    let changed = was ^ now;
    let rising = changed & now;
    let falling = changed & was;
    global_enable && (changed & masks.any_change | rising & masks.low_to_high | falling & masks.high_to_low) != 0
}

/// The trigger settings of one analog input channel (6421h and 6424h..6428h).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AnalogTrigger {
    /// 6421h: bit 0 upper limit, 1 lower limit, 2 delta, 3 negative delta, 4 positive delta.
    pub conditions: u8,
    pub upper_limit: i32,
    pub lower_limit: i32,
    pub delta: i32,
    pub negative_delta: i32,
    pub positive_delta: i32,
}

/// Whether analog input `now` is an event, against `sent`, its value when it last was one,
/// while 6423h (analog global interrupt enable) is set. Unchanged data is never an event.
pub fn analog_event(global_enable: bool, t: AnalogTrigger, sent: i16, was: i16, now: i16) -> bool {
    if !global_enable || was == now {
        return false;
    }
    let (now, sent) = (i32::from(now), i32::from(sent));
    let moved = now - sent;
    let holds = [now > t.upper_limit, now < t.lower_limit, moved.abs() > t.delta, -moved > t.negative_delta, moved > t.positive_delta];
    holds.iter().enumerate().any(|(bit, &h)| h && t.conditions & (1 << bit) != 0)
}

/// Output byte `value` with the error state of 6206h (`mode`: which bits are forced) and
/// 6207h (`error`: the level they are forced to).
pub const fn forced(value: u8, mode: u8, error: u8) -> u8 {
    (value & !mode) | (error & mode)
}

/// What OUT0..OUT7 carry for output byte 0: its polarity (6202h) applied, then inverted
/// (the pins are active low).
pub const fn output_levels(value: u8, polarity: u8) -> u8 {
    !(value ^ polarity)
}

/// What 6000h sub 1 reads for IN0..IN7: the pin levels inverted (active low), then the
/// polarity (6002h) applied.
pub const fn input_value(levels: u8, polarity: u8) -> u8 {
    !levels ^ polarity
}

/// An analog output's error value (6444h, INTEGER32) in the INTEGER16 of 6411h: saturated.
pub fn analog_error_value(value: i32) -> i16 {
    value.clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16
}

#[cfg(test)]
mod tests {
    use super::*;

    const ANY: DigitalMasks = DigitalMasks { any_change: 0xFF, low_to_high: 0, high_to_low: 0 };

    #[test]
    fn digital_changes_pass_the_masks() {
        assert!(digital_event(true, ANY, 0x00, 0x01));
        assert!(!digital_event(true, ANY, 0x01, 0x01), "unchanged data is no event");
        assert!(!digital_event(false, ANY, 0x00, 0x01), "6005h off");
        let rising = DigitalMasks { any_change: 0, low_to_high: 0x01, high_to_low: 0 };
        assert!(digital_event(true, rising, 0x00, 0x01));
        assert!(!digital_event(true, rising, 0x01, 0x00));
        let falling = DigitalMasks { any_change: 0, low_to_high: 0, high_to_low: 0x80 };
        assert!(digital_event(true, falling, 0x80, 0x00));
        assert!(!digital_event(true, falling, 0x40, 0x00), "bit 6 is not in the mask");
    }

    #[test]
    fn analog_conditions_follow_6421() {
        // The defaults: 6421h = 7 (upper, lower, delta), all limits and deltas 0.
        let t = AnalogTrigger { conditions: 7, ..AnalogTrigger::default() };
        assert!(!analog_event(false, t, 0, 0, 5), "6423h is FALSE by default");
        assert!(analog_event(true, t, 0, 0, 5));
        assert!(!analog_event(true, t, 0, 5, 5), "unchanged data is no event");
        let upper = AnalogTrigger { conditions: 1, upper_limit: 100, ..t };
        assert!(!analog_event(true, upper, 0, 0, 100));
        assert!(analog_event(true, upper, 0, 0, 101));
        let lower = AnalogTrigger { conditions: 2, lower_limit: -10, ..t };
        assert!(analog_event(true, lower, 0, 0, -11) && !analog_event(true, lower, 0, 0, -10));
        let delta = AnalogTrigger { conditions: 4, delta: 50, ..t };
        assert!(!analog_event(true, delta, 1000, 1000, 1050) && analog_event(true, delta, 1000, 1000, 949));
        let negative = AnalogTrigger { conditions: 8, negative_delta: 20, ..t };
        assert!(analog_event(true, negative, 100, 100, 79) && !analog_event(true, negative, 100, 100, 200));
        let positive = AnalogTrigger { conditions: 16, positive_delta: 20, ..t };
        assert!(analog_event(true, positive, 100, 100, 121) && !analog_event(true, positive, 100, 100, 0));
    }

    #[test]
    fn outputs_are_forced_polarised_and_inverted() {
        assert_eq!(forced(0b1010_1010, 0xFF, 0x00), 0x00);
        assert_eq!(forced(0b1010_1010, 0x0F, 0xFF), 0b1010_1111);
        // Output bit 0 active (1): pin 0 low.
        assert_eq!(output_levels(0x01, 0x00), 0xFE);
        assert_eq!(output_levels(0x01, 0x01), 0xFF);
        // IN0 low (active): 6000h.1 bit 0 set, unless 6002h inverts it.
        assert_eq!(input_value(0xFE, 0x00), 0x01);
        assert_eq!(input_value(0xFE, 0x01), 0x00);
        assert_eq!((analog_error_value(70_000), analog_error_value(-70_000), analog_error_value(-5)), (i16::MAX, i16::MIN, -5));
    }
}
