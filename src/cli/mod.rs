//! The `rtow` command line: parse flags, call the library, print. One module
//! per command; the library holds no CLI types.

mod args;
mod bench;
mod converge;
mod diff;
mod merge;
mod render;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use rtow::scene;
use rtow::{Error, Result};
use std::path::PathBuf;
use std::process::ExitCode;

/// `println!` that ignores a closed stdout (e.g. piped into `head`) instead of
/// panicking; what matters is in the files and the exit status.
macro_rules! say {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}

/// `eprintln!` that never panics: with stderr on a full or closed device the
/// message is lost, but the exit status stays the documented one.
macro_rules! tell {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($t)*);
    }};
}

#[derive(Parser)]
#[command(name = "rtow", about = "A data-oriented SIMD path tracer for Ray Tracing in One Weekend")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a preset or a scene file (.json / .toml) to PNG (and optionally a float image).
    Render(render::RenderArgs),
    /// Merge partial films (.rtfilm: the shards of one render) into the image,
    /// bit for bit the one-process render's.
    Merge(merge::MergeArgs),
    /// List the built-in scenes, by book (the stress scenes apart).
    Scenes,
    /// Measure rays/s (or, with --instructions, instructions per ray) of each kernel on a scene; compare with a saved baseline.
    Bench(bench::BenchArgs),
    /// Run time against error: measure kernels and estimator variants at several
    /// sample counts against a reference; write a CSV, a markdown table and a log-log plot.
    Converge(converge::ConvergeArgs),
    /// Compare image A with the reference B (PNG, EXR, PFM or .rtfilm): MSE, relMSE, the largest difference,
    /// FLIP, region z-tests when the noise is known; exit status 3 when a --max-* threshold is exceeded.
    Diff(diff::DiffArgs),
    /// Numerical stress tests against an f64 oracle, with both kernels; exit status 1 if a bound breaks.
    Stress {
        /// The small version (what `cargo test` runs).
        #[arg(long)]
        quick: bool,
        /// Seed of the sweeps and renders.
        #[arg(long, allow_negative_numbers = true, default_value_t = 1)]
        seed: u64,
        /// Worker threads [default: one per core]
        #[arg(long, allow_negative_numbers = true)]
        threads: Option<usize>,
    },
    /// Write a preset as a scene file (.json or .toml), or its meshes as Wavefront OBJ (.obj).
    Export {
        /// Preset name (see `rtow scenes`).
        preset: String,
        /// Output scene file, or .obj for the meshes (world space, one object a mesh).
        #[arg(short, long)]
        output: PathBuf,
        /// Every static sphere as an icosphere mesh of level N first (as `render --tessellate`).
        #[arg(long, value_name = "N")]
        tessellate: Option<u32>,
    },
    /// Print the JSON Schema of scene files (JSON, and TOML of the same shape), derived from rtow's scene types.
    Schema,
    /// Print a shell completion script: `rtow completions bash > ~/.local/share/bash-completion/completions/rtow`.
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print the manual page (roff): `rtow man > rtow.1; man ./rtow.1`.
    Man,
}

pub(crate) use say;
pub(crate) use tell;

/// Prints the stress tables; exits with status 1 when a bound is broken.
fn cmd_stress(quick: bool, seed: u64, threads: Option<usize>) -> Result<u8> {
    use std::io::Write;
    let cfg = rtow::instruments::stress::StressConfig { quick, seed, threads };
    let report = rtow::instruments::stress::run(&cfg, &mut |part| tell!("done: {part}"))?;
    say!("{}", report.table().trim_end_matches('\n'));
    let _ = std::io::stdout().flush();
    Ok(if report.passed() { 0 } else { 1 })
}

/// The exit status of a command that ran: 0; 1 when its check failed (bench,
/// stress); 3 when a comparison exceeded a threshold (diff).
fn run(cli: Cli) -> Result<u8> {
    match cli.command {
        Command::Render(a) => render::run(a),
        Command::Merge(a) => merge::run(a).map(|_| 0),
        Command::Bench(a) => bench::run(a).map(|ok| if ok { 0 } else { 1 }),
        Command::Converge(a) => converge::run(a).map(|_| 0),
        Command::Diff(a) => diff::run(a),
        Command::Scenes => {
            let width = scene::presets().iter().map(|p| p.name.len()).max().unwrap_or(0);
            for (i, &group) in scene::PresetGroup::ALL.iter().enumerate() {
                if i > 0 {
                    say!();
                }
                say!("{}:", group.title());
                for p in scene::presets().iter().filter(|p| p.group == group) {
                    say!("  {:<width$}  {}", p.name, p.description);
                }
            }
            Ok(0)
        }
        Command::Schema => {
            let text = serde_json::to_string_pretty(&scene::scene_schema()).expect("a schema is JSON") + "\n";
            write_stdout(text.as_bytes())
        }
        Command::Completions { shell } => {
            let mut out = Vec::new();
            clap_complete::generate(shell, &mut command(), "rtow", &mut out);
            write_stdout(&out)
        }
        Command::Man => {
            let mut out = Vec::new();
            clap_mangen::Man::new(command().version(env!("CARGO_PKG_VERSION")))
                .render(&mut out)
                .map_err(|e| Error::System(format!("cannot render the manual page: {e}")))?;
            write_stdout(&out)
        }
        Command::Stress { quick, seed, threads } => cmd_stress(quick, seed, threads),
        Command::Export { preset, output, tessellate } => {
            let mut s = scene::preset(&preset).ok_or_else(|| {
                let hint = scene::nearest_preset(&preset).map_or(String::new(), |p| format!("did you mean '{p}'? "));
                Error::Input(format!("unknown preset '{}' ({hint}see `rtow scenes`)", rtow::output::clip(&preset)))
            })?;
            if let Some(level) = tessellate {
                s = s.tessellate(level)?;
            }
            if output.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")) {
                scene::save_meshes_obj(&s, &output).map(|_| 0)
            } else {
                scene::save_scene(&s, &output).map(|_| 0)
            }
        }
    }
}

/// Help and version print as clap prints them; usage errors print as one
/// `error: ...` line (exit status 2), like every other error of rtow.
fn clap_exit(e: clap::Error) -> ! {
    use clap::error::ErrorKind;
    if matches!(
        e.kind(),
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        e.exit()
    }
    let text = e.to_string();
    let mut line = String::new();
    for part in text.lines().map(str::trim).filter(|l| !l.is_empty()) {
        if part.starts_with("For more information") {
            continue;
        }
        let part = part.strip_prefix("error: ").unwrap_or(part);
        if !line.is_empty() {
            line.push_str(if line.ends_with(':') { " " } else { "; " });
        }
        line.push_str(part);
    }
    tell!("error: {}", rtow::output::printable(&line));
    std::process::exit(2)
}

/// An error as the command line says it: a setting named by its flag.
pub(crate) fn message(e: &Error) -> String {
    match e {
        Error::Invalid { field, message } => format!("{}: {message}", args::flag_of(field).unwrap_or(field)),
        Error::InFile { path, error } => format!("{}: {}", path.display(), message(error)),
        e => e.to_string(),
    }
}

/// The command line's definition, with the version this build reports.
fn command() -> clap::Command {
    let version = format!("{}\n{}", rtow::provenance::version(), rtow::build_description());
    Cli::command().version(&*Box::leak(version.into_boxed_str()))
}

/// Writes generated text to stdout; a write error is an output failure (exit status 1).
fn write_stdout(bytes: &[u8]) -> Result<u8> {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    out.write_all(bytes)
        .and_then(|_| out.flush())
        .map_err(|e| Error::System(format!("cannot write to stdout: {e}")))?;
    Ok(0)
}

pub fn main() -> ExitCode {
    rtow::output::install_signal_cleanup();
    // The pool that prepares scenes (the trees' parallel builds) and renders
    // feature buffers and verified merges' pixels, with a render's stack
    // (`rtow::WORKER_STACK`). It cannot fail before any other pool exists.
    let _ = rayon::ThreadPoolBuilder::new().stack_size(rtow::WORKER_STACK).build_global();
    let cli = match command().try_get_matches().and_then(|m| Cli::from_arg_matches(&m)) {
        Ok(c) => c,
        Err(e) => clap_exit(e),
    };
    match run(cli) {
        Ok(status) => ExitCode::from(status),
        Err(e) => {
            // One line, bounded, whatever the input it quotes, its control
            // characters escaped (a file name in a scene file may hold any).
            let line = message(&e).replace('\n', " ");
            tell!("error: {}", rtow::output::clip_to(&rtow::output::printable(&line), 2000));
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
