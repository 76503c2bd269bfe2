//! `rtow render`: one scene to a PNG (and optionally a float image and stats),
//! or to a partial film (`.rtfilm`): a shard of the render (`--shard K/N`), or
//! a whole render to be resumed (`--resume`) or merged later.

use super::args::{choice, kernel_parser, positive_f32, EstimatorArgs, ImageArgs};
use super::{load, say};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rtow::film::part::{is_part_path, Part, Split, SplitKind};
use rtow::output::{check_extension, Outputs};
use rtow::render::{render_counted, Progress};
use rtow::shard::{self, Job};
use rtow::{Error, KernelChoice, Result};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
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
    #[command(flatten)]
    image: ImageArgs,
    /// Kernel: the scalar reference, or the SIMD wavefront at the widest lane count
    /// of this build (simd), or forced to 8 or 16 lanes.
    #[arg(long, value_parser = kernel_parser(), default_value = "simd")]
    kernel: KernelChoice,
    /// Also write the linear image: .pfm or .exr.
    #[arg(long, value_name = "FILE")]
    float: Option<PathBuf>,
    /// Write render statistics as JSON (with the exact work counters: node
    /// visits, box and sphere tests, square roots, lane occupancy).
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
fn render_with_progress<T>(
    quiet: bool,
    render: impl FnOnce(Option<&(dyn Fn(Progress) + Sync)>) -> Result<T>,
) -> Result<T> {
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
    let out = render(Some(&cb));
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    out
}

pub fn run(a: RenderArgs) -> Result<()> {
    rtow::limits::check_threads(a.image.threads)?;
    let (scene, name) = load(&a.scene)?;
    let s = a.image.settings(&scene);
    let out = a.output.clone().unwrap_or_else(|| PathBuf::from(format!("{name}.png")));
    let film_out = is_part_path(&out);
    check_extension(&out, &["png", "rtfilm"], "-o")?;
    if let Some(f) = &a.float {
        check_extension(f, &["pfm", "exr"], "--float")?;
    }
    // Bad input first (exit 2), then every output path, before the render:
    // a failure after it would waste the render and leave some outputs written.
    s.validate()?;
    let opts = a.estimator.options(a.kernel, &a.image, &scene)?;
    rtow::Kernel::resolve(opts.kernel)?;
    let split = match &a.shard {
        Some(k) => Split::parse(k, a.split)?,
        None => Split::WHOLE,
    };
    if split.kind != SplitKind::None && !film_out {
        return Err(Error::invalid(
            "--shard",
            format!("a shard writes a partial film: use -o {name}-{}.rtfilm, then rtow merge", split.shard),
        ));
    }
    let resume = match &a.resume {
        Some(p) => Some((p.clone(), Part::read(p)?)),
        None => None,
    };
    let job = Job { split, resume };
    let partial = film_out || job.resume.is_some();
    if partial {
        shard::check(&scene, &s, &opts, &job)?;
    }
    // The outputs are one transaction (see `rtow::output`): checked now,
    // written only when all of them are ready. (The --resume film is read
    // whole before, so -o may replace it: a render continued in place.)
    let mut outputs = Outputs::new();
    if rtow::scene::preset(&a.scene).is_none() {
        outputs.input(Path::new(&a.scene), "scene file");
    }
    let png_id = outputs.add(&out, "-o")?;
    let float_id = a.float.as_deref().map(|f| outputs.add(f, "--float")).transpose()?;
    let stats_id = a.stats_json.as_deref().map(|j| outputs.add(j, "--stats-json")).transpose()?;
    if a.explain {
        say!("{}", rtow::prepare::plan(&scene, &s, opts.accel).explain());
    }
    let gamma = a.gamma.unwrap_or(scene.mode.default_gamma());
    let r = if partial {
        let (r, part) = render_with_progress(a.quiet, |cb| shard::render_part(&scene, s, opts, &job, cb))?;
        r.stats.check_finite()?;
        if film_out {
            outputs.stage(png_id, &part.to_bytes())?;
        } else {
            outputs.stage(png_id, &rtow::output::image_bytes(&r.image, &out, gamma)?)?;
        }
        r
    } else {
        let counted = a.stats_json.is_some();
        let r = render_with_progress(a.quiet, |cb| {
            if counted {
                render_counted(&scene, s, opts, cb)
            } else {
                rtow::render(&scene, s, opts, cb)
            }
        })?;
        r.stats.check_finite()?;
        outputs.stage(png_id, &rtow::output::image_bytes(&r.image, &out, gamma)?)?;
        r
    };
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
            "{name}: {}x{} {} spp{} -> {}: {} rays, {} samples in {:.3} s = {:.2} Mrays/s ({} kernel, {} threads, {}){}",
            st.width,
            st.height,
            st.spp,
            match (&job_desc(&a), &a.resume) {
                (Some(d), _) => format!(" ({d})"),
                (None, Some(p)) => format!(" (resumed from {})", p.display()),
                (None, None) => String::new(),
            },
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

/// The shard a render does, for its summary line.
fn job_desc(a: &RenderArgs) -> Option<String> {
    let s = Split::parse(a.shard.as_deref()?, a.split).ok()?;
    Some(s.describe())
}
