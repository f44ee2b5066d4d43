#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! The runner's serial port goes through the device contract's `HostPort`: what a device
//! sends its host unasked, or long after the byte that asked, reaches the TCP client too.

use coforge_sim::app::RamApp;
use coforge_sim::devices::Console;
use coforge_sim::hub::Hub;
use coforge_stack::device::{Device, HostPort, NodeAccess};
use coforge_stack::frame::CanFrame;
use coforge_stack::leds::Leds;
use coforge_stack::node::{BusState, NodeEvent};
use coforge_stack::store::NoStore;
use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

/// Unasked 0xAA every 100 ms; every byte from the host echoed 50 ms late.
struct Beacon {
    node: co401gw1::Node<RamApp, NoStore>,
    next_beacon_ms: u64,
    echo: Option<(u8, u64)>,
}

impl Device for Beacon {
    fn start(&mut self, now_us: u64) {
        self.node.start(now_us);
    }
    fn on_frame(&mut self, frame: &CanFrame, now_us: u64) {
        self.node.on_frame(frame, now_us);
    }
    fn poll(&mut self, now_us: u64) -> Option<CanFrame> {
        self.node.poll(now_us)
    }
    fn on_bus_state(&mut self, bus: BusState, now_us: u64) {
        self.node.on_bus_state(bus, now_us);
    }
    fn take_event(&mut self) -> Option<NodeEvent> {
        self.node.take_event()
    }
    fn leds(&self) -> Leds {
        self.node.leds()
    }
    fn node(&self) -> &dyn NodeAccess {
        &self.node
    }
    fn node_mut(&mut self) -> &mut dyn NodeAccess {
        &mut self.node
    }
    fn host_port(&mut self) -> Option<&mut dyn HostPort> {
        Some(self)
    }
}

impl HostPort for Beacon {
    fn on_host_byte(&mut self, byte: u8, now_ms: u64) {
        self.echo = Some((byte, now_ms + 50));
    }
    fn host_output(&mut self, now_ms: u64, out: &mut [u8]) -> usize {
        if let Some((byte, due)) = self.echo
            && now_ms >= due
        {
            self.echo = None;
            out[0] = byte;
            return 1;
        }
        if now_ms >= self.next_beacon_ms {
            self.next_beacon_ms = now_ms + 100;
            out[0] = 0xAA;
            return 1;
        }
        0
    }
}

impl Console for Beacon {}

#[test]
fn unasked_and_late_output_reaches_the_client() {
    let od = co401gw1::Od::new(co401gw1::Mode::ALL[0], 5, RamApp::default());
    let node = coforge_stack::node::Node::new(od, NoStore, co401gw1::node_config(5));
    let beacon = Beacon { node, next_beacon_ms: 0, echo: None };
    let hub = Hub::bind("127.0.0.1:0").unwrap();
    let running = coforge_sim::runner::spawn(&hub, vec![Box::new(beacon)]);
    let port = coforge_sim::serial::serve("127.0.0.1:0", 0, running.inputs()).unwrap();
    let mut host = TcpStream::connect(port.local_addr()).unwrap();
    host.set_read_timeout(Some(Duration::from_secs(5))).unwrap();

    let mut byte = [0];
    host.read_exact(&mut byte).unwrap();
    assert_eq!(byte, [0xAA], "unasked output, without a byte from the host");

    host.write_all(&[0x42]).unwrap();
    let sent = Instant::now();
    loop {
        host.read_exact(&mut byte).unwrap();
        if byte != [0xAA] {
            break;
        }
    }
    assert_eq!(byte, [0x42]);
    assert!(sent.elapsed() >= Duration::from_millis(45), "the echo came late, polled without a new byte");
    drop(running);
}
