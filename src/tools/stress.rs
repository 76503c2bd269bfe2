//! `rtow stress`: numerical stress tests of the intersection, the ray offset and
//! the film, for both kernels, against an f64 oracle.
//!
//! Three parts, each run with the scalar functions (`closest_hit_scalar`,
//! `surface::<f32>`, ...) and with the 8-wide ones (`closest_hit_x8`,
//! `surface::<f32x8>`, ...):
//!
//! 1. **Intersection sweeps.** Rays against one sphere, radius and distance over
//!    1e-4 .. 1e6 (ratio 1e-6 .. 1), grazing rays, origins on the surface,
//!    inside and at the centre, negative radii. Every answer is judged by
//!    [`Truth`], the same test in f64 on the same f32 inputs, with the error
//!    bounds of the f32 kernel (see `geometry/intersect.rs` for their derivation):
//!    a decision inside the rounding band of a bound is not an error.
//! 2. **Self-intersection sweeps.** Hit points on spheres of radius 10^U(-4,4)
//!    whose centre (or, for half of them, the hit point) lies 10^U(-4,6) from the
//!    origin, 1000 rays scattered from each (every material's scatter, plus
//!    synthetic grazing directions), each spawned with [`spawn`] and intersected
//!    again: a ray leaving the sphere that hits it again is a re-hit; a ray
//!    entering it that misses the far wall is a wrong decision. Hit points where
//!    the offset exceeds the radius (`|p|_inf > ~1e6 |r|`, below f32 resolution)
//!    are reported apart: there entering rays can be pushed through the sphere.
//! 3. **Scenes.** The stress presets, path traced by an instrumented copy of each
//!    kernel's loop (proved faithful: its image must equal `render()`'s bit for
//!    bit), every ray judged by the oracle against every sphere, every bounce
//!    checked for re-hits; plus image comparisons (scaled scenes against the
//!    unscaled one, the horizon against its analytic colour, the far camera
//!    against the same rays started near the scene) and the NaN count of every
//!    preset.
//!
//! The textbook test (`b*b - 4ac`, `t_min = 0.001`, no re-projection, no offset)
//! is implemented here only, as a reference for the README; it never gates.

use crate::film::{Image, TileFilm};
use crate::geometry::{closest_hit_scalar, closest_hit_x8, spawn, sphere_disc, surface, Spheres, Surface, MISS};
use crate::kernel::{sky, KernelKind};
use crate::material::{dielectric, lambertian, metal};
use crate::plan::{AccelChoice, Prepared, Settings};
use crate::real::Real;
use crate::sampling::{mix64, path_state, ScalarStream, Stream, Xoshiro128PlusX8};
use crate::scene::{self, Kind, Material, Mode, Scene, Sphere};
use crate::vec3::V3;
use crate::{render, Error, RenderOptions, Result};
use glam::DVec3;
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::fmt::Write as _;
use std::time::Instant;
use wide::{f32x8, u32x8};

/// Unit roundoff of f32 (round to nearest): `u = 2^-24`.
pub const U: f64 = 1.0 / 16_777_216.0;

/// Every first-order bound below is multiplied by this, for the higher-order
/// terms the first-order analysis drops (each is O(u) relative to its term).
const SLACK: f64 = 1.01;

/// A direction within this of tangent (|cos| to the normal) leaves the surface
/// on a side decided by rounding: the spawn side test `dir . n >= 0` is computed
/// with an error below `3u + (|n| - 1) + (|dir| - 1) <= 12u`.
pub const SIDE_EPS: f64 = 16.0 * U;

/// The textbook's `t_min`.
pub const TEXTBOOK_T_MIN: f32 = 0.001;

/// Largest |z| (difference of means over its standard error) an image
/// comparison may show. Under the null hypothesis (same expected image) a
/// |z| above 5 has a probability below 1e-5 per statistic.
pub const Z_LIMIT: f64 = 5.0;

// ---------------------------------------------------------------------------
// Small helpers.

fn v64(v: V3<f32>) -> DVec3 {
    DVec3::new(v.x as f64, v.y as f64, v.z as f64)
}

fn v32(v: DVec3) -> V3<f32> {
    V3::new(v.x as f32, v.y as f32, v.z as f32)
}

/// A unit f64 direction as the renderer would hold it: rounded, then
/// normalized in f32.
fn dir32(v: DVec3) -> V3<f32> {
    v32(v.normalize()).normalize()
}

fn finite3(v: V3<f32>) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}

fn splat8(v: V3<f32>) -> V3<f32x8> {
    V3::new(f32x8::splat(v.x), f32x8::splat(v.y), f32x8::splat(v.z))
}

fn pack8(v: &[V3<f32>; 8]) -> V3<f32x8> {
    V3::new(f32x8::new(v.map(|a| a.x)), f32x8::new(v.map(|a| a.y)), f32x8::new(v.map(|a| a.z)))
}

fn lane(v: V3<f32x8>, k: usize) -> V3<f32> {
    V3::new(v.x.to_array()[k], v.y.to_array()[k], v.z.to_array()[k])
}

fn mask8(b: [bool; 8]) -> f32x8 {
    f32x8::new(b.map(|x| if x { f32::from_bits(u32::MAX) } else { 0.0 }))
}

fn umask8(b: [bool; 8]) -> u32x8 {
    u32x8::new(b.map(|x| if x { u32::MAX } else { 0 }))
}

fn stream8(seed: u64, pixel: [u64; 8], sample: [u64; 8]) -> Xoshiro128PlusX8 {
    let st: [[u32; 4]; 8] = std::array::from_fn(|k| path_state(seed, pixel[k], sample[k]));
    Xoshiro128PlusX8 { s: std::array::from_fn(|w| u32x8::new(std::array::from_fn(|k| st[k][w]))) }
}

/// FNV-1a, to compare long streams of results between kernels.
#[derive(Clone, Copy)]
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn u32(&mut self, x: u32) {
        for b in x.to_le_bytes() {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    fn f(&mut self, x: f32) {
        self.u32(x.to_bits())
    }
    fn v(&mut self, v: V3<f32>) {
        self.f(v.x);
        self.f(v.y);
        self.f(v.z);
    }
}

/// The generator of test configurations (f64, independent of the renderer's streams).
struct Gen(Xoshiro256PlusPlus);

impl Gen {
    fn new(seed: u64, stream: u64) -> Self {
        Gen(Xoshiro256PlusPlus::seed_from_u64(mix64(seed ^ stream.wrapping_mul(0x9E37_79B9_7F4A_7C15))))
    }
    /// Uniform in [0, 1).
    fn unif(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.unif()
    }
    /// `10^U(a, b)`.
    fn exp10(&mut self, a: f64, b: f64) -> f64 {
        10f64.powf(self.range(a, b))
    }
    fn unit(&mut self) -> DVec3 {
        let z = 1.0 - 2.0 * self.unif();
        let rr = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f64::consts::TAU * self.unif();
        DVec3::new(rr * phi.cos(), rr * phi.sin(), z)
    }
    /// A random unit vector perpendicular to the unit vector `n`.
    fn perp(&mut self, n: DVec3) -> DVec3 {
        let v = self.unit();
        let p = v - n * v.dot(n);
        if p.length() > 1e-3 {
            p.normalize()
        } else {
            n.any_orthonormal_vector()
        }
    }
}

// ---------------------------------------------------------------------------
// The oracle.

/// A ray as f64, exactly the f32 values the kernel was given.
#[derive(Clone, Copy, Debug)]
pub struct RayF64 {
    pub o: DVec3,
    /// The direction as given (|d| = 1 + eta, not exactly 1).
    pub d: DVec3,
    pub d_len: f64,
    /// Unit direction.
    pub dh: DVec3,
    /// `| |d| - 1 |`.
    pub eta: f64,
}

impl RayF64 {
    pub fn new(o: V3<f32>, d: V3<f32>) -> Self {
        let (o, d) = (v64(o), v64(d));
        let d_len = d.length();
        RayF64 { o, d, d_len, dh: d / d_len, eta: (d_len - 1.0).abs() }
    }

    /// The point at parameter `t` (in units of the f32 direction, as the kernel's `t`).
    pub fn at(&self, t: f64) -> DVec3 {
        self.o + self.d * t
    }
}

/// How a kernel's answer compares with the oracle's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Right,
    /// Inside the rounding band of a bound: any answer is acceptable.
    InBand,
    Wrong,
}

/// What exact (f64) arithmetic says about one ray (given as f32) and one sphere,
/// with the error bounds of the f32 kernel on that ray.
///
/// Notation (as in `geometry/intersect.rs`): `f = o - c`, `b = f . d^`,
/// `h = |f - b d^|` (distance of the centre from the ray's line),
/// `disc = r^2 - h^2`, `cc = |f|^2 - r^2`, `eta = | |d| - 1 |`.
#[derive(Clone, Copy, Debug)]
pub struct Truth {
    /// |radius| and the signed radius.
    pub r: f64,
    pub r_signed: f64,
    pub f_len: f64,
    pub eta: f64,
    pub b: f64,
    pub h: f64,
    pub disc: f64,
    /// Bound on |disc computed by the kernel - disc|.
    pub e_disc: f64,
    pub cc: f64,
    /// Bound on |cc computed by the kernel - cc| (the sign of cc says inside/outside).
    pub e_c: f64,
    /// Both roots in the kernel's units of `t` (ascending), when `disc >= 0`.
    pub roots: Option<[f64; 2]>,
    /// The root at the origin when the origin is within `e_c` of the surface:
    /// the kernel may return it or skip it.
    pub optional: Option<usize>,
    /// The first positive root that is not optional: the answer the kernel owes.
    pub required: Option<f64>,
}

impl Truth {
    pub fn new(ray: &RayF64, c: DVec3, r_signed: f64) -> Truth {
        let r = r_signed.abs();
        let f = ray.o - c;
        let fl = f.length();
        let b = f.dot(ray.dh);
        let l = f - ray.dh * b;
        let h = l.length();
        let disc = (r - h) * (r + h);
        let eta = ray.eta;
        // |l computed - l|: f rounded (u|f|), b's dot (3u|f|, along d), the product
        // b d and the subtraction (u|f| + u|l|), and |d| != 1 (2 eta |f|, along d).
        let delta = (5.0 * U + 2.0 * eta + eta * eta) * fl + U * h;
        let e_disc = SLACK
            * (U * r * r
                + 3.0 * U * (h + delta) * (h + delta)
                + 4.0 * U * h * fl
                + 2.0 * U * h * h
                + delta * delta
                + U * disc.abs());
        let cc = (fl - r) * (fl + r);
        let e_c = SLACK * (5.0 * U * fl * fl + U * r * r + U * cc.abs());
        let mut tr = Truth {
            r,
            r_signed,
            f_len: fl,
            eta,
            b,
            h,
            disc,
            e_disc,
            cc,
            e_c,
            roots: None,
            optional: None,
            required: None,
        };
        if disc >= 0.0 {
            let s = disc.sqrt();
            let q = -(b + s.copysign(b));
            let (t1, t2) = if q != 0.0 { (cc / q, q) } else { (0.0, 0.0) };
            let roots = [t1.min(t2) / ray.d_len, t1.max(t2) / ray.d_len];
            tr.roots = Some(roots);
            if cc.abs() <= e_c {
                tr.optional = Some(if roots[0].abs() <= roots[1].abs() { 0 } else { 1 });
            }
            tr.required = (0..2).filter(|&i| Some(i) != tr.optional && roots[i] > 0.0).map(|i| roots[i]).next();
        }
        tr
    }

    /// The ray passes within the rounding band of tangency: the kernel's
    /// hit/miss decision may go either way.
    pub fn grazing(&self) -> bool {
        self.disc.abs() <= self.e_disc
    }

    /// The index of the root nearest to `t`.
    pub fn nearest(&self, t: f64) -> Option<usize> {
        self.roots.map(|r| if (r[0] - t).abs() <= (r[1] - t).abs() { 0 } else { 1 })
    }

    /// Judges a kernel's answer (hit at `t`, or miss) against this sphere alone.
    pub fn judge(&self, hit: bool, t: f64) -> Verdict {
        if self.grazing() {
            return Verdict::InBand;
        }
        if !hit {
            return if self.required.is_some() { Verdict::Wrong } else { Verdict::Right };
        }
        match (self.roots, self.nearest(t)) {
            (Some(roots), Some(i)) if Some(i) == self.optional || Some(roots[i]) == self.required => Verdict::Right,
            _ => Verdict::Wrong,
        }
    }

    /// Bound on the distance from the sphere of the point `o + t d` where the
    /// kernel reports a hit at `t` (see `geometry/intersect.rs`, "Error bounds").
    pub fn dist_bound(&self, t: f64) -> f64 {
        let (fl, r, h, eta) = (self.f_len, self.r, self.h, self.eta);
        let s = self.disc.max(0.0).sqrt();
        // The exact root of the computed quadratic, then the origin's rounding.
        let on_perturbed = (8.0 * U + 4.0 * eta) * fl + (7.0 * U + 2.0 * eta) * r + U * fl;
        // Rounding of the root returned as q (sqrt, add).
        let far_dt = U * r + U * (fl + r);
        // Returned as c / q: the constant term's inconsistency over |q|, and the division.
        let c_incons = (9.0 * U + 6.0 * eta) * fl * fl
            + 2.0 * U * r * r
            + U * self.cc.abs()
            + 2.0 * U * h * fl
            + 5.0 * U * h * h
            + U * self.disc.abs();
        let q_low = (self.b.abs() - (5.0 * U + 2.0 * eta) * fl).max(0.0)
            + (s - self.e_disc / (s + self.e_disc.sqrt())).max(0.0);
        let near_dt = if q_low > 0.0 { c_incons / q_low + 3.0 * U * t.abs() } else { f64::INFINITY };
        SLACK * (on_perturbed + far_dt.max(near_dt))
    }

    /// How far along the ray a root found at `t` may lie from the true one.
    pub fn t_tol(&self, t: f64) -> f64 {
        let s = self.disc.max(0.0).sqrt();
        let se = self.e_disc.sqrt();
        (self.dist_bound(t) * self.r + self.e_disc) / s.max(se).max(f64::MIN_POSITIVE)
    }

    /// The front/back face at root `i`, or `None` when the ray is too close to
    /// tangent there for the kernel's normal (from its rounded hit point) to decide.
    pub fn front_at(&self, ray: &RayF64, c: DVec3, i: usize) -> Option<bool> {
        let t = self.roots?[i];
        let p = ray.at(t);
        let cos = ray.dh.dot(p - c) / self.r;
        let band = (self.t_tol(t) + 2.0 * U * (t.abs() + p.length())) / self.r + SIDE_EPS;
        if cos.abs() <= band {
            None
        } else {
            Some(cos * self.r_signed.signum() < 0.0)
        }
    }
}

/// The textbook test (the book's first `hit_sphere`): `b*b - 4ac` in f32, the
/// first root above `t_min`. For comparison only; never used by the kernels.
pub fn textbook_hit(o: V3<f32>, d: V3<f32>, c: V3<f32>, r: f32, t_min: f32) -> Option<f32> {
    let oc = o - c;
    let a = d.dot(d);
    let b = 2.0 * oc.dot(d);
    let cc = oc.dot(oc) - r * r;
    let disc = b * b - 4.0 * a * cc;
    if !(disc >= 0.0) {
        return None;
    }
    let sq = disc.sqrt();
    [(-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a)].into_iter().find(|t| *t > t_min && t.is_finite())
}

// ---------------------------------------------------------------------------
// Tallies, rows, the report.

/// What one case measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tally {
    pub rays: u64,
    /// Wrong decisions outside the rounding band (for spawned rays: rays that
    /// entered the sphere they left and did not reach its far wall).
    pub wrong: u64,
    /// Decisions inside the rounding band (not errors).
    pub in_band: u64,
    /// Wrong front/back face outside the band.
    pub faces: u64,
    /// Spawned rays that left their sphere and hit it again.
    pub rehits: u64,
    /// Non-finite values met (t, hit points, directions, samples).
    pub nan: u64,
    /// Largest distance of a hit point from its sphere, over |r| (decisions outside the band).
    pub max_err_r: f64,
    /// The same for hits inside the rounding band (near tangency).
    pub max_err_r_band: f64,
    /// Largest distance of a hit point from its sphere, over its error bound (must be <= 1).
    pub max_err_bound: f64,
}

impl Tally {
    fn err(&mut self, dist: f64, r: f64, bound: Option<f64>, in_band: bool) {
        if in_band {
            self.max_err_r_band = self.max_err_r_band.max(dist / r);
        } else {
            self.max_err_r = self.max_err_r.max(dist / r);
        }
        if let Some(b) = bound {
            self.max_err_bound = self.max_err_bound.max(dist / b);
        }
    }

    fn clean(&self, gate: Gate) -> bool {
        let core = self.faces == 0 && self.rehits == 0 && self.nan == 0 && self.max_err_bound <= 1.0;
        match gate {
            Gate::Full => core && self.wrong == 0,
            Gate::NoLeaks => core,
            Gate::Reference => true,
        }
    }
}

/// What a row must show to pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Gate {
    /// Everything: no wrong decision, face, re-hit or NaN, every error within its bound.
    Full,
    /// The same except `wrong` (hit points below f32 resolution, where the
    /// offset exceeds the radius and an entering ray may be pushed through the
    /// sphere: see `geometry::surface`).
    NoLeaks,
    /// The textbook reference: shown, never gating.
    Reference,
}

/// One line of the table.
#[derive(Clone, Debug)]
pub struct Row {
    pub section: &'static str,
    pub case: String,
    pub kernel: &'static str,
    pub tally: Tally,
    pub gate: Gate,
}

impl Row {
    pub fn ok(&self) -> bool {
        self.tally.clean(self.gate)
    }
}

/// A pass/fail check that is not a row of counts.
#[derive(Clone, Debug)]
pub struct Check {
    pub name: String,
    pub value: f64,
    pub limit: f64,
    pub ok: bool,
    pub note: String,
}

impl Check {
    fn at_most(name: impl Into<String>, value: f64, limit: f64, note: impl Into<String>) -> Self {
        Check { name: name.into(), value, limit, ok: value <= limit, note: note.into() }
    }
}

/// The outside sweep by decade of `r / |o - c|`: robust (scalar) and textbook.
#[derive(Clone, Debug, Default)]
pub struct Decade {
    pub ratio_exp: i32,
    pub robust: Tally,
    pub textbook: Tally,
}

/// Re-hits and leaks with another offset rule (scalar, every scatter).
#[derive(Clone, Debug)]
pub struct OffsetScan {
    pub rule: String,
    pub rays: u64,
    pub rehits: u64,
    /// Entering rays that did not reach the far wall.
    pub wrong: u64,
}

#[derive(Clone, Debug)]
pub struct Report {
    pub quick: bool,
    pub seed: u64,
    pub isa: &'static str,
    pub rows: Vec<Row>,
    pub checks: Vec<Check>,
    pub decades: Vec<Decade>,
    pub offset_scan: Vec<OffsetScan>,
    pub seconds: f64,
}

impl Report {
    pub fn passed(&self) -> bool {
        self.rows.iter().all(Row::ok) && self.checks.iter().all(|c| c.ok)
    }

    fn failures(&self) -> Vec<String> {
        let mut v: Vec<String> =
            self.rows.iter().filter(|r| !r.ok()).map(|r| format!("{} [{}]", r.case, r.kernel)).collect();
        v.extend(self.checks.iter().filter(|c| !c.ok).map(|c| c.name.clone()));
        v
    }

    /// The tables `rtow stress` prints.
    pub fn table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "rtow stress{}: seed {}, SIMD {}, {:.1} s",
            if self.quick { " --quick" } else { "" },
            self.seed,
            self.isa,
            self.seconds
        );
        let _ = writeln!(
            s,
            "wrong = wrong decisions outside the rounding band (spawned rays: entering rays that did not reach\n\
             the far wall); band = decisions inside it (not errors); faces = wrong front/back; err/r = largest\n\
             distance of a hit point from its sphere over |r|, outside / inside the band; err/bound = the same\n\
             over its error bound (must be <= 1); re-hits = spawned rays leaving a sphere that hit it again;\n\
             NaN = non-finite values met. Below f32 resolution: hit points where the offset exceeds |r|\n\
             (|p|_inf > ~1e6 |r|), where entering rays may be pushed through the sphere: wrong does not gate."
        );
        let mut section = "";
        for r in &self.rows {
            if r.section != section {
                section = r.section;
                let _ = writeln!(
                    s,
                    "\n{:<44} {:<8} {:>8} {:>6} {:>6} {:>5} {:>8} {:>8} {:>9} {:>7} {:>4}  ok",
                    section,
                    "kernel",
                    "rays",
                    "wrong",
                    "band",
                    "faces",
                    "err/r",
                    "(band)",
                    "err/bound",
                    "re-hits",
                    "NaN"
                );
            }
            let t = &r.tally;
            let bound = if r.gate != Gate::Reference { format!("{:.3}", t.max_err_bound) } else { "-".into() };
            let _ = writeln!(
                s,
                "{:<44} {:<8} {:>8} {:>6} {:>6} {:>5} {:>8.1e} {:>8.1e} {:>9} {:>7} {:>4}  {}",
                r.case,
                r.kernel,
                t.rays,
                t.wrong,
                t.in_band,
                t.faces,
                t.max_err_r,
                t.max_err_r_band,
                bound,
                t.rehits,
                t.nan,
                match (r.gate, r.ok()) {
                    (Gate::Reference, _) => "ref",
                    (_, true) => "ok",
                    _ => "FAIL",
                }
            );
        }
        if !self.decades.is_empty() {
            let _ = writeln!(
                s,
                "\noutside sweep by r/|o-c| (scalar robust vs textbook b*b-4ac, t_min = 0.001)\n\
                 {:<12} {:>8} {:>14} {:>12} {:>16} {:>14}",
                "r/|o-c|", "rays", "robust wrong", "robust err/r", "textbook wrong", "textbook err/r"
            );
            for d in &self.decades {
                let _ = writeln!(
                    s,
                    "1e{:<3}..1e{:<3} {:>8} {:>14} {:>12.2e} {:>16} {:>14.2e}",
                    d.ratio_exp,
                    d.ratio_exp + 1,
                    d.robust.rays,
                    d.robust.wrong,
                    d.robust.max_err_r,
                    d.textbook.wrong,
                    d.textbook.max_err_r
                );
            }
        }
        if !self.offset_scan.is_empty() {
            let _ = writeln!(
                s,
                "\noffset rules (self-intersection sweep, scalar, every scatter, resolvable hit points; u = 2^-24)\n{:<36} {:>9} {:>8} {:>7}",
                "offset", "rays", "re-hits", "wrong"
            );
            for o in &self.offset_scan {
                let _ = writeln!(s, "{:<36} {:>9} {:>8} {:>7}", o.rule, o.rays, o.rehits, o.wrong);
            }
        }
        let _ = writeln!(s, "\nchecks");
        for c in &self.checks {
            let _ = writeln!(
                s,
                "  {:<4} {:<66} {:>8.4} <= {:<3} {}",
                if c.ok { "ok" } else { "FAIL" },
                c.name,
                c.value,
                c.limit,
                c.note
            );
        }
        let f = self.failures();
        if f.is_empty() {
            let _ = writeln!(s, "\nall bounds hold");
        } else {
            let _ = writeln!(s, "\nBROKEN: {}", f.join(", "));
        }
        s
    }
}

/// How much `rtow stress` does.
#[derive(Clone, Copy, Debug)]
pub struct Config {
    /// The small version `cargo test` runs.
    pub quick: bool,
    pub seed: u64,
    /// Render threads (`None`: one per core).
    pub threads: Option<usize>,
}

#[derive(Clone, Copy, Debug)]
struct Sizes {
    /// Groups of 8 rays per intersection case.
    groups: usize,
    /// Hit points per scatter kind, and rays per hit point (a multiple of 8).
    hit_points: usize,
    per_point: usize,
    /// Scene renders.
    width: u32,
    height: u32,
    spp: u32,
    /// The horizon scene (one sphere: cheap) gets more samples.
    horizon_spp: u32,
    offset_scan: bool,
}

impl Config {
    fn sizes(&self) -> Sizes {
        if self.quick {
            Sizes {
                groups: 2_500,
                hit_points: 40,
                per_point: 1000,
                width: 48,
                height: 27,
                spp: 4,
                horizon_spp: 16,
                offset_scan: false,
            }
        } else {
            Sizes {
                groups: 125_000,
                hit_points: 1000,
                per_point: 1000,
                width: 128,
                height: 72,
                spp: 8,
                horizon_spp: 32,
                offset_scan: true,
            }
        }
    }
}

// ---------------------------------------------------------------------------
// 1. Intersection sweeps.

/// The configurations of the intersection sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IsectCase {
    /// Origin outside, aimed within 1.5 r of the centre (or a random direction).
    Outside,
    /// Origin outside, passing at `r (1 +- 1e-6)` from the centre.
    Grazing,
    /// Origin on the surface (rounded to f32), random and near-tangent directions.
    Surface,
    /// Origin inside.
    Inside,
    /// Origin at the centre.
    Centre,
    /// Any of the above with a negative radius.
    Negative,
}

impl IsectCase {
    pub const ALL: [IsectCase; 6] = [
        IsectCase::Outside,
        IsectCase::Grazing,
        IsectCase::Surface,
        IsectCase::Inside,
        IsectCase::Centre,
        IsectCase::Negative,
    ];

    pub fn name(self) -> &'static str {
        match self {
            IsectCase::Outside => "outside, r 1e-4..1e6, r/dist 1e-6..1",
            IsectCase::Grazing => "grazing, tangent to 1e-6 relative",
            IsectCase::Surface => "origin on the surface",
            IsectCase::Inside => "origin inside",
            IsectCase::Centre => "origin at the centre",
            IsectCase::Negative => "negative radius (all of the above)",
        }
    }
}

/// One sphere and 8 rays at it.
#[derive(Clone, Copy, Debug)]
pub struct Group {
    pub c: V3<f32>,
    pub r: f32,
    pub o: [V3<f32>; 8],
    pub d: [V3<f32>; 8],
    /// The intended `r / |o - c|` (outside cases).
    pub ratio: f64,
}

/// A direction from `o = c + fhat * dist` passing at distance `h` from `c`.
fn aim(g: &mut Gen, fhat: DVec3, dist: f64, h: f64) -> DVec3 {
    let sin = h / dist;
    if sin >= 1.0 {
        return g.unit();
    }
    let cos = (1.0 - sin * sin).sqrt();
    -fhat * cos + g.perp(fhat) * sin
}

fn gen_group(case: IsectCase, g: &mut Gen) -> Group {
    let mut o = [DVec3::ZERO; 8];
    let mut d = [DVec3::ZERO; 8];
    let (c, r, ratio) = match case {
        IsectCase::Outside | IsectCase::Grazing => {
            let (r, dist) = loop {
                let r = g.exp10(-4.0, 6.0);
                let dist = r / g.exp10(-6.0, 0.0);
                if dist <= 1e6 {
                    break (r, dist);
                }
            };
            let c = g.unit() * dist * g.unif();
            for k in 0..8 {
                let fhat = g.unit();
                o[k] = c + fhat * dist;
                d[k] = if case == IsectCase::Grazing {
                    let h = r * (1.0 + 1e-6 * g.range(-1.0, 1.0));
                    aim(g, fhat, dist, h)
                } else if g.unif() < 0.75 {
                    let h = r * g.range(0.0, 1.5);
                    aim(g, fhat, dist, h)
                } else {
                    g.unit()
                };
            }
            (c, r, r / dist)
        }
        IsectCase::Surface | IsectCase::Inside | IsectCase::Centre => {
            let r = g.exp10(-4.0, 6.0);
            let c = g.unit() * r * g.exp10(-2.0, 1.0);
            for k in 0..8 {
                let m = g.unit();
                o[k] = match case {
                    IsectCase::Surface => c + m * r,
                    IsectCase::Inside => c + m * (r * g.unif().cbrt()),
                    _ => c,
                };
                let x = g.unif();
                d[k] = if case == IsectCase::Surface && x < 0.3 {
                    let s = g.exp10(-8.0, -1.0).copysign(g.unif() - 0.5);
                    g.perp(m) * (1.0 - s * s).sqrt() + m * s
                } else {
                    g.unit()
                };
            }
            (c, r, 1.0)
        }
        IsectCase::Negative => {
            let sub =
                [IsectCase::Outside, IsectCase::Grazing, IsectCase::Surface, IsectCase::Inside, IsectCase::Centre]
                    [(g.unif() * 5.0) as usize % 5];
            let mut grp = gen_group(sub, g);
            grp.r = -grp.r;
            return grp;
        }
    };
    Group { c: v32(c), r: r as f32, o: o.map(v32), d: d.map(dir32), ratio }
}

fn one_sphere() -> Spheres {
    let s = Sphere { center: [0.0; 3], radius: 1.0, material: Material::Lambertian { albedo: [0.5; 3] } };
    Spheres::new(&[s], |_| (Kind::Lambertian, 0))
}

fn set_sphere(s: &mut Spheres, c: V3<f32>, r: f32) {
    s.cx[0] = c.x;
    s.cy[0] = c.y;
    s.cz[0] = c.z;
    s.r[0] = r;
    s.r2[0] = r * r;
}

/// The results of one group of 8 rays, for each width and the textbook.
#[derive(Clone, Debug, Default)]
pub struct GroupResult {
    pub scalar: Tally,
    pub simd: Tally,
    pub textbook: Tally,
    /// Lanes where the 8-wide answer (index, t, disc) differs in any bit from the scalar one.
    pub mismatches: u64,
    /// Largest |disc computed - disc| / its bound (must be <= 1).
    pub max_disc_ratio: f64,
}

fn record_hit(t: &mut Tally, tr: &Truth, ray: &RayF64, c: DVec3, hit: bool, tk: f32, front: bool, gated: bool) {
    t.rays += 1;
    if hit && !tk.is_finite() {
        t.nan += 1;
        return;
    }
    let v = tr.judge(hit, tk as f64);
    match v {
        Verdict::Wrong => t.wrong += 1,
        Verdict::InBand => t.in_band += 1,
        Verdict::Right => {}
    }
    if hit {
        let dist = ((ray.at(tk as f64) - c).length() - tr.r).abs();
        t.err(dist, tr.r, gated.then(|| tr.dist_bound(tk as f64)), v == Verdict::InBand);
        if v == Verdict::Right {
            if let Some(fo) = tr.nearest(tk as f64).and_then(|i| tr.front_at(ray, c, i)) {
                if fo != front {
                    t.faces += 1;
                }
            }
        }
    }
}

/// Runs one group through `closest_hit_scalar`, `closest_hit_x8`, `sphere_disc`
/// (both widths) and the textbook test, and judges every answer.
pub fn check_group(grp: &Group, spheres: &mut Spheres) -> GroupResult {
    let mut res = GroupResult::default();
    set_sphere(spheres, grp.c, grp.r);
    let r2 = grp.r * grp.r;
    let (o8, d8) = (pack8(&grp.o), pack8(&grp.d));
    let c8 = splat8(grp.c);
    let (hit8, t8) = closest_hit_x8(spheres, o8, d8);
    let (disc8, _, _) = sphere_disc(o8, d8, c8, f32x8::splat(r2));
    let front8 = surface(o8, d8, t8, c8, f32x8::splat(grp.r)).front.to_bitmask();
    let (hit8, t8, disc8) = (hit8.to_array(), t8.to_array(), disc8.to_array());
    let c64 = v64(grp.c);
    for k in 0..8 {
        let (o, d) = (grp.o[k], grp.d[k]);
        let (hs, ts) = closest_hit_scalar(spheres, o, d);
        let (disc, _, _) = sphere_disc(o, d, grp.c, r2);
        if hs != hit8[k] || ts.to_bits() != t8[k].to_bits() || disc.to_bits() != disc8[k].to_bits() {
            res.mismatches += 1;
        }
        let ray = RayF64::new(o, d);
        let tr = Truth::new(&ray, c64, grp.r as f64);
        res.max_disc_ratio = res.max_disc_ratio.max((disc as f64 - tr.disc).abs() / tr.e_disc);
        let fs = hs != MISS && surface(o, d, ts, grp.c, grp.r).front;
        record_hit(&mut res.scalar, &tr, &ray, c64, hs != MISS, ts, fs, true);
        let f8 = front8 & (1 << k) != 0;
        record_hit(&mut res.simd, &tr, &ray, c64, hit8[k] != MISS, t8[k], f8, true);
        let tb = textbook_hit(o, d, grp.c, grp.r, TEXTBOOK_T_MIN);
        let tt = tb.unwrap_or(f32::INFINITY);
        let ftb = tb.is_some() && d.dot((ray_point32(o, d, tt) - grp.c) * (1.0 / grp.r)) < 0.0;
        record_hit(&mut res.textbook, &tr, &ray, c64, tb.is_some(), tt, ftb, false);
    }
    res
}

fn ray_point32(o: V3<f32>, d: V3<f32>, t: f32) -> V3<f32> {
    o + d * t
}

fn add(a: &mut Tally, b: &Tally) {
    a.rays += b.rays;
    a.wrong += b.wrong;
    a.in_band += b.in_band;
    a.faces += b.faces;
    a.rehits += b.rehits;
    a.nan += b.nan;
    a.max_err_r = a.max_err_r.max(b.max_err_r);
    a.max_err_r_band = a.max_err_r_band.max(b.max_err_r_band);
    a.max_err_bound = a.max_err_bound.max(b.max_err_bound);
}

struct IsectOut {
    scalar: Tally,
    simd: Tally,
    textbook: Tally,
    mismatches: u64,
    max_disc_ratio: f64,
}

fn isect_sweep(case: IsectCase, groups: usize, seed: u64, decades: &mut [Decade]) -> IsectOut {
    let mut g = Gen::new(seed, 100 + case as u64);
    let mut sph = one_sphere();
    let mut out = IsectOut {
        scalar: Tally::default(),
        simd: Tally::default(),
        textbook: Tally::default(),
        mismatches: 0,
        max_disc_ratio: 0.0,
    };
    for _ in 0..groups {
        let grp = gen_group(case, &mut g);
        let res = check_group(&grp, &mut sph);
        add(&mut out.scalar, &res.scalar);
        add(&mut out.simd, &res.simd);
        add(&mut out.textbook, &res.textbook);
        out.mismatches += res.mismatches;
        out.max_disc_ratio = out.max_disc_ratio.max(res.max_disc_ratio);
        if case == IsectCase::Outside {
            let e = grp.ratio.log10().floor().clamp(-6.0, -1.0) as i32;
            if let Some(d) = decades.iter_mut().find(|d| d.ratio_exp == e) {
                add(&mut d.robust, &res.scalar);
                add(&mut d.textbook, &res.textbook);
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------
// 2. Self-intersection sweeps.

/// What scatters the rays leaving a hit point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scatter {
    Lambertian,
    Metal,
    Dielectric,
    /// Synthetic directions within 10^U(-8,-1) of the tangent plane, both sides.
    Grazing,
}

impl Scatter {
    pub const ALL: [Scatter; 4] = [Scatter::Lambertian, Scatter::Metal, Scatter::Dielectric, Scatter::Grazing];
    pub fn name(self) -> &'static str {
        match self {
            Scatter::Lambertian => "lambertian scatter",
            Scatter::Metal => "metal scatter (fuzz 0..1)",
            Scatter::Dielectric => "dielectric scatter (ior 1..2.5)",
            Scatter::Grazing => "grazing directions (1e-8..1e-1)",
        }
    }
}

/// Which implementation runs the self-intersection sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Impl {
    Kernel(KernelKind),
    Textbook,
}

/// The offset a spawned ray gets.
#[derive(Clone, Copy, Debug, PartialEq)]
enum OffsetRule {
    /// The kernels' `surface()` offset, times a factor.
    Scaled(f32),
    /// `u (kr |r| + kp |p|_inf)`.
    Terms { kr: f32, kp: f32 },
}

struct HitSetup {
    c: V3<f32>,
    r: f32,
    o: V3<f32>,
    d: V3<f32>,
    fuzz: f32,
    ior: f32,
}

fn gen_hit(g: &mut Gen, scatter: Scatter) -> HitSetup {
    let r_abs = g.exp10(-4.0, 4.0);
    let r = if g.unif() < 0.25 { -r_abs } else { r_abs };
    let m = g.unit();
    // Half the spheres have their centre 10^U(-4,6) from the origin, half the
    // hit point (a small distance then puts the point near the origin on a big
    // sphere, like the top of the book's ground: there |p| << |r|).
    let dist = g.exp10(-4.0, 6.0);
    let (c, s) = if g.unif() < 0.5 {
        let c = g.unit() * dist;
        (c, c + m * r_abs)
    } else {
        let s = g.unit() * dist;
        (s - m * r_abs, s)
    };
    let p_inside = if scatter == Scatter::Dielectric { 0.5 } else { 0.25 };
    let inside = g.unif() < p_inside;
    let cos = if g.unif() < 0.5 { g.range(1e-9, 1.0) } else { g.exp10(-6.0, -1.0) };
    let sin = (1.0 - cos * cos).sqrt();
    let tng = g.perp(m);
    let (o, d) = if inside {
        let d = m * cos + tng * sin;
        (s - d * (2.0 * r_abs * cos * g.range(0.05, 0.95)), d)
    } else {
        let d = -m * cos + tng * sin;
        (s - d * (r_abs * g.exp10(-1.0, 2.0)), d)
    };
    let fuzz = if g.unif() < 0.25 { 0.0 } else { g.unif() as f32 };
    let ior = if g.unif() < 0.1 { 1.0 } else { g.range(1.1, 2.5) as f32 };
    HitSetup { c: v32(c), r: r as f32, o: v32(o), d: dir32(d), fuzz, ior }
}

/// A scattered direction for one ray or eight (the material functions of the kernels).
fn scatter_dir<R: Real, S: Stream<R>>(
    kind: Scatter,
    d: V3<R>,
    srf: &Surface<R>,
    fuzz: f32,
    ior: f32,
    rng: &mut S,
) -> (V3<R>, R::Mask) {
    let yes = R::splat(0.0).eq(R::splat(0.0));
    match kind {
        Scatter::Lambertian => (lambertian(srf.n, rng), yes),
        Scatter::Metal => metal(d, srf.n, R::splat(fuzz), rng),
        _ => (dielectric(d, srf.n, srf.front, R::splat(ior), rng), yes),
    }
}

/// A synthetic direction within 10^U(-8,-1) of the tangent plane at normal `n`.
/// Scattered direction `j` from hit point `k` (scalar): `None` when the
/// material absorbs the path, or when the direction is not finite (counted in `t.nan`).
fn scattered(
    scatter: Scatter,
    dirs: &mut Gen,
    srf: &Surface<f32>,
    hs: &HitSetup,
    stream_seed: u64,
    (k, j): (usize, usize),
    t: &mut Tally,
) -> Option<V3<f32>> {
    let (dir, alive) = if scatter == Scatter::Grazing {
        (grazing_dir(dirs, srf.n), true)
    } else {
        let mut rng = ScalarStream::for_path(stream_seed, k as u64, j as u64);
        scatter_dir(scatter, hs.d, srf, hs.fuzz, hs.ior, &mut rng)
    };
    if !alive {
        return None;
    }
    if !finite3(dir) {
        t.nan += 1;
        return None;
    }
    Some(dir)
}

fn grazing_dir(g: &mut Gen, n: V3<f32>) -> V3<f32> {
    let n = v64(n).normalize();
    let s = g.exp10(-8.0, -1.0).copysign(g.unif() - 0.5);
    dir32(g.perp(n) * (1.0 - s * s).sqrt() + n * s)
}

/// Classifies a ray spawned from a surface with outward unit normal `m`
/// (the direction of the kernel's own normal) against the sphere it left:
/// a ray that leaves the ball can never meet it again (any hit is a re-hit);
/// a ray that enters it must reach the far wall, `2 r |cos|` away (a miss, or a
/// hit short of half that, is a wrong decision); within `SIDE_EPS` of tangent
/// the side is decided by rounding (in band).
fn classify_spawn(t: &mut Tally, m: DVec3, r_abs: f64, dir: V3<f32>, hit: bool, th: f32) {
    t.rays += 1;
    let dd = v64(dir);
    let dl = dd.length();
    let g = dd.dot(m) / dl;
    if g >= SIDE_EPS {
        if hit {
            t.rehits += 1;
        }
    } else if g <= -SIDE_EPS {
        let chord = 2.0 * r_abs * -g / dl;
        if !hit || (th as f64) < 0.5 * chord {
            t.wrong += 1;
        }
    } else {
        t.in_band += 1;
    }
}

fn apply_offset(srf: &mut Surface<f32>, r: f32, rule: OffsetRule) {
    srf.offset = match rule {
        OffsetRule::Scaled(k) => srf.offset * k,
        OffsetRule::Terms { kr, kp } => (r.abs() * kr + srf.p.max_abs() * kp) * (1.0 / 16_777_216.0),
    };
}

/// Bound on the distance of the re-projected point `p = c + |r| n` from the sphere.
fn reprojection_bound(r_abs: f64, p: DVec3) -> f64 {
    SLACK * (5.5 * U * r_abs + U * p.length())
}

/// The kernels' offset at `p` on a sphere of radius `r` (`surface()`'s formula, in f64).
fn kernel_offset(r_abs: f64, p: DVec3) -> f64 {
    (r_abs + p.abs().max_element()) / 1_048_576.0
}

struct SelfOut {
    /// Hit points where the kernels' offset is at most |r|, and the others
    /// (below f32 resolution: see `geometry::surface`, "the rule has a floor").
    resolved: Tally,
    unresolved: Tally,
    hash: u64,
}

fn self_sweep(scatter: Scatter, imp: Impl, sizes: &Sizes, seed: u64, rule: OffsetRule) -> SelfOut {
    let mut g = Gen::new(seed, 200 + scatter as u64);
    let mut sph = one_sphere();
    let mut ts = [Tally::default(), Tally::default()];
    let mut h = Fnv::new();
    let stream_seed = mix64(seed ^ 0x5e1f);
    for k in 0..sizes.hit_points {
        let hs = gen_hit(&mut g, scatter);
        let mut dirs = Gen::new(seed ^ 0xd1, (scatter as u64) << 32 | k as u64);
        set_sphere(&mut sph, hs.c, hs.r);
        let c64 = v64(hs.c);
        let r_abs = hs.r.abs() as f64;
        let (hit, th) = match imp {
            Impl::Kernel(KernelKind::Scalar) => closest_hit_scalar(&sph, hs.o, hs.d),
            Impl::Kernel(KernelKind::Simd) => {
                let (i8, t8) = closest_hit_x8(&sph, splat8(hs.o), splat8(hs.d));
                (i8.to_array()[0], t8.to_array()[0])
            }
            Impl::Textbook => match textbook_hit(hs.o, hs.d, hs.c, hs.r, TEXTBOOK_T_MIN) {
                Some(t) => (0, t),
                None => (MISS, f32::INFINITY),
            },
        };
        if hit == MISS {
            // No hit point to start from; a miss the oracle calls wrong is counted.
            let ray = RayF64::new(hs.o, hs.d);
            let resolved = kernel_offset(r_abs, c64) <= r_abs;
            let t = &mut ts[!resolved as usize];
            if imp != Impl::Textbook && Truth::new(&ray, c64, hs.r as f64).judge(false, 0.0) == Verdict::Wrong {
                t.wrong += 1;
            }
            continue;
        }
        match imp {
            Impl::Kernel(KernelKind::Scalar) => {
                let mut srf = surface(hs.o, hs.d, th, hs.c, hs.r);
                let p = v64(srf.p);
                let t = &mut ts[!(kernel_offset(r_abs, p) <= r_abs) as usize];
                if !(finite3(srf.p) && finite3(srf.n) && srf.offset.is_finite()) {
                    t.nan += 1;
                    continue;
                }
                apply_offset(&mut srf, hs.r, rule);
                t.err(((p - c64).length() - r_abs).abs(), r_abs, Some(reprojection_bound(r_abs, p)), false);
                let sigma = hs.r.signum() as f64 * if srf.front { 1.0 } else { -1.0 };
                let m = (v64(srf.n) * sigma).normalize();
                for j in 0..sizes.per_point {
                    let Some(dir) = scattered(scatter, &mut dirs, &srf, &hs, stream_seed, (k, j), t) else {
                        continue;
                    };
                    let o2 = spawn(&srf, dir);
                    let (i2, t2) = closest_hit_scalar(&sph, o2, dir);
                    h.v(o2);
                    h.v(dir);
                    h.u32(i2);
                    h.f(t2);
                    classify_spawn(t, m, r_abs, dir, i2 != MISS, t2);
                }
            }
            Impl::Kernel(KernelKind::Simd) => {
                let d8 = splat8(hs.d);
                let srf = surface(splat8(hs.o), d8, f32x8::splat(th), splat8(hs.c), f32x8::splat(hs.r));
                let (p0, n0) = (lane(srf.p, 0), lane(srf.n, 0));
                let p = v64(p0);
                let t = &mut ts[!(kernel_offset(r_abs, p) <= r_abs) as usize];
                if !(finite3(p0) && finite3(n0) && srf.offset.to_array()[0].is_finite()) {
                    t.nan += 1;
                    continue;
                }
                t.err(((p - c64).length() - r_abs).abs(), r_abs, Some(reprojection_bound(r_abs, p)), false);
                let front = srf.front.to_bitmask() & 1 != 0;
                let sigma = hs.r.signum() as f64 * if front { 1.0 } else { -1.0 };
                let m = (v64(n0) * sigma).normalize();
                for j0 in (0..sizes.per_point).step_by(8) {
                    let (dir, alive) = if scatter == Scatter::Grazing {
                        let d: [V3<f32>; 8] = std::array::from_fn(|_| grazing_dir(&mut dirs, n0));
                        (pack8(&d), 0xff)
                    } else {
                        let mut rng = stream8(stream_seed, [k as u64; 8], std::array::from_fn(|l| (j0 + l) as u64));
                        let (d, a) = scatter_dir(scatter, d8, &srf, hs.fuzz, hs.ior, &mut rng);
                        (d, a.to_bitmask())
                    };
                    let o2 = spawn(&srf, dir);
                    let (i2, t2) = closest_hit_x8(&sph, o2, dir);
                    let (i2, t2) = (i2.to_array(), t2.to_array());
                    for l in 0..8 {
                        if alive & (1 << l) == 0 {
                            continue;
                        }
                        let dl = lane(dir, l);
                        if !finite3(dl) {
                            t.nan += 1;
                            continue;
                        }
                        h.v(lane(o2, l));
                        h.v(dl);
                        h.u32(i2[l]);
                        h.f(t2[l]);
                        classify_spawn(t, m, r_abs, dl, i2[l] != MISS, t2[l]);
                    }
                }
            }
            Impl::Textbook => {
                // The book: p = o + t d, n = (p - c) / r, the next ray starts at p.
                let p = hs.o + hs.d * th;
                let out = (p - hs.c) * (1.0 / hs.r);
                let front = hs.d.dot(out) < 0.0;
                let n = if front { out } else { -out };
                let srf = Surface { p, n, front, offset: 0.0 };
                let pp = v64(p);
                let t = &mut ts[!(kernel_offset(r_abs, pp) <= r_abs) as usize];
                t.err(((pp - c64).length() - r_abs).abs(), r_abs, None, false);
                let m = (pp - c64).normalize();
                for j in 0..sizes.per_point {
                    let Some(dir) = scattered(scatter, &mut dirs, &srf, &hs, stream_seed, (k, j), t) else {
                        continue;
                    };
                    let hit2 = textbook_hit(p, dir, hs.c, hs.r, TEXTBOOK_T_MIN);
                    classify_spawn(t, m, r_abs, dir, hit2.is_some(), hit2.unwrap_or(f32::INFINITY));
                }
            }
        }
    }
    let [resolved, unresolved] = ts;
    SelfOut { resolved, unresolved, hash: h.0 }
}

/// The self-intersection sweep (scalar kernel, every scatter, resolvable hit
/// points) with the kernels' offset multiplied by `scale`: `(rays, re-hits,
/// entering rays short of the far wall)`. At `scale = 1`, the kernels' behaviour.
pub fn offset_rehits(scale: f32, hit_points: usize, seed: u64) -> (u64, u64, u64) {
    let sizes = Sizes { hit_points, ..Config { quick: true, seed, threads: None }.sizes() };
    let mut t = Tally::default();
    for scatter in Scatter::ALL {
        let out = self_sweep(scatter, Impl::Kernel(KernelKind::Scalar), &sizes, seed, OffsetRule::Scaled(scale));
        add(&mut t, &out.resolved);
    }
    (t.rays, t.rehits, t.wrong)
}

// ---------------------------------------------------------------------------
// 3. Scenes: instrumented tracers and the scene oracle.

/// The sphere a ray just left: its index and the outward unit normal the kernel used.
#[derive(Clone, Copy, Debug)]
struct Leaving {
    sphere: u32,
    m: DVec3,
    r_abs: f64,
}

impl Leaving {
    fn new(sphere: u32, n: V3<f32>, r: f32, front: bool) -> Self {
        let sigma = r.signum() as f64 * if front { 1.0 } else { -1.0 };
        Leaving { sphere, m: (v64(n) * sigma).normalize(), r_abs: r.abs() as f64 }
    }
}

/// Judges every ray of a scene against every sphere in f64.
struct SceneOracle {
    c: Vec<DVec3>,
    r: Vec<f64>,
}

impl SceneOracle {
    fn new(s: &Spheres) -> Self {
        SceneOracle {
            c: (0..s.len).map(|i| DVec3::new(s.cx[i] as f64, s.cy[i] as f64, s.cz[i] as f64)).collect(),
            r: (0..s.len).map(|i| s.r[i] as f64).collect(),
        }
    }

    /// Checks one traced ray: `hit`/`t` is the kernel's closest hit, `front` its
    /// front/back face there, `prev` the surface the ray left.
    fn check(&self, t: &mut Tally, o: V3<f32>, d: V3<f32>, hit: u32, th: f32, front: bool, prev: Option<Leaving>) {
        if !finite3(o) || !finite3(d) || (hit != MISS && !th.is_finite()) {
            t.nan += 1;
            return;
        }
        t.rays += 1;
        if let Some(lv) = prev {
            if hit == lv.sphere {
                let mut probe = Tally::default();
                classify_spawn(&mut probe, lv.m, lv.r_abs, d, true, th);
                if probe.rehits > 0 || probe.wrong > 0 {
                    t.rehits += probe.rehits;
                    t.wrong += probe.wrong;
                    return;
                }
            }
        }
        let ray = RayF64::new(o, d);
        let th64 = th as f64;
        let mut verdict_k = Verdict::Wrong;
        let mut tol_k = 0.0;
        let mut truth_k = None;
        let (mut best, mut best_tol) = (f64::INFINITY, 0.0);
        let mut any_in_band = false;
        for j in 0..self.c.len() {
            let tr = Truth::new(&ray, self.c[j], self.r[j]);
            if j as u32 == hit {
                verdict_k = tr.judge(true, th64);
                tol_k = tr.t_tol(th64);
                truth_k = Some(tr);
            } else if tr.grazing() {
                any_in_band = true;
            } else if let Some(tj) = tr.required {
                if tj < best {
                    best = tj;
                    best_tol = tr.t_tol(tj);
                }
            }
        }
        let verdict = if hit == MISS {
            if best.is_finite() {
                Verdict::Wrong
            } else if any_in_band {
                Verdict::InBand
            } else {
                Verdict::Right
            }
        } else if verdict_k == Verdict::Wrong || best < th64 - (tol_k + best_tol) {
            Verdict::Wrong
        } else {
            verdict_k
        };
        match verdict {
            Verdict::Wrong => t.wrong += 1,
            Verdict::InBand => t.in_band += 1,
            Verdict::Right => {}
        }
        if let Some(tr) = truth_k {
            let c = self.c[hit as usize];
            let dist = ((ray.at(th64) - c).length() - tr.r).abs();
            t.err(dist, tr.r, Some(tr.dist_bound(th64)), verdict == Verdict::InBand);
            if verdict_k == Verdict::Right {
                if let Some(fo) = tr.nearest(th64).and_then(|i| tr.front_at(&ray, c, i)) {
                    if fo != front {
                        t.faces += 1;
                    }
                }
            }
        }
    }
}

/// What an instrumented trace of a scene produced.
struct Traced {
    image: Image,
    tally: Tally,
    /// Hash of every ray (origin, direction, hit, t), path by path.
    hash: u64,
    rays: u64,
}

/// A camera-ray rewrite (the far camera's reference starts rays near the scene).
type Shift<'a> = &'a dyn Fn(V3<f32>, V3<f32>) -> V3<f32>;

/// The textbook's closest hit: every sphere's first root above `t_min`, ties to the lowest index.
fn textbook_closest(sp: &Spheres, o: V3<f32>, d: V3<f32>) -> (u32, f32) {
    let mut best = (MISS, f32::INFINITY);
    for i in 0..sp.len {
        let c = V3::new(sp.cx[i], sp.cy[i], sp.cz[i]);
        if let Some(t) = textbook_hit(o, d, c, sp.r[i], TEXTBOOK_T_MIN) {
            if t < best.1 {
                best = (i as u32, t);
            }
        }
    }
    best
}

/// The scalar kernel's loop (`kernel::scalar::trace`), instrumented. With
/// `textbook`, the book's version instead: `textbook_hit` with `t_min = 0.001`,
/// `p = o + t d`, `n = (p - c) / r`, and the next ray starting at `p`.
fn trace_scalar(prep: &Prepared, oracle: &SceneOracle, shift: Option<Shift>, textbook: bool) -> Traced {
    let s = prep.settings;
    let sp = &prep.spheres;
    let m = &prep.materials;
    let mut film = TileFilm::new(0, 0, s.width, s.height);
    let mut tally = Tally::default();
    let mut all = Fnv::new();
    let mut rays = 0u64;
    for local in 0..film.sum.len() {
        let (x, y) = film.pixel_of(local);
        let pixel = y as u64 * s.width as u64 + x as u64;
        for sample in 0..s.spp {
            let mut rng = ScalarStream::for_path(s.seed, pixel, sample as u64);
            let mut h = Fnv::new();
            let (mut o, mut d) = prep.camera.ray(x as f32, y as f32, &mut rng);
            if let Some(f) = shift {
                o = f(o, d);
            }
            let mut thr = V3::new(1.0f32, 1.0, 1.0);
            let mut prev = None;
            let mut colour = [0.0f32; 3];
            for _ in 0..s.max_depth {
                rays += 1;
                let (hit, t) = if textbook { textbook_closest(sp, o, d) } else { closest_hit_scalar(sp, o, d) };
                h.v(o);
                h.v(d);
                h.u32(hit);
                h.f(t);
                if hit == MISS {
                    oracle.check(&mut tally, o, d, hit, t, false, prev);
                    colour = thr.mul_elem(sky(&prep.sky, d)).to_array();
                    break;
                }
                let i = hit as usize;
                let c = V3::new(sp.cx[i], sp.cy[i], sp.cz[i]);
                let srf = if textbook {
                    let p = o + d * t;
                    let out = (p - c) * (1.0 / sp.r[i]);
                    let front = d.dot(out) < 0.0;
                    let n = if front { out } else { -out };
                    Surface { p, n, front, offset: 0.0 }
                } else {
                    surface(o, d, t, c, sp.r[i])
                };
                oracle.check(&mut tally, o, d, hit, t, srf.front, prev);
                let row = sp.row[i] as usize;
                let (dir, atten) = match sp.kind[i] {
                    k if k == Kind::Lambertian as u8 => (lambertian(srf.n, &mut rng), m.lambertian[row]),
                    k if k == Kind::Metal as u8 => {
                        let (albedo, fuzz) = m.metal[row];
                        let (dir, alive) = metal(d, srf.n, fuzz, &mut rng);
                        if !alive {
                            break;
                        }
                        (dir, albedo)
                    }
                    _ => (dielectric(d, srf.n, srf.front, m.dielectric[row], &mut rng), [1.0; 3]),
                };
                thr = thr.mul_elem(V3::from_array(atten));
                if thr.x == 0.0 && thr.y == 0.0 && thr.z == 0.0 {
                    break;
                }
                prev = Some(Leaving::new(hit, srf.n, sp.r[i], srf.front));
                o = if textbook { srf.p } else { spawn(&srf, dir) };
                d = dir;
            }
            if !colour.iter().all(|c| c.is_finite()) {
                tally.nan += 1;
            }
            film.add(local, colour);
            all.u32((h.0 >> 32) as u32);
            all.u32(h.0 as u32);
        }
    }
    let mut image = Image::new(s.width, s.height);
    image.put_tile(&film);
    Traced { image, tally, hash: all.0, rays }
}

/// The SIMD kernel's formulas on packets of 8 paths, instrumented. Paths run in
/// lockstep; each lane scatters with its own material's function (the other
/// materials' results, and their draws, are discarded by lane selects), so lane
/// k computes exactly what the wavefront kernel computes for that path.
fn trace_x8(prep: &Prepared, oracle: &SceneOracle) -> Traced {
    let s = prep.settings;
    let sp = &prep.spheres;
    let m = &prep.materials;
    let mut film = TileFilm::new(0, 0, s.width, s.height);
    let mut tally = Tally::default();
    let mut all = Fnv::new();
    let mut rays = 0u64;
    let spp = s.spp as usize;
    let n = film.sum.len() * spp;
    let zero = f32x8::splat(0.0);
    for base in (0..n).step_by(8) {
        let count = (n - base).min(8);
        let idx: [usize; 8] = std::array::from_fn(|k| base + k.min(count - 1));
        let local: [usize; 8] = idx.map(|i| i / spp);
        let sample: [u64; 8] = idx.map(|i| (i % spp) as u64);
        let xy: [(u32, u32); 8] = local.map(|l| film.pixel_of(l));
        let pixel: [u64; 8] = xy.map(|(x, y)| y as u64 * s.width as u64 + x as u64);
        let mut rng = stream8(s.seed, pixel, sample);
        let px = f32x8::new(xy.map(|p| p.0 as f32));
        let py = f32x8::new(xy.map(|p| p.1 as f32));
        let (mut o, mut d) = prep.camera.ray(px, py, &mut rng);
        let mut thr = V3::new(f32x8::splat(1.0), f32x8::splat(1.0), f32x8::splat(1.0));
        let mut alive: [bool; 8] = std::array::from_fn(|k| k < count);
        let mut colour = [[0.0f32; 3]; 8];
        let mut prev: [Option<Leaving>; 8] = [None; 8];
        let mut h = [Fnv::new(); 8];
        for _ in 0..s.max_depth {
            if !alive.iter().any(|a| *a) {
                break;
            }
            let (hit8, t8) = closest_hit_x8(sp, o, d);
            let (hit, t) = (hit8.to_array(), t8.to_array());
            let si: [usize; 8] = hit.map(|i| if i == MISS { 0 } else { i as usize });
            let g = |v: &[f32]| f32x8::new(si.map(|i| v.get(i).copied().unwrap_or(0.0)));
            let c8 = V3::new(g(&sp.cx), g(&sp.cy), g(&sp.cz));
            let r8 = f32x8::new(si.map(|i| sp.r.get(i).copied().unwrap_or(1.0)));
            let srf = surface(o, d, t8, c8, r8);
            let front = srf.front.to_bitmask();
            let sky8 = thr.mul_elem(sky(&prep.sky, d));
            for k in 0..8 {
                if !alive[k] {
                    continue;
                }
                rays += 1;
                let (ok, dk) = (lane(o, k), lane(d, k));
                h[k].v(ok);
                h[k].v(dk);
                h[k].u32(hit[k]);
                h[k].f(t[k]);
                oracle.check(&mut tally, ok, dk, hit[k], t[k], front & (1 << k) != 0, prev[k]);
                if hit[k] == MISS {
                    colour[k] = lane(sky8, k).to_array();
                    alive[k] = false;
                }
            }
            let kind: [u8; 8] = si.map(|i| sp.kind.get(i).copied().unwrap_or(Kind::Lambertian as u8));
            let row: [usize; 8] = si.map(|i| sp.row.get(i).copied().unwrap_or(0) as usize);
            let is = |want: Kind| -> [bool; 8] { kind.map(|k| k == want as u8) };
            let (lam, met) = (is(Kind::Lambertian), is(Kind::Metal));
            let albedo: [[f32; 3]; 8] = std::array::from_fn(|k| {
                if lam[k] {
                    m.lambertian[row[k]]
                } else if met[k] {
                    m.metal[row[k]].0
                } else {
                    [1.0; 3]
                }
            });
            let fuzz = f32x8::new(std::array::from_fn(|k| if met[k] { m.metal[row[k]].1 } else { 0.0 }));
            let ior = f32x8::new(std::array::from_fn(|k| {
                if !lam[k] && !met[k] {
                    m.dielectric.get(row[k]).copied().unwrap_or(1.5)
                } else {
                    1.5
                }
            }));
            let (mut rng_l, mut rng_m, mut rng_d) = (rng, rng, rng);
            let dir_l = lambertian(srf.n, &mut rng_l);
            let (dir_m, ok_m) = metal(d, srf.n, fuzz, &mut rng_m);
            let dir_d = dielectric(d, srf.n, srf.front, ior, &mut rng_d);
            let (ml, mm) = (mask8(lam), mask8(met));
            let dir = V3::select(ml, dir_l, V3::select(mm, dir_m, dir_d));
            let (ul, um) = (umask8(lam), umask8(met));
            rng = Xoshiro128PlusX8 {
                s: std::array::from_fn(|w| ul.select(rng_l.s[w], um.select(rng_m.s[w], rng_d.s[w]))),
            };
            let a = V3::new(
                f32x8::new(albedo.map(|c| c[0])),
                f32x8::new(albedo.map(|c| c[1])),
                f32x8::new(albedo.map(|c| c[2])),
            );
            thr = thr.mul_elem(a);
            let dark = (thr.x.eq(zero) & thr.y.eq(zero) & thr.z.eq(zero)).to_bitmask();
            let ok_m = ok_m.to_bitmask();
            for k in 0..8 {
                if !alive[k] {
                    continue;
                }
                if (met[k] && ok_m & (1 << k) == 0) || dark & (1 << k) != 0 {
                    alive[k] = false;
                    continue;
                }
                prev[k] = Some(Leaving::new(hit[k], lane(srf.n, k), sp.r[si[k]], front & (1 << k) != 0));
            }
            o = spawn(&srf, dir);
            d = dir;
        }
        for k in 0..count {
            if !colour[k].iter().all(|c| c.is_finite()) {
                tally.nan += 1;
            }
            film.add(local[k], colour[k]);
            all.u32((h[k].0 >> 32) as u32);
            all.u32(h[k].0 as u32);
        }
    }
    let mut image = Image::new(s.width, s.height);
    image.put_tile(&film);
    Traced { image, tally, hash: all.0, rays }
}

/// Differences below this (linear colour, about 1/40 of an 8-bit step at mid
/// grey) pass an image comparison whatever their z: renders with the same seed
/// share their random numbers, so the rounding of scaled coordinates (~1e-6
/// here) is "significant" without being visible.
pub const COLOUR_FLOOR: f64 = 1e-4;

/// Max z of the difference `a - b` (per channel), over the whole image and over
/// blocks of `block` x `block` pixels, after the floor: `(|mean| - COLOUR_FLOOR)+ / se`.
/// Pixels are independent (each has its own random streams), so under "same
/// expected image" the mean difference over n pixels has standard error sd / sqrt(n).
fn compare(a: &Image, b: &Image, block: u32) -> (f64, f64) {
    fn z(v: &[f64]) -> f64 {
        let n = v.len() as f64;
        if v.len() < 2 {
            return 0.0;
        }
        let mean = v.iter().sum::<f64>() / n;
        let excess = (mean.abs() - COLOUR_FLOOR).max(0.0);
        let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
        if var == 0.0 {
            return if excess == 0.0 { 0.0 } else { f64::INFINITY };
        }
        excess / (var / n).sqrt()
    }
    let (w, h) = (a.width, a.height);
    let diff = |x: u32, y: u32, ch: usize| a.get(x, y)[ch] as f64 - b.get(x, y)[ch] as f64;
    let mut global: f64 = 0.0;
    let mut blocks: f64 = 0.0;
    for ch in 0..3 {
        let all: Vec<f64> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| diff(x, y, ch)).collect();
        global = global.max(z(&all));
        for by in (0..h).step_by(block as usize) {
            for bx in (0..w).step_by(block as usize) {
                let v: Vec<f64> = (by..(by + block).min(h))
                    .flat_map(|y| (bx..(bx + block).min(w)).map(move |x| (x, y)))
                    .map(|(x, y)| diff(x, y, ch))
                    .collect();
                if v.len() >= 16 {
                    blocks = blocks.max(z(&v));
                }
            }
        }
    }
    (global, blocks)
}

fn mean_colour(img: &Image) -> [f64; 3] {
    let n = img.data.len().max(1) as f64;
    let mut m = [0.0; 3];
    for p in &img.data {
        for c in 0..3 {
            m[c] += p[c] as f64 / n;
        }
    }
    m
}

fn preset(name: &str) -> Result<Scene> {
    scene::preset(name).ok_or_else(|| Error::Input(format!("stress: preset '{name}' is missing")))
}

fn settings(scene: &Scene, w: u32, h: u32, spp: u32, seed: u64) -> Settings {
    let mut s = crate::default_settings(scene);
    s.width = w;
    s.height = h;
    s.spp = spp;
    s.seed = seed;
    s
}

fn render_with(scene: &Scene, s: Settings, kernel: KernelKind, threads: Option<usize>) -> Result<crate::Rendered> {
    render(scene, s, RenderOptions { kernel, threads, tile: 16, ..RenderOptions::default() }, None)
}

/// The horizon scene's ground against its analytic colour: a lambertian
/// sphere seen from just above is a plane to the camera, and every point of a
/// convex diffuse surface under this sky has the expected colour
/// `albedo (horizon (1 - a) + zenith a)`, `a = 1/2 + n.y / 3` (the cosine-weighted
/// mean of `d.y` is `2/3 n.y`; scattered rays leave a convex sphere for good).
/// Returns max |z| over the ground pixels, whole and in three row bands.
fn horizon_check(scene: &Scene, prep: &Prepared, img: &Image) -> Result<(f64, usize, [f64; 3], [f64; 3])> {
    let sph = scene.spheres.first().ok_or_else(|| Error::Input("stress-horizon has no sphere".into()))?;
    let albedo = match sph.material {
        Material::Lambertian { albedo } => albedo,
        _ => return Err(Error::Input("stress-horizon's ground must be lambertian".into())),
    };
    let c = DVec3::from_array(sph.center.map(f64::from));
    let r = sph.radius as f64;
    let cam = &prep.camera;
    let e = DVec3::from_array(cam.center.map(f64::from));
    let to00 = DVec3::from_array(cam.to_pixel00.map(f64::from));
    let du = DVec3::from_array(cam.du.map(f64::from));
    let dv = DVec3::from_array(cam.dv.map(f64::from));
    // A pixel is ground when every ray through it (and through the pixel above) hits the sphere clearly.
    // "Clearly" = outside the kernel's rounding band (4x), for the f32 ray the camera makes.
    let clear_hit = |x: f64, y: f64| {
        let ray = RayF64::new(v32(e), dir32(to00 + du * x + dv * y));
        let tr = Truth::new(&ray, c, r);
        tr.required.is_some() && tr.disc > 4.0 * tr.e_disc
    };
    let sky = prep.sky;
    let a = 0.5 + 1.0 / 3.0;
    let want: [f64; 3] =
        std::array::from_fn(|ch| albedo[ch] as f64 * (sky.horizon[ch] as f64 * (1.0 - a) + sky.zenith[ch] as f64 * a));
    let mut rows: Vec<(u32, Vec<[f32; 3]>)> = Vec::new();
    for y in 0..img.height {
        let v: Vec<[f32; 3]> = (0..img.width)
            .filter(|&x| {
                let (x, y) = (x as f64, y as f64);
                [(-0.5, -1.5), (0.5, -1.5), (-0.5, 0.5), (0.5, 0.5)].iter().all(|(sx, sy)| clear_hit(x + sx, y + sy))
            })
            .map(|x| img.get(x, y))
            .collect();
        if !v.is_empty() {
            rows.push((y, v));
        }
    }
    let z = |px: &[[f32; 3]]| -> f64 {
        let n = px.len() as f64;
        if px.len() < 8 {
            return 0.0;
        }
        (0..3)
            .map(|ch| {
                let mean = px.iter().map(|p| p[ch] as f64).sum::<f64>() / n;
                let var = px.iter().map(|p| (p[ch] as f64 - mean).powi(2)).sum::<f64>() / (n - 1.0);
                let se = (var / n).sqrt();
                if se == 0.0 {
                    // Every pixel the same (a channel the sky does not vary in): equal up to summation rounding.
                    if (mean - want[ch]).abs() <= 1e-6 * want[ch].abs() {
                        0.0
                    } else {
                        f64::INFINITY
                    }
                } else {
                    ((mean - want[ch]) / se).abs()
                }
            })
            .fold(0.0, f64::max)
    };
    let all: Vec<[f32; 3]> = rows.iter().flat_map(|(_, v)| v.iter().copied()).collect();
    if all.len() < 32 {
        return Err(Error::Input("stress-horizon: too few ground pixels to test".into()));
    }
    let mut zmax = z(&all);
    let nb = rows.len().div_ceil(3).max(1);
    for band in rows.chunks(nb) {
        let v: Vec<[f32; 3]> = band.iter().flat_map(|(_, v)| v.iter().copied()).collect();
        zmax = zmax.max(z(&v));
    }
    let n = all.len() as f64;
    let mean: [f64; 3] = std::array::from_fn(|ch| all.iter().map(|p| p[ch] as f64).sum::<f64>() / n);
    Ok((zmax, all.len(), mean, want))
}

// ---------------------------------------------------------------------------
// The run.

/// Runs every sweep and scene; `progress` gets a line per finished part.
pub fn run(cfg: &Config, progress: &mut dyn FnMut(&str)) -> Result<Report> {
    let start = Instant::now();
    let sz = cfg.sizes();
    let mut rows = Vec::new();
    let mut checks = Vec::new();

    // 1. Intersection.
    let mut decades: Vec<Decade> = (-6..0).map(|e| Decade { ratio_exp: e, ..Decade::default() }).collect();
    let (mut mismatches, mut disc_ratio) = (0, 0.0f64);
    let sec = "intersection (1 sphere, f64 oracle)";
    for case in IsectCase::ALL {
        let out = isect_sweep(case, sz.groups, cfg.seed, &mut decades);
        mismatches += out.mismatches;
        disc_ratio = disc_ratio.max(out.max_disc_ratio);
        for (kernel, tally, gate) in [
            ("scalar", out.scalar, Gate::Full),
            ("simd", out.simd, Gate::Full),
            ("textbook", out.textbook, Gate::Reference),
        ] {
            rows.push(Row { section: sec, case: case.name().into(), kernel, tally, gate });
        }
        progress(&format!("intersection: {}", case.name()));
    }
    checks.push(Check::at_most(
        "intersection: scalar and 8-wide answers differ (lanes)",
        mismatches as f64,
        0.0,
        "index, t and disc compared bit for bit",
    ));
    checks.push(Check::at_most(
        "intersection: |disc error| / its bound, largest",
        disc_ratio,
        1.0,
        "the rounding band rests on this bound",
    ));

    // 2. Self-intersection.
    let sec = "self-intersection (1000 rays per hit point)";
    let mut below: [Tally; 3] = Default::default();
    for scatter in Scatter::ALL {
        let run1 = |imp| self_sweep(scatter, imp, &sz, cfg.seed, OffsetRule::Scaled(1.0));
        let s = run1(Impl::Kernel(KernelKind::Scalar));
        let v = run1(Impl::Kernel(KernelKind::Simd));
        let tb = run1(Impl::Textbook);
        checks.push(Check::at_most(
            format!("self-intersection, {}: scalar != simd", scatter.name()),
            (s.hash != v.hash) as u8 as f64,
            0.0,
            "every spawned ray, bit for bit",
        ));
        for (i, (kernel, out, gate)) in
            [("scalar", s, Gate::Full), ("simd", v, Gate::Full), ("textbook", tb, Gate::Reference)]
                .into_iter()
                .enumerate()
        {
            add(&mut below[i], &out.unresolved);
            rows.push(Row { section: sec, case: scatter.name().into(), kernel, tally: out.resolved, gate });
        }
        progress(&format!("self-intersection: {}", scatter.name()));
    }
    for (i, (kernel, gate)) in
        [("scalar", Gate::NoLeaks), ("simd", Gate::NoLeaks), ("textbook", Gate::Reference)].into_iter().enumerate()
    {
        rows.push(Row {
            section: sec,
            case: "below f32 resolution, all of the above".into(),
            kernel,
            tally: below[i].clone(),
            gate,
        });
    }
    let mut offset_scan = Vec::new();
    if sz.offset_scan {
        let rules: Vec<(String, OffsetRule)> = vec![
            ("16u (|r| + |p|_inf) / 16".into(), OffsetRule::Scaled(1.0 / 16.0)),
            ("16u (|r| + |p|_inf) / 8".into(), OffsetRule::Scaled(1.0 / 8.0)),
            ("16u (|r| + |p|_inf) / 4".into(), OffsetRule::Scaled(0.25)),
            ("16u (|r| + |p|_inf) / 2".into(), OffsetRule::Scaled(0.5)),
            ("16u (|r| + |p|_inf) (the kernels')".into(), OffsetRule::Scaled(1.0)),
            ("16u |r| only".into(), OffsetRule::Terms { kr: 16.0, kp: 0.0 }),
            ("16u |p|_inf only".into(), OffsetRule::Terms { kr: 0.0, kp: 16.0 }),
            ("u (9 |r| + 4 |p|_inf) (derived)".into(), OffsetRule::Terms { kr: 9.0, kp: 4.0 }),
        ];
        for (name, rule) in rules {
            let mut t = Tally::default();
            for scatter in Scatter::ALL {
                let s = self_sweep(scatter, Impl::Kernel(KernelKind::Scalar), &sz, cfg.seed, rule);
                add(&mut t, &s.resolved);
            }
            offset_scan.push(OffsetScan { rule: name, rays: t.rays, rehits: t.rehits, wrong: t.wrong });
        }
        progress("offset rules");
    }

    // 3. Scenes.
    let sec = "scenes (every ray vs f64 oracle)";
    let mut images: Vec<(String, Image)> = Vec::new();
    let stress_scenes =
        ["stress-final-small", "stress-final-large", "stress-horizon", "stress-tiny", "stress-far-camera"];
    for name in stress_scenes {
        let scene = preset(name)?;
        let spp = if name == "stress-horizon" { sz.horizon_spp } else { sz.spp };
        let st = settings(&scene, sz.width, sz.height, spp, cfg.seed);
        let prep = Prepared::new(&scene, st, AccelChoice::Brute)?;
        if prep.plan.mode != Mode::Path {
            return Err(Error::Input(format!("{name}: stress scenes must be path traced")));
        }
        let oracle = SceneOracle::new(&prep.spheres);
        let ts = trace_scalar(&prep, &oracle, None, false);
        let tv = trace_x8(&prep, &oracle);
        let tb = trace_scalar(&prep, &oracle, None, true);
        for (kernel, tr) in [(KernelKind::Scalar, &ts), (KernelKind::Simd, &tv)] {
            let r = render_with(&scene, st, kernel, cfg.threads)?;
            let mut tally = tr.tally.clone();
            tally.nan += r.stats.rejected_samples;
            checks.push(Check::at_most(
                format!("{name} [{}]: traced image != render() image", kernel.name()),
                (tr.image != r.image) as u8 as f64 + (tr.rays != r.stats.rays) as u8 as f64,
                0.0,
                "the instrumented loop is the kernel (image bits and ray count)",
            ));
            rows.push(Row { section: sec, case: name.into(), kernel: kernel.name(), tally, gate: Gate::Full });
            if kernel == KernelKind::Scalar {
                images.push((name.to_string(), r.image));
            }
        }
        let (mb, ms) = (mean_colour(&tb.image), mean_colour(&ts.image));
        // The textbook image's mean colour relative to the kernels' (same seed).
        let rel = (0..3).map(|ch| mb[ch] / ms[ch] - 1.0).sum::<f64>() / 3.0;
        rows.push(Row {
            section: sec,
            case: format!("{name} (mean {:+.1}%)", 100.0 * rel),
            kernel: "textbook",
            tally: tb.tally,
            gate: Gate::Reference,
        });
        checks.push(Check::at_most(
            format!("{name}: scalar and simd rays differ"),
            (ts.hash != tv.hash) as u8 as f64,
            0.0,
            "hash of every ray's origin, direction, hit and t",
        ));
        if name == "stress-horizon" {
            let (z, n, mean, want) = horizon_check(&scene, &prep, &ts.image)?;
            checks.push(Check::at_most(
                "stress-horizon: ground vs analytic colour, max |z|",
                z,
                Z_LIMIT,
                format!(
                    "{n} ground px, mean ({:.4} {:.4} {:.4}) vs ({:.4} {:.4} {:.4})",
                    mean[0], mean[1], mean[2], want[0], want[1], want[2]
                ),
            ));
        }
        if name == "stress-far-camera" {
            // The same rays, started 30 units before look_at instead of 1e5 away.
            let at = DVec3::from_array(scene.camera.look_at.map(f64::from));
            let shift = move |o: V3<f32>, d: V3<f32>| {
                let (o, dh) = (v64(o), v64(d).normalize());
                v32(o + dh * ((at - o).dot(dh) - 30.0))
            };
            let near = trace_scalar(&prep, &oracle, Some(&shift), false);
            let (zg, zb) = compare(&ts.image, &near.image, 8);
            checks.push(Check::at_most(
                "stress-far-camera vs same rays started near, max z",
                zg.max(zb),
                Z_LIMIT,
                format!("whole image {zg:.2}, 8x8 blocks {zb:.2}"),
            ));
        }
        progress(&format!("scene: {name}"));
    }
    // Scaled scenes against the unscaled ones.
    for (name, reference) in
        [("stress-final-small", "final"), ("stress-final-large", "final"), ("stress-tiny", "ch09-glass")]
    {
        let scene = preset(reference)?;
        let st = settings(&scene, sz.width, sz.height, sz.spp, cfg.seed);
        let r = render_with(&scene, st, KernelKind::Simd, cfg.threads)?;
        let img = images
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, i)| i)
            .ok_or_else(|| Error::Input(format!("stress: no image of {name}")))?;
        let (zg, zb) = compare(img, &r.image, 8);
        let (ma, mb) = (mean_colour(img), mean_colour(&r.image));
        checks.push(Check::at_most(
            format!("{name} vs {reference}, max z"),
            zg.max(zb),
            Z_LIMIT,
            format!(
                "whole {zg:.2}, blocks {zb:.2}; mean ({:.4} {:.4} {:.4}) vs ({:.4} {:.4} {:.4})",
                ma[0], ma[1], ma[2], mb[0], mb[1], mb[2]
            ),
        ));
    }
    // Every preset, both kernels: no sample rejected.
    let mut rejected = 0u64;
    let mut presets = 0;
    for p in scene::presets() {
        let scene = (p.build)();
        let st = settings(&scene, 32, 18, 2, cfg.seed);
        for kernel in [KernelKind::Scalar, KernelKind::Simd] {
            rejected += render_with(&scene, st, kernel, cfg.threads)?.stats.rejected_samples;
        }
        presets += 1;
    }
    checks.push(Check::at_most(
        format!("every preset ({presets}), both kernels: NaN/Inf samples rejected"),
        rejected as f64,
        0.0,
        "32x18, 2 spp",
    ));
    progress("presets");

    Ok(Report {
        quick: cfg.quick,
        seed: cfg.seed,
        isa: crate::isa(),
        rows,
        checks,
        decades,
        offset_scan,
        seconds: start.elapsed().as_secs_f64(),
    })
}
