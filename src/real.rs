//! `Real`: the one numeric interface that both kernels are written against.
//!
//! Every formula of the renderer (camera rays, intersection, scatter, sampling)
//! is written once, generic over `R: Real`, and instantiated twice: with `f32`
//! for the scalar reference kernel and with [`wide::f32x8`] for the SIMD kernel.
//! Because both instantiations perform the same IEEE-754 operations in the same
//! order (add, sub, mul, div and sqrt are correctly rounded in both; no fused
//! multiply-add, no approximate reciprocal), lane k of the SIMD kernel computes
//! exactly the bits that the scalar kernel computes for the same path.
//!
//! Comparisons return a `Mask`; branches become `select`. For `f32` the mask is
//! a `bool` and `select` a plain `if`, so the scalar kernel stays readable.

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};
use wide::{f32x8, u32x8};

/// A lane mask: `bool` for one lane, an all-ones/all-zeros `f32x8` for eight.
pub trait Mask: Copy + BitAnd<Output = Self> + BitOr<Output = Self> + Not<Output = Self> {
    fn any(self) -> bool;
    fn all(self) -> bool;
}

impl Mask for bool {
    #[inline(always)]
    fn any(self) -> bool {
        self
    }
    #[inline(always)]
    fn all(self) -> bool {
        self
    }
}

impl Mask for f32x8 {
    #[inline(always)]
    fn any(self) -> bool {
        f32x8::any(self)
    }
    #[inline(always)]
    fn all(self) -> bool {
        f32x8::all(self)
    }
}

/// A real number, one lane (`f32`) or eight (`f32x8`).
pub trait Real:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self>
{
    type Mask: Mask;
    /// The matching unsigned integer lanes (random streams).
    type U32: Copy;
    const LANES: usize;

    fn splat(x: f32) -> Self;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    /// Minimum; if either is NaN the result is the other operand's lane rule of
    /// `f32::min` (never used on NaN inputs in the kernels).
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    /// Minimum and maximum for inputs that are never NaN, where the sign of a
    /// zero result does not matter (one instruction on `f32x8`). Not for
    /// values that reach the image: use `min`/`max` there, whose tie rule is
    /// the same on both widths.
    fn fast_min(self, o: Self) -> Self;
    fn fast_max(self, o: Self) -> Self;
    /// `self` with the sign bit of `sign` (exact).
    fn copysign(self, sign: Self) -> Self;
    fn lt(self, o: Self) -> Self::Mask;
    fn le(self, o: Self) -> Self::Mask;
    fn gt(self, o: Self) -> Self::Mask;
    fn ge(self, o: Self) -> Self::Mask;
    fn eq(self, o: Self) -> Self::Mask;
    /// Lanes that are neither NaN nor infinite.
    fn is_finite(self) -> Self::Mask;
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// Uniform float in [0, 1) from 32 random bits: `(x >> 8) * 2^-24`.
    fn unit_from_bits(bits: Self::U32) -> Self;
}

impl Real for f32 {
    type Mask = bool;
    type U32 = u32;
    const LANES: usize = 1;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        x
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        if o < self {
            o
        } else {
            self
        }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        if o > self {
            o
        } else {
            self
        }
    }
    #[inline(always)]
    fn fast_min(self, o: Self) -> Self {
        f32::min(self, o)
    }
    #[inline(always)]
    fn fast_max(self, o: Self) -> Self {
        f32::max(self, o)
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        f32::copysign(self, sign)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> bool {
        self < o
    }
    #[inline(always)]
    fn le(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn gt(self, o: Self) -> bool {
        self > o
    }
    #[inline(always)]
    fn ge(self, o: Self) -> bool {
        self >= o
    }
    #[inline(always)]
    fn eq(self, o: Self) -> bool {
        self == o
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m {
            a
        } else {
            b
        }
    }
    #[inline(always)]
    fn unit_from_bits(bits: u32) -> Self {
        (bits >> 8) as f32 * (1.0 / 16_777_216.0)
    }
}

impl Real for f32x8 {
    type Mask = f32x8;
    type U32 = u32x8;
    const LANES: usize = 8;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        f32x8::splat(x)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32x8::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32x8::abs(self)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        // Same rule as the scalar `min` above: take `o` only where `o < self`.
        o.simd_lt(self).select(o, self)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        o.simd_gt(self).select(o, self)
    }
    #[inline(always)]
    fn fast_min(self, o: Self) -> Self {
        f32x8::fast_min(self, o)
    }
    #[inline(always)]
    fn fast_max(self, o: Self) -> Self {
        f32x8::fast_max(self, o)
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        let s = f32x8::splat(-0.0);
        (self & !s) | (sign & s)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> f32x8 {
        self.simd_lt(o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> f32x8 {
        self.simd_le(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> f32x8 {
        self.simd_gt(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> f32x8 {
        self.simd_ge(o)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> f32x8 {
        self.simd_eq(o)
    }
    #[inline(always)]
    fn is_finite(self) -> f32x8 {
        f32x8::is_finite(self)
    }
    #[inline(always)]
    fn select(m: f32x8, a: Self, b: Self) -> Self {
        m.select(a, b)
    }
    #[inline(always)]
    fn unit_from_bits(bits: u32x8) -> Self {
        // (bits >> 8) < 2^24, so the signed conversion is exact.
        let i: wide::i32x8 = bytemuck::cast(bits >> 8);
        f32x8::from_i32x8(i) * f32x8::splat(1.0 / 16_777_216.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_from_bits_agrees_across_widths() {
        let words = [0u32, 1, 255, 256, 0x8000_0000, u32::MAX, 0xdead_beef, 12345];
        let wide = f32x8::unit_from_bits(u32x8::new(words)).to_array();
        for (k, w) in words.iter().enumerate() {
            let s = f32::unit_from_bits(*w);
            assert_eq!(s.to_bits(), wide[k].to_bits());
            assert!((0.0..1.0).contains(&s));
        }
    }

    #[test]
    fn min_max_copysign_agree_across_widths() {
        let a = [1.0f32, -2.0, 0.0, -0.0, 3.5, f32::INFINITY, -1e-30, 7.0];
        let b = [2.0f32, -3.0, -0.0, 0.0, 3.5, 1.0, 1e-30, -7.0];
        let (wa, wb) = (f32x8::new(a), f32x8::new(b));
        let mn = Real::min(wa, wb).to_array();
        let mx = Real::max(wa, wb).to_array();
        let cs = Real::copysign(wa, wb).to_array();
        for k in 0..8 {
            assert_eq!(Real::min(a[k], b[k]).to_bits(), mn[k].to_bits());
            assert_eq!(Real::max(a[k], b[k]).to_bits(), mx[k].to_bits());
            assert_eq!(Real::copysign(a[k], b[k]).to_bits(), cs[k].to_bits());
        }
    }
}
