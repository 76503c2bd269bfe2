//! `rtow stress`: numerical stress tests of the intersection, the ray offset and
//! the film, for both kernels, against an f64 oracle.
//!
//! Three parts (the sweeps run the kernels' functions at one lane and at 8):
//!
//! 1. **Intersection sweeps.** Rays against one sphere, radius and distance over
//!    1e-4 .. 1e6 (ratio 1e-6 .. 1), grazing rays, origins on the surface,
//!    inside and at the centre, negative radii. Every answer is judged by
//!    [`Truth`], the same test in f64 on the same f32 inputs, with the error
//!    bounds of the f32 kernel (see `geometry/spheres.rs` for their derivation):
//!    a decision inside the rounding band of a bound is not an error.
//! 2. **Self-intersection sweeps.** Hit points on spheres of radius 10^U(-4,4)
//!    whose centre (or, for half of them, the hit point) lies 10^U(-4,6) from the
//!    origin, 1000 rays scattered from each (every material's scatter, plus
//!    synthetic grazing directions), each spawned with `geometry::spawn` and intersected
//!    again: a ray leaving the sphere that hits it again is a re-hit; a ray
//!    entering it that misses the far wall is a wrong decision. Hit points where
//!    the offset exceeds the radius (`|p|_inf > ~1e6 |r|`, below f32 resolution)
//!    are reported apart: there entering rays can be pushed through the sphere.
//! 3. **Scenes.** The stress presets, rendered by the real renderer with every
//!    kernel and accelerator (and with Russian roulette and adaptive sampling)
//!    under a probe (`StressProbe`) that judges every ray by the oracle
//!    against every sphere and checks every bounce for re-hits; every
//!    configuration must trace the same rays bit for bit. Plus image comparisons
//!    (scaled scenes against the unscaled one, the horizon against its analytic
//!    colour, the far camera against the same rays started near the scene) and
//!    the NaN count of every preset.
//!
//! The textbook test (`b*b - 4ac`, `t_min = 0.001`, no re-projection, no offset)
//! is implemented here only, as a reference for docs/stability.md; it never gates.

mod books;
mod oracle;
mod report;
mod scenes;
mod sweeps;

pub use oracle::{textbook_hit, HitVerdict, RayF64, Truth, SIDE_EPS, TEXTBOOK_T_MIN, U, Z_LIMIT};
pub use report::{Check, Decade, Gate, OffsetScan, StressReport, StressRow, Tally};
pub use scenes::COLOUR_FLOOR;
pub use sweeps::{check_group, offset_rehits, Group, GroupResult, IsectCase, Scatter};

use crate::choice::{AccelChoice, KernelChoice, Mode};
use crate::error::{Error, Result};
use crate::estimator::{Adaptive, Roulette};
use crate::film::part::Fnv1a;
use crate::film::Image;
use crate::job::{Job, RenderOptions};
use crate::sampling::mix64;
use crate::scene;
use crate::vec3::V3;
use glam::DVec3;
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use scenes::{compare, horizon_check, mean_colour, preset, render_with, settings, trace, SceneOracle};
use std::time::Instant;
use sweeps::{add, isect_sweep, self_sweep, Impl, OffsetRule};

pub(super) fn v64(v: V3<f32>) -> DVec3 {
    DVec3::new(v.x as f64, v.y as f64, v.z as f64)
}

pub(super) fn v32(v: DVec3) -> V3<f32> {
    V3::new(v.x as f32, v.y as f32, v.z as f32)
}

/// A unit f64 direction as the renderer would hold it: rounded, then
/// normalized in f32.
pub(super) fn dir32(v: DVec3) -> V3<f32> {
    v32(v.normalize()).normalize()
}

pub(super) fn finite3(v: V3<f32>) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}

/// FNV-1a, to compare long streams of results between kernels.
#[derive(Clone, Copy, Default)]
pub(super) struct Fnv(Fnv1a);

impl Fnv {
    pub(super) fn new() -> Self {
        Fnv::default()
    }
    /// The hash so far.
    pub(super) fn value(&self) -> u64 {
        self.0 .0
    }
    pub(super) fn u32(&mut self, x: u32) {
        self.0.add(&x.to_le_bytes());
    }
    pub(super) fn f(&mut self, x: f32) {
        self.u32(x.to_bits())
    }
    pub(super) fn v(&mut self, v: V3<f32>) {
        self.f(v.x);
        self.f(v.y);
        self.f(v.z);
    }
}

/// The generator of test configurations (f64, independent of the renderer's streams).
pub(super) struct Gen(Xoshiro256PlusPlus);

impl Gen {
    pub(super) fn new(seed: u64, stream: u64) -> Self {
        Gen(Xoshiro256PlusPlus::seed_from_u64(mix64(seed ^ stream.wrapping_mul(0x9E37_79B9_7F4A_7C15))))
    }
    /// Uniform in [0, 1).
    pub(super) fn unif(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }
    pub(super) fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.unif()
    }
    /// `10^U(a, b)`.
    pub(super) fn exp10(&mut self, a: f64, b: f64) -> f64 {
        10f64.powf(self.range(a, b))
    }
    pub(super) fn unit(&mut self) -> DVec3 {
        let z = 1.0 - 2.0 * self.unif();
        let rr = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f64::consts::TAU * self.unif();
        DVec3::new(rr * phi.cos(), rr * phi.sin(), z)
    }
    /// A random unit vector perpendicular to the unit vector `n`.
    pub(super) fn perp(&mut self, n: DVec3) -> DVec3 {
        let v = self.unit();
        let p = v - n * v.dot(n);
        if p.length() > 1e-3 {
            p.normalize()
        } else {
            n.any_orthonormal_vector()
        }
    }
}

/// How much `rtow stress` does.
#[derive(Clone, Copy, Debug)]
pub struct StressConfig {
    /// The small version `cargo test` runs.
    pub quick: bool,
    pub seed: u64,
    /// Render threads (`None`: one per core).
    pub threads: Option<usize>,
}

#[derive(Clone, Copy, Debug)]
pub(super) struct Sizes {
    /// Groups of 8 rays per intersection case.
    pub(super) groups: usize,
    /// Hit points per scatter kind, and rays per hit point (a multiple of 8).
    pub(super) hit_points: usize,
    pub(super) per_point: usize,
    /// Scene renders.
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) spp: u32,
    /// The horizon scene (one sphere: cheap) gets more samples.
    pub(super) horizon_spp: u32,
    pub(super) offset_scan: bool,
}

impl StressConfig {
    pub(super) fn sizes(&self) -> Sizes {
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

/// Runs every sweep and scene; `progress` gets a line per finished part.
pub fn run(cfg: &StressConfig, progress: &mut dyn FnMut(&str)) -> Result<StressReport> {
    crate::limits::check_threads(cfg.threads)?;
    let start = Instant::now();
    let sz = cfg.sizes();
    let mut out = Parts::default();
    intersection(cfg, &sz, &mut out, progress);
    self_intersection(cfg, &sz, &mut out, progress);
    let images = scenes(cfg, &sz, &mut out, progress)?;
    scaled_scenes(cfg, &sz, &images, &mut out)?;
    every_preset(cfg, &mut out)?;
    progress("presets");
    books::small_lights(cfg, &mut out, progress)?;
    books::furnaces(cfg, &mut out, progress)?;
    books::quad_scale(cfg, &mut out, progress)?;
    books::emitter_magnitude(cfg, &mut out, progress)?;
    books::media_density(cfg, &mut out, progress)?;
    Ok(StressReport {
        quick: cfg.quick,
        seed: cfg.seed,
        isa: crate::kernel::isa(),
        rows: out.rows,
        checks: out.checks,
        decades: out.decades,
        offset_scan: out.offset_scan,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// What the parts of a run add to its report.
#[derive(Default)]
struct Parts {
    rows: Vec<StressRow>,
    checks: Vec<Check>,
    decades: Vec<Decade>,
    offset_scan: Vec<OffsetScan>,
}

/// Part 1, intersection: rays against one sphere, every case, every implementation.
fn intersection(cfg: &StressConfig, sz: &Sizes, out: &mut Parts, progress: &mut dyn FnMut(&str)) {
    out.decades = (-6..0).map(|e| Decade { ratio_exp: e, ..Decade::default() }).collect();
    let (mut mismatches, mut disc_ratio) = (0, 0.0f64);
    let sec = "intersection (1 sphere, f64 oracle)";
    for case in IsectCase::ALL {
        let r = isect_sweep(case, sz.groups, cfg.seed, &mut out.decades);
        mismatches += r.mismatches;
        disc_ratio = disc_ratio.max(r.max_disc_ratio);
        for (kernel, tally, gate) in
            [("scalar", r.scalar, Gate::Full), ("simd", r.simd, Gate::Full), ("textbook", r.textbook, Gate::Reference)]
        {
            out.rows.push(StressRow { section: sec, case: case.name().into(), kernel, tally, gate });
        }
        progress(&format!("intersection: {}", case.name()));
    }
    out.checks.push(Check::at_most(
        "intersection: scalar and 8-wide answers differ (lanes)",
        mismatches as f64,
        0.0,
        "index, t and disc compared bit for bit",
    ));
    out.checks.push(Check::at_most(
        "intersection: |disc error| / its bound, largest",
        disc_ratio,
        1.0,
        "the rounding band rests on this bound",
    ));
}

/// Part 2, self-intersection: rays spawned from hit points, every scatter
/// kind; in the full run, the offset rule against smaller and partial offsets.
fn self_intersection(cfg: &StressConfig, sz: &Sizes, out: &mut Parts, progress: &mut dyn FnMut(&str)) {
    let sec = "self-intersection (1000 rays per hit point)";
    let mut below: [Tally; 3] = Default::default();
    for scatter in Scatter::ALL {
        let run1 = |imp| self_sweep(scatter, imp, sz, cfg.seed, OffsetRule::Scaled(1.0));
        let s = run1(Impl::Scalar);
        let v = run1(Impl::Simd);
        let tb = run1(Impl::Textbook);
        out.checks.push(Check::at_most(
            format!("self-intersection, {}: scalar != simd", scatter.name()),
            (s.hash != v.hash) as u8 as f64,
            0.0,
            "every spawned ray, bit for bit",
        ));
        for (i, (kernel, r, gate)) in
            [("scalar", s, Gate::Full), ("simd", v, Gate::Full), ("textbook", tb, Gate::Reference)]
                .into_iter()
                .enumerate()
        {
            add(&mut below[i], &r.unresolved);
            out.rows.push(StressRow { section: sec, case: scatter.name().into(), kernel, tally: r.resolved, gate });
        }
        progress(&format!("self-intersection: {}", scatter.name()));
    }
    for (i, (kernel, gate)) in
        [("scalar", Gate::NoLeaks), ("simd", Gate::NoLeaks), ("textbook", Gate::Reference)].into_iter().enumerate()
    {
        out.rows.push(StressRow {
            section: sec,
            case: "below f32 resolution, all of the above".into(),
            kernel,
            tally: below[i].clone(),
            gate,
        });
    }
    if sz.offset_scan {
        out.offset_scan = offset_scan(cfg, sz);
        progress("offset rules");
    }
}

/// Re-hits and wrong decisions of smaller and partial offset rules.
fn offset_scan(cfg: &StressConfig, sz: &Sizes) -> Vec<OffsetScan> {
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
    rules
        .into_iter()
        .map(|(rule, r)| {
            let mut t = Tally::default();
            for scatter in Scatter::ALL {
                add(&mut t, &self_sweep(scatter, Impl::Scalar, sz, cfg.seed, r).resolved);
            }
            OffsetScan { rule, rays: t.rays, rehits: t.rehits, wrong: t.wrong }
        })
        .collect()
}

/// The stress presets the scene part renders.
const STRESS_SCENES: [&str; 5] =
    ["stress-final-small", "stress-final-large", "stress-horizon", "stress-tiny", "stress-far-camera"];

/// The configurations of the scene part: (label, options, group); every
/// configuration of a group must trace the same rays.
fn scene_configs(cfg: &StressConfig) -> Result<Vec<(&'static str, RenderOptions, u8)>> {
    let base = RenderOptions { threads: cfg.threads, ..RenderOptions::default() };
    let with = |kernel, accel| RenderOptions { kernel, accel, ..base };
    let adaptive = Some(Adaptive::new(0.05, 2)?);
    let estimators = RenderOptions { roulette: Some(Roulette::new(2)?), adaptive, ..base };
    let mut configs = vec![
        ("scalar", with(KernelChoice::Scalar, AccelChoice::Auto), 0),
        ("scalar, brute force", with(KernelChoice::Scalar, AccelChoice::Brute), 0),
        ("simd", with(KernelChoice::Simd, AccelChoice::Auto), 0),
        ("simd, brute force", with(KernelChoice::Simd, AccelChoice::Brute), 0),
        ("simd, bvh-ray", with(KernelChoice::Simd, AccelChoice::BvhRay), 0),
        ("scalar, rr + adaptive", RenderOptions { kernel: KernelChoice::Scalar, ..estimators }, 1),
        ("simd, rr + adaptive", RenderOptions { kernel: KernelChoice::Simd, ..estimators }, 1),
    ];
    if crate::kernel::HAS_SIMD16 {
        configs.push(("simd8", with(KernelChoice::Simd8, AccelChoice::Auto), 0));
    }
    Ok(configs)
}

/// Part 3, scenes: the real renderer under the stress probe, every kernel
/// and accelerator; returns the scalar kernel's image of each stress preset.
fn scenes(
    cfg: &StressConfig,
    sz: &Sizes,
    out: &mut Parts,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<(String, Image)>> {
    let sec = "scenes (every ray vs f64 oracle)";
    let configs = scene_configs(cfg)?;
    let mut images = Vec::new();
    for name in STRESS_SCENES {
        let scene = preset(name)?;
        let spp = if name == "stress-horizon" { sz.horizon_spp } else { sz.spp };
        let st = settings(sz.width, sz.height, spp, cfg.seed);
        let brute = Job::new(&scene, &st, &RenderOptions { accel: AccelChoice::Brute, ..Default::default() })?;
        if brute.mode() != Mode::Path {
            return Err(Error::Input(format!("{name}: stress scenes must be path traced")));
        }
        let prep = brute.prepared();
        let oracle = SceneOracle::new(&prep.shapes.spheres);
        let mut first: [Option<(&str, u64, u64)>; 2] = [None, None];
        let mut scalar_image = None;
        for &(label, opts, group) in &configs {
            let tr = trace(&Job::new(&scene, &st, &opts)?, &oracle, None)?;
            let mut tally = tr.tally.clone();
            tally.nan += tr.rejected;
            out.rows.push(StressRow { section: sec, case: name.into(), kernel: label, tally, gate: Gate::Full });
            match first[group as usize] {
                None => first[group as usize] = Some((label, tr.hash, tr.rays)),
                Some((l0, h0, r0)) => out.checks.push(Check::at_most(
                    format!("{name}: rays of [{label}] != [{l0}]"),
                    ((tr.hash != h0) as u8 + (tr.rays != r0) as u8) as f64,
                    0.0,
                    "hash of every ray's origin, direction, hit and t, path by path",
                )),
            }
            if label == "scalar" {
                scalar_image = Some(tr.image);
            }
        }
        let img = scalar_image.ok_or_else(|| Error::Input("stress: no scalar render".into()))?;
        if name == "stress-horizon" {
            let (z, n, mean, want) = horizon_check(&scene, prep, &img)?;
            out.checks.push(Check::at_most(
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
            let near = trace(&Job::new(&scene, &st, &configs[0].1)?, &oracle, Some(&shift))?;
            let (zg, zb) = compare(&img, &near.image, 8);
            out.checks.push(Check::at_most(
                "stress-far-camera vs same rays started near, max z",
                zg.max(zb),
                Z_LIMIT,
                format!("whole image {zg:.2}, 8x8 blocks {zb:.2}"),
            ));
        }
        images.push((name.to_string(), img));
        progress(&format!("scene: {name}"));
    }
    Ok(images)
}

/// Scaled scenes against the unscaled ones.
fn scaled_scenes(cfg: &StressConfig, sz: &Sizes, images: &[(String, Image)], out: &mut Parts) -> Result<()> {
    for (name, reference) in
        [("stress-final-small", "final"), ("stress-final-large", "final"), ("stress-tiny", "ch09-glass")]
    {
        let scene = preset(reference)?;
        let st = settings(sz.width, sz.height, sz.spp, cfg.seed);
        let r = render_with(&scene, &st, KernelChoice::Simd, cfg.threads)?;
        let img = images
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, i)| i)
            .ok_or_else(|| Error::Input(format!("stress: no image of {name}")))?;
        let (zg, zb) = compare(img, &r.image, 8);
        let (ma, mb) = (mean_colour(img), mean_colour(&r.image));
        out.checks.push(Check::at_most(
            format!("{name} vs {reference}, max z"),
            zg.max(zb),
            Z_LIMIT,
            format!(
                "whole {zg:.2}, blocks {zb:.2}; mean ({:.4} {:.4} {:.4}) vs ({:.4} {:.4} {:.4})",
                ma[0], ma[1], ma[2], mb[0], mb[1], mb[2]
            ),
        ));
    }
    Ok(())
}

/// Every preset, both kernels: no sample rejected.
fn every_preset(cfg: &StressConfig, out: &mut Parts) -> Result<()> {
    let mut rejected = 0u64;
    let mut presets = 0;
    let mut skipped = Vec::new();
    for p in scene::presets() {
        let scene = (p.build)();
        // A preset that names image files renders where RTOW_IMAGES holds them.
        if !scene.image_files().is_empty() && crate::job::images_folder().is_none() {
            skipped.push(p.name);
            continue;
        }
        let st = settings(32, 18, 2, cfg.seed);
        for kernel in [KernelChoice::Scalar, KernelChoice::Simd] {
            rejected += render_with(&scene, &st, kernel, cfg.threads)?.stats.rejected_samples;
        }
        presets += 1;
    }
    let skipped = match skipped.len() {
        0 => String::new(),
        _ => format!(" (not {}: their images need {})", skipped.join(", "), crate::job::IMAGES_ENV),
    };
    out.checks.push(Check::at_most(
        format!("every preset ({presets}{skipped}), both kernels: samples rejected (any cause)"),
        rejected as f64,
        0.0,
        "32x18, 2 spp",
    ));
    Ok(())
}
