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

use crate::error::{Error, Result};
use crate::estimator::{Adaptive, ROULETTE_AFTER_RAYS};
use crate::film::Image;
use crate::kernel::KernelKind;
use crate::plan::Settings;
use crate::render::{render, RenderOptions};
use crate::sampling::mix64;
use crate::scene::Scene;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Added to a pixel's squared reference value in relMSE.
pub const RELMSE_EPSILON: f64 = 0.01;

/// Added to a pixel's reference value in the mean signed relative error.
pub const SIGNED_EPSILON: f64 = 0.01;

/// The threshold of the `adaptive` variant when none is given (`adaptive:T`).
pub const DEFAULT_ADAPTIVE_THRESHOLD: f32 = 0.02;

/// An estimator variant: plain, Russian roulette, adaptive sampling, or both.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variant {
    /// Russian roulette from this many rays on.
    pub rr: Option<u32>,
    /// Relative error threshold of adaptive sampling.
    pub adaptive: Option<f32>,
}

impl Variant {
    pub const PLAIN: Variant = Variant { rr: None, adaptive: None };

    /// Parses `plain`, `rr`, `rr:N`, `adaptive`, `adaptive:T` or a
    /// `+`-joined combination such as `rr+adaptive:0.05`.
    pub fn parse(text: &str) -> Result<Variant> {
        let bad = |m: String| Error::invalid("--variants", m);
        let mut v = Variant::PLAIN;
        let text = text.trim();
        if text == "plain" {
            return Ok(v);
        }
        for part in text.split('+') {
            let part = part.trim();
            let (name, value) = match part.split_once(':') {
                Some((n, x)) => (n, Some(x)),
                None => (part, None),
            };
            match name {
                "rr" if v.rr.is_none() => {
                    let n = match value {
                        None => ROULETTE_AFTER_RAYS,
                        Some(x) => match x.parse::<u32>() {
                            Ok(n) if n >= 1 => n,
                            _ => {
                                return Err(bad(format!(
                                    "'{text}': '{x}' is not a number of rays of at least 1 (rr:N)"
                                )))
                            }
                        },
                    };
                    v.rr = Some(n);
                }
                "adaptive" if v.adaptive.is_none() => {
                    let t = match value {
                        None => DEFAULT_ADAPTIVE_THRESHOLD,
                        Some(x) => x.parse::<f32>().unwrap_or(f32::NAN),
                    };
                    if !(t.is_finite() && t > 0.0) {
                        return Err(bad(format!(
                            "'{text}': the adaptive threshold must be a positive number (adaptive:THRESHOLD)"
                        )));
                    }
                    v.adaptive = Some(t);
                }
                _ => {
                    return Err(bad(format!(
                        "unknown or repeated variant '{part}' in '{text}' (use plain, rr, rr:N, adaptive, adaptive:THRESHOLD, or e.g. rr+adaptive:0.05)"
                    )))
                }
            }
        }
        Ok(v)
    }

    pub fn name(&self) -> String {
        let rr = match self.rr {
            Some(n) if n == ROULETTE_AFTER_RAYS => "rr".to_string(),
            Some(n) => format!("rr:{n}"),
            None => String::new(),
        };
        match (rr.as_str(), self.adaptive) {
            ("", None) => "plain".into(),
            (rr, None) => rr.into(),
            ("", Some(t)) => format!("adaptive:{t}"),
            (rr, Some(t)) => format!("{rr}+adaptive:{t}"),
        }
    }
}

/// Where the reference image comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Reference {
    /// A linear float image (.exr or .pfm) of the same size.
    File(PathBuf),
    /// Rendered here with this many samples per pixel (SIMD kernel, plain).
    Spp(u32),
}

/// What `rtow converge` measures.
#[derive(Clone, Debug)]
pub struct Config {
    /// Image size, depth and seed of the measured renders (`spp` is ignored).
    pub settings: Settings,
    pub kernels: Vec<KernelKind>,
    pub variants: Vec<Variant>,
    pub spp_list: Vec<u32>,
    pub reference: Reference,
    pub threads: Option<usize>,
    pub tile: u32,
    /// Passes over every measurement; the fastest time counts (the image is the same every time).
    pub repeat: u32,
    /// First adaptive decision point.
    pub adaptive_min: u32,
    /// Also compare every configuration at the error the baseline reaches at
    /// this sample count (one of `spp_list`).
    pub at_spp: Option<u32>,
}

impl Config {
    pub fn validate(&self) -> Result<()> {
        if self.kernels.is_empty() {
            return Err(Error::invalid("--kernels", "name at least one kernel (scalar, simd)"));
        }
        if self.variants.is_empty() {
            return Err(Error::invalid("--variants", "name at least one variant"));
        }
        for (i, v) in self.variants.iter().enumerate() {
            if self.variants[..i].contains(v) {
                return Err(Error::invalid("--variants", format!("'{}' is listed twice", v.name())));
            }
        }
        for (i, k) in self.kernels.iter().enumerate() {
            if self.kernels[..i].contains(k) {
                return Err(Error::invalid("--kernels", format!("'{}' is listed twice", k.name())));
            }
        }
        if self.spp_list.is_empty() {
            return Err(Error::invalid("--spp-list", "give at least one sample count"));
        }
        if self.spp_list.contains(&0) {
            return Err(Error::invalid("--spp-list", "sample counts must be at least 1"));
        }
        if self.spp_list.windows(2).any(|w| w[0] >= w[1]) {
            return Err(Error::invalid("--spp-list", "sample counts must increase strictly"));
        }
        if let Some(n) = self.at_spp {
            if !self.spp_list.contains(&n) {
                return Err(Error::invalid("--at-spp", format!("{n} is not one of --spp-list")));
            }
        }
        if self.repeat == 0 {
            return Err(Error::invalid("--repeat", "must be at least 1"));
        }
        if let Reference::Spp(0) = self.reference {
            return Err(Error::invalid("--reference-spp", "must be at least 1"));
        }
        if self.variants.iter().any(|v| v.adaptive.is_some()) {
            Adaptive::new(DEFAULT_ADAPTIVE_THRESHOLD, self.adaptive_min).map_err(|e| match e {
                Error::Invalid { message, .. } => Error::invalid("--adaptive-min", message),
                e => e,
            })?;
        }
        for &spp in self.spp_list.iter().chain(match &self.reference {
            Reference::Spp(n) => std::slice::from_ref(n),
            _ => &[],
        }) {
            Settings { spp, ..self.settings }.validate()?;
        }
        Ok(())
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
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    pub rmse: f64,
    /// Mean of `(x - r)^2 / (r^2 + 0.01)`.
    pub relmse: f64,
    /// Mean signed relative error, `(x - r) / (r + 0.01)` averaged over every
    /// channel of every pixel: zero in expectation for an unbiased estimator
    /// (it is linear in `x`), so it shows a bias such as adaptive sampling's.
    pub mean_rel_error: f64,
}

/// Error of `image` against `reference` (the sizes must match).
pub fn error_metrics(image: &Image, reference: &Image) -> Metrics {
    let mut se = 0.0;
    let mut rel = 0.0;
    let mut signed = 0.0;
    let mut n = 0usize;
    for (p, r) in image.data.iter().zip(&reference.data) {
        for k in 0..3 {
            let d = p[k] as f64 - r[k] as f64;
            let r = r[k] as f64;
            se += d * d;
            rel += d * d / (r * r + RELMSE_EPSILON);
            signed += d / (r.abs() + SIGNED_EPSILON);
            n += 1;
        }
    }
    let n = n.max(1) as f64;
    Metrics { rmse: (se / n).sqrt(), relmse: rel / n, mean_rel_error: signed / n }
}

/// One measured render.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub kernel: KernelKind,
    pub variant: Variant,
    pub spp: u32,
    pub seconds: f64,
    pub rays: u64,
    pub samples: u64,
    pub rmse: f64,
    pub relmse: f64,
    pub mean_rel_error: f64,
    pub image_hash: String,
}

impl Row {
    pub fn mse(&self) -> f64 {
        self.rmse * self.rmse
    }
    /// `1 / (MSE x seconds)`.
    pub fn efficiency(&self) -> f64 {
        1.0 / (self.mse() * self.seconds)
    }
    pub fn label(&self) -> String {
        format!("{}/{}", self.kernel.name(), self.variant.name())
    }
}

/// Everything a converge run measured.
#[derive(Clone, Debug)]
pub struct Report {
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
    /// See [`Config::at_spp`].
    pub at_spp: Option<u32>,
    /// The reference, when this run rendered it (written out for reuse with `--reference`).
    pub rendered_reference: Option<Image>,
    pub rows: Vec<Row>,
}

/// What a run tells its caller as it goes.
pub enum Event<'a> {
    ReferenceStart(u32),
    ReferenceDone { seconds: f64 },
    Measured(&'a Row),
}

/// Renders (or loads) the reference, then measures every kernel, variant and
/// sample count, in that order.
pub fn run(scene: &Scene, name: &str, cfg: &Config, mut on: impl FnMut(Event)) -> Result<Report> {
    cfg.validate()?;
    let s = cfg.settings;
    let base =
        RenderOptions { kernel: KernelKind::Simd, threads: cfg.threads, tile: cfg.tile, ..RenderOptions::default() };
    let (reference, ref_text, rendered) = match &cfg.reference {
        Reference::File(path) => {
            let img = Image::load_float(path).map_err(|e| Error::invalid("--reference", e.to_string()))?;
            if (img.width, img.height) != (s.width, s.height) {
                return Err(Error::invalid(
                    "--reference",
                    format!(
                        "{} is {}x{} but the renders are {}x{} (set --width/--height to match)",
                        path.display(),
                        img.width,
                        img.height,
                        s.width,
                        s.height
                    ),
                ));
            }
            if img.data.iter().flatten().any(|v| !v.is_finite()) {
                return Err(Error::invalid("--reference", format!("{} has NaN or infinite values", path.display())));
            }
            (img, format!("{}", path.display()), false)
        }
        Reference::Spp(n) => {
            on(Event::ReferenceStart(*n));
            let seed = reference_seed(s.seed);
            let r = render(scene, Settings { spp: *n, seed, ..s }, base, None)?;
            on(Event::ReferenceDone { seconds: r.stats.seconds });
            (r.image, format!("{n} spp, seed {seed} (simd kernel, plain)"), true)
        }
    };
    // Every measurement once per pass, `repeat` passes: a change of load on
    // the machine then falls on every configuration alike instead of on
    // whichever ran at the time. The fastest time counts; the image (and so
    // the error) is the same in every pass.
    let mut plan = Vec::new();
    for &kernel in &cfg.kernels {
        for &variant in &cfg.variants {
            for &spp in &cfg.spp_list {
                let adaptive = match variant.adaptive {
                    Some(t) => Some(Adaptive::new(t, cfg.adaptive_min).map_err(|e| match e {
                        Error::Invalid { message, .. } => Error::invalid("--variants", message),
                        e => e,
                    })?),
                    None => None,
                };
                let opts = RenderOptions {
                    kernel,
                    rr: variant.rr.is_some(),
                    rr_after: variant.rr.unwrap_or(ROULETTE_AFTER_RAYS),
                    adaptive,
                    ..base
                };
                plan.push((kernel, variant, spp, opts));
            }
        }
    }
    let mut rows: Vec<Row> = Vec::with_capacity(plan.len());
    let mut threads = 0;
    for pass in 0..cfg.repeat {
        for (i, &(kernel, variant, spp, opts)) in plan.iter().enumerate() {
            let r = render(scene, Settings { spp, ..s }, opts, None)?;
            threads = r.stats.threads;
            if pass == 0 {
                let m = error_metrics(&r.image, &reference);
                rows.push(Row {
                    kernel,
                    variant,
                    spp,
                    seconds: r.stats.seconds,
                    rays: r.stats.rays,
                    samples: r.stats.samples,
                    rmse: m.rmse,
                    relmse: m.relmse,
                    mean_rel_error: m.mean_rel_error,
                    image_hash: r.stats.image_hash,
                });
            } else {
                let row = &mut rows[i];
                if row.image_hash != r.stats.image_hash {
                    return Err(Error::Input(format!(
                        "{} at {spp} spp rendered a different image on pass {}: renders must be deterministic",
                        row.label(),
                        pass + 1
                    )));
                }
                row.seconds = row.seconds.min(r.stats.seconds);
            }
            if pass + 1 == cfg.repeat {
                on(Event::Measured(&rows[i]));
            }
        }
    }
    Ok(Report {
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
        rows,
    })
}

/// Axis ticks of a log scale: 1, 2 and 5 times the powers of ten in `lo..=hi`.
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut out = Vec::new();
    if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
        return out;
    }
    let mut d = lo.log10().floor() as i32;
    while d <= hi.log10().ceil() as i32 {
        for m in [1.0, 2.0, 5.0] {
            let v = m * 10f64.powi(d);
            if v >= lo && v <= hi {
                out.push(v);
            }
        }
        d += 1;
    }
    if out.len() < 2 {
        out = vec![lo, hi];
    }
    out
}

/// A tick value with as many decimals as it needs (0.005, 0.02, 1, 20).
fn tick_label(v: f64) -> String {
    let decimals = if v > 0.0 { (-v.log10().floor()).max(0.0) as usize } else { 0 };
    format!("{v:.decimals$}")
}

/// A configuration's measurements as (seconds, RMSE) points, in sample-count order.
#[derive(Clone, Debug)]
pub struct Curve {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

fn lerp_log(x: f64, (x0, y0): (f64, f64), (x1, y1): (f64, f64)) -> f64 {
    let (lx, lx0, lx1) = (x.ln(), x0.ln(), x1.ln());
    if lx1 == lx0 {
        return y0.min(y1);
    }
    let f = (lx - lx0) / (lx1 - lx0);
    (y0.ln() + f * (y1.ln() - y0.ln())).exp()
}

impl Curve {
    fn usable(&self) -> Vec<(f64, f64)> {
        self.points.iter().copied().filter(|&(t, e)| t > 0.0 && e > 0.0 && t.is_finite() && e.is_finite()).collect()
    }

    /// RMSE at `t` seconds, interpolated in log-log between the two measured
    /// times around it (the points sorted by time); `None` outside the range.
    pub fn error_at(&self, t: f64) -> Option<f64> {
        let mut p = self.usable();
        p.sort_by(|a, b| a.0.total_cmp(&b.0));
        p.windows(2)
            .find(|w| w[0].0 <= t && t <= w[1].0)
            .map(|w| lerp_log(t, w[0], w[1]))
            .or_else(|| p.iter().find(|q| q.0 == t).map(|q| q.1))
    }

    /// Seconds to reach RMSE `e`: the first segment, in sample-count order,
    /// whose errors bracket `e`, interpolated in log-log; `None` if never reached.
    pub fn time_at(&self, e: f64) -> Option<f64> {
        let p = self.usable();
        if let Some(q) = p.iter().find(|q| q.1 == e) {
            return Some(q.0);
        }
        p.windows(2)
            .find(|w| (w[0].1 - e) * (w[1].1 - e) < 0.0)
            .map(|w| lerp_log(e, (w[0].1, w[0].0), (w[1].1, w[1].0)))
    }

    fn time_range(&self) -> Option<(f64, f64)> {
        let p = self.usable();
        let lo = p.iter().map(|q| q.0).reduce(f64::min)?;
        let hi = p.iter().map(|q| q.0).reduce(f64::max)?;
        Some((lo, hi))
    }

    fn min_error(&self) -> Option<f64> {
        self.usable().iter().map(|q| q.1).reduce(f64::min)
    }
}

/// What a curve's horizontal axis measures. Seconds are what a user waits,
/// but on a shared machine they are noisy; rays are exact and repeatable (and
/// ignore differences in the cost of a ray, e.g. between kernels).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cost {
    Seconds,
    Rays,
}

/// How `other` compares to `base`.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    pub base: String,
    pub other: String,
    /// (RMSE level, base seconds / other seconds) at the lowest error both reach.
    pub equal_error: Option<(f64, f64)>,
    /// (seconds, base MSE / other MSE) at the longest time both cover: the
    /// speedup if both errors fall as 1/time.
    pub equal_time: Option<(f64, f64)>,
}

/// Compares two curves (see [`Comparison`]).
pub fn compare(base: &Curve, other: &Curve) -> Comparison {
    let equal_error = match (base.min_error(), other.min_error()) {
        (Some(a), Some(b)) => {
            let e = a.max(b);
            match (base.time_at(e), other.time_at(e)) {
                (Some(tb), Some(to)) if to > 0.0 => Some((e, tb / to)),
                _ => None,
            }
        }
        _ => None,
    };
    let equal_time = match (base.time_range(), other.time_range()) {
        (Some((lb, hb)), Some((lo, ho))) if lb.max(lo) <= hb.min(ho) => {
            let t = hb.min(ho);
            match (base.error_at(t), other.error_at(t)) {
                (Some(eb), Some(eo)) if eo > 0.0 => Some((t, (eb * eb) / (eo * eo))),
                _ => None,
            }
        }
        _ => None,
    };
    Comparison { base: base.label.clone(), other: other.label.clone(), equal_error, equal_time }
}

impl Report {
    /// One curve per (kernel, variant), in the order measured.
    pub fn curves(&self) -> Vec<Curve> {
        self.curves_by(Cost::Seconds)
    }

    /// One curve per (kernel, variant) with `cost` on the horizontal axis.
    pub fn curves_by(&self, cost: Cost) -> Vec<Curve> {
        let mut out: Vec<Curve> = Vec::new();
        for r in &self.rows {
            let label = r.label();
            let x = match cost {
                Cost::Seconds => r.seconds,
                Cost::Rays => r.rays as f64,
            };
            match out.iter_mut().find(|c| c.label == label) {
                Some(c) => c.points.push((x, r.rmse)),
                None => out.push(Curve { label, points: vec![(x, r.rmse)] }),
            }
        }
        out
    }

    /// Every configuration against the first one, and, for every other kernel,
    /// its variants against its own first variant.
    pub fn comparisons(&self) -> Vec<Comparison> {
        self.comparisons_by(Cost::Seconds)
    }

    /// [`Report::comparisons`] with `cost` in place of seconds.
    pub fn comparisons_by(&self, cost: Cost) -> Vec<Comparison> {
        let curves = self.curves_by(cost);
        let mut out = Vec::new();
        let Some(first) = curves.first() else {
            return out;
        };
        for c in &curves[1..] {
            out.push(compare(first, c));
        }
        let mut kernels: Vec<KernelKind> = Vec::new();
        for r in &self.rows {
            if !kernels.contains(&r.kernel) {
                kernels.push(r.kernel);
            }
        }
        for k in kernels.iter().skip(1) {
            let prefix = format!("{}/", k.name());
            let own: Vec<&Curve> = curves.iter().filter(|c| c.label.starts_with(&prefix)).collect();
            for c in own.iter().skip(1) {
                out.push(compare(own[0], c));
            }
        }
        out
    }

    pub fn csv(&self) -> String {
        let mut s = String::from(
            "scene,width,height,kernel,variant,spp,seconds,rays,samples,mrays_per_s,rmse,relmse,mean_rel_error,efficiency,image_hash\n",
        );
        for r in &self.rows {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{:.6},{},{},{:.4},{:.6e},{:.6e},{:.6e},{:.6e},{}",
                self.scene,
                self.width,
                self.height,
                r.kernel.name(),
                r.variant.name(),
                r.spp,
                r.seconds,
                r.rays,
                r.samples,
                r.rays as f64 / r.seconds / 1e6,
                r.rmse,
                r.relmse,
                r.mean_rel_error,
                r.efficiency(),
                r.image_hash
            );
        }
        s
    }

    /// Lines describing the comparisons, for the terminal and the markdown file.
    pub fn comparison_lines(&self) -> Vec<String> {
        let by_rays = self.comparisons_by(Cost::Rays);
        self.comparisons()
            .iter()
            .zip(&by_rays)
            .map(|(c, r)| {
                let ee = match c.equal_error {
                    Some((e, x)) => format!("equal error (RMSE {e:.4}): {x:.2}x in time"),
                    None => "equal error: curves do not overlap in time".into(),
                };
                let er = match r.equal_error {
                    Some((e, x)) => format!("{x:.2}x in rays (RMSE {e:.4})"),
                    None => "curves do not overlap in rays".into(),
                };
                let et = match c.equal_time {
                    Some((t, x)) => format!("equal time ({t:.3} s): MSE ratio {x:.2}x"),
                    None => "equal time: time ranges do not overlap".into(),
                };
                format!("{} vs {}: {ee}, {er}; {et}", c.other, c.base)
            })
            .collect()
    }

    /// With `at_spp` set: what every other configuration needs to reach the
    /// RMSE that the baseline (the first configuration) measured at `at_spp`.
    pub fn reach_lines(&self) -> Vec<String> {
        let Some(n) = self.at_spp else {
            return vec![];
        };
        let (by_time, by_rays) = (self.curves(), self.curves_by(Cost::Rays));
        let Some(base) = by_time.first() else {
            return vec![];
        };
        let Some(b) = self.rows.iter().find(|r| r.label() == base.label && r.spp == n) else {
            return vec![];
        };
        let mut out = vec![format!(
            "to reach the RMSE of {} at {n} spp ({:.5}, {:.3} s, {:.2}M rays):",
            b.label(),
            b.rmse,
            b.seconds,
            b.rays as f64 / 1e6
        )];
        for (ct, cr) in by_time.iter().zip(&by_rays).skip(1) {
            out.push(match (ct.time_at(b.rmse), cr.time_at(b.rmse)) {
                (Some(t), Some(r)) => format!(
                    "  {}: {t:.3} s ({:.2}x the time), {:.2}M rays ({:.2}x the rays)",
                    ct.label,
                    t / b.seconds,
                    r / 1e6,
                    r / b.rays as f64
                ),
                _ => format!("  {}: does not reach it at the measured sample counts", ct.label),
            });
        }
        out
    }

    /// Kernels that rendered the same variant and spp to different images
    /// (they must not: both kernels are one estimator).
    pub fn kernel_mismatches(&self) -> Vec<String> {
        let mut out = Vec::new();
        for (i, a) in self.rows.iter().enumerate() {
            for b in &self.rows[i + 1..] {
                if a.kernel != b.kernel && a.variant == b.variant && a.spp == b.spp && a.image_hash != b.image_hash {
                    out.push(format!("{} and {} differ at {} spp ({})", a.label(), b.label(), a.spp, a.variant.name()));
                }
            }
        }
        out
    }

    pub fn markdown(&self) -> String {
        let mut s = format!(
            "# Run time against error: {} ({}x{}, depth {}, seed {})\n\nReference: {}. Seconds: wall time of the render \
             (scene preparation apart), the fastest of {} run(s), {} thread(s). Error against the reference: RMSE and relMSE \
             of the linear image; mean signed rel. error = mean of (x - r) / (r + 0.01), zero in expectation without bias.\n\n",
            self.scene, self.width, self.height, self.max_depth, self.seed, self.reference, self.repeat, self.threads
        );
        s += "| kernel | variant | spp | seconds | Mrays/s | samples/px | RMSE | relMSE | mean signed rel. error | efficiency 1/(MSE s) |\n";
        s += "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
        let px = (self.width as f64 * self.height as f64).max(1.0);
        for r in &self.rows {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.3} | {:.2} | {:.1} | {:.5} | {:.3e} | {:+.5} | {:.4e} |",
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
            );
        }
        let reach = self.reach_lines();
        if let Some((head, rest)) = reach.split_first() {
            let _ = writeln!(s, "\n{}\n", head.replace("to reach", "To reach"));
            for l in rest {
                let _ = writeln!(s, "- {}", l.trim_start());
            }
        }
        let lines = self.comparison_lines();
        if !lines.is_empty() {
            s +=
                "\nSpeedups (log-log interpolation between measured sample counts; in rays: the same with rays traced \
                  in place of seconds):\n\n";
            for l in lines {
                let _ = writeln!(s, "- {l}");
            }
        }
        s
    }

    /// The log-log plot of RMSE against seconds, as SVG text.
    pub fn svg(&self) -> Result<String> {
        use plotters::prelude::*;
        let curves = self.curves();
        let mut pts: Vec<(f64, f64)> = curves.iter().flat_map(|c| c.usable()).collect();
        let empty = pts.is_empty();
        if empty {
            // Nothing to draw (e.g. a scene without noise: every error is 0);
            // still write a plot that says so rather than fail after measuring.
            pts = vec![(1e-3, 1e-3), (1.0, 1.0)];
        }
        let bound = |f: fn(&(f64, f64)) -> f64, lo: bool| {
            let v = pts.iter().map(f);
            if lo {
                v.reduce(f64::min).unwrap_or(1.0)
            } else {
                v.reduce(f64::max).unwrap_or(1.0)
            }
        };
        let (t0, t1) = (bound(|p| p.0, true) / 1.3, bound(|p| p.0, false) * 1.3);
        let (e0, e1) = (bound(|p| p.1, true) / 1.3, bound(|p| p.1, false) * 1.3);
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (820, 560)).into_drawing_area();
            let plot_err = |e: &dyn std::fmt::Display| Error::Input(format!("plot: {e}"));
            root.fill(&WHITE).map_err(|e| plot_err(&e))?;
            let title = format!(
                "{} {}x{}: RMSE against render time (log-log){}",
                self.scene,
                self.width,
                self.height,
                if empty { ": no measurement has a positive error" } else { "" }
            );
            let mut chart = ChartBuilder::on(&root)
                .caption(title, ("sans-serif", 20))
                .margin(12)
                .x_label_area_size(44)
                .y_label_area_size(70)
                .build_cartesian_2d(
                    (t0..t1).log_scale().with_key_points(ticks(t0, t1)),
                    (e0..e1).log_scale().with_key_points(ticks(e0, e1)),
                )
                .map_err(|e| plot_err(&e))?;
            chart
                .configure_mesh()
                .x_desc("render time (s)")
                .y_desc("RMSE vs reference")
                .x_label_formatter(&|v| tick_label(*v))
                .y_label_formatter(&|v| tick_label(*v))
                .draw()
                .map_err(|e| plot_err(&e))?;
            let palette = [
                RGBColor(31, 119, 180),
                RGBColor(255, 127, 14),
                RGBColor(44, 160, 44),
                RGBColor(214, 39, 40),
                RGBColor(148, 103, 189),
                RGBColor(140, 86, 75),
                RGBColor(227, 119, 194),
                RGBColor(127, 127, 127),
            ];
            for (i, c) in curves.iter().enumerate() {
                let col = palette[i % palette.len()];
                let p = c.usable();
                chart
                    .draw_series(LineSeries::new(p.clone(), col.stroke_width(2)))
                    .map_err(|e| plot_err(&e))?
                    .label(c.label.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2)));
                chart.draw_series(p.iter().map(|&q| Circle::new(q, 3, col.filled()))).map_err(|e| plot_err(&e))?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| plot_err(&e))?;
            root.present().map_err(|e| plot_err(&e))?;
        }
        Ok(svg)
    }

    /// Writes `<scene>.csv`, `<scene>.md` and `<scene>.svg` into `dir` (created
    /// if missing), and `<scene>-reference.exr` if the run rendered its
    /// reference; returns their paths.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        std::fs::create_dir_all(dir)
            .map_err(|e| Error::Output { path: dir.to_path_buf(), message: format!("--out: {e}") })?;
        let stem: String = self
            .scene
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' })
            .collect();
        let svg = self.svg()?;
        let mut paths = Vec::new();
        for (ext, text) in [("csv", self.csv()), ("md", self.markdown()), ("svg", svg)] {
            let p = dir.join(format!("{stem}.{ext}"));
            crate::output::write_atomic(&p, text.as_bytes())?;
            paths.push(p);
        }
        if let Some(img) = &self.rendered_reference {
            let p = dir.join(format!("{stem}-reference.exr"));
            img.save(&p, 1.0)?;
            paths.push(p);
        }
        Ok(paths)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!((v.rr, v.adaptive), (Some(ROULETTE_AFTER_RAYS), Some(0.05)));
        assert_eq!(Variant::parse(&v.name()).unwrap(), v);
        let v = Variant::parse("adaptive:0.1+rr:3").unwrap();
        assert_eq!((v.rr, v.adaptive), (Some(3), Some(0.1)));
        assert_eq!(v.name(), "rr:3+adaptive:0.1");
        assert_eq!(Variant::parse(&v.name()).unwrap(), v);
        for bad in [
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
        ] {
            let e = Variant::parse(bad).unwrap_err().to_string();
            assert!(e.starts_with("--variants:"), "{bad}: {e}");
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
        let row = |variant: Variant, spp: u32, rays: u64, rmse: f64| Row {
            kernel: KernelKind::Simd,
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
        let report = Report {
            scene: "s".into(),
            width: 1,
            height: 1,
            max_depth: 1,
            seed: 0,
            reference: String::new(),
            repeat: 1,
            threads: 1,
            at_spp: Some(16),
            rendered_reference: None,
            rows,
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
    fn log_ticks() {
        assert_eq!(ticks(0.003, 0.06), vec![0.005, 0.01, 0.02, 0.05]);
        assert_eq!(ticks(0.9, 25.0), vec![1.0, 2.0, 5.0, 10.0, 20.0]);
        assert!(ticks(0.0, 1.0).is_empty());
        assert_eq!(ticks(0.003, 0.0045), vec![0.003, 0.0045]);
        let labels: Vec<String> = [0.005, 0.02, 1.0, 20.0].iter().map(|&v| tick_label(v)).collect();
        assert_eq!(labels, ["0.005", "0.02", "1", "20"]);
    }

    #[test]
    fn reference_seed_differs() {
        for s in [0u64, 1, 42, u64::MAX] {
            assert_ne!(reference_seed(s), s);
        }
    }

    #[test]
    fn bad_configs_name_their_flag() {
        let good = Config {
            settings: Settings { width: 8, height: 4, spp: 1, max_depth: 5, seed: 0 },
            kernels: vec![KernelKind::Simd],
            variants: vec![Variant::PLAIN],
            spp_list: vec![1, 2],
            reference: Reference::Spp(4),
            threads: Some(1),
            tile: 16,
            repeat: 1,
            adaptive_min: 16,
            at_spp: None,
        };
        good.validate().unwrap();
        type Break = Box<dyn Fn(&mut Config)>;
        let cases: Vec<(&str, Break)> = vec![
            ("--kernels", Box::new(|c| c.kernels.clear())),
            ("--kernels", Box::new(|c| c.kernels = vec![KernelKind::Simd, KernelKind::Simd])),
            ("--variants", Box::new(|c| c.variants.clear())),
            ("--variants", Box::new(|c| c.variants = vec![Variant::PLAIN, Variant::PLAIN])),
            ("--spp-list", Box::new(|c| c.spp_list.clear())),
            ("--spp-list", Box::new(|c| c.spp_list = vec![0, 1])),
            ("--spp-list", Box::new(|c| c.spp_list = vec![4, 2])),
            ("--reference-spp", Box::new(|c| c.reference = Reference::Spp(0))),
            ("--repeat", Box::new(|c| c.repeat = 0)),
            ("--at-spp", Box::new(|c| c.at_spp = Some(3))),
            (
                "--adaptive-min",
                Box::new(|c| {
                    c.variants = vec![Variant::parse("adaptive").unwrap()];
                    c.adaptive_min = 1;
                }),
            ),
        ];
        for (flag, f) in cases {
            let mut c = good.clone();
            f(&mut c);
            let e = c.validate().unwrap_err().to_string();
            assert!(e.starts_with(&format!("{flag}:")), "{flag}: {e}");
        }
    }
}
