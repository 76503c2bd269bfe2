//! The `rtow` command line: parse, call the library, show progress.

use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use rtow::output::{check_extension, Outputs};
use rtow::plan::AccelChoice;
use rtow::scene::{self, Scene};
use rtow::{Error, KernelKind, RenderOptions, Result, Settings};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

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
    Render(RenderArgs),
    /// List the built-in scenes.
    Scenes,
    /// Measure rays/s of each kernel on a scene; compare with a saved baseline.
    Bench(BenchArgs),
    /// Run time against error: measure kernels and estimator variants at several
    /// sample counts against a reference; write a CSV, a markdown table and a log-log plot.
    Converge(ConvergeArgs),
    /// Numerical stress tests against an f64 oracle, with both kernels; exit status 1 if a bound breaks.
    Stress {
        /// The small version (what `cargo test` runs).
        #[arg(long)]
        quick: bool,
        /// Seed of the sweeps and renders.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Worker threads [default: one per core]
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Write a preset as a scene file (.json or .toml).
    Export {
        /// Preset name (see `rtow scenes`).
        preset: String,
        /// Output scene file.
        #[arg(short, long)]
        output: PathBuf,
    },
}

/// Image settings shared by every command that renders.
#[derive(Args, Clone, Debug)]
struct ImageArgs {
    /// Image width in pixels [default: the scene's]
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels [default: the scene's]
    #[arg(long)]
    height: Option<u32>,
    /// Samples per pixel [default: the scene's]
    #[arg(long)]
    spp: Option<u32>,
    /// Maximum rays per path [default: the scene's, the book's 50]
    #[arg(long)]
    depth: Option<u32>,
    /// Seed of the random streams [default: the scene's, else 0]
    #[arg(long)]
    seed: Option<u64>,
    /// The book's final settings: 1200x675, 500 spp, depth 50 (flags given explicitly still win)
    #[arg(long)]
    book: bool,
    /// Worker threads [default: one per core]
    #[arg(long)]
    threads: Option<usize>,
    /// Tile edge in pixels
    #[arg(long, default_value_t = 16)]
    tile: u32,
    /// Closest-hit search: auto (by the plan), brute force, or BVH
    #[arg(long, value_enum, default_value_t = AccelChoice::Auto)]
    accel: AccelChoice,
}

#[derive(Args)]
struct RenderArgs {
    /// A preset name (see `rtow scenes`) or a scene file (.json / .toml).
    scene: String,
    /// Output PNG (8-bit, gamma encoded) [default: <scene name>.png]
    #[arg(short, long)]
    output: Option<PathBuf>,
    #[command(flatten)]
    image: ImageArgs,
    /// Kernel: the scalar reference or the SIMD wavefront.
    #[arg(long, value_enum, default_value_t = KernelKind::Simd)]
    kernel: KernelKind,
    /// Also write the linear image: .pfm or .exr.
    #[arg(long, value_name = "FILE")]
    float: Option<PathBuf>,
    /// Write render statistics as JSON.
    #[arg(long, value_name = "FILE")]
    stats_json: Option<PathBuf>,
    /// PNG gamma [default: 2 for path traced scenes, 1 for the debug chapters, as in the book]
    #[arg(long, value_parser = positive_f32)]
    gamma: Option<f32>,
    /// Print the render plan (what the scene needs) before rendering.
    #[arg(long)]
    explain: bool,
    #[command(flatten)]
    estimator: EstimatorArgs,
    /// No progress bar and no summary line.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Args)]
struct BenchArgs {
    /// A preset name or a scene file.
    #[arg(default_value = "final")]
    scene: String,
    /// Kernels to measure, in order.
    #[arg(long, value_delimiter = ',', default_value = "scalar,simd")]
    kernels: Vec<KernelKind>,
    #[command(flatten)]
    image: ImageArgs,
    /// Renders per kernel; the median-time one is reported.
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Write the report as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Save the report as a baseline for later runs.
    #[arg(long, value_name = "FILE")]
    save: Option<PathBuf>,
    /// Compare with a saved baseline: exit status 1 if throughput fell by more
    /// than the tolerance or the image changed.
    #[arg(long, value_name = "FILE")]
    baseline: Option<PathBuf>,
    /// Allowed throughput drop against the baseline, in percent.
    #[arg(long, default_value_t = 5.0)]
    tolerance: f64,
}

fn cmd_bench(a: BenchArgs) -> Result<bool> {
    // Everything is checked before the first measurement: the scene, the
    // flags, the baseline against this run, and every output path.
    rtow::limits::check_threads(a.image.threads)?;
    let (scene, name) = load(&a.scene)?;
    let s = settings(&scene, &a.image);
    s.validate()?;
    if a.image.tile != 16 {
        return Err(Error::invalid("--tile", "rtow bench uses the default tile size"));
    }
    if !(a.tolerance >= 0.0) {
        return Err(Error::invalid("--tolerance", "must be a percentage >= 0"));
    }
    if a.repeat == 0 {
        return Err(Error::invalid("--repeat", "must be at least 1"));
    }
    let baseline = a.baseline.as_deref().map(rtow::tools::bench::Baseline::load).transpose()?;
    if let Some(b) = &baseline {
        b.check_matches(&name, s, &a.kernels)?;
    }
    let mut outputs = Outputs::new();
    if scene::preset(&a.scene).is_none() {
        outputs.input(Path::new(&a.scene), "scene file");
    }
    if let Some(b) = &a.baseline {
        outputs.input(b, "baseline");
    }
    let mut ids = Vec::new();
    for (path, flag) in [(&a.json, "--json"), (&a.save, "--save")] {
        if let Some(p) = path {
            ids.push(outputs.add(p, flag)?);
        }
    }
    tell!(
        "bench {name}: {}x{} {} spp depth {} seed {}, {} repetition(s) per kernel, built for {}",
        s.width,
        s.height,
        s.spp,
        s.max_depth,
        s.seed,
        a.repeat,
        rtow::isa()
    );
    let report =
        rtow::tools::bench::run(&scene, &name, s, &a.kernels, a.image.threads, a.image.accel, a.repeat, |k, i, st| {
            tell!("  {} run {}: {:.3} s, {:.2} Mrays/s", k.name(), i + 1, st.seconds, st.mrays_per_s)
        })?;
    say!("{}", report.table().trim_end_matches('\n'));
    let json = report.to_json();
    for id in ids {
        outputs.stage(id, json.as_bytes())?;
    }
    outputs.commit()?;
    let mut ok = true;
    if let Some(b) = &baseline {
        for c in rtow::tools::bench::compare(&report, b, a.tolerance)? {
            say!(
                "{:<7} baseline {:.2} Mrays/s -> {:.2} Mrays/s ({:+.1}%), image {}: {}",
                c.kernel,
                c.baseline_mrays,
                c.mrays,
                c.change_percent,
                if c.image_same { "identical" } else { "CHANGED" },
                if c.regressed { "REGRESSION" } else { "ok" }
            );
            ok &= !c.regressed;
        }
    }
    Ok(ok)
}

fn positive_f32(s: &str) -> std::result::Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        Ok(v) => Err(format!("must be a finite number > 0, got {v}")),
        Err(e) => Err(e.to_string()),
    }
}

/// Russian roulette and adaptive sampling (both off by default).
#[derive(Args, Clone, Debug)]
struct EstimatorArgs {
    /// Russian roulette: after a few bounces a path survives with probability
    /// min(1, max throughput component) and is reweighted (unbiased; changes the noise).
    #[arg(long)]
    rr: bool,
    /// With --rr: the roulette starts once a path has traced N rays.
    #[arg(long, value_name = "N", default_value_t = rtow::estimator::ROULETTE_AFTER_RAYS)]
    rr_after: u32,
    /// Adaptive sampling: a pixel stops taking samples once the relative
    /// standard error of its mean is at most THRESHOLD (e.g. 0.02); --spp is the maximum.
    #[arg(long, value_name = "THRESHOLD")]
    adaptive: Option<f32>,
    /// Adaptive sampling decides after N, 2N, 4N, ... samples.
    #[arg(long, value_name = "N", default_value_t = rtow::estimator::ADAPTIVE_MIN_SPP)]
    adaptive_min: u32,
}

impl EstimatorArgs {
    fn adaptive(&self) -> Result<Option<rtow::estimator::Adaptive>> {
        self.adaptive.map(|t| rtow::estimator::Adaptive::new(t, self.adaptive_min)).transpose()
    }
}

#[derive(Args)]
struct ConvergeArgs {
    /// A preset name (see `rtow scenes`) or a scene file (.json / .toml).
    scene: String,
    /// Kernels to measure, comma separated.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "simd")]
    kernels: Vec<KernelKind>,
    /// Estimator variants, comma separated: plain, rr (roulette after the default number of rays),
    /// rr:N (after N rays), adaptive (threshold 0.02), adaptive:THRESHOLD, or combinations such as
    /// rr+adaptive:0.05. The first kernel's first variant is the baseline.
    #[arg(long, value_delimiter = ',', default_value = "plain,rr,adaptive")]
    variants: Vec<String>,
    /// Samples per pixel to measure, increasing (the maximum, for adaptive variants).
    #[arg(long, value_delimiter = ',', default_value = "4,16,64,256")]
    spp_list: Vec<u32>,
    /// A linear reference image (.exr or .pfm) of the same size.
    #[arg(long, value_name = "FILE", conflicts_with = "reference_spp")]
    reference: Option<PathBuf>,
    /// Render the reference with N samples per pixel (and a different seed)
    /// [default: 8 x the largest --spp-list value]
    #[arg(long, value_name = "N")]
    reference_spp: Option<u32>,
    /// Output folder for <scene>.csv, <scene>.md, <scene>.svg (and <scene>-reference.exr).
    #[arg(long, default_value = "converge")]
    out: PathBuf,
    /// Image width in pixels [default: the scene's]
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels [default: the scene's]
    #[arg(long)]
    height: Option<u32>,
    /// Maximum rays per path [default: the scene's]
    #[arg(long)]
    depth: Option<u32>,
    /// Seed of the measured renders (the reference uses a seed derived from it) [default: the scene's, else 0]
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads [default: one per core]
    #[arg(long)]
    threads: Option<usize>,
    /// Tile edge in pixels
    #[arg(long, default_value_t = 16)]
    tile: u32,
    /// Render every measurement N times, in N passes over all of them, and keep the fastest
    /// time (the image is the same).
    #[arg(long, value_name = "N", default_value_t = 1)]
    repeat: u32,
    /// Adaptive variants decide after N, 2N, 4N, ... samples.
    #[arg(long, value_name = "N", default_value_t = rtow::estimator::ADAPTIVE_MIN_SPP)]
    adaptive_min: u32,
    /// Also report what every configuration needs to reach the error of the baseline at N spp
    /// (N from --spp-list).
    #[arg(long, value_name = "N")]
    at_spp: Option<u32>,
}

fn cmd_converge(a: ConvergeArgs) -> Result<()> {
    use rtow::tools::converge::{self, Event, Reference, Variant};
    rtow::limits::check_threads(a.threads)?;
    let (scene, name) = load(&a.scene)?;
    let mut s = rtow::default_settings(&scene);
    s.width = a.width.unwrap_or(s.width);
    s.height = a.height.unwrap_or(s.height);
    s.max_depth = a.depth.unwrap_or(s.max_depth);
    s.seed = a.seed.unwrap_or(s.seed);
    let variants = a.variants.iter().map(|v| Variant::parse(v)).collect::<Result<Vec<_>>>()?;
    let reference = match (&a.reference, a.reference_spp) {
        (Some(p), _) => Reference::File(p.clone()),
        (None, Some(n)) => Reference::Spp(n),
        (None, None) => {
            let max = a.spp_list.iter().copied().max().unwrap_or(1);
            Reference::Spp(max.checked_mul(8).ok_or_else(|| {
                Error::invalid("--spp-list", format!("{max} is too large for the default --reference-spp (8x)"))
            })?)
        }
    };
    let cfg = converge::Config {
        settings: s,
        kernels: a.kernels.clone(),
        variants,
        spp_list: a.spp_list.clone(),
        reference: reference.clone(),
        threads: a.threads,
        tile: a.tile,
        repeat: a.repeat,
        adaptive_min: a.adaptive_min,
        at_spp: a.at_spp,
    };
    cfg.validate()?;
    if a.out.exists() && !a.out.is_dir() {
        return Err(Error::Output { path: a.out.clone(), message: "--out must be a folder".into() });
    }
    say!("{name}: {}x{}, depth {}, seed {}", s.width, s.height, s.max_depth, s.seed);
    let px = s.width as f64 * s.height as f64;
    let mut header = false;
    let report = converge::run(&scene, &name, &cfg, |e| match e {
        Event::ReferenceStart(n) => say!("reference: {n} spp with seed {} ...", converge::reference_seed(s.seed)),
        Event::ReferenceDone { seconds } => say!("reference: done in {seconds:.2} s"),
        Event::Measured(r) => {
            if !std::mem::replace(&mut header, true) {
                say!(
                    "  {:<6} {:<18} {:>6} {:>9} {:>9} {:>8} {:>10} {:>10} {:>10} {:>11}",
                    "kernel",
                    "variant",
                    "spp",
                    "seconds",
                    "Mrays/s",
                    "spp/px",
                    "RMSE",
                    "relMSE",
                    "signed err",
                    "efficiency"
                );
            }
            say!(
                "  {:<6} {:<18} {:>6} {:>9.3} {:>9.2} {:>8.1} {:>10.5} {:>10.3e} {:>+10.5} {:>11.4e}",
                r.kernel.name(),
                r.variant.name(),
                r.spp,
                r.seconds,
                r.rays as f64 / r.seconds / 1e6,
                r.samples as f64 / px,
                r.rmse,
                r.relmse,
                r.mean_rel_error,
                r.efficiency()
            )
        }
    })?;
    for l in report.comparison_lines().iter().chain(&report.reach_lines()) {
        say!("{l}");
    }
    for p in report.write(&a.out)? {
        say!("wrote {}", p.display());
    }
    let mismatches = report.kernel_mismatches();
    if !mismatches.is_empty() {
        return Err(Error::Input(format!("the kernels must agree bit for bit, but {}", mismatches.join("; "))));
    }
    Ok(())
}

/// A preset or a file: the scene and a short name for default outputs.
fn load(spec: &str) -> Result<(Scene, String)> {
    if let Some(s) = scene::preset(spec) {
        return Ok((s, spec.to_string()));
    }
    let path = Path::new(spec);
    if path.extension().is_some() || path.exists() {
        let s = scene::load_scene(path)?;
        let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into());
        return Ok((s, name));
    }
    Err(Error::Input(format!("unknown scene '{spec}': not a preset (see `rtow scenes`) and not a .json/.toml file")))
}

fn settings(scene: &Scene, a: &ImageArgs) -> Settings {
    let mut s = rtow::default_settings(scene);
    if a.book {
        s.width = 1200;
        s.height = 675;
        s.spp = 500;
        s.max_depth = 50;
    }
    s.width = a.width.unwrap_or(s.width);
    s.height = a.height.unwrap_or(s.height);
    s.spp = a.spp.unwrap_or(s.spp);
    s.max_depth = a.depth.unwrap_or(s.max_depth);
    s.seed = a.seed.unwrap_or(s.seed);
    s
}

fn progress_bar(quiet: bool) -> Option<ProgressBar> {
    if quiet || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta} {msg}")
            .expect("valid template"),
    );
    Some(bar)
}

/// Renders with a progress bar (on a terminal) showing live Mrays/s.
fn render_with_progress(scene: &Scene, s: Settings, opts: RenderOptions, quiet: bool) -> Result<rtow::Rendered> {
    let bar = progress_bar(quiet);
    let start = Instant::now();
    let cb = |p: rtow::render::Progress| {
        if let Some(b) = &bar {
            b.set_length(p.tiles_total);
            b.set_position(p.tiles_done);
            let secs = start.elapsed().as_secs_f64().max(1e-9);
            b.set_message(format!("{:.2} Mrays/s", p.rays as f64 / secs / 1e6));
        }
    };
    let out = rtow::render(scene, s, opts, Some(&cb));
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    out
}

fn cmd_render(a: RenderArgs) -> Result<()> {
    rtow::limits::check_threads(a.image.threads)?;
    let (scene, name) = load(&a.scene)?;
    let s = settings(&scene, &a.image);
    let out = a.output.clone().unwrap_or_else(|| PathBuf::from(format!("{name}.png")));
    check_extension(&out, &["png"], "-o")?;
    if let Some(f) = &a.float {
        check_extension(f, &["pfm", "exr"], "--float")?;
    }
    // Bad input first (exit 2), then every output path, before the render:
    // the outputs are one transaction, written only when all of them are ready.
    s.validate()?;
    let mut outputs = Outputs::new();
    if scene::preset(&a.scene).is_none() {
        outputs.input(Path::new(&a.scene), "scene file");
    }
    let png_id = outputs.add(&out, "-o")?;
    let float_id = a.float.as_deref().map(|f| outputs.add(f, "--float")).transpose()?;
    let stats_id = a.stats_json.as_deref().map(|j| outputs.add(j, "--stats-json")).transpose()?;
    let opts = RenderOptions {
        kernel: a.kernel,
        threads: a.image.threads,
        tile: a.image.tile,
        accel: a.image.accel,
        rr: a.estimator.rr,
        rr_after: a.estimator.rr_after,
        adaptive: a.estimator.adaptive()?,
    };
    if a.explain {
        let prep = rtow::plan::Prepared::new(&scene, s, a.image.accel)?;
        say!("{}", prep.plan.explain());
    }
    let r = render_with_progress(&scene, s, opts, a.quiet)?;
    r.stats.check_finite()?;
    let gamma = a.gamma.unwrap_or(scene.mode.default_gamma());
    outputs.stage(png_id, &rtow::output::image_bytes(&r.image, &out, gamma)?)?;
    if let (Some(id), Some(f)) = (float_id, &a.float) {
        outputs.stage(id, &rtow::output::image_bytes(&r.image, f, 1.0)?)?;
    }
    if let Some(id) = stats_id {
        let text = serde_json::to_string_pretty(&r.stats).expect("stats serialize") + "\n";
        outputs.stage(id, text.as_bytes())?;
    }
    outputs.commit()?;
    if !a.quiet {
        let st = &r.stats;
        say!(
            "{name}: {}x{} {} spp -> {}: {} rays, {} samples in {:.3} s = {:.2} Mrays/s ({} kernel, {} threads, {}){}",
            st.width,
            st.height,
            st.spp,
            out.display(),
            st.rays,
            st.samples,
            st.seconds,
            st.mrays_per_s,
            st.kernel,
            st.threads,
            st.isa,
            if st.rejected_samples > 0 {
                format!(", {} NaN/Inf samples rejected", st.rejected_samples)
            } else {
                String::new()
            }
        );
    }
    Ok(())
}

/// Prints the stress tables; exits with status 1 when a bound is broken.
fn cmd_stress(quick: bool, seed: u64, threads: Option<usize>) -> Result<bool> {
    rtow::limits::check_threads(threads)?;
    use std::io::Write;
    let cfg = rtow::tools::stress::Config { quick, seed, threads };
    let report = rtow::tools::stress::run(&cfg, &mut |part| tell!("done: {part}"))?;
    say!("{}", report.table().trim_end_matches('\n'));
    let _ = std::io::stdout().flush();
    Ok(report.passed())
}

/// Ok(false): the command ran but its check failed (exit status 1).
fn run(cli: Cli) -> Result<bool> {
    match cli.command {
        Command::Render(a) => cmd_render(a).map(|_| true),
        Command::Bench(a) => cmd_bench(a),
        Command::Converge(a) => cmd_converge(a).map(|_| true),
        Command::Scenes => {
            let width = scene::presets().iter().map(|p| p.name.len()).max().unwrap_or(0);
            for p in scene::presets() {
                say!("{:<width$}  {}", p.name, p.description);
            }
            Ok(true)
        }
        Command::Stress { quick, seed, threads } => cmd_stress(quick, seed, threads),
        Command::Export { preset, output } => {
            let s = scene::preset(&preset)
                .ok_or_else(|| Error::Input(format!("unknown preset '{preset}' (see `rtow scenes`)")))?;
            check_extension(&output, &["json", "toml"], "-o")?;
            scene::save_scene(&s, &output).map(|_| true)
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
    tell!("error: {line}");
    std::process::exit(2)
}

pub fn main() -> ExitCode {
    rtow::output::install_signal_cleanup();
    let version = format!("{} (SIMD: {})", env!("CARGO_PKG_VERSION"), rtow::isa());
    let version: &'static str = Box::leak(version.into_boxed_str());
    let cli = match Cli::command().version(version).try_get_matches().and_then(|m| Cli::from_arg_matches(&m)) {
        Ok(c) => c,
        Err(e) => clap_exit(e),
    };
    match run(cli) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            tell!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
