//! Statistics for the distribution tests: chi-square with equal-probability cells.

/// Standard normal CDF, Phi(z) = 1/2 + integral of the density from 0 to z
/// (Simpson's rule, 2000 intervals: error far below what the test needs).
pub fn normal_cdf(z: f64) -> f64 {
    let n = 2000;
    let h = z / n as f64;
    let pdf = |x: f64| (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let mut s = pdf(0.0) + pdf(z);
    for i in 1..n {
        s += pdf(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    0.5 + s * h / 3.0
}

/// The standard normal quantile, by bisection on `normal_cdf`.
pub fn normal_quantile(p: f64) -> f64 {
    let (mut lo, mut hi) = (-10.0, 10.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if normal_cdf(mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The chi-square value exceeded with probability `alpha` at `dof` degrees of
/// freedom, by the Wilson-Hilferty approximation: (X/k)^(1/3) is nearly
/// normal with mean 1 - 2/(9k) and variance 2/(9k) (accurate to well under 1%
/// for k in the hundreds).
pub fn chi2_critical(dof: usize, alpha: f64) -> f64 {
    let k = dof as f64;
    let z = normal_quantile(1.0 - alpha);
    let v = 2.0 / (9.0 * k);
    k * (1.0 - v + z * v.sqrt()).powi(3)
}

/// Pearson's statistic for equal-probability cells.
pub fn chi2(counts: &[u64]) -> f64 {
    let n: u64 = counts.iter().sum();
    let e = n as f64 / counts.len() as f64;
    counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum()
}
