//! Runs simulated nodes in real time on a hub: one thread steps every node, so a full
//! 127-node bus costs one thread, not 127.

use crate::devices::SimNode;
use crate::hub::{Hub, Port};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How often the runner steps the nodes when the bus is quiet.
pub const STEP: Duration = Duration::from_micros(500);

/// Counters of a running simulation.
#[derive(Debug, Default)]
pub struct Stats {
    pub frames_in: AtomicU64,
    pub frames_out: AtomicU64,
    /// Steps that took longer than [`STEP`] (the simulation fell behind real time).
    pub late_steps: AtomicU64,
    pub steps: AtomicU64,
}

/// Nodes running on a background thread until [`Running::stop`] or drop.
#[derive(Debug)]
pub struct Running {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    pub stats: Arc<Stats>,
}

impl Running {
    pub fn stop(mut self) {
        self.halt();
    }

    fn halt(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        self.halt();
    }
}

/// Starts `nodes` on `hub`, each on its own port, stepped by one thread. Returns once every
/// node has booted and its boot-up message is on the bus, so a client that connects after
/// this never sees a boot-up it did not cause.
pub fn spawn(hub: &Hub, nodes: Vec<Box<dyn SimNode>>) -> Running {
    let ports: Vec<Port> = nodes.iter().map(|_| hub.attach()).collect();
    let stop = Arc::new(AtomicBool::new(false));
    let stats = Arc::new(Stats::default());
    let (stop2, stats2) = (stop.clone(), stats.clone());
    let (booted_tx, booted) = std::sync::mpsc::channel();
    let thread = std::thread::Builder::new().name("coforge-sim".into()).spawn(move || run(nodes, ports, &stop2, &stats2, &booted_tx)).ok();
    // If the thread could not start, there is nothing to wait for.
    if thread.is_some() {
        let _ = booted.recv();
    }
    Running { stop, thread, stats }
}

fn run(mut nodes: Vec<Box<dyn SimNode>>, ports: Vec<Port>, stop: &AtomicBool, stats: &Stats, booted: &std::sync::mpsc::Sender<()>) {
    let epoch = Instant::now();
    let now_us = || u64::try_from(epoch.elapsed().as_micros()).unwrap_or(u64::MAX);
    for (node, port) in nodes.iter_mut().zip(&ports) {
        node.start(now_us());
        while let Some(frame) = node.poll(now_us()) {
            port.send(frame);
        }
    }
    let _ = booted.send(());
    while !stop.load(Ordering::Relaxed) {
        let started = Instant::now();
        let mut busy = false;
        for (node, port) in nodes.iter_mut().zip(&ports) {
            while let Some(frame) = port.try_recv() {
                node.on_frame(&frame, now_us());
                stats.frames_in.fetch_add(1, Ordering::Relaxed);
                busy = true;
            }
            while let Some(frame) = node.poll(now_us()) {
                port.send(frame);
                stats.frames_out.fetch_add(1, Ordering::Relaxed);
                busy = true;
            }
        }
        stats.steps.fetch_add(1, Ordering::Relaxed);
        let took = started.elapsed();
        if took > STEP {
            stats.late_steps.fetch_add(1, Ordering::Relaxed);
        } else if !busy {
            std::thread::sleep(STEP - took);
        }
    }
}
