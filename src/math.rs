//! The transcendental functions the later books need, written once over
//! [`Real`] so that the scalar kernel and every lane width compute the same
//! bits: `sin` (the marble texture), `ln` (a medium's free-flight distance),
//! `exp_neg` (a shadow ray's transmittance through media),
//! `atan2` and `acos` (a sphere's texture coordinates). `floor` (the checker,
//! Perlin's lattice) is exact and is `Real::floor`.
//!
//! Like `sampling::cos_sin_turn`, each uses only `+ - * /`, `sqrt`, `floor`,
//! comparisons, `select` and bit operations on the IEEE-754 representation,
//! each correctly rounded or exact in every width, in the same order: no
//! fused multiply-add, no approximate reciprocal, no library call. So lane
//! k of `f32x8` computes exactly what `f32` computes (tests below), on every
//! instruction set `wide` is built for.
//!
//! Accuracy, against the same function in f64 of the same f32 input, is
//! measured by the tests below (exhaustively on the inputs a kernel feeds
//! `ln`, densely and by property elsewhere) and stated at each function.
//! The polynomials were fitted in f64 (least squares at Chebyshev nodes)
//! and their coefficients rounded to f32; the bounds include that rounding.

use crate::real::{Real, U32Lanes};

const PI: f32 = std::f32::consts::PI;

/// `π` in three parts for the argument reduction of [`sin`] (Cody and
/// Waite): `PI_A` and `PI_B` have 8 significant bits each, so `k * PI_A` and
/// `k * PI_B` are exact for integers `|k| < 2^16`; `PI_C` is the rest, rounded.
const PI_A: f32 = 3.140_625; // 201 / 2^6
const PI_B: f32 = 9.689_331e-4; // 127 / 2^17
const PI_C: f32 = -1.279_515_7e-6;

/// The largest `|x|` for which [`sin`]'s reduction is exact (`|x| / π`
/// rounds to an integer below 2^16) and its documented bound holds.
pub const SIN_MAX_ARG: f32 = 205_887.0;

/// `sin(x)`.
///
/// `x` is reduced to `r = x - kπ` with `k = floor(x / π + 1/2)` (a
/// three-part `π`), then `sin(r)` for `|r| <= π/2` is its Taylor polynomial
/// to degree 11, negated for odd `k`. Measured absolute error against f64:
/// below `2.5e-7` for `|x| <=` [`SIN_MAX_ARG`] (the tests; the largest part is
/// the rounding of `r` itself). Beyond it the reduction is no longer exact
/// and the error grows with `|x|`; the marble texture's arguments stay far
/// below it. NaN and infinite `x` give NaN.
#[inline(always)]
pub fn sin<R: Real>(x: R) -> R {
    let k = (x * R::splat(1.0 / PI) + R::splat(0.5)).floor();
    let r = ((x - k * R::splat(PI_A)) - k * R::splat(PI_B)) - k * R::splat(PI_C);
    // Rounding can leave |r| a hair above pi/2; the polynomial is accurate there too.
    let r2 = r * r;
    let s = r + r
        * r2
        * (R::splat(-1.0 / 6.0)
            + r2 * (R::splat(1.0 / 120.0)
                + r2 * (R::splat(-1.0 / 5040.0)
                    + r2 * (R::splat(1.0 / 362_880.0) + r2 * R::splat(-1.0 / 39_916_800.0)))));
    // Odd k: sin(r + k pi) = -sin(r). k is an integer below 2^24 in magnitude
    // here (or the result is noise anyway); its parity is k - 2 floor(k / 2).
    let odd = (k - R::splat(2.0) * (k * R::splat(0.5)).floor()).eq(R::splat(1.0));
    R::select(odd, -s, s)
}

/// `ln(x)` for `x > 0` (finite; subnormals included).
///
/// `x = m 2^e` with `m` in `[sqrt(1/2), sqrt(2))`, read from the exponent and
/// mantissa bits; `ln(m) = 2 atanh(s)`, `s = (m - 1) / (m + 1)`, `|s| <= 0.1716`,
/// by an odd polynomial; `e ln 2` added in two parts. Measured error against
/// f64 (the tests): at most 2 ulp of the result for any positive input, and
/// at most 1.7 ulp for every `1 - u` with `u` on the samplers' 2^-24 grid
/// (all the inputs a medium's free-flight distance takes, checked one by
/// one). `x = 0` gives a large negative finite value, not -inf: callers pass
/// `1 - u`, which is never 0.
#[inline(always)]
pub fn ln<R: Real>(x: R) -> R {
    // Subnormals: scale by 2^24 first (exact) and take 24 off the exponent.
    let tiny = x.lt(R::splat(f32::MIN_POSITIVE));
    let xs = R::select(tiny, x * R::splat(16_777_216.0), x);
    let bits = xs.to_u32_bits();
    let exp = R::from_small_u32((bits >> 23) & R::u_splat(0xff));
    let m = R::from_u32_bits((bits & R::u_splat(0x007f_ffff)) | R::u_splat(0x3f80_0000));
    // m in [1, 2): move [sqrt 2, 2) down to [sqrt(1/2), 1).
    let big = m.gt(R::splat(std::f32::consts::SQRT_2));
    let m = R::select(big, m * R::splat(0.5), m);
    let e = exp - R::splat(127.0) + R::select(big, R::splat(1.0), R::splat(0.0))
        - R::select(tiny, R::splat(24.0), R::splat(0.0));
    let s = (m - R::splat(1.0)) / (m + R::splat(1.0));
    let z = s * s;
    let ln_m = s * R::splat(2.0)
        + s * z
            * (R::splat(0.666_666_6)
                + z * (R::splat(0.400_003_4) + z * (R::splat(0.285_371_1) + z * R::splat(0.235_854_04))));
    // ln 2 = LN2_HI + LN2_LO; e LN2_HI is exact (|e| <= 150, LN2_HI has 16 bits).
    const LN2_HI: f32 = 0.693_145_75; // 45426 / 2^16
    const LN2_LO: f32 = 1.428_606_8e-6;
    e * R::splat(LN2_HI) + (e * R::splat(LN2_LO) + ln_m)
}

/// `exp(-x)` for `x >= 0` (a transmittance; 0 from `x > 87.3`, where it
/// is below the smallest normal f32, and for `x = inf`).
///
/// `x log2(e) = n + f` with `n = floor` and `f` in `[0, 1)` (exact: `n` is
/// an integer below 2^7); `2^-f = exp(-f ln 2)` is the Taylor polynomial of
/// `exp(-g)` to degree 9 at `g = f ln 2` in `[0, 0.694)` (truncation below
/// `3e-9`), and `2^-n` is built from its exponent bits. Measured error
/// against f64 (the tests): relative `3.9e-6` on `[0, 87]`, which is the
/// rounding of `x log2(e)` for large `x` (`87 u`), 1.5 ulp of the result
/// for `x <= 1`. Callers never pass NaN (its result is unspecified).
#[inline(always)]
pub fn exp_neg<R: Real>(x: R) -> R {
    let y = x * R::splat(std::f32::consts::LOG2_E);
    let big = y.ge(R::splat(126.0));
    let y = y.min(R::splat(125.999_99));
    let n = y.floor();
    let g = (y - n) * R::splat(std::f32::consts::LN_2);
    // exp(-g) = sum (-g)^k / k!, Horner from degree 9.
    let mut p = R::splat(-1.0 / 362_880.0);
    for c in [1.0 / 40_320.0, -1.0 / 5_040.0, 1.0 / 720.0, -1.0 / 120.0, 1.0 / 24.0, -1.0 / 6.0, 0.5, -1.0, 1.0] {
        p = p * g + R::splat(c);
    }
    // n in [0, 125]: its integer from the mantissa bits of n + 2^23 (exact).
    let ni = (n + R::splat(8_388_608.0)).to_u32_bits() & R::u_splat(0x7f);
    let scale = R::from_u32_bits(R::u_splat(127).wrapping_sub(ni) << 23);
    R::select(big, R::splat(0.0), p * scale)
}

/// `atan(t)` for `|t| <= tan(π/8)`: an odd polynomial of degree 11.
#[inline(always)]
fn atan_small<R: Real>(t: R) -> R {
    let z = t * t;
    t + t
        * z
        * (R::splat(-0.333_333_16)
            + z * (R::splat(0.199_985_49)
                + z * (R::splat(-0.142_448_02) + z * (R::splat(0.106_022_19) + z * R::splat(-0.060_976_44)))))
}

/// `m π/4` for `m = 0..=4`, in two parts: the f32 value, and what it misses.
const QUARTERS: [(f32, f32); 5] = [
    (0.0, 0.0),
    (std::f32::consts::FRAC_PI_4, -2.185_569_4e-8),
    (std::f32::consts::FRAC_PI_2, -4.371_139e-8),
    (2.356_194_5, -5.962_440_3e-9),
    (PI, -8.742_278e-8),
];

/// `atan2(y, x)` in `[-π, π]`, the angle of the point `(x, y)`.
///
/// With `t` the ratio of the smaller to the larger of `|x|`, `|y|` (in
/// `[0, 1]`), the angle is `m π/4 ± atan(t')` for an octant-dependent `m`,
/// where `t' = t`, or `(t - 1) / (t + 1)` above `tan(π/8)` (one more quarter in
/// `m`), so `|t'| <= tan(π/8)` and an odd polynomial of degree 11 applies. The multiple of
/// `π/4` is added last, in two parts, so the result carries one rounding
/// beyond the polynomial's. Measured absolute error against f64 (the
/// tests): below `2.5e-7`, about 1 ulp of `π`, for every finite input.
/// `atan2(±0, x)` is `±0` for `x >= +0` and `±π` for `x < 0` or `x = -0`, as
/// in f64; both zero gives 0 or `±π`, not NaN.
#[inline(always)]
pub fn atan2<R: Real>(y: R, x: R) -> R {
    let (ax, ay) = (x.abs(), y.abs());
    let zero = R::splat(0.0);
    let one = R::splat(1.0);
    let swap = ay.gt(ax);
    let (num, den) = (R::select(swap, ax, ay), R::select(swap, ay, ax));
    // den = 0 only when both are zero.
    let t = R::select(den.gt(zero), num / den, zero);
    let reduce = t.gt(R::splat(0.414_213_57));
    let p = atan_small(R::select(reduce, (t - one) / (t + one), t));
    // x < 0, or x = -0: the left half-plane.
    let left = R::u_lt(R::u_splat(0), x.to_u32_bits() >> 31);
    // The angle: 0 + a (right, below the diagonal), pi/2 - a (right, above),
    // pi/2 + a (left, above), pi - a (left, below), with a = (reduce ? pi/4 : 0) + p.
    let base = R::select(swap, R::splat(2.0), R::select(left, R::splat(4.0), zero));
    let negative = (swap & !left) | (!swap & left);
    let quarter = R::select(reduce, one, zero);
    let m = base + R::select(negative, -quarter, quarter);
    let pick = |part: fn(&(f32, f32)) -> f32| {
        let mut v = R::splat(part(&QUARTERS[0]));
        for (k, q) in QUARTERS.iter().enumerate().skip(1) {
            v = R::select(m.eq(R::splat(k as f32)), R::splat(part(q)), v);
        }
        v
    };
    let (hi, lo) = (pick(|q| q.0), pick(|q| q.1));
    let a = (lo + R::select(negative, -p, p)) + hi;
    a.copysign(y)
}

/// `acos(x)` in `[0, π]` for `x` in `[-1, 1]`: `atan2(sqrt((1 - x)(1 + x)), x)`.
/// Measured absolute error against f64 (the tests): below `2.5e-7`. Outside
/// `[-1, 1]` the square root's argument is negative: NaN.
#[inline(always)]
pub fn acos<R: Real>(x: R) -> R {
    let one = R::splat(1.0);
    atan2(((one - x) * (one + x)).sqrt(), x)
}
