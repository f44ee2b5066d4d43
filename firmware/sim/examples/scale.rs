//! `scale [nodes] [seconds]`: how many simulated nodes the hub and runner carry in real time.
//! Every node sends a heartbeat every 16 ms (127 nodes: about 7 900 frames/s, the frame rate of
//! a loaded 1 Mbit/s bus), and a master port does SDO uploads round-robin; the example reports
//! the heartbeat rate received, SDO answers and latency, and steps that fell behind.

use coforge_sim::devices::{DeviceKind, StoreAt};
use coforge_sim::hub::Hub;
use coforge_stack::frame::CanFrame;
use std::time::{Duration, Instant};

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let count: u8 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(127);
    let seconds: u64 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(10);
    let kind = DeviceKind::find("co401gw1")?;
    let mut nodes = Vec::new();
    for id in 1..=count {
        nodes.push(kind.create(None, id, &StoreAt::Memory)?);
    }
    let hub = Hub::bind("127.0.0.1:0").map_err(|e| e.to_string())?;
    let master = hub.attach();
    let running = coforge_sim::runner::spawn(&hub, nodes);
    // Heartbeat producer time 16 ms, by SDO as a master would set it.
    for id in 1..=u16::from(count) {
        if let Some(f) = CanFrame::data(0x600 + id, &[0x2B, 0x17, 0x10, 0, 16, 0, 0, 0]) {
            master.send(f);
        }
    }
    std::thread::sleep(Duration::from_millis(200));
    while master.try_recv().is_some() {}
    let start = Instant::now();
    let (mut heartbeats, mut answers, mut asked) = (0_u64, 0_u64, 0_u64);
    let mut worst = Duration::ZERO;
    let mut next_sdo = start;
    let mut pending: Option<(u16, Instant)> = None;
    while start.elapsed() < Duration::from_secs(seconds) {
        if pending.is_none() && Instant::now() >= next_sdo {
            let id = (asked % u64::from(count)) as u16 + 1;
            if let Some(f) = CanFrame::data(0x600 + id, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]) {
                master.send(f);
            }
            pending = Some((id, Instant::now()));
            asked += 1;
            next_sdo += Duration::from_millis(1);
        }
        let Some(f) = master.recv_timeout(Duration::from_micros(200)) else { continue };
        if (0x701..=0x77F).contains(&f.id) {
            heartbeats += 1;
        }
        if let Some((id, t)) = pending
            && f.id == 0x580 + id
        {
            answers += 1;
            worst = worst.max(t.elapsed());
            pending = None;
        }
    }
    let secs = start.elapsed().as_secs_f64();
    let stats = &running.stats;
    use std::sync::atomic::Ordering::Relaxed;
    println!("{count} nodes for {secs:.1} s:");
    println!("  heartbeats received {:.0}/s (expected {:.0}/s)", heartbeats as f64 / secs, f64::from(count) * 1000.0 / 16.0);
    println!("  SDO uploads answered {answers} of {asked}, worst latency {:.2} ms", worst.as_secs_f64() * 1000.0);
    println!("  runner steps {}, late {}; hub routed {} frames", stats.steps.load(Relaxed), stats.late_steps.load(Relaxed), hub.frames_routed());
    running.stop();
    Ok(())
}
