//! Manual check with real SLCAN tools: a hub whose one in-process node echoes every frame
//! back with id + 1 (a remote frame stays remote).
//!
//! `cargo run -p coforge-sim --example hub_echo -- 127.0.0.1:28000`, then for instance
//! `can.Bus(interface='slcan', channel='socket://127.0.0.1:28000', sleep_after_open=0)`.
//! Stops after the optional second argument's seconds (default: runs until killed).

use coforge_sim::hub::Hub;
use coforge_stack::frame::CanFrame;
use std::time::{Duration, Instant};

fn main() -> std::io::Result<()> {
    let mut args = std::env::args().skip(1);
    let addr = args.next().unwrap_or_else(|| "127.0.0.1:28000".into());
    let limit = args.next().and_then(|s| s.parse::<u64>().ok()).map(Duration::from_secs);
    let hub = Hub::bind(addr.as_str())?;
    let port = hub.attach();
    println!("hub_echo listening on {}", hub.local_addr());
    let start = Instant::now();
    while limit.is_none_or(|limit| start.elapsed() < limit) {
        let Some(frame) = port.recv_timeout(Duration::from_millis(100)) else { continue };
        let id = (frame.id + 1) & 0x7FF;
        let echo = if frame.rtr { CanFrame::remote(id, frame.dlc) } else { CanFrame::data(id, frame.payload()) };
        println!("{frame:?} -> {echo:?}");
        if let Some(echo) = echo {
            port.send(echo);
        }
    }
    println!("routed {} frames", hub.frames_routed());
    Ok(())
}
