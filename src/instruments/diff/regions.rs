//! Region z-tests: whether two noisy images have the same expected image,
//! region by region, within their noise.
//!
//! The image is split into K x K regions (region (row, col) covers rows
//! `row * H / K .. (row + 1) * H / K` and likewise columns). Each side gives,
//! per region and channel, the mean of its pixels and the variance of that
//! mean, from one of two sources:
//!
//! - **Two independent renders** (different seeds): the side's mean is their
//!   average, and its variance `s^2 = sum_p (x1_p - x2_p)^2 / (4 n^2)`, the
//!   variance of the region's two-render mean estimated from the renders'
//!   per-pixel differences (`n` pixels). Pixels' errors are independent:
//!   every pixel draws its own samples.
//! - **Per-pixel moments** (a film's count, sum and sum of squares): the
//!   variance of a pixel's mean is its samples' variance over their count,
//!   and the region's `s^2 = sum_p var_p / n^2`.
//!
//! Then `z = (mean_a - mean_b) / sqrt(s_a^2 + s_b^2)`: about standard normal
//! when both sides have the same expected image, so `|z| > 3` is rare (0.27%
//! of region-channels). A region-channel without noise on either side has
//! `z = 0` if the means are equal, else an infinite `z`.

use serde::Serialize;
use std::ops::Range;

/// The pixels of region (`row`, `col`) of `k` x `k` over a `width` x `height`
/// image: its rows and its columns.
pub fn bounds(k: usize, width: usize, height: usize, row: usize, col: usize) -> (Range<usize>, Range<usize>) {
    (row * height / k..(row + 1) * height / k, col * width / k..(col + 1) * width / k)
}

/// One region of one side.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Region {
    pub row: usize,
    pub col: usize,
    pub pixels: usize,
    /// Per channel, the mean of the region's pixels.
    pub mean: [f64; 3],
    /// Per channel, the variance of that mean.
    pub var: [f64; 3],
    /// Two renders only: per channel, render 1's mean minus render 2's.
    #[serde(skip)]
    pub split: Option<[f64; 3]>,
}

/// A side's regions.
#[derive(Clone, Debug, PartialEq)]
pub struct Regions {
    pub k: usize,
    pub cells: Vec<Region>,
}

/// Per pixel, its mean and the variance of its mean; with the difference of
/// two renders if the side has two.
pub type PixelStats = ([f64; 3], [f64; 3], Option<[f64; 3]>);

impl Regions {
    /// The regions of a side, from each pixel's statistics (`pixel(i)`, `i`
    /// row-major over `width` x `height`).
    pub fn new(k: usize, width: usize, height: usize, pixel: impl Fn(usize) -> PixelStats) -> Regions {
        let mut cells = Vec::with_capacity(k * k);
        for row in 0..k {
            for col in 0..k {
                let (ys, xs) = bounds(k, width, height, row, col);
                let n = ys.len() * xs.len();
                let (mut sum, mut var, mut split) = ([0.0; 3], [0.0; 3], None::<[f64; 3]>);
                for y in ys {
                    for x in xs.clone() {
                        let (m, v, d) = pixel(y * width + x);
                        for c in 0..3 {
                            sum[c] += m[c];
                            var[c] += v[c];
                        }
                        if let Some(d) = d {
                            let s = split.get_or_insert([0.0; 3]);
                            (0..3).for_each(|c| s[c] += d[c]);
                        }
                    }
                }
                let per = |v: f64| v / n.max(1) as f64;
                let var = var.map(|v| per(v) / n.max(1) as f64);
                cells.push(Region { row, col, pixels: n, mean: sum.map(per), var, split: split.map(|s| s.map(per)) });
            }
        }
        Regions { k, cells }
    }

    /// A side of two independent renders, `first(i)` and `second(i)` (pixel
    /// `i`, linear values).
    pub fn two_renders(
        k: usize,
        width: usize,
        height: usize,
        first: impl Fn(usize) -> [f64; 3],
        second: impl Fn(usize) -> [f64; 3],
    ) -> Regions {
        Regions::new(k, width, height, |i| {
            let (p, q) = (first(i), second(i));
            let d: [f64; 3] = std::array::from_fn(|c| p[c] - q[c]);
            (std::array::from_fn(|c| 0.5 * (p[c] + q[c])), d.map(|d| d * d / 4.0), Some(d))
        })
    }

    /// Seed against seed on a side of two renders: per region and channel,
    /// `(mean1 - mean2) / (2 s)` (the difference of the two means has
    /// variance `4 s^2`), whose root mean square is about 1 when pixels'
    /// errors are independent and the estimate is right. The root mean
    /// square and the region-channels it covers (those with noise); `None`
    /// for a side of moments.
    pub fn self_check(&self) -> Option<(f64, usize)> {
        let mut z2 = Vec::new();
        for r in &self.cells {
            let d = r.split?;
            z2.extend((0..3).filter(|&c| r.var[c] > 0.0).map(|c| d[c] * d[c] / (4.0 * r.var[c])));
        }
        Some(((z2.iter().sum::<f64>() / z2.len().max(1) as f64).sqrt(), z2.len()))
    }
}

/// The z of one region-channel: `d / s`, 0 when both are 0, infinite when
/// only `s` is.
fn z_of(d: f64, s: f64) -> f64 {
    if s > 0.0 {
        d / s
    } else if d == 0.0 {
        0.0
    } else {
        d.signum() * f64::INFINITY
    }
}

/// The z-tests of two sides' regions.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ZTest {
    /// K (the image is split into K x K regions).
    pub regions: usize,
    /// A region-channel fails when `|z|` is above this.
    pub threshold: f64,
    /// Region-channels tested (3 K^2).
    pub count: usize,
    /// Region-channels with `|z|` above the threshold.
    pub over: usize,
    /// The root mean square of z over every region-channel (about 1 when the
    /// sides agree within their noise; `null` when infinite).
    pub rms: f64,
    /// The region-channel of the largest `|z|`.
    pub worst: Worst,
    /// Every region: its z per channel (`null` where infinite).
    pub cells: Vec<RegionZ>,
}

/// Where the largest `|z|` is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Worst {
    pub row: usize,
    pub col: usize,
    /// 0, 1, 2: red, green, blue.
    pub channel: usize,
    pub z: f64,
}

/// One region's z-test.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RegionZ {
    pub row: usize,
    pub col: usize,
    pub z: [f64; 3],
}

impl ZTest {
    /// Compares side `a` with side `b` (the same K): `z = (a - b) / sqrt(s_a^2 + s_b^2)`.
    pub fn new(a: &Regions, b: &Regions, threshold: f64) -> ZTest {
        assert_eq!(a.k, b.k, "regions of different splits");
        let mut t = ZTest {
            regions: a.k,
            threshold,
            count: 0,
            over: 0,
            rms: 0.0,
            worst: Worst { row: 0, col: 0, channel: 0, z: 0.0 },
            cells: Vec::with_capacity(a.cells.len()),
        };
        let mut sum_z2 = 0.0;
        for (p, q) in a.cells.iter().zip(&b.cells) {
            let z: [f64; 3] = std::array::from_fn(|c| z_of(p.mean[c] - q.mean[c], (p.var[c] + q.var[c]).sqrt()));
            for (channel, &v) in z.iter().enumerate() {
                t.over += (v.abs() > threshold) as usize;
                sum_z2 += v * v;
                t.count += 1;
                if v.abs() > t.worst.z.abs() {
                    t.worst = Worst { row: p.row, col: p.col, channel, z: v };
                }
            }
            t.cells.push(RegionZ { row: p.row, col: p.col, z });
        }
        t.rms = (sum_z2 / t.count.max(1) as f64).sqrt();
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_cover_the_image_once() {
        for (w, h, k) in [(48, 32, 6), (7, 5, 5), (100, 3, 3), (1, 1, 1)] {
            let mut seen = vec![0; w * h];
            for r in 0..k {
                for c in 0..k {
                    let (ys, xs) = bounds(k, w, h, r, c);
                    for y in ys {
                        for x in xs.clone() {
                            seen[y * w + x] += 1;
                        }
                    }
                }
            }
            assert!(seen.iter().all(|&s| s == 1), "{w}x{h} in {k}x{k}");
        }
    }

    /// Known renders: the means, the variance from the seeds' differences,
    /// z, and the noise check.
    #[test]
    fn two_renders_of_known_values() {
        // 2x2 image, one region: render 1 is 1 everywhere, render 2 is 3 in red.
        let a = Regions::two_renders(1, 2, 2, |_| [1.0, 1.0, 1.0], |_| [3.0, 1.0, 1.0]);
        let r = a.cells[0];
        assert_eq!((r.pixels, r.mean), (4, [2.0, 1.0, 1.0]));
        // s^2 = 4 * (1 - 3)^2 / (4 * 16) = 0.25.
        assert_eq!(r.var, [0.25, 0.0, 0.0]);
        assert_eq!(r.split, Some([-2.0, 0.0, 0.0]));
        // (mean1 - mean2) / (2 s) = -2 / 1: rms 2 over the one noisy channel.
        assert_eq!(a.self_check(), Some((2.0, 1)));
        let b = Regions::two_renders(1, 2, 2, |_| [1.5, 1.0, 1.0], |_| [1.5, 1.0, 2.0]);
        let t = ZTest::new(&a, &b, 3.0);
        // Red: (2 - 1.5) / sqrt(0.25); green: 0 / 0; blue: -0.5 / sqrt(0.0625).
        assert_eq!(t.cells[0].z, [1.0, 0.0, -2.0]);
        assert_eq!((t.count, t.over), (3, 0));
        assert!((t.rms - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert_eq!(t.worst, Worst { row: 0, col: 0, channel: 2, z: -2.0 });
        // A difference where neither side has noise is infinitely significant.
        let c = Regions::two_renders(1, 2, 2, |_| [2.0, 1.1, 1.5], |_| [2.0, 1.1, 1.5]);
        let t = ZTest::new(&a, &c, 3.0);
        assert_eq!(t.cells[0].z, [0.0, -f64::INFINITY, -f64::INFINITY]);
        assert_eq!((t.over, t.rms), (2, f64::INFINITY));
        let m = Regions::new(1, 2, 2, |_| ([1.0; 3], [0.5; 3], None));
        assert_eq!((m.cells[0].var, m.self_check()), ([0.125; 3], None));
    }
}
