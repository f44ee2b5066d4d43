//! One expedited SDO upload through the manager, request queued to result taken, repeated:
//! the x86-64 instruction count of `cargo xtask bench` comes from running this under
//! callgrind with collection on for `upload_once` only.
//!
//! `valgrind --tool=callgrind --toggle-collect='manager_upload::upload_once' target/release/examples/manager_upload`

use coforge_stack::frame::CanFrame;
use coforge_stack::manager::scan::ScanConfig;
use coforge_stack::manager::{Manager, ManagerEvent};
use coforge_stack::sdo::client::SdoResult;
use std::hint::black_box;

/// Uploads done per run: the per-upload figure is the collected total divided by this.
const UPLOADS: u64 = 1000;

#[inline(never)]
fn upload_once(m: &mut Manager<31, 4>, response: &CanFrame, buf: &mut [u8; 8]) -> Option<ManagerEvent> {
    let _ = m.upload(5, 0x1018, 1);
    while let Some(frame) = m.poll(10_000, buf) {
        black_box(frame);
    }
    m.on_frame(response, 10_000, buf);
    m.take_event()
}

fn main() {
    let mut m: Box<Manager<31, 4>> = Box::new(Manager::new(ScanConfig { pdos: 4, heartbeat_ms: None }));
    m.set_auto_scan(false);
    let response = CanFrame::data(0x585, &[0x43, 0x18, 0x10, 0x01, 0x58, 0, 0, 0]).expect("an SDO response");
    let mut buf = [0; 8];
    for _ in 0..UPLOADS {
        let event = upload_once(black_box(&mut m), &response, &mut buf);
        assert_eq!(event, Some(ManagerEvent::Sdo(SdoResult::Uploaded { len: 4 })));
    }
    println!("{UPLOADS} uploads");
}
