//! `rtow render`: one scene to a PNG (and optionally a float image and stats),
//! or to a partial film (`.rtfilm`): a shard of the render (`--shard K/N`), or
//! a whole render to be resumed (`--resume`) or merged later.

use super::args::{choice, kernel_parser, EstimatorArgs, ImageArgs, OutputArgs, RejectedArgs, RunArgs, VerifyArgs};
use super::{say, tell};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rtow::files::{self, RenderRequest};
use rtow::shard::{Split, SplitKind};
use rtow::{Job, KernelChoice, Progress, Result, Stats};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct RenderArgs {
    /// A preset name (see `rtow scenes`) or a scene file (.json / .toml).
    scene: String,
    /// Output PNG (8-bit, gamma encoded), or a partial film (.rtfilm) for
    /// `rtow merge` or `--resume` [default: <scene name>.png]
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Render only the K-th of N deterministic pieces of the work (K from 1 to N)
    /// into a partial film (-o part-K.rtfilm); `rtow merge` puts the N parts
    /// together into exactly the one-process image. A failed shard is rerun and
    /// writes the identical file.
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
    /// How --shard splits the work: by sample range (every shard covers the
    /// whole image: balanced) or by bands of image rows.
    #[arg(long, value_parser = choice::<SplitKind>(SplitKind::NAMES), default_value = "samples", requires = "shard")]
    split: SplitKind,
    /// Continue a render that wrote a partial film with fewer samples per
    /// pixel (same scene and settings): gives exactly the image of --spp.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    // How the film to resume is checked (--verify N --verify-seed S).
    #[command(flatten)]
    verify: VerifyArgs,
    #[command(flatten)]
    image: ImageArgs,
    /// Kernel: the scalar reference, or the SIMD wavefront at the widest lane count
    /// of this build (simd), or forced to 8 or 16 lanes.
    #[arg(long, value_parser = kernel_parser(), default_value = "simd")]
    kernel: KernelChoice,
    #[command(flatten)]
    run: RunArgs,
    #[command(flatten)]
    estimator: EstimatorArgs,
    #[command(flatten)]
    files: OutputArgs,
    #[command(flatten)]
    rejected: RejectedArgs,
    /// Print the render plan (what the scene needs) before rendering.
    #[arg(long)]
    explain: bool,
    /// No progress bar and no summary line (warnings are still printed).
    #[arg(short, long)]
    quiet: bool,
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

/// Runs `work` with a progress bar (on a terminal) showing live Mrays/s.
pub fn with_progress<T>(quiet: bool, work: impl FnOnce(Option<&(dyn Fn(Progress) + Sync)>) -> Result<T>) -> Result<T> {
    let bar = progress_bar(quiet);
    let start = Instant::now();
    let cb = |p: Progress| {
        if let Some(b) = &bar {
            b.set_length(p.tiles_total);
            b.set_position(p.tiles_done);
            let secs = start.elapsed().as_secs_f64().max(1e-9);
            b.set_message(format!("{:.2} Mrays/s", p.rays as f64 / secs / 1e6));
        }
    };
    let out = work(Some(&cb));
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    out
}

pub fn run(a: RenderArgs) -> Result<()> {
    let source = a.image.open(&a.scene)?;
    let options = a.estimator.options(a.run.options(a.kernel))?;
    let job = Job::from_source(&source, &a.image.overrides(), &options)?;
    for w in job.warnings() {
        tell!("warning: {}", rtow::output::printable(&super::message(w)));
    }
    let split = match &a.shard {
        Some(k) => Split::parse(k, a.split)?,
        None => Split::WHOLE,
    };
    let output = a.output.clone().unwrap_or_else(|| files::default_output(&source));
    let req = RenderRequest {
        source: &source,
        job: &job,
        split,
        resume: a.resume.clone(),
        verify: a.verify.verify(),
        files: a.files.files(output.clone()),
        on_rejected: a.rejected.on_rejected,
    };
    if a.explain {
        say!("{}", job.explain());
    }
    let st = with_progress(a.quiet, |cb| files::render_to_files(&req, cb))?;
    // Never silent: a render that left samples out of its image says so, even with -q.
    if let Some(w) = st.rejected().warning() {
        tell!("warning: {w}");
    }
    if !a.quiet {
        say!("{}", summary(&source.name, &st, &req, &output));
    }
    Ok(())
}

/// The one line a render ends with.
fn summary(name: &str, st: &Stats, req: &RenderRequest, output: &std::path::Path) -> String {
    let piece = match (&req.split, &req.resume) {
        (s, _) if s.kind != SplitKind::None => format!(" ({})", s.describe()),
        (_, Some(p)) => format!(
            " (resumed from {}, verified with --verify {} --verify-seed {})",
            p.display(),
            req.verify.pixels,
            req.verify.seed
        ),
        _ => String::new(),
    };
    let rejected =
        if st.rejected_samples > 0 { format!(", {} samples rejected", st.rejected_samples) } else { String::new() };
    let shadow = if st.shadow_rays > 0 {
        format!(" + {} shadow rays = {:.2} M/s", st.shadow_rays, st.mshadow_rays_per_s)
    } else {
        String::new()
    };
    format!(
        "{name}: {}x{} {} spp{piece} -> {}: {} rays, {} samples in {:.3} s = {:.2} Mrays/s{shadow} ({} kernel, {} threads, {}){rejected}",
        st.width,
        st.height,
        st.spp,
        output.display(),
        st.rays,
        st.samples,
        st.seconds,
        st.mrays_per_s,
        st.kernel,
        st.threads,
        st.isa,
    )
}
