//! Integer helpers of the samplers over [`U32Lanes`] (one lane or many):
//! the hash every scramble and dimension seed goes through. Written once
//! against that trait, a generator computes in lane k exactly what the scalar
//! version computes (every operation is exact integer arithmetic modulo 2^32).

pub use crate::real::U32Lanes;
#[cfg(test)]
use wide::{u32x16, u32x8};

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
        let table: [u32; 16] = std::array::from_fn(|j| hash32(j as u32 % 8));
        agree::<U>(|a, _| U::lookup8(&table, a), |a, _| table[a as usize % 8]);
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
