//! Integer helpers of the samplers over [`U32Lanes`] (one lane or many):
//! the hash every scramble and dimension seed goes through. Written once
//! against that trait, a generator computes in lane k exactly what the scalar
//! version computes (every operation is exact integer arithmetic modulo 2^32).

pub use crate::real::U32Lanes;

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

    #[test]
    fn generic_reverse_matches_the_intrinsic() {
        // The vector types use the generic shift-and-mask reversal.
        for x in (0..1000u32).map(|k| hash32(k.wrapping_mul(0x9e37_79b9)) ^ k) {
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
}
