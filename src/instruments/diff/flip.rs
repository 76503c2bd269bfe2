//! LDR-FLIP, NVIDIA's perceptual difference of two images (Andersson,
//! Nilsson, Akenine-Möller, Oskarsson, Åström and Fairchild, "FLIP: A
//! Difference Evaluator for Alternating Images", HPG 2020), computed as
//! NVIDIA's reference implementation computes it (`FLIP.h` of FLIP 1.6: its
//! constants, its separated filters, its clamped borders, in f32): the
//! unit tests hold it to values that implementation gives.
//!
//! Both images are linear RGB in [0, 1] (values outside are clamped), as a
//! display shows them, seen at `ppd` pixels per degree of visual angle
//! ([`DEFAULT_PPD`]: a 0.7 m wide 4K monitor seen from 0.7 m). Per pixel:
//!
//! 1. **Colour**: both images go to YCxCz (opponent space, D65), are filtered
//!    by the contrast sensitivity functions of the achromatic and the two
//!    chromatic channels (Gaussians, a sum of two for blue-yellow), go back to
//!    linear RGB clamped to [0, 1], then to CIELAB with the Hunt adjustment
//!    (`a` and `b` scaled by `0.01 L`); their HyAB distance
//!    (`|dL| + sqrt(da^2 + db^2)`) to the power 0.7 is mapped to [0, 1]: the
//!    lower 40% of the largest possible distance (green against blue) to
//!    [0, 0.95], the rest to (0.95, 1].
//! 2. **Features**: the luminance of each image is filtered by the first and
//!    second derivatives of a Gaussian (standard deviation `0.5 * 0.082 * ppd`
//!    pixels): edges and points. The feature difference is
//!    `(max(|edge_a - edge_b|, |point_a - point_b|) / sqrt 2)^0.5`.
//! 3. **FLIP** is `colour^(1 - feature)`: 0 for identical images, at most 1.
//!
//! HDR-FLIP (exposures of a tone mapper) is not implemented.

// The constants as FLIP writes them (nine or more digits: the same f32 in C++ and here).
#![allow(clippy::excessive_precision)]

use rayon::prelude::*;
// FLIP's 3.14159265358979f: the same f32.
use std::f32::consts::PI;

/// FLIP's pixels per degree by default: a 0.7 m wide monitor of 3840 pixels
/// seen from 0.7 m (67.02).
pub const DEFAULT_PPD: f32 = 0.7 * (3840.0 / 0.7) * (PI / 180.0);

/// Colour difference exponent, cut-off fraction of the largest difference, and where it maps to.
const GQC: f32 = 0.7;
const GPC: f32 = 0.4;
const GPT: f32 = 0.95;
/// Feature detector's width (degrees) and exponent.
const GW: f32 = 0.082;
const GQF: f32 = 0.5;
/// The contrast sensitivity Gaussians `a sqrt(pi / b) exp(-pi^2 x^2 / b)`,
/// per channel (Y, Cx, Cz); the second is used by Cz only.
const A1: [f32; 3] = [1.0, 1.0, 34.1];
const B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const A2Z: f32 = 13.5;
const B2Z: f32 = 0.025;
/// D65, and its inverse, as FLIP writes them.
const ILLUMINANT: [f32; 3] = [0.950428545, 1.000000000, 1.088900371];
const INV_ILLUMINANT: [f32; 3] = [1.052156925, 1.000000000, 0.918357670];

type C3 = [f32; 3];

/// The sRGB transfer function's inverse: an encoded value in [0, 1] (as a
/// display receives it) to linear light.
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_rgb_to_xyz(c: C3) -> C3 {
    let m = [
        [10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0],
        [2613072.0 / 12288897.0, 8788810.0 / 12288897.0, 887015.0 / 12288897.0],
        [1425312.0 / 73733382.0, 8788810.0 / 73733382.0, 70074185.0 / 73733382.0],
    ];
    m.map(|r: [f32; 3]| r[0] * c[0] + r[1] * c[1] + r[2] * c[2])
}

fn xyz_to_linear_rgb(c: C3) -> C3 {
    let m = [
        [3.241003275, -1.537398934, -0.498615861],
        [-0.969224334, 1.875930071, 0.041554224],
        [0.055639423, -0.204011202, 1.057148933],
    ];
    m.map(|r: [f32; 3]| r[0] * c[0] + r[1] * c[1] + r[2] * c[2])
}

fn xyz_to_lab(c: C3) -> C3 {
    let delta = 6.0f32 / 29.0;
    let delta_square = delta * delta;
    let delta_cube = delta * delta_square;
    let factor = 1.0 / (3.0 * delta_square);
    let term = 4.0f32 / 29.0;
    let f = |v: f32| if v > delta_cube { v.powf(1.0 / 3.0) } else { factor * v + term };
    let [x, y, z] = [f(c[0] * INV_ILLUMINANT[0]), f(c[1] * INV_ILLUMINANT[1]), f(c[2] * INV_ILLUMINANT[2])];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn xyz_to_ycxcz(c: C3) -> C3 {
    let [x, y, z] = [c[0] * INV_ILLUMINANT[0], c[1] * INV_ILLUMINANT[1], c[2] * INV_ILLUMINANT[2]];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_xyz(c: C3) -> C3 {
    let y = (c[0] + 16.0) / 116.0;
    let (cx, cz) = (c[1] / 500.0, c[2] / 200.0);
    [(y + cx) * ILLUMINANT[0], y * ILLUMINANT[1], (y - cz) * ILLUMINANT[2]]
}

/// CIELAB with the Hunt adjustment: chroma scaled by `0.01 L`.
fn lab_hunt(linear: C3) -> C3 {
    let [l, a, b] = xyz_to_lab(linear_rgb_to_xyz(linear));
    [l, 0.01 * l * a, 0.01 * l * b]
}

fn hyab(p: C3, q: C3) -> f32 {
    (p[0] - q[0]).abs() + ((p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2])).sqrt()
}

/// The largest colour difference (green against blue), to the power `GQC`.
fn max_distance() -> f32 {
    hyab(lab_hunt([0.0, 1.0, 0.0]), lab_hunt([0.0, 0.0, 1.0])).powf(GQC)
}

/// `a sqrt(pi / b) exp(-pi^2 x2 / b)`; with `root`, the square root of the
/// factor (each of the two separated passes of a sum of Gaussians takes it).
fn gaussian(x2: f32, a: f32, b: f32, root: bool) -> f32 {
    let pi_sq = PI * PI;
    let k = a * (PI / b).sqrt();
    (if root { k.sqrt() } else { k }) * (-pi_sq * x2 / b).exp()
}

/// The separated spatial filters: per tap, (Y, Cx) and the two Gaussians of Cz.
fn spatial_filters(ppd: f32) -> (Vec<[f32; 2]>, Vec<[f32; 2]>) {
    let max_b = B1.iter().fold(B2Z, |m, &b| m.max(b)).max(1.0e-5);
    let radius = (3.0 * (max_b / (2.0 * (PI * PI))).sqrt() * ppd).ceil() as i32;
    let dx = 1.0 / ppd;
    let (mut ycx, mut cz) = (Vec::new(), Vec::new());
    let (mut sum_ycx, mut sum_cz) = ([0.0f32; 2], [0.0f32; 2]);
    for x in -radius..=radius {
        let ix = x as f32 * dx;
        let x2 = ix * ix;
        let v = [gaussian(x2, A1[0], B1[0], false), gaussian(x2, A1[1], B1[1], false)];
        let w = [gaussian(x2, A1[2], B1[2], true), gaussian(x2, A2Z, B2Z, true)];
        for k in 0..2 {
            sum_ycx[k] += v[k];
            sum_cz[k] += w[k];
        }
        ycx.push(v);
        cz.push(w);
    }
    let norm_cz = 1.0 / (sum_cz[0] * sum_cz[0] + sum_cz[1] * sum_cz[1]).sqrt();
    let norm_ycx = [1.0 / sum_ycx[0], 1.0 / sum_ycx[1]];
    ycx.iter_mut().for_each(|v| *v = [v[0] * norm_ycx[0], v[1] * norm_ycx[1]]);
    cz.iter_mut().for_each(|w| *w = [w[0] * norm_cz, w[1] * norm_cz]);
    (ycx, cz)
}

/// The separated feature filter: per tap, the Gaussian, its first and its
/// second derivative, normalized as FLIP does (the Gaussian sums to 1, the
/// positive and the negative weights of each derivative to 1 and -1).
fn feature_filter(ppd: f32) -> Vec<C3> {
    let sd = 0.5 * GW * ppd;
    let radius = (3.0 * sd).ceil() as i32;
    let mut taps = Vec::new();
    let (mut g_sum, mut dg_pos, mut dg_neg, mut ddg_pos, mut ddg_neg) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for x in -radius..=radius {
        let xf = x as f32;
        let g = (-(xf * xf) / (2.0 * sd * sd)).exp();
        g_sum += g;
        let dg = -xf * g;
        if dg > 0.0 {
            dg_pos += dg;
        } else {
            dg_neg -= dg;
        }
        let ddg = (xf * xf / (sd * sd) - 1.0) * g;
        if ddg > 0.0 {
            ddg_pos += ddg;
        } else {
            ddg_neg -= ddg;
        }
        taps.push([g, dg, ddg]);
    }
    for t in &mut taps {
        *t = [
            t[0] / g_sum,
            t[1] / if t[1] > 0.0 { dg_pos } else { dg_neg },
            t[2] / if t[2] > 0.0 { ddg_pos } else { ddg_neg },
        ];
    }
    taps
}

/// Row-major images of `width` pixels a row, filtered by rows in parallel.
struct Plane {
    width: usize,
    height: usize,
}

impl Plane {
    /// The pixel `d` steps from `i` along the row, clamped to the image.
    fn across(&self, i: usize, d: i32) -> usize {
        let (y, x) = (i / self.width, (i % self.width) as i64);
        y * self.width + (x + d as i64).clamp(0, self.width as i64 - 1) as usize
    }
    /// The pixel `d` steps from `i` along the column, clamped to the image.
    fn down(&self, i: usize, d: i32) -> usize {
        let (y, x) = ((i / self.width) as i64, i % self.width);
        (y + d as i64).clamp(0, self.height as i64 - 1) as usize * self.width + x
    }
    /// `out[i] = f(i)` for every pixel, rows in parallel.
    fn fill<T: Send>(&self, out: &mut [T], f: impl Fn(usize) -> T + Sync) {
        out.par_chunks_mut(self.width).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                *o = f(y * self.width + x);
            }
        });
    }
}

/// The FLIP error of every pixel of `test` against `reference` (linear RGB,
/// row-major, `width` x `height`, clamped to [0, 1]), seen at `ppd` pixels
/// per degree.
pub fn ldr_flip(reference: &[C3], test: &[C3], width: usize, height: usize, ppd: f32) -> Vec<f32> {
    assert!(reference.len() == width * height && test.len() == width * height, "sizes differ");
    let plane = Plane { width, height };
    let to_ycxcz = |img: &[C3]| -> Vec<C3> {
        img.par_iter().map(|c| xyz_to_ycxcz(linear_rgb_to_xyz(c.map(|v| v.clamp(0.0, 1.0))))).collect()
    };
    let (r, t) = (to_ycxcz(reference), to_ycxcz(test));
    let mut error = vec![0.0f32; width * height];
    colour_difference(&plane, &r, &t, ppd, &mut error);
    feature_difference(&plane, &r, &t, ppd, &mut error);
    error
}

/// Step 1: the filtered images' colour difference, into `out`.
fn colour_difference(plane: &Plane, r: &[C3], t: &[C3], ppd: f32, out: &mut [f32]) {
    let (ycx, cz) = spatial_filters(ppd);
    let half = (ycx.len() / 2) as i32;
    // Along rows: (Y, Cx) and the two Gaussians of Cz, of each image.
    let mut mid = vec![[[0.0f32; 4]; 2]; r.len()];
    plane.fill(&mut mid, |i| {
        let mut acc = [[0.0f32; 4]; 2];
        for d in -half..=half {
            let (w, v) = (ycx[(d + half) as usize], cz[(d + half) as usize]);
            let j = plane.across(i, d);
            for (a, img) in acc.iter_mut().zip([r, t]) {
                let c = img[j];
                a[0] += w[0] * c[0];
                a[1] += w[1] * c[1];
                a[2] += v[0] * c[2];
                a[3] += v[1] * c[2];
            }
        }
        acc
    });
    let cmax = max_distance();
    let pccmax = GPC * cmax;
    plane.fill(out, |i| {
        let mut acc = [[0.0f32; 4]; 2];
        for d in -half..=half {
            let (w, v) = (ycx[(d + half) as usize], cz[(d + half) as usize]);
            let m = mid[plane.down(i, d)];
            for (a, c) in acc.iter_mut().zip(m) {
                a[0] += w[0] * c[0];
                a[1] += w[1] * c[1];
                a[2] += v[0] * c[2];
                a[3] += v[1] * c[3];
            }
        }
        let lab = acc.map(|a| {
            let rgb = xyz_to_linear_rgb(ycxcz_to_xyz([a[0], a[1], a[2] + a[3]]));
            lab_hunt(rgb.map(|v| v.clamp(0.0, 1.0)))
        });
        let d = hyab(lab[0], lab[1]).powf(GQC);
        if d < pccmax {
            d * (GPT / pccmax)
        } else {
            GPT + ((d - pccmax) / (cmax - pccmax)) * (1.0 - GPT)
        }
    });
}

/// Steps 2 and 3: the feature difference, and FLIP from `error` (the colour
/// difference) in place.
fn feature_difference(plane: &Plane, r: &[C3], t: &[C3], ppd: f32, error: &mut [f32]) {
    let taps = feature_filter(ppd);
    let half = (taps.len() / 2) as i32;
    // Luminance normalized to [0, 1].
    let grey = |c: C3| c[0] * (1.0 / 116.0) + 16.0 / 116.0;
    // Along rows: the first and second derivatives and the Gaussian, of each image.
    let mut mid = vec![[[0.0f32; 3]; 2]; r.len()];
    plane.fill(&mut mid, |i| {
        let mut acc = [[0.0f32; 3]; 2];
        for d in -half..=half {
            let w = taps[(d + half) as usize];
            let j = plane.across(i, d);
            for (a, img) in acc.iter_mut().zip([r, t]) {
                let y = grey(img[j]);
                a[0] += w[1] * y;
                a[1] += w[2] * y;
                a[2] += w[0] * y;
            }
        }
        acc
    });
    let colour = error.to_vec();
    plane.fill(error, |i| {
        // Per image: dx, ddx, dy, ddy.
        let mut acc = [[0.0f32; 4]; 2];
        for d in -half..=half {
            let w = taps[(d + half) as usize];
            let m = mid[plane.down(i, d)];
            for (a, c) in acc.iter_mut().zip(m) {
                a[0] += w[0] * c[0];
                a[1] += w[0] * c[1];
                a[2] += w[1] * c[2];
                a[3] += w[2] * c[2];
            }
        }
        let edge = acc.map(|a| (a[0] * a[0] + a[2] * a[2]).sqrt());
        let point = acc.map(|a| (a[1] * a[1] + a[3] * a[3]).sqrt());
        let diff = (edge[0] - edge[1]).abs().max((point[0] - point[1]).abs());
        let feature = ((1.0 / 2.0f32.sqrt()) * diff).powf(GQF);
        colour[i].powf(1.0 - feature)
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The synthetic images the reference values were computed on (the
    /// same formulas, in f32, fed to NVIDIA's `FLIP::evaluate` for LDR).
    fn synthetic(w: usize, h: usize, which: u32) -> Vec<C3> {
        let mut out = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let mut r = ((x * 7) % w) as f32 / (w - 1) as f32;
                let mut g = ((y * 5) % h) as f32 / (h - 1) as f32;
                let mut b = ((x + 2 * y) % 5) as f32 / 4.0;
                if which == 1 {
                    if x >= w / 4 && x < w / 2 && y >= h / 4 && y < h / 2 {
                        (r, g, b) = (1.0, 1.0, 1.0);
                    }
                    if y == h - 3 {
                        (r, g, b) = (r * 0.5, g * 0.5, b * 0.5);
                    }
                    if x > 3 * w / 4 {
                        b = 1.0 - b;
                    }
                } else if which == 2 {
                    let mut s = (x as u32).wrapping_mul(73856093) ^ (y as u32).wrapping_mul(19349663);
                    s ^= s >> 13;
                    s = s.wrapping_mul(0x5bd1_e995);
                    s ^= s >> 15;
                    let n = (s & 0xffff) as f32 / 65535.0 - 0.5;
                    r = (r + 0.1 * n).clamp(0.0, 1.0);
                    g = (g - 0.05 * n).clamp(0.0, 1.0);
                }
                out.push([r, g, b]);
            }
        }
        out
    }

    /// FLIP of `which` against image 0: its mean and the pixels listed.
    fn check(w: usize, h: usize, which: u32, ppd: f32, mean: f64, pixels: &[((usize, usize), f32)]) {
        let map = ldr_flip(&synthetic(w, h, 0), &synthetic(w, h, which), w, h, ppd);
        let got = map.iter().map(|&v| v as f64).sum::<f64>() / map.len() as f64;
        assert!((got - mean).abs() < 2e-6, "{w}x{h} image {which} at {ppd} ppd: mean {got}, reference {mean}");
        for &((x, y), want) in pixels {
            let v = map[y * w + x];
            assert!((v - want).abs() < 2e-5, "{w}x{h} image {which}: pixel ({x}, {y}) {v}, reference {want}");
        }
    }

    /// The values of NVIDIA's implementation (FLIP 1.6, `FLIP::evaluate`
    /// with LDR, compiled with g++ -O1 on x86-64) for the synthetic images.
    #[test]
    fn flip_gives_the_reference_implementations_values() {
        assert!((DEFAULT_PPD - 67.020_645).abs() < 1e-4);
        check(
            40,
            30,
            1,
            DEFAULT_PPD,
            0.164_797_278,
            &[((0, 0), 9.430_18e-5), ((10, 7), 0.820_555_03), ((20, 15), 0.407_781_84), ((39, 29), 0.380_970_8)],
        );
        check(40, 30, 1, DEFAULT_PPD, 0.164_797_278, &[((13, 27), 0.325_499_6), ((38, 1), 0.322_248_22)]);
        check(
            40,
            30,
            2,
            DEFAULT_PPD,
            0.040_415_681,
            &[((0, 0), 0.149_604_17), ((10, 7), 0.019_281_885), ((39, 29), 0.074_174_374)],
        );
        check(
            40,
            30,
            1,
            10.0,
            0.245_409_611,
            &[((0, 0), 0.0), ((10, 7), 0.990_222_87), ((20, 15), 0.019_482_749), ((38, 1), 0.960_231_25)],
        );
        // Smaller than the filters: every tap clamps to the border.
        check(
            7,
            5,
            1,
            DEFAULT_PPD,
            0.413_734_897,
            &[((0, 0), 0.563_422_7), ((1, 1), 0.858_827_1), ((5, 1), 0.066_800_28)],
        );
    }

    #[test]
    fn identical_images_have_no_error_and_black_against_white_is_large() {
        let a = synthetic(16, 9, 0);
        assert!(ldr_flip(&a, &a, 16, 9, DEFAULT_PPD).iter().all(|&v| v == 0.0));
        let black = vec![[0.0; 3]; 64];
        let white = vec![[1.0; 3]; 64];
        let m = ldr_flip(&black, &white, 8, 8, DEFAULT_PPD);
        assert!(m.iter().all(|&v| v > 0.9 && v <= 1.0), "{m:?}");
        // Out of range values are clamped, as FLIP's LDR input is.
        let bright = vec![[7.0; 3]; 64];
        assert_eq!(ldr_flip(&white, &bright, 8, 8, DEFAULT_PPD), vec![0.0; 64]);
    }
}
