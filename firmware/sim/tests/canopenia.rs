#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! CANopenIA's remote-access engine on the virtual bus, its host talking to it byte by byte:
//! W/R on the local dictionary, S/U through the manager to a CO401Memory1 module, busy, the
//! error bits, answers in the form of their command's start byte, resync after garbage, and
//! the indications D (writes from the bus, node statuses, scanned TPDOs).

use canopenia::serial::{self, DeviceToHost, HostToDevice};
use coforge_link::Deframer;
use coforge_link::start_crc::reencode;
use coforge_sim::devices::{DeviceKind, StoreAt};
use coforge_sim::vbus::VirtualBus;
use coforge_stack::frame::CanFrame;

const IA: u8 = 1;
const MEM: u8 = 2;

/// A decoded frame from the device, owned: (start byte, message as its Debug text).
#[derive(Debug, Clone, PartialEq)]
enum Out {
    W { index: u16, sub: u8, err: u16 },
    R { index: u16, sub: u8, err: u16, data: Vec<u8> },
    S { node: u8, index: u16, sub: u8, err: u16 },
    U { node: u8, index: u16, sub: u8, err: u16, data: Vec<u8> },
    D { node: u8, index: u16, sub: u8, data: Vec<u8> },
}

struct Net {
    bus: VirtualBus,
    decoder: serial::Decoder,
    /// Every frame the host received: its start byte and what it says.
    received: Vec<(u8, Out)>,
    /// Every byte the host received, as sent.
    raw: Vec<u8>,
}

impl Net {
    fn new(nodes: &[(&str, u8)]) -> Self {
        let nodes = nodes.iter().map(|(name, id)| DeviceKind::find(name).unwrap().create(None, *id, &StoreAt::Memory).unwrap()).collect();
        let mut net = Net { bus: VirtualBus::new(nodes), decoder: serial::decoder(), received: Vec::new(), raw: Vec::new() };
        net.collect();
        net
    }

    fn ms(&self) -> u64 {
        self.bus.now_us() / 1000
    }

    /// Bytes from the host, all at once, then the bus settles.
    fn host_bytes(&mut self, bytes: &[u8]) {
        let now = self.ms();
        let port = self.bus.nodes[0].host_port().unwrap();
        for &b in bytes {
            port.on_host_byte(b, now);
        }
        self.bus.settle();
        self.collect();
    }

    fn command(&mut self, command: HostToDevice<'_>) {
        self.host_bytes(&frame(&command, 0x11));
    }

    fn run_ms(&mut self, ms: u64) {
        for _ in 0..ms {
            self.bus.advance_ms(1);
            self.collect();
        }
    }

    fn collect(&mut self) {
        let now = self.ms();
        let mut buf = [0_u8; 512];
        let n = self.bus.nodes[0].host_port().unwrap().host_output(now, &mut buf);
        self.raw.extend_from_slice(&buf[..n]);
        for &b in &buf[..n] {
            if let Some(Ok(f)) = self.decoder.push(b, now as u32) {
                let out = match DeviceToHost::decode(&f).unwrap() {
                    DeviceToHost::WriteLocalResponse { index, sub, err } => Out::W { index, sub, err },
                    DeviceToHost::ReadLocalResponse { index, sub, err, data } => Out::R { index, sub, err, data: data.to_vec() },
                    DeviceToHost::WriteRemoteResponse { node_id, index, sub, err } => Out::S { node: node_id, index, sub, err },
                    DeviceToHost::ReadRemoteResponse { node_id, index, sub, err, data } => Out::U { node: node_id, index, sub, err, data: data.to_vec() },
                    DeviceToHost::NewDataIndication { node_id, index, sub, data } => Out::D { node: node_id, index, sub, data: data.to_vec() },
                };
                let start = self.decoder.start_byte();
                self.received.push((start, out));
            }
        }
    }

    /// Everything but the indications, taken.
    fn answers(&mut self) -> Vec<Out> {
        let all: Vec<(u8, Out)> = self.received.drain(..).collect();
        let (d, answers): (Vec<_>, Vec<_>) = all.into_iter().partition(|(_, o)| matches!(o, Out::D { .. }));
        self.received = d;
        answers.into_iter().map(|(_, o)| o).collect()
    }

    /// The indications, taken.
    fn indications(&mut self) -> Vec<Out> {
        let all: Vec<(u8, Out)> = self.received.drain(..).collect();
        let (d, answers): (Vec<_>, Vec<_>) = all.into_iter().partition(|(_, o)| matches!(o, Out::D { .. }));
        self.received = answers;
        d.into_iter().map(|(_, o)| o).collect()
    }
}

/// A command frame with start byte `start` (its options: CRC or none, 8- or 16-bit length).
fn frame(command: &HostToDevice<'_>, start: u8) -> Vec<u8> {
    let mut buf = [0_u8; 64];
    let n = command.encode(&mut buf).unwrap();
    let mut out = [0_u8; 64];
    let m = reencode(&serial::FRAMING, &buf[..n], start, &mut out).unwrap();
    out[..m].to_vec()
}

fn d(node: u8, index: u16, sub: u8, data: &[u8]) -> Out {
    Out::D { node, index, sub, data: data.to_vec() }
}

#[test]
fn local_reads_and_writes_with_their_error_bits() {
    let mut net = Net::new(&[("canopenia", IA)]);
    net.indications();
    net.command(HostToDevice::ReadLocalRequest { index: 0x1000, sub: 0 });
    net.command(HostToDevice::WriteLocalRequest { index: 0x6000, sub: 1, data: &[0x5A] });
    net.command(HostToDevice::ReadLocalRequest { index: 0x6000, sub: 1 });
    // No such object; read-only for the host (5F00h); a value of the wrong length.
    net.command(HostToDevice::ReadLocalRequest { index: 0x2345, sub: 0 });
    net.command(HostToDevice::WriteLocalRequest { index: 0x5F00, sub: 1, data: &[5] });
    net.command(HostToDevice::WriteLocalRequest { index: 0x6000, sub: 2, data: &[1, 2] });
    assert_eq!(
        net.answers(),
        [
            Out::R { index: 0x1000, sub: 0, err: 0, data: 0x000F_0191_u32.to_le_bytes().to_vec() },
            Out::W { index: 0x6000, sub: 1, err: 0 },
            Out::R { index: 0x6000, sub: 1, err: 0, data: vec![0x5A] },
            Out::R { index: 0x2345, sub: 0, err: 1 << 0, data: vec![] },
            Out::W { index: 0x5F00, sub: 1, err: 1 << 11 },
            Out::W { index: 0x6000, sub: 2, err: 1 << 1 },
        ]
    );
    // The host's write of a mapped input had the side effect of an SDO write: TPDO1 went out
    // (the node is pre-operational: not yet; start it and write again).
    net.bus.send(CanFrame::data(0, &[0x01, IA]).unwrap());
    net.bus.drain();
    net.command(HostToDevice::WriteLocalRequest { index: 0x6000, sub: 1, data: &[0x5B] });
    let tpdo = net.bus.drain().into_iter().find(|f| f.id == 0x180 + u16::from(IA)).unwrap();
    assert_eq!(tpdo.data[0], 0x5B);
}

#[test]
fn answers_take_the_form_of_their_command_and_bad_frames_get_none() {
    let mut net = Net::new(&[("canopenia", IA)]);
    net.received.clear();
    let r = HostToDevice::ReadLocalRequest { index: 0x1000, sub: 0 };
    // Without CRC, with a 16-bit length, and on network 2 (which this coprocessor lacks).
    for start in [0x01, 0x31, 0x12] {
        net.host_bytes(&frame(&r, start));
    }
    let got: Vec<(u8, Out)> = net.received.drain(..).collect();
    assert_eq!(got.iter().map(|(s, _)| *s).collect::<Vec<_>>(), [0x01, 0x31, 0x12]);
    assert!(matches!(got[0].1, Out::R { err: 0, .. }) && matches!(got[1].1, Out::R { err: 0, .. }));
    assert_eq!(got[2].1, Out::R { index: 0x1000, sub: 0, err: 1 << 11, data: vec![] }, "another network: not supported");
    // Garbage, a frame with a bad CRC, a letter the protocol lacks: nothing; then a valid R.
    let mut bad = frame(&r, 0x11);
    let last = bad.len() - 1;
    bad[last] ^= 0xFF;
    let mut bytes = vec![0x00, 0xC0, 0x7F];
    bytes.extend(&bad);
    bytes.extend([0x11, 0x01, b'X', 0x00, 0x00]);
    net.host_bytes(&bytes);
    net.host_bytes(&frame(&r, 0x11));
    assert_eq!(net.answers().len(), 1, "only the valid R is answered");
    // A known letter with a wrong length is answered, with bit 1.
    net.host_bytes(&[0x01, 0x03, b'R', 0x00, 0x10]);
    assert_eq!(net.answers(), [Out::R { index: 0x1000, sub: 0, err: 1 << 1, data: vec![] }]);
}

#[test]
fn remote_reads_and_writes_through_the_manager_one_at_a_time() {
    let mut net = Net::new(&[("canopenia", IA), ("co401memory1", MEM)]);
    net.run_ms(50);
    net.received.clear();
    net.command(HostToDevice::ReadRemoteRequest { node_id: MEM, index: 0x1018, sub: 1 });
    net.command(HostToDevice::WriteRemoteRequest { node_id: MEM, index: 0x1017, sub: 0, data: &100_u16.to_le_bytes() });
    net.command(HostToDevice::ReadRemoteRequest { node_id: MEM, index: 0x1017, sub: 0 });
    net.command(HostToDevice::ReadRemoteRequest { node_id: MEM, index: 0x2999, sub: 0 });
    let vendor = co401memory1::VENDOR_ID.to_le_bytes().to_vec();
    assert_eq!(
        net.answers(),
        [
            Out::U { node: MEM, index: 0x1018, sub: 1, err: 0, data: vendor },
            Out::S { node: MEM, index: 0x1017, sub: 0, err: 0 },
            Out::U { node: MEM, index: 0x1017, sub: 0, err: 0, data: vec![100, 0] },
            Out::U { node: MEM, index: 0x2999, sub: 0, err: 1 << 6 | 1 << 0, data: vec![] },
        ]
    );
    // Two in one burst: the second is busy at once, a W in between is served meanwhile.
    // (1017h is not in the scan cache: this U goes to the node.)
    let mut burst = frame(&HostToDevice::ReadRemoteRequest { node_id: MEM, index: 0x1017, sub: 0 }, 0x11);
    burst.extend(frame(&HostToDevice::WriteRemoteRequest { node_id: MEM, index: 0x1017, sub: 0, data: &[0, 0] }, 0x11));
    burst.extend(frame(&HostToDevice::WriteLocalRequest { index: 0x6000, sub: 3, data: &[7] }, 0x11));
    net.host_bytes(&burst);
    assert_eq!(
        net.answers(),
        [
            Out::S { node: MEM, index: 0x1017, sub: 0, err: 1 << 3 },
            Out::W { index: 0x6000, sub: 3, err: 0 },
            Out::U { node: MEM, index: 0x1017, sub: 0, err: 0, data: vec![100, 0] }
        ]
    );
    // A node that is not there: the SDO client's timeout, and the node-IDs no node can have.
    net.command(HostToDevice::ReadRemoteRequest { node_id: 9, index: 0x1000, sub: 0 });
    assert_eq!(net.answers(), []);
    net.run_ms(1001);
    net.command(HostToDevice::ReadRemoteRequest { node_id: 0, index: 0x1000, sub: 0 });
    net.command(HostToDevice::WriteRemoteRequest { node_id: 200, index: 0x1000, sub: 0, data: &[1] });
    assert_eq!(
        net.answers(),
        [
            Out::U { node: 9, index: 0x1000, sub: 0, err: 1 << 6 | 1 << 9, data: vec![] },
            Out::U { node: 0, index: 0x1000, sub: 0, err: 1 << 2, data: vec![] },
            Out::S { node: 200, index: 0x1000, sub: 0, err: 1 << 2 },
        ]
    );
    // Its own node-ID: served from its own dictionary, with the bus's rules.
    net.command(HostToDevice::ReadRemoteRequest { node_id: IA, index: 0x1000, sub: 0 });
    assert_eq!(net.answers(), [Out::U { node: IA, index: 0x1000, sub: 0, err: 0, data: 0x000F_0191_u32.to_le_bytes().to_vec() }]);
}

#[test]
fn the_host_is_told_of_bus_writes_node_statuses_and_scanned_tpdos() {
    let mut net = Net::new(&[("canopenia", IA), ("co401memory1", MEM)]);
    net.run_ms(50);
    let boot = net.indications();
    // Its own status first (node-ID, pre-operational, INIT), then module 2: boot-up, the scan
    // started, the two emergencies the module sends for its blank EEPROM banks, the scan done.
    let own = |sub: u8, v: u8| d(IA, 0x5F00, sub, &[v]);
    let node2 = |v: u8| d(IA, 0x5F04, MEM, &[v]);
    assert_eq!(boot, [own(1, IA), own(2, 0x7F), own(3, 0x01), node2(0x00), node2(0x9F), node2(0x80), node2(0x80), node2(0xA0)]);
    // A master writes 6200h.1 by SDO, then RPDO1 carries two bytes: one D per entry.
    net.bus.send(CanFrame::data(0x600 + u16::from(IA), &[0x2F, 0x00, 0x62, 0x01, 0xA5, 0, 0, 0]).unwrap());
    net.bus.send(CanFrame::data(0, &[0x01, 0]).unwrap());
    net.bus.send(CanFrame::data(0x200 + u16::from(IA), &[1, 2, 3, 4, 5, 6, 7, 8]).unwrap());
    net.collect();
    let got = net.indications();
    assert_eq!(got[0], d(0, 0x6200, 1, &[0xA5]));
    assert!(got.contains(&own(2, 0x05)), "operational: {got:?}");
    let rpdo: Vec<&Out> = got.iter().filter(|o| matches!(o, Out::D { index: 0x6200, .. })).skip(1).collect();
    assert_eq!(rpdo, (1..=8).map(|i| d(0, 0x6200, i, &[i])).collect::<Vec<_>>().iter().collect::<Vec<_>>());
    // TPDO receive all: module 2's TPDO1 (6000h.1 and .2, its status bytes) arrives split by its
    // scanned mapping, once 5F01h.04 bit 2 is set.
    let tpdo = CanFrame::data(0x180 + u16::from(MEM), &[0x03, 0x40]).unwrap();
    net.command(HostToDevice::WriteLocalRequest { index: 0x5F01, sub: 4, data: &0_u32.to_le_bytes() });
    net.bus.send(tpdo);
    net.collect();
    assert_eq!(net.indications(), [], "bit 2 clear: not received");
    net.command(HostToDevice::WriteLocalRequest { index: 0x5F01, sub: 4, data: &(1_u32 << 2).to_le_bytes() });
    net.bus.send(tpdo);
    net.collect();
    assert_eq!(net.indications(), [d(MEM, 0x6000, 1, &[0x03]), d(MEM, 0x6000, 2, &[0x40])]);
    // An NMT master message through 5F0Ah: module 2 stops, and a reset is recorded in 5F04h.
    net.command(HostToDevice::WriteLocalRequest { index: 0x5F0A, sub: 1, data: &[0x02, MEM] });
    assert!(net.bus.log.iter().any(|(_, f)| f.id == 0 && f.data[..2] == [0x02, MEM]));
    net.command(HostToDevice::WriteLocalRequest { index: 0x5F0A, sub: 1, data: &[0x81, MEM] });
    assert!(net.indications().contains(&node2(0xB0)));
}

/// A small deterministic generator (xorshift), so the arbitrary inputs are the same each run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

#[test]
fn arbitrary_host_bytes_and_frames_never_panic_and_every_answer_is_a_whole_valid_frame() {
    let mut net = Net::new(&[("canopenia", IA), ("co401memory1", MEM)]);
    let mut rng = Rng(0x1A2B_3C4D_5E6F_7081);
    let commands = [
        HostToDevice::ReadLocalRequest { index: 0x1000, sub: 0 },
        HostToDevice::WriteLocalRequest { index: 0x6000, sub: 1, data: &[1] },
        HostToDevice::ReadRemoteRequest { node_id: MEM, index: 0x1018, sub: 1 },
        HostToDevice::WriteRemoteRequest { node_id: MEM, index: 0x1017, sub: 0, data: &[10, 0] },
        HostToDevice::WriteLocalRequest { index: 0x5F0A, sub: 1, data: &[0x80, 0] },
        HostToDevice::WriteLocalRequest { index: 0x5F01, sub: 4, data: &[0xFF, 0xFF, 0xFF, 0xFF] },
    ];
    let mut valid = 0;
    for round in 0..3000 {
        let r = rng.next();
        match r % 4 {
            // A valid command in any start-byte form.
            0 => {
                let start = [0x11, 0x01, 0x21, 0x31][(r >> 8) as usize % 4];
                net.host_bytes(&frame(&commands[(r >> 16) as usize % commands.len()], start));
                valid += 1;
            }
            // Garbage bytes.
            1 => {
                let bytes: Vec<u8> = (0..(r >> 8) % 40).map(|_| rng.next() as u8).collect();
                net.host_bytes(&bytes);
            }
            // Any frame on the bus, to the coprocessor's node or manager IDs most of the time.
            2 => {
                let ids = [0x000, 0x080 + u16::from(MEM), 0x181, 0x182, 0x201, 0x581, 0x582, 0x601, 0x702, 0x70F, (r >> 20) as u16 & 0x7FF];
                let id = ids[(r >> 8) as usize % ids.len()];
                let data = rng.next().to_le_bytes();
                let len = (r >> 40) as usize % 9;
                net.bus.send(CanFrame::data(id, &data[..len]).unwrap());
                net.collect();
            }
            _ => net.run_ms((r >> 8) % 300),
        }
        // The decoder saw only whole, valid frames: a frame split or interleaved would fail
        // its CRC or length, and `collect` unwraps every decode.
        assert_eq!(net.decoder.skipped, 0, "round {round}: bytes between frames");
    }
    // Garbage may swallow a valid frame that follows it (resync), and a garbage frame without
    // CRC may even decode: the counts only bound each other.
    let answers = net.answers().len();
    assert!(answers <= valid + 50 && answers > valid / 2, "{answers} answers to {valid} valid commands");
    // After the storm the engine is whole: a pause resynchronises, then each command is
    // answered exactly once.
    net.run_ms(2000);
    net.host_bytes(&[0x00; 40]);
    net.answers();
    for _ in 0..10 {
        net.command(HostToDevice::ReadLocalRequest { index: 0x1000, sub: 0 });
    }
    net.command(HostToDevice::ReadRemoteRequest { node_id: MEM, index: 0x1000, sub: 0 });
    let after = net.answers();
    assert_eq!(after.len(), 11, "{after:?}");
    assert!(matches!(after[10], Out::U { err: 0, .. }), "{after:?}");
}

#[test]
fn the_manager_keeps_nodes_operational_and_resets_a_lost_one() {
    let mut net = Net::new(&[("canopenia", IA), ("co401memory1", MEM)]);
    let node2 = |v: u8| d(IA, 0x5F04, MEM, &[v]);
    // Node 2's statuses (its TPDOs are indicated too: PDO receive all is on).
    let statuses = |net: &mut Net| net.indications().into_iter().filter(|o| matches!(o, Out::D { index: 0x5F04, .. })).collect::<Vec<_>>();
    // The defaults (5F01h.04 = 087F0017h): the scan wrote 5F01h.05 (1000 ms) into the module's
    // 1017h, KEEP_OP started it, and its heartbeats are monitored.
    net.run_ms(1100);
    let seen = statuses(&mut net);
    assert!(seen.ends_with(&[node2(0xA0), node2(0x05), node2(0x90)]), "{seen:?}");
    assert!(net.bus.log.iter().any(|(_, f)| f.id == 0 && f.data[..2] == [0x01, MEM]), "NMT start of node 2");
    // A master stops it: its next heartbeat says so, and KEEP_OP starts it again.
    net.bus.send(CanFrame::data(0, &[0x02, MEM]).unwrap());
    net.run_ms(2100);
    let seen = statuses(&mut net);
    assert!(seen.windows(2).any(|w| w == [node2(0x04), node2(0x05)]), "{seen:?}");
    // Its heartbeat stops (1017h = 0): lost after 1500 ms, reset; it boots, is scanned again
    // (its 1017h written again) and started.
    net.bus.send(CanFrame::data(0x600 + u16::from(MEM), &[0x2B, 0x17, 0x10, 0x00, 0, 0, 0, 0]).unwrap());
    net.run_ms(3000);
    let seen = statuses(&mut net);
    let lost = seen.iter().position(|o| *o == node2(0x91)).unwrap_or_else(|| panic!("{seen:?}"));
    assert_eq!(seen[lost..lost + 3], [node2(0x91), node2(0xB0), node2(0x00)], "{seen:?}");
    assert!(seen[lost..].contains(&node2(0xA0)) && seen[lost..].contains(&node2(0x90)), "scanned and monitored again: {seen:?}");
    // With KEEP_OP and HB receive all off nothing is restarted or reset.
    net.command(HostToDevice::WriteLocalRequest { index: 0x5F01, sub: 4, data: &0_u32.to_le_bytes() });
    net.bus.send(CanFrame::data(0, &[0x02, MEM]).unwrap());
    net.run_ms(2100);
    assert!(statuses(&mut net).contains(&node2(0x04)));
    let starts = net.bus.log.iter().filter(|(t, f)| *t > net.bus.now_us() - 2_000_000 && f.id == 0 && f.data[0] == 0x01).count();
    assert_eq!(starts, 0, "KEEP_OP off: the stopped node stays stopped");
}

#[test]
fn autorun_starts_the_coprocessor_after_every_reset() {
    let mut net = Net::new(&[("canopenia", IA)]);
    let state = |v: u8| d(IA, 0x5F00, 2, &[v]);
    assert!(net.indications().contains(&state(0x7F)), "AUTORUN low: pre-operational");
    net.bus.nodes[0].console("autorun on").unwrap();
    // A soft reset (5F01h.1 = 129) reads the pin again.
    net.command(HostToDevice::WriteLocalRequest { index: 0x5F01, sub: 1, data: &[129] });
    let seen = net.indications();
    assert_eq!(seen, [d(IA, 0x5F00, 1, &[IA]), state(0x05), d(IA, 0x5F00, 3, &[0x01])], "the reset shows every status again");
    assert!(net.bus.nodes[0].console("autorun maybe").is_err());
}

#[test]
fn rpdo_transmit_all_sends_host_writes_as_the_scanned_nodes_rpdos() {
    let mut net = Net::new(&[("canopenia", IA), ("co401memory1", MEM)]);
    net.run_ms(1100);
    // RPDO transmit all on (5F01h.04 bit 3), update time 20 ms, no event or inhibit time.
    net.command(HostToDevice::WriteLocalRequest { index: 0x5F01, sub: 4, data: &(0x087F_0017_u32 | 1 << 3).to_le_bytes() });
    net.command(HostToDevice::WriteLocalRequest { index: 0x5F01, sub: 7, data: &[20] });
    net.received.clear();
    let rpdo1 = 0x200 + u16::from(MEM);
    // The frames since log position `mark` (times can repeat: commands take no time).
    let sent = |net: &Net, mark: usize| net.bus.log[mark..].iter().filter(|(_, f)| f.id == rpdo1).map(|(t, f)| (*t, f.payload().to_vec())).collect::<Vec<_>>();
    let sdo_requests = |net: &Net, mark: usize| net.bus.log[mark..].iter().filter(|(_, f)| f.id == 0x600 + u16::from(MEM)).count();

    // The module's RPDO1 maps 6200h.1 and .2: the first write is answered at once and goes
    // nowhere yet (6200h.2 was never written), not even after five update times.
    let m0 = net.bus.log.len();
    net.command(HostToDevice::WriteRemoteRequest { node_id: MEM, index: 0x6200, sub: 1, data: &[0x00] });
    assert_eq!(net.answers(), [Out::S { node: MEM, index: 0x6200, sub: 1, err: 0 }]);
    net.run_ms(150);
    assert_eq!(sent(&net, m0), [], "not every mapped entry written yet");
    // Writing the last mapped entry sends the PDO at once, with both values; no SDO at all.
    net.command(HostToDevice::WriteRemoteRequest { node_id: MEM, index: 0x6200, sub: 2, data: &[0x00] });
    assert_eq!(net.answers(), [Out::S { node: MEM, index: 0x6200, sub: 2, err: 0 }]);
    assert_eq!(sent(&net, m0).iter().map(|(_, d)| d.clone()).collect::<Vec<_>>(), [vec![0x00, 0x00]]);
    assert_eq!(sdo_requests(&net, m0), 0);
    // Another write of the first entry: sent when the update time (20 ms) has passed.
    let (m1, t1) = (net.bus.log.len(), net.bus.now_us());
    net.command(HostToDevice::WriteRemoteRequest { node_id: MEM, index: 0x6200, sub: 1, data: &[0x00] });
    assert_eq!(net.answers(), [Out::S { node: MEM, index: 0x6200, sub: 1, err: 0 }]);
    net.run_ms(10);
    assert_eq!(sent(&net, m1), [], "before the update time");
    net.run_ms(20);
    let after = sent(&net, m1);
    assert_eq!(after.len(), 1, "{after:?}");
    assert!(after[0].0 - t1 >= 20_000, "{after:?}");
    // A value of the wrong size for the mapped entry; an entry no RPDO maps goes by SDO.
    net.command(HostToDevice::WriteRemoteRequest { node_id: MEM, index: 0x6200, sub: 1, data: &[0, 0] });
    net.command(HostToDevice::WriteRemoteRequest { node_id: MEM, index: 0x1017, sub: 0, data: &1000_u16.to_le_bytes() });
    assert_eq!(net.answers(), [Out::S { node: MEM, index: 0x6200, sub: 1, err: 1 << 1 }, Out::S { node: MEM, index: 0x1017, sub: 0, err: 0 }]);
    assert_eq!(sdo_requests(&net, m1), 1);
    // An inhibit time of 50 ms keeps the transmissions of writes every 10 ms that far apart.
    net.command(HostToDevice::WriteLocalRequest { index: 0x5F01, sub: 9, data: &500_u16.to_le_bytes() });
    let m3 = net.bus.log.len();
    for _ in 0..12 {
        net.command(HostToDevice::WriteRemoteRequest { node_id: MEM, index: 0x6200, sub: 2, data: &[0x00] });
        net.run_ms(10);
    }
    let inhibited = sent(&net, m3);
    assert!((2..=3).contains(&inhibited.len()), "{inhibited:?}");
    assert!(inhibited.windows(2).all(|w| w[1].0 - w[0].0 >= 50_000), "{inhibited:?}");
    net.answers();
    // With an event time the PDO goes out cyclically, written or not.
    net.command(HostToDevice::WriteLocalRequest { index: 0x5F01, sub: 8, data: &100_u16.to_le_bytes() });
    let m2 = net.bus.log.len();
    net.run_ms(1000);
    let cyclic = sent(&net, m2);
    assert!((9..=11).contains(&cyclic.len()), "every 100 ms: {}", cyclic.len());
}

/// Hex bytes as the manual prints them.
fn hex(text: &str) -> Vec<u8> {
    text.split_whitespace().map(|b| u8::from_str_radix(b, 16).unwrap()).collect()
}

#[test]
fn the_manuals_remote_examples_byte_for_byte_with_a_second_coprocessor() {
    // Section 4.2's node: a second CANopenIA at node-ID 2 with serial number 04040D41h, which
    // the host configures through this coprocessor (node 1) with S and U.
    let mut net = Net::new(&[("canopenia", IA), ("canopenia", 2)]);
    // KEEP_OP off, so node 2 stays pre-operational (step 2 of the sequence).
    net.command(HostToDevice::WriteLocalRequest { index: 0x5F01, sub: 4, data: &0x087F_0016_u32.to_le_bytes() });
    net.bus.nodes[1].console("serial-number 04040D41").unwrap();
    net.bus.send(CanFrame::data(0, &[0x81, 2]).unwrap());
    net.run_ms(1100);
    net.raw.clear();
    // The spec's examples of section 4.2 (steps 3..5), each answer byte for byte.
    let examples = [
        ("11 05 55 02 18 10 04 39 31", "11 0B 55 02 18 10 04 00 00 41 0D 04 04 11 08"),
        ("11 09 53 02 50 1F 01 41 0D 04 04 B3 C2", "11 07 53 02 50 1F 01 00 00 06 93"),
        ("11 06 53 02 51 1F 01 00 3E 04", "11 07 53 02 51 1F 01 00 00 57 39"),
    ];
    for (command, answer) in examples {
        net.host_bytes(&hex(command));
        net.run_ms(20);
        // The answer among the indications the host also gets (start 11h: 8-bit length, CRC).
        let mut frames = Vec::new();
        let mut rest = std::mem::take(&mut net.raw);
        while rest.len() >= 4 {
            let len = 1 + 1 + usize::from(rest[1]) + 2;
            let frame: Vec<u8> = rest.drain(..len).collect();
            if frame[2] != b'D' {
                frames.push(frame);
            }
        }
        assert_eq!(frames, [hex(answer)], "answer to {command}");
    }
    // Node 2 resets into bootloader mode as node 70h.
    assert!(net.bus.log.iter().any(|(_, f)| f.id == 0x770 && f.payload() == [0]), "boot-up of node 70h");
}
