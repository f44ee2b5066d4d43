//! `coforge`: check specs, export EDS files and docs, keep spec files canonically formatted,
//! simulate devices and talk to a bus.
#![forbid(unsafe_code)]

mod master;

use clap::{Parser, Subcommand};
use coforge_spec::model::Direction;
use coforge_spec::{Loaded, load_file};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "coforge", version, about = "CANopen device specs -> firmware, EDS and docs")]
struct Cli {
    #[command(subcommand)]
    command: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Validate specs and print every diagnostic; exit 1 on any error.
    Check {
        #[arg(required = true)]
        specs: Vec<PathBuf>,
    },
    /// Export the EDS (CiA 306) of a spec. Devices with modes need --mode.
    Eds {
        spec: PathBuf,
        /// Operating mode to export (one EDS per mode).
        #[arg(long)]
        mode: Option<String>,
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Export a spec (or, with --from-eds, a CiA 306 EDS file) as a binary EDS v2.00 file,
    /// the dictionary configuration CANopenIA loads through 1F50h.2.
    Beds {
        /// The spec (YAML), or the EDS file with --from-eds.
        input: PathBuf,
        /// The input is an EDS file, not a spec.
        #[arg(long)]
        from_eds: bool,
        /// With --from-eds: apply what CANopenIA's own tool assumes beyond the EDS (5FF5h is
        /// served by the firmware, the chip ID 5F00h.05 is 12 bytes), so that its files come
        /// out byte for byte.
        #[arg(long, requires = "from_eds")]
        vendor_conventions: bool,
        /// Operating mode to export (devices with modes).
        #[arg(long)]
        mode: Option<String>,
        /// The node-ID the file configures; values with $NODEID are resolved for it.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=127))]
        node_id: u8,
        /// The bit rate the file configures, in kbit/s.
        #[arg(long, default_value = "125", value_parser = ["10", "20", "50", "125", "250", "500", "800", "1000"])]
        bitrate: String,
        /// FUNC bit 0: LSS supported.
        #[arg(long)]
        lss: bool,
        /// FUNC bit 1: start operational without a master.
        #[arg(long)]
        autostart: bool,
        /// FUNC bit 2: boot-up manager (NMT master).
        #[arg(long)]
        nmt_master: bool,
        /// FUNC bit 3: CANopen manager.
        #[arg(long)]
        manager: bool,
        /// FUNC bit 5: node-ID and bit rate come from hardware, not from this file.
        #[arg(long)]
        settings_from_hardware: bool,
        /// The identification string (default: the spec's name and the coforge version; for an
        /// EDS, what the vendor's tool writes: its file name, modification date and author).
        #[arg(long)]
        ident: Option<String>,
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Write the Markdown documentation of a spec.
    Docs {
        spec: PathBuf,
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Print the normalised object dictionary as JSON (values resolved for --node-id).
    Model {
        spec: PathBuf,
        #[arg(long, default_value_t = 1)]
        node_id: u8,
        #[arg(long)]
        mode: Option<String>,
    },
    /// Print the Rust code `device!` generates for a spec, formatted.
    Dump { spec: PathBuf },
    /// Decode one serial frame (hex bytes) by a spec's framing and command table.
    Decode {
        spec: PathBuf,
        /// The frame, e.g. "33 12 50 04" (quote it, or pass the bytes as separate arguments).
        #[arg(required = true, num_args = 1..)]
        bytes: Vec<String>,
        /// Which side sent it; without it both directions are tried.
        #[arg(long, value_parser = ["host", "device"])]
        from: Option<String>,
    },
    /// Print a JSON summary of a spec: name, identifier, modes, EDS file names, counts.
    Info { spec: PathBuf },
    /// Run a simulated device on an SLCAN bus hub over TCP (python-can:
    /// `can.Bus(interface='slcan', channel='socket://127.0.0.1:PORT', sleep_after_open=0)`).
    ///
    /// Lines on standard input are console commands for the first node, answered on standard
    /// output with `coforge sim: ok ...` or `coforge sim: error ...`. CO401Memory1 takes
    /// `supply <mV>` (the board's supply reading), `corrupt <bank 1|2> <offset> <value>` (one
    /// EEPROM byte, offsets as in the bank layout of coforge-storage) and `outputs`. CO401GW1
    /// takes `in <bits>` (bit n: input INn active), `emy0 on|off`, `emy1 on|off`, `enable
    /// [alt]` (what the host's 02 00 / 02 81 does) and `pins` (outputs, LEDs, watchdog).
    /// CR3101 takes `card remove`, `card insert [protected]`, `battery low|ok` and `leds`; its
    /// node-ID and mode come from 20F0h/20F1h and 20F5h at power-on, `--node-id` being the
    /// pair's factory setting and `--mode` overriding 20F5h.
    Sim {
        /// Device crate name: co401memory1, co401gw1, cr3101 or canopenia.
        device: String,
        /// Node-ID 1..=127 (the ID pins); for co401gw1, 0 sets its ID pins all high, so that
        /// the host programs the node-ID (100Bh) before it enables CAN.
        #[arg(long, default_value_t = 1)]
        node_id: u8,
        /// TCP port of the hub (0 picks a free one; the address is printed).
        #[arg(long, default_value_t = 0)]
        port: u16,
        /// Operating mode (default: the spec's first).
        #[arg(long)]
        mode: Option<String>,
        /// Keep stored parameters (1010h) in this file instead of in memory (CO401Memory1:
        /// its banks in FILE.bank1 and FILE.bank2; CANopenIA: its loaded configuration files in
        /// FILE.configuration).
        #[arg(long)]
        store: Option<PathBuf>,
        /// CR3101: the memory card in the slot is this image file (made and formatted, 64 MiB,
        /// if there is none; `coforge card` makes one of another size). Without it the slot
        /// holds a new card in memory. A PC reads the image with `mdir -i FILE@@1M ::`.
        #[arg(long)]
        card: Option<PathBuf>,
        /// Serve the first node's serial host interface on this TCP port (0 picks a free
        /// one; the address is printed). pyserial: `serial_for_url('socket://127.0.0.1:PORT')`.
        #[arg(long)]
        serial: Option<u16>,
        /// Enable the CAN side at start, as the serial host would (CO401GW1 starts with CAN
        /// off until its host enables it; mode digital_alt uses the alternate command).
        #[arg(long)]
        enable_can: bool,
        /// Run this many nodes, with node-IDs node_id, node_id + 1, ...
        #[arg(long, default_value_t = 1)]
        nodes: u8,
        /// Put this hub's bus on another SLCAN bus at HOST:PORT (another `coforge sim` or
        /// `coforge hub`, or an image's SLCAN UART), so devices of different kinds share one
        /// bus; repeatable.
        #[arg(long)]
        connect: Vec<String>,
        /// Stop after this many seconds (default: run until killed).
        #[arg(long)]
        seconds: Option<u64>,
    },
    /// Run an SLCAN bus hub over TCP with no simulated node, connected to SLCAN adapters such
    /// as firmware images in QEMU (their UART as a TCP server): python-canopen joins the hub
    /// and talks to the images as on a shared CAN bus.
    Hub {
        /// TCP port of the hub (0 picks a free one; the address is printed).
        #[arg(long, default_value_t = 0)]
        port: u16,
        /// An SLCAN adapter to connect to (HOST:PORT); repeatable.
        #[arg(long)]
        connect: Vec<String>,
        /// Stop after this many seconds (default: run until killed).
        #[arg(long)]
        seconds: Option<u64>,
    },
    /// Make a new memory card image for CR3101 (the simulator's card, QEMU's
    /// `-drive if=sd,format=raw,file=FILE`): an MBR with one FAT16 partition from 1 MiB on, as a
    /// PC formats a card. A PC reads it with `mdir -i FILE@@1M ::`.
    Card {
        /// The image file to write (replaced if it exists).
        file: PathBuf,
        /// Size in MiB: a power of two from 16 to 2048 (QEMU's SD card needs a power of two).
        #[arg(long, default_value_t = 16)]
        mib: u64,
        /// The volume label (up to 11 characters; 2000h holds the card's name).
        #[arg(long, default_value = "CANMEM")]
        label: String,
    },
    /// Talk to a CANopen bus through a bus hub (`coforge sim`, `coforge hub`): scan the nodes,
    /// read and write their dictionaries, send NMT commands, watch heartbeats and emergencies.
    Master {
        /// The hub's TCP port on this machine, or HOST:PORT (what `coforge sim` printed).
        #[arg(long)]
        port: String,
        /// How long to wait for each SDO answer.
        #[arg(long, default_value_t = 1000)]
        timeout_ms: u64,
        #[command(subcommand)]
        cmd: master::MasterCmd,
    },
    /// Rewrite specs in canonical formatting, or with --check report files that differ.
    Fmt {
        #[arg(long)]
        check: bool,
        #[arg(required = true)]
        specs: Vec<PathBuf>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli.command) {
        Ok(code) => code,
        Err(msg) => {
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}

/// Loads a spec and prints its diagnostics; `None` if it has errors.
fn load_reporting(path: &Path) -> Option<Loaded> {
    let loaded = load_file(path);
    if !loaded.diagnostics.items.is_empty() {
        eprintln!("{}", loaded.render_diagnostics());
    }
    if loaded.diagnostics.has_errors() { None } else { Some(loaded) }
}

fn write_output(output: Option<&Path>, text: &str) -> Result<(), String> {
    match output {
        Some(path) => std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display())),
        None => {
            use std::io::Write as _;
            // A closed pipe (`coforge eds x | head`) is not an error worth a panic.
            match std::io::stdout().lock().write_all(text.as_bytes()) {
                Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(format!("cannot write to stdout: {e}")),
                _ => Ok(()),
            }
        }
    }
}

/// How `coforge sim` was asked to run.
struct SimArgs<'a> {
    device: &'a str,
    first_id: u8,
    port: u16,
    mode: Option<&'a str>,
    store: Option<PathBuf>,
    card: Option<PathBuf>,
    count: u8,
    connect: &'a [String],
    seconds: Option<u64>,
    serial: Option<u16>,
    enable_can: bool,
}

fn sim(args: SimArgs<'_>) -> Result<ExitCode, String> {
    let SimArgs { device, first_id, port, mode, store, card, count, connect, seconds, serial, enable_can } = args;
    use coforge_sim::devices::{DeviceKind, StoreAt};
    let kind = DeviceKind::find(device)?;
    if count == 0 || u16::from(first_id) + u16::from(count) - 1 > 127 {
        return Err(format!("{count} nodes from node-ID {first_id} do not fit node-IDs 1..=127"));
    }
    if count > 1 && store.is_some() {
        return Err("--store keeps one node's parameters; use it with --nodes 1".into());
    }
    if count > 1 && card.is_some() {
        return Err("--card is one node's card; use it with --nodes 1".into());
    }
    let at = store.map_or(StoreAt::Memory, StoreAt::File);
    let mut nodes = (first_id..first_id + count)
        .map(|id| match &card {
            Some(card) => kind.create_with_card(mode, id, &at, card),
            None => kind.create(mode, id, &at),
        })
        .collect::<Result<Vec<_>, _>>()?;
    let hub = coforge_sim::hub::Hub::bind(("127.0.0.1", port)).map_err(|e| format!("cannot listen on port {port}: {e}"))?;
    connect_all(&hub, connect)?;
    let has_serial = nodes.first_mut().is_some_and(|n| n.host_port().is_some());
    let running = coforge_sim::runner::spawn(&hub, nodes);
    if enable_can {
        let command = if mode == Some("digital_alt") { "enable alt" } else { "enable" };
        for node in 0..usize::from(count) {
            running.control(node, command).map_err(|why| format!("--enable-can: {why}"))?;
        }
    }
    if let Some(serial_port) = serial {
        if !has_serial {
            return Err(format!("{} has no serial host interface", kind.name));
        }
        let port =
            coforge_sim::serial::serve(("127.0.0.1", serial_port), 0, running.inputs()).map_err(|e| format!("cannot listen on port {serial_port}: {e}"))?;
        println!("coforge sim: serial host on socket://{}", port.local_addr());
    }
    // Tests and scripts wait for this line before connecting.
    println!(
        "coforge sim: {} node-ID {first_id}{} on slcan socket://{}",
        kind.name,
        if count > 1 { format!("..{}", first_id + count - 1) } else { String::new() },
        hub.local_addr()
    );
    use std::io::Write as _;
    let _ = std::io::stdout().flush();
    let deadline = seconds.map(|s| std::time::Instant::now() + std::time::Duration::from_secs(s));
    console(&running, deadline);
    let stats = &running.stats;
    use std::sync::atomic::Ordering::Relaxed;
    println!(
        "coforge sim: {} frames in, {} frames out, {} of {} steps late",
        stats.frames_in.load(Relaxed),
        stats.frames_out.load(Relaxed),
        stats.late_steps.load(Relaxed),
        stats.steps.load(Relaxed)
    );
    running.stop();
    Ok(ExitCode::SUCCESS)
}

/// Runs console commands from standard input until the deadline (or forever).
fn console(running: &coforge_sim::runner::Running, deadline: Option<std::time::Instant>) {
    use std::io::{BufRead as _, Write as _};
    let (lines_tx, lines) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::stdin().lock().lines().map_while(Result::ok) {
            if lines_tx.send(line).is_err() {
                break;
            }
        }
    });
    loop {
        let wait = deadline.map_or(std::time::Duration::from_secs(3600), |d| d.saturating_duration_since(std::time::Instant::now()));
        if wait.is_zero() {
            return;
        }
        match lines.recv_timeout(wait) {
            Ok(line) if line.trim().is_empty() => {}
            Ok(line) => {
                match running.control(0, line.trim()) {
                    Ok(what) => println!("coforge sim: ok {what}"),
                    Err(why) => println!("coforge sim: error {why}"),
                }
                let _ = std::io::stdout().flush();
            }
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
            // Standard input closed: keep running until the deadline or a signal.
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => match deadline {
                Some(d) => std::thread::sleep(d.saturating_duration_since(std::time::Instant::now())),
                None => loop {
                    std::thread::park();
                },
            },
        }
    }
}

/// Puts `hub`'s bus on each SLCAN bus in `adapters` (HOST:PORT).
fn connect_all(hub: &coforge_sim::hub::Hub, adapters: &[String]) -> Result<(), String> {
    for addr in adapters {
        // An emulator may still be starting: give its UART a few seconds to listen.
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
        while let Err(e) = hub.connect(addr.as_str()) {
            if std::time::Instant::now() > deadline {
                return Err(format!("cannot connect to the SLCAN adapter at {addr}: {e}"));
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    }
    Ok(())
}

fn hub(port: u16, adapters: &[String], seconds: Option<u64>) -> Result<ExitCode, String> {
    let hub = coforge_sim::hub::Hub::bind(("127.0.0.1", port)).map_err(|e| format!("cannot listen on port {port}: {e}"))?;
    connect_all(&hub, adapters)?;
    println!("coforge hub: {} adapter(s) on slcan socket://{}", adapters.len(), hub.local_addr());
    use std::io::Write as _;
    let _ = std::io::stdout().flush();
    match seconds {
        Some(s) => std::thread::sleep(std::time::Duration::from_secs(s)),
        None => loop {
            std::thread::park();
        },
    }
    Ok(ExitCode::SUCCESS)
}

fn run(cmd: Cmd) -> Result<ExitCode, String> {
    match cmd {
        Cmd::Hub { port, connect, seconds } => hub(port, &connect, seconds),
        Cmd::Card { file, mib, label } => coforge_sim::card::CardImage::create(&file, mib << 20, &label)
            .map(|_| {
                println!("coforge card: {} ({mib} MiB, FAT16 from 1 MiB, label {label})", file.display());
                ExitCode::SUCCESS
            })
            .map_err(|e| format!("{}: {e}", file.display())),
        Cmd::Master { port, timeout_ms, cmd } => master::run(&port, timeout_ms, cmd),
        Cmd::Sim { device, node_id, port, mode, store, card, nodes, connect, seconds, serial, enable_can } => sim(SimArgs {
            device: &device,
            first_id: node_id,
            port,
            mode: mode.as_deref(),
            store,
            card,
            count: nodes,
            connect: &connect,
            seconds,
            serial,
            enable_can,
        }),
        Cmd::Check { specs } => {
            let mut failed = 0;
            for path in &specs {
                let loaded = load_file(path);
                if !loaded.diagnostics.items.is_empty() {
                    eprintln!("{}", loaded.render_diagnostics());
                }
                let errors = loaded.diagnostics.error_count();
                if errors > 0 {
                    failed += 1;
                    eprintln!("{}: {errors} error(s)", path.display());
                } else if let Some(d) = loaded.device() {
                    let entries: usize = d.objects.iter().map(|o| o.entries.len()).sum();
                    println!(
                        "{}: ok ({} objects, {entries} entries, {} PDOs, {} emergencies, {} serial commands, {} errata)",
                        path.display(),
                        d.objects.len(),
                        d.pdo.pdos.len(),
                        d.emergencies.len(),
                        d.serial.as_ref().map_or(0, |s| s.commands.len()),
                        d.errata.len()
                    );
                }
            }
            Ok(if failed > 0 { ExitCode::FAILURE } else { ExitCode::SUCCESS })
        }
        Cmd::Eds { spec, mode, output } => {
            let Some(loaded) = load_reporting(&spec) else { return Ok(ExitCode::FAILURE) };
            let device = loaded.device().ok_or("spec did not load")?;
            let text = coforge_spec::eds::export(device, mode.as_deref()).map_err(|e| e.to_string())?;
            write_output(output.as_deref(), &text)?;
            Ok(ExitCode::SUCCESS)
        }
        Cmd::Beds {
            input,
            from_eds,
            vendor_conventions,
            mode,
            node_id,
            bitrate,
            lss,
            autostart,
            nmt_master,
            manager,
            settings_from_hardware,
            ident,
            output,
        } => {
            use coforge_beds::layout::func;
            let flags = [
                (lss, func::LSS),
                (autostart, func::AUTOSTART),
                (nmt_master, func::BOOTUP_MANAGER),
                (manager, func::MANAGER),
                (settings_from_hardware, func::SETTINGS_FROM_HARDWARE),
            ];
            let func = flags.iter().filter(|(on, _)| *on).fold(0, |acc, (_, bit)| acc | bit);
            let bitrate_kbit = bitrate.parse().map_err(|_| format!("bad bit rate {bitrate}"))?;
            let bytes = if from_eds {
                let text = std::fs::read(&input).map_err(|e| format!("cannot read {}: {e}", input.display()))?;
                // EDS files are ISO-8859-1: each byte is the character of that code.
                let text: String = text.iter().map(|&b| char::from(b)).collect();
                let ident = ident.unwrap_or_else(|| coforge_spec::beds::eds_import::vendor_ident(&text, None));
                let settings = coforge_spec::beds::Settings { node_id, bitrate_kbit, func, ident };
                let conventions = if vendor_conventions { coforge_spec::beds::Conventions::canopenia() } else { Default::default() };
                coforge_spec::beds::export_eds(&text, settings, &conventions)
            } else {
                let Some(loaded) = load_reporting(&input) else { return Ok(ExitCode::FAILURE) };
                let device = loaded.device().ok_or("spec did not load")?;
                let ident = ident.unwrap_or_else(|| format!("'{}' coforge {}", device.identity.ident, env!("CARGO_PKG_VERSION")));
                let settings = coforge_spec::beds::Settings { node_id, bitrate_kbit, func, ident };
                coforge_spec::beds::export(device, mode.as_deref(), settings)
            }
            .map_err(|e| e.to_string())?;
            // Read back with the reader the firmware uses, so a file we write is one it takes.
            let file = coforge_beds::BinaryEds::parse(&bytes).map_err(|e| format!("internal error: the written file does not read back: {e}"))?;
            std::fs::write(&output, &bytes).map_err(|e| format!("cannot write {}: {e}", output.display()))?;
            let h = file.header();
            eprintln!(
                "coforge beds: {} ({} bytes): node {}, {} kbit/s, FUNC {:02X}h, {} SDO replies, {} + {} image entries ({} bytes), {} RPDOs, {} TPDOs",
                output.display(),
                bytes.len(),
                h.node_id,
                h.bitrate_kbit,
                h.func,
                file.sdo_replies().count(),
                file.od_entries().count(),
                file.generic_entries().count(),
                h.image_size,
                h.rpdos,
                h.tpdos
            );
            Ok(ExitCode::SUCCESS)
        }
        Cmd::Docs { spec, output } => {
            let Some(loaded) = load_reporting(&spec) else { return Ok(ExitCode::FAILURE) };
            let device = loaded.device().ok_or("spec did not load")?;
            write_output(output.as_deref(), &coforge_spec::docs::markdown(device))?;
            Ok(ExitCode::SUCCESS)
        }
        Cmd::Model { spec, node_id, mode } => {
            let Some(loaded) = load_reporting(&spec) else { return Ok(ExitCode::FAILURE) };
            let device = loaded.device().ok_or("spec did not load")?;
            let json = coforge_spec::eds::model_json(device, mode.as_deref(), node_id).map_err(|e| e.to_string())?;
            write_output(None, &format!("{json}\n"))?;
            Ok(ExitCode::SUCCESS)
        }
        Cmd::Dump { spec } => {
            let Some(loaded) = load_reporting(&spec) else { return Ok(ExitCode::FAILURE) };
            let device = loaded.device().ok_or("spec did not load")?;
            let code = coforge_codegen::pretty(coforge_codegen::generate(device, &coforge_codegen::Options::default()))?;
            write_output(None, &code)?;
            Ok(ExitCode::SUCCESS)
        }
        Cmd::Decode { spec, bytes, from } => {
            let Some(loaded) = load_reporting(&spec) else { return Ok(ExitCode::FAILURE) };
            let device = loaded.device().ok_or("spec did not load")?;
            let text = bytes.join(" ");
            let direction = from.as_deref().map(|f| if f == "host" { Direction::HostToDevice } else { Direction::DeviceToHost });
            match coforge_spec::frame::describe(device, &text, direction) {
                Ok(lines) => {
                    write_output(None, &lines)?;
                    Ok(ExitCode::SUCCESS)
                }
                Err(e) => {
                    eprintln!("error: {text}: {e}");
                    Ok(ExitCode::FAILURE)
                }
            }
        }
        Cmd::Info { spec } => {
            let Some(loaded) = load_reporting(&spec) else { return Ok(ExitCode::FAILURE) };
            let device = loaded.device().ok_or("spec did not load")?;
            write_output(None, &format!("{}\n", coforge_spec::eds::info_json(device)))?;
            Ok(ExitCode::SUCCESS)
        }
        Cmd::Fmt { check, specs } => {
            let mut differ = 0;
            for path in &specs {
                let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
                let formatted = coforge_spec::fmt::format(&text).map_err(|e| format!("{}: {e}", path.display()))?;
                if formatted != text {
                    if check {
                        differ += 1;
                        eprintln!("{}: not canonically formatted (run `coforge fmt {}`)", path.display(), path.display());
                        eprint!("{}", coforge_spec::fmt::first_difference(&text, &formatted));
                    } else {
                        std::fs::write(path, formatted).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
                        println!("formatted {}", path.display());
                    }
                }
            }
            Ok(if differ > 0 { ExitCode::FAILURE } else { ExitCode::SUCCESS })
        }
    }
}
