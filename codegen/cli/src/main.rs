//! `coforge`: check specs, export EDS files and docs, keep spec files canonically formatted.
#![forbid(unsafe_code)]

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

fn run(cmd: Cmd) -> Result<ExitCode, String> {
    match cmd {
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
