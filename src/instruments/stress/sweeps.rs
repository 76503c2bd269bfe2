//! The sweeps: rays against one sphere, judged by the f64 oracle.
//!
//! 1. **Intersection.** Radius and distance over 1e-4 .. 1e6, grazing rays,
//!    origins on the surface, inside and at the centre, negative radii; each
//!    group of 8 rays through `closest_brute` at one lane and at 8.
//! 2. **Self-intersection.** Hit points on spheres of radius 10^U(-4,4), rays
//!    scattered from each by every material (and synthetic grazing
//!    directions), spawned with `spawn` and intersected again, by the same
//!    generic function at one lane and at 8.

use super::oracle::*;
use super::report::{Decade, Tally};
use super::{dir32, finite3, v32, v64, Fnv, Gen, Sizes, StressConfig};
use crate::geometry::{closest_brute, spawn, sphere_disc, surface, Spheres, Surface, MISS};
use crate::material::{dielectric, lambertian, metal};
use crate::real::Real;
use crate::sampling::{mix64, path_state, ScalarStream, Stream, XoshiroLanes};
use crate::vec3::V3;
use glam::DVec3;
use wide::{f32x8, u32x8};

fn splat8(v: V3<f32>) -> V3<f32x8> {
    V3::splat3(v.to_array())
}

fn pack8(v: &[V3<f32>; 8]) -> V3<f32x8> {
    V3::new(f32x8::new(v.map(|a| a.x)), f32x8::new(v.map(|a| a.y)), f32x8::new(v.map(|a| a.z)))
}

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

/// What the f64 oracle knows of one ray of a group: the ray, the sphere's
/// centre, and the exact answer an implementation's is judged against.
struct RayOracle {
    /// The ray, in f64 on its f32 inputs.
    ray: RayF64,
    /// The sphere's centre.
    c: DVec3,
    /// The exact answer for the ray against the sphere.
    truth: Truth,
}

/// One implementation's answer for a ray: hit or miss, where, and which face.
#[derive(Clone, Copy, Debug)]
struct Answer {
    /// A hit was reported.
    hit: bool,
    /// The distance to the hit, in lengths of the ray's direction.
    t: f32,
    /// The hit was called a front face.
    front: bool,
}

/// Judges `answer` against `oracle` into `t`; `gated`: also records the hit
/// point's error over its bound (the kernels' tests, not the textbook's).
fn record_hit(t: &mut Tally, oracle: &RayOracle, answer: Answer, gated: bool) {
    let (tr, ray, c) = (&oracle.truth, &oracle.ray, oracle.c);
    let Answer { hit, t: tk, front } = answer;
    t.rays += 1;
    if hit && !tk.is_finite() {
        t.nan += 1;
        return;
    }
    let v = tr.judge(hit, tk as f64);
    match v {
        HitVerdict::Wrong => t.wrong += 1,
        HitVerdict::InBand => t.in_band += 1,
        HitVerdict::Right => {}
    }
    if hit {
        let dist = ((ray.at(tk as f64) - c).length() - tr.r).abs();
        t.err(dist, tr.r, gated.then(|| tr.dist_bound(tk as f64)), v == HitVerdict::InBand);
        if v == HitVerdict::Right {
            if let Some(fo) = tr.nearest(tk as f64).and_then(|i| tr.front_at(ray, c, i)) {
                if fo != front {
                    t.faces += 1;
                }
            }
        }
    }
}

/// Runs one group through `closest_brute` and `sphere_disc` at one and 8 lanes
/// (both widths) and the textbook test, and judges every answer.
pub fn check_group(grp: &Group, spheres: &mut Spheres) -> GroupResult {
    let mut res = GroupResult::default();
    spheres.set(0, grp.c.to_array(), grp.r);
    let r2 = grp.r * grp.r;
    let (o8, d8) = (pack8(&grp.o), pack8(&grp.d));
    let c8 = splat8(grp.c);
    let (hit8, t8): (u32x8, f32x8) = closest_brute(spheres, o8, d8, f32x8::splat(0.0), &mut ());
    let (disc8, _, _) = sphere_disc(o8, d8, c8, f32x8::splat(r2));
    let front8 = surface(o8, d8, t8, c8, f32x8::splat(grp.r)).front.to_bitmask();
    let (hit8, t8, disc8) = (hit8.to_array(), t8.to_array(), disc8.to_array());
    let c64 = v64(grp.c);
    for k in 0..8 {
        let (o, d) = (grp.o[k], grp.d[k]);
        let (hs, ts) = closest_brute(spheres, o, d, 0.0, &mut ());
        let (disc, _, _) = sphere_disc(o, d, grp.c, r2);
        if hs != hit8[k] || ts.to_bits() != t8[k].to_bits() || disc.to_bits() != disc8[k].to_bits() {
            res.mismatches += 1;
        }
        let ray = RayF64::new(o, d);
        let tr = Truth::new(&ray, c64, grp.r as f64);
        res.max_disc_ratio = res.max_disc_ratio.max((disc as f64 - tr.disc).abs() / tr.e_disc);
        let oracle = RayOracle { ray, c: c64, truth: tr };
        let fs = hs != MISS && surface(o, d, ts, grp.c, grp.r).front;
        record_hit(&mut res.scalar, &oracle, Answer { hit: hs != MISS, t: ts, front: fs }, true);
        let f8 = front8 & (1 << k) != 0;
        record_hit(&mut res.simd, &oracle, Answer { hit: hit8[k] != MISS, t: t8[k], front: f8 }, true);
        let tb = textbook_hit(o, d, grp.c, grp.r, TEXTBOOK_T_MIN);
        let tt = tb.unwrap_or(f32::INFINITY);
        let ftb = tb.is_some() && d.dot((ray_point32(o, d, tt) - grp.c) * (1.0 / grp.r)) < 0.0;
        record_hit(&mut res.textbook, &oracle, Answer { hit: tb.is_some(), t: tt, front: ftb }, false);
    }
    res
}

fn ray_point32(o: V3<f32>, d: V3<f32>, t: f32) -> V3<f32> {
    o + d * t
}

pub(super) fn add(a: &mut Tally, b: &Tally) {
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

pub(super) struct IsectOut {
    pub(super) scalar: Tally,
    pub(super) simd: Tally,
    pub(super) textbook: Tally,
    pub(super) mismatches: u64,
    pub(super) max_disc_ratio: f64,
}

pub(super) fn isect_sweep(case: IsectCase, groups: usize, seed: u64, decades: &mut [Decade]) -> IsectOut {
    let mut g = Gen::new(seed, 100 + case as u64);
    let mut sph = Spheres::one([0.0; 3], 1.0);
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
pub(super) enum Impl {
    Scalar,
    Simd,
    Textbook,
}

/// The offset a spawned ray gets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum OffsetRule {
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
pub(super) fn classify_spawn(t: &mut Tally, m: DVec3, r_abs: f64, dir: V3<f32>, hit: bool, th: f32) {
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

fn apply_offset<R: Real>(srf: &mut Surface<R>, r: f32, rule: OffsetRule) {
    srf.offset = match rule {
        OffsetRule::Scaled(k) => srf.offset * R::splat(k),
        OffsetRule::Terms { kr, kp } => {
            (R::splat(r.abs() * kr) + srf.p.max_abs() * R::splat(kp)) * R::splat(1.0 / 16_777_216.0)
        }
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

pub(super) struct SelfOut {
    /// Hit points where the kernels' offset is at most |r|, and the others
    /// (below f32 resolution: see `geometry::surface`, "the rule has a floor").
    pub resolved: Tally,
    pub unresolved: Tally,
    pub hash: u64,
}

/// Lane widths the kernel sweep runs at: the kernels' own functions, at one
/// lane (`f32`) or eight (`f32x8`).
trait SweepLanes: Real {
    type S: Stream<Self>;
    /// The scatter streams of rays `j0..j0 + LANES` of hit point `k`.
    fn streams(seed: u64, k: usize, j0: usize) -> Self::S;
}

impl SweepLanes for f32 {
    type S = ScalarStream;
    fn streams(seed: u64, k: usize, j0: usize) -> ScalarStream {
        ScalarStream::for_path(seed, k as u64, j0 as u64)
    }
}

impl SweepLanes for f32x8 {
    type S = XoshiroLanes<u32x8>;
    fn streams(seed: u64, k: usize, j0: usize) -> Self::S {
        let st: [[u32; 4]; 8] = std::array::from_fn(|l| path_state(seed, k as u64, (j0 + l) as u64));
        XoshiroLanes { s: std::array::from_fn(|w| u32x8::new(std::array::from_fn(|l| st[l][w]))) }
    }
}

pub(super) fn self_sweep(scatter: Scatter, imp: Impl, sizes: &Sizes, seed: u64, rule: OffsetRule) -> SelfOut {
    match imp {
        Impl::Scalar => kernel_sweep::<f32>(scatter, sizes, seed, rule),
        Impl::Simd => kernel_sweep::<f32x8>(scatter, sizes, seed, rule),
        Impl::Textbook => textbook_sweep(scatter, sizes, seed),
    }
}

/// Hit points on one sphere, and rays scattered from each by the kernels'
/// functions (`closest_brute`, `surface`, `spawn`, the materials) at width `R`,
/// `R::LANES` rays at a time.
fn kernel_sweep<R: SweepLanes>(scatter: Scatter, sizes: &Sizes, seed: u64, rule: OffsetRule) -> SelfOut {
    let mut g = Gen::new(seed, 200 + scatter as u64);
    let mut sph = Spheres::one([0.0; 3], 1.0);
    let mut ts = [Tally::default(), Tally::default()];
    let mut h = Fnv::new();
    let stream_seed = mix64(seed ^ 0x5e1f);
    let v = |x: V3<f32>| V3::<R>::splat3(x.to_array());
    for k in 0..sizes.hit_points {
        let hs = gen_hit(&mut g, scatter);
        let mut dirs = Gen::new(seed ^ 0xd1, (scatter as u64) << 32 | k as u64);
        sph.set(0, hs.c.to_array(), hs.r);
        let c64 = v64(hs.c);
        let r_abs = hs.r.abs() as f64;
        let (hit, th) = closest_brute(&sph, v(hs.o), v(hs.d), R::splat(0.0), &mut ());
        let (hit, th) = (R::lane_u(hit, 0), th.lane(0));
        if hit == MISS {
            // No hit point to start from; a miss the oracle calls wrong is counted.
            let ray = RayF64::new(hs.o, hs.d);
            let resolved = kernel_offset(r_abs, c64) <= r_abs;
            if Truth::new(&ray, c64, hs.r as f64).judge(false, 0.0) == HitVerdict::Wrong {
                ts[!resolved as usize].wrong += 1;
            }
            continue;
        }
        let mut srf = surface(v(hs.o), v(hs.d), R::splat(th), v(hs.c), R::splat(hs.r));
        let (p0, n0) = (srf.p.lane(0), srf.n.lane(0));
        let p = v64(p0);
        let t = &mut ts[!(kernel_offset(r_abs, p) <= r_abs) as usize];
        if !(finite3(p0) && finite3(n0) && srf.offset.lane(0).is_finite()) {
            t.nan += 1;
            continue;
        }
        apply_offset(&mut srf, hs.r, rule);
        t.err(((p - c64).length() - r_abs).abs(), r_abs, Some(reprojection_bound(r_abs, p)), false);
        let front = R::mask_bits(srf.front) & 1 != 0;
        let sigma = hs.r.signum() as f64 * if front { 1.0 } else { -1.0 };
        let m = (v64(n0) * sigma).normalize();
        for j0 in (0..sizes.per_point).step_by(R::LANES) {
            let n = (sizes.per_point - j0).min(R::LANES);
            let (dir, alive) = if scatter == Scatter::Grazing {
                let d: Vec<V3<f32>> = (0..n).map(|_| grazing_dir(&mut dirs, n0)).collect();
                let pick = |f: fn(&V3<f32>) -> f32| R::from_fn(|l| f(&d[l.min(n - 1)]));
                (V3::new(pick(|a| a.x), pick(|a| a.y), pick(|a| a.z)), u32::MAX)
            } else {
                let mut rng = R::streams(stream_seed, k, j0);
                let (d, a) = scatter_dir(scatter, v(hs.d), &srf, hs.fuzz, hs.ior, &mut rng);
                (d, R::mask_bits(a))
            };
            let o2 = spawn(&srf, dir);
            let (i2, t2) = closest_brute(&sph, o2, dir, R::splat(0.0), &mut ());
            for l in (0..n).filter(|l| alive & (1 << l) != 0) {
                let dl = dir.lane(l);
                if !finite3(dl) {
                    t.nan += 1;
                    continue;
                }
                let (i2, t2) = (R::lane_u(i2, l), t2.lane(l));
                h.v(o2.lane(l));
                h.v(dl);
                h.u32(i2);
                h.f(t2);
                classify_spawn(t, m, r_abs, dl, i2 != MISS, t2);
            }
        }
    }
    let [resolved, unresolved] = ts;
    SelfOut { resolved, unresolved, hash: h.value() }
}

/// The book's way, as a reference: `p = o + t d`, `n = (p - c) / r`, the next
/// ray starts at `p`, the textbook test with `t_min = 0.001`.
fn textbook_sweep(scatter: Scatter, sizes: &Sizes, seed: u64) -> SelfOut {
    let mut g = Gen::new(seed, 200 + scatter as u64);
    let mut ts = [Tally::default(), Tally::default()];
    let stream_seed = mix64(seed ^ 0x5e1f);
    for k in 0..sizes.hit_points {
        let hs = gen_hit(&mut g, scatter);
        let mut dirs = Gen::new(seed ^ 0xd1, (scatter as u64) << 32 | k as u64);
        let c64 = v64(hs.c);
        let r_abs = hs.r.abs() as f64;
        let Some(th) = textbook_hit(hs.o, hs.d, hs.c, hs.r, TEXTBOOK_T_MIN) else {
            continue;
        };
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
    let [resolved, unresolved] = ts;
    SelfOut { resolved, unresolved, hash: 0 }
}

/// The self-intersection sweep (scalar kernel, every scatter, resolvable hit
/// points) with the kernels' offset multiplied by `scale`: `(rays, re-hits,
/// entering rays short of the far wall)`. At `scale = 1`, the kernels' behaviour.
pub fn offset_rehits(scale: f32, hit_points: usize, seed: u64) -> (u64, u64, u64) {
    let sizes = Sizes { hit_points, ..StressConfig { quick: true, seed, threads: None }.sizes() };
    let mut t = Tally::default();
    for scatter in Scatter::ALL {
        let out = self_sweep(scatter, Impl::Scalar, &sizes, seed, OffsetRule::Scaled(scale));
        add(&mut t, &out.resolved);
    }
    (t.rays, t.rehits, t.wrong)
}
