//! `rtow render`: one scene to a PNG (and optionally a float image and stats).

use super::args::{kernel_parser, positive_f32, EstimatorArgs, ImageArgs};
use super::{load, say};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rtow::render::{render_counted, Progress};
use rtow::{Error, KernelChoice, RenderOptions, Rendered, Result, Scene, Settings};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args)]
pub struct RenderArgs {
    /// A preset name (see `rtow scenes`) or a scene file (.json / .toml).
    scene: String,
    /// Output PNG (8-bit, gamma encoded) [default: <scene name>.png]
    #[arg(short, long)]
    output: Option<PathBuf>,
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

fn check_ext(path: &Path, allowed: &[&str], what: &str) -> Result<()> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    if allowed.contains(&ext.as_str()) {
        Ok(())
    } else {
        Err(Error::Output {
            path: path.to_path_buf(),
            message: format!("{what} must end in .{}", allowed.join(" or .")),
        })
    }
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
fn render_with_progress(
    scene: &Scene,
    s: Settings,
    opts: RenderOptions,
    quiet: bool,
    counted: bool,
) -> Result<Rendered> {
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
    let out = if counted { render_counted(scene, s, opts, Some(&cb)) } else { rtow::render(scene, s, opts, Some(&cb)) };
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    out
}

pub fn run(a: RenderArgs) -> Result<()> {
    let (scene, name) = load(&a.scene)?;
    let s = a.image.settings(&scene);
    let out = a.output.clone().unwrap_or_else(|| PathBuf::from(format!("{name}.png")));
    check_ext(&out, &["png"], "the output image")?;
    if let Some(f) = &a.float {
        check_ext(f, &["pfm", "exr"], "--float")?;
    }
    // Bad input first (exit 2), then every output path, before the render:
    // a failure after it would waste the render and leave some outputs written.
    s.validate()?;
    let opts = a.estimator.options(a.kernel, &a.image)?;
    rtow::Kernel::resolve(opts.kernel)?;
    for p in std::iter::once(&out).chain(&a.float).chain(&a.stats_json) {
        rtow::output::check_writable(p)?;
    }
    if a.explain {
        say!("{}", rtow::prepare::plan(&scene, &s, opts.accel).explain());
    }
    let r = render_with_progress(&scene, s, opts, a.quiet, a.stats_json.is_some())?;
    let gamma = a.gamma.unwrap_or(scene.mode.default_gamma());
    r.image.save(&out, gamma)?;
    if let Some(f) = &a.float {
        r.image.save(f, 1.0)?;
    }
    if let Some(j) = &a.stats_json {
        let text = serde_json::to_string_pretty(&r.stats).expect("stats serialize") + "\n";
        rtow::output::write_atomic(j, text.as_bytes())?;
    }
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
