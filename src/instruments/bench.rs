//! `rtow bench`: render one scene with each kernel, measure rays per second and
//! the exact work per ray, and compare against a saved baseline (throughput,
//! work and image hash), so that a speedup can be regression-tested: faster,
//! the same image, and no more work.
//!
//! Timed renders run with the probe off (`()`); one more render per kernel runs
//! with [`WorkCounters`] on. The counters are deterministic for a seed and the
//! settings, so a change in them is a change in the algorithm, whatever the
//! machine's load; a change in time alone is labelled as such.

use crate::choice::KernelChoice;
use crate::error::{Error, Result};
use crate::job::{Job, RenderOptions, DEFAULT_TILE};
use crate::kernel::Kernel;
use crate::probe::WorkCounters;
use crate::render::{render, render_counted, Stats};
use crate::sampling::Sampler;
use crate::settings::Settings;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Timed renders per kernel by default.
pub const DEFAULT_REPEAT: usize = 3;

/// What to measure: each of `kernels` on a job's scene, settings and options.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    pub kernels: Vec<KernelChoice>,
    /// Timed renders per kernel; the median one is reported.
    pub repeat: usize,
    /// Allowed throughput drop against a baseline, in percent.
    pub tolerance: f64,
}

impl BenchConfig {
    /// Checks everything before any render (the job's own values were checked when it was made).
    pub fn validate(&self, job: &Job) -> Result<()> {
        if self.repeat == 0 {
            return Err(Error::invalid("repeat", "must be at least 1"));
        }
        if self.kernels.is_empty() {
            return Err(Error::invalid("kernels", "name at least one kernel"));
        }
        if !(self.tolerance >= 0.0) {
            return Err(Error::invalid("tolerance", "must be a percentage >= 0"));
        }
        if job.options().tile != DEFAULT_TILE {
            return Err(Error::invalid("tile", format!("benchmarks use the default tile size, {DEFAULT_TILE}")));
        }
        Ok(())
    }

    /// `job` with each kernel.
    fn jobs(&self, job: &Job) -> Result<Vec<Job>> {
        self.kernels.iter().map(|&kernel| job.with_options(&RenderOptions { kernel, ..*job.options() })).collect()
    }
}

/// Work per ray, from exact counters.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct PerRay {
    pub nodes: f64,
    pub box_tests: f64,
    pub sphere_tests: f64,
    pub roots: f64,
}

impl PerRay {
    pub fn new(w: &WorkCounters, rays: u64) -> PerRay {
        let r = rays.max(1) as f64;
        PerRay {
            nodes: w.nodes as f64 / r,
            box_tests: w.box_tests as f64 / r,
            sphere_tests: w.sphere_tests as f64 / r,
            roots: w.roots as f64 / r,
        }
    }
}

/// One kernel's measurement: the median run's stats, the exact work, and the
/// speedup over scalar.
#[derive(Clone, Debug, Serialize)]
pub struct BenchEntry {
    #[serde(flatten)]
    pub stats: Stats,
    pub work_per_ray: PerRay,
    /// Mrays/s divided by the scalar kernel's in the same run (absent without scalar).
    pub speedup: Option<f64>,
    /// Seconds of every timed repetition, in run order.
    pub runs_seconds: Vec<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    pub scene: String,
    pub repeat: usize,
    pub kernels: Vec<BenchEntry>,
}

/// Renders `job`'s scene `repeat` times with each kernel (median kept), then
/// once more with the work counters on.
pub fn run(
    job: &Job,
    name: &str,
    cfg: &BenchConfig,
    mut on_run: impl FnMut(Kernel, usize, &Stats),
) -> Result<BenchReport> {
    cfg.validate(job)?;
    let mut entries = Vec::new();
    for job in cfg.jobs(job)? {
        let kernel = job.kernel();
        let mut runs = Vec::new();
        for i in 0..cfg.repeat {
            let r = render(&job, None)?;
            r.stats.check_finite()?;
            on_run(kernel, i, &r.stats);
            runs.push(r.stats);
        }
        let counted = render_counted(&job, None)?.stats;
        let runs_seconds: Vec<f64> = runs.iter().map(|s| s.seconds).collect();
        for s in runs.iter().chain([&counted]) {
            if s.image_hash != runs[0].image_hash || s.rays != runs[0].rays {
                return Err(Error::Input(format!(
                    "{} kernel: image changed between repetitions ({} vs {}): the render is not deterministic",
                    kernel.name(),
                    runs[0].image_hash,
                    s.image_hash
                )));
            }
        }
        runs.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
        let mut median = runs.swap_remove(runs.len() / 2);
        let work = counted.work.expect("a counted render has counters");
        median.work = Some(work);
        let work_per_ray = PerRay::new(&work, median.rays);
        entries.push(BenchEntry { stats: median, work_per_ray, speedup: None, runs_seconds });
    }
    let scalar = entries.iter().find(|e| e.stats.kernel == "scalar").map(|e| e.stats.mrays_per_s);
    if let Some(base) = scalar {
        for e in &mut entries {
            e.speedup = Some(e.stats.mrays_per_s / base);
        }
    }
    Ok(BenchReport { scene: name.to_string(), repeat: cfg.repeat, kernels: entries })
}

impl BenchReport {
    /// The table `rtow bench` prints.
    pub fn table(&self) -> String {
        let mut t = format!(
            "{:<7} {:>12} {:>9} {:>9} {:>8} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7}  {}\n",
            "kernel",
            "rays",
            "seconds",
            "Mrays/s",
            "speedup",
            "isect%",
            "scat%",
            "nodes",
            "boxes",
            "spheres",
            "roots",
            "image hash"
        );
        for e in &self.kernels {
            let s = &e.stats;
            let (isect, scatter) = s.work.map_or((None, None), |w| w.occupancy());
            let w = &e.work_per_ray;
            t += &format!(
                "{:<7} {:>12} {:>9.3} {:>9.2} {:>8} {:>7} {:>7} {:>7.2} {:>7.2} {:>7.2} {:>7.2}  {}\n",
                s.kernel,
                s.rays,
                s.seconds,
                s.mrays_per_s,
                e.speedup.map_or("-".to_string(), |x| format!("{x:.2}x")),
                pct(isect),
                pct(scatter),
                w.nodes,
                w.box_tests,
                w.sphere_tests,
                w.roots,
                s.image_hash
            );
        }
        t += "(work per ray: node visits, box tests, sphere tests and square roots, per packet or per ray as the kernel issues them)\n";
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
    /// Exact work counters (absent in baselines saved before they existed).
    #[serde(default)]
    pub work: Option<WorkCounters>,
    /// The sampler (absent in baselines saved before there was a choice: independent).
    #[serde(default)]
    pub sampler: Option<String>,
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

    /// Checks, before anything is measured, that this baseline measured the same
    /// scene and settings and has at least one of `kernels`.
    pub fn check(&self, scene: &str, s: &Settings, kernels: &[KernelChoice]) -> Result<()> {
        let sampler = s.sampler;
        if self.scene != scene {
            return Err(Error::Input(format!("baseline is of scene '{}', this run of '{scene}'", self.scene)));
        }
        for b in &self.kernels {
            let theirs = b.sampler.as_deref().unwrap_or(Sampler::Independent.name());
            if theirs != sampler.name() {
                return Err(Error::Input(format!(
                    "baseline sampler {theirs} differs from this run's {}",
                    sampler.name()
                )));
            }
        }
        for b in &self.kernels {
            if (b.width, b.height, b.spp, b.max_depth, b.seed) != (s.width, s.height, s.spp, s.max_depth, s.seed) {
                return Err(Error::Input(format!(
                    "baseline settings {}x{} {} spp depth {} seed {} differ from this run's {}x{} {} spp depth {} seed {}",
                    b.width, b.height, b.spp, b.max_depth, b.seed, s.width, s.height, s.spp, s.max_depth, s.seed
                )));
            }
        }
        let names: Vec<&str> = kernels.iter().map(|&k| Kernel::resolve(k).name()).collect();
        if !self.kernels.iter().any(|b| names.contains(&b.kernel.as_str())) {
            return Err(Error::Input(format!(
                "the baseline has none of the kernels measured ({}; it has {})",
                names.join(", "),
                self.kernels.iter().map(|b| b.kernel.as_str()).collect::<Vec<_>>().join(", ")
            )));
        }
        Ok(())
    }
}

/// What changed against the baseline, for one kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BaselineVerdict {
    /// Same image, same work, throughput within the tolerance.
    Same,
    /// Same image and work, throughput beyond the tolerance: a timing change
    /// only (load, machine, code generation), not the algorithm.
    TimingOnly,
    /// The work per ray changed: the algorithm did more (a regression) or less.
    Work,
    /// The image changed.
    Image,
}

/// The verdict of one kernel against the baseline.
#[derive(Clone, Debug, PartialEq)]
pub struct BaselineComparison {
    pub kernel: String,
    pub baseline_mrays: f64,
    pub mrays: f64,
    /// Relative change in throughput, percent (negative: slower).
    pub change_percent: f64,
    pub image_same: bool,
    /// Relative change of the total traversal work (nodes + box + sphere tests),
    /// percent; `None` when the baseline has no counters.
    pub work_change_percent: Option<f64>,
    pub verdict: BaselineVerdict,
    /// Exit status 1: the image changed, the work grew, or throughput fell beyond the tolerance.
    pub regressed: bool,
}

fn total(w: &WorkCounters) -> u64 {
    w.nodes + w.box_tests + w.sphere_tests + w.roots
}

/// Compares a fresh report with a baseline (checked with [`Baseline::check`]).
pub fn compare(report: &BenchReport, base: &Baseline, tolerance_percent: f64) -> Vec<BaselineComparison> {
    let mut out = Vec::new();
    for e in &report.kernels {
        let s = &e.stats;
        let Some(b) = base.kernels.iter().find(|b| b.kernel == s.kernel) else {
            continue;
        };
        let change = 100.0 * (s.mrays_per_s / b.mrays_per_s - 1.0);
        let image_same = b.image_hash == s.image_hash;
        let work = match (b.work, s.work) {
            (Some(bw), Some(sw)) if bw != sw => Some(100.0 * (total(&sw) as f64 / total(&bw).max(1) as f64 - 1.0)),
            (Some(_), Some(_)) => Some(0.0),
            _ => None,
        };
        let work_changed = matches!((b.work, s.work), (Some(bw), Some(sw)) if bw != sw);
        let slower = change < -tolerance_percent;
        let verdict = if !image_same {
            BaselineVerdict::Image
        } else if work_changed {
            BaselineVerdict::Work
        } else if change.abs() > tolerance_percent {
            BaselineVerdict::TimingOnly
        } else {
            BaselineVerdict::Same
        };
        out.push(BaselineComparison {
            kernel: s.kernel.to_string(),
            baseline_mrays: b.mrays_per_s,
            mrays: s.mrays_per_s,
            change_percent: change,
            image_same,
            work_change_percent: work,
            verdict,
            regressed: !image_same || work.is_some_and(|w| w > 0.0) || slower,
        });
    }
    out
}

/// Traversal work per intersection packet (or per ray, for the scalar kernel)
/// at each ray depth (0: camera rays), from one counted render.
#[derive(Clone, Debug, Serialize)]
pub struct DepthRow {
    pub depth: usize,
    pub rays: u64,
    /// Intersection packets issued (rays for the scalar kernel).
    pub packets: u64,
    pub lane_occupancy: f64,
    pub nodes_per_packet: f64,
    pub box_tests_per_packet: f64,
    pub sphere_tests_per_packet: f64,
    pub roots_per_packet: f64,
}

/// [`work_by_depth`] for each of the configuration's kernels.
pub fn work_by_depth_per_kernel(job: &Job, cfg: &BenchConfig) -> Result<Vec<(Kernel, Vec<DepthRow>)>> {
    cfg.validate(job)?;
    cfg.jobs(job)?.iter().map(|j| Ok((j.kernel(), work_by_depth(j)?))).collect()
}

/// The work at each ray depth of one render of `job` (how coherence is lost bounce by bounce).
pub fn work_by_depth(job: &Job) -> Result<Vec<DepthRow>> {
    let lanes = job.kernel().lanes() as u64;
    let (_, probes) = crate::render::render_probed(job, None, &crate::probe::WorkByDepth::default)?;
    let mut all = crate::probe::WorkByDepth::default();
    probes.iter().for_each(|p| all.merge(p));
    Ok(all
        .by_depth
        .iter()
        .enumerate()
        .filter(|(_, w)| w.nodes + w.sphere_tests > 0)
        .map(|(depth, w)| {
            let packets = if lanes == 1 { all.rays[depth] } else { w.isect_lanes / lanes };
            let p = packets.max(1) as f64;
            DepthRow {
                depth,
                rays: all.rays[depth],
                packets,
                lane_occupancy: if w.isect_lanes > 0 { w.isect_active as f64 / w.isect_lanes as f64 } else { 1.0 },
                nodes_per_packet: w.nodes as f64 / p,
                box_tests_per_packet: w.box_tests as f64 / p,
                sphere_tests_per_packet: w.sphere_tests as f64 / p,
                roots_per_packet: w.roots as f64 / p,
            }
        })
        .collect())
}

/// The table of [`work_by_depth`].
pub fn depth_table(rows: &[DepthRow]) -> String {
    let mut t = format!(
        "{:>5} {:>11} {:>10} {:>6} {:>8} {:>8} {:>8} {:>8}\n",
        "depth", "rays", "packets", "occ%", "nodes", "boxes", "spheres", "roots"
    );
    for r in rows {
        t += &format!(
            "{:>5} {:>11} {:>10} {:>6.1} {:>8.2} {:>8.2} {:>8.2} {:>8.2}\n",
            r.depth,
            r.rays,
            r.packets,
            100.0 * r.lane_occupancy,
            r.nodes_per_packet,
            r.box_tests_per_packet,
            r.sphere_tests_per_packet,
            r.roots_per_packet
        );
    }
    t + "(per intersection packet: node visits, box tests, sphere tests, square roots)\n"
}
