//! `rtow bench`: render one scene with each kernel, measure rays per second,
//! and compare against a saved baseline (throughput and image hash), so that
//! a speedup can be regression-tested: faster, and the same image.

use crate::error::{Error, Result};
use crate::kernel::KernelKind;
use crate::plan::{AccelChoice, Settings};
use crate::render::{render, RenderOptions, Stats};
use crate::scene::Scene;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One kernel's measurement: the median run's stats plus the speedup over scalar.
#[derive(Clone, Debug, Serialize)]
pub struct BenchEntry {
    #[serde(flatten)]
    pub stats: Stats,
    /// Mrays/s divided by the scalar kernel's in the same run (absent without scalar).
    pub speedup: Option<f64>,
    /// Seconds of every repetition, in run order.
    pub runs_seconds: Vec<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    pub scene: String,
    pub repeat: usize,
    pub kernels: Vec<BenchEntry>,
}

/// Renders `scene` `repeat` times with each kernel; keeps the median-time run.
pub fn run(
    scene: &Scene,
    name: &str,
    settings: Settings,
    kernels: &[KernelKind],
    threads: Option<usize>,
    accel: AccelChoice,
    repeat: usize,
    mut on_run: impl FnMut(KernelKind, usize, &Stats),
) -> Result<BenchReport> {
    if repeat == 0 {
        return Err(Error::invalid("repeat", "must be at least 1"));
    }
    let mut entries = Vec::new();
    for &kernel in kernels {
        let opts = RenderOptions { kernel, threads, accel, ..RenderOptions::default() };
        let mut runs = Vec::new();
        for i in 0..repeat {
            let r = render(scene, settings, opts, None)?;
            r.stats.check_finite()?;
            on_run(kernel, i, &r.stats);
            runs.push(r.stats);
        }
        let runs_seconds: Vec<f64> = runs.iter().map(|s| s.seconds).collect();
        if let Some(s) = runs.iter().find(|s| s.image_hash != runs[0].image_hash) {
            return Err(Error::Input(format!(
                "{} kernel: image changed between repetitions ({} vs {}): the render is not deterministic",
                kernel.name(),
                runs[0].image_hash,
                s.image_hash
            )));
        }
        runs.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
        let median = runs.swap_remove(runs.len() / 2);
        entries.push(BenchEntry { stats: median, speedup: None, runs_seconds });
    }
    let scalar = entries.iter().find(|e| e.stats.kernel == "scalar").map(|e| e.stats.mrays_per_s);
    if let Some(base) = scalar {
        for e in &mut entries {
            e.speedup = Some(e.stats.mrays_per_s / base);
        }
    }
    Ok(BenchReport { scene: name.to_string(), repeat, kernels: entries })
}

impl BenchReport {
    /// The table `rtow bench` prints.
    pub fn table(&self) -> String {
        let mut t = format!(
            "{:<7} {:>12} {:>9} {:>9} {:>8} {:>7} {:>7}  {}\n",
            "kernel", "rays", "seconds", "Mrays/s", "speedup", "isect%", "scat%", "image hash"
        );
        for e in &self.kernels {
            let s = &e.stats;
            t += &format!(
                "{:<7} {:>12} {:>9.3} {:>9.2} {:>8} {:>7} {:>7}  {}\n",
                s.kernel,
                s.rays,
                s.seconds,
                s.mrays_per_s,
                e.speedup.map_or("-".to_string(), |x| format!("{x:.2}x")),
                pct(s.isect_occupancy),
                pct(s.scatter_occupancy),
                s.image_hash
            );
        }
        t
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("report serializes") + "\n"
    }
}

fn pct(x: Option<f64>) -> String {
    x.map_or("-".to_string(), |x| format!("{:.1}", 100.0 * x))
}

/// What a saved baseline must hold for each kernel (extra fields are ignored).
#[derive(Clone, Debug, Deserialize)]
pub struct BaselineEntry {
    pub kernel: String,
    pub mrays_per_s: f64,
    pub image_hash: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub seed: u64,
}

#[derive(Clone, Debug, Deserialize)]
pub struct Baseline {
    pub scene: String,
    pub kernels: Vec<BaselineEntry>,
}

impl Baseline {
    pub fn load(path: &Path) -> Result<Baseline> {
        let bytes = crate::limits::read_bounded(path, crate::limits::MAX_BASELINE_BYTES, "baseline")?;
        serde_json::from_slice(&bytes)
            .map_err(|e| Error::Parse { path: path.to_path_buf(), message: format!("not a rtow bench baseline: {e}") })
    }
}

impl Baseline {
    /// Checks, before anything is measured, that this baseline measured what
    /// a run of `scene` with `settings` and `kernels` will: the same scene,
    /// the same settings for each kernel it has, at least one of the kernels.
    pub fn check_matches(&self, scene: &str, settings: Settings, kernels: &[KernelKind]) -> Result<()> {
        if self.scene != scene {
            return Err(Error::Input(format!("baseline is of scene '{}', this run of '{scene}'", self.scene)));
        }
        let s = settings;
        let mut any = false;
        for b in self.kernels.iter().filter(|b| kernels.iter().any(|k| k.name() == b.kernel)) {
            any = true;
            if (b.width, b.height, b.spp, b.max_depth, b.seed) != (s.width, s.height, s.spp, s.max_depth, s.seed) {
                return Err(Error::Input(format!(
                    "baseline settings {}x{} {} spp depth {} seed {} differ from this run's {}x{} {} spp depth {} seed {}",
                    b.width, b.height, b.spp, b.max_depth, b.seed, s.width, s.height, s.spp, s.max_depth, s.seed
                )));
            }
        }
        if !any {
            return Err(Error::Input("the baseline has none of the kernels measured".into()));
        }
        Ok(())
    }
}

/// The verdict of one kernel against the baseline.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    pub kernel: String,
    pub baseline_mrays: f64,
    pub mrays: f64,
    /// Relative change in throughput, percent (negative: slower).
    pub change_percent: f64,
    pub image_same: bool,
    pub regressed: bool,
}

/// Compares a fresh report with a baseline. An error if they measured different things.
pub fn compare(report: &BenchReport, base: &Baseline, tolerance_percent: f64) -> Result<Vec<Comparison>> {
    if report.scene != base.scene {
        return Err(Error::Input(format!("baseline is of scene '{}', this run of '{}'", base.scene, report.scene)));
    }
    let mut out = Vec::new();
    for e in &report.kernels {
        let s = &e.stats;
        let Some(b) = base.kernels.iter().find(|b| b.kernel == s.kernel) else {
            continue;
        };
        if (b.width, b.height, b.spp, b.max_depth, b.seed) != (s.width, s.height, s.spp, s.max_depth, s.seed) {
            return Err(Error::Input(format!(
                "baseline settings {}x{} {} spp depth {} seed {} differ from this run's {}x{} {} spp depth {} seed {}",
                b.width, b.height, b.spp, b.max_depth, b.seed, s.width, s.height, s.spp, s.max_depth, s.seed
            )));
        }
        let change = 100.0 * (s.mrays_per_s / b.mrays_per_s - 1.0);
        let image_same = b.image_hash == s.image_hash;
        out.push(Comparison {
            kernel: s.kernel.to_string(),
            baseline_mrays: b.mrays_per_s,
            mrays: s.mrays_per_s,
            change_percent: change,
            image_same,
            regressed: change < -tolerance_percent || !image_same,
        });
    }
    if out.is_empty() {
        return Err(Error::Input("the baseline has none of the kernels measured".into()));
    }
    Ok(out)
}
