//! Hub fan-out throughput: `cargo bench -p coforge-sim --bench fanout`.
//!
//! 1. Saturation: one thread owns N ports, sends round-robin from all of them and drains every
//!    port after each burst (how a simulator stepping all nodes on one thread uses the hub).
//! 2. A full bus: 127 ports split over 2 threads, paced at 9 000 frames/s (1 Mbit/s of 8-byte
//!    frames), each frame delivered to the 126 others; reports the CPU it took (Linux only).
//! 3. The same load with one thread per node blocking in `recv_timeout`.

use coforge_sim::hub::{Hub, Port};
use coforge_stack::frame::CanFrame;
use std::time::{Duration, Instant};

fn frame(n: u64) -> CanFrame {
    let id = 0x180 + (n % 0x7F) as u16;
    CanFrame::data(id, &n.to_le_bytes()).unwrap_or(CanFrame { id, rtr: false, dlc: 0, data: [0; 8] })
}

fn drain(ports: &[Port]) -> u64 {
    let mut n = 0;
    for port in ports {
        while port.try_recv().is_some() {
            n += 1;
        }
    }
    n
}

fn saturation(nodes: usize, frames: u64) {
    let Ok(hub) = Hub::bind("127.0.0.1:0") else { return eprintln!("bind failed") };
    let ports: Vec<Port> = (0..nodes).map(|_| hub.attach()).collect();
    let start = Instant::now();
    let mut received = 0;
    for n in 0..frames {
        if let Some(port) = ports.get(n as usize % nodes) {
            port.send(frame(n));
        }
        if n % 64 == 63 {
            received += drain(&ports);
        }
    }
    received += drain(&ports);
    let secs = start.elapsed().as_secs_f64();
    println!(
        "saturation {nodes:>3} nodes: {:>9.0} frames/s, {:>10.0} deliveries/s ({received} delivered, {} dropped)",
        frames as f64 / secs,
        received as f64 / secs,
        hub.frames_dropped()
    );
}

/// User + system CPU seconds of this process, from /proc (Linux); `None` elsewhere.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn full_bus(nodes: usize, rate: u64, duration: Duration) {
    let Ok(hub) = Hub::bind("127.0.0.1:0") else { return eprintln!("bind failed") };
    let ports: Vec<Port> = (0..nodes).map(|_| hub.attach()).collect();
    let mut halves: [Vec<Port>; 2] = [Vec::new(), Vec::new()];
    for (i, port) in ports.into_iter().enumerate() {
        if let Some(half) = halves.get_mut(i % 2) {
            half.push(port);
        }
    }
    let cpu0 = cpu_seconds();
    let start = Instant::now();
    let received: u64 = std::thread::scope(|s| {
        let workers: Vec<_> = halves
            .into_iter()
            .map(|ports| {
                s.spawn(move || {
                    let ports = ports.as_slice();
                    let (mut sent, mut received) = (0u64, 0u64);
                    let per_thread = rate / 2;
                    while start.elapsed() < duration {
                        let due = (start.elapsed().as_secs_f64() * per_thread as f64) as u64;
                        while sent < due {
                            if let Some(port) = ports.get(sent as usize % ports.len()) {
                                port.send(frame(sent));
                            }
                            sent += 1;
                        }
                        received += drain(ports);
                        std::thread::sleep(Duration::from_millis(1));
                    }
                    received + drain(ports)
                })
            })
            .collect();
        workers.into_iter().map(|w| w.join().unwrap_or(0)).sum()
    });
    let wall = start.elapsed().as_secs_f64();
    let cpu = cpu0.zip(cpu_seconds()).map(|(a, b)| format!("{:.0}% of one core", (b - a) / wall * 100.0)).unwrap_or_else(|| "cpu n/a".into());
    println!(
        "full bus   {nodes:>3} nodes at {rate} frames/s for {:.1} s: {} routed, {:.0} deliveries/s, {} dropped, {cpu}",
        wall,
        hub.frames_routed(),
        received as f64 / wall,
        hub.frames_dropped()
    );
}

/// The same load with a thread per node blocking in `recv_timeout`: every frame wakes 126
/// threads, the cost a one-thread-per-node simulator pays.
fn thread_per_node(nodes: usize, rate: u64, duration: Duration) {
    let Ok(hub) = Hub::bind("127.0.0.1:0") else { return eprintln!("bind failed") };
    let ports: Vec<Port> = (0..nodes).map(|_| hub.attach()).collect();
    let cpu0 = cpu_seconds();
    let start = Instant::now();
    let received: u64 = std::thread::scope(|s| {
        let workers: Vec<_> = ports
            .into_iter()
            .enumerate()
            .map(|(i, port)| {
                s.spawn(move || {
                    let (mut sent, mut received) = (0u64, 0u64);
                    let per_node = rate as f64 / nodes as f64;
                    while start.elapsed() < duration {
                        let due = (start.elapsed().as_secs_f64() * per_node) as u64;
                        while sent < due {
                            port.send(frame(sent * nodes as u64 + i as u64));
                            sent += 1;
                        }
                        if port.recv_timeout(Duration::from_millis(1)).is_some() {
                            received += 1;
                        }
                    }
                    received + std::iter::from_fn(|| port.try_recv()).count() as u64
                })
            })
            .collect();
        workers.into_iter().map(|w| w.join().unwrap_or(0)).sum()
    });
    let wall = start.elapsed().as_secs_f64();
    let cpu = cpu0.zip(cpu_seconds()).map(|(a, b)| format!("{:.0}% of one core", (b - a) / wall * 100.0)).unwrap_or_else(|| "cpu n/a".into());
    println!(
        "per-thread {nodes:>3} nodes at {rate} frames/s for {:.1} s: {} routed, {:.0} deliveries/s, {} dropped, {cpu}",
        wall,
        hub.frames_routed(),
        received as f64 / wall,
        hub.frames_dropped()
    );
}

fn main() {
    // `cargo test --all-targets` runs benches in test mode with `--bench` absent: keep it short.
    let quick = !std::env::args().any(|a| a == "--bench");
    let frames = if quick { 2_000 } else { 200_000 };
    for nodes in [2, 16, 64, 127] {
        saturation(nodes, frames);
    }
    let duration = Duration::from_millis(if quick { 200 } else { 3_000 });
    full_bus(127, 9_000, duration);
    thread_per_node(127, 9_000, duration);
}
