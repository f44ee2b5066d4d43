//! Runs simulated nodes in real time on a hub: one thread steps every node, so a full
//! 127-node bus costs one thread, not 127.

use crate::devices::SimDevice;
use crate::hub::{Hub, Port};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
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

/// Input for a running node other than CAN frames: its serial host, and the console.
#[derive(Debug)]
pub enum Input {
    /// A serial host connected to the node: what the node sends its host goes to `output`
    /// from now on (no longer to an earlier host).
    HostConnected { node: usize, output: Sender<Vec<u8>> },
    /// A byte from the node's serial host, received at `at`.
    HostByte { node: usize, byte: u8, at: Instant },
    /// A console command (fault injection); the outcome goes to `reply`.
    Control { node: usize, command: String, reply: Sender<Result<String, String>> },
}

/// Nodes running on a background thread until [`Running::stop`] or drop.
#[derive(Debug)]
pub struct Running {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    pub stats: Arc<Stats>,
    inputs: Sender<Input>,
}

impl Running {
    /// Where serial bytes and console commands for the nodes go.
    pub fn inputs(&self) -> Sender<Input> {
        self.inputs.clone()
    }

    /// Runs a console command on node `node` and waits for its outcome.
    pub fn control(&self, node: usize, command: &str) -> Result<String, String> {
        let (reply, outcome) = channel();
        self.inputs.send(Input::Control { node, command: command.to_string(), reply }).map_err(|_| "the simulation has stopped".to_string())?;
        outcome.recv().map_err(|_| "the simulation has stopped".to_string())?
    }

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
pub fn spawn(hub: &Hub, nodes: Vec<Box<dyn SimDevice>>) -> Running {
    let ports: Vec<Port> = nodes.iter().map(|_| hub.attach()).collect();
    let stop = Arc::new(AtomicBool::new(false));
    let stats = Arc::new(Stats::default());
    let (stop2, stats2) = (stop.clone(), stats.clone());
    let (booted_tx, booted) = channel();
    let (inputs, inputs_rx) = channel();
    let thread = std::thread::Builder::new().name("coforge-sim".into()).spawn(move || run(nodes, ports, &stop2, &stats2, &booted_tx, &inputs_rx)).ok();
    // If the thread could not start, there is nothing to wait for.
    if thread.is_some() {
        let _ = booted.recv();
    }
    Running { stop, thread, stats, inputs }
}

fn run(mut nodes: Vec<Box<dyn SimDevice>>, ports: Vec<Port>, stop: &AtomicBool, stats: &Stats, booted: &Sender<()>, inputs: &Receiver<Input>) {
    let epoch = Instant::now();
    // Serial bytes carry their arrival time, so a pause between them is seen as the host made it.
    let us_at = |at: Instant| u64::try_from(at.saturating_duration_since(epoch).as_micros()).unwrap_or(u64::MAX);
    let now_us = || us_at(Instant::now());
    for (node, port) in nodes.iter_mut().zip(&ports) {
        node.start(now_us());
        while let Some(frame) = node.poll(now_us()) {
            port.send(frame);
        }
    }
    let _ = booted.send(());
    // Where each node's serial output goes: its connected host, if any.
    let mut hosts: Vec<Option<Sender<Vec<u8>>>> = vec![None; nodes.len()];
    while !stop.load(Ordering::Relaxed) {
        let started = Instant::now();
        let mut busy = false;
        while let Ok(input) = inputs.try_recv() {
            busy = true;
            match input {
                Input::HostConnected { node, output } => {
                    if let Some(host) = hosts.get_mut(node) {
                        *host = Some(output);
                    }
                }
                Input::HostByte { node, byte, at } => {
                    if let Some(port) = nodes.get_mut(node).and_then(|n| n.host_port()) {
                        port.on_host_byte(byte, us_at(at) / 1000);
                    }
                }
                Input::Control { node, command, reply } => {
                    let outcome = nodes.get_mut(node).map_or_else(|| Err(format!("no node {node}")), |n| n.console(&command));
                    let _ = reply.send(outcome);
                }
            }
        }
        for ((node, port), host) in nodes.iter_mut().zip(&ports).zip(&mut hosts) {
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
            // Answers, late answers and unsolicited output alike; without a host they are lost,
            // as on an unconnected UART.
            let mut out = [0_u8; 64];
            while let Some(n) = node.host_port().map(|p| p.host_output(now_us() / 1000, &mut out)).filter(|&n| n > 0) {
                busy = true;
                if host.as_ref().is_some_and(|h| h.send(out.get(..n).unwrap_or(&[]).to_vec()).is_err()) {
                    *host = None;
                }
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
