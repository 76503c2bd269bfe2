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

use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Shl, Shr, Sub};
use wide::{f32x16, f32x8, i32x16, i32x8, u32x16, u32x8};

/// The most lanes any width has (`f32x16`): the size of per-packet scratch arrays.
pub const MAX_LANES: usize = 16;

/// A lane mask: `bool` for one lane, an all-ones/all-zeros float vector for several.
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

macro_rules! impl_mask {
    ($f:ident) => {
        impl Mask for $f {
            #[inline(always)]
            fn any(self) -> bool {
                $f::any(self)
            }
            #[inline(always)]
            fn all(self) -> bool {
                $f::all(self)
            }
        }
    };
}
impl_mask!(f32x8);
impl_mask!(f32x16);

/// A real number: one lane (`f32`), eight (`f32x8`) or sixteen (`f32x16`).
pub trait Real:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self>
{
    type Mask: Mask;
    /// The matching unsigned integer lanes (random streams).
    type U32: U32Lanes;
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
    /// `self * m + a`, fused (one rounding) where the build has FMA, two
    /// roundings otherwise: for tests whose error is bounded either way (the
    /// BVH's slab test), never for values that reach the image, which every
    /// build must compute alike.
    fn mul_add_bound(self, m: Self, a: Self) -> Self;
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
    /// Rounded down to an integer (exact, as `f32::floor`; `-0.0` stays `-0.0`).
    fn floor(self) -> Self;
    /// The IEEE-754 bits of each lane.
    fn to_u32_bits(self) -> Self::U32;
    /// The real whose IEEE-754 bits are `u`, in each lane.
    fn from_u32_bits(u: Self::U32) -> Self;
    /// Each lane's integer `u` (below 2^24, so exactly) as a real.
    fn from_small_u32(u: Self::U32) -> Self;
    fn u_splat(x: u32) -> Self::U32;
    /// `a < b` per lane, as a mask of this width (closest-hit ties: lower index wins).
    fn u_lt(a: Self::U32, b: Self::U32) -> Self::Mask;
    /// `a == b` per lane, as a mask of this width.
    fn u_eq(a: Self::U32, b: Self::U32) -> Self::Mask;
    fn u_select(m: Self::Mask, a: Self::U32, b: Self::U32) -> Self::U32;
    /// Lane k as an `f32` (probes and tests; not for the hot path).
    fn lane(self, k: usize) -> f32;
    fn lane_u(x: Self::U32, k: usize) -> u32;
    /// Bit k set where lane k of the mask is on.
    fn mask_bits(m: Self::Mask) -> u32;
    /// The value with `f(k)` in lane k.
    fn from_fn(f: impl FnMut(usize) -> f32) -> Self;
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
    fn mul_add_bound(self, m: Self, a: Self) -> Self {
        #[cfg(target_feature = "fma")]
        {
            f32::mul_add(self, m, a)
        }
        #[cfg(not(target_feature = "fma"))]
        {
            self * m + a
        }
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
    #[inline(always)]
    fn floor(self) -> Self {
        f32::floor(self)
    }
    #[inline(always)]
    fn to_u32_bits(self) -> u32 {
        f32::to_bits(self)
    }
    #[inline(always)]
    fn from_u32_bits(u: u32) -> Self {
        f32::from_bits(u)
    }
    #[inline(always)]
    fn from_small_u32(u: u32) -> Self {
        u as f32
    }
    #[inline(always)]
    fn u_splat(x: u32) -> u32 {
        x
    }
    #[inline(always)]
    fn u_lt(a: u32, b: u32) -> bool {
        a < b
    }
    #[inline(always)]
    fn u_eq(a: u32, b: u32) -> bool {
        a == b
    }
    #[inline(always)]
    fn u_select(m: bool, a: u32, b: u32) -> u32 {
        if m {
            a
        } else {
            b
        }
    }
    #[inline(always)]
    fn lane(self, _k: usize) -> f32 {
        self
    }
    #[inline(always)]
    fn lane_u(x: u32, _k: usize) -> u32 {
        x
    }
    #[inline(always)]
    fn mask_bits(m: bool) -> u32 {
        m as u32
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        f(0)
    }
}

/// The SIMD widths: `Real` plus what the wavefront kernel needs to move lanes
/// in and out of its structure-of-arrays queues.
pub trait Wide:
    Real<Mask = Self, U32 = <Self as Wide>::U>
    + Mask
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + Not<Output = Self>
    + Send
    + Sync
    + 'static
{
    /// The matching unsigned lanes (same as `Real::U32`, with its arithmetic).
    type U: U32Lanes;
    /// Lane indices of one packet (`[u32; LANES]`).
    type Idx: Copy + Default + AsRef<[u32]> + AsMut<[u32]>;
    /// Whole-vector load of `v[i..i + LANES]`.
    fn load(v: &[f32], i: usize) -> Self;
    fn store(self, v: &mut [f32], i: usize);
    fn load_u(v: &[u32], i: usize) -> Self::U32;
    fn store_u(x: Self::U32, v: &mut [u32], i: usize);
    /// `v[idx[k]]` in lane k.
    fn gather(v: &[f32], idx: &[u32]) -> Self;
    fn gather_u(v: &[u32], idx: &[u32]) -> Self::U32;
    /// `v[idx[k] % N]` in lane k, for a power of two `N`: the index is masked
    /// (`& (N - 1)`), so it is in bounds by construction and no lane is
    /// bounds-checked. The mask is one `and` per lane, which the compiler
    /// drops where it already knows the bits (an index masked before).
    fn gather_pow2<const N: usize>(v: &[f32; N], idx: &Self::Idx) -> Self;
    fn gather_u_pow2<const N: usize>(v: &[u32; N], idx: &Self::Idx) -> Self::U32;
    /// Whole-vector load of `v[j..j + LANES]` with `j = i % N` rounded down to
    /// a multiple of `LANES` (`i` itself for the multiples of `LANES` below
    /// `N` that the kernels use), `N` a power of two: in bounds by construction.
    fn load_pow2<const N: usize>(v: &[f32; N], i: usize) -> Self;
    fn load_u_pow2<const N: usize>(v: &[u32; N], i: usize) -> Self::U32;
    fn store_pow2<const N: usize>(self, v: &mut [f32; N], i: usize);
    fn store_u_pow2<const N: usize>(x: Self::U32, v: &mut [u32; N], i: usize);
    /// The lanes as indices (an array).
    fn idx_of(x: Self::U32) -> Self::Idx;
    /// Rows of 8 floats gathered and transposed: lane k of output `j` is
    /// `rows[idx[k]][j]` (one whole-row load per lane and an 8x8 transpose,
    /// instead of 8 gathers). `rows.len()` must be a power of two above every
    /// index: the index is masked with `len - 1`, in bounds by construction
    /// (an empty `rows` gives zeros).
    fn gather_rows8<T: AsRef<[f32; 8]>>(rows: &[T], idx: &Self::Idx) -> [Self; 8];
    /// [`Wide::compress_store_u`] into an array of power-of-two length `N`
    /// (at least `2 LANES`), at `at <= N - 2 LANES`: no bounds checks.
    fn compress_store_u_pow2<const N: usize>(x: Self::U32, keep: u32, v: &mut [u32; N], at: usize) -> usize;
    fn u_from_fn(f: impl FnMut(usize) -> u32) -> Self::U32;
    /// The mask with lane k on where bit k of `bits` is set.
    fn mask_from_bits(bits: u32) -> Self;
    /// The bits of every lane (for stores through the `u32` compaction).
    fn to_bits(self) -> Self::U;
    /// Stream compaction: stores the lanes of `x` whose bit is set in `keep`,
    /// in lane order, at `v[at..]`. May write up to `LANES` values past the
    /// kept ones (the arrays have `LANES` of slack); returns how many were kept.
    fn compress_store_u(x: Self::U32, keep: u32, v: &mut [u32], at: usize) -> usize;
}

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

    /// Lane k: `table[idx_k % 8]`, a lookup per lane in an eight-entry
    /// table (one permute: `vpermd`). The table's second half repeats its
    /// first, so that sixteen lanes may index it modulo 16.
    fn lookup8(table: &[u32; 16], idx: Self) -> Self;

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
    fn lookup8(table: &[u32; 16], idx: Self) -> Self {
        table[(idx & 7) as usize]
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
            fn lookup8(table: &[u32; 16], idx: Self) -> Self {
                // Lane k takes entry idx_k modulo the width, the same
                // entry as modulo 8 since the table's halves are equal.
                if $n == 8 || cfg!(target_feature = "avx512f") {
                    let t: [u32; $n] = table[..$n].try_into().unwrap();
                    <$t>::new(t).shuffle_wrapping(idx)
                } else {
                    // Sixteen lanes in two registers: a permute of the
                    // eight entries per half (the full 16-entry lookup
                    // would blend two permutes per half).
                    let t = u32x8::new(table[..8].try_into().unwrap());
                    let halves: [u32x8; $n / 8] = bytemuck::cast(idx);
                    bytemuck::cast(halves.map(|h| t.shuffle_wrapping(h)))
                }
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

/// For each 8-bit lane mask, the indices of its set lanes first (stream compaction).
static COMPRESS: [[u32; 8]; 256] = compress_table();

const fn compress_table() -> [[u32; 8]; 256] {
    let mut t = [[0u32; 8]; 256];
    let mut m = 0;
    while m < 256 {
        let (mut k, mut n) = (0, 0);
        while k < 8 {
            if m & (1 << k) != 0 {
                t[m][n] = k as u32;
                n += 1;
            }
            k += 1;
        }
        m += 1;
    }
    t
}

/// Compaction of 8 lanes: the kept lanes permuted to the front by a table
/// lookup and stored as one whole vector.
#[inline(always)]
fn compress8(x: u32x8, keep: u32, v: &mut [u32], at: usize) -> usize {
    let packed = x.shuffle(u32x8::new(COMPRESS[(keep & 0xff) as usize]));
    v[at..at + 8].copy_from_slice(&packed.to_array());
    (keep & 0xff).count_ones() as usize
}

/// [`compress8`] into an array, at `at <= N - 8` (checked once per call by the caller's bound).
#[inline(always)]
fn compress8_array<const N: usize>(x: u32x8, keep: u32, v: &mut [u32; N], at: usize) -> usize {
    let packed = x.shuffle(u32x8::new(COMPRESS[(keep & 0xff) as usize]));
    let at = at.min(N - 8);
    v[at..at + 8].copy_from_slice(&packed.to_array());
    (keep & 0xff).count_ones() as usize
}

macro_rules! impl_wide {
    ($f:ident, $u:ident, $i:ident, $n:literal, $from_int:ident) => {
        impl Real for $f {
            type Mask = $f;
            type U32 = $u;
            const LANES: usize = $n;

            #[inline(always)]
            fn splat(x: f32) -> Self {
                $f::splat(x)
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                $f::sqrt(self)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                $f::abs(self)
            }
            #[inline(always)]
            fn min(self, o: Self) -> Self {
                // Same rule as the scalar `min`: take `o` only where `o < self`.
                o.simd_lt(self).select(o, self)
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                o.simd_gt(self).select(o, self)
            }
            #[inline(always)]
            fn fast_min(self, o: Self) -> Self {
                $f::fast_min(self, o)
            }
            #[inline(always)]
            fn fast_max(self, o: Self) -> Self {
                $f::fast_max(self, o)
            }
            #[inline(always)]
            fn copysign(self, sign: Self) -> Self {
                let s = $f::splat(-0.0);
                (self & !s) | (sign & s)
            }
            #[inline(always)]
            fn mul_add_bound(self, m: Self, a: Self) -> Self {
                // `wide` fuses where the build has FMA, and multiplies then adds otherwise.
                $f::mul_add(self, m, a)
            }
            #[inline(always)]
            fn lt(self, o: Self) -> $f {
                self.simd_lt(o)
            }
            #[inline(always)]
            fn le(self, o: Self) -> $f {
                self.simd_le(o)
            }
            #[inline(always)]
            fn gt(self, o: Self) -> $f {
                self.simd_gt(o)
            }
            #[inline(always)]
            fn ge(self, o: Self) -> $f {
                self.simd_ge(o)
            }
            #[inline(always)]
            fn eq(self, o: Self) -> $f {
                self.simd_eq(o)
            }
            #[inline(always)]
            fn is_finite(self) -> $f {
                $f::is_finite(self)
            }
            #[inline(always)]
            fn select(m: $f, a: Self, b: Self) -> Self {
                m.select(a, b)
            }
            #[inline(always)]
            fn unit_from_bits(bits: $u) -> Self {
                // (bits >> 8) < 2^24, so the signed conversion is exact.
                let i: $i = bytemuck::cast(bits >> 8);
                $f::$from_int(i) * $f::splat(1.0 / 16_777_216.0)
            }
            #[inline(always)]
            fn floor(self) -> Self {
                $f::floor(self)
            }
            #[inline(always)]
            fn to_u32_bits(self) -> $u {
                bytemuck::cast(self)
            }
            #[inline(always)]
            fn from_u32_bits(u: $u) -> Self {
                bytemuck::cast(u)
            }
            #[inline(always)]
            fn from_small_u32(u: $u) -> Self {
                // Below 2^24, so the signed conversion is exact.
                $f::$from_int(bytemuck::cast::<$u, $i>(u))
            }
            #[inline(always)]
            fn u_splat(x: u32) -> $u {
                $u::splat(x)
            }
            #[inline(always)]
            fn u_lt(a: $u, b: $u) -> $f {
                bytemuck::cast(a.simd_lt(b))
            }
            #[inline(always)]
            fn u_eq(a: $u, b: $u) -> $f {
                bytemuck::cast(a.simd_eq(b))
            }
            #[inline(always)]
            fn u_select(m: $f, a: $u, b: $u) -> $u {
                // A float blend of the bits (a select moves bits, it does not
                // compute with them): on AVX-512 a move under the compare's
                // mask register, where the integer select is a byte blend
                // that converts the mask to a vector and back.
                bytemuck::cast(m.select(bytemuck::cast::<$u, $f>(a), bytemuck::cast::<$u, $f>(b)))
            }
            #[inline(always)]
            fn lane(self, k: usize) -> f32 {
                self.to_array()[k]
            }
            #[inline(always)]
            fn lane_u(x: $u, k: usize) -> u32 {
                x.to_array()[k]
            }
            #[inline(always)]
            fn mask_bits(m: $f) -> u32 {
                m.to_bitmask()
            }
            #[inline(always)]
            fn from_fn(f: impl FnMut(usize) -> f32) -> Self {
                $f::new(std::array::from_fn(f))
            }
        }

        impl Wide for $f {
            type U = $u;
            type Idx = [u32; $n];
            #[inline(always)]
            fn load(v: &[f32], i: usize) -> Self {
                $f::new(v[i..i + $n].try_into().unwrap())
            }
            #[inline(always)]
            fn store(self, v: &mut [f32], i: usize) {
                v[i..i + $n].copy_from_slice(&self.to_array());
            }
            #[inline(always)]
            fn load_u(v: &[u32], i: usize) -> $u {
                $u::new(v[i..i + $n].try_into().unwrap())
            }
            #[inline(always)]
            fn store_u(x: $u, v: &mut [u32], i: usize) {
                v[i..i + $n].copy_from_slice(&x.to_array());
            }
            #[inline(always)]
            fn gather(v: &[f32], idx: &[u32]) -> Self {
                $f::new(std::array::from_fn(|k| v[idx[k] as usize]))
            }
            #[inline(always)]
            fn gather_u(v: &[u32], idx: &[u32]) -> $u {
                $u::new(std::array::from_fn(|k| v[idx[k] as usize]))
            }
            #[inline(always)]
            fn gather_pow2<const N: usize>(v: &[f32; N], idx: &[u32; $n]) -> Self {
                const { assert!(N.is_power_of_two()) };
                $f::new(std::array::from_fn(|k| v[idx[k] as usize & (N - 1)]))
            }
            #[inline(always)]
            fn gather_u_pow2<const N: usize>(v: &[u32; N], idx: &[u32; $n]) -> $u {
                const { assert!(N.is_power_of_two()) };
                $u::new(std::array::from_fn(|k| v[idx[k] as usize & (N - 1)]))
            }
            #[inline(always)]
            fn load_pow2<const N: usize>(v: &[f32; N], i: usize) -> Self {
                const { assert!(N.is_power_of_two() && N >= $n) };
                let j = i & (N - $n);
                $f::new(v[j..j + $n].try_into().unwrap())
            }
            #[inline(always)]
            fn load_u_pow2<const N: usize>(v: &[u32; N], i: usize) -> $u {
                const { assert!(N.is_power_of_two() && N >= $n) };
                let j = i & (N - $n);
                $u::new(v[j..j + $n].try_into().unwrap())
            }
            #[inline(always)]
            fn store_pow2<const N: usize>(self, v: &mut [f32; N], i: usize) {
                const { assert!(N.is_power_of_two() && N >= $n) };
                let j = i & (N - $n);
                v[j..j + $n].copy_from_slice(&self.to_array());
            }
            #[inline(always)]
            fn store_u_pow2<const N: usize>(x: $u, v: &mut [u32; N], i: usize) {
                const { assert!(N.is_power_of_two() && N >= $n) };
                let j = i & (N - $n);
                v[j..j + $n].copy_from_slice(&x.to_array());
            }
            #[inline(always)]
            fn idx_of(x: $u) -> [u32; $n] {
                x.to_array()
            }
            #[inline(always)]
            fn gather_rows8<T: AsRef<[f32; 8]>>(rows: &[T], idx: &[u32; $n]) -> [Self; 8] {
                let Some(last) = rows.len().checked_sub(1) else { return [$f::splat(0.0); 8] };
                debug_assert!(rows.len().is_power_of_two() && idx.iter().all(|&i| (i as usize) <= last));
                // A loop and an array literal, not `from_fn`: its closures
                // were compiled out of line (a call per gather) in the
                // 16-lane kernels.
                let mut halves = [[f32x8::splat(0.0); 8]; $n / 8];
                for (h, half) in halves.iter_mut().enumerate() {
                    let row = |k: usize| f32x8::new(*rows[idx[8 * h + k] as usize & last].as_ref());
                    *half = f32x8::transpose([row(0), row(1), row(2), row(3), row(4), row(5), row(6), row(7)]);
                }
                std::array::from_fn(|j| {
                    let parts: [f32x8; $n / 8] = std::array::from_fn(|h| halves[h][j]);
                    bytemuck::cast(parts)
                })
            }
            #[inline(always)]
            fn compress_store_u_pow2<const N: usize>(x: $u, keep: u32, v: &mut [u32; N], at: usize) -> usize {
                const { assert!(N.is_power_of_two() && N >= 2 * $n) };
                debug_assert!(at <= N - 2 * $n);
                let lanes: [u32x8; $n / 8] = bytemuck::cast(x);
                // `min` keeps the stores in bounds for the compiler (a no-op for valid `at`).
                let mut j = at.min(N - 2 * $n);
                for (c, half) in lanes.into_iter().enumerate() {
                    j += compress8_array(half, keep >> (8 * c), v, j);
                }
                j - at.min(N - 2 * $n)
            }
            #[inline(always)]
            fn u_from_fn(f: impl FnMut(usize) -> u32) -> $u {
                $u::new(std::array::from_fn(f))
            }
            #[inline(always)]
            fn mask_from_bits(bits: u32) -> Self {
                // Lane k tests its own bit: a broadcast, an and and a compare.
                let lane_bit = $u::new(std::array::from_fn(|k| 1u32 << k));
                bytemuck::cast(($u::splat(bits) & lane_bit).simd_eq(lane_bit))
            }
            #[inline(always)]
            fn to_bits(self) -> $u {
                bytemuck::cast(self)
            }
            #[inline(always)]
            fn compress_store_u(x: $u, keep: u32, v: &mut [u32], at: usize) -> usize {
                let lanes: [u32x8; $n / 8] = bytemuck::cast(x);
                let mut n = at;
                for (c, half) in lanes.into_iter().enumerate() {
                    n += compress8(half, keep >> (8 * c), v, n);
                }
                n - at
            }
        }
    };
}

impl_wide!(f32x8, u32x8, i32x8, 8, from_i32x8);
impl_wide!(f32x16, u32x16, i32x16, 16, from_i32x16);
const _: () = assert!(<f32x8 as Real>::LANES <= MAX_LANES && <f32x16 as Real>::LANES <= MAX_LANES);
