//! Owen-scrambled Sobol points, generated lane-wise.
//!
//! The value of dimension `dim` of sample `index` of a pixel is a pure function
//! of (render seed, pixel, index, dim):
//!
//! 1. **Sobol** (Sobol' 1967, Joe and Kuo 2008): the point's 32 bits are the XOR
//!    of the direction numbers of `dim` selected by the set bits of `index`
//!    (the generator matrix times the index over GF(2), taken three index
//!    bits per table lookup); no Gray code, so any index is computed directly
//!    and any split of the sample range gives the same points. Direction
//!    numbers: Joe and Kuo's `new-joe-kuo-6.21201` parameters (`JOE_KUO`),
//!    expanded by the Bratley-Fox recurrence at compile time; dimension 0 is
//!    van der Corput.
//! 2. **Owen scramble**, hash-based (Burley, "Practical Hash-based Owen
//!    Scrambling", JCGT 2020): the bits are reversed, permuted by a
//!    Laine-Karras style hash in which each bit is flipped as a function of the
//!    bits below it only (so, read back in the original order, as a function of
//!    the *more significant* bits: a nested uniform scramble), and reversed
//!    back. The hash is Vegdahl's improved version (2021) of Burley's.
//!    The scramble seed is a hash of the pixel's key and the dimension, so every
//!    pixel and every dimension has its own independent random scramble; the
//!    pixel's key is mixed from (render seed, pixel).
//! 3. The sample index is not shuffled: the per-pixel scrambles already make
//!    the pixels independent, and an unshuffled index keeps the matrix product
//!    short (only the bits that an index below `spp` has).
//!
//! Dimensions at or past [`SOBOL_DIMS`] (or past a lower limit a render sets,
//! to measure what each group of dimensions gains) are **padding**: an
//! independent uniform value hashed from the same (key, index, dim).
//!
//! Owen scrambling keeps the net properties of the unscrambled points: every
//! dimension alone is a (0,1)-sequence in base 2, dimensions 0 and 1 together a
//! (0,2)-sequence, and each value is uniform on [0, 1) on its own, so an
//! estimate with these points is unbiased.
//!
//! Every function is generic over [`U32Lanes`], so lane k of `u32x8` or
//! `u32x16` computes exactly what the scalar `u32` version computes.

use super::lanes::{hash32, U32Lanes};
use super::mix64;

/// Tabulated Sobol dimensions: the dimension layout (see
/// [`super::layout`]) uses all of them for the pixel, the lens and 40 bounces.
pub const SOBOL_DIMS: usize = 124;

/// Joe and Kuo's direction-number parameters (`new-joe-kuo-6.21201`,
/// <https://web.maths.unsw.edu.au/~fkuo/sobol/>) for dimensions 1 to 123 (their
/// d = 2 to 124): the degree `s` of the primitive polynomial, its inner
/// coefficients `a` as bits, and the initial direction numbers `m_1..m_s`.
#[rustfmt::skip]
const JOE_KUO: [(u32, u32, &[u32]); SOBOL_DIMS - 1] = [
    (1, 0, &[1]),
    (2, 1, &[1, 3]),
    (3, 1, &[1, 3, 1]),
    (3, 2, &[1, 1, 1]),
    (4, 1, &[1, 1, 3, 3]),
    (4, 4, &[1, 3, 5, 13]),
    (5, 2, &[1, 1, 5, 5, 17]),
    (5, 4, &[1, 1, 5, 5, 5]),
    (5, 7, &[1, 1, 7, 11, 19]),
    (5, 11, &[1, 1, 5, 1, 1]),
    (5, 13, &[1, 1, 1, 3, 11]),
    (5, 14, &[1, 3, 5, 5, 31]),
    (6, 1, &[1, 3, 3, 9, 7, 49]),
    (6, 13, &[1, 1, 1, 15, 21, 21]),
    (6, 16, &[1, 3, 1, 13, 27, 49]),
    (6, 19, &[1, 1, 1, 15, 7, 5]),
    (6, 22, &[1, 3, 1, 15, 13, 25]),
    (6, 25, &[1, 1, 5, 5, 19, 61]),
    (7, 1, &[1, 3, 7, 11, 23, 15, 103]),
    (7, 4, &[1, 3, 7, 13, 13, 15, 69]),
    (7, 7, &[1, 1, 3, 13, 7, 35, 63]),
    (7, 8, &[1, 3, 5, 9, 1, 25, 53]),
    (7, 14, &[1, 3, 1, 13, 9, 35, 107]),
    (7, 19, &[1, 3, 1, 5, 27, 61, 31]),
    (7, 21, &[1, 1, 5, 11, 19, 41, 61]),
    (7, 28, &[1, 3, 5, 3, 3, 13, 69]),
    (7, 31, &[1, 1, 7, 13, 1, 19, 1]),
    (7, 32, &[1, 3, 7, 5, 13, 19, 59]),
    (7, 37, &[1, 1, 3, 9, 25, 29, 41]),
    (7, 41, &[1, 3, 5, 13, 23, 1, 55]),
    (7, 42, &[1, 3, 7, 3, 13, 59, 17]),
    (7, 50, &[1, 3, 1, 3, 5, 53, 69]),
    (7, 55, &[1, 1, 5, 5, 23, 33, 13]),
    (7, 56, &[1, 1, 7, 7, 1, 61, 123]),
    (7, 59, &[1, 1, 7, 9, 13, 61, 49]),
    (7, 62, &[1, 3, 3, 5, 3, 55, 33]),
    (8, 14, &[1, 3, 1, 15, 31, 13, 49, 245]),
    (8, 21, &[1, 3, 5, 15, 31, 59, 63, 97]),
    (8, 22, &[1, 3, 1, 11, 11, 11, 77, 249]),
    (8, 38, &[1, 3, 1, 11, 27, 43, 71, 9]),
    (8, 47, &[1, 1, 7, 15, 21, 11, 81, 45]),
    (8, 49, &[1, 3, 7, 3, 25, 31, 65, 79]),
    (8, 50, &[1, 3, 1, 1, 19, 11, 3, 205]),
    (8, 52, &[1, 1, 5, 9, 19, 21, 29, 157]),
    (8, 56, &[1, 3, 7, 11, 1, 33, 89, 185]),
    (8, 67, &[1, 3, 3, 3, 15, 9, 79, 71]),
    (8, 70, &[1, 3, 7, 11, 15, 39, 119, 27]),
    (8, 84, &[1, 1, 3, 1, 11, 31, 97, 225]),
    (8, 97, &[1, 1, 1, 3, 23, 43, 57, 177]),
    (8, 103, &[1, 3, 7, 7, 17, 17, 37, 71]),
    (8, 115, &[1, 3, 1, 5, 27, 63, 123, 213]),
    (8, 122, &[1, 1, 3, 5, 11, 43, 53, 133]),
    (9, 8, &[1, 3, 5, 5, 29, 17, 47, 173, 479]),
    (9, 13, &[1, 3, 3, 11, 3, 1, 109, 9, 69]),
    (9, 16, &[1, 1, 1, 5, 17, 39, 23, 5, 343]),
    (9, 22, &[1, 3, 1, 5, 25, 15, 31, 103, 499]),
    (9, 25, &[1, 1, 1, 11, 11, 17, 63, 105, 183]),
    (9, 44, &[1, 1, 5, 11, 9, 29, 97, 231, 363]),
    (9, 47, &[1, 1, 5, 15, 19, 45, 41, 7, 383]),
    (9, 52, &[1, 3, 7, 7, 31, 19, 83, 137, 221]),
    (9, 55, &[1, 1, 1, 3, 23, 15, 111, 223, 83]),
    (9, 59, &[1, 1, 5, 13, 31, 15, 55, 25, 161]),
    (9, 62, &[1, 1, 3, 13, 25, 47, 39, 87, 257]),
    (9, 67, &[1, 1, 1, 11, 21, 53, 125, 249, 293]),
    (9, 74, &[1, 1, 7, 11, 11, 7, 57, 79, 323]),
    (9, 81, &[1, 1, 5, 5, 17, 13, 81, 3, 131]),
    (9, 82, &[1, 1, 7, 13, 23, 7, 65, 251, 475]),
    (9, 87, &[1, 3, 5, 1, 9, 43, 3, 149, 11]),
    (9, 91, &[1, 1, 3, 13, 31, 13, 13, 255, 487]),
    (9, 94, &[1, 3, 3, 1, 5, 63, 89, 91, 127]),
    (9, 103, &[1, 1, 3, 3, 1, 19, 123, 127, 237]),
    (9, 104, &[1, 1, 5, 7, 23, 31, 37, 243, 289]),
    (9, 109, &[1, 1, 5, 11, 17, 53, 117, 183, 491]),
    (9, 122, &[1, 1, 1, 5, 1, 13, 13, 209, 345]),
    (9, 124, &[1, 1, 3, 15, 1, 57, 115, 7, 33]),
    (9, 137, &[1, 3, 1, 11, 7, 43, 81, 207, 175]),
    (9, 138, &[1, 3, 1, 1, 15, 27, 63, 255, 49]),
    (9, 143, &[1, 3, 5, 3, 27, 61, 105, 171, 305]),
    (9, 145, &[1, 1, 5, 3, 1, 3, 57, 249, 149]),
    (9, 152, &[1, 1, 3, 5, 5, 57, 15, 13, 159]),
    (9, 157, &[1, 1, 1, 11, 7, 11, 105, 141, 225]),
    (9, 167, &[1, 3, 3, 5, 27, 59, 121, 101, 271]),
    (9, 173, &[1, 3, 5, 9, 11, 49, 51, 59, 115]),
    (9, 176, &[1, 1, 7, 1, 23, 45, 125, 71, 419]),
    (9, 181, &[1, 1, 3, 5, 23, 5, 105, 109, 75]),
    (9, 182, &[1, 1, 7, 15, 7, 11, 67, 121, 453]),
    (9, 185, &[1, 3, 7, 3, 9, 13, 31, 27, 449]),
    (9, 191, &[1, 3, 1, 15, 19, 39, 39, 89, 15]),
    (9, 194, &[1, 1, 1, 1, 1, 33, 73, 145, 379]),
    (9, 199, &[1, 3, 1, 15, 15, 43, 29, 13, 483]),
    (9, 218, &[1, 1, 7, 3, 19, 27, 85, 131, 431]),
    (9, 220, &[1, 3, 3, 3, 5, 35, 23, 195, 349]),
    (9, 227, &[1, 3, 3, 7, 9, 27, 39, 59, 297]),
    (9, 229, &[1, 1, 3, 9, 11, 17, 13, 241, 157]),
    (9, 230, &[1, 3, 7, 15, 25, 57, 33, 189, 213]),
    (9, 234, &[1, 1, 7, 1, 9, 55, 73, 83, 217]),
    (9, 236, &[1, 3, 3, 13, 19, 27, 23, 113, 249]),
    (9, 241, &[1, 3, 5, 3, 23, 43, 3, 253, 479]),
    (9, 244, &[1, 1, 5, 5, 11, 5, 45, 117, 217]),
    (9, 253, &[1, 3, 3, 7, 29, 37, 33, 123, 147]),
    (10, 4, &[1, 3, 1, 15, 5, 5, 37, 227, 223, 459]),
    (10, 13, &[1, 1, 7, 5, 5, 39, 63, 255, 135, 487]),
    (10, 19, &[1, 3, 1, 7, 9, 7, 87, 249, 217, 599]),
    (10, 22, &[1, 1, 3, 13, 9, 47, 7, 225, 363, 247]),
    (10, 50, &[1, 3, 7, 13, 19, 13, 9, 67, 9, 737]),
    (10, 55, &[1, 3, 5, 5, 19, 59, 7, 41, 319, 677]),
    (10, 64, &[1, 1, 5, 3, 31, 63, 15, 43, 207, 789]),
    (10, 69, &[1, 1, 7, 9, 13, 39, 3, 47, 497, 169]),
    (10, 98, &[1, 3, 1, 7, 21, 17, 97, 19, 415, 905]),
    (10, 107, &[1, 3, 7, 1, 3, 31, 71, 111, 165, 127]),
    (10, 115, &[1, 1, 5, 11, 1, 61, 83, 119, 203, 847]),
    (10, 121, &[1, 3, 3, 13, 9, 61, 19, 97, 47, 35]),
    (10, 127, &[1, 1, 7, 7, 15, 29, 63, 95, 417, 469]),
    (10, 134, &[1, 3, 1, 9, 25, 9, 71, 57, 213, 385]),
    (10, 140, &[1, 3, 5, 13, 31, 47, 101, 57, 39, 341]),
    (10, 145, &[1, 1, 3, 3, 31, 57, 125, 173, 365, 551]),
    (10, 152, &[1, 3, 7, 1, 13, 57, 67, 157, 451, 707]),
    (10, 158, &[1, 1, 1, 7, 21, 13, 105, 89, 429, 965]),
    (10, 161, &[1, 1, 5, 9, 17, 51, 45, 119, 157, 141]),
    (10, 171, &[1, 3, 7, 7, 13, 45, 91, 9, 129, 741]),
    (10, 181, &[1, 3, 7, 1, 23, 57, 67, 141, 151, 571]),
    (10, 194, &[1, 1, 3, 11, 17, 47, 93, 107, 375, 157]),
    (10, 199, &[1, 3, 3, 5, 11, 21, 43, 51, 169, 915]),
];

/// Direction numbers `V[dim][j]` (the generator matrix's column j, most
/// significant bit first): `m_j 2^(32 - j)` for j < s, then the recurrence
/// `V_j = V_(j-s) ^ (V_(j-s) >> s) ^ sum_k a_k V_(j-k)`.
pub static DIRECTIONS: [[u32; 32]; SOBOL_DIMS] = directions();

/// The index bits one lookup of the matrix product takes.
const GROUP_BITS: usize = 3;

/// Groups of [`GROUP_BITS`] index bits in a `u32`.
const GROUPS: usize = 32usize.div_ceil(GROUP_BITS);

/// The matrix product by groups of three index bits, in the reversed domain
/// (the product then yields the reversed point, which is what the scramble
/// works on): `.0[dim][g][j]` is the XOR of the bit-reversed direction numbers
/// `3g + b` of `dim` for the set bits `b` of `j % 8`. Each row's second half
/// repeats its first ([`U32Lanes::lookup8`]); rows are cache-line aligned.
#[repr(C, align(64))]
struct DirectionGroups([[[u32; 16]; GROUPS]; SOBOL_DIMS]);

static DIRECTION_GROUPS: DirectionGroups = DirectionGroups(groups(reversed(directions())));

const fn directions() -> [[u32; 32]; SOBOL_DIMS] {
    let mut v = [[0u32; 32]; SOBOL_DIMS];
    let mut j = 0;
    while j < 32 {
        v[0][j] = 1 << (31 - j);
        j += 1;
    }
    let mut d = 1;
    while d < SOBOL_DIMS {
        let (s, a, m) = JOE_KUO[d - 1];
        let s = s as usize;
        assert!(m.len() == s);
        let mut j = 0;
        while j < 32 {
            v[d][j] = if j < s {
                m[j] << (31 - j)
            } else {
                let mut x = v[d][j - s] ^ (v[d][j - s] >> s);
                let mut k = 1;
                while k < s {
                    if (a >> (s - 1 - k)) & 1 == 1 {
                        x ^= v[d][j - k];
                    }
                    k += 1;
                }
                x
            };
            j += 1;
        }
        d += 1;
    }
    v
}

const fn reversed(mut v: [[u32; 32]; SOBOL_DIMS]) -> [[u32; 32]; SOBOL_DIMS] {
    let mut d = 0;
    while d < SOBOL_DIMS {
        let mut j = 0;
        while j < 32 {
            v[d][j] = v[d][j].reverse_bits();
            j += 1;
        }
        d += 1;
    }
    v
}

const fn groups(v: [[u32; 32]; SOBOL_DIMS]) -> [[[u32; 16]; GROUPS]; SOBOL_DIMS] {
    let mut t = [[[0u32; 16]; GROUPS]; SOBOL_DIMS];
    let mut d = 0;
    while d < SOBOL_DIMS {
        let mut g = 0;
        while g < GROUPS {
            let mut j = 0;
            while j < 16 {
                let mut x = 0;
                let mut b = 0;
                while b < GROUP_BITS {
                    let col = g * GROUP_BITS + b;
                    if (j >> b) & 1 == 1 && col < 32 {
                        x ^= v[d][col];
                    }
                    b += 1;
                }
                t[d][g][j] = x;
                j += 1;
            }
            g += 1;
        }
        d += 1;
    }
    t
}

/// The unscrambled Sobol point: dimension `dim` of point `index`, as a 32-bit
/// binary fraction. The scalar reference of the matrix product.
pub fn sobol_u32(index: u32, dim: usize) -> u32 {
    let mut x = 0;
    for (j, v) in DIRECTIONS[dim].iter().enumerate() {
        if (index >> j) & 1 == 1 {
            x ^= v;
        }
    }
    x
}

/// A Laine-Karras style permutation of bit-reversed values: bit j of the
/// result depends only on bits 0..=j of `x` (each step is an add, an xor with
/// a multiple by an even constant, or a multiply by an odd number, which all
/// carry information only upwards), and it is a bijection. Constants from
/// Vegdahl, "Building a Better LK Hash" (2021).
#[inline(always)]
fn lk_permute<U: U32Lanes>(x: U, seed: U) -> U {
    let x = x ^ x.wrapping_mul(U::splat(0x3d20_adea));
    let x = x.wrapping_add(seed);
    let x = x.wrapping_mul((seed >> 16) | U::splat(1));
    let x = x ^ x.wrapping_mul(U::splat(0x0552_6c56));
    x ^ x.wrapping_mul(U::splat(0x53a2_2864))
}

/// Nested uniform (Owen) scramble of 32-bit binary fractions with `seed`:
/// bit k (counted from the most significant) is flipped as a function of the
/// bits above it and the seed.
#[inline(always)]
pub fn owen_scramble<U: U32Lanes>(x: U, seed: U) -> U {
    lk_permute(x.reverse_bits(), seed).reverse_bits()
}

/// The Owen-scrambled Sobol point, lane-wise: [`owen_scramble`] of
/// [`sobol_u32`], computed in the reversed domain. The matrix product takes
/// the index three bits at a time, one table lookup per group
/// ([`U32Lanes::lookup8`]), up to the highest set bit among the lanes'
/// indices (a bound uniform across lanes; the value does not depend on it):
/// two lookups for an index below 64.
#[inline(always)]
pub fn sobol_owen<U: U32Lanes>(index: U, dim: usize, seed: U) -> U {
    let mut x = U::splat(0);
    let mut rest = index;
    for group in &DIRECTION_GROUPS.0[dim] {
        if rest.all_zero() {
            break;
        }
        x = x ^ U::lookup8(group, rest);
        rest = rest >> GROUP_BITS as u32;
    }
    lk_permute(x, seed).reverse_bits()
}

/// The key of a pixel's points in a render with `seed` (`pixel` = y * width + x
/// in the full image). 32 bits: two pixels of a large image may share a key,
/// and then their points, which makes their errors correlated but not biased.
#[inline]
pub fn pixel_key(seed: u64, pixel: u64) -> u32 {
    (mix64(mix64(seed ^ 0x5f0b_01c0_0000_0000) ^ pixel) >> 32) as u32
}

/// The scramble seed of dimension `dim` of the pixel with key `key`.
#[inline(always)]
pub fn dim_seed<U: U32Lanes>(key: U, dim: u32) -> U {
    hash32(key ^ U::splat(hash32(dim.wrapping_mul(0x9e37_79b9) ^ 0x2545_f491)))
}

/// The 32 random bits of dimension `dim` of sample `index` of the pixel with
/// key `key`: Owen-scrambled Sobol below `sobol_dims` (at most
/// [`SOBOL_DIMS`]), padding (an independent hash) at and above it.
/// `sobol_dims` and `dim` are uniform across lanes.
#[inline(always)]
pub fn sample_bits<U: U32Lanes>(key: U, index: U, dim: u32, sobol_dims: u32) -> U {
    let seed = dim_seed(key, dim);
    if dim < sobol_dims && (dim as usize) < SOBOL_DIMS {
        sobol_owen(index, dim as usize, seed)
    } else {
        hash32(seed ^ hash32(index.wrapping_add(U::splat(0x6a09_e667))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::real::Real;
    use wide::u32x8;

    /// Direction numbers of new-joe-kuo-6.21201 expanded to 32 bits, as
    /// published in pbrt-v4's `SobolMatrices32` (dimension, first 32 columns).
    #[rustfmt::skip]
    const PUBLISHED: [(usize, [u32; 32]); 6] = [
        (
            1,
            [
                0x8000_0000, 0xc000_0000, 0xa000_0000, 0xf000_0000, 0x8800_0000, 0xcc00_0000, 0xaa00_0000, 0xff00_0000,
                0x8080_0000, 0xc0c0_0000, 0xa0a0_0000, 0xf0f0_0000, 0x8888_0000, 0xcccc_0000, 0xaaaa_0000, 0xffff_0000,
                0x8000_8000, 0xc000_c000, 0xa000_a000, 0xf000_f000, 0x8800_8800, 0xcc00_cc00, 0xaa00_aa00, 0xff00_ff00,
                0x8080_8080, 0xc0c0_c0c0, 0xa0a0_a0a0, 0xf0f0_f0f0, 0x8888_8888, 0xcccc_cccc, 0xaaaa_aaaa, 0xffff_ffff,
            ],
        ),
        (
            2,
            [
                0x8000_0000, 0xc000_0000, 0x6000_0000, 0x9000_0000, 0xe800_0000, 0x5c00_0000, 0x8e00_0000, 0xc500_0000,
                0x6880_0000, 0x9cc0_0000, 0xee60_0000, 0x5590_0000, 0x8068_0000, 0xc09c_0000, 0x60ee_0000, 0x9055_0000,
                0xe880_8000, 0x5cc0_c000, 0x8e60_6000, 0xc590_9000, 0x6868_e800, 0x9c9c_5c00, 0xeeee_8e00, 0x5555_c500,
                0x8000_e880, 0xc000_5cc0, 0x6000_8e60, 0x9000_c590, 0xe800_6868, 0x5c00_9c9c, 0x8e00_eeee, 0xc500_5555,
            ],
        ),
        (
            3,
            [
                0x8000_0000, 0xc000_0000, 0x2000_0000, 0x5000_0000, 0xf800_0000, 0x7400_0000, 0xa200_0000, 0x9300_0000,
                0xd880_0000, 0x2540_0000, 0x59e0_0000, 0xe6d0_0000, 0x7808_0000, 0xb40c_0000, 0x8202_0000, 0xc305_0000,
                0x208f_8000, 0x5147_4000, 0xfbea_2000, 0x75d9_3000, 0xa085_8800, 0x914e_5400, 0xdbe7_9e00, 0x25db_6d00,
                0x5880_0080, 0xe540_00c0, 0x79e0_0020, 0xb6d0_0050, 0x8008_00f8, 0xc00c_0074, 0x2002_00a2, 0x5005_0093,
            ],
        ),
        (
            10,
            [
                0x8000_0000, 0x4000_0000, 0xa000_0000, 0x1000_0000, 0x0800_0000, 0x6c00_0000, 0x9e00_0000, 0x2300_0000,
                0x5780_0000, 0xadc0_0000, 0x7fa0_0000, 0x91d0_0000, 0x4988_0000, 0xced4_0000, 0x880a_0000, 0x2c0f_0000,
                0x3e0d_8000, 0x3317_c000, 0x5fb0_6000, 0xc1f8_b000, 0xe18d_8800, 0xb2d7_c400, 0x1e10_6a00, 0x6328_b100,
                0xf785_8880, 0xbdc3_c2c0, 0x77ba_63e0, 0xfdf7_b330, 0xd780_0df8, 0xedc0_081c, 0xdfa0_041a, 0x81d0_0a2d,
            ],
        ),
        (
            63,
            [
                0x8000_0000, 0x4000_0000, 0x6000_0000, 0xd000_0000, 0xc800_0000, 0xbc00_0000, 0x4e00_0000, 0x5700_0000,
                0x8080_0000, 0x0a40_0000, 0xfd20_0000, 0x8db0_0000, 0xffa8_0000, 0xa684_0000, 0x110e_0000, 0x4bdf_0000,
                0x74d7_8000, 0xb872_4000, 0x8408_2000, 0x8a74_1000, 0xbd06_1800, 0xedab_3400, 0x2fd1_b200, 0x6ed9_6f00,
                0xad59_b380, 0x05ed_45c0, 0x23ff_9820, 0x38b6_6690, 0x8e26_3548, 0x771b_286c, 0x30f9_866a, 0x121d_6761,
            ],
        ),
        (
            123,
            [
                0x8000_0000, 0xc000_0000, 0x6000_0000, 0x5000_0000, 0x5800_0000, 0x5400_0000, 0x5600_0000, 0x3300_0000,
                0x5480_0000, 0xe4c0_0000, 0x17a0_0000, 0x1870_0000, 0xcf78_0000, 0x05c4_0000, 0xbe1e_0000, 0xaf29_0000,
                0x6e8f_8000, 0x85db_c000, 0x7e23_a000, 0xcf05_7000, 0x3e91_8800, 0xddf2_cc00, 0x2a2c_2600, 0x991e_b500,
                0x0d92_2d80, 0x8947_b940, 0xcee5_ab60, 0x8e98_7a30, 0x15f8_0ec8, 0x4604_020c, 0xcb3e_079a, 0x3099_02f7,
            ],
        ),
    ];

    #[test]
    fn direction_numbers_match_the_published_joe_kuo_matrices() {
        for (d, cols) in PUBLISHED {
            assert_eq!(DIRECTIONS[d], cols, "dimension {d}");
        }
        for (j, c) in DIRECTIONS[0].iter().enumerate() {
            assert_eq!(*c, 1 << (31 - j));
        }
        // Every generator matrix is upper triangular with a unit diagonal
        // (column j is an odd m_j times 2^(31 - j)), as a Sobol matrix must be.
        for (d, cols) in DIRECTIONS.iter().enumerate() {
            for (j, c) in cols.iter().enumerate() {
                assert_eq!(c.trailing_zeros() as usize, 31 - j, "dimension {d} column {j}");
            }
        }
    }

    #[test]
    fn matrix_product_matches_the_gray_code_generator() {
        // Joe and Kuo's own generator walks the Gray code: X_(i+1) = X_i ^ V_c
        // with c the lowest zero bit of i, so X_i is point gray(i) = i ^ (i >> 1).
        for dim in [0, 1, 2, 5, 40, 123] {
            let mut x = 0u32;
            for i in 0u32..5000 {
                assert_eq!(x, sobol_u32(i ^ (i >> 1), dim), "dim {dim} i {i}");
                x ^= DIRECTIONS[dim][i.trailing_ones() as usize];
            }
        }
        // The first points of dimension 1 (s = 1): 0, 1/2, 3/4, 1/4, ...
        let first: Vec<u32> = (0..4).map(|i| sobol_u32(i, 1)).collect();
        assert_eq!(first, [0, 0x8000_0000, 0xc000_0000, 0x4000_0000]);
    }

    #[test]
    fn owen_scramble_is_nested_uniform() {
        // Flipping bit k (from the top) of the input flips bit k of the output
        // and leaves every bit above it unchanged.
        let mut h = 7u32;
        for _ in 0..20_000 {
            h = hash32(h.wrapping_add(1));
            let (x, seed) = (h, hash32(h ^ 0xabcd));
            let y = owen_scramble(x, seed);
            for k in 0..32 {
                let y2 = owen_scramble(x ^ (0x8000_0000 >> k), seed);
                let diff = y ^ y2;
                assert_eq!(diff.leading_zeros(), k, "x {x:#x} seed {seed:#x} bit {k}");
            }
        }
        // Unscrambled points agree with the reversed-domain generator.
        for (i, dim) in [(0u32, 0usize), (1, 3), (77, 9), (1 << 20, 100), (u32::MAX, 123), (1 << 31, 7)] {
            assert_eq!(sobol_owen(i, dim, 12345), owen_scramble(sobol_u32(i, dim), 12345));
        }
        // Every index bit of every dimension goes through its group's table.
        for dim in 0..SOBOL_DIMS {
            for i in (0..32).map(|b| 1u32 << b).chain([0x0000_00ff, 0x1234_5678, 0xdead_beef, u32::MAX]) {
                let seed = hash32(i ^ dim as u32);
                assert_eq!(sobol_owen(i, dim, seed), owen_scramble(sobol_u32(i, dim), seed), "dim {dim} i {i:#x}");
            }
        }
    }

    /// Every elementary interval of volume 1/n holds exactly one of the n points
    /// (a (0, m, 2)-net), for every split of the m bits between the axes.
    fn is_net_2d(pts: &[(u32, u32)], m: u32) -> bool {
        (0..=m).all(|a| {
            let b = m - a;
            let mut seen = vec![false; 1 << m];
            pts.iter().all(|&(x, y)| {
                let cell = (((x as u64) >> (32 - a)) << b | ((y as u64) >> (32 - b))) as usize;
                !std::mem::replace(&mut seen[cell], true)
            })
        })
    }

    #[test]
    fn pixel_jitter_dimensions_are_a_0_2_sequence() {
        for key in [0u32, 1, 0xdead_beef, pixel_key(9, 12345)] {
            for m in 0..=12u32 {
                for block in [0u32, 3] {
                    let n = 1u32 << m;
                    let pts: Vec<(u32, u32)> = (block * n..(block + 1) * n)
                        .map(|i| (sample_bits(key, i, 0, 124), sample_bits(key, i, 1, 124)))
                        .collect();
                    assert!(is_net_2d(&pts, m), "key {key:#x} m {m} block {block}");
                }
            }
        }
    }

    #[test]
    fn every_dimension_is_stratified_in_1d() {
        for dim in 0..SOBOL_DIMS as u32 {
            let key = pixel_key(3, dim as u64 * 31);
            for m in [1u32, 4, 7, 10] {
                let mut seen = vec![false; 1 << m];
                for i in 0..1u32 << m {
                    let cell = (sample_bits(key, i, dim, 124) >> (32 - m)) as usize;
                    assert!(!std::mem::replace(&mut seen[cell], true), "dim {dim} m {m}");
                }
            }
        }
    }

    /// The smallest t for which the first 2^m points of (d1, d2) are a (t, m, 2)-net.
    fn t_value(d1: u32, d2: u32, m: u32) -> u32 {
        let pts: Vec<(u32, u32)> =
            (0..1u32 << m).map(|i| (sample_bits(5, i, d1, 124), sample_bits(5, i, d2, 124))).collect();
        (0..=m)
            .find(|&t| {
                let k = m - t;
                (0..=k).all(|a| {
                    let b = k - a;
                    let mut count = vec![0u32; 1 << k];
                    for &(x, y) in &pts {
                        count[(((x as u64) >> (32 - a)) << b | ((y as u64) >> (32 - b))) as usize] += 1;
                    }
                    count.iter().all(|&c| c == 1 << t)
                })
            })
            .unwrap()
    }

    #[test]
    fn layout_pairs_are_good_2d_nets() {
        // Measured t of the scattering pairs (the lens pair is t <= 1): at most
        // 4 at 256 points, and 6 at 1024, over the 40 bounces of the layout.
        assert_eq!(t_value(0, 1, 10), 0);
        assert!(t_value(2, 3, 10) <= 1);
        for b in 0..40 {
            let d = 4 + 3 * b;
            assert!(t_value(d, d + 1, 8) <= 4, "bounce {b}");
            assert!(t_value(d, d + 1, 10) <= 6, "bounce {b}");
        }
    }

    #[test]
    fn values_are_uniform_across_pixels_and_below_one() {
        // For one index and dimension the scramble makes the value uniform over
        // pixels: 16 bins of 16384 keys each, chi-square with 15 degrees of
        // freedom far below its 1e-6 tail (about 52).
        for (index, dim) in [(0u32, 0u32), (1, 1), (5, 4), (77, 30), (300, 123), (3, 500)] {
            let mut bins = [0u32; 16];
            let n = 16 * 16384;
            for p in 0..n {
                let bits = sample_bits(pixel_key(1, p), index, dim, 124);
                let u = f32::unit_from_bits(bits);
                assert!((0.0..1.0).contains(&u));
                bins[(bits >> 28) as usize] += 1;
            }
            let e = n as f64 / 16.0;
            let chi2: f64 = bins.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
            assert!(chi2 < 52.0, "index {index} dim {dim}: chi2 {chi2}");
        }
        // The largest bits give the largest float, which is below 1.
        assert!(f32::unit_from_bits(u32::MAX) < 1.0);
        assert!(wide::f32x8::unit_from_bits(u32x8::splat(u32::MAX)).to_array().iter().all(|&u| u < 1.0));
    }

    #[test]
    fn padding_starts_at_the_limit() {
        let (key, i) = (pixel_key(1, 2), 3u32);
        assert_eq!(sample_bits(key, i, 3, 4), sobol_owen(i, 3, dim_seed(key, 3)));
        assert_ne!(sample_bits(key, i, 4, 4), sample_bits(key, i, 4, 124));
        assert_eq!(sample_bits(key, i, 200, 124), sample_bits(key, i, 200, 4));
    }
}
