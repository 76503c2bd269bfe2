//! The exact, grouping-independent accumulation of samples.
//!
//! Each sample's three f32 channels are converted to fixed point by the
//! film's [`Scale`]: multiplied by `2^(FRACTION_BITS - e)` (a power of two,
//! exact in f64), then rounded to the nearest integer, ties to even, and summed
//! per pixel in `i128`. Integer addition is associative and commutative, so the
//! sum, and the mean computed from it, do not depend on how samples were
//! grouped: by tile, thread, kernel batch, shard or resume point.
//!
//! The exponent `e` is the film's, chosen once per render from the scene
//! before any work ([`Scale::for_brightness`]: from the brightest emission the
//! scene can produce) and recorded in partial films; films of different
//! exponents are never added. Every scene whose brightest emission is below
//! 2^47 (every preset) has `e = 0`.
//!
//! - **Resolution**: 2^(e-32) per sample (2^-32, about 2.3e-10, at `e = 0`).
//!   Every f32 of magnitude 2^(e-9) or more is a multiple of it and converts
//!   exactly; a darker sample is rounded by at most half of it.
//! - **Range**: a sample is accepted when every channel's magnitude is below
//!   [`SAMPLE_LIMIT`] `* 2^e` (2^63, about 9.2e18, at `e = 0`). A finite sample
//!   outside it is rejected whole and counted as out of range; a sample with a
//!   NaN or infinite channel is rejected and counted as non-finite. Neither is
//!   ever added. At [`MAX_EXPONENT`] the range holds every finite f32.
//! - **No overflow**: a converted channel is below 2^95 in magnitude and a
//!   pixel takes at most 2^32 - 1 samples (its count is a `u32`), so a sum stays
//!   below 2^127, inside `i128`.
//! - **Mean**: `(sum as f64 / count as f64 * 2^(e-32)) as f32`, a deterministic
//!   function of the integer sum, the count and the exponent (0 for a pixel
//!   without samples).

/// Fractional bits of the fixed-point samples at exponent 0.
pub const FRACTION_BITS: i32 = 32;

/// At exponent 0, a sample is accepted when every channel's magnitude is
/// below this (2^63); at exponent `e`, below `SAMPLE_LIMIT * 2^e`.
pub const SAMPLE_LIMIT: f64 = 9_223_372_036_854_775_808.0;

/// Bits of headroom the exponent leaves above the brightest emission: a path
/// whose throughput is below 2^16 times that emission stays in range.
pub const HEADROOM_BITS: u32 = 16;

/// The largest exponent: `SAMPLE_LIMIT * 2^81 = 2^144`, above `f32::MAX * 2^16`,
/// so every finite f32 emission gets an exponent, and at this one every
/// finite sample is in range.
pub const MAX_EXPONENT: u32 = 81;

/// `2^k` for `-1022 <= k <= 1023`, exactly.
const fn pow2(k: i32) -> f64 {
    f64::from_bits(((1023 + k) as u64) << 52)
}

/// Scaled channels below this convert by one rounding to `i64`.
const I64_LIMIT: f64 = pow2(63);
/// `SAMPLE_LIMIT * 2^FRACTION_BITS` = 2^95: the bound after scaling, at any exponent.
const SCALED_LIMIT: f64 = pow2(95);

/// Why a sample was left out of the film.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rejection {
    /// A channel is NaN or infinite.
    NonFinite,
    /// Every channel is finite, but one is outside the film's range ([`Scale::limit`]).
    OutOfRange,
}

/// The film's fixed-point scale: samples are converted as
/// `x * 2^(FRACTION_BITS - exponent)` ([`Scale::to_fixed`]) and sums read back
/// as `sum * 2^(exponent - FRACTION_BITS)`. Exponent 0 is the scale of every
/// scene whose brightest emission is below 2^47 (every preset).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale {
    exponent: u32,
    /// `2^(FRACTION_BITS - exponent)`.
    mul: f64,
    /// `2^(exponent - FRACTION_BITS)`.
    inv: f64,
}

impl Default for Scale {
    fn default() -> Self {
        Scale::UNIT
    }
}

impl Scale {
    /// Exponent 0: resolution 2^-32, range 2^63.
    pub const UNIT: Scale = Scale { exponent: 0, mul: pow2(FRACTION_BITS), inv: pow2(-FRACTION_BITS) };

    /// The scale of exponent `exponent` (`None` above [`MAX_EXPONENT`]).
    pub fn new(exponent: u32) -> Option<Scale> {
        (exponent <= MAX_EXPONENT).then(|| {
            let k = FRACTION_BITS - exponent as i32;
            Scale { exponent, mul: pow2(k), inv: pow2(-k) }
        })
    }

    /// The scale of a render whose brightest emission (the largest channel of
    /// any emitter or background colour) is `brightest`: the smallest exponent
    /// `e >= 0` with `brightest * 2^HEADROOM_BITS < SAMPLE_LIMIT * 2^e`
    /// (0 for every `brightest < 2^47`; [`MAX_EXPONENT`] for NaN, which
    /// validation never lets through).
    pub fn for_brightness(brightest: f64) -> Scale {
        let need = brightest.abs() * pow2(HEADROOM_BITS as i32);
        let mut e = 0;
        while e < MAX_EXPONENT && !(need < SAMPLE_LIMIT * pow2(e as i32)) {
            e += 1;
        }
        Scale::new(e).expect("at most MAX_EXPONENT")
    }

    pub fn exponent(self) -> u32 {
        self.exponent
    }

    /// A sample is accepted when every channel's magnitude is below this:
    /// `SAMPLE_LIMIT * 2^exponent`.
    pub fn limit(self) -> f64 {
        SAMPLE_LIMIT * pow2(self.exponent as i32)
    }

    /// The value of one step of the fixed point: `2^(exponent - FRACTION_BITS)`.
    pub fn resolution(self) -> f64 {
        self.inv
    }

    /// One sample in fixed point, or why it is rejected: a channel NaN or
    /// infinite, or every channel finite but one outside [`Scale::limit`].
    #[inline(always)]
    pub fn to_fixed(self, c: [f32; 3]) -> Result<[i128; 3], Rejection> {
        let v = c.map(|x| x as f64 * self.mul);
        // `!(a < b)` is true for NaN too.
        if v[0].abs() < I64_LIMIT && v[1].abs() < I64_LIMIT && v[2].abs() < I64_LIMIT {
            Ok(v.map(|x| round_in_range(x) as i128))
        } else {
            wide_or_rejected(v)
        }
    }

    /// The value a fixed-point sum stands for, in f64 (rounded once).
    #[inline]
    pub fn to_f64(self, sum: i128) -> f64 {
        int_to_f64(sum) * self.inv
    }

    /// The pixel mean of `n` samples whose fixed-point channel sums are `sum`.
    #[inline]
    pub fn mean(self, sum: [i128; 3], n: u32) -> [f32; 3] {
        if n == 0 {
            return [0.0; 3];
        }
        let n = n as f64;
        sum.map(|s| (int_to_f64(s) / n * self.inv) as f32)
    }
}

/// [`Scale::to_fixed`] past the `i64` range (scaled samples from 2^63 to
/// 2^95, integers in f64, which convert exactly), and the rejections. Rare:
/// out of line.
#[cold]
#[inline(never)]
fn wide_or_rejected(v: [f64; 3]) -> Result<[i128; 3], Rejection> {
    if v.iter().all(|x| x.abs() < SCALED_LIMIT) {
        Ok(v.map(|x| if x.abs() < I64_LIMIT { round_in_range(x) as i128 } else { x as i128 }))
    } else if v.iter().all(|x| x.is_finite()) {
        // (A finite f32 times at most 2^32 is a finite f64.)
        Err(Rejection::OutOfRange)
    } else {
        Err(Rejection::NonFinite)
    }
}

/// `x.round_ties_even() as i64` for `|x| < 2^63` (what [`Scale::to_fixed`]
/// checks first): on x86-64 one conversion that rounds to nearest, ties to
/// even (the default rounding mode, which Rust code never changes), instead of
/// a rounding, a conversion and the saturation checks of `as`; elsewhere the
/// portable expression. Equal for every such `x` (the tests compare them on
/// ties, edges and random values).
#[inline(always)]
fn round_in_range(x: f64) -> i64 {
    debug_assert!(x.abs() < I64_LIMIT, "{x}");
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

/// Scaled channels below this magnitude (samples below 2^19 = 524,288 at
/// exponent 0) convert by [`Run::try_add`]'s one addition.
const RUN_SCALED_LIMIT: f64 = (1u64 << 51) as f64;
/// `1.5 * 2^52`: for `|x| < 2^51`, `x + MAGIC` lies in `[2^52, 2^53)`, where
/// the f64 spacing is 1, so the addition rounds `x` to the nearest integer,
/// ties to even (the default rounding mode), and that integer is the
/// difference of the sum's bits and `MAGIC`'s.
const MAGIC: f64 = 6_755_399_441_055_744.0;

/// The fixed-point sums of a run of samples of one pixel, for the common
/// case of samples below 2^19 per channel (at exponent 0; `2^(19 + e)` at
/// exponent `e`): each converted channel is below 2^51, so up to [`Run::MAX`]
/// of them sum inside an `i64`. The three channels convert and add as one
/// 4-lane vector (one multiply, one range test, one addition of `1.5 * 2^52`
/// and one integer addition per sample); the sums are exactly
/// [`Scale::to_fixed`]'s. A sample outside the fast range is left to the
/// caller ([`Scale::to_fixed`], which also rejects NaN and Inf).
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

    /// Adds `c`, converted by `scale`, when every channel is in the fast
    /// range (and the run has room); otherwise adds nothing and returns false.
    /// (Every sample of a run is converted by the same scale.)
    #[inline(always)]
    pub fn try_add(&mut self, c: [f32; 3], scale: Scale) -> bool {
        let v = wide::f64x4::from([c[0] as f64, c[1] as f64, c[2] as f64, 0.0]) * wide::f64x4::splat(scale.mul);
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

    /// The run's fixed-point sums, exact: `[scale.to_fixed(c)[k]]` summed over its samples.
    #[inline(always)]
    pub fn sums(&self) -> [i64; 3] {
        let b = self.bits.to_array();
        let m = MAGIC.to_bits().wrapping_mul(self.n as u64);
        [0, 1, 2].map(|k| b[k].wrapping_sub(m) as i64)
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    const UNIT: Scale = Scale::UNIT;

    /// The `i64` shortcut converts exactly as `i128 as f64` does, at the
    /// edges of the `i64` range, where rounding decides (halfway cases and
    /// their neighbours), and on random sums of every magnitude.
    #[test]
    fn int_to_f64_is_the_i128_conversion() {
        let mut xs: Vec<i128> = vec![0, 1, -1, i64::MAX as i128, i64::MIN as i128, i64::MAX as i128 + 1];
        xs.push(i64::MIN as i128 - 1);
        for e in [24, 53, 54, 62, 63, 64, 94, 126] {
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
        let top = (SAMPLE_LIMIT as f32).next_down();
        for x in [0.0f32, 1.0, 0.5, 0.1, 1e3, 2.0f32.powi(-9), -0.75, 3e9, -1e18, top, -top] {
            let q = UNIT.to_fixed([x; 3]).unwrap();
            if x.abs() >= 2.0f32.powi(-9) || x == 0.0 {
                assert_eq!(UNIT.to_f64(q[0]), x as f64, "{x}");
                assert_eq!(UNIT.mean(q, 1), [x; 3], "{x}");
            }
        }
        // 2^-34 is a quarter step: rounds to 0; 3 * 2^-34 rounds to one step; 2^-33 is a tie -> even (0).
        assert_eq!(UNIT.to_fixed([2.0f32.powi(-34), 3.0 * 2.0f32.powi(-34), 2.0f32.powi(-33)]), Ok([0, 1, 0]));
        assert_eq!(UNIT.to_fixed([3.0 * 2.0f32.powi(-33), 0.0, 0.0]), Ok([2, 0, 0]));
    }

    /// Exponent 0 is the fixed point rtow always had (every preset's image
    /// depends on it): 2^32 steps per unit.
    #[test]
    fn exponent_zero_is_the_unit_scale() {
        assert_eq!(Scale::new(0), Some(UNIT));
        assert_eq!(Scale::default(), UNIT);
        assert_eq!((UNIT.mul, UNIT.inv), (4_294_967_296.0, 1.0 / 4_294_967_296.0));
        assert_eq!(UNIT.limit(), SAMPLE_LIMIT);
        assert_eq!(Scale::new(MAX_EXPONENT + 1), None);
    }

    /// At every exponent: multiples of the step convert exactly, ties round
    /// to even, the range's edges are where they are documented, and a
    /// sample a step or more above 2^(e-9) converts exactly and is its own mean.
    #[test]
    fn scaled_samples_convert_exactly_with_ties_to_even_at_every_exponent() {
        for e in [0, 1, 7, 16, 31, 32, 53, 64, 65, 80, MAX_EXPONENT] {
            let s = Scale::new(e).unwrap();
            let r = s.resolution();
            assert_eq!(r, 2f64.powi(e as i32 - FRACTION_BITS), "{e}");
            assert_eq!(s.limit(), 2f64.powi(63 + e as i32), "{e}");
            let f = |k: f64| (k * r) as f32;
            // Exact steps, both signs; ties to even; a quarter step rounds down.
            assert_eq!(s.to_fixed([f(1.0), f(-7.0), f(2.0f64.powi(40))]), Ok([1, -7, 1 << 40]), "{e}");
            assert_eq!(s.to_fixed([f(2.5), f(3.5), f(-2.5)]), Ok([2, 4, -2]), "{e}");
            assert_eq!(s.to_fixed([f(0.5), f(1.5), f(0.25)]), Ok([0, 2, 0]), "{e}");
            assert_eq!(s.to_fixed([f(0.75), f(-0.75), 0.0]), Ok([1, -1, 0]), "{e}");
            // The range: just below the limit converts exactly, at the limit
            // it is refused as out of range (past f32::MAX, every finite f32 is in).
            let limit = s.limit();
            if limit <= f32::MAX as f64 {
                let below = (limit as f32).next_down();
                let q = s.to_fixed([below, -below, 1.0]).unwrap();
                assert_eq!(s.to_f64(q[0]), below as f64, "{e}");
                assert_eq!(s.to_fixed([1.0, limit as f32, 1.0]), Err(Rejection::OutOfRange), "{e}");
                assert_eq!(s.to_fixed([-(limit as f32), 1.0, 1.0]), Err(Rejection::OutOfRange), "{e}");
                assert_eq!(s.to_fixed([f32::MAX, 1.0, 1.0]), Err(Rejection::OutOfRange), "{e}");
            } else {
                let q = s.to_fixed([f32::MAX, -f32::MAX, 1.0]).unwrap();
                assert_eq!(s.mean(q, 1)[..2], [f32::MAX, -f32::MAX], "{e}");
            }
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                assert_eq!(s.to_fixed([1.0, bad, 1.0]), Err(Rejection::NonFinite), "{e} {bad}");
            }
            // NaN wins over out of range: the sample is not finite.
            assert_eq!(s.to_fixed([f32::NAN, f32::MAX, 1.0]), Err(Rejection::NonFinite), "{e}");
            // Random samples of magnitude from 2^(e-9) to the limit convert exactly.
            let mut state = 0x2545_F491_4F6C_DD1Du64 ^ e as u64;
            let (lo, hi) = ((2.0f64).powi(e as i32 - 9), limit.min(f32::MAX as f64));
            for _ in 0..20_000 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let x = f32::from_bits(state as u32);
                if !(x.is_finite() && (x.abs() as f64) >= lo && (x.abs() as f64) < hi) {
                    continue;
                }
                let q = s.to_fixed([x, 0.0, -x]).unwrap();
                assert_eq!(s.to_f64(q[0]), x as f64, "{e} {x:e}");
                assert_eq!(q[2], -q[0]);
                assert_eq!(s.mean(q, 1), [x, 0.0, -x], "{e} {x:e}");
            }
        }
    }

    /// The exponent is the smallest that leaves 2^16 of headroom above the
    /// brightest emission: 0 below 2^47, and at most `MAX_EXPONENT`.
    #[test]
    fn the_exponent_is_the_smallest_with_headroom() {
        let head = 2f64.powi(HEADROOM_BITS as i32);
        for (l, want) in [
            (0.0, Some(0)),
            (1.0, Some(0)),
            (15.0, Some(0)),
            (2f64.powi(47) * (1.0 - 1e-9), Some(0)),
            (2f64.powi(47), Some(1)),
            (1e30, None),
            (f32::MAX as f64 / 2.0, Some(80)),
            (f32::MAX as f64, Some(MAX_EXPONENT)),
        ] {
            let s = Scale::for_brightness(l);
            if let Some(w) = want {
                assert_eq!(s.exponent(), w, "{l:e}");
            }
            assert!(l * head < s.limit(), "{l:e}");
            if s.exponent() > 0 {
                assert!(l * head >= s.limit() / 2.0, "{l:e}: not the smallest");
            }
        }
        assert_eq!(Scale::for_brightness(1e30).exponent(), 53);
        assert_eq!(Scale::for_brightness(f64::NAN).exponent(), MAX_EXPONENT);
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
        xs.extend([I64_LIMIT.next_down(), -I64_LIMIT.next_down()]);
        // Random values over the range, in f32 samples scaled as `to_fixed` scales them.
        let mut r = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..200_000 {
            r ^= r << 13;
            r ^= r >> 7;
            r ^= r << 17;
            let f = f32::from_bits(r as u32);
            if f.is_finite() && (f.abs() as f64) * UNIT.mul < I64_LIMIT {
                xs.push(f as f64 * UNIT.mul);
            }
        }
        for x in xs {
            assert_eq!(round_in_range(x), x.round_ties_even() as i64, "{x:e}");
        }
    }

    /// The run's sums are exactly the sums of `to_fixed` over every sample
    /// it takes: ties, both signs, the edges of its range, dark samples, and
    /// random ones; samples outside its range, NaN and Inf are left out. At
    /// exponent 0 and at a large one (samples scaled up by as much).
    #[test]
    fn a_run_sums_exactly_what_to_fixed_converts() {
        for e in [0, 53] {
            let s = Scale::new(e).unwrap();
            let up = 2.0f32.powi(e as i32);
            let edge = ((1u64 << 19) as f32).next_down() * up;
            let mut xs: Vec<f32> = vec![0.0, -0.0, 1.0, -1.0, edge, -edge, 2.0f32.powi(-33), 3.0 * 2.0f32.powi(-33)];
            xs.extend([-2.0f32.powi(-33), 2.0f32.powi(-34), 5.0 * 2.0f32.powi(-34), f32::MIN_POSITIVE, 1e-40]);
            let mut r = 0x2545_F491_4F6C_DD1Du64;
            for _ in 0..100_000 {
                r ^= r << 13;
                r ^= r >> 7;
                r ^= r << 17;
                // Mostly magnitudes below 2^19 (0x4900_0000), any sign; some of any bits.
                let b = r as u32;
                xs.push(if b & 7 == 0 {
                    f32::from_bits(b)
                } else {
                    f32::from_bits(((b >> 3) % 0x4900_0000) | (b & 0x8000_0000)) * up
                });
            }
            let fast = (1u64 << 19) as f64 * up as f64;
            let mut run = Run::default();
            let mut want = [0i64; 3];
            let mut taken = 0;
            for c in xs.chunks_exact(3) {
                let c = [c[0], c[1], c[2]];
                if run.len() == Run::MAX {
                    assert_eq!(run.sums(), want);
                    (run, want) = (Run::default(), [0; 3]);
                }
                let fits = c.iter().all(|x| (x.abs() as f64) < fast);
                assert_eq!(run.try_add(c, s), fits, "{c:?}");
                if fits {
                    let q = s.to_fixed(c).unwrap();
                    for k in 0..3 {
                        want[k] += q[k] as i64;
                    }
                    taken += 1;
                }
            }
            assert!(taken > 10_000);
            assert_eq!(run.sums(), want);
            // Full: refuses more, and its sums are still exact at the largest values.
            let mut full = Run::default();
            for _ in 0..Run::MAX {
                assert!(full.try_add([edge, -edge, 0.5], s));
            }
            assert!(!full.try_add([0.5; 3], s));
            let q = s.to_fixed([edge, -edge, 0.5]).unwrap();
            assert_eq!(full.sums(), q.map(|x| x as i64 * Run::MAX as i64));
            for bad in [f32::NAN, f32::INFINITY, (fast as f32), -1e9 * up] {
                assert!(!Run::default().try_add([0.5, bad, 0.5], s), "{bad}");
            }
        }
    }

    #[test]
    fn out_of_range_nan_and_inf_are_refused_by_cause() {
        for bad in [SAMPLE_LIMIT as f32, -(SAMPLE_LIMIT as f32), f32::MAX, -f32::MAX] {
            assert_eq!(UNIT.to_fixed([0.5, bad, 0.5]), Err(Rejection::OutOfRange), "{bad}");
        }
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(UNIT.to_fixed([0.5, bad, 0.5]), Err(Rejection::NonFinite), "{bad}");
        }
    }

    #[test]
    fn the_largest_sums_do_not_overflow() {
        for e in [0, 40, MAX_EXPONENT] {
            let s = Scale::new(e).unwrap();
            let top = (s.limit().min(f32::MAX as f64) as f32).next_down();
            for x in [top, -top] {
                let q = s.to_fixed([x; 3]).unwrap()[0];
                let sum = q * u32::MAX as i128;
                assert!(sum.unsigned_abs() < 1u128 << 127);
                assert_eq!(s.mean([sum; 3], u32::MAX), [x; 3], "{e}");
            }
        }
    }

    #[test]
    fn the_mean_does_not_depend_on_grouping() {
        // Samples whose f32 running sum depends on the order.
        let xs = [1.0e7f32, 0.3, -1.0e7, 0.7, 1e-5, 3.25, 0.1, 2.0f32.powi(-20)];
        let q: Vec<i128> = xs.iter().map(|&x| UNIT.to_fixed([x; 3]).unwrap()[0]).collect();
        let all: i128 = q.iter().sum();
        let a: i128 = q[..3].iter().sum::<i128>() + q[3..].iter().rev().sum::<i128>();
        assert_eq!(all, a);
        let f32_fwd = xs.iter().fold(0.0f32, |s, &x| s + x);
        let f32_rev = xs.iter().rev().fold(0.0f32, |s, &x| s + x);
        assert_ne!(f32_fwd, f32_rev, "the example should defeat f32 sums");
        assert_eq!(UNIT.mean([all; 3], 8), UNIT.mean([a; 3], 8));
    }
}
