//! A deterministic in-process CAN bus on a virtual clock, for tests: no threads, no sockets.
//! Every frame a node or the test sends reaches every other party; time only moves when the
//! test says so.

use crate::devices::SimDevice;
use coforge_stack::frame::CanFrame;

/// Nodes plus one test "master" on a virtual bus.
pub struct VirtualBus {
    pub nodes: Vec<Box<dyn SimDevice>>,
    now_us: u64,
    /// Frames the nodes sent that the master has not taken yet.
    to_master: std::collections::VecDeque<CanFrame>,
    /// Every frame on the bus, in order, with its time.
    pub log: Vec<(u64, CanFrame)>,
}

impl std::fmt::Debug for VirtualBus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VirtualBus").field("nodes", &self.nodes.len()).field("now_us", &self.now_us).finish()
    }
}

impl VirtualBus {
    /// Starts every node at time 0 (their boot-up messages go on the bus).
    pub fn new(nodes: Vec<Box<dyn SimDevice>>) -> Self {
        let mut bus = VirtualBus { nodes, now_us: 0, to_master: Default::default(), log: Vec::new() };
        for n in &mut bus.nodes {
            n.start(0);
        }
        bus.settle();
        bus
    }

    pub fn now_us(&self) -> u64 {
        self.now_us
    }

    /// The master sends a frame; nodes react until the bus is quiet.
    pub fn send(&mut self, frame: CanFrame) {
        self.log.push((self.now_us, frame));
        self.deliver(None, &frame);
        self.settle();
    }

    /// Advances the clock in 1 ms steps (nodes poll at every step).
    pub fn advance_ms(&mut self, ms: u64) {
        for _ in 0..ms {
            self.now_us += 1000;
            self.settle();
        }
    }

    /// The next frame a node sent to the master.
    pub fn recv(&mut self) -> Option<CanFrame> {
        self.to_master.pop_front()
    }

    /// Everything the nodes sent since the last call.
    pub fn drain(&mut self) -> Vec<CanFrame> {
        self.to_master.drain(..).collect()
    }

    fn deliver(&mut self, from: Option<usize>, frame: &CanFrame) {
        let now = self.now_us;
        for (i, n) in self.nodes.iter_mut().enumerate() {
            if Some(i) != from {
                n.on_frame(frame, now);
            }
        }
    }

    /// Polls every node until none has anything left to send (also after a test acted on a
    /// node directly, through its console or its host port).
    pub fn settle(&mut self) {
        loop {
            let mut sent = false;
            for i in 0..self.nodes.len() {
                let now = self.now_us;
                let Some(frame) = self.nodes.get_mut(i).and_then(|n| n.poll(now)) else { continue };
                sent = true;
                self.log.push((now, frame));
                self.to_master.push_back(frame);
                self.deliver(Some(i), &frame);
            }
            if !sent {
                return;
            }
        }
    }
}
