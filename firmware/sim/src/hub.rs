//! A virtual CAN bus shared by in-process [`Port`]s and TCP SLCAN clients.
//!
//! Every frame a node sends reaches every other node, never its sender. All nodes see all
//! frames in the same order, as on a real bus: a send fans the frame out to every receive
//! queue under one lock, on the sender's own thread (no router thread, no thread per
//! in-process port).
//!
//! Each accepted TCP connection is a node speaking [SLCAN](crate::slcan), with `TCP_NODELAY`
//! and two threads: one reads lines, sends their frames on the bus and queues the Lawicel
//! answers; the other writes the node's queue (received frames and answers) to the socket,
//! batching what has accumulated. Open/close state is not enforced: a client's frames go on
//! the bus and bus frames go to the client whether or not it sent `O`, so raw `nc`-style tools
//! work as well as python-can (`can.Bus(interface='slcan', channel='socket://HOST:PORT')`).
//! Extended frames are acknowledged and dropped.
//!
//! Every node's receive queue holds at most [`PORT_QUEUE_CAPACITY`] items; past that, frames
//! for that node are dropped (counted by [`Hub::frames_dropped`]), like a CAN controller's
//! receive overrun, so a node that stops reading never stalls the bus or grows without bound.
//!
//! Dropping the [`Hub`] stops accepting, disconnects the TCP clients and joins the threads;
//! in-process ports keep working as a bus among themselves.
//!
//! ```
//! use coforge_sim::hub::Hub;
//! use coforge_stack::frame::CanFrame;
//! use std::time::Duration;
//!
//! let hub = Hub::bind("127.0.0.1:0")?; // SLCAN clients connect to hub.local_addr()
//! let (a, b) = (hub.attach(), hub.attach());
//! let sync = CanFrame::data(0x080, &[]).expect("an 11-bit id");
//! a.send(sync);
//! assert_eq!(b.recv_timeout(Duration::from_secs(1)), Some(sync));
//! assert_eq!(a.try_recv(), None); // never back to the sender
//! # Ok::<(), std::io::Error>(())
//! ```

use crate::slcan::{self, Command};
use coforge_stack::frame::CanFrame;
use std::io::{self, Read, Write};
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, Shutdown, SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering::Relaxed, Ordering::SeqCst};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

/// Receive queue depth of each node (about two seconds of a fully loaded 1 Mbit/s bus).
pub const PORT_QUEUE_CAPACITY: usize = 16_384;

/// Bytes a TCP client's writer gathers into one `write`.
const WRITE_BATCH: usize = 8 * 1024;

/// What a node's queue carries: bus frames, and for a TCP client the answers to its commands.
#[derive(Debug, Clone, Copy)]
enum Item {
    Frame(CanFrame),
    Reply(&'static [u8]),
}

#[derive(Debug)]
struct Node {
    id: u64,
    tx: Sender<Item>,
    queued: Arc<AtomicUsize>,
    /// Scratch for [`Bus::route`]: this node has room reserved for the frame being routed.
    reserved: bool,
}

/// Reserves room on a node's queue; `false` if it is full.
fn reserve(queued: &AtomicUsize) -> bool {
    if queued.fetch_add(1, Relaxed) >= PORT_QUEUE_CAPACITY {
        queued.fetch_sub(1, Relaxed);
        return false;
    }
    true
}

/// Pushes onto a node's queue unless it is full; `false` if dropped.
fn enqueue(tx: &Sender<Item>, queued: &AtomicUsize, item: Item) -> bool {
    if !reserve(queued) {
        return false;
    }
    if tx.send(item).is_err() {
        queued.fetch_sub(1, Relaxed);
        return false;
    }
    true
}

#[derive(Debug, Default)]
struct Bus {
    nodes: Mutex<Vec<Node>>,
    next_id: AtomicU64,
    routed: AtomicU64,
    delivered: AtomicU64,
    dropped: AtomicU64,
}

fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(PoisonError::into_inner)
}

impl Bus {
    /// A new node, and a second handle on its queue (for a TCP client's answers).
    fn attach(self: &Arc<Self>) -> (Port, Sender<Item>) {
        let (tx, rx) = mpsc::channel();
        let queued = Arc::new(AtomicUsize::new(0));
        let id = self.next_id.fetch_add(1, Relaxed);
        lock(&self.nodes).push(Node { id, tx: tx.clone(), queued: Arc::clone(&queued), reserved: false });
        (Port { bus: Arc::clone(self), id, rx, queued }, tx)
    }

    fn detach(&self, id: u64) {
        let mut nodes = lock(&self.nodes);
        if let Some(at) = nodes.iter().position(|n| n.id == id) {
            nodes.swap_remove(at);
        }
    }

    /// Fans `frame` out to every node but `from`, under the lock so that all nodes see one
    /// order. The counters are updated before any node can receive the frame.
    fn route(&self, from: u64, frame: CanFrame) {
        let mut nodes = lock(&self.nodes);
        let (mut delivered, mut dropped) = (0, 0);
        for node in nodes.iter_mut() {
            node.reserved = node.id != from && reserve(&node.queued);
            if node.reserved {
                delivered += 1;
            } else if node.id != from {
                dropped += 1;
            }
        }
        self.routed.fetch_add(1, Relaxed);
        self.delivered.fetch_add(delivered, Relaxed);
        self.dropped.fetch_add(dropped, Relaxed);
        for node in nodes.iter().filter(|n| n.reserved) {
            // A listed node still has its receiver (a port detaches before dropping it); be safe.
            if node.tx.send(Item::Frame(frame)).is_err() {
                node.queued.fetch_sub(1, Relaxed);
                self.delivered.fetch_sub(1, Relaxed);
            }
        }
    }
}

/// An in-process node on the bus. Dropping it detaches it.
///
/// `Send` but not `Sync`: one thread owns a port; a simulator stepping many nodes on one
/// thread polls each with [`try_recv`](Port::try_recv).
#[derive(Debug)]
pub struct Port {
    bus: Arc<Bus>,
    id: u64,
    rx: Receiver<Item>,
    queued: Arc<AtomicUsize>,
}

impl Port {
    /// Puts `frame` on the bus: every other node receives it, in send order. Never blocks on
    /// receivers (a full receive queue drops the frame for that receiver only).
    pub fn send(&self, frame: CanFrame) {
        self.bus.route(self.id, frame);
    }

    /// The next received frame, if one is waiting.
    pub fn try_recv(&self) -> Option<CanFrame> {
        loop {
            match self.take(self.rx.try_recv().ok()?) {
                Item::Frame(frame) => return Some(frame),
                Item::Reply(_) => continue,
            }
        }
    }

    /// The next received frame, waiting at most `timeout`.
    pub fn recv_timeout(&self, timeout: Duration) -> Option<CanFrame> {
        let deadline = Instant::now().checked_add(timeout);
        loop {
            let item = match deadline {
                Some(deadline) => self.rx.recv_timeout(deadline.saturating_duration_since(Instant::now())),
                None => self.rx.recv().map_err(|_| RecvTimeoutError::Disconnected),
            };
            match self.take(item.ok()?) {
                Item::Frame(frame) => return Some(frame),
                Item::Reply(_) => continue,
            }
        }
    }

    /// Frames waiting in this port's receive queue.
    pub fn pending(&self) -> usize {
        self.queued.load(Relaxed)
    }

    /// Blocks for the next item; `None` once the port is detached from the bus (its sender gone).
    fn recv_item(&self) -> Option<Item> {
        self.rx.recv().ok().map(|item| self.take(item))
    }

    fn try_recv_item(&self) -> Option<Item> {
        self.rx.try_recv().ok().map(|item| self.take(item))
    }

    fn take(&self, item: Item) -> Item {
        self.queued.fetch_sub(1, Relaxed);
        item
    }
}

impl Drop for Port {
    fn drop(&mut self) {
        self.bus.detach(self.id);
    }
}

/// The bus plus a TCP listener for SLCAN clients.
#[derive(Debug)]
pub struct Hub {
    bus: Arc<Bus>,
    local_addr: SocketAddr,
    stop: Arc<AtomicBool>,
    listener: Option<JoinHandle<()>>,
    /// SLCAN adapters the hub connected to itself ([`Hub::connect`]).
    adapters: Mutex<Vec<Client>>,
}

impl Hub {
    /// Binds the SLCAN listener (port 0 picks a free one, see [`local_addr`](Hub::local_addr))
    /// and starts accepting clients.
    pub fn bind(addr: impl ToSocketAddrs) -> io::Result<Hub> {
        let listener = TcpListener::bind(addr)?;
        let local_addr = listener.local_addr()?;
        let bus = Arc::new(Bus::default());
        let stop = Arc::new(AtomicBool::new(false));
        let accept = {
            let (bus, stop) = (Arc::clone(&bus), Arc::clone(&stop));
            thread::Builder::new().name(format!("slcan-hub {local_addr}")).spawn(move || accept_loop(&listener, &bus, &stop))?
        };
        Ok(Hub { bus, local_addr, stop, listener: Some(accept), adapters: Mutex::new(Vec::new()) })
    }

    /// The address the listener is bound to.
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// Connects to an SLCAN adapter listening at `addr` (a firmware image in QEMU whose UART is
    /// a TCP server) and puts its bus on this one: frames on the hub go to the adapter as
    /// SLCAN lines, frame lines from the adapter go on the hub. The hub is the adapter's host,
    /// so the adapter's answers (`z`, `\r`, BELL) are read and dropped, never answered.
    pub fn connect(&self, addr: impl ToSocketAddrs) -> io::Result<()> {
        let client = serve(TcpStream::connect(addr)?, &self.bus, Role::Host)?;
        lock(&self.adapters).push(client);
        Ok(())
    }

    /// A new in-process node.
    pub fn attach(&self) -> Port {
        self.bus.attach().0
    }

    /// Nodes on the bus: attached ports plus connected TCP clients.
    pub fn node_count(&self) -> usize {
        lock(&self.bus.nodes).len()
    }

    /// Frames sent on the bus, by ports and TCP clients together (each counted once, however
    /// many nodes receive it).
    pub fn frames_routed(&self) -> u64 {
        self.bus.routed.load(Relaxed)
    }

    /// Frame deliveries into receive queues: about `frames_routed() * (nodes - 1)`.
    pub fn frames_delivered(&self) -> u64 {
        self.bus.delivered.load(Relaxed)
    }

    /// Deliveries dropped because a receive queue was full.
    pub fn frames_dropped(&self) -> u64 {
        self.bus.dropped.load(Relaxed)
    }
}

impl Drop for Hub {
    fn drop(&mut self) {
        self.stop.store(true, SeqCst);
        for adapter in lock(&self.adapters).drain(..) {
            let _ = adapter.stream.shutdown(Shutdown::Both);
            for thread in adapter.threads {
                let _ = thread.join();
            }
        }
        // Wake the blocking accept with a connection of our own.
        let mut wake = self.local_addr;
        if wake.ip().is_unspecified() {
            wake.set_ip(match wake.ip() {
                IpAddr::V4(_) => IpAddr::V4(Ipv4Addr::LOCALHOST),
                IpAddr::V6(_) => IpAddr::V6(Ipv6Addr::LOCALHOST),
            });
        }
        let woke = TcpStream::connect_timeout(&wake, Duration::from_secs(2)).is_ok();
        if let Some(accept) = self.listener.take()
            && woke
        {
            let _ = accept.join();
        }
    }
}

/// Which side of the SLCAN link the hub is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    /// The hub is the adapter: it answers every command line (`z`, `\r`, BELL).
    Adapter,
    /// The hub is the host of an adapter: it takes frame lines and answers nothing.
    Host,
}

/// A connected client: its socket (to shut it down) and its two threads.
#[derive(Debug)]
struct Client {
    stream: TcpStream,
    threads: [JoinHandle<()>; 2],
}

fn accept_loop(listener: &TcpListener, bus: &Arc<Bus>, stop: &AtomicBool) {
    let mut clients: Vec<Client> = Vec::new();
    for conn in listener.incoming() {
        if stop.load(SeqCst) {
            break;
        }
        match conn {
            Ok(stream) => {
                clients.retain(|c| !c.threads.iter().all(JoinHandle::is_finished));
                if let Ok(client) = serve(stream, bus, Role::Adapter) {
                    clients.push(client);
                }
            }
            // Out of descriptors and the like: let them free up instead of spinning.
            Err(_) => thread::sleep(Duration::from_millis(10)),
        }
    }
    for client in &clients {
        let _ = client.stream.shutdown(Shutdown::Both);
    }
    for client in clients {
        for thread in client.threads {
            let _ = thread.join();
        }
    }
}

fn serve(stream: TcpStream, bus: &Arc<Bus>, role: Role) -> io::Result<Client> {
    stream.set_nodelay(true)?;
    let peer = stream.peer_addr()?;
    let (read_half, write_half) = (stream.try_clone()?, stream.try_clone()?);
    // The reader queues answers on the client's own queue, so it never blocks on the socket.
    let (port, reply_tx) = bus.attach();
    let (node, queued) = (port.id, Arc::clone(&port.queued));
    let writer = thread::Builder::new().name(format!("slcan-tx {peer}")).spawn(move || write_loop(&port, write_half))?;
    let reader = {
        let bus = Arc::clone(bus);
        thread::Builder::new().name(format!("slcan-rx {peer}")).spawn(move || read_loop(read_half, &bus, node, role, &reply_tx, &queued))
    };
    match reader {
        Ok(reader) => Ok(Client { stream, threads: [writer, reader] }),
        Err(err) => {
            bus.detach(node);
            let _ = stream.shutdown(Shutdown::Both);
            Err(err)
        }
    }
}

fn read_loop(mut stream: TcpStream, bus: &Bus, node: u64, role: Role, replies: &Sender<Item>, queued: &AtomicUsize) {
    let mut decoder = slcan::Decoder::new();
    let mut buf = [0u8; 4096];
    loop {
        let n = match stream.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(err) if err.kind() == io::ErrorKind::Interrupted => continue,
            Err(_) => break,
        };
        let bytes = buf.get(..n).unwrap_or_default();
        match role {
            Role::Host => decoder.push_from_adapter(bytes),
            Role::Adapter => decoder.push(bytes),
        }
        for cmd in decoder.by_ref() {
            if let Command::Frame(frame) = cmd {
                bus.route(node, frame);
            }
            if role == Role::Adapter {
                enqueue(replies, queued, Item::Reply(slcan::reply(&cmd)));
            }
        }
    }
    // Disconnected: leave the bus; the writer sees its queue close and ends.
    bus.detach(node);
    let _ = stream.shutdown(Shutdown::Both);
}

fn write_loop(port: &Port, mut stream: TcpStream) {
    let mut buf = Vec::with_capacity(WRITE_BATCH + 64);
    let mut next = port.recv_item();
    while let Some(item) = next {
        buf.clear();
        let mut item = Some(item);
        while let Some(it) = item {
            match it {
                Item::Frame(frame) => slcan::encode(&frame, &mut buf),
                Item::Reply(reply) => buf.extend_from_slice(reply),
            }
            item = if buf.len() < WRITE_BATCH { port.try_recv_item() } else { None };
        }
        if stream.write_all(&buf).is_err() {
            // Wake the reader, which detaches the node.
            let _ = stream.shutdown(Shutdown::Both);
            break;
        }
        next = port.recv_item();
    }
}
