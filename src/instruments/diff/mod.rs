//! `rtow diff A B`: how far image A is from image B (the reference), for a
//! renderer's port checked against rtow's images, or rtow's renders against
//! each other.
//!
//! - **Inputs** ([`input`]): PNG (8-bit, linearized with a gamma), EXR, PFM
//!   or a partial film (its mean), of the same size.
//! - **Metrics**, over every channel of every pixel of the linear images:
//!   MSE, relMSE (the mean of `(a - b)^2 / (b^2 + 0.01)`, B the reference:
//!   [`converge::error_metrics`](super::converge::error_metrics)'s
//!   definition), the largest `|a - b|` and where it is; and the mean and
//!   largest LDR-FLIP ([`flip`]) of the 8-bit images as a display shows
//!   them (a PNG's own bytes; a linear image encoded as rtow writes its PNGs
//!   with the gamma given), decoded with the sRGB curve.
//! - **Region z-tests** ([`regions`]) when both sides' noise is known: a side
//!   of two independent renders (A and A2), or a film with per-pixel moments.
//! - **Outputs**: a JSON report ([`Report`]) and a heatmap of the per-pixel
//!   FLIP through the magma ramp, written as one transaction
//!   ([`crate::output::Outputs`]).
//! - **Thresholds** ([`Limits`]): a run that exceeds one says which
//!   ([`Report::exceeded`]); the command line exits with [`EXIT_EXCEEDED`].

pub mod flip;
pub mod input;
pub mod regions;

pub use input::{decode_byte, Input, Kind};
pub use regions::{Regions, ZTest};

use crate::error::{Error, Result};
use crate::film::Image;
use crate::output::{check_extension, Outputs};
use crate::provenance::Provenance;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The exit status of a comparison that exceeded a threshold (1: an output
/// could not be written; 2: bad input).
pub const EXIT_EXCEEDED: u8 = 3;
/// The PNG gamma by default: rtow writes its PNGs with gamma 2, as the book does.
pub const DEFAULT_GAMMA: f32 = 2.0;
/// Regions by default: 6 x 6.
pub const DEFAULT_REGIONS: usize = 6;
/// The most regions across.
pub const MAX_REGIONS: usize = 256;
/// A region-channel fails the z-test above this `|z|` by default.
pub const DEFAULT_Z: f64 = 3.0;
/// The value of [`Report::schema`].
pub const SCHEMA: &str = "rtow-diff/1";

/// The figures a comparison may be held to; `None`: not checked.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Limits {
    pub max_mse: Option<f64>,
    pub max_rel_mse: Option<f64>,
    /// The mean FLIP.
    pub max_flip: Option<f64>,
    /// Region-channels with `|z|` above the z threshold.
    pub max_z_fails: Option<usize>,
}

/// A comparison: the files, how to read and measure them, and what to write.
#[derive(Clone, Debug)]
pub struct DiffSpec {
    pub a: PathBuf,
    /// The reference.
    pub b: PathBuf,
    /// A second, independent render of A (another seed): A's noise.
    pub a2: Option<PathBuf>,
    /// A second, independent render of B: B's noise.
    pub b2: Option<PathBuf>,
    /// The gamma PNG inputs were encoded with, and linear inputs are encoded with for FLIP.
    pub gamma: f32,
    /// FLIP's pixels per degree.
    pub ppd: f32,
    /// K: the z-tests split the image into K x K regions.
    pub regions: usize,
    /// A region-channel fails the z-test above this `|z|`.
    pub z: f64,
    pub limits: Limits,
    /// The JSON report.
    pub json: Option<PathBuf>,
    /// The heatmap (PNG) of the per-pixel FLIP.
    pub heatmap: Option<PathBuf>,
}

impl DiffSpec {
    /// A comparison of `a` against `b` with the defaults and no outputs.
    pub fn new(a: &Path, b: &Path) -> DiffSpec {
        DiffSpec {
            a: a.to_path_buf(),
            b: b.to_path_buf(),
            a2: None,
            b2: None,
            gamma: DEFAULT_GAMMA,
            ppd: flip::DEFAULT_PPD,
            regions: DEFAULT_REGIONS,
            z: DEFAULT_Z,
            limits: Limits::default(),
            json: None,
            heatmap: None,
        }
    }

    /// The values' own rules (exit status 2), named by field.
    fn check(&self) -> Result<()> {
        let positive = |field: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(field, format!("must be a finite number > 0, got {v}")))
            }
        };
        positive("gamma", self.gamma as f64)?;
        positive("ppd", self.ppd as f64)?;
        positive("z", self.z)?;
        if !(1..=MAX_REGIONS).contains(&self.regions) {
            return Err(Error::invalid("regions", format!("must be from 1 to {MAX_REGIONS}, got {}", self.regions)));
        }
        let l = &self.limits;
        for (field, v) in [("max_mse", l.max_mse), ("max_rel_mse", l.max_rel_mse), ("max_flip", l.max_flip)] {
            if let Some(v) = v.filter(|v| !(v.is_finite() && *v >= 0.0)) {
                return Err(Error::invalid(field, format!("must be a finite number >= 0, got {v}")));
            }
        }
        if let Some(h) = &self.heatmap {
            check_extension(h, &["png"], "heatmap")?;
        }
        Ok(())
    }
}

/// Where a side's noise comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Noise {
    /// Two independent renders (the second given apart).
    TwoRenders,
    /// A partial film's per-pixel moments.
    Moments,
}

/// One side as the report names it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Side {
    pub file: String,
    pub kind: Kind,
    /// The second render's file, if one was given.
    pub second: Option<String>,
    /// Where its noise comes from (`null`: unknown).
    pub noise: Option<Noise>,
}

/// The largest absolute difference.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MaxAbs {
    pub value: f64,
    pub x: u32,
    pub y: u32,
    /// 0, 1, 2: red, green, blue.
    pub channel: usize,
}

/// The FLIP figures.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FlipFigures {
    pub mean: f64,
    pub max: f64,
    /// Where the largest is.
    pub x: u32,
    pub y: u32,
    pub ppd: f32,
}

/// A threshold and the figure it was held to.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Check {
    /// The limit's field ([`Limits`]): `max_mse`, `max_rel_mse`, `max_flip`, `max_z_fails`.
    pub limit: &'static str,
    /// What is measured, for a person: `MSE`, `relMSE`, `mean FLIP`, `region-channels with |z| > 3`.
    pub what: String,
    pub value: f64,
    pub max: f64,
    pub passed: bool,
}

/// Everything a comparison found (the JSON report; docs/usage.md lists it).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// [`SCHEMA`].
    pub schema: &'static str,
    pub a: Side,
    /// The reference.
    pub b: Side,
    pub width: u32,
    pub height: u32,
    pub gamma: f32,
    pub mse: f64,
    pub rmse: f64,
    /// The mean of `(a - b)^2 / (b^2 + 0.01)`.
    pub rel_mse: f64,
    pub max_abs: MaxAbs,
    pub flip: FlipFigures,
    /// The region z-tests (`null`: a side's noise is unknown; `z_test_skipped` says which).
    pub z_test: Option<ZTest>,
    pub z_test_skipped: Option<String>,
    /// A side of two renders, render 1 against render 2: the root mean square
    /// of `(mean1 - mean2) / (2 s)` over its noisy region-channels (about 1
    /// when the noise estimate is right) and their number.
    pub noise_check_a: Option<(f64, usize)>,
    pub noise_check_b: Option<(f64, usize)>,
    pub checks: Vec<Check>,
    /// Whether every threshold held.
    pub passed: bool,
    pub provenance: Provenance,
}

/// The two sides read: each input and its second render.
struct Sides {
    a: Input,
    b: Input,
    a2: Option<Input>,
    b2: Option<Input>,
}

impl Sides {
    /// Reads every input and checks that their sizes match, naming them.
    fn read(spec: &DiffSpec) -> Result<Sides> {
        let read = |p: &Option<PathBuf>| p.as_deref().map(|p| Input::read(p, spec.gamma)).transpose();
        let s = Sides {
            a: Input::read(&spec.a, spec.gamma)?,
            b: Input::read(&spec.b, spec.gamma)?,
            a2: read(&spec.a2)?,
            b2: read(&spec.b2)?,
        };
        let a = &s.a;
        for other in [Some(&s.b), s.a2.as_ref(), s.b2.as_ref()].into_iter().flatten() {
            if other.size() != a.size() {
                let (w, h) = a.size();
                let (ow, oh) = other.size();
                return Err(Error::Input(format!(
                    "sizes differ: {} is {w}x{h}, {} is {ow}x{oh}",
                    a.path.display(),
                    other.path.display()
                )));
            }
        }
        for (one, two) in [(&s.a, &s.a2), (&s.b, &s.b2)] {
            if two.as_ref().is_some_and(|t| t.image == one.image) {
                return Err(Error::Input(format!(
                    "{} and {} are the same image: the second render of a side needs another seed",
                    one.path.display(),
                    two.as_ref().map_or(String::new(), |t| t.path.display().to_string())
                )));
            }
        }
        Ok(s)
    }

    fn noise(one: &Input, two: Option<&Input>) -> Option<Noise> {
        match two {
            Some(_) => Some(Noise::TwoRenders),
            None if one.has_moments() => Some(Noise::Moments),
            None => None,
        }
    }

    fn side(one: &Input, two: Option<&Input>) -> Side {
        Side {
            file: one.path.display().to_string(),
            kind: one.kind,
            second: two.map(|t| t.path.display().to_string()),
            noise: Sides::noise(one, two),
        }
    }

    /// A side's regions, if its noise is known.
    fn regions(one: &Input, two: Option<&Input>, k: usize) -> Option<Regions> {
        let (w, h) = (one.image.width as usize, one.image.height as usize);
        let px = |img: &Image, i: usize| img.data[i].map(|v| v as f64);
        match two {
            Some(t) => Some(Regions::two_renders(k, w, h, |i| px(&one.image, i), |i| px(&t.image, i))),
            None if one.has_moments() => Some(Regions::new(k, w, h, |i| {
                let (m, v) = one.moments(i);
                (m, v, None)
            })),
            None => None,
        }
    }
}

/// Why the z-tests cannot run (`None`: they can).
fn z_test_skipped(s: &Sides) -> Option<String> {
    let unknown = |one: &Input, two: Option<&Input>, name: &str, flag: &str| {
        Sides::noise(one, two).is_none().then(|| {
            format!("{name}'s noise is unknown: give a film with moments (rendered with --adaptive) or {flag}")
        })
    };
    let a = unknown(&s.a, s.a2.as_ref(), "A", "a second render of it (--a2)");
    let b = unknown(&s.b, s.b2.as_ref(), "B", "a second render of it (--b2)");
    match (a, b) {
        (Some(a), Some(b)) => Some(format!("{a}; {b}")),
        (a, b) => a.or(b),
    }
}

/// Compares `spec.a` with `spec.b` and writes the outputs `spec` names:
/// every input is read and checked first (exit status 2), then every output
/// (2 or 1), then the figures are computed and the outputs written together.
pub fn run(spec: &DiffSpec) -> Result<(Report, Vec<f32>)> {
    spec.check()?;
    let sides = Sides::read(spec)?;
    let (w, h) = sides.a.size();
    let skipped = z_test_skipped(&sides);
    if let (Some(why), Some(_)) = (&skipped, spec.limits.max_z_fails) {
        return Err(Error::invalid("max_z_fails", format!("needs the z-tests, but {why}")));
    }
    if skipped.is_none() && spec.regions > w.min(h) as usize {
        return Err(Error::invalid(
            "regions",
            format!("{} regions across a {w}x{h} image leave some empty", spec.regions),
        ));
    }
    let mut outputs = Outputs::new();
    for p in [Some(&spec.a), Some(&spec.b), spec.a2.as_ref(), spec.b2.as_ref()].into_iter().flatten() {
        outputs.input(p, "input");
    }
    let json = spec.json.as_deref().map(|p| outputs.add(p, "json")).transpose()?;
    let heat = spec.heatmap.as_deref().map(|p| outputs.add(p, "heatmap")).transpose()?;
    let (report, map) = compare(&sides, spec, skipped);
    if let Some(id) = heat {
        outputs.stage(id, &heatmap_png(&map, w, h))?;
    }
    if let Some(id) = json {
        let text = serde_json::to_string_pretty(&report).expect("a report serializes") + "\n";
        outputs.stage(id, text.as_bytes())?;
    }
    outputs.commit()?;
    Ok((report, map))
}

/// The figures of a comparison (inputs read and checked), and the per-pixel FLIP.
fn compare(s: &Sides, spec: &DiffSpec, skipped: Option<String>) -> (Report, Vec<f32>) {
    let (w, h) = s.a.size();
    let m = super::converge::error_metrics(&s.a.image, &s.b.image);
    let (map, flip) = flip_of(&s.a, &s.b, spec.ppd);
    let z_test = match &skipped {
        Some(_) => None,
        None => {
            let ra = Sides::regions(&s.a, s.a2.as_ref(), spec.regions).expect("A's noise is known");
            let rb = Sides::regions(&s.b, s.b2.as_ref(), spec.regions).expect("B's noise is known");
            Some((ZTest::new(&ra, &rb, spec.z), ra.self_check(), rb.self_check()))
        }
    };
    let mut report = Report {
        schema: SCHEMA,
        a: Sides::side(&s.a, s.a2.as_ref()),
        b: Sides::side(&s.b, s.b2.as_ref()),
        width: w,
        height: h,
        gamma: spec.gamma,
        mse: m.mse,
        rmse: m.rmse,
        rel_mse: m.relmse,
        max_abs: max_abs(&s.a.image, &s.b.image),
        flip,
        noise_check_a: z_test.as_ref().and_then(|z| z.1),
        noise_check_b: z_test.as_ref().and_then(|z| z.2),
        z_test: z_test.map(|z| z.0),
        z_test_skipped: skipped,
        checks: Vec::new(),
        passed: true,
        provenance: Provenance::collect(),
    };
    report.checks = checks(&report, &spec.limits);
    report.passed = report.checks.iter().all(|c| c.passed);
    (report, map)
}

/// The largest `|a - b|` (the first, in reading order, of equal ones).
fn max_abs(a: &Image, b: &Image) -> MaxAbs {
    let mut best = MaxAbs { value: 0.0, x: 0, y: 0, channel: 0 };
    for (i, (p, q)) in a.data.iter().zip(&b.data).enumerate() {
        for c in 0..3 {
            let d = (p[c] as f64 - q[c] as f64).abs();
            if d > best.value {
                best = MaxAbs { value: d, x: i as u32 % a.width, y: i as u32 / a.width, channel: c };
            }
        }
    }
    best
}

/// LDR-FLIP of A's display image against B's (the reference), per pixel, and its figures.
fn flip_of(a: &Input, b: &Input, ppd: f32) -> (Vec<f32>, FlipFigures) {
    let lut: Vec<f32> = (0..=255u8).map(|v| flip::srgb_to_linear(v as f32 / 255.0)).collect();
    let linear = |bytes: &[u8]| -> Vec<[f32; 3]> {
        bytes.chunks_exact(3).map(|p| [lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]]).collect()
    };
    let (w, h) = a.size();
    let map = flip::ldr_flip(&linear(&b.display), &linear(&a.display), w as usize, h as usize, ppd);
    let (i, max) = map.iter().enumerate().fold((0, 0.0f32), |m, (i, &v)| if v > m.1 { (i, v) } else { m });
    let mean = map.iter().map(|&v| v as f64).sum::<f64>() / map.len() as f64;
    let figures = FlipFigures { mean, max: max as f64, x: i as u32 % w, y: i as u32 / w, ppd };
    (map, figures)
}

/// Every limit given, held to its figure.
fn checks(r: &Report, l: &Limits) -> Vec<Check> {
    let mut out = Vec::new();
    let mut check = |limit: &'static str, what: String, value: f64, max: Option<f64>| {
        if let Some(max) = max {
            out.push(Check { limit, what, value, max, passed: value <= max });
        }
    };
    check("max_mse", "MSE".into(), r.mse, l.max_mse);
    check("max_rel_mse", "relMSE".into(), r.rel_mse, l.max_rel_mse);
    check("max_flip", "mean FLIP".into(), r.flip.mean, l.max_flip);
    if let Some(z) = &r.z_test {
        let what = format!("region-channels with |z| > {}", z.threshold);
        check("max_z_fails", what, z.over as f64, l.max_z_fails.map(|n| n as f64));
    }
    out
}

impl Report {
    /// The thresholds exceeded.
    pub fn exceeded(&self) -> impl Iterator<Item = &Check> {
        self.checks.iter().filter(|c| !c.passed)
    }

    /// The summary, a line per figure, for a person.
    pub fn summary(&self) -> Vec<String> {
        let ch = ["red", "green", "blue"];
        let side = |name: &str, s: &Side| {
            let noise = match s.noise {
                Some(Noise::TwoRenders) => {
                    format!(", noise from a second render, {}", s.second.as_deref().unwrap_or(""))
                }
                Some(Noise::Moments) => ", noise from its moments".into(),
                None => String::new(),
            };
            format!("{name}: {} ({}{noise})", s.file, s.kind.name())
        };
        let mut out = vec![
            side("A", &self.a),
            side("B (reference)", &self.b),
            format!("size {}x{}, PNG gamma {}", self.width, self.height, self.gamma),
            format!("MSE {:.6e} (RMSE {:.6e}), relMSE {:.6e}", self.mse, self.rmse, self.rel_mse),
            format!(
                "max |A - B| {:.6e} at pixel ({}, {}), {}",
                self.max_abs.value, self.max_abs.x, self.max_abs.y, ch[self.max_abs.channel]
            ),
            format!(
                "FLIP mean {:.6}, max {:.6} at pixel ({}, {}) (LDR-FLIP, {:.2} pixels per degree)",
                self.flip.mean, self.flip.max, self.flip.x, self.flip.y, self.flip.ppd
            ),
        ];
        match (&self.z_test, &self.z_test_skipped) {
            (Some(z), _) => {
                let w = &z.worst;
                out.push(format!(
                    "z-test: {k}x{k} regions, {} region-channels: {} with |z| > {}, rms z {:.3}, worst z {:+.2} in \
                     region ({}, {}) {}",
                    z.count,
                    z.over,
                    z.threshold,
                    z.rms,
                    w.z,
                    w.row,
                    w.col,
                    ch[w.channel],
                    k = z.regions
                ));
            }
            (None, why) => out.push(format!("z-test: not run: {}", why.as_deref().unwrap_or("no noise"))),
        }
        for (name, c) in [("A", self.noise_check_a), ("B", self.noise_check_b)] {
            if let Some((rms, n)) = c {
                out.push(format!(
                    "noise check, {name} render 1 against render 2: rms z {rms:.3} ({n} region-channels)"
                ));
            }
        }
        for c in &self.checks {
            let verdict = if c.passed { "within" } else { "above" };
            out.push(format!("{}: {} is {verdict} the limit {}", c.what, c.value, c.max));
        }
        out
    }
}

/// The magma ramp (matplotlib's, sampled every 16th of its 256 entries, and
/// its last), as 8-bit sRGB.
const MAGMA: [[u8; 3]; 17] = [
    [0, 0, 4],
    [10, 8, 34],
    [29, 17, 71],
    [54, 16, 107],
    [81, 18, 124],
    [106, 28, 129],
    [131, 38, 129],
    [156, 46, 127],
    [183, 55, 121],
    [208, 65, 111],
    [231, 82, 99],
    [245, 107, 92],
    [252, 137, 97],
    [254, 167, 114],
    [254, 196, 136],
    [253, 226, 163],
    [252, 253, 191],
];

/// A value in [0, 1] through the magma ramp (its entry `j` at `16 j / 255`, the last at 1), linearly.
pub fn magma(v: f32) -> [u8; 3] {
    let at = v.clamp(0.0, 1.0) * 255.0;
    let j = ((at / 16.0) as usize).min(15);
    let (lo, hi) = (16.0 * j as f32, if j == 15 { 255.0 } else { 16.0 * (j + 1) as f32 });
    let t = (at - lo) / (hi - lo);
    std::array::from_fn(|c| (MAGMA[j][c] as f32 + t * (MAGMA[j + 1][c] as f32 - MAGMA[j][c] as f32)).round() as u8)
}

/// The per-pixel FLIP `map` (`w` x `h`) through [`magma`], as a PNG.
pub fn heatmap_png(map: &[f32], w: u32, h: u32) -> Vec<u8> {
    let bytes: Vec<u8> = map.iter().flat_map(|&v| magma(v)).collect();
    let img = image::RgbImage::from_raw(w, h, bytes).expect("size matches");
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png).expect("PNG encodes in memory");
    out
}
