//! A simulated device's serial host interface on a TCP port (one client at a time), so a host
//! program or pyserial (`serial_for_url("socket://127.0.0.1:PORT")`) talks to it as to the
//! module's RS232 pins. Bytes go to the device's [`HostPort`] with their arrival time; the
//! runner polls the device's output and sends it to the client whenever there is some.
//!
//! [`HostPort`]: coforge_stack::device::HostPort

use crate::runner::Input;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::mpsc::{Sender, channel};
use std::time::Instant;

/// A listening serial port.
#[derive(Debug)]
pub struct SerialPort {
    addr: SocketAddr,
}

impl SerialPort {
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }
}

/// Listens on `addr` for the serial host of node `node` of a running simulation.
pub fn serve(addr: impl ToSocketAddrs, node: usize, inputs: Sender<Input>) -> std::io::Result<SerialPort> {
    let listener = TcpListener::bind(addr)?;
    let addr = listener.local_addr()?;
    std::thread::Builder::new().name("coforge-serial".into()).spawn(move || {
        for stream in listener.incoming().flatten() {
            // One client at a time: the next connects when this one hangs up.
            client(stream, node, &inputs);
        }
    })?;
    Ok(SerialPort { addr })
}

fn client(stream: TcpStream, node: usize, inputs: &Sender<Input>) {
    let _ = stream.set_nodelay(true);
    let Ok(mut writer) = stream.try_clone() else { return };
    let (output, bytes) = channel::<Vec<u8>>();
    if inputs.send(Input::HostConnected { node, output }).is_err() {
        return;
    }
    // Ends when the client is gone, or when the runner drops `output` (the next client
    // connected, the simulation stopped).
    let _ = std::thread::Builder::new().name("coforge-serial-out".into()).spawn(move || {
        for chunk in bytes {
            if writer.write_all(&chunk).is_err() {
                break;
            }
        }
    });
    let mut reader = stream;
    let mut buf = [0_u8; 64];
    while let Ok(n) = reader.read(&mut buf) {
        if n == 0 {
            break;
        }
        let at = Instant::now();
        for &byte in buf.get(..n).unwrap_or(&[]) {
            if inputs.send(Input::HostByte { node, byte, at }).is_err() {
                return;
            }
        }
    }
}
