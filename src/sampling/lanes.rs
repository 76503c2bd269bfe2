//! `U32Lanes`: unsigned 32-bit integer lanes, one (`u32`) or many (`u32x8`,
//! `u32x16`), for the integer work of the samplers (hashes, bit reversal, Sobol
//! matrix products). Written once against this trait, a generator computes in
//! lane k exactly what the scalar version computes: every operation here is
//! exact integer arithmetic modulo 2^32.

use std::ops::{BitAnd, BitOr, BitXor, Shl, Shr};
use wide::{u32x16, u32x8};

/// Unsigned 32-bit lanes with wrapping arithmetic.
pub trait U32Lanes:
    Copy
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + BitXor<Output = Self>
    + Shl<u32, Output = Self>
    + Shr<u32, Output = Self>
{
    const LANES: usize;
    fn splat(x: u32) -> Self;
    fn wrapping_add(self, o: Self) -> Self;
    fn wrapping_sub(self, o: Self) -> Self;
    fn wrapping_mul(self, o: Self) -> Self;
    /// Whether every lane is zero.
    fn all_zero(self) -> bool;
    /// Lane `k` (tests and scalar fallbacks).
    fn lane(self, k: usize) -> u32;
    fn from_fn(f: impl FnMut(usize) -> u32) -> Self;

    /// All ones in the lanes whose lowest bit is set, zero elsewhere.
    #[inline(always)]
    fn low_bit_mask(self) -> Self {
        Self::splat(0).wrapping_sub(self & Self::splat(1))
    }

    /// The bits of every lane in reverse order (bit 0 <-> bit 31).
    #[inline(always)]
    fn reverse_bits(self) -> Self {
        let swap = |x: Self, s: u32, m: u32| ((x >> s) & Self::splat(m)) | ((x & Self::splat(m)) << s);
        let x = swap(self, 1, 0x5555_5555);
        let x = swap(x, 2, 0x3333_3333);
        let x = swap(x, 4, 0x0f0f_0f0f);
        let x = swap(x, 8, 0x00ff_00ff);
        (x >> 16) | (x << 16)
    }
}

impl U32Lanes for u32 {
    const LANES: usize = 1;
    #[inline(always)]
    fn splat(x: u32) -> Self {
        x
    }
    #[inline(always)]
    fn wrapping_add(self, o: Self) -> Self {
        u32::wrapping_add(self, o)
    }
    #[inline(always)]
    fn wrapping_sub(self, o: Self) -> Self {
        u32::wrapping_sub(self, o)
    }
    #[inline(always)]
    fn wrapping_mul(self, o: Self) -> Self {
        u32::wrapping_mul(self, o)
    }
    #[inline(always)]
    fn all_zero(self) -> bool {
        self == 0
    }
    #[inline(always)]
    fn lane(self, _k: usize) -> u32 {
        self
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> u32) -> Self {
        f(0)
    }
    #[inline(always)]
    fn low_bit_mask(self) -> Self {
        (self & 1).wrapping_neg()
    }
    #[inline(always)]
    fn reverse_bits(self) -> Self {
        u32::reverse_bits(self)
    }
}

macro_rules! wide_lanes {
    ($t:ty, $n:expr) => {
        impl U32Lanes for $t {
            const LANES: usize = $n;
            #[inline(always)]
            fn splat(x: u32) -> Self {
                <$t>::splat(x)
            }
            #[inline(always)]
            fn wrapping_add(self, o: Self) -> Self {
                self + o // lane-wise, wrapping
            }
            #[inline(always)]
            fn wrapping_sub(self, o: Self) -> Self {
                self - o
            }
            #[inline(always)]
            fn wrapping_mul(self, o: Self) -> Self {
                self * o // the low 32 bits of each product
            }
            #[inline(always)]
            fn all_zero(self) -> bool {
                self.simd_eq(<$t>::splat(0)).all()
            }
            #[inline(always)]
            fn lane(self, k: usize) -> u32 {
                self.to_array()[k]
            }
            #[inline(always)]
            fn from_fn(f: impl FnMut(usize) -> u32) -> Self {
                <$t>::new(std::array::from_fn(f))
            }
        }
    };
}

wide_lanes!(u32x8, 8);
wide_lanes!(u32x16, 16);

/// Chris Wellons's `lowbias32` integer hash: a bijection of u32 with low bias.
#[inline(always)]
pub fn hash32<U: U32Lanes>(x: U) -> U {
    let x = x ^ (x >> 16);
    let x = x.wrapping_mul(U::splat(0x7feb_352d));
    let x = x ^ (x >> 15);
    let x = x.wrapping_mul(U::splat(0x846c_a68b));
    x ^ (x >> 16)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(n: usize, seed: u32) -> Vec<u32> {
        let mut s = seed;
        let mut v = vec![0, 1, u32::MAX, 0x8000_0000, 0x7fff_ffff];
        while v.len() < n {
            s = hash32(s.wrapping_add(0x9e37_79b9));
            v.push(s);
        }
        v
    }

    fn agree<U: U32Lanes>(f: impl Fn(U, U) -> U, g: impl Fn(u32, u32) -> u32) {
        let a = words(64 * U::LANES, 1);
        let b = words(64 * U::LANES, 2);
        for (ca, cb) in a.chunks(U::LANES).zip(b.chunks(U::LANES)) {
            let r = f(U::from_fn(|k| ca[k]), U::from_fn(|k| cb[k]));
            for k in 0..U::LANES {
                assert_eq!(r.lane(k), g(ca[k], cb[k]));
            }
        }
    }

    fn all_ops<U: U32Lanes>() {
        agree::<U>(|a, b| a.wrapping_add(b), u32::wrapping_add);
        agree::<U>(|a, b| a.wrapping_sub(b), u32::wrapping_sub);
        agree::<U>(|a, b| a.wrapping_mul(b), u32::wrapping_mul);
        agree::<U>(|a, b| (a ^ b) | (a & b), |a, b| (a ^ b) | (a & b));
        agree::<U>(|a, _| (a << 7) ^ (a >> 13), |a, _| (a << 7) ^ (a >> 13));
        agree::<U>(|a, _| a.reverse_bits(), |a, _| a.reverse_bits());
        agree::<U>(|a, _| a.low_bit_mask(), |a, _| if a & 1 == 1 { u32::MAX } else { 0 });
        agree::<U>(|a, _| hash32(a), |a, _| hash32(a));
    }

    #[test]
    fn lanes_agree_with_scalar_u32() {
        all_ops::<u32>();
        all_ops::<u32x8>();
        all_ops::<u32x16>();
    }

    #[test]
    fn generic_reverse_matches_the_intrinsic() {
        // The vector types use the generic shift-and-mask reversal.
        for x in words(1000, 3) {
            let generic = {
                let swap = |x: u32, s: u32, m: u32| ((x >> s) & m) | ((x & m) << s);
                let x = swap(x, 1, 0x5555_5555);
                let x = swap(x, 2, 0x3333_3333);
                let x = swap(x, 4, 0x0f0f_0f0f);
                let x = swap(x, 8, 0x00ff_00ff);
                x.rotate_left(16)
            };
            assert_eq!(generic, x.reverse_bits());
        }
    }

    #[test]
    fn all_zero_sees_every_lane() {
        assert!(u32x8::splat(0).all_zero());
        assert!(!u32x8::new([0, 0, 0, 0, 0, 0, 0, 1]).all_zero());
        assert!(!u32x16::from_fn(|k| (k == 15) as u32).all_zero());
        assert!(0u32.all_zero() && !1u32.all_zero());
    }
}
