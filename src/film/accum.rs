//! The exact, grouping-independent accumulation of samples.
//!
//! Each sample's three f32 channels are converted to fixed point with
//! [`FRACTION_BITS`] fractional bits (a multiplication by a power of two, exact
//! in f64, then rounding to the nearest integer, ties to even) and summed per
//! pixel in `i128`. Integer addition is associative and commutative, so the
//! sum, and the mean computed from it, do not depend on how samples were
//! grouped: by tile, thread, kernel batch, shard or resume point.
//!
//! - **Resolution**: 2^-32 (about 2.3e-10) per sample. Every f32 of magnitude
//!   2^-9 (about 0.002) or more is a multiple of 2^-32 and converts exactly; a
//!   darker sample is rounded by at most 2^-33.
//! - **Range**: a sample is accepted when every channel's magnitude is below
//!   [`SAMPLE_LIMIT`] = 2^31 (about 2.1e9). A sample outside it (and NaN or
//!   Inf) is rejected whole and counted, never added.
//! - **No overflow**: a converted channel is below 2^63 in magnitude and a
//!   pixel takes at most 2^32 - 1 samples (its count is a `u32`), so a sum stays
//!   below 2^95, far inside `i128`.
//! - **Mean**: `(sum as f64 / count as f64 * 2^-32) as f32`, a deterministic
//!   function of the integer sum and the count (0 for a pixel without samples).

/// Fractional bits of the fixed-point samples.
pub const FRACTION_BITS: i32 = 32;

/// A sample is accepted when every channel's magnitude is below this.
pub const SAMPLE_LIMIT: f64 = (1u64 << 31) as f64;

const SCALE: f64 = (1u64 << FRACTION_BITS) as f64;
const INV_SCALE: f64 = 1.0 / SCALE;
/// `SAMPLE_LIMIT * SCALE` = 2^63: the bound after scaling.
const SCALED_LIMIT: f64 = SAMPLE_LIMIT * SCALE;

/// One sample in fixed point, or `None` if a channel is NaN, infinite or
/// outside [`SAMPLE_LIMIT`].
#[inline(always)]
pub fn to_fixed(c: [f32; 3]) -> Option<[i64; 3]> {
    let v = c.map(|x| x as f64 * SCALE);
    // `!(a < b)` is true for NaN too.
    if v[0].abs() < SCALED_LIMIT && v[1].abs() < SCALED_LIMIT && v[2].abs() < SCALED_LIMIT {
        Some(v.map(round_in_range))
    } else {
        None
    }
}

/// `x.round_ties_even() as i64` for `|x| < 2^63` (what [`to_fixed`] checks
/// first): on x86-64 one conversion that rounds to nearest, ties to even (the
/// default rounding mode, which Rust code never changes), instead of a
/// rounding, a conversion and the saturation checks of `as`; elsewhere the
/// portable expression. Equal for every such `x` (the tests compare them on
/// ties, edges and random values).
#[inline(always)]
fn round_in_range(x: f64) -> i64 {
    debug_assert!(x.abs() < SCALED_LIMIT, "{x}");
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    {
        use std::arch::x86_64::{_mm_cvtsd_si64, _mm_set_sd};
        // SAFETY: the two intrinsics need SSE2, which this build enables (the
        // cfg above; it is part of every x86-64 target). They read no memory.
        // In range, cvtsd2si never gives its out-of-range value.
        unsafe { _mm_cvtsd_si64(_mm_set_sd(x)) }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
    {
        x.round_ties_even() as i64
    }
}

/// Scaled channels below this magnitude (samples below 2^19 = 524,288)
/// convert by [`Run::try_add`]'s one addition.
const RUN_SCALED_LIMIT: f64 = (1u64 << 51) as f64;
/// `1.5 * 2^52`: for `|x| < 2^51`, `x + MAGIC` lies in `[2^52, 2^53)`, where
/// the f64 spacing is 1, so the addition rounds `x` to the nearest integer,
/// ties to even (the default rounding mode), and that integer is the
/// difference of the sum's bits and `MAGIC`'s.
const MAGIC: f64 = 6_755_399_441_055_744.0;

/// The fixed-point sums of a run of samples of one pixel, for the common
/// case of samples below 2^19 per channel: each converted channel is below
/// 2^51, so up to [`Run::MAX`] of them sum inside an `i64`. The three
/// channels convert and add as one 4-lane vector (one multiply, one
/// range test, one addition of `1.5 * 2^52` and one integer addition per
/// sample); the sums are exactly [`to_fixed`]'s. A sample outside the fast
/// range is left to the caller ([`to_fixed`], which also rejects NaN and Inf).
#[derive(Clone, Copy, Debug, Default)]
pub struct Run {
    /// Per channel (the fourth lane is unused), the sum of the bits of
    /// `x + MAGIC`, wrapping: `n` times `MAGIC`'s bits more than the sum.
    bits: wide::u64x4,
    n: u32,
}

impl Run {
    /// Samples a run may hold: `2^12 * 2^51 = 2^63`.
    pub const MAX: u32 = 1 << 12;

    /// Adds `c` when every channel is in the fast range (and the run has
    /// room); otherwise adds nothing and returns false.
    #[inline(always)]
    pub fn try_add(&mut self, c: [f32; 3]) -> bool {
        let v = wide::f64x4::from([c[0] as f64, c[1] as f64, c[2] as f64, 0.0]) * wide::f64x4::splat(SCALE);
        // NaN fails the comparison, so it is left to `to_fixed` too.
        let small = v.abs().simd_lt(wide::f64x4::splat(RUN_SCALED_LIMIT)).all();
        if !small || self.n == Self::MAX {
            return false;
        }
        self.bits += bytemuck::cast::<wide::f64x4, wide::u64x4>(v + wide::f64x4::splat(MAGIC));
        self.n += 1;
        true
    }

    /// Samples in the run.
    #[inline(always)]
    pub fn len(&self) -> u32 {
        self.n
    }

    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The run's fixed-point sums, exact: `[to_fixed(c)[k]]` summed over its samples.
    #[inline(always)]
    pub fn sums(&self) -> [i64; 3] {
        let b = self.bits.to_array();
        let m = MAGIC.to_bits().wrapping_mul(self.n as u64);
        [0, 1, 2].map(|k| b[k].wrapping_sub(m) as i64)
    }
}

/// The value a fixed-point sum stands for, in f64 (rounded once).
#[inline]
pub fn to_f64(sum: i128) -> f64 {
    int_to_f64(sum) * INV_SCALE
}

/// `sum as f64`: the integer rounded to the nearest f64, ties to even. A sum
/// that fits an `i64` (every pixel of fewer than 2^31 samples of magnitude
/// below 1) takes the one-instruction conversion of `i64`, which rounds the
/// same value the same way; the `i128` conversion is a library call of
/// about 45 instructions, three per pixel.
#[inline]
pub fn int_to_f64(sum: i128) -> f64 {
    match i64::try_from(sum) {
        Ok(s) => s as f64,
        Err(_) => sum as f64,
    }
}

/// The pixel mean of `n` samples whose fixed-point channel sums are `sum`.
#[inline]
pub fn mean(sum: [i128; 3], n: u32) -> [f32; 3] {
    if n == 0 {
        return [0.0; 3];
    }
    let n = n as f64;
    sum.map(|s| (int_to_f64(s) / n * INV_SCALE) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The `i64` shortcut converts exactly as `i128 as f64` does, at the
    /// edges of the `i64` range, where rounding decides (halfway cases and
    /// their neighbours), and on random sums of every magnitude.
    #[test]
    fn int_to_f64_is_the_i128_conversion() {
        let mut xs: Vec<i128> = vec![0, 1, -1, i64::MAX as i128, i64::MIN as i128, i64::MAX as i128 + 1];
        xs.push(i64::MIN as i128 - 1);
        for e in [24, 53, 54, 62, 63, 64, 94] {
            for d in -3i128..=3 {
                let p = 1i128 << e;
                // Near a power of two, and halfway between two f64 above 2^53.
                xs.extend([p + d, -(p + d), p + (p >> 53) + d, (p | (p >> 52)) + (p >> 54) + d]);
            }
        }
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..100_000 {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let bits = (state >> 58) as u32 + 33;
            let v = ((state as i128) << 32 | (state >> 32) as i128) >> (96 - bits.min(95));
            xs.push(if state & 1 == 0 { v } else { -v });
        }
        for x in xs {
            assert_eq!(int_to_f64(x).to_bits(), (x as f64).to_bits(), "{x}");
        }
    }

    #[test]
    fn bright_samples_convert_exactly_and_dark_ones_round_to_nearest() {
        for x in [0.0f32, 1.0, 0.5, 0.1, 1e3, 2.0f32.powi(-9), -0.75, (SAMPLE_LIMIT as f32).next_down()] {
            let q = to_fixed([x; 3]).unwrap();
            if x.abs() >= 2.0f32.powi(-9) || x == 0.0 {
                assert_eq!(q[0] as f64 * INV_SCALE, x as f64, "{x}");
            }
        }
        // 2^-34 is a quarter step: rounds to 0; 3 * 2^-34 rounds to one step; 2^-33 is a tie -> even (0).
        assert_eq!(to_fixed([2.0f32.powi(-34), 3.0 * 2.0f32.powi(-34), 2.0f32.powi(-33)]), Some([0, 1, 0]));
        assert_eq!(to_fixed([3.0 * 2.0f32.powi(-33), 0.0, 0.0]), Some([2, 0, 0]));
    }

    #[test]
    fn the_fast_rounding_is_round_ties_even_over_the_whole_range() {
        let mut xs: Vec<f64> = vec![0.0, -0.0, 0.5, 1.5, 2.5, -0.5, -1.5, -2.5, 1e-300, -1e-300];
        // Ties and their neighbours at every binade, and the range's edges.
        for e in 0..62 {
            let b = (1u64 << e) as f64;
            for x in [b, b + 0.5, b - 0.5, (b + 0.5).next_up(), (b + 0.5).next_down(), b * 1.75] {
                xs.extend([x, -x]);
            }
        }
        xs.extend([SCALED_LIMIT.next_down(), -SCALED_LIMIT.next_down()]);
        // Random values over the range, in f32 samples scaled as `to_fixed` scales them.
        let mut r = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..200_000 {
            r ^= r << 13;
            r ^= r >> 7;
            r ^= r << 17;
            let f = f32::from_bits(r as u32);
            if f.is_finite() && (f.abs() as f64) < SAMPLE_LIMIT {
                xs.push(f as f64 * SCALE);
            }
        }
        for x in xs {
            assert_eq!(round_in_range(x), x.round_ties_even() as i64, "{x:e}");
        }
    }

    /// The run's sums are exactly the sums of `to_fixed` over every sample
    /// it takes: ties, both signs, the edges of its range, dark samples, and
    /// random ones; samples outside its range, NaN and Inf are left out.
    #[test]
    fn a_run_sums_exactly_what_to_fixed_converts() {
        let edge = ((1u64 << 19) as f32).next_down();
        let mut xs: Vec<f32> = vec![0.0, -0.0, 1.0, -1.0, edge, -edge, 2.0f32.powi(-33), 3.0 * 2.0f32.powi(-33)];
        xs.extend([-2.0f32.powi(-33), 2.0f32.powi(-34), 5.0 * 2.0f32.powi(-34), f32::MIN_POSITIVE, 1e-40]);
        let mut r = 0x2545_F491_4F6C_DD1Du64;
        for _ in 0..100_000 {
            r ^= r << 13;
            r ^= r >> 7;
            r ^= r << 17;
            // Mostly magnitudes below 2^19 (0x4900_0000), any sign; some of any bits.
            let b = r as u32;
            xs.push(f32::from_bits(if b & 7 == 0 { b } else { ((b >> 3) % 0x4900_0000) | (b & 0x8000_0000) }));
        }
        let mut run = Run::default();
        let mut want = [0i64; 3];
        let mut taken = 0;
        for c in xs.chunks_exact(3) {
            let c = [c[0], c[1], c[2]];
            if run.len() == Run::MAX {
                assert_eq!(run.sums(), want);
                (run, want) = (Run::default(), [0; 3]);
            }
            let fits = c.iter().all(|x| (x.abs() as f64) < (1u64 << 19) as f64);
            assert_eq!(run.try_add(c), fits, "{c:?}");
            if fits {
                let q = to_fixed(c).unwrap();
                for k in 0..3 {
                    want[k] += q[k];
                }
                taken += 1;
            }
        }
        assert!(taken > 10_000);
        assert_eq!(run.sums(), want);
        // Full: refuses more, and its sums are still exact at the largest values.
        let mut full = Run::default();
        for _ in 0..Run::MAX {
            assert!(full.try_add([edge, -edge, 0.5]));
        }
        assert!(!full.try_add([0.5; 3]));
        let q = to_fixed([edge, -edge, 0.5]).unwrap();
        assert_eq!(full.sums(), q.map(|x| x * Run::MAX as i64));
        for bad in [f32::NAN, f32::INFINITY, (1u64 << 19) as f32, -1e9] {
            assert!(!Run::default().try_add([0.5, bad, 0.5]), "{bad}");
        }
    }

    #[test]
    fn out_of_range_nan_and_inf_are_refused() {
        for bad in [SAMPLE_LIMIT as f32, -(SAMPLE_LIMIT as f32), f32::MAX, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(to_fixed([0.5, bad, 0.5]), None, "{bad}");
        }
    }

    #[test]
    fn the_largest_sums_do_not_overflow() {
        let q = to_fixed([(SAMPLE_LIMIT as f32).next_down(); 3]).unwrap()[0] as i128;
        let sum = q * u32::MAX as i128;
        assert!(sum < 1i128 << 95);
        let m = mean([sum; 3], u32::MAX);
        assert_eq!(m[0], (SAMPLE_LIMIT as f32).next_down());
    }

    #[test]
    fn the_mean_does_not_depend_on_grouping() {
        // Samples whose f32 running sum depends on the order.
        let xs = [1.0e7f32, 0.3, -1.0e7, 0.7, 1e-5, 3.25, 0.1, 2.0f32.powi(-20)];
        let q: Vec<i128> = xs.iter().map(|&x| to_fixed([x; 3]).unwrap()[0] as i128).collect();
        let all: i128 = q.iter().sum();
        let a: i128 = q[..3].iter().sum::<i128>() + q[3..].iter().rev().sum::<i128>();
        assert_eq!(all, a);
        let f32_fwd = xs.iter().fold(0.0f32, |s, &x| s + x);
        let f32_rev = xs.iter().rev().fold(0.0f32, |s, &x| s + x);
        assert_ne!(f32_fwd, f32_rev, "the example should defeat f32 sums");
        assert_eq!(mean([all; 3], 8), mean([a; 3], 8));
    }
}
