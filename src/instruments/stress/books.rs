//! `rtow stress`'s families for The Next Week and The Rest of Your Life: the
//! numerics of lights, quads, boxes, emitters and media at scales the books
//! never use, each against an oracle (a closed form, an f64 test, or an
//! identity), each printing its measured worst case beside its bound.
//!
//! - **small lights**: a sphere or square light over a diffuse floor, its
//!   size swept over five decades at constant power, under `bsdf`, `book`
//!   and `nee-mis`: the floor's radiance against its closed form (a sphere:
//!   `albedo L (r / D)^2 cos`; a square: the parallel-rectangle view factor),
//!   as a z-score;
//! - **furnaces with tiny `sample_toward` shapes**: a white sphere under a
//!   uniform sky, the `book` mixture aimed at a sphere or quad of 1e-2 down
//!   to 1e-5: exactly the albedo, as a z-score;
//! - **quad and box scale**: quads and turned boxes from `1e-6` to `1e6` in
//!   a scene whose extent is `1e6`: hit, miss and `t` of the f32 tests
//!   against f64, and how far outside the shape a hit is accepted, over its
//!   size;
//! - **emitter magnitude**: a light from `1e-30` to f32's largest, seen
//!   directly and on a floor: the image is the emission, no sample dropped;
//! - **media density**: `-0.0` renders as `0.0`, bit for bit; subnormal,
//!   tiny and huge densities render finite, with no sample dropped.

use super::report::Check;
use super::scenes::render_with;
use super::{Gen, Parts, StressConfig};
use crate::choice::{EstimatorChoice, KernelChoice};
use crate::error::Result;
use crate::film::Image;
use crate::geometry::{Closest, Cuboids, Primitive, Quads, MISS, QUAD_BASE};
use crate::handle::Kind;
use crate::job::{Job, Overrides, RenderOptions};
use crate::scene::{Background, Camera, Material, Medium, MediumBoundary, Mode, Quad, Scene, Shape, Sky, Sphere};
use crate::vec3::V3;
use glam::DVec3;
use std::f64::consts::PI;

/// The film's resolution, a sample (`2^-32`, docs/stability.md).
const RESOLUTION: f64 = 1.0 / 4_294_967_296.0;

/// The bound on a z-score of a mean against its oracle.
const Z_BOUND: f64 = super::Z_LIMIT;

fn scene(camera: Camera, background: [f32; 3]) -> Scene {
    Scene {
        mode: Mode::Path,
        camera,
        spheres: vec![],
        quads: vec![],
        boxes: vec![],
        groups: vec![],
        media: vec![],
        meshes: vec![],
        sky: Sky::default(),
        background: Background::Constant(background),
        sample_toward: vec![],
        render: Default::default(),
    }
}

fn lambertian(a: f32) -> Material {
    Material::Lambertian { albedo: [a; 3].into() }
}

fn light(l: f32) -> Material {
    Material::DiffuseLight { emit: [l; 3], one_sided: false }
}

fn overrides(w: u32, spp: u32, seed: u64, estimator: EstimatorChoice, depth: u32) -> Overrides {
    Overrides {
        width: Some(w),
        height: Some(w),
        spp: Some(spp),
        seed: Some(seed),
        max_depth: Some(depth),
        estimator: Some(estimator),
        ..Overrides::default()
    }
}

/// The estimators' own rounding, relative: f32 arithmetic on every sample
/// (directions, densities, weights) leaves the mean off by up to a few
/// `1e-6` whatever the number of samples (measured: 3e-6 on a furnace whose
/// Sobol-sampled pixels converge to 1e-7); a z-score counts only what lies
/// beyond it.
const REL: f64 = 1e-5;

/// The z-score of the pixels' mean against the per-pixel expectations
/// `want` (channel 0; the scenes are grey) beyond [`REL`], its standard
/// error from the pixels' spread, or at least `floor_se` (a noise bound
/// known in closed form, for estimators whose rare large samples a small
/// run may not see); and the mean's ratio to the expected mean.
fn z_score(img: &Image, want: &[f64], floor_se: f64) -> (f64, f64) {
    let n = img.data.len() as f64;
    let d: Vec<f64> = img.data.iter().zip(want).map(|(p, w)| p[0] as f64 - w).collect();
    let mean = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let se = (var / n).sqrt().max(floor_se);
    let want_mean = want.iter().sum::<f64>() / n;
    let ratio = (mean + want_mean) / want_mean;
    let beyond = (mean.abs() - REL * want_mean).max(0.0);
    if beyond == 0.0 {
        return (0.0, ratio);
    }
    (if se == 0.0 { f64::INFINITY } else { beyond / se }, ratio)
}

/// Where the camera rays through each pixel meet the plane `y = 0` (row by
/// row, as the image stores them): 4 x 4 points spread over the pixel, whose
/// average of a smooth function is the pixel's mean to about `1e-6` here.
fn floor_points(job: &Job) -> Vec<[DVec3; 16]> {
    let cam = &job.prepared().camera;
    let f = |a: [f32; 3]| DVec3::from_array(a.map(f64::from));
    let (e, to00, du, dv) = (f(cam.center), f(cam.to_pixel00), f(cam.du), f(cam.dv));
    let s = job.settings();
    let mut v = Vec::new();
    for y in 0..s.height {
        for x in 0..s.width {
            v.push(std::array::from_fn(|k| {
                let (sx, sy) = ((k % 4) as f64 * 0.25 - 0.375, (k / 4) as f64 * 0.25 - 0.375);
                let d = to00 + du * (x as f64 + sx) + dv * (y as f64 + sy);
                e + d * (-e.y / d.y)
            }));
        }
    }
    v
}

/// The view factor from a floor point to the rectangle `[x0, x1] x [z0,
/// z1]` at height `h` above it, parallel to the floor (`F(X, Y)` of a
/// corner, by inclusion and exclusion; `F` is odd in both).
fn rectangle_factor(p: DVec3, x: [f64; 2], z: [f64; 2], h: f64) -> f64 {
    let f = |a: f64, b: f64| {
        let (xx, yy) = (a / h, b / h);
        let (sx, sy) = ((1.0 + xx * xx).sqrt(), (1.0 + yy * yy).sqrt());
        (xx / sx * (yy / sx).atan() + yy / sy * (xx / sy).atan()) / (2.0 * PI)
    };
    f(x[1] - p.x, z[1] - p.z) - f(x[0] - p.x, z[1] - p.z) - f(x[1] - p.x, z[0] - p.z) + f(x[0] - p.x, z[0] - p.z)
}

/// Family 1: the lights' height above the floor.
const LIGHT_HEIGHT: f64 = 1.0;

/// Family 1: the floor's albedo.
const FLOOR_ALBEDO: f32 = 0.5;

/// Family 1: small lights at constant power over a floor.
pub(super) fn small_lights(cfg: &StressConfig, out: &mut Parts, progress: &mut dyn FnMut(&str)) -> Result<()> {
    let (w, spp) = if cfg.quick { (8, 64) } else { (16, 1024) };
    let estimators = [EstimatorChoice::Bsdf, EstimatorChoice::Book, EstimatorChoice::NeeMis];
    let mut rejected = 0u64;
    for shape in ["sphere", "square"] {
        for est in estimators {
            let o = overrides(w, spp, cfg.seed, est, 4);
            out.checks.push(small_light_check(shape, est, &o, &mut rejected)?);
            progress(&format!("small lights: {shape}, {}", est.name()));
        }
    }
    out.checks.push(Check::at_most(
        "small lights: samples rejected",
        rejected as f64,
        0.0,
        "emission up to 1e10 at constant power",
    ));
    Ok(())
}

/// One check of family 1: a `shape` light at every size, rendered with `o`
/// under `est`, its floor's largest z-score against the closed form; adds the
/// renders' rejected samples to `rejected`.
fn small_light_check(shape: &'static str, est: EstimatorChoice, o: &Overrides, rejected: &mut u64) -> Result<Check> {
    let (mut zmax, mut worst) = (0.0f64, 1.0f64);
    let mut line = String::new();
    for e in 1..=5 {
        let size = 10f64.powi(-e);
        // Constant power: L size^2 = h^2.
        let light = SmallLight { shape, size, emit: (LIGHT_HEIGHT / size).powi(2) };
        let (z, ratio) = light.score(est, o, rejected)?;
        if z > zmax {
            zmax = z;
        }
        if (ratio - 1.0).abs() > (worst - 1.0).abs() {
            worst = ratio;
        }
        line.push_str(&format!(" 1e-{e}: {ratio:.6}"));
    }
    Ok(Check::at_most(
        format!(
            "small lights: {shape} light, r/d 1e-1..1e-5, {}: floor vs closed form, max |z| beyond 1e-5",
            est.name()
        ),
        zmax,
        Z_BOUND,
        format!("image / closed form at size{line}"),
    ))
}

/// A light of family 1 at one size, [`LIGHT_HEIGHT`] above the floor's centre.
struct SmallLight {
    /// `"sphere"` or `"square"`.
    shape: &'static str,
    /// The sphere's radius or the square's edge.
    size: f64,
    /// Its emitted radiance, `(h / size)^2`: the same power at every size.
    emit: f64,
}

impl SmallLight {
    /// The light over a wide diffuse floor, in the dark, seen from above.
    fn scene(&self) -> Scene {
        let (h, l) = (LIGHT_HEIGHT, self.emit);
        let mut sc = scene(Camera::looking([0.0, 1.5, 3.0], [0.0, 0.0, 0.0], 0.4), [0.0; 3]);
        sc.quads.push(Quad {
            q: [-100.0, 0.0, -100.0],
            u: [0.0, 0.0, 200.0],
            v: [200.0, 0.0, 0.0],
            material: lambertian(FLOOR_ALBEDO),
        });
        if self.shape == "sphere" {
            sc.spheres.push(Sphere {
                center: [0.0, h as f32, 0.0],
                center1: None,
                radius: self.size as f32,
                material: light(l as f32),
            });
        } else {
            let s = self.size as f32;
            sc.quads.push(Quad {
                q: [-s / 2.0, h as f32, -s / 2.0],
                u: [s, 0.0, 0.0],
                v: [0.0, 0.0, s],
                material: light(l as f32),
            });
        }
        sc
    }

    /// The floor's radiance at `p` in closed form (a sphere: `albedo L (r /
    /// D)^2 cos`; a square: the parallel-rectangle view factor).
    fn floor_radiance(&self, p: &DVec3) -> f64 {
        let h = LIGHT_HEIGHT;
        let (ls, r) = (self.emit * FLOOR_ALBEDO as f64, self.size);
        if self.shape == "sphere" {
            let dd = DVec3::new(-p.x, h, -p.z).length();
            ls * (r / dd).powi(2) * (h / dd)
        } else {
            let half = self.size / 2.0;
            ls * rectangle_factor(*p, [-half, half], [-half, half], h)
        }
    }

    /// Renders the light's scene with `o` under `est` and scores its floor
    /// against [`Self::floor_radiance`]: [`z_score`]'s `(z, ratio)`; adds the
    /// render's rejected samples to `rejected`.
    fn score(&self, est: EstimatorChoice, o: &Overrides, rejected: &mut u64) -> Result<(f64, f64)> {
        let job = Job::new(&self.scene(), o, &RenderOptions::default())?;
        let want: Vec<f64> =
            floor_points(&job).iter().map(|ps| ps.iter().map(|p| self.floor_radiance(p)).sum::<f64>() / 16.0).collect();
        let r = crate::render::render(&job, None)?;
        *rejected += r.stats.rejected_samples;
        // bsdf finds the light by chance: the noise of a sample that
        // is `albedo L` with probability `mean / (albedo L)`.
        let n = r.stats.samples as f64;
        let mean_want = want.iter().sum::<f64>() / want.len() as f64;
        let floor_se = match est {
            EstimatorChoice::Bsdf => (mean_want * FLOOR_ALBEDO as f64 * self.emit / n).sqrt(),
            _ => 0.0,
        };
        Ok(z_score(&r.image, &want, floor_se))
    }
}

/// Family 2: a white furnace whose `book` mixture samples toward tiny shapes.
pub(super) fn furnaces(cfg: &StressConfig, out: &mut Parts, progress: &mut dyn FnMut(&str)) -> Result<()> {
    let (w, spp) = if cfg.quick { (8, 64) } else { (16, 512) };
    let albedo = 0.8f32;
    for kind in ["sphere", "quad"] {
        let (mut zmax, mut line) = (0.0f64, String::new());
        // Down to the smallest radius and edge validation accepts (1e-5).
        for e in [2, 3, 4, 5] {
            let size = 10f32.powi(-e);
            let mut sc = scene(Camera::looking([0.0, 0.0, 4.0], [0.0, 0.0, 0.0], 10.0), [1.0; 3]);
            sc.spheres.push(Sphere { center: [0.0; 3], center1: None, radius: 1.0, material: lambertian(albedo) });
            sc.sample_toward.push(match kind {
                "sphere" => Shape::Sphere { center: [0.3, 3.0, 2.0], radius: size },
                _ => Shape::Quad { q: [0.3, 3.0, 2.0], u: [size, 0.0, 0.0], v: [0.0, size, size] },
            });
            let job = Job::new(&sc, &overrides(w, spp, cfg.seed, EstimatorChoice::Book, 8), &RenderOptions::default())?;
            let r = crate::render::render(&job, None)?;
            let want = vec![albedo as f64; r.image.data.len()];
            let (z, ratio) = z_score(&r.image, &want, 0.0);
            zmax = zmax.max(z);
            line.push_str(&format!(" 1e-{e}: {ratio:.6}"));
        }
        out.checks.push(Check::at_most(
            format!("furnace: book toward a tiny {kind} (1e-2..1e-5, 3.6 away), max |z| beyond 1e-5"),
            zmax,
            Z_BOUND,
            format!("image / albedo at size{line}"),
        ));
        progress(&format!("furnace: {kind}"));
    }
    Ok(())
}

/// The exact answer for a ray against a parallelogram, in f64 on the f32
/// inputs: `(t, a, b)`, or `None` for a ray parallel to its plane.
fn quad_oracle(o: DVec3, d: DVec3, q: DVec3, u: DVec3, v: DVec3) -> Option<(f64, f64, f64)> {
    let n = u.cross(v);
    let nd = n.dot(d);
    if nd == 0.0 {
        return None;
    }
    let t = n.dot(q - o) / nd;
    let p = o + d * t - q;
    let w = n / n.dot(n);
    Some((t, w.dot(p.cross(v)), w.dot(u.cross(p))))
}

fn f3(v: DVec3) -> [f32; 3] {
    v.to_array().map(|x| x as f32)
}

fn d3(v: [f32; 3]) -> DVec3 {
    DVec3::from_array(v.map(f64::from))
}

/// Family 3: the extent of the scene the quads are built for.
const SCALE_EXTENT: f32 = 1e6;

/// What family 3 counted, over every size.
#[derive(Default)]
struct ScaleTally {
    /// Rays judged against f64.
    tested: u64,
    /// Hits and misses the f64 test contradicts, clear of the ray's band.
    wrong: u64,
    /// Hits whose `t` is off the f64 `t` by more than 1e-4 relative.
    t_bad: u64,
    /// Rays from inside a box that hit none of its faces.
    leaks: u64,
    /// The largest distance outside a quad at which a hit was accepted, over the quad's size.
    grow_near: f64,
    /// The same over the ray's band.
    band_ratio: f64,
    /// That largest distance over the size at every third decade, for the check's note.
    line: String,
}

/// Family 3: quads and boxes from 1e-6 to 1e6 in a scene of extent 1e6.
pub(super) fn quad_scale(cfg: &StressConfig, out: &mut Parts, progress: &mut dyn FnMut(&str)) -> Result<()> {
    let rays = if cfg.quick { 200 } else { 4000 };
    let mut g = Gen::new(cfg.seed, 0x9ad5);
    let mut tally = ScaleTally::default();
    for e in -6..=6 {
        let s = 10f64.powi(e);
        let mut grow_decade = 0.0f64;
        for _ in 0..rays {
            if let Some(grow) = quad_ray(&mut g, s, &mut tally) {
                grow_decade = grow_decade.max(grow);
            }
        }
        tally.grow_near = tally.grow_near.max(grow_decade);
        if e % 3 == 0 {
            tally.line.push_str(&format!(" 1e{e}: {grow_decade:.1e}"));
        }
        // Boxes: turned cuboids of size s, rays from inside at edges and
        // corners (never a leak) and from outside (hit where the f64 slab
        // test says, clear of the edges).
        for _ in 0..rays / 4 {
            let c = random_box(&mut g, s);
            box_ray_from_inside(&mut g, &c, &mut tally);
            box_rays_from_outside(&mut g, &c, &mut tally);
        }
        progress(&format!("quad and box scale: 1e{e}"));
    }
    quad_scale_checks(&tally, out);
    Ok(())
}

/// A parallelogram `q + a u + b v`, `a` and `b` in `[0, 1]`, with f32 corners.
#[derive(Clone, Copy, Debug)]
struct Parallelogram {
    q: DVec3,
    u: DVec3,
    v: DVec3,
}

/// A quad of size about `s`, 10 s from the origin (at most 1e5), turned at
/// random; `None` when it came out too thin to test.
fn random_quad(g: &mut Gen, s: f64) -> Option<Parallelogram> {
    let centre = g.unit() * (10.0 * s).min(1e5);
    let ud = g.unit();
    let across = g.perp(ud);
    let (k, skew) = (g.range(0.3, 1.0), g.range(-0.5, 0.5));
    let (u, v) = (d3(f3(ud * s)), d3(f3((across + ud * skew) * (s * k))));
    if u.cross(v).length() < 0.2 * u.length() * v.length() {
        return None;
    }
    let q = d3(f3(centre - (u + v) * 0.5));
    Some(Parallelogram { q, u, v })
}

/// One ray at a random quad of size about `s`, judged against f64 into
/// `tally`: for a hit, how far outside the quad it was accepted, over `s`;
/// `None` for a miss or a ray not judged (too thin a quad, too grazing a ray).
fn quad_ray(g: &mut Gen, s: f64, tally: &mut ScaleTally) -> Option<f64> {
    let Parallelogram { q, u, v } = random_quad(g, s)?;
    let mut quads = Quads::default();
    quads.push(f3(q), f3(u), f3(v), SCALE_EXTENT, Kind::Lambertian, 0);
    quads.pad();
    let rec = quads.rec[0];
    // From nearby (1 to 10 sizes away), aimed at a point in, on or
    // near the quad.
    let (a, b) = (g.range(-0.2, 1.2), g.range(-0.2, 1.2));
    let target = q + u * a + v * b;
    let o = d3(f3(target + g.unit() * (s * g.range(1.0, 10.0))));
    let dir = d3(f3((target - o).normalize())).normalize();
    let (of, df) = (V3::from_array(f3(o)), V3::from_array(f3(dir)));
    let mut best = Closest::<f32>::none();
    quads.brute::<_, _, false>(of, df, 0.0, &mut best, &mut ());
    let hit = best.index != MISS;
    let (te, ae, be) = quad_oracle(d3(f3(o)), d3(f3(dir)), q, u, v)?;
    let cos = u.cross(v).normalize().dot(dir).abs();
    if cos < 0.05 {
        return None;
    }
    tally.tested += 1;
    // The band, as a length: what the test accepts beyond the edges.
    let tol = rec.tolerance(of.max_abs(), te as f32) as f64;
    let (ha, hb) = (u.cross(v).length() / v.length(), u.cross(v).length() / u.length());
    // Outside the parallelogram, as a length across its edges.
    let outside = ((-ae).max(ae - 1.0) * ha).max((-be).max(be - 1.0) * hb);
    // The test's own error is a small part of the band (a margin of 4).
    let clear_in = outside < -tol && te > 0.0;
    let clear_out = outside > 2.0 * tol || te < 0.0;
    if (clear_in && !hit) || (clear_out && hit) {
        tally.wrong += 1;
    }
    if !hit {
        return None;
    }
    if ((best.t as f64 - te) / te).abs() > 1e-4 {
        tally.t_bad += 1;
    }
    tally.band_ratio = tally.band_ratio.max(outside / tol);
    Some(outside / s)
}

/// A box of size about `s`, 10 s from the origin (at most 1e5), turned at random.
fn random_box(g: &mut Gen, s: f64) -> Cuboids {
    let centre = g.unit() * (10.0 * s).min(1e5);
    let a0 = g.unit();
    let a1 = g.perp(a0);
    let axes = [a0, a1, a0.cross(a1)];
    let half = [s * g.range(0.2, 1.0), s * g.range(0.2, 1.0), s * g.range(0.2, 1.0)];
    let mut c = Cuboids::default();
    c.push(centre.to_array(), axes.map(|a| a.to_array()), half, 0);
    c
}

/// A ray from inside box `c` toward a corner or an edge point of it: always
/// a hit on one of its faces (a leak into `tally` if not).
fn box_ray_from_inside(g: &mut Gen, c: &Cuboids, tally: &mut ScaleTally) {
    let rec = c.rec[0];
    let (cc, ax, hh) = (d3(rec.c), rec.axes.map(d3), d3(rec.half));
    let inner = cc + ax[0] * (hh.x * g.range(-0.9, 0.9)) + ax[1] * (hh.y * g.range(-0.9, 0.9));
    let signs = [g.range(-1.0, 1.0).signum(), g.range(-1.0, 1.0).signum(), g.range(-1.0, 1.0)];
    let corner = cc + ax[0] * (hh.x * signs[0]) + ax[1] * (hh.y * signs[1]) + ax[2] * (hh.z * signs[2]);
    let (o, dir) = (d3(f3(inner)), d3(f3((corner - inner).normalize())).normalize());
    let mut best = Closest::<f32>::none();
    c.brute::<_, _, false>(V3::from_array(f3(o)), V3::from_array(f3(dir)), 0.0, &mut best, &mut ());
    tally.tested += 1;
    if best.index == MISS || best.index < QUAD_BASE {
        tally.leaks += 1;
    }
}

/// Two rays from outside box `c`, at one of its faces: at a point well inside
/// it (a hit on that face at the exact distance), and straight down its
/// normal past an edge (a miss); judged into `tally`.
fn box_rays_from_outside(g: &mut Gen, c: &Cuboids, tally: &mut ScaleTally) {
    let rec = c.rec[0];
    let (cc, ax, hh) = (d3(rec.c), rec.axes.map(d3), d3(rec.half));
    let k = (g.range(0.0, 3.0) as usize).min(2);
    let side = (g.range(0.0, 1.0) < 0.5) as usize;
    let sign = if side == 1 { 1.0 } else { -1.0 };
    let (j, l) = ((k + 1) % 3, (k + 2) % 3);
    let (hk, hj, hl) = (hh[k], hh[j], hh[l]);
    let face_point = |fj: f64, fl: f64| cc + ax[k] * (sign * hk) + ax[j] * (fj * hj) + ax[l] * (fl * hl);
    let normal = ax[k] * sign;
    let target = face_point(g.range(-0.8, 0.8), g.range(-0.8, 0.8));
    let from = target + (normal * 2.0 + ax[j] * g.range(-0.5, 0.5)) * hh.max_element();
    let (o, dir) = (d3(f3(from)), d3(f3((target - from).normalize())).normalize());
    let mut best = Closest::<f32>::none();
    c.brute::<_, _, false>(V3::from_array(f3(o)), V3::from_array(f3(dir)), 0.0, &mut best, &mut ());
    let te = (target - o).dot(dir);
    tally.tested += 2;
    if best.index != rec.faces[k][side] {
        tally.wrong += 1;
    } else if ((best.t as f64 - te) / te).abs() > 1e-4 {
        tally.t_bad += 1;
    }
    let past = face_point(1.5 * g.range(-1.0, 1.0).signum(), g.range(-0.8, 0.8));
    let o = d3(f3(past + normal * (2.0 * hh.max_element())));
    let mut best = Closest::<f32>::none();
    c.brute::<_, _, false>(V3::from_array(f3(o)), V3::from_array(f3(-normal)), 0.0, &mut best, &mut ());
    if best.index != MISS {
        tally.wrong += 1;
    }
}

/// Family 3's verdict: its checks, from what `tally` counted over every size.
fn quad_scale_checks(tally: &ScaleTally, out: &mut Parts) {
    let ScaleTally { tested, wrong, t_bad, leaks, grow_near, band_ratio, line } = tally;
    out.checks.push(Check::at_most(
        format!("quad and box scale 1e-6..1e6 (extent 1e6): wrong hit/miss vs f64 ({tested} rays)"),
        *wrong as f64,
        0.0,
        "clear by the ray's band (a hit outside 2x its band, a miss inside it)",
    ));
    out.checks.push(Check::at_most(
        "quad and box scale: hits with t off the f64 t by more than 1e-4 relative",
        *t_bad as f64,
        0.0,
        "rays from 1 to 10 sizes away, cos >= 0.05",
    ));
    out.checks.push(Check::at_most(
        "quad scale: accepted distance outside a quad / its size, rays from nearby",
        *grow_near,
        1e-3,
        format!("the band follows the ray (old: 64u x extent, 1e6 sizes at 1e-6);{line}"),
    ));
    out.checks.push(Check::at_most(
        "quad scale: accepted distance outside / the ray's band",
        *band_ratio,
        2.0,
        "the band bounds what is accepted (with the test's own rounding)",
    ));
    out.checks.push(Check::at_most(
        "box scale 1e-6..1e6: rays from inside toward corners and edges that leak",
        *leaks as f64,
        0.0,
        "faces that meet at an edge share its distances",
    ));
}

/// Family 4: emitters from 1e-30 to f32's largest.
pub(super) fn emitter_magnitude(cfg: &StressConfig, out: &mut Parts, progress: &mut dyn FnMut(&str)) -> Result<()> {
    let (w, spp) = if cfg.quick { (8, 16) } else { (16, 128) };
    let (mut worst, mut rejected, mut line) = (0.0f64, 0u64, String::new());
    for m in [1e-30f32, 1e-10, 1.0, 1e10, 1e20, 1e30, f32::MAX / 4.0] {
        // A quad light filling the view, and a floor lit by it.
        let mut camera = Camera::looking([0.0, 1.0, 0.0], [0.0, 2.0, 0.0], 20.0);
        camera.vup = [0.0, 0.0, 1.0];
        let mut sc = scene(camera, [0.0; 3]);
        sc.quads.push(Quad { q: [-1.0, 2.0, -1.0], u: [2.0, 0.0, 0.0], v: [0.0, 0.0, 2.0], material: light(m) });
        let job = Job::new(&sc, &overrides(w, spp, cfg.seed, EstimatorChoice::Bsdf, 4), &RenderOptions::default())?;
        let r = crate::render::render(&job, None)?;
        rejected += r.stats.rejected_samples;
        let mean = r.image.data.iter().map(|p| p[0] as f64).sum::<f64>() / r.image.data.len() as f64;
        // Relative, or within the film's resolution (2^-32 a sample) for
        // an emitter darker than it.
        let err = (mean - m as f64).abs() / (m as f64).max(RESOLUTION / 1e-6);
        worst = worst.max(if err.is_finite() { err } else { f64::INFINITY });
        line.push_str(&format!(" {m:.0e}: {:.2e}", mean / m as f64));
    }
    progress("emitter magnitude");
    out.checks.push(Check::at_most(
        "emitters 1e-30..f32::MAX/4 seen directly: |image - emission| / max(emission, film resolution / 1e-6)",
        worst,
        1e-6,
        format!("image / emission at{line}"),
    ));
    out.checks.push(Check::at_most("emitters: samples rejected", rejected as f64, 0.0, "every sample kept"));
    Ok(())
}

/// Family 5: media densities at the edges of f32.
pub(super) fn media_density(cfg: &StressConfig, out: &mut Parts, progress: &mut dyn FnMut(&str)) -> Result<()> {
    let (w, spp) = if cfg.quick { (8, 8) } else { (16, 64) };
    let render = |density: f32| -> Result<(Image, u64)> {
        let mut sc = scene(Camera::looking([0.0, 0.0, 6.0], [0.0, 0.0, 0.0], 30.0), [0.7, 0.8, 1.0]);
        sc.spheres.push(Sphere { center: [0.0, -101.0, 0.0], center1: None, radius: 100.0, material: lambertian(0.5) });
        sc.media.push(Medium {
            boundary: MediumBoundary::Sphere { center: [0.0; 3], radius: 1.0 },
            density,
            albedo: [0.9; 3],
        });
        let st = overrides(w, spp, cfg.seed, EstimatorChoice::Bsdf, 16);
        let r = render_with(&sc, &st, KernelChoice::Simd, cfg.threads)?;
        Ok((r.image, r.stats.rejected_samples))
    };
    let (zero, _) = render(0.0)?;
    let (neg, _) = render(-0.0)?;
    let differ = zero.data.iter().zip(&neg.data).filter(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits)).count();
    out.checks.push(Check::at_most(
        "media: density -0.0 renders 0.0's image: pixels that differ",
        differ as f64,
        0.0,
        "bit for bit",
    ));
    let mut bad = 0u64;
    for density in [f32::from_bits(1), 1e-40, 1e-30, 1.0, 1e30, f32::MAX] {
        let (img, rej) = render(density)?;
        bad += rej + img.data.iter().filter(|p| p.iter().any(|c| !c.is_finite())).count() as u64;
        // A subnormal or tiny density is all but empty: the image of 0.
        if density < 1e-20 {
            let most = img.data.iter().zip(&zero.data).map(|(a, b)| (a[0] - b[0]).abs()).fold(0.0f32, f32::max);
            bad += (most > 1e-6) as u64;
        }
    }
    progress("media density");
    out.checks.push(Check::at_most(
        "media: densities 1e-45 (subnormal)..f32::MAX: non-finite or rejected samples, tiny != empty",
        bad as f64,
        0.0,
        "subnormal and 1e-30 render the empty medium's image",
    ));
    Ok(())
}
