#![allow(clippy::unwrap_used, clippy::expect_used)]
//! CO401Memory1 in the real-time runner: its serial host on a TCP port, the console's fault
//! injection, and the same memory seen from the bus side.

use coforge_sim::devices::{DeviceKind, StoreAt};
use coforge_sim::hub::Hub;
use coforge_stack::od::Side;
use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

/// Sends `request` and reads exactly `len` answer bytes.
fn exchange(stream: &mut TcpStream, request: &[u8], len: usize) -> Vec<u8> {
    stream.write_all(request).unwrap();
    let mut answer = vec![0; len];
    stream.read_exact(&mut answer).unwrap();
    answer
}

#[test]
fn the_serial_host_and_the_console_reach_the_running_module() {
    let hub = Hub::bind("127.0.0.1:0").unwrap();
    let mut node = DeviceKind::find("co401memory1").unwrap().create(None, 9, &StoreAt::Memory).unwrap();
    assert!(node.host_port().is_some());
    let running = coforge_sim::runner::spawn(&hub, vec![node]);
    let port = coforge_sim::serial::serve("127.0.0.1:0", 0, running.inputs()).unwrap();
    let mut host = TcpStream::connect(port.local_addr()).unwrap();
    host.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    host.set_nodelay(true).unwrap();

    assert_eq!(exchange(&mut host, &[0x00], 5), [0x04, 0x40, 0x40, 0x03, 0x00]);
    assert_eq!(exchange(&mut host, &[0x44, 0x07, 0x50, 0x02, 0x99], 2), [0x41, 0x01]);
    assert_eq!(exchange(&mut host, &[0x33, 0x07, 0x50, 0x02], 3), [0x32, 0x01, 0x99]);

    // A frame cut short, a pause longer than the 100 ms resync time, then a whole command.
    host.write_all(&[0x44, 0x07]).unwrap();
    let paused = Instant::now();
    std::thread::sleep(Duration::from_millis(250));
    assert!(paused.elapsed() >= Duration::from_millis(100));
    assert_eq!(exchange(&mut host, &[0x33, 0x07, 0x50, 0x02], 3), [0x32, 0x01, 0x99]);

    // The console: a low supply refuses writes; corruption of one bank is repaired on read.
    assert_eq!(running.control(0, "supply 14000").unwrap(), "supply 14000 mV");
    assert_eq!(exchange(&mut host, &[0x44, 0x07, 0x50, 0x02, 0x11], 2), [0x41, 0x00]);
    assert!(running.control(0, "supply 24000").is_ok());
    let offset = 7 * 132 + 1;
    assert!(running.control(0, &format!("corrupt 2 {offset} 0x98")).unwrap().ends_with("0x99 -> 0x98"));
    assert_eq!(exchange(&mut host, &[0x33, 0x07, 0x50, 0x02], 3), [0x32, 0x01, 0x99]);
    assert_eq!(exchange(&mut host, &[0x00], 5)[2], 0x40 | 0x30, "bank 2: cleared, checksum error, overwritten");
    assert!(running.control(0, "corrupt 3 0 0").is_err());
    assert!(running.control(0, "supply lots").is_err());
    drop(running);
}

#[test]
fn banks_kept_in_files_survive_a_restart_of_the_simulated_module() {
    let scratch = tempfile::tempdir().unwrap();
    let dir = scratch.path();
    let store = StoreAt::File(dir.join("banks"));
    let kind = DeviceKind::find("co401memory1").unwrap();
    let mut node = kind.create(None, 3, &store).unwrap();
    node.start(0);
    node.node_mut().write(0x5010, 0x80, &[0x5A], Side::Bus).unwrap();
    drop(node);
    assert!(dir.join("banks.bank1").exists() && dir.join("banks.bank2").exists());
    let mut node = kind.create(None, 3, &store).unwrap();
    node.start(0);
    let mut value = [0];
    node.node_mut().read(0x5010, 0x80, 0, &mut value, Side::Device).unwrap();
    assert_eq!(value, [0x5A]);
    node.node_mut().read(0x6000, 1, 0, &mut value, Side::Device).unwrap();
    assert_eq!(value, [0], "a clean restart reports nothing");
}
