//! Measured scenarios of coforge-stack's manager for `cargo xtask bench`, as the device bench
//! images do: only the manager's code between the marker functions, every result checked
//! after the end marker, and the stack peak.
//!
//! The manager watches all 127 node-IDs (consumer time 1 s each, heartbeats from all of them
//! received in the setup) and caches scans of 31 nodes with 4 TPDOs and RPDOs each, the
//! sizes CANopenIA needs; auto-scan is off so that only the measured transfers run. The
//! figure the issue asks for is an expedited SDO upload, request queued to result taken:
//! `upload`, `poll` until the initiate request is out, the server's response into `on_frame`,
//! and the result out of `take_event`.
#![no_std]
#![no_main]

use coforge_board_qemu::bench::{Answers, expect, fail, finish, frame, measure, paint_stack, stack_peak};
use coforge_stack::frame::CanFrame;
use coforge_stack::manager::monitor::MonitorEvent;
use coforge_stack::manager::scan::ScanConfig;
use coforge_stack::manager::{Manager, ManagerEvent};
use coforge_stack::sdo::client::{SdoClient, SdoResult};
use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use panic_semihosting as _;

type Mgr = Manager<31, 4>;

const SERVER: u8 = 5;
const NOW_US: u64 = 10_000;

const NAMES: [&str; 5] = [
    "calibration (empty)",
    "manager expedited upload 1018.1 (request queued to result taken)",
    "sdo-client channel alone: expedited upload 1018.1",
    "heartbeat of a monitored node (127 monitored)",
    "monitor check, 127 nodes monitored, none due (the earliest deadline skips the scan)",
];

/// The manager's frames until it is quiet.
fn poll_all(m: &mut Mgr, now_us: u64, buf: &mut [u8]) -> Answers {
    let mut answers = Answers::NONE;
    while let Some(f) = m.poll(now_us, buf) {
        if let Some(slot) = answers.frames.get_mut(answers.n) {
            *slot = f;
        }
        answers.n += 1;
    }
    answers
}

/// Builds the manager in a static, in a frame of its own.
#[inline(never)]
fn mount() -> &'static mut Mgr {
    let Some(m) = cortex_m::singleton!(: Mgr = Manager::new(ScanConfig { pdos: 4, heartbeat_ms: None })) else { panic!("mounted twice") };
    m
}

#[entry]
fn main() -> ! {
    paint_stack();
    let m = mount();
    m.set_auto_scan(false);
    m.monitor_mut().set_consumer_ms(None, 1000);
    let mut buf = [0_u8; 8];
    for node in 1..=127_u16 {
        m.on_frame(&frame(0x700 + node, &[0x05]), 0, &mut buf);
        if !matches!(m.take_event(), Some(ManagerEvent::Node(MonitorEvent::HeartbeatStarted { .. }))) {
            fail("heartbeat started", &Answers::NONE);
        }
    }
    let response = frame(0x580 + u16::from(SERVER), &[0x43, 0x18, 0x10, 0x01, 0x58, 0, 0, 0]);
    hprintln!("stack-peak-setup-bytes: {}", stack_peak());
    hprintln!("manager-bytes: {}", core::mem::size_of::<Mgr>());
    paint_stack();

    measure(0, || {});

    let (requests, event) = measure(1, || {
        let _ = m.upload(SERVER, 0x1018, 1);
        let requests = poll_all(m, NOW_US, &mut buf);
        m.on_frame(&response, NOW_US, &mut buf);
        (requests, m.take_event())
    });
    expect("manager: initiate upload 1018.1", &requests, &[(0x600 + u16::from(SERVER), &[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0])]);
    if event != Some(ManagerEvent::Sdo(SdoResult::Uploaded { len: 4 })) || buf[..4] != [0x58, 0, 0, 0] {
        fail("manager: upload result", &Answers::NONE);
    }

    let mut client = SdoClient::new();
    let (request, result) = measure(2, || {
        let request = client.upload(SERVER, 0x1018, 1, NOW_US).ok();
        let _ = client.on_frame(&response, NOW_US, &mut buf);
        (request, client.take_result())
    });
    let sent = request.map_or(Answers::NONE, |f: CanFrame| Answers { frames: [f; 4], n: 1 });
    expect("client: initiate upload 1018.1", &sent, &[(0x600 + u16::from(SERVER), &[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0])]);
    if result != Some(SdoResult::Uploaded { len: 4 }) {
        fail("client: upload result", &Answers::NONE);
    }

    let heartbeat = frame(0x700 + 64, &[0x05]);
    measure(3, || m.on_frame(&heartbeat, 500_000, &mut buf));
    if m.take_event().is_some() {
        fail("heartbeat: no event for an unchanged state", &Answers::NONE);
    }

    let event = measure(4, || m.monitor_mut().check(900_000));
    if event.is_some() {
        fail("check: nothing due at 900 ms", &Answers::NONE);
    }

    finish(&NAMES, stack_peak())
}
