//! The materials' sampling against f64 references and their distributions:
//! the dielectric against Snell's law, total internal reflection and Schlick's
//! reflectance (each decision at the exact threshold); the metal's fuzz sample
//! uniform on the unit sphere; the lens sample uniform in the unit disk.

use crate::common;
use common::stats::{chi2, chi2_critical};
use glam::DVec3;
use rtow::internals::material::dielectric;
use rtow::internals::sampling::{in_unit_disk, unit_vector, ScalarStream, Stream};
use rtow::internals::vec3::V3;

/// A stream that always draws `u` (the dielectric draws exactly one value).
struct Fixed(f32);

impl Stream<f32> for Fixed {
    fn next(&mut self) -> f32 {
        self.0
    }
}

fn v3(v: DVec3) -> V3<f32> {
    V3::new(v.x as f32, v.y as f32, v.z as f32).normalize()
}

fn d64(v: V3<f32>) -> DVec3 {
    DVec3::new(v.x as f64, v.y as f64, v.z as f64)
}

/// Schlick's reflectance and the refracted direction in f64 for unit `d`
/// arriving against unit `n` (d.n < 0), with ratio of indices `ri`.
fn reference(d: DVec3, n: DVec3, ri: f64) -> (f64, Option<DVec3>) {
    let cos = (-d.dot(n)).min(1.0);
    let sin2 = 1.0 - cos * cos;
    let r0 = ((1.0 - ri) / (1.0 + ri)).powi(2);
    let schlick = r0 + (1.0 - r0) * (1.0 - cos).powi(5);
    if ri * ri * sin2 > 1.0 {
        return (schlick, None);
    }
    let t = d * ri + n * (ri * cos - (1.0 - ri * ri * sin2).sqrt());
    (schlick, Some(t.normalize()))
}

/// Incident directions from grazing to normal, on both sides of an interface.
fn cases() -> Vec<(DVec3, DVec3, bool, f32)> {
    let mut v = Vec::new();
    let mut rng = ScalarStream::for_path(9, 0, 0);
    for i in 0..2000 {
        let n = d64(unit_vector::<f32, _>(&mut rng)).normalize();
        let t = n.any_orthonormal_vector();
        // cos from 1e-3 to 1 against the normal.
        let cos = 1e-3 + (1.0 - 1e-3) * (i as f64 / 1999.0);
        let d = (-n * cos + t * (1.0 - cos * cos).sqrt()).normalize();
        let front = i % 2 == 0;
        let ior = [1.1f32, 1.33, 1.5, 2.4][i % 4];
        v.push((d, n, front, ior));
    }
    v
}

#[test]
fn refraction_follows_snell_and_total_internal_reflection_always_reflects() {
    let (mut refracted, mut tir) = (0, 0);
    for (d, n, front, ior) in cases() {
        let ri = if front { 1.0 / ior as f64 } else { ior as f64 };
        let (schlick, t) = reference(d, n, ri);
        // u just below 1: refract wherever refraction is possible and Schlick < u.
        let out = d64(dielectric(v3(d), v3(n), front, ior, &mut Fixed(1.0 - 2f32.powi(-24))));
        let mirror = (d - n * (2.0 * d.dot(n))).normalize();
        match t {
            Some(t) if schlick < 0.999 => {
                assert!((out - t).length() < 2e-5, "Snell: {out:?} vs {t:?} (d {d:?}, n {n:?}, ri {ri})");
                refracted += 1;
            }
            Some(_) => {}
            None => {
                assert!((out - mirror).length() < 2e-5, "TIR must reflect: {out:?} vs {mirror:?} (ri {ri})");
                tir += 1;
            }
        }
    }
    assert!(refracted > 1000 && tir > 100, "cases cover both: {refracted} refracted, {tir} TIR");
}

#[test]
fn schlick_decides_reflection_at_its_exact_value() {
    let mut checked = 0;
    for (d, n, front, ior) in cases() {
        let ri = if front { 1.0 / ior as f64 } else { ior as f64 };
        let (schlick, t) = reference(d, n, ri);
        let Some(t) = t else { continue };
        // A margin above the f32 rounding of the reflectance (a few ulps of 1).
        if !(0.001..0.999).contains(&schlick) {
            continue;
        }
        let mirror = (d - n * (2.0 * d.dot(n))).normalize();
        let below = d64(dielectric(v3(d), v3(n), front, ior, &mut Fixed((schlick - 1e-4) as f32)));
        let above = d64(dielectric(v3(d), v3(n), front, ior, &mut Fixed((schlick + 1e-4) as f32)));
        assert!((below - mirror).length() < 2e-5, "u below Schlick {schlick} must reflect");
        assert!((above - t).length() < 2e-5, "u above Schlick {schlick} must refract");
        checked += 1;
    }
    assert!(checked > 1000, "{checked}");
}

#[test]
fn fuzz_sample_is_uniform_on_the_unit_sphere() {
    // Uniform on the sphere: z uniform in [-1, 1] and the azimuth uniform,
    // independent (Archimedes): equal-probability cells in (z, phi).
    let (zb, pb) = (16, 16);
    let mut counts = vec![0u64; zb * pb];
    let mut rng = ScalarStream::for_path(4, 1, 2);
    for _ in 0..200_000 {
        let v = unit_vector::<f32, _>(&mut rng);
        assert!((v.length_squared() - 1.0).abs() < 1e-5);
        let z = ((v.z as f64 + 1.0) / 2.0 * zb as f64).clamp(0.0, zb as f64 - 1.0) as usize;
        let phi = (v.y as f64).atan2(v.x as f64) + std::f64::consts::PI;
        let p = (phi / std::f64::consts::TAU * pb as f64).clamp(0.0, pb as f64 - 1.0) as usize;
        counts[z * pb + p] += 1;
    }
    let (x, crit) = (chi2(&counts), chi2_critical(zb * pb - 1, 0.001));
    assert!(x < crit, "chi-square {x} >= {crit}");
}

#[test]
fn lens_sample_is_uniform_in_the_unit_disk() {
    // Uniform in the disk: r^2 uniform in [0, 1] and the angle uniform.
    let (rb, ab) = (16, 16);
    let mut counts = vec![0u64; rb * ab];
    let mut rng = ScalarStream::for_path(5, 3, 1);
    for _ in 0..200_000 {
        let (x, y) = in_unit_disk::<f32, _>(&mut rng);
        let r2 = x as f64 * x as f64 + y as f64 * y as f64;
        assert!(r2 < 1.0 + 1e-6);
        let ri = (r2 * rb as f64).clamp(0.0, rb as f64 - 1.0) as usize;
        let a = (y as f64).atan2(x as f64) + std::f64::consts::PI;
        let ai = (a / std::f64::consts::TAU * ab as f64).clamp(0.0, ab as f64 - 1.0) as usize;
        counts[ri * ab + ai] += 1;
    }
    let (x, crit) = (chi2(&counts), chi2_critical(rb * ab - 1, 0.001));
    assert!(x < crit, "chi-square {x} >= {crit}");
}
