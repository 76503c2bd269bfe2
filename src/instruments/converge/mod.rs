//! Run time against error: render a scene at a list of sample counts with each
//! kernel and estimator variant, measure the error of each image against a
//! reference, and compare the configurations at equal time and equal error.
//!
//! - The reference is rendered with a seed derived from (and different to) the
//!   measured renders' seed ([`reference_seed`]), or loaded from a float image.
//!   With the same seed the error of a measured image would be correlated with
//!   the reference's and come out too low.
//! - Error: RMSE over every channel of every pixel of the linear image, and
//!   relMSE, the mean of `(x - r)^2 / (r^2 + 0.01)` (Rousselle et al. 2011; the
//!   0.01 keeps black reference pixels from dominating). Efficiency is
//!   `1 / (MSE x seconds)`: for an unbiased estimator it is roughly constant
//!   along a curve, and the ratio of two efficiencies is a speedup.
//! - Comparisons interpolate each curve linearly in log-log (log seconds against
//!   log RMSE, between consecutive sample counts).

mod curve;
mod metrics;
#[cfg(feature = "plot")]
mod plot;
mod report;
mod split;
mod variant;

pub use curve::{compare, Cost, Curve, CurveComparison};
pub use metrics::{error_metrics, ConvergeRow, Metrics, RELMSE_EPSILON, SIGNED_EPSILON};
pub use report::ReportFiles;
pub use split::{comparison_markdown, length_label, split_seed, Split, LENGTHS, MAX_SPLIT_PIXELS, MAX_SPLIT_SEEDS};
pub use variant::{Variant, DEFAULT_ADAPTIVE_THRESHOLD};

use crate::choice::{EstimatorChoice, KernelChoice};
use crate::error::{Error, Result};
use crate::estimator::Adaptive;
use crate::film::Image;
use crate::job::{Job, Overrides, RenderOptions};
use crate::render::render;
use crate::sampling::{mix64, Sampler};
use std::path::PathBuf;

/// The reference's samples per pixel when none is given: this many times the largest measured count.
pub const REFERENCE_SPP_FACTOR: u32 = 8;

/// Where the reference image comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Reference {
    /// A linear float image (.exr or .pfm) of the same size.
    File(PathBuf),
    /// Rendered here with this many samples per pixel (SIMD kernel, plain).
    Spp(u32),
}

/// What `rtow converge` is asked to measure, on a job's scene, image size,
/// depth, seed, threads and tile size (its sample count, sampler and
/// estimator options are the variants' and the sample list's); unchecked
/// until it makes a [`ConvergeConfig`].
#[derive(Clone, Debug)]
pub struct ConvergeSpec {
    pub kernels: Vec<KernelChoice>,
    pub variants: Vec<Variant>,
    pub spp_list: Vec<u32>,
    pub reference: Reference,
    /// Passes over every measurement; the fastest time counts (the image is the same every time).
    pub repeat: u32,
    /// First adaptive decision point.
    pub adaptive_min: u32,
    /// Also compare every configuration at the error the baseline reaches at
    /// this sample count (one of `spp_list`).
    pub at_spp: Option<u32>,
    /// Also split every variant's error at this sample count (one of
    /// `spp_list`) by path length and strategy ([`Split`]), over `split_seeds` renders.
    pub split: Option<u32>,
    pub split_seeds: u32,
}

/// A [`ConvergeSpec`] checked, once ([`ConvergeConfig::new`]): what a run
/// measures. It reads as its spec.
#[derive(Clone, Debug)]
pub struct ConvergeConfig {
    spec: ConvergeSpec,
    /// Each variant's adaptive sampling, with the spec's first decision point.
    adaptive: Vec<Option<Adaptive>>,
}

impl std::ops::Deref for ConvergeConfig {
    type Target = ConvergeSpec;
    fn deref(&self) -> &ConvergeSpec {
        &self.spec
    }
}

/// The renders of a split when none is given.
pub const DEFAULT_SPLIT_SEEDS: u32 = 8;

/// One measurement of a run: a kernel, a variant, a sample count, and the job that renders it.
struct Measurement {
    kernel: KernelChoice,
    variant: Variant,
    spp: u32,
    job: Job,
}

impl Reference {
    /// The reference a run of `spp_list` renders when none is given:
    /// [`REFERENCE_SPP_FACTOR`] times its largest sample count.
    pub fn default_for(spp_list: &[u32]) -> Result<Reference> {
        let max = spp_list.iter().copied().max().unwrap_or(1);
        max.checked_mul(REFERENCE_SPP_FACTOR).map(Reference::Spp).ok_or_else(|| {
            Error::invalid(
                "spp_list",
                format!("{max} is too large for the default reference ({REFERENCE_SPP_FACTOR}x)"),
            )
        })
    }
}

impl ConvergeConfig {
    /// Checks the spec's own values (lists, repeat, reference, the adaptive
    /// variants' thresholds and first decision point); the renders' settings
    /// are checked when the run resolves their jobs.
    pub fn new(spec: ConvergeSpec) -> Result<ConvergeConfig> {
        spec.validate()?;
        // Each adaptive variant's options, made once: a bad threshold is the
        // variant's, a bad first decision point the spec's.
        let adaptive = spec
            .variants
            .iter()
            .map(|v| {
                let made = v.adaptive.map(|t| Adaptive::new(t, spec.adaptive_min)).transpose();
                made.map_err(|e| match e {
                    Error::Invalid { field, message } if field == "adaptive.min_spp" => {
                        Error::invalid("adaptive_min", message)
                    }
                    Error::Invalid { message, .. } => Error::invalid("variants", message),
                    e => e,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(ConvergeConfig { spec, adaptive })
    }
}

impl ConvergeSpec {
    /// The spec's values other than adaptive sampling's (see [`ConvergeConfig::new`]).
    fn validate(&self) -> Result<()> {
        if self.kernels.is_empty() {
            return Err(Error::invalid("kernels", "name at least one kernel (scalar, simd)"));
        }
        if self.variants.is_empty() {
            return Err(Error::invalid("variants", "name at least one variant"));
        }
        for (i, v) in self.variants.iter().enumerate() {
            if self.variants[..i].contains(v) {
                return Err(Error::invalid(
                    "variants",
                    format!(
                        "'{}' is listed twice (a variant that names no sampler takes --sampler's, by default \
                         render's: sobol; --sampler independent makes plain the independent one)",
                        v.name()
                    ),
                ));
            }
        }
        for (i, k) in self.kernels.iter().enumerate() {
            if self.kernels[..i].contains(k) {
                return Err(Error::invalid("kernels", format!("'{}' is listed twice", k.name())));
            }
        }
        if self.spp_list.is_empty() {
            return Err(Error::invalid("spp_list", "give at least one sample count"));
        }
        if self.spp_list.contains(&0) {
            return Err(Error::invalid("spp_list", "sample counts must be at least 1"));
        }
        if self.spp_list.windows(2).any(|w| w[0] >= w[1]) {
            return Err(Error::invalid("spp_list", "sample counts must increase strictly"));
        }
        if let Some(n) = self.at_spp {
            if !self.spp_list.contains(&n) {
                return Err(Error::invalid("at_spp", format!("{n} is not one of the sample counts measured")));
            }
        }
        if let Some(n) = self.split {
            if !self.spp_list.contains(&n) {
                return Err(Error::invalid("split", format!("{n} is not one of the sample counts measured")));
            }
            if let Some(v) = self.variants.iter().find(|v| v.adaptive.is_some()) {
                return Err(Error::invalid(
                    "split",
                    format!("'{}' is adaptive: its pixels stop at different sample counts; split without it", v.name()),
                ));
            }
            if !(2..=MAX_SPLIT_SEEDS).contains(&self.split_seeds) {
                return Err(Error::invalid("split_seeds", format!("must be from 2 to {MAX_SPLIT_SEEDS}")));
            }
        }
        if self.repeat == 0 {
            return Err(Error::invalid("repeat", "must be at least 1"));
        }
        if let Reference::Spp(0) = self.reference {
            return Err(Error::invalid("reference_spp", "must be at least 1"));
        }
        Ok(())
    }
}

impl ConvergeConfig {
    /// Every measurement's job (checked, not yet rendered), in run order:
    /// kernels, then variants, then sample counts.
    fn measurements(&self, job: &Job) -> Result<Vec<Measurement>> {
        let mut out = Vec::new();
        for &kernel in &self.kernels {
            for (&variant, &adaptive) in self.variants.iter().zip(&self.adaptive) {
                for &spp in &self.spp_list {
                    let opts = RenderOptions { kernel, roulette: variant.rr, adaptive, ..*job.options() };
                    let o = Overrides {
                        spp: Some(spp),
                        sampler: Some(variant.sampler),
                        estimator: Some(variant.estimator.unwrap_or(job.settings().estimator)),
                        ..Overrides::from(*job.settings())
                    };
                    out.push(Measurement { kernel, variant, spp, job: job.with(&o, &opts)? });
                }
            }
        }
        Ok(out)
    }

    /// The reference render's job: `n` samples per pixel with [`reference_seed`],
    /// the widest SIMD kernel, independent sampling, the `bsdf` estimator,
    /// no roulette or adaptive sampling (the plainest unbiased estimator, so
    /// that no variant is measured against an image of its own making).
    fn reference_job(&self, job: &Job, n: u32) -> Result<Job> {
        let opts = RenderOptions { kernel: KernelChoice::Simd, roulette: None, adaptive: None, ..*job.options() };
        let o = Overrides {
            spp: Some(n),
            seed: Some(reference_seed(job.settings().seed)),
            sampler: Some(Sampler::Independent),
            estimator: Some(EstimatorChoice::Bsdf),
            ..Overrides::from(*job.settings())
        };
        job.with(&o, &opts)
    }
}

/// The seed of the reference render: a different stream family from `seed`'s.
pub fn reference_seed(seed: u64) -> u64 {
    let r = mix64(seed ^ 0x5245_4645_5245_4E43);
    if r == seed {
        r ^ 1
    } else {
        r
    }
}

/// Error of an image against the reference.
/// Everything a converge run measured.
#[derive(Clone, Debug)]
pub struct ConvergeReport {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    pub seed: u64,
    /// How the reference was made (for the outputs).
    pub reference: String,
    /// Renders per measurement (the fastest counts) and worker threads.
    pub repeat: u32,
    pub threads: usize,
    /// See [`ConvergeSpec::at_spp`].
    pub at_spp: Option<u32>,
    /// The reference, when this run rendered it (written out for reuse with `--reference`).
    pub rendered_reference: Option<Image>,
    /// The rendered reference's own noise (`None` for a reference from a file, or of 1 spp).
    pub reference_noise: Option<ReferenceNoise>,
    /// The build, machine, date and command of the run (written to `<scene>.json`).
    pub provenance: crate::provenance::Provenance,
    pub rows: Vec<ConvergeRow>,
    /// With [`ConvergeSpec::split`]: each variant's error split.
    pub splits: Vec<Split>,
}

/// What a run tells its caller as it goes.
pub enum Event<'a> {
    /// The reference render starts: its samples per pixel and seed.
    ReferenceStart {
        spp: u32,
        seed: u64,
    },
    ReferenceDone {
        seconds: f64,
    },
    /// The rendered reference's noise, once the errors are measured.
    ReferenceNoise(&'a ReferenceNoise),
    Measured(&'a ConvergeRow),
    /// A variant's split starts: `seeds` scalar renders at `spp`.
    SplitStart {
        variant: &'a Variant,
        spp: u32,
        seeds: u32,
    },
    SplitDone(&'a Split),
}

/// The reference: a float image of the job's size, or rendered by `job` (seconds reported).
fn load_reference(path: &std::path::Path, width: u32, height: u32) -> Result<Image> {
    let img = Image::load_float(path).map_err(|e| Error::invalid("reference", e.to_string()))?;
    if (img.width, img.height) != (width, height) {
        return Err(Error::invalid(
            "reference",
            format!(
                "{} is {}x{} but the renders are {width}x{height} (set the width and height to match)",
                path.display(),
                img.width,
                img.height,
            ),
        ));
    }
    if img.data.iter().flatten().any(|v| !v.is_finite()) {
        return Err(Error::invalid("reference", format!("{} has NaN or infinite values", path.display())));
    }
    Ok(img)
}

/// Renders (or loads) the reference, then measures every kernel, variant and
/// sample count of `cfg` on `job`'s scene and settings, in that order.
pub fn run(job: &Job, name: &str, cfg: &ConvergeConfig, mut on: impl FnMut(Event)) -> Result<ConvergeReport> {
    let s = *job.settings();
    if cfg.split.is_some() {
        split::check(s.width, s.height, cfg.split_seeds)?;
    }
    // Every job is resolved (and so checked) before anything renders.
    let plan = cfg.measurements(job)?;
    let reference_job = match &cfg.reference {
        Reference::Spp(n) => Some((*n, cfg.reference_job(job, *n)?)),
        Reference::File(_) => None,
    };
    let (reference, ref_text, rendered, reference_mse) = match (&cfg.reference, reference_job) {
        (Reference::File(path), _) => {
            (load_reference(path, s.width, s.height)?, format!("{}", path.display()), false, None)
        }
        (_, Some((n, rj))) => {
            on(Event::ReferenceStart { spp: n, seed: rj.settings().seed });
            let t = std::time::Instant::now();
            let (image, mse, text) = render_reference(&rj, n)?;
            on(Event::ReferenceDone { seconds: t.elapsed().as_secs_f64() });
            (image, text, true, mse)
        }
        (Reference::Spp(_), None) => unreachable!("a rendered reference has its job"),
    };
    let (rows, threads) = measure(&plan, cfg.repeat, &reference, &mut on)?;
    let noise = reference_mse.map(|mse| ReferenceNoise {
        mse,
        smallest_mse: rows.iter().map(ConvergeRow::mse).fold(f64::INFINITY, f64::min),
    });
    if let Some(n) = &noise {
        on(Event::ReferenceNoise(n));
    }
    let mut splits = Vec::new();
    if let Some(n) = cfg.split {
        // The first kernel's measurement of each variant at `n` spp.
        for v in &cfg.variants {
            let (m, row) = plan
                .iter()
                .zip(&rows)
                .find(|(m, _)| m.kernel == cfg.kernels[0] && m.variant == *v && m.spp == n)
                .expect("every variant is measured at every sample count");
            on(Event::SplitStart { variant: v, spp: n, seeds: cfg.split_seeds });
            let sp = split::split(&m.job, *v, cfg.split_seeds, row.seconds, &row.image_hash)?;
            on(Event::SplitDone(&sp));
            splits.push(sp);
        }
    }
    Ok(ConvergeReport {
        scene: name.to_string(),
        width: s.width,
        height: s.height,
        max_depth: s.max_depth,
        seed: s.seed,
        reference: ref_text,
        repeat: cfg.repeat,
        threads,
        at_spp: cfg.at_spp,
        rendered_reference: rendered.then_some(reference),
        reference_noise: noise,
        provenance: crate::provenance::Provenance::collect(),
        rows,
        splits,
    })
}

/// The reference rendered by `rj` (`n` samples per pixel) in two halves of
/// independent seeds (the second [`reference_seed`] of the first), averaged
/// by their samples; with the estimate of its own expected MSE from their
/// difference: `var = E[(h1 - h2)^2] n1 n2 / n^2` per channel (`None` for
/// one sample per pixel, which cannot be halved).
fn render_reference(rj: &Job, n: u32) -> Result<(Image, Option<f64>, String)> {
    let seed = rj.settings().seed;
    if n < 2 {
        let r = render(rj, None)?;
        return Ok((r.image, None, format!("{n} spp, seed {seed} (simd kernel, plain: independent sampling)")));
    }
    let (n1, n2) = (n / 2, n - n / 2);
    let seed2 = reference_seed(seed);
    let half = |spp: u32, seed: u64| {
        rj.with_overrides(&Overrides { spp: Some(spp), seed: Some(seed), ..Overrides::from(*rj.settings()) })
    };
    let a = render(&half(n1, seed)?, None)?.image;
    let b = render(&half(n2, seed2)?, None)?.image;
    let (w1, w2) = (n1 as f64 / n as f64, n2 as f64 / n as f64);
    let mut image = Image::new(a.width, a.height);
    let mut sq = 0.0;
    for ((out, p), q) in image.data.iter_mut().zip(&a.data).zip(&b.data) {
        for k in 0..3 {
            let (x, y) = (p[k] as f64, q[k] as f64);
            out[k] = (w1 * x + w2 * y) as f32;
            sq += (x - y) * (x - y);
        }
    }
    let mse = sq / (3 * image.data.len().max(1)) as f64 * w1 * w2;
    let text = format!(
        "{n} spp: {n1} with seed {seed} and {n2} with seed {seed2}, averaged (simd kernel, plain: independent \
         sampling)"
    );
    Ok((image, Some(mse), text))
}

/// The reference's own noise against the errors measured: every MSE
/// measured against it carries the reference's (about `mse` more than
/// against the true image), and its noise biases the mean signed error in
/// dark pixels.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ReferenceNoise {
    /// The reference's expected MSE (estimated from its two halves).
    pub mse: f64,
    /// The smallest MSE measured against it.
    pub smallest_mse: f64,
}

impl ReferenceNoise {
    /// Above this share of the smallest error measured, the reference is too noisy.
    pub const TOO_NOISY: f64 = 0.1;

    /// The reference's MSE as a share of the smallest MSE measured.
    pub fn share(&self) -> f64 {
        self.mse / self.smallest_mse
    }

    /// A warning when the reference's noise is not small against the errors measured.
    pub fn warning(&self) -> Option<String> {
        (!(self.share() <= Self::TOO_NOISY)).then(|| {
            format!(
                "the reference's own noise (estimated MSE {:.3e}) is {:.0}% of the smallest error measured \
                 ({:.3e}): every MSE carries it and the mean signed error is biased by it; raise --reference-spp \
                 (its MSE falls as 1/spp)",
                self.mse,
                100.0 * self.share(),
                self.smallest_mse
            )
        })
    }
}

/// Every measurement once per pass, `repeat` passes: a change of load on the
/// machine then falls on every configuration alike instead of on whichever
/// ran at the time. The fastest time counts; the image (and so the error) is
/// the same in every pass. Returns the rows and the worker threads used.
fn measure(
    plan: &[Measurement],
    repeat: u32,
    reference: &Image,
    on: &mut impl FnMut(Event),
) -> Result<(Vec<ConvergeRow>, usize)> {
    let mut rows: Vec<ConvergeRow> = Vec::with_capacity(plan.len());
    let mut threads = 0;
    for pass in 0..repeat {
        for (i, m) in plan.iter().enumerate() {
            let r = render(&m.job, None)?;
            threads = r.stats.threads;
            if pass == 0 {
                let e = error_metrics(&r.image, reference);
                rows.push(ConvergeRow {
                    kernel: m.kernel,
                    variant: m.variant,
                    spp: m.spp,
                    seconds: r.stats.seconds,
                    rays: r.stats.rays,
                    samples: r.stats.samples,
                    rmse: e.rmse,
                    relmse: e.relmse,
                    mean_rel_error: e.mean_rel_error,
                    image_hash: r.stats.image_hash,
                });
            } else {
                let row = &mut rows[i];
                if row.image_hash != r.stats.image_hash {
                    return Err(Error::Input(format!(
                        "{} at {} spp rendered a different image on pass {}: renders must be deterministic",
                        row.label(),
                        m.spp,
                        pass + 1
                    )));
                }
                row.seconds = row.seconds.min(r.stats.seconds);
            }
            if pass + 1 == repeat {
                on(Event::Measured(&rows[i]));
            }
        }
    }
    Ok((rows, threads))
}

/// Axis ticks of a log scale: 1, 2 and 5 times the powers of ten in `lo..=hi`.
#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimator::Roulette;

    fn curve(label: &str, c: f64, times: &[f64]) -> Curve {
        // An unbiased estimator: MSE = c / t.
        Curve { label: label.into(), points: times.iter().map(|&t| (t, (c / t).sqrt())).collect() }
    }

    #[test]
    fn variants_parse_and_name() {
        assert_eq!(Variant::parse("plain").unwrap(), Variant::PLAIN);
        assert_eq!(Variant::parse("rr").unwrap().name(), "rr");
        assert_eq!(Variant::parse("adaptive").unwrap().adaptive, Some(DEFAULT_ADAPTIVE_THRESHOLD));
        let v = Variant::parse("rr+adaptive:0.05").unwrap();
        assert_eq!((v.rr, v.adaptive), (Some(Roulette::default()), Some(0.05)));
        assert_eq!(Variant::parse(&v.name()).unwrap(), v);
        let v = Variant::parse("sobol+rr").unwrap();
        assert_eq!(
            (v.sampler, v.rr, v.name().as_str()),
            (crate::sampling::Sampler::SOBOL, Some(Roulette::default()), "sobol+rr")
        );
        assert_eq!(Variant::parse(&v.name()).unwrap(), v);
        let v = Variant::parse("rr+sobol-lens+adaptive:0.05").unwrap();
        assert_eq!(v.name(), "sobol-lens+rr+adaptive:0.05");
        assert_eq!(Variant::parse(&v.name()).unwrap(), v);
        let v = Variant::parse("adaptive:0.1+rr:3").unwrap();
        assert_eq!((v.rr, v.adaptive), (Some(Roulette::new(3).unwrap()), Some(0.1)));
        assert_eq!(v.name(), "rr:3+adaptive:0.1");
        assert_eq!(Variant::parse(&v.name()).unwrap(), v);
        let v = Variant::parse("sobol+book").unwrap();
        assert_eq!((v.estimator, v.name().as_str()), (Some(EstimatorChoice::Book), "book+sobol"));
        assert_eq!(Variant::parse(&v.name()).unwrap(), v);
        assert_eq!(Variant::parse("bsdf").unwrap().name(), "bsdf");
        for bad in [
            "book+bsdf",
            "",
            "fast",
            "rr+rr",
            "adaptive:x",
            "adaptive:0",
            "adaptive:-1",
            "adaptive:nan",
            "adaptive:inf",
            "plain+rr",
            "rr:0",
            "rr:x",
            "rr:-2",
            "adaptive:",
            "rr+adaptive+adaptive",
            "sobol+sobol",
            "sobol:3",
            "sobolx",
        ] {
            let e = Variant::parse(bad).unwrap_err().to_string();
            assert!(e.starts_with("variants:"), "{bad}: {e}");
        }
    }

    #[test]
    fn speedups_of_known_curves() {
        // `fast` reaches every error in half the time: 2x at equal error, and
        // at equal time its MSE is half the other's.
        let slow = curve("slow", 1e-3, &[0.1, 0.2, 0.4, 0.8, 1.6]);
        let fast = curve("fast", 0.5e-3, &[0.07, 0.13, 0.29, 0.55, 1.1]);
        let c = compare(&slow, &fast);
        let (e, x) = c.equal_error.unwrap();
        assert!((x - 2.0).abs() < 1e-9, "{x}");
        assert!((e - (1e-3f64 / 1.6).sqrt()).abs() < 1e-12);
        let (t, m) = c.equal_time.unwrap();
        assert!((t - 1.1).abs() < 1e-12);
        assert!((m - 2.0).abs() < 1e-9, "{m}");
        let back = compare(&fast, &slow);
        assert!((back.equal_error.unwrap().1 - 0.5).abs() < 1e-9);
        // Disjoint time ranges: no equal-time comparison.
        let later = curve("later", 1e-3, &[10.0, 20.0]);
        assert_eq!(compare(&slow, &later).equal_time, None);
    }

    #[test]
    fn report_compares_in_seconds_and_in_rays() {
        // `simd/rr` traces half the rays for the same errors but takes as long.
        let row = |variant: Variant, spp: u32, rays: u64, rmse: f64| ConvergeRow {
            kernel: KernelChoice::Simd,
            variant,
            spp,
            seconds: spp as f64,
            rays,
            samples: 0,
            rmse,
            relmse: 0.0,
            mean_rel_error: 0.0,
            image_hash: String::new(),
        };
        let rr = Variant::parse("rr").unwrap();
        let rows = vec![
            row(Variant::PLAIN, 4, 400, 0.5),
            row(Variant::PLAIN, 16, 1600, 0.25),
            row(rr, 4, 200, 0.5),
            row(rr, 16, 800, 0.25),
        ];
        let report = ConvergeReport {
            scene: "s".into(),
            width: 1,
            height: 1,
            max_depth: 1,
            seed: 0,
            reference: String::new(),
            repeat: 1,
            threads: 1,
            at_spp: Some(16),
            provenance: crate::provenance::Provenance::collect(),
            rendered_reference: None,
            reference_noise: None,
            rows,
            splits: vec![],
        };
        let t = report.comparisons_by(Cost::Seconds);
        let r = report.comparisons_by(Cost::Rays);
        assert_eq!((t.len(), r.len()), (1, 1));
        assert_eq!((t[0].base.as_str(), t[0].other.as_str()), ("simd/plain", "simd/rr"));
        assert!((t[0].equal_error.unwrap().1 - 1.0).abs() < 1e-12);
        assert!((r[0].equal_error.unwrap().1 - 2.0).abs() < 1e-12);
        let line = &report.comparison_lines()[0];
        assert!(line.contains("1.00x in time") && line.contains("2.00x in rays"), "{line}");
        // At the baseline's 16-spp error, rr takes the same time and half the rays.
        let reach = report.reach_lines();
        assert!(reach[0].contains("simd/plain at 16 spp (0.25000"), "{reach:?}");
        assert!(reach[1].contains("1.00x the time") && reach[1].contains("0.50x the rays"), "{reach:?}");
        assert!(report.markdown().contains("- simd/rr: 16.000 s"), "{}", report.markdown());
        assert!(report.svg().unwrap().contains("simd/rr"));
        assert_eq!(report.csv().lines().count(), 5);
    }

    #[test]
    fn interpolation_is_log_log() {
        let c = Curve { label: "c".into(), points: vec![(1.0, 1.0), (100.0, 0.01)] };
        assert!((c.error_at(10.0).unwrap() - 0.1).abs() < 1e-12);
        assert!((c.time_at(0.1).unwrap() - 10.0).abs() < 1e-9);
        assert_eq!(c.error_at(1000.0), None);
        assert_eq!(c.time_at(0.001), None);
        // A curve that flattens (adaptive sampling at its threshold) is read
        // at its first crossing.
        let flat = Curve { label: "f".into(), points: vec![(1.0, 1.0), (2.0, 0.5), (4.0, 0.6), (8.0, 0.4)] };
        assert_eq!(flat.time_at(0.5), Some(2.0));
        assert!(flat.time_at(0.55).unwrap() < 2.0);
    }

    #[test]
    fn metrics_of_known_images() {
        let r = Image { width: 2, height: 1, data: vec![[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]] };
        let x = Image { width: 2, height: 1, data: vec![[0.1, 0.1, 0.1], [1.0, 1.0, 1.3]] };
        let m = error_metrics(&x, &r);
        let want = ((3.0 * 0.01 + 0.09) / 6.0f64).sqrt();
        assert!((m.rmse - want).abs() < 1e-6);
        let want_rel = (3.0 * 0.01 / 0.01 + 0.09 / 1.01) / 6.0;
        assert!((m.relmse - want_rel).abs() < 1e-5);
        let want_signed = (3.0 * 0.1 / 0.01 + 0.3 / 1.01) / 6.0;
        assert!((m.mean_rel_error - want_signed).abs() < 1e-5);
        let zero = error_metrics(&r, &r);
        assert_eq!((zero.rmse, zero.relmse, zero.mean_rel_error), (0.0, 0.0, 0.0));
    }

    #[test]
    fn reference_seed_differs() {
        for s in [0u64, 1, 42, u64::MAX] {
            assert_ne!(reference_seed(s), s);
        }
    }

    #[test]
    fn bad_configs_name_their_setting() {
        let good = ConvergeSpec {
            kernels: vec![KernelChoice::Simd],
            variants: vec![Variant::PLAIN],
            spp_list: vec![1, 2],
            reference: Reference::Spp(4),
            repeat: 1,
            adaptive_min: 16,
            at_spp: None,
            split: None,
            split_seeds: DEFAULT_SPLIT_SEEDS,
        };
        ConvergeConfig::new(good.clone()).unwrap();
        type Break = Box<dyn Fn(&mut ConvergeSpec)>;
        let cases: Vec<(&str, Break)> = vec![
            ("kernels", Box::new(|c| c.kernels.clear())),
            ("kernels", Box::new(|c| c.kernels = vec![KernelChoice::Simd, KernelChoice::Simd])),
            ("variants", Box::new(|c| c.variants.clear())),
            ("variants", Box::new(|c| c.variants = vec![Variant::PLAIN, Variant::PLAIN])),
            ("spp_list", Box::new(|c| c.spp_list.clear())),
            ("spp_list", Box::new(|c| c.spp_list = vec![0, 1])),
            ("spp_list", Box::new(|c| c.spp_list = vec![4, 2])),
            ("reference_spp", Box::new(|c| c.reference = Reference::Spp(0))),
            ("repeat", Box::new(|c| c.repeat = 0)),
            ("at_spp", Box::new(|c| c.at_spp = Some(3))),
            ("split", Box::new(|c| c.split = Some(3))),
            (
                "split",
                Box::new(|c| {
                    c.split = Some(2);
                    c.variants = vec![Variant::parse("adaptive").unwrap()];
                }),
            ),
            (
                "split_seeds",
                Box::new(|c| {
                    c.split = Some(2);
                    c.split_seeds = 1;
                }),
            ),
            ("variants", Box::new(|c| c.variants = vec![Variant { adaptive: Some(-1.0), ..Variant::PLAIN }])),
            (
                "adaptive_min",
                Box::new(|c| {
                    c.variants = vec![Variant::parse("adaptive").unwrap()];
                    c.adaptive_min = 1;
                }),
            ),
        ];
        for (field, f) in cases {
            let mut c = good.clone();
            f(&mut c);
            let e = ConvergeConfig::new(c).unwrap_err().to_string();
            assert!(e.starts_with(&format!("{field}:")), "{field}: {e}");
        }
    }
}
