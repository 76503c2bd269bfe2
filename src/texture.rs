//! Textures: what a lambertian's albedo is at a hit point, written once over
//! [`Real`] for the scalar kernel and every lane width, and the per-kind
//! texture tables the kernels read.
//!
//! A material row refers to a texture ([`TexRef`]): a solid colour (the
//! material table's own albedo, as before textures existed), or a row of
//! one texture kind's table. The wavefront evaluates each textured kind in a
//! pass of its own, before the material passes, over the lanes that share
//! it; the scalar kernel calls the same functions at one lane. A lane's
//! table row may differ from its neighbours' (two checkers in one packet):
//! the parameters are loaded per lane ([`Real::from_fn`]), never broadcast.
//!
//! * **Checker**: the book's 3-D spatial checker, the parity of
//!   `floor(p.x / s) + floor(p.y / s) + floor(p.z / s)` (computed as
//!   `floor(inv_scale p)`, inv_scale rounded once to f32, as the book does in
//!   double). The sum is exact while each floor is below 2^24 in magnitude;
//!   beyond that every f32 is an even integer and the checker reads "even".
//! * **Noise**: the book's marble, `0.5 (1 + sin(scale p.z + 10 turb(p)))`,
//!   with `turb` the 7-octave sum of Perlin gradient noise of the unscaled
//!   point (v4's code; its text and v4.0.0-alpha.1 scale the point first). [`Perlin`]'s lattice
//!   tables come from rtow's own seeded generator: the book's come from
//!   `random_double()` in the order its program happens to call it, which
//!   cannot be reproduced (and need not be: the pattern is the same
//!   process, not the same picture).
//! * **Image**: the book's `image_texture`, the nearest texel at the hit's
//!   (u, v): a sphere's from its outward normal (`u = (atan2(-z, x) + π) /
//!   2π`, `v = acos(-y) / π`), a quad's its (alpha, beta); u and v clamped to
//!   [0, 1], v flipped (row 0 is the image's top). Texels are linearized as
//!   the book's fixed v4.0.x pipeline does, one table entry per byte value
//!   ([`linear_byte`]).

use crate::math::{acos, atan2, sin};
use crate::real::Real;
use crate::vec3::V3;
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Serialize, Serializer};

/// Texture kinds; every kind but `Solid` gets a pass of its own.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
#[repr(u8)]
pub enum TexKind {
    /// The material table's albedo (no pass: what every scene without textures uses).
    #[default]
    Solid = 0,
    Checker = 1,
    Noise = 2,
    Image = 3,
}

impl TexKind {
    /// The kinds that have a pass, in pass order.
    pub const PASSES: [TexKind; 3] = [TexKind::Checker, TexKind::Noise, TexKind::Image];
    pub fn name(self) -> &'static str {
        match self {
            TexKind::Solid => "solid",
            TexKind::Checker => "checker",
            TexKind::Noise => "noise",
            TexKind::Image => "image",
        }
    }
}

/// A set of texture kinds (serialized as the list of their names).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TexSet(u8);

impl TexSet {
    pub fn insert(&mut self, k: TexKind) {
        self.0 |= 1 << k as u8;
    }
    pub fn contains(self, k: TexKind) -> bool {
        self.0 & (1 << k as u8) != 0
    }
    pub fn iter(self) -> impl Iterator<Item = TexKind> {
        TexKind::PASSES.into_iter().filter(move |&k| self.contains(k))
    }
    pub fn is_empty(&self) -> bool {
        self.0 == 0
    }
}

impl Serialize for TexSet {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.iter().map(TexKind::name))
    }
}

/// A material's texture: its kind and its row in that kind's table (0 for `Solid`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TexRef {
    pub kind: TexKind,
    pub row: u32,
}

/// The book's `checker_texture(scale, even, odd)` with solid colours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Checker {
    /// `1 / scale`, rounded to f32 once.
    pub inv_scale: f32,
    pub even: [f32; 3],
    pub odd: [f32; 3],
}

/// The book's `noise_texture(scale)` (marble).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    pub scale: f32,
}

/// The lattice of Perlin's gradient noise: 256 unit gradient vectors and a
/// permutation of 0..256 per axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Perlin {
    pub ranvec: Box<[[f32; 3]; 256]>,
    pub perm: [[u8; 256]; 3],
}

/// The seed of every scene's Perlin lattice. A constant, so a scene's marble
/// is part of the scene (the same under every render seed, in every shard).
pub const PERLIN_SEED: u64 = 0x5045_524c_494e_0001;

impl Perlin {
    /// The lattice drawn from xoshiro256++ seeded with `seed`: the book's
    /// construction (each gradient a uniform point of the cube [-1, 1)^3,
    /// normalized, in f64, then rounded; each permutation the identity
    /// shuffled by Fisher-Yates from the top, `target = random_int(0, i)`),
    /// with one change: a point within 1e-3 of the centre is drawn again, so
    /// no gradient is a normalized rounding error.
    pub fn new(seed: u64) -> Perlin {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut unit = move || (rng.next_u64() >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0);
        let mut ranvec = Box::new([[0.0f32; 3]; 256]);
        for g in ranvec.iter_mut() {
            *g = loop {
                let v: [f64; 3] = std::array::from_fn(|_| 2.0 * unit() - 1.0);
                let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                if len > 1e-3 {
                    break v.map(|x| (x / len) as f32);
                }
            };
        }
        let mut perm = [[0u8; 256]; 3];
        for p in perm.iter_mut() {
            for (i, x) in p.iter_mut().enumerate() {
                *x = i as u8;
            }
            for i in (1..256).rev() {
                let target = ((unit() * (i + 1) as f64) as usize).min(i);
                p.swap(i, target);
            }
        }
        Perlin { ranvec, perm }
    }
}

/// An image texture's texels, linear RGB, row 0 the image's top row.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageTex {
    pub width: u32,
    pub height: u32,
    /// `width * height` texels, row by row.
    pub texels: Vec<[f32; 3]>,
}

impl ImageTex {
    /// The texture of 8-bit RGB `bytes` (`3 width height` of them, row by
    /// row from the top), each byte linearized by [`linear_byte`].
    /// `None` when the sizes disagree or the image is empty.
    pub fn from_rgb8(width: u32, height: u32, bytes: &[u8]) -> Option<ImageTex> {
        let n = (width as usize).checked_mul(height as usize)?;
        if n == 0 || bytes.len() != n.checked_mul(3)? {
            return None;
        }
        let lut: [f32; 256] = std::array::from_fn(|b| linear_byte(b as u8));
        let texels =
            bytes.chunks_exact(3).map(|c| [lut[c[0] as usize], lut[c[1] as usize], lut[c[2] as usize]]).collect();
        Some(ImageTex { width, height, texels })
    }
}

/// The book's linear value of an 8-bit component `b` (its fixed v4.0.x
/// pipeline): stb_image's `(b / 255)^2.2` as a float, back to a byte as
/// `rtw_image::float_to_byte` does (`<= 0`: 0, `>= 1`: 255, else the
/// truncation of `256 v`), divided by 255. So 255 stays 1 (the March-2024
/// code, without the clamp, turned it into 256, out of a byte's range: the
/// book's bug on pure white), and the texels take the book's 256 values.
pub fn linear_byte(b: u8) -> f32 {
    let v = (b as f32 / 255.0).powf(2.2);
    let byte = if v <= 0.0 {
        0.0
    } else if v >= 1.0 {
        255.0
    } else {
        (256.0 * v as f64).floor()
    };
    (byte / 255.0) as f32
}

/// Every texture table a scene needs (empty ones for a scene without textures).
#[derive(Clone, Debug, Default)]
pub struct TextureTables {
    pub checker: Vec<Checker>,
    pub noise: Vec<Noise>,
    /// Present when some material uses a noise texture.
    pub perlin: Option<Perlin>,
    /// Each image texture row's image (rows naming one file share it).
    pub image: Vec<std::sync::Arc<ImageTex>>,
}

/// The checker's colour at `p`; lane k reads its parameters from `row(k)`.
#[inline(always)]
pub fn checker<R: Real>(p: V3<R>, row: impl Fn(usize) -> Checker) -> V3<R> {
    let inv = R::from_fn(|k| row(k).inv_scale);
    let s = (inv * p.x).floor() + (inv * p.y).floor() + (inv * p.z).floor();
    let even = (s - R::splat(2.0) * (s * R::splat(0.5)).floor()).eq(R::splat(0.0));
    let col = |f: fn(&Checker) -> [f32; 3]| {
        V3::new(R::from_fn(|k| f(&row(k))[0]), R::from_fn(|k| f(&row(k))[1]), R::from_fn(|k| f(&row(k))[2]))
    };
    V3::select(even, col(|c| c.even), col(|c| c.odd))
}

/// The nearest texel of `img(k)` at (`u`, `v`) for each lane k (the book's
/// `image_texture::value`): u and v clamped to [0, 1], v flipped,
/// `i = floor(u W)` and `j = floor((1 - v) H)` clamped to the last column
/// and row (u = 1 would be one past it).
#[inline(always)]
pub fn image_texel<'a, R: Real>(u: R, v: R, img: impl Fn(usize) -> &'a ImageTex) -> V3<R> {
    let (zero, one) = (R::splat(0.0), R::splat(1.0));
    let u = u.max(zero).min(one);
    let v = one - v.max(zero).min(one);
    let x = u * R::from_fn(|k| img(k).width as f32);
    let y = v * R::from_fn(|k| img(k).height as f32);
    let mut c = [[0.0f32; 3]; crate::real::MAX_LANES];
    for (k, c) in c.iter_mut().enumerate().take(R::LANES) {
        let t = img(k);
        // `as` saturates (and takes NaN to 0); `min` keeps the index in the image.
        let i = (x.lane(k) as usize).min(t.width as usize - 1);
        let j = (y.lane(k) as usize).min(t.height as usize - 1);
        *c = t.texels[j * t.width as usize + i];
    }
    V3::new(R::from_fn(|k| c[k][0]), R::from_fn(|k| c[k][1]), R::from_fn(|k| c[k][2]))
}

/// A sphere's texture coordinates (the book's `get_sphere_uv`) at the
/// outward unit normal `n`: `u = (atan2(-z, x) + π) / 2π`, `v = acos(-y) / π`
/// (y clamped to [-1, 1], which rounding can leave).
#[inline(always)]
pub fn sphere_uv<R: Real>(n: V3<R>) -> (R, R) {
    use std::f32::consts::PI;
    let one = R::splat(1.0);
    let phi = atan2(-n.z, n.x) + R::splat(PI);
    let theta = acos((-n.y).max(-one).min(one));
    (phi * R::splat(0.5 / PI), theta * R::splat(1.0 / PI))
}

/// A quad's texture coordinates (the book's (alpha, beta)) at `p`:
/// `alpha = w . ((p - q) x v)`, `beta = w . (u x (p - q))`, `w = n / (n . n)`.
#[inline(always)]
pub fn quad_uv<R: Real>(p: V3<R>, q: V3<R>, u: V3<R>, v: V3<R>, w: V3<R>) -> (R, R) {
    let pq = p - q;
    (w.dot(pq.cross(v)), w.dot(u.cross(pq)))
}

/// The lattice integer of each lane of `f` (a floor), wrapped to 0..256 as
/// the book's `int(...) & 255` (two's complement, so negative cells wrap too;
/// beyond `i64`'s range the conversion saturates).
#[inline(always)]
fn cells<R: Real>(f: R) -> [usize; crate::real::MAX_LANES] {
    let mut c = [0usize; crate::real::MAX_LANES];
    for (k, c) in c.iter_mut().enumerate().take(R::LANES) {
        *c = (f.lane(k) as i64 & 255) as usize;
    }
    c
}

/// Perlin's gradient noise at `p` (the book's `perlin::noise`): the
/// gradients of the cell's 8 corners, each dotted with the offset from its
/// corner and weighted trilinearly by the Hermite-smoothed fractions.
#[inline(always)]
pub fn noise<R: Real>(p: V3<R>, lattice: &Perlin) -> R {
    let (fx, fy, fz) = (p.x.floor(), p.y.floor(), p.z.floor());
    let (u, v, w) = (p.x - fx, p.y - fy, p.z - fz);
    let (one, two, three) = (R::splat(1.0), R::splat(2.0), R::splat(3.0));
    let (uu, vv, ww) = (u * u * (three - two * u), v * v * (three - two * v), w * w * (three - two * w));
    let (ci, cj, ck) = (cells(fx), cells(fy), cells(fz));
    let [px, py, pz] = &lattice.perm;
    let mut accum = R::splat(0.0);
    for i in 0..2usize {
        let wi = if i == 1 { uu } else { one - uu };
        for j in 0..2usize {
            let wj = if j == 1 { vv } else { one - vv };
            for k in 0..2usize {
                let wk = if k == 1 { ww } else { one - ww };
                // The corner's gradient, hashed once per lane, loaded per lane.
                let mut h = [0usize; crate::real::MAX_LANES];
                for (l, h) in h.iter_mut().enumerate().take(R::LANES) {
                    *h = (px[(ci[l] + i) & 255] ^ py[(cj[l] + j) & 255] ^ pz[(ck[l] + k) & 255]) as usize;
                }
                let g = |a: usize| R::from_fn(|l| lattice.ranvec[h[l]][a]);
                let off = V3::new(u - R::splat(i as f32), v - R::splat(j as f32), w - R::splat(k as f32));
                accum = accum + wi * wj * wk * V3::new(g(0), g(1), g(2)).dot(off);
            }
        }
    }
    accum
}

/// The book's turbulence: `|sum of 2^-i noise(2^i p)|` over 7 octaves.
#[inline(always)]
pub fn turb<R: Real>(p: V3<R>, lattice: &Perlin) -> R {
    let mut accum = R::splat(0.0);
    let mut weight = R::splat(1.0);
    let mut q = p;
    for _ in 0..7 {
        accum = accum + weight * noise(q, lattice);
        weight = weight * R::splat(0.5);
        q = q * R::splat(2.0);
    }
    accum.abs()
}

/// The book's marble (`noise_texture::value`, v4 code):
/// `0.5 (1 + sin(scale p.z + 10 turb(p)))`, grey. The sine is clamped to
/// [-1, 1] (it is within 2.5e-7 of the true sine up to `math::SIN_MAX_ARG`;
/// beyond, where its reduction is no longer exact, the clamp keeps the
/// albedo in [0, 1]).
#[inline(always)]
pub fn marble<R: Real>(p: V3<R>, scale: R, lattice: &Perlin) -> V3<R> {
    let one = R::splat(1.0);
    let s = sin(scale * p.z + R::splat(10.0) * turb(p, lattice)).max(-one).min(one);
    let g = R::splat(0.5) * (one + s);
    V3::new(g, g, g)
}
