//! `rtow bench`: rays/s and work per ray of each kernel; baselines.

use super::args::{choice, kernel_parser, ImageArgs, RunArgs};
use super::{say, tell};
use clap::Args;
use rtow::instruments::bench::{self, Baseline, BaselineVerdict, BenchConfig, Gate, DEFAULT_REPEAT, DEFAULT_TOLERANCE};
use rtow::instruments::instructions::{
    self, CountedProcess, InstructionsBaseline, InstructionsEntry, InstructionsReport,
};
use rtow::output::{OutputId, Outputs};
use rtow::{Error, Job, KernelChoice, Result, SceneSource};
use std::ffi::OsString;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct BenchArgs {
    /// A preset name or a scene file.
    #[arg(default_value = "final")]
    scene: String,
    /// Kernels to measure, in order (simd: the widest this build has).
    #[arg(long, value_delimiter = ',', value_parser = kernel_parser(), default_value = "scalar,simd")]
    kernels: Vec<KernelChoice>,
    #[command(flatten)]
    image: ImageArgs,
    #[command(flatten)]
    run: RunArgs,
    /// Timed renders per kernel; the median-time one is reported (plus one render with the work counters on).
    #[arg(long, allow_negative_numbers = true, default_value_t = DEFAULT_REPEAT)]
    repeat: usize,
    /// Write the report as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Save the report as a baseline for later runs.
    #[arg(long, value_name = "FILE")]
    save: Option<PathBuf>,
    /// Compare with a saved baseline of the same scene, settings and thread count:
    /// exit status 1 if the image changed, the work per ray grew, or (--gate time)
    /// throughput fell by more than the tolerance beyond the noise of the runs.
    #[arg(long, value_name = "FILE")]
    baseline: Option<PathBuf>,
    /// Allowed throughput drop against the baseline, in percent.
    #[arg(long, default_value_t = DEFAULT_TOLERANCE, allow_negative_numbers = true)]
    tolerance: f64,
    /// What a comparison with --baseline fails on: time (the image, the work, and a
    /// slowdown the noise cannot explain) or work (the image and the exact work
    /// counters only: for a noisy CI; timings are still printed).
    #[arg(long, value_parser = choice::<Gate>(Gate::NAMES), default_value = "time")]
    gate: Gate,
    /// Instead of timing: the traversal work per packet at each ray depth (how
    /// coherence is lost bounce by bounce), for each kernel, from one counted render.
    #[arg(long)]
    by_depth: bool,
    /// Instead of timing: instructions per ray of each kernel, counted exactly by
    /// valgrind's callgrind (this executable re-run under it, once per kernel):
    /// deterministic on any load; --save / --baseline compare counts exactly. A build
    /// with the `phases` feature also splits the render loop by phase.
    #[arg(long, conflicts_with_all = ["by_depth", "gate", "tolerance", "repeat"])]
    instructions: bool,
    /// With --instructions: also simulate the branch predictor (callgrind's
    /// --branch-sim=yes) and report branches and mispredictions per ray, by phase
    /// in a `phases` build (the counted runs take about twice as long).
    #[arg(long, requires = "instructions")]
    branch_sim: bool,
    /// With --instructions --baseline: the rise in a kernel's count that still
    /// passes, in percent of the baseline's (0: exact; the CI gate allows 0.5,
    /// for the C library's memcpy and the like, which differ between machines).
    #[arg(long, value_name = "PERCENT", default_value_t = 0.0, allow_negative_numbers = true, requires_all = ["instructions", "baseline"])]
    max_rise: f64,
    /// With --instructions --save: one line kept in the baseline saying why
    /// these counts are the baseline (what a committed baseline's change was for).
    #[arg(long, value_name = "TEXT", requires_all = ["instructions", "save"])]
    reason: Option<String>,
    /// The process --instructions counts: render once, print the result.
    #[arg(long, hide = true)]
    instructions_child: bool,
}

/// Ok(false): a regression against the baseline (exit status 1).
pub fn run(a: BenchArgs) -> Result<bool> {
    let source = a.image.open(&a.scene)?;
    let job = Job::from_source(&source, &a.image.overrides(), &a.run.options(KernelChoice::Simd))?;
    let name = &source.name;
    if a.instructions_child {
        // The process `--instructions` counts: one render of one kernel, no output file.
        let kernel = a.kernels.first().copied().unwrap_or(KernelChoice::Simd);
        let job = job.with_options(&rtow::RenderOptions { kernel, ..*job.options() })?;
        say!("{}", instructions::child_render(&job)?);
        return Ok(true);
    }
    // Everything is checked before anything is measured.
    let cfg = BenchConfig::new(&job, &a.kernels, a.repeat, a.tolerance, a.gate)?;
    if a.instructions {
        return count_instructions(&a, &source, &job);
    }
    let baseline = a.baseline.as_deref().map(Baseline::load).transpose()?;
    if let Some(b) = &baseline {
        b.check(name, job.settings(), job.threads(), &a.kernels)?;
    }
    let (outputs, ids) = outputs(&a, &source)?;
    if a.by_depth {
        for (kernel, rows) in bench::work_by_depth_per_kernel(&cfg)? {
            say!("{}:", kernel.name());
            say!("{}", bench::depth_table(&rows).trim_end());
        }
        return Ok(true);
    }
    let s = job.settings();
    tell!(
        "bench {name}: {}x{} {} spp depth {} seed {}, {} sampler, {} estimator, {} repetition(s) per kernel, built for {}",
        s.width,
        s.height,
        s.spp,
        s.max_depth,
        s.seed,
        s.sampler,
        s.estimator,
        a.repeat,
        rtow::isa()
    );
    let report = bench::run(&cfg, name, |k, i, st| {
        tell!("  {} run {}: {:.3} s, {:.2} Mrays/s", k.name(), i + 1, st.seconds, st.mrays_per_s)
    })?;
    write_report(&report.table(), &report.to_json(), outputs, ids)?;
    Ok(baseline.as_ref().is_none_or(|b| print_comparison(&report, b, &cfg)))
}

/// The outputs are one transaction: distinct from each other and from the
/// inputs, checked now, written together after the measurements.
fn outputs(a: &BenchArgs, source: &SceneSource) -> Result<(Outputs, Vec<OutputId>)> {
    let mut outputs = Outputs::new();
    if let Some(f) = &source.file {
        outputs.input(f, "scene file");
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
    Ok((outputs, ids))
}

/// Prints a report's table and writes its JSON to every output, together.
fn write_report(table: &str, json: &str, mut outputs: Outputs, ids: Vec<OutputId>) -> Result<()> {
    say!("{}", table.trim_end_matches('\n'));
    for id in ids {
        outputs.stage(id, json.as_bytes())?;
    }
    outputs.commit()
}

/// `--instructions`: each kernel counted under callgrind; against a baseline, exactly.
fn count_instructions(a: &BenchArgs, source: &SceneSource, job: &Job) -> Result<bool> {
    instructions::check_max_rise(a.max_rise)?;
    if let Some(r) = &a.reason {
        instructions::check_reason(r)?;
    }
    rtow::instruments::callgrind::valgrind_version()?;
    // The baseline file is read first, whichever build counts: one that is
    // not an instruction baseline is refused here, before a build for
    // valgrind is looked for (that build checks it against its own run).
    let baseline = a.baseline.as_deref().map(InstructionsBaseline::load).transpose()?;
    if cfg!(target_feature = "avx512f") {
        if let Some(v3) = countable_build()? {
            return delegate(&v3);
        }
    }
    if let Some(b) = &baseline {
        b.check(&source.name, job.settings(), job.threads(), &a.kernels)?;
    }
    let (outputs, ids) = outputs(a, source)?;
    let program = std::env::current_exe().map_err(|e| Error::System(format!("cannot find this executable: {e}")))?;
    let child_args = |job: &Job| counted_command(&a.scene, a.image.tessellate, job);
    rtow::instruments::callgrind::valgrind_version()?;
    rtow::instruments::callgrind::check_countable_build()?;
    let s = job.settings();
    tell!(
        "bench --instructions {}: {}x{} {} spp depth {} seed {}, {} sampler, {} estimator, {} thread(s), built for \
         {}; each kernel under callgrind (about 50x slower than a plain render)",
        source.name,
        s.width,
        s.height,
        s.spp,
        s.max_depth,
        s.seed,
        s.sampler,
        s.estimator,
        job.threads(),
        rtow::isa()
    );
    let process = CountedProcess { program: &program, child_args: &child_args, branch_sim: a.branch_sim };
    let mut report = instructions::count(job, &source.name, &a.kernels, &process, tell_count)?;
    report.reason = a.reason.clone();
    write_report(&report.table(), &report.to_json(), outputs, ids)?;
    let Some(b) = baseline else { return Ok(true) };
    Ok(print_instructions_comparison(&report, &b, a.max_rise))
}

/// Where an x86-64-v3 build of this rtow is looked for when this one uses
/// AVX-512 (which valgrind does not know): `RTOW_COUNT_WITH`, else
/// `target/isa-v3/x86_64-unknown-linux-gnu/release/rtow` beside this build's
/// `target/release/rtow` (where the README's command and the gate build it).
/// `None` when there is none; an error when the one found is of another
/// commit (it would count other code).
fn countable_build() -> Result<Option<PathBuf>> {
    let named = std::env::var_os("RTOW_COUNT_WITH").filter(|v| !v.is_empty()).map(PathBuf::from);
    let found = named.clone().or_else(|| {
        let me = std::env::current_exe().ok()?;
        let target = me.parent()?.parent()?;
        Some(target.join("isa-v3/x86_64-unknown-linux-gnu/release/rtow"))
    });
    let Some(path) = found.filter(|p| p.is_file()) else {
        return match named {
            Some(p) => Err(Error::invalid("RTOW_COUNT_WITH", format!("{}: not a file", p.display()))),
            None => Ok(None),
        };
    };
    let theirs = std::process::Command::new(&path)
        .arg("--version")
        .output()
        .map_err(|e| Error::System(format!("cannot run {}: {e}", path.display())))?;
    let text = String::from_utf8_lossy(&theirs.stdout);
    let (version, isa) = (text.lines().next().unwrap_or_default(), text.lines().nth(1).unwrap_or_default());
    if version != format!("rtow {}", rtow::provenance::version()) || isa.contains("AVX-512") {
        return Err(Error::System(format!(
            "this build uses AVX-512, which valgrind does not know, and {} is not an x86-64-v3 build of this \
             rtow ({version}; {isa}): rebuild it with RUSTFLAGS=\"-C target-cpu=x86-64-v3\" cargo build --release \
             --target x86_64-unknown-linux-gnu --target-dir target/isa-v3",
            path.display(),
        )));
    }
    Ok(Some(path))
}

/// Runs this very command line with the x86-64-v3 build `v3` instead (it
/// counts, prints and writes everything); its exit status is this one's.
fn delegate(v3: &Path) -> Result<bool> {
    tell!(
        "bench --instructions: this build uses AVX-512, which valgrind does not know; counting with {}",
        v3.display()
    );
    let status = std::process::Command::new(v3)
        .args(std::env::args_os().skip(1))
        .status()
        .map_err(|e| Error::System(format!("cannot run {}: {e}", v3.display())))?;
    match status.code() {
        Some(0) => Ok(true),
        Some(1) => Ok(false),
        // Any other status (2: a refused input) is passed on as it is; the
        // build that counted already said why.
        Some(code) => std::process::exit(code),
        None => Err(Error::System(format!("{} ended with {status} (its messages are above)", v3.display()))),
    }
}

/// The process `--instructions` counts: this very command line's job (the
/// scene `scene`), one kernel, rendered once.
fn counted_command(scene: &str, tessellate: Option<u32>, job: &Job) -> Vec<OsString> {
    let s = job.settings();
    let mut v: Vec<String> = vec!["bench".into(), scene.to_string()];
    for (flag, value) in [
        ("--width", s.width.to_string()),
        ("--height", s.height.to_string()),
        ("--spp", s.spp.to_string()),
        ("--depth", s.max_depth.to_string()),
        ("--seed", s.seed.to_string()),
        ("--sampler", s.sampler.name().to_string()),
        ("--estimator", s.estimator.name().to_string()),
        ("--threads", job.threads().to_string()),
        ("--accel", job.options().accel.name().to_string()),
        ("--kernels", job.kernel().name().to_string()),
    ] {
        v.push(flag.into());
        v.push(value);
    }
    if let Some(level) = tessellate {
        v.push("--tessellate".into());
        v.push(level.to_string());
    }
    v.push("--instructions-child".into());
    v.into_iter().map(OsString::from).collect()
}

/// Tells one kernel's count as it is made.
fn tell_count(e: &InstructionsEntry) {
    match &e.branches {
        Some(b) => tell!(
            "  {}: {} instructions, {:.2} per ray; {:.3} mispredicted branches per ray",
            e.kernel,
            e.instructions,
            e.per_ray,
            b.mispredicts_per_ray
        ),
        None => tell!("  {}: {} instructions, {:.2} per ray", e.kernel, e.instructions, e.per_ray),
    }
}

/// Prints each kernel's count against the instruction baseline (after a note
/// if another compiler built the baseline); false on a regression.
fn print_instructions_comparison(report: &InstructionsReport, b: &InstructionsBaseline, max_rise: f64) -> bool {
    if b.provenance.rustc != report.provenance.rustc {
        say!(
            "note: the baseline was built with {}, this run with {}: counts depend on the compiler",
            rtow::output::clip(&b.provenance.rustc),
            report.provenance.rustc
        );
    }
    if let Some(r) = &b.reason {
        say!("baseline: {}", rtow::output::clip_to(r, instructions::MAX_REASON_CHARS));
    }
    let mut ok = true;
    for c in instructions::compare(report, b, max_rise) {
        let delta = c.instructions as i128 - c.baseline as i128;
        let verdict = match (c.image_same, delta) {
            (false, _) => "REGRESSION (the image changed)".to_string(),
            (true, 0) => "ok (identical)".to_string(),
            (true, d) if c.regressed => format!("REGRESSION ({d:+} instructions, {max_rise}% allowed)"),
            (true, d) if d > 0 => format!("ok ({d:+} instructions, within the {max_rise}% allowed)"),
            (true, d) => format!("ok ({d:+} instructions)"),
        };
        say!(
            "{:<7} baseline {} -> {} instructions ({:.2} -> {:.2} per ray, {:+.3}%), image {}: {verdict}",
            c.kernel,
            c.baseline,
            c.instructions,
            c.baseline_per_ray,
            c.per_ray,
            100.0 * (c.instructions as f64 / c.baseline as f64 - 1.0),
            if c.image_same { "identical" } else { "CHANGED" },
        );
        ok &= !c.regressed;
    }
    ok
}

/// Prints the verdict of each kernel against the baseline; false on a regression.
fn print_comparison(report: &bench::BenchReport, b: &Baseline, cfg: &BenchConfig) -> bool {
    let mut ok = true;
    for c in bench::compare(report, b, cfg.tolerance(), cfg.gate()) {
        let work = match c.work_change_percent {
            None => "work: not in the baseline".to_string(),
            Some(0.0) => "work identical".to_string(),
            Some(w) => format!("work {w:+.2}%"),
        };
        let noise = match c.change_ci {
            Some(ci) => format!("{:.0}% CI {:+.1}% to {:+.1}%", 100.0 * ci.level, ci.lo, ci.hi),
            None => "no noise estimate: give both runs --repeat 2 or more".to_string(),
        };
        let timing = if c.change_percent < 0.0 { "slower" } else { "faster" };
        say!(
            "{:<7} baseline {:.2} Mrays/s -> {:.2} Mrays/s ({:+.1}%, {noise}), image {}, {work}: {}{}",
            c.kernel,
            c.baseline_mrays,
            c.mrays,
            c.change_percent,
            if c.image_same { "identical" } else { "CHANGED" },
            if c.regressed { "REGRESSION" } else { "ok" },
            match c.verdict {
                BaselineVerdict::Same => format!(" (within the {}% tolerance)", cfg.tolerance()),
                BaselineVerdict::WithinNoise =>
                    " (within noise: the runs cannot tell this change from the machine's noise)".into(),
                BaselineVerdict::TimingOnly if cfg.gate() == Gate::Work =>
                    format!(" (timing only, {timing}: same image and work; not gated with --gate work)"),
                BaselineVerdict::TimingOnly => format!(" (timing only, {timing}: same image and work)"),
                BaselineVerdict::Work => " (the algorithm's work changed)".into(),
                BaselineVerdict::Image => " (the image changed)".into(),
            }
        );
        ok &= !c.regressed;
    }
    ok
}
