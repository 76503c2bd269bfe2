//! The Lambertian sampler follows cos(theta) / pi, by a chi-square test; the
//! slip of the C# retelling rtow grew from (normal + a normalized cube sample) fails the same test.
//!
//! For a cosine-distributed direction about n, mu = cos(theta) has density 2 mu
//! on [0, 1], so mu^2 is uniform; the azimuth phi is uniform on [0, 2 pi) and
//! independent of mu. Cells that split mu^2 and phi evenly therefore all have
//! the same probability, and Pearson's statistic over them follows a
//! chi-square law with (cells - 1) degrees of freedom.

use crate::common;
use common::stats::{chi2, chi2_critical, normal_quantile};
use rtow::internals::material::lambertian;
use rtow::internals::sampling::{ScalarStream, Stream};
use rtow::internals::vec3::V3;

const SAMPLES: usize = 200_000;
/// Bins in mu^2 and in phi: 16 x 16 cells, about 780 expected per cell.
const MU_BINS: usize = 16;
const PHI_BINS: usize = 16;
/// Significance level: a correct sampler fails one run in a thousand.
const ALPHA: f64 = 0.001;

type D3 = [f64; 3];

fn dot(a: D3, b: D3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: D3, b: D3) -> D3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn normalized(a: D3) -> D3 {
    let l = dot(a, a).sqrt();
    a.map(|x| x / l)
}

/// Counts of `SAMPLES` directions about `n` in the (mu^2, phi) cells, and how
/// many fell below the surface (mu < 0).
struct Histogram {
    cells: Vec<u64>,
    below: u64,
}

impl Histogram {
    fn of(n: D3, mut sample: impl FnMut() -> D3) -> Self {
        let helper = if n[0].abs() > 0.9 { [0.0, 1.0, 0.0] } else { [1.0, 0.0, 0.0] };
        let t = normalized(cross(n, helper));
        let b = cross(n, t);
        let mut cells = vec![0u64; MU_BINS * PHI_BINS];
        let mut below = 0;
        for _ in 0..SAMPLES {
            let d = sample();
            let mu = dot(d, n);
            if mu < 0.0 {
                below += 1;
            }
            let mu2 = mu.clamp(0.0, 1.0).powi(2);
            let phi = dot(d, b).atan2(dot(d, t)) + std::f64::consts::PI;
            let i = ((mu2 * MU_BINS as f64) as usize).min(MU_BINS - 1);
            let j = ((phi / std::f64::consts::TAU * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
            cells[i * PHI_BINS + j] += 1;
        }
        Histogram { cells, below }
    }

    /// The cos(theta) marginal: the mu^2 bins summed over phi.
    fn mu_marginal(&self) -> Vec<u64> {
        self.cells.chunks(PHI_BINS).map(|row| row.iter().sum()).collect()
    }

    /// (statistic, critical value) of the joint test and of the cos(theta) marginal.
    fn tests(&self) -> [(f64, f64); 2] {
        let m = self.mu_marginal();
        [(chi2(&self.cells), chi2_critical(self.cells.len() - 1, ALPHA)), (chi2(&m), chi2_critical(m.len() - 1, ALPHA))]
    }
}

const NORMALS: [D3; 3] = [[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 2.0, 3.0]];

fn f32_normal(n: D3) -> (V3<f32>, D3) {
    let v = V3::new(n[0] as f32, n[1] as f32, n[2] as f32).normalize();
    (v, [v.x as f64, v.y as f64, v.z as f64])
}

#[test]
fn critical_values_match_the_tables() {
    // Published values of the chi-square quantile at p = 0.001 (e.g. NIST/SEMATECH
    // e-Handbook, table 1.3.6.7.4) against the approximation used above.
    assert!((normal_quantile(0.999) - 3.0902).abs() < 1e-3);
    for (dof, table) in [(10, 29.588), (15, 37.697), (100, 149.449)] {
        let c = chi2_critical(dof, ALPHA);
        assert!((c / table - 1.0).abs() < 0.01, "dof {dof}: {c} vs {table}");
    }
}

#[test]
fn the_test_passes_an_ideal_cosine_sampler() {
    // Directions drawn by inverting the cosine law exactly (mu = sqrt(u), phi
    // uniform, in f64 from an independent generator): the test is not too strict.
    for (k, n) in NORMALS.into_iter().enumerate() {
        let n = normalized(n);
        let helper = if n[0].abs() > 0.9 { [0.0, 1.0, 0.0] } else { [1.0, 0.0, 0.0] };
        let t = normalized(cross(n, helper));
        let b = cross(n, t);
        let mut rng = ScalarStream::for_path(99, k as u64, 0);
        let mut u = || Stream::<f32>::next(&mut rng) as f64;
        let h = Histogram::of(n, || {
            let mu = u().sqrt();
            let phi = u() * std::f64::consts::TAU;
            let s = (1.0 - mu * mu).sqrt();
            std::array::from_fn(|k| n[k] * mu + t[k] * s * phi.cos() + b[k] * s * phi.sin())
        });
        for (stat, crit) in h.tests() {
            assert!(stat < crit, "normal {n:?}: chi2 {stat:.1} >= {crit:.1}");
        }
    }
}

#[test]
fn lambertian_directions_follow_cos_theta_over_pi() {
    for (k, n) in NORMALS.into_iter().enumerate() {
        let (nf, n) = f32_normal(n);
        let mut rng = ScalarStream::for_path(2024, k as u64, 0);
        let h = Histogram::of(n, || {
            let d = lambertian::<f32, _>(nf, &mut rng);
            [d.x as f64, d.y as f64, d.z as f64]
        });
        assert_eq!(h.below, 0, "normal {n:?}: directions below the surface");
        for (stat, crit) in h.tests() {
            assert!(stat < crit, "normal {n:?}: chi2 {stat:.1} >= {crit:.1} (cells {:?})", h.cells);
        }
    }
}

#[test]
fn the_seeds_normal_plus_normalized_cube_sample_fails() {
    // The seed's diffuse direction: normal + normalize(a uniform point in the
    // cube [-1, 1]^3). A normalized cube sample crowds towards the cube's
    // corners, so the sum is not cosine distributed; the test must see it.
    for (k, n) in NORMALS.into_iter().enumerate() {
        let (nf, n) = f32_normal(n);
        let mut rng = ScalarStream::for_path(2024, k as u64, 0);
        let h = Histogram::of(n, || {
            let mut u = || 2.0 * Stream::<f32>::next(&mut rng) - 1.0;
            let cube = V3::new(u(), u(), u()).normalize();
            let d = (nf + cube).normalize();
            [d.x as f64, d.y as f64, d.z as f64]
        });
        // Both the joint test and the cos(theta) marginal alone reject it.
        for (stat, crit) in h.tests() {
            assert!(stat > crit, "normal {n:?}: the slip passed, chi2 {stat:.1} < {crit:.1}");
        }
    }
}
