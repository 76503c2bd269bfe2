//! How much of a timing is noise: the spread of repeated runs and
//! distribution-free confidence intervals, for the median of one kernel's
//! runs and for the ratio between a baseline's runs and this run's.
//!
//! Timings on a shared machine are skewed (a run is only ever slowed by
//! load), so nothing here assumes a normal distribution:
//!
//! - **The median of n runs**: the interval between two order statistics,
//!   `[x(k), x(n+1-k)]`, covers the true median with probability
//!   `1 - 2 P(Binomial(n, 1/2) < k)`, whatever the distribution.
//! - **The ratio of two sets of runs** (this run's times over the
//!   baseline's): the Hodges-Lehmann estimate (the median of all pairwise
//!   differences of log times) with the Mann-Whitney (Moses) interval,
//!   `[d(k), d(mn+1-k)]` of the m x n sorted differences, whose coverage
//!   comes from the exact null distribution of the Mann-Whitney count. It
//!   assumes only that load scales both sets alike (a shift in log time),
//!   uses every run of both sides, and is exact for the handful of runs a
//!   benchmark has (3 against 3 already gives a 90% interval).
//!
//! Both pick the narrowest interval whose coverage is at least [`LEVEL`];
//! with too few runs for that they use the widest one and report its
//! actual coverage.

use serde::{Deserialize, Serialize};

/// The confidence level aimed at.
pub const LEVEL: f64 = 0.95;

/// An interval and the probability that it covers the true value.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
    /// Coverage probability (e.g. 0.9375 for [min, max] of 5 runs).
    pub level: f64,
}

/// The spread of one kernel's repeated runs (seconds).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    pub min: f64,
    pub median: f64,
    pub max: f64,
    /// A confidence interval for the median (`null` below 2 runs).
    pub median_ci: Option<Interval>,
}

/// The median (the mean of the two middle values for an even count).
pub fn median(xs: &[f64]) -> f64 {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// P(Binomial(n, 1/2) <= k).
fn binomial_half_cdf(n: usize, k: usize) -> f64 {
    let mut c = 1.0f64; // C(n, 0)
    let mut sum = 0.0;
    for i in 0..=k.min(n) {
        if i > 0 {
            c = c * (n + 1 - i) as f64 / i as f64;
        }
        sum += c;
    }
    sum / 2f64.powi(n as i32)
}

impl Spread {
    /// The spread of `xs` (at least one value).
    pub fn of(xs: &[f64]) -> Spread {
        let mut v = xs.to_vec();
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median_ci = (n >= 2).then(|| {
            // The largest k whose interval still covers LEVEL; else k = 1.
            let mut k = 1;
            while k < n.div_ceil(2) && 1.0 - 2.0 * binomial_half_cdf(n, k) >= LEVEL {
                k += 1;
            }
            Interval { lo: v[k - 1], hi: v[n - k], level: 1.0 - 2.0 * binomial_half_cdf(n, k - 1) }
        });
        Spread { min: v[0], median: median(&v), max: v[n - 1], median_ci }
    }
}

/// The exact null distribution of the Mann-Whitney count U for samples of
/// sizes m and n: `P(U <= u)` for u = 0..=m*n.
fn mann_whitney_cdf(m: usize, n: usize) -> Vec<f64> {
    // counts[j][u]: arrangements of i x-values and j y-values with U = u,
    // built up over i (the number of ways is C(m+n, m) in all).
    let mut prev: Vec<Vec<f64>> = (0..=n).map(|_| vec![1.0]).collect(); // i = 0: U = 0 only
    for i in 1..=m {
        let mut cur: Vec<Vec<f64>> = Vec::with_capacity(n + 1);
        for j in 0..=n {
            // The largest value is an x (it beats all j y's: U += j) or a y.
            let mut c = vec![0.0; i * j + 1];
            for (u, &w) in prev[j].iter().enumerate() {
                c[u + j] += w;
            }
            if j > 0 {
                for (u, &w) in cur[j - 1].iter().enumerate() {
                    c[u] += w;
                }
            }
            cur.push(c);
        }
        prev = cur;
    }
    let counts = &prev[n];
    let total: f64 = counts.iter().sum();
    let mut acc = 0.0;
    counts
        .iter()
        .map(|&c| {
            acc += c;
            acc / total
        })
        .collect()
}

/// The ratio `current / baseline` of two sets of positive values (times),
/// estimated by Hodges-Lehmann on their logarithms, with the Mann-Whitney
/// (Moses) confidence interval; `None` unless both sides have 2 values or more.
pub fn ratio(baseline: &[f64], current: &[f64]) -> Option<(f64, Interval)> {
    let (m, n) = (baseline.len(), current.len());
    if m < 2 || n < 2 || m * n > 10_000 {
        return None;
    }
    let mut d: Vec<f64> = Vec::with_capacity(m * n);
    for &b in baseline {
        for &c in current {
            d.push(c.ln() - b.ln());
        }
    }
    if d.iter().any(|x| !x.is_finite()) {
        return None;
    }
    d.sort_by(f64::total_cmp);
    let estimate = median(&d).exp();
    let cdf = mann_whitney_cdf(m, n);
    // Coverage of [d(k), d(mn+1-k)] is 1 - 2 P(U <= k-1).
    let coverage = |k: usize| 1.0 - 2.0 * cdf[k - 1];
    let mut k = 1;
    while k < (m * n).div_ceil(2) && coverage(k + 1) >= LEVEL {
        k += 1;
    }
    let (lo, hi) = (d[k - 1].exp(), d[m * n - k].exp());
    Some((estimate, Interval { lo, hi, level: coverage(k) }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_interval_covers_what_the_binomial_says() {
        let s = Spread::of(&[3.0, 1.0, 2.0]);
        assert_eq!((s.min, s.median, s.max), (1.0, 2.0, 3.0));
        let ci = s.median_ci.unwrap();
        assert_eq!((ci.lo, ci.hi, ci.level), (1.0, 3.0, 0.75));
        let ci = Spread::of(&[5.0, 1.0, 4.0, 2.0, 3.0]).median_ci.unwrap();
        assert_eq!((ci.lo, ci.hi, ci.level), (1.0, 5.0, 0.9375));
        // 9 runs: [x(2), x(8)] covers 1 - 2 * 10/512 = 96.1%; [x(3), x(7)] only 82%.
        let xs: Vec<f64> = (1..=9).map(f64::from).collect();
        let ci = Spread::of(&xs).median_ci.unwrap();
        assert_eq!((ci.lo, ci.hi), (2.0, 8.0));
        assert!((ci.level - (1.0 - 20.0 / 512.0)).abs() < 1e-12, "{}", ci.level);
        assert!(Spread::of(&[1.0]).median_ci.is_none());
    }

    #[test]
    fn the_mann_whitney_distribution_is_exact() {
        // 3 against 3: 20 arrangements, one each with U = 0 and U = 9.
        let cdf = mann_whitney_cdf(3, 3);
        assert_eq!(cdf.len(), 10);
        assert!((cdf[0] - 1.0 / 20.0).abs() < 1e-15 && (cdf[1] - 2.0 / 20.0).abs() < 1e-15);
        assert!((cdf[9] - 1.0).abs() < 1e-15);
        // Symmetric: P(U <= u) = P(U >= mn - u).
        let cdf = mann_whitney_cdf(4, 7);
        for u in 0..28 {
            let above = 1.0 - cdf[27 - u];
            assert!((cdf[u] - above).abs() < 1e-12, "u {u}");
        }
        // 5 against 5: P(U <= 2) = 4/252.
        assert!((mann_whitney_cdf(5, 5)[2] - 4.0 / 252.0).abs() < 1e-15);
    }

    #[test]
    fn the_ratio_interval_tells_noise_from_a_shift() {
        let base = [1.00, 1.03, 0.98, 1.10, 1.01];
        // The same distribution: the interval covers 1.
        let same = [1.02, 0.99, 1.07, 1.00, 1.04];
        let (r, ci) = ratio(&base, &same).unwrap();
        assert!(ci.lo < 1.0 && ci.hi > 1.0 && ci.lo <= r && r <= ci.hi, "{r} {ci:?}");
        assert!((ci.level - (1.0 - 2.0 * 4.0 / 252.0)).abs() < 1e-12, "{ci:?}");
        // 30% slower with the same spread: the whole interval is well above 1.
        let slower: Vec<f64> = base.iter().map(|x| x * 1.3).collect();
        let (r, ci) = ratio(&base, &slower).unwrap();
        assert!((r - 1.3).abs() < 1e-9 && ci.lo > 1.15, "{r} {ci:?}");
        // 3 against 3: the widest interval, [min, max] of the 9 ratios, covers 90%.
        let (_, ci) = ratio(&[1.0, 1.1, 1.2], &[1.0, 1.1, 1.2]).unwrap();
        assert!((ci.level - 0.9).abs() < 1e-12 && (ci.lo - 1.0 / 1.2).abs() < 1e-12, "{ci:?}");
        assert!(ratio(&[1.0], &[1.0, 2.0]).is_none());
        assert!(ratio(&[1.0, 0.0], &[1.0, 2.0]).is_none());
    }
}
