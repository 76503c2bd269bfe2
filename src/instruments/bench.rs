//! `rtow bench`: render one scene with each kernel, measure rays per second and
//! the exact work per ray, and compare against a saved baseline (throughput,
//! work and image hash), so that a speedup can be regression-tested: faster,
//! the same image, and no more work.
//!
//! Timed renders run with the probe off (`()`); one more render per kernel runs
//! with [`WorkCounters`] on. The counters are deterministic for a seed and the
//! settings, so a change in them is a change in the algorithm, whatever the
//! machine's load. Timings are not: each kernel reports the spread of its
//! runs, and against a baseline the change in throughput comes with a
//! confidence interval ([`super::noise`]); a change the interval cannot tell
//! from noise is reported as such, and [`Gate::Work`] gates on the image and
//! the work alone (what a noisy CI should use).

use super::noise::{self, Interval, Spread};
use crate::choice::KernelChoice;
use crate::error::{Error, Result};
use crate::job::{Job, RenderOptions, DEFAULT_TILE};
use crate::kernel::Kernel;
use crate::probe::WorkCounters;
use crate::provenance::Provenance;
use crate::render::{render, render_counted, Stats};
use crate::sampling::Sampler;
use crate::settings::Settings;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Timed renders per kernel by default.
pub const DEFAULT_REPEAT: usize = 3;
/// Allowed throughput drop against a baseline by default, in percent.
pub const DEFAULT_TOLERANCE: f64 = 5.0;
/// The value of [`BenchReport::schema`].
pub const BENCH_SCHEMA: &str = "rtow-bench/1";

/// What a comparison with a baseline fails on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Gate {
    /// The image, the work, and a slowdown beyond the tolerance that the
    /// noise cannot explain.
    #[default]
    Time,
    /// The image and the exact work counters only: independent of the
    /// machine's load, for a noisy CI. Timings are still reported.
    Work,
}

impl Gate {
    pub const NAMES: &'static [&'static str] = &["time", "work"];
}

impl std::str::FromStr for Gate {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "time" => Ok(Gate::Time),
            "work" => Ok(Gate::Work),
            _ => Err(format!("'{s}' is not one of {}", Gate::NAMES.join(", "))),
        }
    }
}

/// What to measure: each of some kernels on a job's scene, settings and
/// options; checked once, when it is made ([`BenchConfig::new`]).
#[derive(Debug)]
pub struct BenchConfig {
    /// The job with each kernel, in order (at least one; they share the
    /// job's prepared scene).
    jobs: Vec<Job>,
    repeat: usize,
    tolerance: f64,
    gate: Gate,
}

impl BenchConfig {
    /// `job` with each of `kernels`, `repeat` timed renders each, compared
    /// with a baseline at `tolerance` percent and failing on `gate`; checks
    /// everything before any render (the job's own values were checked when
    /// it was made).
    pub fn new(job: &Job, kernels: &[KernelChoice], repeat: usize, tolerance: f64, gate: Gate) -> Result<BenchConfig> {
        if repeat == 0 {
            return Err(Error::invalid("repeat", "must be at least 1"));
        }
        if kernels.is_empty() {
            return Err(Error::invalid("kernels", "name at least one kernel"));
        }
        if !(tolerance >= 0.0 && tolerance.is_finite()) {
            return Err(Error::invalid("tolerance", format!("must be a percentage >= 0, got {tolerance}")));
        }
        if job.options().tile != DEFAULT_TILE {
            return Err(Error::invalid("tile", format!("benchmarks use the default tile size, {DEFAULT_TILE}")));
        }
        let jobs = kernels
            .iter()
            .map(|&kernel| job.with_options(&RenderOptions { kernel, ..*job.options() }))
            .collect::<Result<_>>()?;
        Ok(BenchConfig { jobs, repeat, tolerance, gate })
    }

    /// The job with each kernel, in order.
    pub fn jobs(&self) -> &[Job] {
        &self.jobs
    }

    /// Timed renders per kernel; the median one is reported.
    pub fn repeat(&self) -> usize {
        self.repeat
    }

    /// Allowed throughput drop against a baseline, in percent.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// What a comparison with a baseline fails on.
    pub fn gate(&self) -> Gate {
        self.gate
    }
}

/// Work per ray, from exact counters.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct PerRay {
    pub nodes: f64,
    pub box_tests: f64,
    pub sphere_tests: f64,
    pub roots: f64,
    /// Quad tests (absent from baselines of sphere-only scenes).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub quad_tests: f64,
    /// Cuboid tests (absent from baselines of scenes without boxes).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub cuboid_tests: f64,
    /// Triangle tests (absent from baselines of scenes without meshes).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub triangle_tests: f64,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

impl PerRay {
    pub fn new(w: &WorkCounters, rays: u64) -> PerRay {
        let r = rays.max(1) as f64;
        PerRay {
            nodes: w.nodes as f64 / r,
            box_tests: w.box_tests as f64 / r,
            sphere_tests: w.sphere_tests as f64 / r,
            roots: w.roots as f64 / r,
            quad_tests: w.quad_tests as f64 / r,
            cuboid_tests: w.cuboid_tests as f64 / r,
            triangle_tests: w.triangle_tests as f64 / r,
        }
    }
}

/// One kernel's measurement: the median run's stats, the exact work, the
/// spread of the runs and the speedup over scalar.
#[derive(Clone, Debug, Serialize)]
pub struct BenchEntry {
    #[serde(flatten)]
    pub stats: Stats,
    pub work_per_ray: PerRay,
    /// Mrays/s divided by the scalar kernel's in the same run (absent without scalar).
    pub speedup: Option<f64>,
    /// Seconds of every timed repetition, in run order.
    pub runs_seconds: Vec<f64>,
    /// Their minimum, median and maximum, and a confidence interval for the median.
    pub spread: Spread,
}

/// What `rtow bench` measured, and where (the JSON `--json` and `--save` write).
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    /// [`BENCH_SCHEMA`].
    pub schema: &'static str,
    pub scene: String,
    pub repeat: usize,
    /// Worker threads of every render.
    pub threads: usize,
    pub kernels: Vec<BenchEntry>,
    pub provenance: Provenance,
}

/// Renders the configuration's job `repeat` times with each kernel (median
/// kept), then once more with the work counters on; `name` names its scene.
pub fn run(cfg: &BenchConfig, name: &str, mut on_run: impl FnMut(Kernel, usize, &Stats)) -> Result<BenchReport> {
    let provenance = Provenance::collect();
    let mut entries = Vec::new();
    for job in &cfg.jobs {
        let kernel = job.kernel();
        let mut runs = Vec::new();
        for i in 0..cfg.repeat {
            let r = render(job, None)?;
            r.stats.check_finite()?;
            on_run(kernel, i, &r.stats);
            runs.push(r.stats);
        }
        let counted = render_counted(job, None)?.stats;
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
        let spread = Spread::of(&runs_seconds);
        entries.push(BenchEntry { stats: median, work_per_ray, speedup: None, runs_seconds, spread });
    }
    let scalar = entries.iter().find(|e| e.stats.kernel == "scalar").map(|e| e.stats.mrays_per_s);
    if let Some(base) = scalar {
        for e in &mut entries {
            e.speedup = Some(e.stats.mrays_per_s / base);
        }
    }
    // At least one kernel, by construction.
    let threads = entries[0].stats.threads;
    Ok(BenchReport {
        schema: BENCH_SCHEMA,
        scene: name.to_string(),
        repeat: cfg.repeat,
        threads,
        kernels: entries,
        provenance,
    })
}

impl BenchReport {
    /// The table `rtow bench` prints.
    pub fn table(&self) -> String {
        let level = self.kernels.iter().find_map(|e| e.spread.median_ci).map(|c| c.level);
        let ci_head = level.map_or("median CI".to_string(), |l| format!("{:.0}% CI", 100.0 * l));
        let mut t = format!(
            "{:<7} {:>12} {:>9} {:>9} {:>13} {:>8} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7}  {}\n",
            "kernel",
            "rays",
            "seconds",
            "Mrays/s",
            ci_head,
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
            let rate = |secs: f64| s.rays as f64 / secs / 1e6;
            // A time interval is a rate interval the other way round.
            let ci = e.spread.median_ci.map_or("-".to_string(), |c| format!("{:.2}-{:.2}", rate(c.hi), rate(c.lo)));
            t += &format!(
                "{:<7} {:>12} {:>9.3} {:>9.2} {:>13} {:>8} {:>7} {:>7} {:>7.2} {:>7.2} {:>7.2} {:>7.2}  {}\n",
                s.kernel,
                s.rays,
                s.seconds,
                s.mrays_per_s,
                ci,
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
        if self.kernels.iter().any(|e| e.work_per_ray.quad_tests > 0.0) {
            let per: Vec<String> =
                self.kernels.iter().map(|e| format!("{} {:.2}", e.stats.kernel, e.work_per_ray.quad_tests)).collect();
            t += &format!("quad tests per ray: {}\n", per.join(", "));
        }
        if self.kernels.iter().any(|e| e.work_per_ray.cuboid_tests > 0.0) {
            let per: Vec<String> =
                self.kernels.iter().map(|e| format!("{} {:.2}", e.stats.kernel, e.work_per_ray.cuboid_tests)).collect();
            t += &format!("cuboid tests per ray: {}\n", per.join(", "));
        }
        if self.kernels.iter().any(|e| e.work_per_ray.triangle_tests > 0.0) {
            let per: Vec<String> = self
                .kernels
                .iter()
                .map(|e| format!("{} {:.2}", e.stats.kernel, e.work_per_ray.triangle_tests))
                .collect();
            t += &format!("triangle tests per ray: {}\n", per.join(", "));
        }
        t += &format!(
            "(seconds and Mrays/s: the median of {} run(s); CI: a distribution-free confidence interval for the median \
             rate, from the order statistics of the runs; work per ray: node visits, box tests, sphere tests and square \
             roots, per packet or per ray as the kernel issues them)\n",
            self.repeat
        );
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
    pub rays: u64,
    /// The median run's seconds and rate.
    pub seconds: f64,
    pub mrays_per_s: f64,
    pub threads: usize,
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
    /// Every timed run (absent in the oldest baselines: no noise estimate then).
    #[serde(default)]
    pub runs_seconds: Option<Vec<f64>>,
}

/// A saved `rtow bench --save` report, as a comparison reads it.
#[derive(Clone, Debug, Deserialize)]
pub struct Baseline {
    pub scene: String,
    pub kernels: Vec<BaselineEntry>,
}

/// Relative difference of two positive numbers.
fn rel_diff(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs())
}

impl Baseline {
    pub fn load(path: &Path) -> Result<Baseline> {
        let bytes = crate::limits::read_bounded(path, crate::limits::MAX_BASELINE_BYTES, "baseline")?;
        Baseline::from_bytes(&bytes, path)
    }

    /// Parses a baseline read from `path` and refuses impossible figures
    /// (every error names `path`; exit status 2).
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Baseline> {
        let schema = serde_json::from_slice::<serde_json::Value>(bytes)
            .ok()
            .and_then(|v| v.get("schema").and_then(|s| s.as_str()).map(str::to_string));
        if schema.as_deref() == Some(super::instructions::INSTRUCTIONS_SCHEMA) {
            return Err(Error::Parse {
                path: path.to_path_buf(),
                message: "holds instruction counts, not timings: compare it with `rtow bench --instructions`".into(),
            });
        }
        let b: Baseline = serde_json::from_slice(bytes).map_err(|e| {
            // serde quotes the offending input: a bounded part of it, and the position.
            let text = e.to_string();
            let text = text.rsplit_once(" at line ").map_or(text.as_str(), |(t, _)| t);
            let message = format!(
                "not a rtow bench baseline: {} (line {}, column {})",
                crate::output::clip_to(text, 160),
                e.line(),
                e.column()
            );
            Error::Parse { path: path.to_path_buf(), message }
        })?;
        b.validate().map_err(|m| Error::Parse { path: path.to_path_buf(), message: m })?;
        Ok(b)
    }

    /// Every figure possible and consistent with the others: a measurement
    /// that could not have been made is refused, not compared.
    fn validate(&self) -> std::result::Result<(), String> {
        if self.kernels.is_empty() {
            return Err("the baseline has no kernel".into());
        }
        for (i, b) in self.kernels.iter().enumerate() {
            let k = &b.kernel;
            let bad = |m: String| format!("kernel {}: {m}", crate::output::clip(k));
            let lanes = match k.as_str() {
                "scalar" => 1,
                "simd8" => 8,
                "simd16" => 16,
                _ => return Err(format!("kernels[{i}]: unknown kernel '{}'", crate::output::clip(k))),
            };
            if self.kernels[..i].iter().any(|o| &o.kernel == k) {
                return Err(bad("measured twice".into()));
            }
            if !(b.rays > 0 && b.seconds.is_finite() && b.seconds > 0.0) {
                return Err(bad(format!("{} rays in {} s is not a measurement", b.rays, b.seconds)));
            }
            if !(b.mrays_per_s.is_finite() && b.mrays_per_s > 0.0)
                || rel_diff(b.mrays_per_s, b.rays as f64 / b.seconds / 1e6) > 1e-6
            {
                return Err(bad(format!(
                    "{} Mrays/s is not {} rays in {} s: the figures disagree",
                    b.mrays_per_s, b.rays, b.seconds
                )));
            }
            if let Some(runs) = &b.runs_seconds {
                if runs.is_empty() || runs.iter().any(|t| !(t.is_finite() && *t > 0.0)) {
                    return Err(bad("runs_seconds must be positive times".into()));
                }
                let mut sorted = runs.clone();
                sorted.sort_by(f64::total_cmp);
                if rel_diff(sorted[sorted.len() / 2], b.seconds) > 1e-9 {
                    return Err(bad(format!("{} s is not the median of its runs {runs:?}", b.seconds)));
                }
            }
            if !(1..=crate::limits::MAX_THREADS).contains(&b.threads) {
                return Err(bad(format!("{} threads is not a thread count", b.threads)));
            }
            if b.image_hash.len() != 16 || !b.image_hash.bytes().all(|c| c.is_ascii_hexdigit()) {
                return Err(bad(format!("'{}' is not an image hash", crate::output::clip(&b.image_hash))));
            }
            let samples = b.width as u64 * b.height as u64 * b.spp as u64;
            if samples == 0
                || b.max_depth == 0
                || b.rays < samples
                || b.rays > samples.saturating_mul(b.max_depth as u64)
            {
                return Err(bad(format!(
                    "{} rays cannot come from {}x{} pixels, {} spp and depth {}",
                    b.rays, b.width, b.height, b.spp, b.max_depth
                )));
            }
            if let Some(w) = b.work {
                // A packet has `lanes` lanes and at least one of them active.
                let lanes_ok = |active: u64, total: u64| {
                    active <= total && total <= active.saturating_mul(lanes) && total.is_multiple_of(lanes)
                };
                if w.roots > w.sphere_tests
                    || w.box_tests > w.nodes.saturating_mul(8)
                    || !lanes_ok(w.isect_active, w.isect_lanes)
                    || !lanes_ok(w.scatter_active, w.scatter_lanes)
                    || (lanes > 1 && w.isect_active != b.rays)
                {
                    return Err(bad("the work counters contradict each other or the rays".into()));
                }
            }
        }
        Ok(())
    }

    /// Checks, before anything is measured, that this baseline measured the
    /// same scene and settings with as many threads and has at least one of `kernels`.
    pub fn check(&self, scene: &str, s: &Settings, threads: usize, kernels: &[KernelChoice]) -> Result<()> {
        let sampler = s.sampler;
        if self.scene != scene {
            return Err(Error::Input(format!(
                "baseline is of scene '{}', this run of '{scene}'",
                crate::output::clip(&self.scene)
            )));
        }
        for b in &self.kernels {
            let theirs = b.sampler.as_deref().unwrap_or(Sampler::Independent.name());
            if theirs != sampler.name() {
                return Err(Error::Input(format!(
                    "baseline sampler {} differs from this run's {}",
                    crate::output::clip(theirs),
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
            if b.threads != threads {
                return Err(Error::Input(format!(
                    "baseline {} kernel ran on {} thread(s), this run on {threads}: rates on other thread counts \
                     do not compare (set --threads {})",
                    b.kernel, b.threads, b.threads
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
    /// Same image and work; the throughput interval reaches past the
    /// tolerance but also inside it: the runs cannot tell this change from
    /// the machine's noise.
    WithinNoise,
    /// Same image and work, throughput beyond the tolerance: a timing change
    /// only (load, machine, code generation), not the algorithm. Faster or
    /// slower: see [`BaselineComparison::change_percent`].
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
    /// Relative change in throughput, percent (negative: slower): the
    /// Hodges-Lehmann estimate over every pair of runs when both sides have
    /// two runs or more, else the change of the medians.
    pub change_percent: f64,
    /// A confidence interval for `change_percent` (percent) and its level
    /// (`None` with fewer than two runs on a side).
    pub change_ci: Option<Interval>,
    pub image_same: bool,
    /// Relative change of the total traversal work (nodes + box + sphere tests),
    /// percent; `None` when the baseline has no counters.
    pub work_change_percent: Option<f64>,
    pub verdict: BaselineVerdict,
    /// Exit status 1: the image changed, the work grew, or (gate `time`)
    /// throughput fell beyond the tolerance by more than the noise explains.
    pub regressed: bool,
}

fn total(w: &WorkCounters) -> u64 {
    w.nodes + w.box_tests + w.sphere_tests + w.roots + w.quad_tests + w.cuboid_tests + w.triangle_tests
}

/// Compares a fresh report with a baseline (checked with [`Baseline::check`]).
pub fn compare(report: &BenchReport, base: &Baseline, tolerance_percent: f64, gate: Gate) -> Vec<BaselineComparison> {
    let mut out = Vec::new();
    let t = tolerance_percent / 100.0;
    for e in &report.kernels {
        let s = &e.stats;
        let Some(b) = base.kernels.iter().find(|b| b.kernel == s.kernel) else {
            continue;
        };
        // Rate ratio (this run over the baseline), from the times of the runs.
        let runs = b.runs_seconds.as_deref().unwrap_or(&[]);
        let noise = noise::ratio(runs, &e.runs_seconds)
            .map(|(time, ci)| (1.0 / time, Interval { lo: 1.0 / ci.hi, hi: 1.0 / ci.lo, level: ci.level }));
        let (ratio, ci) = match noise {
            Some((r, ci)) => (r, Some(ci)),
            None => (s.mrays_per_s / b.mrays_per_s, None),
        };
        let image_same = b.image_hash == s.image_hash;
        let work = match (b.work, s.work) {
            (Some(bw), Some(sw)) if bw != sw => Some(100.0 * (total(&sw) as f64 / total(&bw).max(1) as f64 - 1.0)),
            (Some(_), Some(_)) => Some(0.0),
            _ => None,
        };
        let work_changed = matches!((b.work, s.work), (Some(bw), Some(sw)) if bw != sw);
        // Slower beyond the tolerance: the whole interval, or without one the estimate.
        let (lo, hi) = ci.map_or((ratio, ratio), |c| (c.lo, c.hi));
        let slower = hi < 1.0 - t;
        let timing = if lo >= 1.0 - t && hi <= 1.0 + t {
            BaselineVerdict::Same
        } else if slower || lo > 1.0 + t {
            BaselineVerdict::TimingOnly
        } else {
            BaselineVerdict::WithinNoise
        };
        let verdict = if !image_same {
            BaselineVerdict::Image
        } else if work_changed {
            BaselineVerdict::Work
        } else {
            timing
        };
        out.push(BaselineComparison {
            kernel: s.kernel.to_string(),
            baseline_mrays: b.mrays_per_s,
            mrays: s.mrays_per_s,
            change_percent: 100.0 * (ratio - 1.0),
            change_ci: ci.map(|c| Interval { lo: 100.0 * (c.lo - 1.0), hi: 100.0 * (c.hi - 1.0), level: c.level }),
            image_same,
            work_change_percent: work,
            verdict,
            regressed: !image_same || work.is_some_and(|w| w > 0.0) || (gate == Gate::Time && slower),
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
pub fn work_by_depth_per_kernel(cfg: &BenchConfig) -> Result<Vec<(Kernel, Vec<DepthRow>)>> {
    cfg.jobs.iter().map(|j| Ok((j.kernel(), work_by_depth(j)?))).collect()
}

/// The work at each ray depth of one render of `job` (how coherence is lost bounce by bounce).
pub fn work_by_depth(job: &Job) -> Result<Vec<DepthRow>> {
    let lanes = job.kernel().lanes() as u64;
    let (_, probes) = crate::render::render_probed(job, None, &crate::probe::Observed::counting)?;
    let mut all = crate::probe::WorkByDepth::default();
    probes.iter().for_each(|p| all.merge(&p.work));
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
