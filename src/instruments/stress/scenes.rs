//! The scene checks: stress presets rendered by the real renderer (every
//! kernel and accelerator, with Russian roulette and adaptive sampling too)
//! under [`StressProbe`], every ray judged by the f64 oracle against every
//! sphere; and image comparisons (scaled scenes against the unscaled one, the
//! horizon against its analytic colour, the far camera against the same rays
//! started near the scene).

use super::oracle::*;
use super::report::Tally;
use super::sweeps::{add, classify_spawn};
use super::{dir32, finite3, v32, v64, Fnv};
use crate::choice::KernelChoice;
use crate::error::{Error, Result};
use crate::film::Image;
use crate::geometry::{Spheres, MISS};
use crate::job::{Job, Overrides, RenderOptions, DEFAULT_TILE};
use crate::plan::Prepared;
use crate::probe::{Lanes, Observed, PathEvents};
use crate::real::MAX_LANES;
use crate::render::{render, render_probed, Rendered};
use crate::scene::{self, Material, Scene, Texture};
use crate::vec3::V3;
use glam::DVec3;
use std::any::Any;
use std::collections::HashMap;

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

/// One ray as a kernel traced it: where it starts, where it goes, and the
/// closest hit the kernel found.
#[derive(Clone, Copy, Debug)]
struct TracedRay {
    /// The origin.
    o: V3<f32>,
    /// The direction.
    d: V3<f32>,
    /// The sphere hit, or [`MISS`].
    hit: u32,
    /// The distance to the hit, in lengths of `d`.
    t: f32,
}

/// Judges every ray of a scene against every sphere in f64.
pub(super) struct SceneOracle {
    c: Vec<DVec3>,
    r: Vec<f64>,
}

impl SceneOracle {
    pub(super) fn new(s: &Spheres) -> Self {
        SceneOracle {
            c: (0..s.len).map(|i| DVec3::new(s.cx[i] as f64, s.cy[i] as f64, s.cz[i] as f64)).collect(),
            r: (0..s.len).map(|i| s.r[i] as f64).collect(),
        }
    }

    /// Checks one traced ray: `traced.hit`/`traced.t` is the kernel's closest
    /// hit, `front` its front/back face there, `prev` the surface the ray left.
    fn check(&self, t: &mut Tally, traced: TracedRay, front: bool, prev: Option<Leaving>) {
        let TracedRay { o, d, hit, t: th } = traced;
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
        let mut verdict_k = HitVerdict::Wrong;
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
                HitVerdict::Wrong
            } else if any_in_band {
                HitVerdict::InBand
            } else {
                HitVerdict::Right
            }
        } else if verdict_k == HitVerdict::Wrong || best < th64 - (tol_k + best_tol) {
            HitVerdict::Wrong
        } else {
            verdict_k
        };
        match verdict {
            HitVerdict::Wrong => t.wrong += 1,
            HitVerdict::InBand => t.in_band += 1,
            HitVerdict::Right => {}
        }
        if let Some(tr) = truth_k {
            let c = self.c[hit as usize];
            let dist = ((ray.at(th64) - c).length() - tr.r).abs();
            t.err(dist, tr.r, Some(tr.dist_bound(th64)), verdict == HitVerdict::InBand);
            if verdict_k == HitVerdict::Right {
                if let Some(fo) = tr.nearest(th64).and_then(|i| tr.front_at(&ray, c, i)) {
                    if fo != front {
                        t.faces += 1;
                    }
                }
            }
        }
    }
}

/// A rewrite of camera ray origins (origin, direction) -> origin.
pub(super) type Shift = dyn Fn(V3<f32>, V3<f32>) -> V3<f32> + Sync;

/// The state of one path between its probe events.
#[derive(Default)]
struct PathLog {
    /// The surface the path's current ray left.
    prev: Option<Leaving>,
    /// A hit waiting for its shading (front face) to be judged.
    pending: Option<TracedRay>,
    /// Hash of every ray of the path (origin, direction, hit, t).
    hash: Fnv,
}

/// `rtow stress`'s probe: judges every ray a real render traces against the
/// f64 oracle, checks every spawned ray for a re-hit of the surface it left,
/// and hashes every ray path by path (so kernels and accelerators can be
/// compared ray for ray). Optionally moves camera rays along themselves (the
/// far camera's reference).
pub(super) struct StressProbe<'a> {
    oracle: &'a SceneOracle,
    shift: Option<&'a Shift>,
    paths: HashMap<(u32, u32), PathLog>,
    tally: Tally,
}

impl<'a> StressProbe<'a> {
    pub(super) fn new(oracle: &'a SceneOracle, shift: Option<&'a Shift>) -> Self {
        StressProbe { oracle, shift, paths: HashMap::new(), tally: Tally::default() }
    }
}

impl PathEvents for StressProbe<'_> {
    fn camera(&mut self, ids: &Lanes, o: &mut [V3<f32>; MAX_LANES], d: &[V3<f32>; MAX_LANES]) {
        if let Some(f) = self.shift {
            for k in 0..ids.n {
                o[k] = f(o[k], d[k]);
            }
        }
    }

    fn traced(
        &mut self,
        ids: &Lanes,
        o: &[V3<f32>; MAX_LANES],
        d: &[V3<f32>; MAX_LANES],
        hit: &[u32; MAX_LANES],
        t: &[f32; MAX_LANES],
    ) {
        for k in ids.live() {
            let key = (ids.pixel[k], ids.sample[k]);
            let ray = TracedRay { o: o[k], d: d[k], hit: hit[k], t: t[k] };
            let log = self.paths.entry(key).or_default();
            log.hash.v(ray.o);
            log.hash.v(ray.d);
            log.hash.u32(ray.hit);
            log.hash.f(ray.t);
            if ray.hit == MISS {
                self.oracle.check(&mut self.tally, ray, false, log.prev);
            } else {
                log.pending = Some(ray);
            }
        }
    }

    fn shaded(&mut self, ids: &Lanes, radius: &[f32; MAX_LANES], n: &[V3<f32>; MAX_LANES], front: u32) {
        for k in ids.live() {
            let key = (ids.pixel[k], ids.sample[k]);
            let log = self.paths.entry(key).or_default();
            let Some(ray) = log.pending.take() else {
                self.tally.wrong += 1; // a shading without its ray: the probe's events are out of order
                continue;
            };
            let f = front & (1 << k) != 0;
            self.oracle.check(&mut self.tally, ray, f, log.prev);
            log.prev = Some(Leaving::new(ray.hit, n[k], radius[k], f));
        }
    }

    fn finish(self: Box<Self>) -> Box<dyn Any + Send> {
        let paths: PathHashes = self.paths.into_iter().map(|(k, v)| (k, v.hash.value())).collect();
        Box::new((self.tally, paths))
    }
}

/// Each path's ray hash, by (pixel, sample).
type PathHashes = Vec<((u32, u32), u64)>;

/// What a probed render of a scene found.
pub(super) struct Traced {
    pub image: Image,
    pub tally: Tally,
    /// Hash of every ray, path by path in (pixel, sample) order.
    pub hash: u64,
    pub rays: u64,
    pub rejected: u64,
}

/// Renders `job` with the real renderer and the stress probe.
pub(super) fn trace(job: &Job, oracle: &SceneOracle, shift: Option<&Shift>) -> Result<Traced> {
    let (r, probes) = render_probed(job, None, &|| Observed::with(StressProbe::new(oracle, shift)))?;
    let mut tally = Tally::default();
    let mut paths: Vec<((u32, u32), u64)> = Vec::new();
    for p in probes {
        let (t, p): (Tally, PathHashes) = p.finish();
        add(&mut tally, &t);
        paths.extend(p);
    }
    paths.sort_unstable();
    let mut h = Fnv::new();
    for (_, ph) in paths {
        h.u32((ph >> 32) as u32);
        h.u32(ph as u32);
    }
    Ok(Traced { image: r.image, tally, hash: h.value(), rays: r.stats.rays, rejected: r.stats.rejected_samples })
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
pub(super) fn compare(a: &Image, b: &Image, block: u32) -> (f64, f64) {
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

pub(super) fn mean_colour(img: &Image) -> [f64; 3] {
    let n = img.data.len().max(1) as f64;
    let mut m = [0.0; 3];
    for p in &img.data {
        for c in 0..3 {
            m[c] += p[c] as f64 / n;
        }
    }
    m
}

pub(super) fn preset(name: &str) -> Result<Scene> {
    scene::preset(name).ok_or_else(|| Error::Input(format!("stress: preset '{name}' is missing")))
}

/// A stress render's size, samples and seed (the scene's depth and sampler).
pub(super) fn settings(w: u32, h: u32, spp: u32, seed: u64) -> Overrides {
    Overrides { width: Some(w), height: Some(h), spp: Some(spp), seed: Some(seed), ..Overrides::default() }
}

pub(super) fn render_with(
    scene: &Scene,
    o: &Overrides,
    kernel: KernelChoice,
    threads: Option<usize>,
) -> Result<Rendered> {
    let opts = RenderOptions { kernel, threads, tile: DEFAULT_TILE, ..RenderOptions::default() };
    render(&Job::new(scene, o, &opts)?, None)
}

/// The horizon scene's ground against its analytic colour: a lambertian
/// sphere seen from just above is a plane to the camera, and every point of a
/// convex diffuse surface under this sky has the expected colour
/// `albedo (horizon (1 - a) + zenith a)`, `a = 1/2 + n.y / 3` (the cosine-weighted
/// mean of `d.y` is `2/3 n.y`; scattered rays leave a convex sphere for good).
/// Returns max |z| over the ground pixels, whole and in three row bands.
pub(super) fn horizon_check(scene: &Scene, prep: &Prepared, img: &Image) -> Result<(f64, usize, [f64; 3], [f64; 3])> {
    let sph = scene.spheres.first().ok_or_else(|| Error::Input("stress-horizon has no sphere".into()))?;
    let albedo = match sph.material {
        Material::Lambertian { albedo: Texture::Solid(albedo) } => albedo,
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
