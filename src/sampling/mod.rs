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
//!
//! Two samplers feed those functions ([`SamplerKind`]): the independent
//! streams above, and Owen-scrambled Sobol points ([`sobol`], [`SobolStream`]),
//! whose values are addressed by dimension along the [`layout`].

pub mod lanes;
pub mod sobol;

use crate::real::{Real, U32Lanes, Wide};
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
    /// Moves to dimension `dim` of the [`layout`] (uniform across lanes): the
    /// next value is that dimension's, the one after it `dim + 1`'s. Streams
    /// that do not address dimensions (the independent one) ignore it, so it
    /// costs them nothing.
    #[inline(always)]
    fn seek(&mut self, _dim: u32) {}
}

/// Which sampler draws a path's values (the estimator's choice; it changes
/// the noise, not the expected image). The default is Sobol: on the final
/// scene it reaches the independent sampler's 500-spp error in 0.32x the time
/// (docs/sampling.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampler {
    /// Independent uniform numbers: one xoshiro128+ stream per path (the book's way).
    Independent,
    /// Owen-scrambled Sobol points along the [`layout`]: the first `dims`
    /// dimensions (at most [`sobol::SOBOL_DIMS`]) are Sobol, the rest padding.
    Sobol { dims: u32 },
}

impl Default for Sampler {
    fn default() -> Self {
        Sampler::SOBOL
    }
}

impl Sampler {
    /// Every dimension of the layout on Sobol points.
    pub const SOBOL: Sampler = Sampler::Sobol { dims: sobol::SOBOL_DIMS as u32 };
    /// The names [`Sampler::parse`] accepts (the `sobol-*` ones put only the
    /// named groups of the layout on Sobol points, to measure what each gains).
    pub const NAMES: &'static [&'static str] = &["independent", "sobol", "sobol-pixel", "sobol-lens", "sobol-bounce1"];

    pub fn name(self) -> &'static str {
        match self {
            Sampler::Independent => "independent",
            Sampler::Sobol { dims } if dims >= sobol::SOBOL_DIMS as u32 => "sobol",
            Sampler::Sobol { dims: layout::LENS } => "sobol-pixel",
            Sampler::Sobol { dims: layout::FIRST_BOUNCE } => "sobol-lens",
            Sampler::Sobol { dims } if dims == layout::scatter(1) => "sobol-bounce1",
            // Built by hand with another count: named, but not one `parse` takes.
            Sampler::Sobol { .. } => "sobol-partial",
        }
    }

    pub fn parse(text: &str) -> Option<Sampler> {
        Some(match text {
            "independent" => Sampler::Independent,
            "sobol" => Sampler::SOBOL,
            "sobol-pixel" => Sampler::Sobol { dims: layout::LENS },
            "sobol-lens" => Sampler::Sobol { dims: layout::FIRST_BOUNCE },
            "sobol-bounce1" => Sampler::Sobol { dims: layout::scatter(1) },
            _ => return None,
        })
    }
}

impl std::fmt::Display for Sampler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Sampler {
    type Err = String;
    fn from_str(s: &str) -> Result<Sampler, String> {
        Sampler::parse(s).ok_or_else(|| format!("'{s}' is not one of {}", Sampler::NAMES.join(", ")))
    }
}

impl serde::Serialize for Sampler {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for Sampler {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Sampler, D::Error> {
        let name = String::deserialize(d)?;
        name.parse().map_err(serde::de::Error::custom)
    }
}

/// How the kernels make and keep a path's stream, one implementation per
/// sampler. The kernels are instantiated for each (chosen once per tile), so
/// the hot path has no dispatch, and with [`Independent`] they run exactly the
/// code they ran before samplers existed.
pub trait PathSampler: Copy + Send + Sync {
    /// The `u32` words of per-path state the wavefront keeps (at most 4).
    const WORDS: usize;
    type Scalar: Stream<f32>;
    type Lanes<W: Wide>: Stream<W>;
    /// The scalar stream of path (`pixel`, `sample`) of a render with `seed`.
    fn scalar(&self, seed: u64, pixel: u64, sample: u32) -> Self::Scalar;
    /// The same path's state words (the first `WORDS` are used).
    #[inline]
    fn words(&self, seed: u64, pixel: u64, sample: u32) -> [u32; 4] {
        self.words_at(self.pixel_words(seed, pixel), sample)
    }
    /// What the state words of every path of `pixel` share, computed once
    /// per pixel (the Sobol pixel key; the seed and pixel otherwise).
    fn pixel_words(&self, seed: u64, pixel: u64) -> [u32; 4];
    /// The state words of sample `sample` of the pixel whose
    /// [`PathSampler::pixel_words`] are `pixel_words`: exactly
    /// [`PathSampler::words`].
    fn words_at(&self, pixel_words: [u32; 4], sample: u32) -> [u32; 4];
    /// Lanes of streams from their state words.
    fn lanes<W: Wide>(&self, words: [W::U; 4]) -> Self::Lanes<W>;
    /// The state words of lanes of streams (after their draws).
    fn lane_words<W: Wide>(s: &Self::Lanes<W>) -> [W::U; 4];
}

/// Evaluates `$body` with `$s` bound to the [`PathSampler`] that the
/// [`Sampler`] value `$sampler` names: the one place a sampler choice becomes
/// a type. The kernels are instantiated per sampler, so the hot path has no
/// dispatch.
macro_rules! with_path_sampler {
    ($sampler:expr, $s:ident => $body:expr) => {
        match $sampler {
            $crate::sampling::Sampler::Independent => {
                let $s = $crate::sampling::Independent;
                $body
            }
            $crate::sampling::Sampler::Sobol { dims } => {
                let $s = $crate::sampling::Sobol { dims };
                $body
            }
        }
    };
}
pub(crate) use with_path_sampler;

/// The independent sampler: rand_xoshiro's stream per path (scalar), the same
/// xoshiro128+ lane-wise (wavefront).
#[derive(Clone, Copy, Debug, Default)]
pub struct Independent;

impl PathSampler for Independent {
    const WORDS: usize = 4;
    type Scalar = ScalarStream;
    type Lanes<W: Wide> = XoshiroLanes<W::U>;
    #[inline]
    fn scalar(&self, seed: u64, pixel: u64, sample: u32) -> ScalarStream {
        ScalarStream::for_path(seed, pixel, sample as u64)
    }
    #[inline]
    fn pixel_words(&self, seed: u64, pixel: u64) -> [u32; 4] {
        [seed as u32, (seed >> 32) as u32, pixel as u32, (pixel >> 32) as u32]
    }
    #[inline]
    fn words_at(&self, w: [u32; 4], sample: u32) -> [u32; 4] {
        let join = |lo: u32, hi: u32| lo as u64 | (hi as u64) << 32;
        path_state(join(w[0], w[1]), join(w[2], w[3]), sample as u64)
    }
    #[inline(always)]
    fn lanes<W: Wide>(&self, words: [W::U; 4]) -> XoshiroLanes<W::U> {
        XoshiroLanes { s: words }
    }
    #[inline(always)]
    fn lane_words<W: Wide>(s: &XoshiroLanes<W::U>) -> [W::U; 4] {
        s.s
    }
}

/// The Sobol sampler: state words (pixel key, sample index); the dimension is
/// set by the kernel along the [`layout`] and is the same in every lane.
#[derive(Clone, Copy, Debug)]
pub struct Sobol {
    /// Leading dimensions on Sobol points; the rest are padding.
    pub dims: u32,
}

impl PathSampler for Sobol {
    const WORDS: usize = 2;
    type Scalar = SobolStream<u32>;
    type Lanes<W: Wide> = SobolStream<W::U>;
    #[inline]
    fn scalar(&self, seed: u64, pixel: u64, sample: u32) -> SobolStream<u32> {
        SobolStream::for_path(seed, pixel, sample, self.dims)
    }
    #[inline]
    fn pixel_words(&self, seed: u64, pixel: u64) -> [u32; 4] {
        [sobol::pixel_key(seed, pixel), 0, 0, 0]
    }
    #[inline]
    fn words_at(&self, w: [u32; 4], sample: u32) -> [u32; 4] {
        [w[0], sample, 0, 0]
    }
    #[inline(always)]
    fn lanes<W: Wide>(&self, w: [W::U; 4]) -> SobolStream<W::U> {
        SobolStream { key: w[0], index: w[1], dim: 0, sobol_dims: self.dims }
    }
    #[inline(always)]
    fn lane_words<W: Wide>(s: &SobolStream<W::U>) -> [W::U; 4] {
        [s.key, s.index, s.key, s.index]
    }
}

/// The dimension layout: which dimension of a path's sample each random
/// decision takes. `depth` counts the rays a path traced before the hit that
/// scatters (0: the camera ray's hit).
///
/// | dimensions | use |
/// |---|---|
/// | 0, 1 | pixel jitter (x, y): a (0,2)-sequence |
/// | 2, 3 | lens (radius, angle), when the camera has a lens |
/// | 4 + 3 depth, +1 | scattering: two for a lambertian or metal direction (z, angle); a dielectric's reflect-or-refract choice takes the first |
/// | 4 + 3 depth + 2 | the Russian-roulette decision after that bounce |
/// | `TIME` = 0x4000_0000 | the path's time in [0, 1) (motion blur), drawn by the camera after its ray, scenes with moving spheres only |
/// | 0x4000_1000 + k 2^22 + depth | scenes with media: the free-flight distance of medium k at that bounce ([`layout::free_flight`]; padding, not Sobol) |
/// | under `book`: 4 + 6 depth, ..., 9 + 6 depth | the `book` estimator's layout ([`layout::Bounces::BOOK`]): scattering (2), roulette (1), then the light sample at a diffuse vertex (3: the mixture's choice and which shape, then the point on the shape); bounces 0 to 19 on Sobol dimensions |
///
/// Bounces 0 to 39 take Sobol dimensions (4 to 123, [`sobol::SOBOL_DIMS`] in
/// all); from bounce 40 on the dimensions are padding (independent hashed
/// values). The dimensions wrap around past 2^32 (a path of more than 1.4e9
/// bounces), which no render reaches.
///
/// The time dimension is **not** Sobol-stratified: it lies far above the
/// Sobol dimensions, so under the Sobol sampler its value is padding (an
/// independent hashed value per path), under the independent sampler the
/// next draw of the path's stream. It cannot take a low dimension: the
/// bounces fill the low range contiguously, and moving them to make room
/// would change every documented image. No bounce below depth 357,913,940
/// reaches it (bounce `depth` uses dimensions up to `4 + 3 depth + 2`).
pub mod layout {
    pub const PIXEL: u32 = 0;
    pub const LENS: u32 = 2;
    pub const FIRST_BOUNCE: u32 = 4;
    pub const PER_BOUNCE: u32 = 3;
    /// Bounces whose dimensions are all Sobol dimensions.
    pub const SOBOL_BOUNCES: u32 = 40;
    /// The path's time (motion blur), for scenes with moving spheres.
    pub const TIME: u32 = 0x4000_0000;

    /// The first of the two scattering dimensions of bounce `depth`.
    #[inline(always)]
    pub const fn scatter(depth: u32) -> u32 {
        FIRST_BOUNCE.wrapping_add(PER_BOUNCE.wrapping_mul(depth))
    }

    /// The Russian-roulette dimension of bounce `depth`.
    #[inline(always)]
    pub const fn roulette(depth: u32) -> u32 {
        scatter(depth).wrapping_add(2)
    }

    /// The dimensions of each bounce: [`scatter`] and [`roulette`]'s
    /// layout (3 per bounce) for the `bsdf` estimator, 6 per bounce for the
    /// `book` estimator, whose light samples take the last 3, so that they
    /// too are Sobol points for the first 20 bounces. A render takes one
    /// (`Prepared::bounces`); both kernels read the same.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub struct Bounces {
        pub per_bounce: u32,
    }

    impl Bounces {
        /// The `bsdf` estimator's: [`scatter`], [`roulette`] (every documented image).
        pub const BSDF: Bounces = Bounces { per_bounce: PER_BOUNCE };
        /// The `book` and `nee-mis` estimators': scattering, roulette, then 3
        /// light dimensions (the mixture's choice or the light's pick, then
        /// the point on the shape).
        pub const BOOK: Bounces = Bounces { per_bounce: PER_BOUNCE + 3 };

        /// The first of the two scattering dimensions of bounce `depth`.
        #[inline(always)]
        pub const fn scatter(self, depth: u32) -> u32 {
            FIRST_BOUNCE.wrapping_add(self.per_bounce.wrapping_mul(depth))
        }

        /// The Russian-roulette dimension of bounce `depth`.
        #[inline(always)]
        pub const fn roulette(self, depth: u32) -> u32 {
            self.scatter(depth).wrapping_add(2)
        }

        /// The first of the three light-sample dimensions of bounce `depth`
        /// (the `book` layout only, which `nee-mis` shares).
        #[inline(always)]
        pub const fn light(self, depth: u32) -> u32 {
            self.scatter(depth).wrapping_add(3)
        }
    }

    /// The first free-flight dimension (constant media).
    pub const FREE_FLIGHT: u32 = 0x4000_1000;
    /// The stride between the free-flight dimensions of two media: paths of
    /// up to 2^22 bounces never share one.
    pub const FREE_FLIGHT_STRIDE: u32 = 1 << 22;

    /// The free-flight dimension of medium `k` (the scene's k-th, at most
    /// `limits::MAX_MEDIA`) at bounce `depth`: `0x4000_1000 + k 2^22 + depth`.
    ///
    /// Padding under Sobol (independent hashed values), not Sobol points: the
    /// low dimensions belong to the pixel, the lens and the bounces, in the
    /// order every documented image hash was rendered with, and a
    /// medium's draw at every bounce would otherwise shift them. Each path
    /// draws these at every bounce, whether its ray meets the medium or not,
    /// so the layout stays independent of the data.
    #[inline(always)]
    pub const fn free_flight(depth: u32, k: u32) -> u32 {
        FREE_FLIGHT.wrapping_add(k.wrapping_mul(FREE_FLIGHT_STRIDE)).wrapping_add(depth)
    }
}

/// A path's Sobol sample, lane-wise: the pixel's key and the sample index per
/// lane, the current dimension (uniform) and the number of leading dimensions
/// that are Sobol (the rest padding). A pure function of those: no state is
/// carried between draws but the dimension.
#[derive(Clone, Copy, Debug)]
pub struct SobolStream<U> {
    pub key: U,
    pub index: U,
    pub dim: u32,
    pub sobol_dims: u32,
}

impl SobolStream<u32> {
    /// The scalar stream of path (`pixel`, `sample`) of a render with `seed`.
    pub fn for_path(seed: u64, pixel: u64, sample: u32, sobol_dims: u32) -> Self {
        SobolStream { key: sobol::pixel_key(seed, pixel), index: sample, dim: 0, sobol_dims }
    }
}

impl<R: Real> Stream<R> for SobolStream<R::U32>
where
    R::U32: lanes::U32Lanes,
{
    #[inline(always)]
    fn next(&mut self) -> R {
        let bits = sobol::sample_bits(self.key, self.index, self.dim, self.sobol_dims);
        self.dim = self.dim.wrapping_add(1);
        R::unit_from_bits(bits)
    }
    #[inline(always)]
    fn seek(&mut self, dim: u32) {
        self.dim = dim;
    }
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

impl<U: U32Lanes> XoshiroLanes<U> {
    /// The next 32 bits of every lane: exactly `Xoshiro128Plus::next_u32`.
    #[inline(always)]
    pub fn next_u32(&mut self) -> U {
        let [s0, s1, s2, s3] = self.s;
        let result = s0.wrapping_add(s3); // as in rand_xoshiro
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

    #[test]
    fn a_pixels_shared_words_give_every_paths_state() {
        // The wavefront computes `pixel_words` once per pixel and round; the
        // scalar kernel's streams start from the path's whole key.
        for (seed, pixel) in [(0u64, 0u64), (7, 89_999), (u64::MAX, 1 << 40), (1 << 33, u32::MAX as u64 + 5)] {
            for sample in [0u32, 1, 31, 499, u32::MAX] {
                let pw = Independent.pixel_words(seed, pixel);
                assert_eq!(Independent.words_at(pw, sample), path_state(seed, pixel, sample as u64));
                let sobol = Sobol { dims: 4 };
                let pw = sobol.pixel_words(seed, pixel);
                assert_eq!(sobol.words_at(pw, sample), [sobol::pixel_key(seed, pixel), sample, 0, 0]);
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
    fn sampler_names_round_trip() {
        for name in Sampler::NAMES {
            assert_eq!(Sampler::parse(name).unwrap().name(), *name);
        }
        assert_eq!(Sampler::default(), Sampler::SOBOL);
        assert_eq!(Sampler::Sobol { dims: 50 }.name(), "sobol-partial");
        assert!("halton".parse::<Sampler>().unwrap_err().contains("independent, sobol"));
    }

    #[test]
    fn streams_differ_between_paths() {
        assert_ne!(path_state(1, 0, 0), path_state(1, 1, 0));
        assert_ne!(path_state(1, 0, 0), path_state(1, 0, 1));
        assert_ne!(path_state(1, 0, 0), path_state(2, 0, 0));
    }
}
