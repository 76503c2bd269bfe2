//! `rtow render`: one scene to a PNG (and optionally a float image and stats),
//! or to a partial film (`.rtfilm`): a shard of the render (`--shard K/N`), or
//! a whole render to be resumed (`--resume`) or merged later.

use super::args::{choice, kernel_parser, EstimatorArgs, ImageArgs, OutputArgs, RejectedArgs, RunArgs, VerifyArgs};
use super::{say, tell};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rtow::files::{self, RenderRequest, RoundsRequest};
use rtow::rounds::Stopped;
use rtow::shard::{Split, SplitKind};
use rtow::{Job, KernelChoice, OnInterrupt, Overrides, Progress, Result, Stats};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(Args)]
pub struct RenderArgs {
    /// A preset name (see `rtow scenes`) or a scene file (.json / .toml);
    /// with --resume it may be left out: the film's own scene and settings.
    #[arg(required_unless_present = "resume")]
    scene: Option<String>,
    /// Output image by its extension: PNG (8-bit, gamma encoded), EXR or PFM
    /// (linear), or a partial film (.rtfilm) for `rtow merge` or `--resume`
    /// [default: <scene name>.png]
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
    /// Without a scene, the film's own scene and settings (flags given still win).
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    /// Render whole rounds of samples while the next fits in DURATION (e.g.
    /// 30s, 10m, 1h30m), then write the image of the samples reached (at
    /// least one per pixel; --spp is the most): exactly the render of that
    /// sample count, which the summary and --stats-json give.
    #[arg(long, value_name = "DURATION", value_parser = duration)]
    time_limit: Option<Duration>,
    /// Rewrite the output image (atomically, for a viewer to reload) after
    /// the first round of samples and then every DURATION (e.g. 10s).
    #[arg(long, value_name = "DURATION", value_parser = duration)]
    preview_every: Option<Duration>,
    /// On SIGINT, SIGTERM or SIGHUP: film (finish the round of samples under
    /// way, write a film of the samples done to resume: the output's name
    /// with .rtfilm; a second signal quits at once) or quit (stop at once).
    /// Either way the other outputs are not written.
    #[arg(long, value_parser = choice::<OnInterrupt>(OnInterrupt::NAMES), default_value = "film")]
    on_interrupt: OnInterrupt,
    /// Render only the window of columns x0..x1 and rows y0..y1 (pixels,
    /// ends excluded) into an image of its size, its pixels bit for bit
    /// those of the whole render. In one go, to an image.
    #[arg(long, value_name = "x0,x1,y0,y1", allow_hyphen_values = true)]
    crop: Option<String>,
    /// Feature buffers for a denoiser, each pixel the mean over its samples
    /// of its camera rays' first surface: albedo (after textures), normal
    /// (unit, facing the camera), depth (distance). Written as layers of the
    /// EXR the run writes (-o or --float), else as PFM files beside the
    /// image (x.png: x.albedo.pfm, x.normal.pfm, x.depth.pfm).
    #[arg(long, value_name = "LIST")]
    aov: Option<String>,
    /// Print the paths of pixel (x, y) event by event (hits, materials,
    /// normals, scattered directions with their densities and attenuations,
    /// the terms added to the radiance) for --trace-samples samples, and the
    /// pixel's value over them; renders nothing else, writes no file.
    #[arg(
        long,
        value_name = "x,y",
        allow_hyphen_values = true,
        conflicts_with_all = ["output", "shard", "resume", "crop", "aov", "time_limit", "preview_every", "float", "stats_json"]
    )]
    trace_pixel: Option<String>,
    /// How many samples --trace-pixel follows (its first ones, 1 to 64).
    #[arg(long, value_name = "N", default_value_t = 4, requires = "trace_pixel")]
    trace_samples: u32,
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

/// A duration as humans write one: `30s`, `10m`, `1h30m`, `500ms`.
fn duration(text: &str) -> std::result::Result<Duration, String> {
    humantime::parse_duration(text).map_err(|e| format!("{e} (write e.g. 30s, 10m, 1h30m)"))
}

/// The scene to render and the settings under the flags: the scene named,
/// or a film's own (`--resume FILM` without a scene).
fn scene_and_settings(a: &RenderArgs) -> Result<(rtow::SceneSource, Overrides, rtow::RenderOptions)> {
    let mut options = a.estimator.options(a.run.options(a.kernel))?;
    let overrides = a.image.overrides();
    match (&a.scene, &a.resume) {
        (Some(spec), _) => Ok((a.image.open(spec)?, overrides, options)),
        (None, Some(film)) => {
            let f = rtow::shard::scene_of_film(film)?;
            let mut source = a.image.set.apply(f.source)?;
            if let Some(level) = a.image.tessellate {
                source.scene = source.scene.tessellate(level)?;
            }
            options.roulette = options.roulette.or(f.estimator.roulette);
            options.adaptive = options.adaptive.or(f.estimator.adaptive);
            Ok((source, overrides.or(&Overrides::from(f.settings)), options))
        }
        (None, None) => Err(rtow::Error::invalid("scene", "name a scene, or a film with --resume")),
    }
}

/// Renders; the exit status is 0, or 128 + the signal that stopped the
/// render (its film written).
pub fn run(a: RenderArgs) -> Result<u8> {
    let (source, overrides, options) = scene_and_settings(&a)?;
    let job = Job::from_source(&source, &overrides, &options)?;
    for w in job.warnings() {
        tell!("warning: {}", rtow::output::printable(&super::message(w)));
    }
    if let Some(pixel) = &a.trace_pixel {
        let (x, y) = rtow::instruments::trace::parse_pixel(pixel)?;
        say!("{}", rtow::instruments::trace::trace_pixel(&job, x, y, 0..a.trace_samples)?.trim_end());
        return Ok(0);
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
        rounds: RoundsRequest {
            time_limit: a.time_limit,
            preview_every: a.preview_every,
            on_interrupt: a.on_interrupt,
        },
        crop: a.crop.as_deref().map(rtow::Crop::parse).transpose()?,
        aov: a.aov.as_deref().map(rtow::film::aov::Aovs::parse).transpose()?.unwrap_or_default(),
    };
    if a.explain {
        say!("{}", job.explain());
    }
    let st = with_progress(a.quiet, |cb| files::render_to_files(&req, cb))?;
    // Never silent: a render that left samples out of its image says so, even with -q.
    if let Some(w) = st.rejected().warning() {
        tell!("warning: {w}");
    }
    if let Some(r) = st.rounds.as_ref().filter(|r| r.stopped == Some(Stopped::Signal)) {
        // Said even with -q: the outputs asked for were not written.
        let film = r.film.as_deref().unwrap_or(&output);
        tell!(
            "rtow: {}: stopped after {} of {} samples per pixel; wrote only {} (continue: rtow render --resume {} \
             --spp {} -o {})",
            r.signal.unwrap_or("signal"),
            st.spp,
            r.spp_requested,
            film.display(),
            film.display(),
            r.spp_requested,
            output.display()
        );
        return Ok((128 + r.signal_number).clamp(0, 255) as u8);
    }
    if !a.quiet {
        say!("{}", summary(&source.name, &st, &req, &output));
    }
    Ok(0)
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
    let piece = match &st.crop {
        Some(c) => format!("{piece} (window {}..{} x {}..{})", c.x.start, c.x.end, c.y.start, c.y.end),
        None => piece,
    };
    let piece = match &st.rounds {
        Some(r) if r.stopped == Some(Stopped::TimeLimit) => {
            format!("{piece} (time limit: {} of {} spp, in {} rounds)", st.spp, r.spp_requested, r.rounds)
        }
        _ => piece,
    };
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
    ) + &aov_summary(st)
}

/// The feature buffers written, for the summary line (empty: none).
fn aov_summary(st: &Stats) -> String {
    let Some(a) = &st.aov else { return String::new() };
    let files: Vec<String> = a.files.iter().map(|f| f.display().to_string()).collect();
    format!("; {} -> {} in {:.3} s", a.buffers.join(", "), files.join(", "), a.seconds)
}
