//! The main loop, for any device: its serial host port (if it has one) on USART2 ([`NoHost`]
//! for an image without one), its CAN side on bxCAN, its CiA 303-3 indicators on two LEDs
//! ([`Indicators`]: the loop's, or the device's own when it drives them through its board, as
//! CO401GW1 and CR3101 do).

use crate::{can, clock};
use coforge_stack::device::Device;
use coforge_stack::leds::{LedState, Leds as LedStates};
use coforge_stack::node::BusState;
use embedded_hal_02::digital::v2::OutputPin;
use embedded_hal_02::serial::{Read, Write};
use stm32f0xx_hal::can::CanInstance;
use stm32f0xx_hal::can::bxcan;
use stm32f0xx_hal::gpio::gpioa::{PA2, PA3, PA11, PA12};
use stm32f0xx_hal::gpio::gpiob::{PB0, PB1};
use stm32f0xx_hal::gpio::{AF1, AF4, Alternate, Output, PushPull};
use stm32f0xx_hal::pac;
use stm32f0xx_hal::serial::Serial;

/// The serial host: USART2 on PA2/PA3.
pub type Host = Serial<pac::USART2, PA2<Alternate<AF1>>, PA3<Alternate<AF1>>>;
/// bxCAN on PA12/PA11.
pub type Can = bxcan::Can<CanInstance<PA12<Alternate<AF4>>, PA11<Alternate<AF4>>>>;
/// CANLEDR#, CANLEDE#.
pub type Leds = (PB0<Output<PushPull>>, PB1<Output<PushPull>>);

/// What shows the device's CiA 303-3 indicators once per pass of the loop.
pub trait Indicators {
    /// Shows `states` at `ms`, the millisecond clock's low 32 bits.
    fn show(&mut self, states: LedStates, ms: u32);
}

/// Two active-low LEDs (run, error) driven from [`Device::leds`]: CO401Memory1's CANLEDR# and
/// CANLEDE#.
impl Indicators for Leds {
    #[inline(always)]
    fn show(&mut self, states: LedStates, ms: u32) {
        // The milliseconds' low 32 bits: a u64 here would take a 64-bit remainder for the
        // patterns' periods; the wrap after 49 days only shifts a flash phase once.
        let level = |s: LedState| s.level_in_period(ms % u32::from(s.period()));
        let _ = self.0.set_state((!level(states.run)).into());
        let _ = self.1.set_state((!level(states.error)).into());
    }
}

/// A device that drives its indicators itself, through its own board, whenever it handles an
/// input or a poll (CO401GW1: CFG0/R, CFG1/E and CFG2/WD, with its own run-LED flicker): the
/// loop has nothing to show.
#[derive(Debug, Clone, Copy, Default)]
pub struct OwnIndicators;

impl Indicators for OwnIndicators {
    #[inline(always)]
    fn show(&mut self, _: LedStates, _: u32) {}
}

/// No serial host line: a device without a host port (CR3101), whose image leaves USART2 and
/// PA2/PA3 alone. Reads nothing, takes every byte.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoHost;

impl Read<u8> for NoHost {
    type Error = core::convert::Infallible;

    fn read(&mut self) -> nb::Result<u8, Self::Error> {
        Err(nb::Error::WouldBlock)
    }
}

impl Write<u8> for NoHost {
    type Error = core::convert::Infallible;

    fn write(&mut self, _: u8) -> nb::Result<(), Self::Error> {
        Ok(())
    }

    fn flush(&mut self) -> nb::Result<(), Self::Error> {
        Ok(())
    }
}

/// Starts the device and serves it for ever. `bxcan` comes disabled (off the bus) with its
/// bit timing and filters set: it is enabled once the device's CAN side is
/// active (`NodeAccess::can_enabled`: at once for most devices, after the host's enable
/// command for CO401GW1). Not inlined: the device's handlers inlined here have frames of their own,
/// which must not add to the frame that built the device.
#[inline(never)]
pub fn serve<D: Device>(device: &mut D, host: Host, bxcan: Can, indicators: impl Indicators) -> ! {
    device.start(0);
    serve_loop(device, host, bxcan, indicators, |_, _| {})
}

/// [`serve`] for a device its caller has already started (`Device::start(0)`), for a device
/// whose start decides what the controller needs (CR3101's bit rate comes from its stored
/// 20F2h/20F3h pair), over any serial host line (`NoHost` for none), with `each_pass` called
/// at the end of every pass with the device and the loop's time in microseconds.
#[inline(never)]
pub fn serve_started<D: Device, H: Read<u8> + Write<u8>>(
    device: &mut D,
    host: H,
    bxcan: Can,
    indicators: impl Indicators,
    each_pass: impl FnMut(&mut D, u64),
) -> ! {
    serve_loop(device, host, bxcan, indicators, each_pass)
}

#[inline(always)]
fn serve_loop<D: Device, H: Read<u8> + Write<u8>>(
    device: &mut D,
    mut host: H,
    mut bxcan: Can,
    mut indicators: impl Indicators,
    mut each_pass: impl FnMut(&mut D, u64),
) -> ! {
    let mut on_bus = false;
    // A frame the mailboxes did not take (all three busy with frames of higher or equal
    // priority, or one bxcan took out to make room): sent before anything new is polled.
    let mut held: Option<bxcan::Frame> = None;
    let mut bus_state = BusState::Active;
    loop {
        let now_ms = clock::millis();
        let now_us = now_ms * 1000;

        if let Some(port) = device.host_port() {
            loop {
                match host.read() {
                    Ok(byte) => port.on_host_byte(byte, now_ms),
                    // Framing, noise, overrun: the flag is cleared, the byte (if any) comes next.
                    Err(nb::Error::Other(_)) => {}
                    Err(nb::Error::WouldBlock) => break,
                }
            }
            // Polled on every pass, not only after a byte: answers may come late or unasked.
            // One byte at a time: the UART sends no faster anyway.
            let mut byte = [0];
            while port.host_output(now_ms, &mut byte) == 1 {
                let _ = nb::block!(host.write(byte[0]));
            }
        }

        if !on_bus && device.node().can_enabled() {
            // Joins the bus once it sees 11 recessive bits, in the background: a bus held
            // dominant must not stop the serial host. ABOM (set by `enable_non_blocking`)
            // restarts after bus-off by itself.
            let _ = bxcan.enable_non_blocking();
            on_bus = true;
        }

        loop {
            match bxcan.receive() {
                Ok(frame) => {
                    if let Some(frame) = can::from_bxcan(&frame) {
                        device.on_frame(&frame, now_us);
                    }
                }
                // A FIFO overrun: frames were lost, the rest are still there.
                Err(nb::Error::Other(())) => {}
                Err(nb::Error::WouldBlock) => break,
            }
        }

        let state = can::bus_state(esr(&mut bxcan));
        if state != bus_state {
            bus_state = state;
            device.on_bus_state(state, now_us);
        }

        if let Some(frame) = held.take() {
            held = transmit(&mut bxcan, frame);
        }
        while held.is_none() {
            let Some(frame) = device.poll(now_us) else { break };
            held = can::to_bxcan(&frame).and_then(|f| transmit(&mut bxcan, f));
        }

        indicators.show(device.leds(), now_ms as u32);
        each_pass(device, now_us);
    }
}

/// Queues `frame`; returns what could not be queued: `frame` itself, or the lower-priority
/// frame bxcan aborted to make room for it.
fn transmit<I: bxcan::Instance>(can: &mut bxcan::Can<I>, frame: bxcan::Frame) -> Option<bxcan::Frame> {
    match can.transmit(&frame) {
        Ok(status) => status.dequeued_frame().cloned(),
        Err(_) => Some(frame),
    }
}

/// CAN_ESR: the controller's error state (bxcan 0.6 has no accessor for it).
#[allow(unsafe_code)]
fn esr(can: &mut Can) -> u32 {
    // SAFETY: a read of a read-only status register, without side effects; bxcan owns the
    // peripheral but never writes ESR's read-only bits, and nothing else runs concurrently.
    unsafe { can.instance().peripheral() }.esr.read().bits()
}
