//! Random streams and sampling functions, for both widths.
//!
//! Every path (pixel, sample) owns its own stream: a 64-bit key mixed from
//! (seed, pixel, sample) seeds rand_xoshiro's `Xoshiro128Plus` through
//! SplitMix64 (`seed_from_u64`). The scalar kernel draws from that generator
//! directly; the SIMD kernel runs the same xoshiro128+ step lane by lane in
//! `u32x8` ([`Xoshiro128PlusX8`]), so lane k draws exactly what the scalar path
//! draws (tested below against rand_xoshiro itself).
//!
//! Sampling functions are branch-free (no rejection loops), so every path draws
//! the same number of values per event on both widths: camera jitter 2, lens 2,
//! lambertian 2, metal 2, dielectric 1.

use crate::real::{Lanes32, Real, Wide};
use crate::vec3::V3;
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro128Plus;
use wide::u32x8;

/// SplitMix64's output function (Steele, Lea and Flood 2014), a bijective mixer.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The seed of the stream of path (`pixel`, `sample`) of a render with `seed`.
/// `pixel` is the index `y * width + x` in the full image, so a path's stream
/// does not depend on tiles, threads or the render region.
#[inline]
pub fn path_key(seed: u64, pixel: u64, sample: u64) -> u64 {
    mix64(mix64(mix64(seed) ^ pixel) ^ sample.wrapping_mul(0xD2B7_4407_B1CE_6E93))
}

/// The four xoshiro128+ state words of a path's stream.
#[inline]
pub fn path_state(seed: u64, pixel: u64, sample: u64) -> [u32; 4] {
    let rng = Xoshiro128Plus::seed_from_u64(path_key(seed, pixel, sample));
    let b = rng.state();
    std::array::from_fn(|i| u32::from_le_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]]))
}

/// A source of uniform reals in [0, 1), one per lane.
pub trait Stream<R: Real> {
    fn next(&mut self) -> R;
}

/// The scalar stream: rand_xoshiro's generator, used as is.
pub struct ScalarStream(pub Xoshiro128Plus);

impl ScalarStream {
    pub fn for_path(seed: u64, pixel: u64, sample: u64) -> Self {
        ScalarStream(Xoshiro128Plus::seed_from_u64(path_key(seed, pixel, sample)))
    }
}

impl Stream<f32> for ScalarStream {
    #[inline(always)]
    fn next(&mut self) -> f32 {
        f32::unit_from_bits(self.0.next_u32())
    }
}

/// xoshiro128+ generators side by side, one per lane (8 in `u32x8`, 16 in `u32x16`).
#[derive(Clone, Copy, Debug)]
pub struct XoshiroLanes<U> {
    pub s: [U; 4],
}

/// Eight lanes, as the tests and the 8-wide kernel name them.
pub type Xoshiro128PlusX8 = XoshiroLanes<u32x8>;

impl<U: Lanes32> XoshiroLanes<U> {
    /// The next 32 bits of every lane: exactly `Xoshiro128Plus::next_u32`.
    #[inline(always)]
    pub fn next_u32(&mut self) -> U {
        let [s0, s1, s2, s3] = self.s;
        let result = s0 + s3; // wrapping, as in rand_xoshiro
        let t = s1 << 9;
        let s2 = s2 ^ s0;
        let s3 = s3 ^ s1;
        let s1 = s1 ^ s2;
        let s0 = s0 ^ s3;
        let s2 = s2 ^ t;
        let s3 = (s3 << 11) | (s3 >> 21);
        self.s = [s0, s1, s2, s3];
        result
    }
}

impl<W: Wide> Stream<W> for XoshiroLanes<W::U> {
    #[inline(always)]
    fn next(&mut self) -> W {
        W::unit_from_bits(self.next_u32())
    }
}

const PI: f32 = std::f32::consts::PI;
const HALF_PI: f32 = std::f32::consts::FRAC_PI_2;

/// `(cos a, sin a)` for `a = 2 pi (u - 1/2)`, a uniform angle in [-pi, pi) when u
/// is uniform in [0, 1). Written with +, -, * and select only, so both widths
/// agree bit for bit. Range-reduced to [-pi/2, pi/2] by symmetry, then Taylor
/// polynomials of degree 11 (sin) and 14 (cos): absolute error below 1e-7 for
/// the f32 angle; the angle itself rounds to within ~2.1e-7 of `2 pi (u - 1/2)`
/// near +-pi (half an ulp there, plus the f32 constants 2 pi and pi), so against
/// the exact angle the error is at most 2.08e-7 (measured over every u on the
/// 2^-24 grid the streams draw).
#[inline(always)]
pub fn cos_sin_turn<R: Real>(u: R) -> (R, R) {
    let a = (u - R::splat(0.5)) * R::splat(2.0 * PI);
    // Fold |a| > pi/2 onto pi - a (sin unchanged, cos negated).
    let fold = a.abs().gt(R::splat(HALF_PI));
    let x = R::select(fold, R::splat(PI).copysign(a) - a, a);
    let x2 = x * x;
    let sin = x
        * (R::splat(1.0)
            + x2 * (R::splat(-1.0 / 6.0)
                + x2 * (R::splat(1.0 / 120.0)
                    + x2 * (R::splat(-1.0 / 5040.0)
                        + x2 * (R::splat(1.0 / 362_880.0) + x2 * R::splat(-1.0 / 39_916_800.0))))));
    let cos = R::splat(1.0)
        + x2 * (R::splat(-0.5)
            + x2 * (R::splat(1.0 / 24.0)
                + x2 * (R::splat(-1.0 / 720.0)
                    + x2 * (R::splat(1.0 / 40_320.0)
                        + x2 * (R::splat(-1.0 / 3_628_800.0) + x2 * R::splat(1.0 / 479_001_600.0))))));
    (R::select(fold, -cos, cos), sin)
}

/// A uniform direction on the unit sphere (Archimedes: z uniform in [-1, 1]).
#[inline(always)]
pub fn unit_vector<R: Real, S: Stream<R>>(rng: &mut S) -> V3<R> {
    let z = R::splat(1.0) - R::splat(2.0) * rng.next();
    let r = (R::splat(1.0) - z * z).max(R::splat(0.0)).sqrt();
    let (c, s) = cos_sin_turn(rng.next());
    V3::new(r * c, r * s, z)
}

/// A uniform point in the unit disk, as (x, y) (polar map: r = sqrt(u)).
#[inline(always)]
pub fn in_unit_disk<R: Real, S: Stream<R>>(rng: &mut S) -> (R, R) {
    let r = rng.next().sqrt();
    let (c, s) = cos_sin_turn(rng.next());
    (r * c, r * s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f32x8;

    fn lanes(keys: [(u64, u64, u64); 8]) -> Xoshiro128PlusX8 {
        let st: Vec<[u32; 4]> = keys.iter().map(|&(a, b, c)| path_state(a, b, c)).collect();
        Xoshiro128PlusX8 { s: std::array::from_fn(|w| u32x8::new(std::array::from_fn(|k| st[k][w]))) }
    }

    #[test]
    fn lanes_draw_exactly_what_rand_xoshiro_draws() {
        let keys: [(u64, u64, u64); 8] = std::array::from_fn(|k| (7, 1000 + k as u64 * 13, k as u64 % 3));
        let mut x8 = lanes(keys);
        let mut scalar: Vec<Xoshiro128Plus> =
            keys.iter().map(|&(a, b, c)| Xoshiro128Plus::seed_from_u64(path_key(a, b, c))).collect();
        for _ in 0..1000 {
            let w = x8.next_u32().to_array();
            for k in 0..8 {
                assert_eq!(w[k], scalar[k].next_u32());
            }
        }
    }

    #[test]
    fn float_streams_agree() {
        let keys: [(u64, u64, u64); 8] = std::array::from_fn(|k| (42, k as u64, 5));
        let mut x8 = lanes(keys);
        let mut sc: Vec<ScalarStream> = keys.iter().map(|&(a, b, c)| ScalarStream::for_path(a, b, c)).collect();
        for _ in 0..200 {
            let w: f32x8 = x8.next();
            let v3: V3<f32x8> = unit_vector(&mut x8);
            for (k, sk) in sc.iter_mut().enumerate() {
                assert_eq!(w.to_array()[k].to_bits(), Stream::<f32>::next(sk).to_bits());
                let s: V3<f32> = unit_vector(sk);
                assert_eq!(s.x.to_bits(), v3.x.to_array()[k].to_bits());
                assert_eq!(s.y.to_bits(), v3.y.to_array()[k].to_bits());
                assert_eq!(s.z.to_bits(), v3.z.to_array()[k].to_bits());
            }
        }
    }

    #[test]
    fn cos_sin_is_accurate() {
        // Every u the streams can draw (k 2^-24). The bound is the polynomials'
        // 1e-7 plus the rounding of the f32 angle near +-pi (see cos_sin_turn).
        for k in 0..(1u32 << 24) {
            let u = k as f32 * (1.0 / 16_777_216.0);
            let (c, s) = cos_sin_turn(u);
            let a = (u as f64 - 0.5) * 2.0 * std::f64::consts::PI;
            assert!((c as f64 - a.cos()).abs() < 2.5e-7, "cos at {u}");
            assert!((s as f64 - a.sin()).abs() < 2.5e-7, "sin at {u}");
        }
    }

    #[test]
    fn streams_differ_between_paths() {
        assert_ne!(path_state(1, 0, 0), path_state(1, 1, 0));
        assert_ne!(path_state(1, 0, 0), path_state(1, 0, 1));
        assert_ne!(path_state(1, 0, 0), path_state(2, 0, 0));
    }
}
