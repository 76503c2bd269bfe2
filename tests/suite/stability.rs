//! Numerical stability: the f32 intersection (scalar and 8-wide) against the f64
//! oracle of `rtow::instruments::stress`, the ray offset, NaN-free films, and the quick form of
//! `rtow stress` (sweeps, stress scenes, image comparisons) with both kernels.

use crate::common;
use common::self_contained;
use glam::DVec3;
use proptest::prelude::*;
use rtow::instruments::stress::{self, check_group, Group, GroupResult};
use rtow::internals::geometry::{surface, Spheres};
use rtow::internals::vec3::V3;
use rtow::scene;
use rtow::{KernelChoice, RenderOptions};
use std::f64::consts::TAU;
use wide::f32x8;

fn v32(v: DVec3) -> V3<f32> {
    V3::new(v.x as f32, v.y as f32, v.z as f32)
}

fn dir32(v: DVec3) -> V3<f32> {
    v32(v.normalize()).normalize()
}

/// A unit vector from two uniforms (z in [-1, 1], angle in [0, 2 pi)).
fn unit(z: f64, phi: f64) -> DVec3 {
    let r = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn one_sphere() -> Spheres {
    Spheres::one([0.0; 3], 1.0)
}

fn assert_clean(res: &GroupResult, what: &str) {
    for (k, t) in [("scalar", &res.scalar), ("simd", &res.simd)] {
        assert_eq!(t.wrong, 0, "{what} [{k}]: wrong decisions {t:?}");
        assert_eq!(t.faces, 0, "{what} [{k}]: wrong faces {t:?}");
        assert_eq!(t.nan, 0, "{what} [{k}]: NaN {t:?}");
        assert!(t.max_err_bound <= 1.0, "{what} [{k}]: hit point beyond its bound {t:?}");
    }
    assert_eq!(res.mismatches, 0, "{what}: scalar and 8-wide differ");
    assert!(res.max_disc_ratio <= 1.0, "{what}: disc error {} x its bound", res.max_disc_ratio);
}

/// 8 rays from `dist` away at a sphere of radius `r`, each passing `h_k` from the centre.
fn outside_group(r: f64, dist: f64, centre: DVec3, dirs: &[(f64, f64, f64, f64, f64); 8], grazing: bool) -> Group {
    let mut o = [V3::new(0.0, 0.0, 0.0); 8];
    let mut d = o;
    for (k, &(z, phi, pz, pphi, h)) in dirs.iter().enumerate() {
        let fhat = unit(z, phi);
        let origin = centre + fhat * dist;
        let e = unit(pz, pphi);
        let e = (e - fhat * e.dot(fhat)).try_normalize().unwrap_or(fhat.any_orthonormal_vector());
        let h = if grazing { r * (1.0 + 1e-6 * (2.0 * h - 1.0)) } else { r * 1.5 * h };
        let sin = (h / dist).min(1.0);
        let dir = -fhat * (1.0 - sin * sin).sqrt() + e * sin;
        o[k] = v32(origin);
        d[k] = dir32(dir);
    }
    Group { c: v32(centre), r: r as f32, o, d, ratio: r / dist }
}

fn dirs8() -> impl Strategy<Value = [(f64, f64, f64, f64, f64); 8]> {
    prop::array::uniform8((-1.0..1.0f64, 0.0..TAU, -1.0..1.0f64, 0.0..TAU, 0.0..1.0f64))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(384))]

    /// Radius and distance over 1e-4 .. 1e6, ratio 1e-6 .. 1, either sign of radius.
    #[test]
    fn outside_rays_match_the_oracle(lr in -4.0..6.0f64, lq in -6.0..0.0f64, neg in any::<bool>(),
                                     cz in -1.0..1.0f64, cphi in 0.0..TAU, cs in 0.0..1.0f64,
                                     dirs in dirs8()) {
        let r = 10f64.powf(lr);
        let dist = r / 10f64.powf(lq);
        prop_assume!(dist <= 1e6);
        let mut g = outside_group(r, dist, unit(cz, cphi) * dist * cs, &dirs, false);
        if neg { g.r = -g.r; }
        assert_clean(&check_group(&g, &mut one_sphere()), "outside");
    }

    /// Rays tangent to within 1e-6 relative: decisions inside the band are free,
    /// everything else (and every hit point's error) must hold.
    #[test]
    fn grazing_rays_match_the_oracle(lr in -4.0..6.0f64, lq in -6.0..-0.01f64, dirs in dirs8()) {
        let r = 10f64.powf(lr);
        let dist = r / 10f64.powf(lq);
        prop_assume!(dist <= 1e6);
        let g = outside_group(r, dist, DVec3::ZERO, &dirs, true);
        assert_clean(&check_group(&g, &mut one_sphere()), "grazing");
    }

    /// Origins on the surface, inside and at the centre, either sign of radius.
    #[test]
    fn origins_on_inside_and_at_the_centre_match_the_oracle(
        lr in -4.0..6.0f64, lc in -2.0..1.0f64, neg in any::<bool>(), where_ in 0..3u8,
        pts in prop::array::uniform8((-1.0..1.0f64, 0.0..TAU, 0.0..1.0f64, -1.0..1.0f64, 0.0..TAU)),
    ) {
        let r = 10f64.powf(lr);
        let c = unit(0.3, 1.0) * r * 10f64.powf(lc);
        let mut o = [V3::new(0.0, 0.0, 0.0); 8];
        let mut d = o;
        for (k, &(z, phi, depth, dz, dphi)) in pts.iter().enumerate() {
            let m = unit(z, phi);
            o[k] = v32(match where_ {
                0 => c + m * r,
                1 => c + m * (r * depth.cbrt()),
                _ => c,
            });
            d[k] = dir32(unit(dz, dphi));
        }
        let g = Group { c: v32(c), r: if neg { -r } else { r } as f32, o, d, ratio: 1.0 };
        assert_clean(&check_group(&g, &mut one_sphere()), ["on the surface", "inside", "at the centre"][where_ as usize]);
    }
}

/// A hit point that rounds onto the centre (a sphere smaller than the f32
/// spacing of its coordinates) gives a finite surface facing the ray, both widths.
#[test]
fn surface_is_finite_when_the_hit_point_rounds_onto_the_centre() {
    let c = V3::new(1.0e6f32, 0.0, 0.0);
    let o = V3::new(1.0e6f32 - 1.0, 0.0, 0.0);
    let d = V3::new(1.0f32, 0.0, 0.0);
    assert_eq!((o + d * 1.0).to_array(), c.to_array());
    let s = surface(o, d, 1.0, c, 1e-4);
    assert!(s.p.to_array().iter().chain(s.n.to_array().iter()).all(|x| x.is_finite()));
    assert_eq!(s.n.to_array(), [-1.0, 0.0, 0.0]);
    assert!(s.front);
    let sp = |v: V3<f32>| V3::new(f32x8::splat(v.x), f32x8::splat(v.y), f32x8::splat(v.z));
    let s8 = surface(sp(o), sp(d), f32x8::splat(1.0), sp(c), f32x8::splat(1e-4));
    assert_eq!(s8.n.x.to_array(), [-1.0; 8]);
    assert_eq!(s8.p.x.to_array(), [s.p.x; 8]);
}

/// The self-intersection sweep has teeth: with the kernels' offset no spawned
/// ray re-hits or falls short of the far wall; with a sixteenth of it some do.
#[test]
fn the_offset_is_needed_and_sufficient_on_the_sweep() {
    let (rays, rehits, short) = stress::offset_rehits(1.0, 12, 7);
    assert!(rays > 30_000, "{rays}");
    assert_eq!((rehits, short), (0, 0));
    let (_, rehits, short) = stress::offset_rehits(1.0 / 16.0, 12, 7);
    assert!(rehits + short > 0, "a 16x smaller offset should fail the sweep");
}

/// No preset rejects a sample (NaN or Inf), with either kernel, and no pixel is non-finite.
#[test]
fn no_preset_produces_nan_or_inf() {
    for p in scene::presets() {
        let sc = self_contained(&(p.build)());
        let st = rtow::Overrides { width: Some(24), height: Some(16), spp: Some(2), ..Default::default() };
        for kernel in [KernelChoice::Scalar, KernelChoice::Simd] {
            let opts = RenderOptions { kernel, threads: Some(2), tile: 16, ..RenderOptions::default() };
            let r = rtow::render(&rtow::Job::new(&sc, &st, &opts).unwrap(), None).unwrap();
            assert_eq!(r.stats.rejected_samples, 0, "{} [{}]", p.name, kernel.name());
        }
    }
}

/// `rtow stress --quick`: every bound holds for both kernels, and the textbook
/// form it compares against really does fail where the robust one does not.
#[test]
fn quick_stress_run_passes() {
    let cfg = stress::StressConfig { quick: true, seed: 1, threads: Some(2) };
    let report = stress::run(&cfg, &mut |_| {}).unwrap();
    assert!(report.passed(), "{}", report.table());
    for kernel in ["scalar", "simd"] {
        assert!(report.rows.iter().filter(|r| r.kernel == kernel).count() >= 15);
    }
    let far: Vec<_> = report.decades.iter().filter(|d| d.ratio_exp <= -5).collect();
    assert!(far.iter().all(|d| d.robust.wrong == 0 && d.textbook.wrong * 5 > d.textbook.rays));
}
