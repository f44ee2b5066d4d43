//! `coforge master`: talk to a CANopen bus from the command line, on the same `no_std`
//! manager code a coforge device runs (coforge-stack's SDO client, node scan, node monitor and
//! NMT master), over a `coforge sim` or `coforge hub` bus hub.

mod link;
mod value;

use clap::Subcommand;
use coforge_stack::frame::CanFrame;
use coforge_stack::manager::monitor::{Monitor, MonitorEvent, NodeState};
use coforge_stack::manager::nmt_frame;
use coforge_stack::manager::scan::{NodeScan, Progress, ScanConfig, ScanTransfer};
use coforge_stack::nmt::NmtCommand;
use coforge_stack::od::SdoAbort;
use coforge_stack::sdo::client::{AbortSource, SdoClient, SdoResult, response_id};
use link::Link;
use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};
use value::Type;

/// What `coforge master` does.
#[derive(Subcommand)]
pub enum MasterCmd {
    /// List the nodes on the bus: every node-ID 1..=127 is asked for 1000h and 1018h at once;
    /// those that answer are printed with their device type and identity.
    Scan {
        /// Also read the communication and mapping parameters of the first N TPDOs and RPDOs.
        #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u8).range(0..=8))]
        pdos: u8,
    },
    /// Read or write an entry of a node's object dictionary (SDO, expedited or segmented).
    Sdo {
        #[command(subcommand)]
        op: SdoCmd,
    },
    /// Send an NMT command to a node or to all nodes.
    Nmt {
        #[arg(value_parser = ["start", "stop", "preop", "reset", "reset-comm"])]
        command: String,
        /// A node-ID 1..=127, or `all`.
        target: String,
    },
    /// Print boot-ups, heartbeat changes and emergencies as they happen.
    Monitor {
        /// Report a node whose heartbeats stop for this long as lost (0: loss not watched).
        #[arg(long, default_value_t = 0)]
        consumer_ms: u16,
        /// Stop after this many seconds (default: run until killed).
        #[arg(long)]
        seconds: Option<f64>,
    },
}

/// `coforge master sdo`.
#[derive(Subcommand)]
pub enum SdoCmd {
    /// Print the value of NODE's INDEX/SUB; without --type or --eds as hex bytes.
    Read {
        node: String,
        /// Object index: 0x1018, 1018h or decimal.
        index: String,
        sub: String,
        /// The value's type: bool, i8..i64, u8..u64, f32, f64, str, bytes.
        #[arg(long = "type", conflicts_with = "eds")]
        ty: Option<String>,
        /// Take the type from this EDS file.
        #[arg(long)]
        eds: Option<PathBuf>,
    },
    /// Write VALUE to NODE's INDEX/SUB; the type comes from --type or --eds.
    Write {
        node: String,
        index: String,
        sub: String,
        value: String,
        #[arg(long = "type", conflicts_with = "eds", required_unless_present = "eds")]
        ty: Option<String>,
        #[arg(long)]
        eds: Option<PathBuf>,
    },
}

/// Where the hub is: a port on this machine, or HOST:PORT.
fn hub_address(port: &str) -> String {
    if port.contains(':') { port.to_string() } else { format!("127.0.0.1:{port}") }
}

/// A number as users write CANopen numbers: `0x1018`, `1018h`, or decimal.
fn number(what: &str, text: &str, max: u32) -> Result<u32, String> {
    let parsed = if let Some(hex) = text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        u32::from_str_radix(hex, 16)
    } else if let Some(hex) = text.strip_suffix('h').or_else(|| text.strip_suffix('H')) {
        u32::from_str_radix(hex, 16)
    } else {
        text.parse()
    };
    parsed.ok().filter(|&v| v <= max).ok_or_else(|| format!("{what} `{text}` is not a number 0..={max} (0x1018, 1018h or decimal)"))
}

fn node_id(text: &str) -> Result<u8, String> {
    let n = number("node-ID", text, 127)?;
    if n == 0 {
        return Err("node-ID 0 addresses no node; node-IDs are 1..=127".into());
    }
    Ok(n as u8)
}

pub fn run(port: &str, timeout_ms: u64, cmd: MasterCmd) -> Result<ExitCode, String> {
    let mut link = Link::connect(&hub_address(port))?;
    match cmd {
        MasterCmd::Scan { pdos } => scan(&mut link, timeout_ms, pdos),
        MasterCmd::Sdo { op } => sdo(&mut link, timeout_ms, op),
        MasterCmd::Nmt { command, target } => nmt(&mut link, &command, &target),
        MasterCmd::Monitor { consumer_ms, seconds } => monitor(&mut link, consumer_ms, seconds),
    }
}

/// The data type of an entry, from `--type` or `--eds`.
fn entry_type(ty: Option<&str>, eds: Option<&std::path::Path>, index: u16, sub: u8) -> Result<Option<Type>, String> {
    match (ty, eds) {
        (Some(name), _) => Type::named(name).map(Some),
        (None, Some(path)) => value::from_eds(path, index, sub).map(Some),
        (None, None) => Ok(None),
    }
}

fn sdo(link: &mut Link, timeout_ms: u64, op: SdoCmd) -> Result<ExitCode, String> {
    let mut client = SdoClient::new();
    client.set_timeout_us(timeout_ms.saturating_mul(1000));
    let (node, index, sub, ty, eds, value) = match &op {
        SdoCmd::Read { node, index, sub, ty, eds } => (node, index, sub, ty, eds, None),
        SdoCmd::Write { node, index, sub, value, ty, eds } => (node, index, sub, ty, eds, Some(value)),
    };
    let node = node_id(node)?;
    let index = number("index", index, 0xFFFF)? as u16;
    let sub = number("sub-index", sub, 0xFF)? as u8;
    let ty = entry_type(ty.as_deref(), eds.as_deref(), index, sub)?;
    let what = format!("node {node} {index:04X}h sub {sub}");
    match value {
        None => {
            let mut buf = vec![0; 1 << 20];
            let first = client.upload(node, index, sub, link.now_us()).map_err(|e| format!("{e:?}"))?;
            match transfer(link, &mut client, first, &mut buf)? {
                SdoResult::Uploaded { len } => println!("{}", ty.unwrap_or(Type::Bytes).decode(&buf[..len])),
                other => return Err(failure(&what, other, timeout_ms)),
            }
        }
        Some(text) => {
            let ty = ty.ok_or("a write needs --type or --eds")?;
            let mut data = ty.encode(text)?;
            let first = client.download(node, index, sub, &data, link.now_us()).map_err(|e| format!("{e:?}"))?;
            match transfer(link, &mut client, first, &mut data)? {
                SdoResult::Downloaded => println!("ok: {what} = {}", ty.decode(&data)),
                other => return Err(failure(&what, other, timeout_ms)),
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Runs one SDO transfer from its first request to its result.
fn transfer(link: &mut Link, client: &mut SdoClient, first: CanFrame, buf: &mut [u8]) -> Result<SdoResult, String> {
    link.send(&first)?;
    loop {
        if let Some(result) = client.take_result() {
            return Ok(result);
        }
        if let Some(abort) = client.poll(link.now_us()) {
            link.send(&abort)?;
            continue;
        }
        if let Some(frame) = link.recv(Duration::from_millis(5))?
            && let Some(next) = client.on_frame(&frame, link.now_us(), buf)
        {
            link.send(&next)?;
        }
    }
}

/// Why a transfer failed, for a person.
fn failure(what: &str, result: SdoResult, timeout_ms: u64) -> String {
    let text = |code: u32| SdoAbort::from_code(code).map_or("not a CiA 301 abort code", |a| a.description());
    match result {
        SdoResult::Aborted { code, by: AbortSource::Client } if code == SdoAbort::Timeout.code() => {
            format!("{what}: no answer within {timeout_ms} ms (is the node on the bus and not stopped?)")
        }
        SdoResult::Aborted { code, by: AbortSource::Server } => {
            format!("{what}: the node aborted with {:04X} {:04X}h: {}", code >> 16, code & 0xFFFF, text(code))
        }
        SdoResult::Aborted { code, by: AbortSource::Client } => format!("{what}: aborted here with {:04X} {:04X}h: {}", code >> 16, code & 0xFFFF, text(code)),
        other => format!("{what}: unexpected result {other:?}"),
    }
}

fn nmt(link: &mut Link, command: &str, target: &str) -> Result<ExitCode, String> {
    let cmd = match command {
        "start" => NmtCommand::Start,
        "stop" => NmtCommand::Stop,
        "preop" => NmtCommand::EnterPreOperational,
        "reset" => NmtCommand::ResetNode,
        _ => NmtCommand::ResetCommunication,
    };
    let node = if target == "all" { 0 } else { node_id(target)? };
    let frame = nmt_frame(cmd, node).ok_or("not an NMT frame")?;
    link.send(&frame)?;
    // Give the hub the line before the connection closes.
    std::thread::sleep(Duration::from_millis(20));
    println!("sent NMT {command} to {}", if node == 0 { "all nodes".to_string() } else { format!("node {node}") });
    Ok(ExitCode::SUCCESS)
}

/// One node-ID's scan: its own client channel, so that all 127 run at once.
struct Probe {
    client: SdoClient,
    scan: NodeScan<8>,
    buf: [u8; 4],
    /// How the scan ended: `None` while it runs.
    end: Option<Progress>,
}

fn start(probe: &mut Probe, now_us: u64) -> Option<CanFrame> {
    let started = match probe.scan.transfer()? {
        ScanTransfer::Read { node, index, sub } => probe.client.upload(node, index, sub, now_us),
        ScanTransfer::Write { node, index, sub, data } => probe.client.download(node, index, sub, &data, now_us),
    };
    started.ok()
}

fn scan(link: &mut Link, timeout_ms: u64, pdos: u8) -> Result<ExitCode, String> {
    let began = Instant::now();
    let config = ScanConfig { pdos, heartbeat_ms: None };
    let mut probes: Vec<Probe> = (1..=127).map(|n| Probe { client: SdoClient::new(), scan: NodeScan::new(n, config), buf: [0; 4], end: None }).collect();
    for p in &mut probes {
        p.client.set_timeout_us(timeout_ms.saturating_mul(1000));
        if let Some(first) = start(p, link.now_us()) {
            link.send(&first)?;
        }
    }
    while probes.iter().any(|p| p.end.is_none()) {
        let frame = link.recv(Duration::from_millis(2))?;
        let now = link.now_us();
        for p in probes.iter_mut().filter(|p| p.end.is_none()) {
            let mut out = None;
            if let Some(frame) = frame.filter(|f| f.id == response_id(p.scan.node())) {
                out = p.client.on_frame(&frame, now, &mut p.buf);
            }
            out = out.or_else(|| p.client.poll(now));
            if let Some(f) = out {
                link.send(&f)?;
            }
            if let Some(result) = p.client.take_result() {
                match p.scan.on_result(&result, &p.buf) {
                    Progress::Continue => {
                        if let Some(next) = start(p, now) {
                            link.send(&next)?;
                        }
                    }
                    end => p.end = Some(end),
                }
            }
        }
    }
    let mut out = std::io::stdout().lock();
    let w = |out: &mut std::io::StdoutLock<'_>, line: String| writeln!(out, "{line}").map_err(|e| e.to_string());
    w(&mut out, "node  device type  vendor-ID   product     revision    serial".into())?;
    let mut found = 0;
    for p in &probes {
        let r = p.scan.record();
        match p.end {
            Some(Progress::Complete) => {
                found += 1;
                let [vendor, product, revision, serial] = r.identity;
                w(&mut out, format!("{:4}  0x{:08X}   0x{vendor:08X}  0x{product:08X}  0x{revision:08X}  0x{serial:08X}", r.node, r.device_type))?;
                for (kind, list) in [("TPDO", &r.tpdos), ("RPDO", &r.rpdos)] {
                    for (i, pdo) in list.iter().take(usize::from(pdos)).enumerate() {
                        let map: Vec<String> = pdo.mapping().iter().map(|m| format!("{:04X}h.{}/{}", m >> 16, (m >> 8) & 0xFF, m & 0xFF)).collect();
                        let state = if pdo.is_valid() { "" } else { " (not valid)" };
                        w(&mut out, format!("      {kind}{} COB-ID 0x{:08X}{state} type {} map {}", i + 1, pdo.cob_id, pdo.transmission, map.join(" ")))?;
                    }
                }
            }
            // A node that answered but refused a mandatory object is on the bus all the same.
            Some(Progress::Aborted(code)) if code != SdoAbort::Timeout.code() => {
                found += 1;
                let why = SdoAbort::from_code(code).map_or("not a CiA 301 abort code", |a| a.description());
                w(&mut out, format!("{:4}  scan aborted: {:04X} {:04X}h: {why}", r.node, code >> 16, code & 0xFFFF))?;
            }
            _ => {}
        }
    }
    w(&mut out, format!("{found} node(s) answered; 127 node-IDs scanned in {} ms", began.elapsed().as_millis()))?;
    Ok(ExitCode::SUCCESS)
}

fn state_name(state: NodeState) -> &'static str {
    match state {
        NodeState::Unknown => "unknown",
        NodeState::BootUp => "boot-up",
        NodeState::Stopped => "stopped",
        NodeState::Operational => "operational",
        NodeState::PreOperational => "pre-operational",
    }
}

/// One line of `coforge master monitor`.
fn describe(event: &MonitorEvent) -> String {
    match *event {
        MonitorEvent::BootUp(n) => format!("node {n}: boot-up"),
        MonitorEvent::HeartbeatStarted { node, state } => format!("node {node}: heartbeat started, {}", state_name(state)),
        MonitorEvent::StateChanged { node, from, to } => format!("node {node}: {} -> {}", state_name(from), state_name(to)),
        MonitorEvent::HeartbeatLost(n) => format!("node {n}: heartbeat lost"),
        MonitorEvent::Emergency { node, code, register, data } => {
            let data: Vec<String> = data.iter().map(|b| format!("{b:02X}")).collect();
            format!("node {node}: emergency {code:04X}h register {register:02X}h data {}", data.join(" "))
        }
        MonitorEvent::EmergencyCleared { node, register } => format!("node {node}: error reset, register {register:02X}h"),
    }
}

fn monitor(link: &mut Link, consumer_ms: u16, seconds: Option<f64>) -> Result<ExitCode, String> {
    let mut monitor = Monitor::new();
    monitor.set_consumer_ms(None, consumer_ms);
    let deadline = match seconds {
        Some(s) if s.is_finite() && s >= 0.0 => Some(Instant::now() + Duration::from_secs_f64(s)),
        Some(s) => return Err(format!("--seconds {s} is not a duration")),
        None => None,
    };
    println!("monitoring the bus (consumer time {consumer_ms} ms)");
    while deadline.is_none_or(|d| Instant::now() < d) {
        let frame = link.recv(Duration::from_millis(10))?;
        let now = link.now_us();
        let mut events: Vec<MonitorEvent> = frame.and_then(|f| monitor.on_frame(&f, now)).into_iter().collect();
        while let Some(e) = monitor.check(now) {
            events.push(e);
        }
        for e in events {
            println!("{:10.3} s  {}", now as f64 / 1e6, describe(&e));
            let _ = std::io::stdout().flush();
        }
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_as_users_write_them() {
        assert_eq!(number("index", "0x1018", 0xFFFF), Ok(0x1018));
        assert_eq!(number("index", "1018h", 0xFFFF), Ok(0x1018));
        assert_eq!(number("index", "4120", 0xFFFF), Ok(4120));
        assert!(number("index", "0x10000", 0xFFFF).is_err_and(|e| e.contains("0..=65535")));
        assert!(number("index", "x", 0xFFFF).is_err());
        assert!(node_id("0").is_err_and(|e| e.contains("1..=127")));
        assert!(node_id("128").is_err());
        assert_eq!(node_id("5"), Ok(5));
        assert_eq!(hub_address("4000"), "127.0.0.1:4000");
        assert_eq!(hub_address("host:4000"), "host:4000");
    }

    #[test]
    fn failures_name_the_abort() {
        let server = SdoResult::Aborted { code: 0x0602_0000, by: AbortSource::Server };
        assert_eq!(
            failure("node 5 2000h sub 0", server, 1000),
            "node 5 2000h sub 0: the node aborted with 0602 0000h: object does not exist in the object dictionary"
        );
        let timeout = SdoResult::Aborted { code: 0x0504_0000, by: AbortSource::Client };
        assert!(failure("node 9 1000h sub 0", timeout, 300).contains("no answer within 300 ms"));
        let odd = SdoResult::Aborted { code: 0x1234_5678, by: AbortSource::Server };
        assert!(failure("x", odd, 1).ends_with("1234 5678h: not a CiA 301 abort code"));
    }
}
