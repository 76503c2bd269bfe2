//! The kernels: the scalar reference (one path at a time) and the wavefront
//! (queues of paths, packets of `W::LANES` rays, generic over the lane width),
//! and what they share: the sky, the debug shadings; which kernel runs
//! ([`Kernel`]) and what this build's SIMD is ([`isa`]).

pub mod first_hit;
pub mod scalar;
pub mod wavefront;

use crate::choice::KernelChoice;
use crate::geometry::{Hit, HitKind, QuadRec};
use crate::plan::{Prepared, SkyColours};
use crate::real::Real;
use crate::texture::{checker, image_texel, marble, quad_uv, sphere_uv, TexKind};
use crate::vec3::V3;
use serde::Serialize;

/// The kernel that runs, after `simd` was resolved to a lane width.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kernel {
    Scalar,
    Simd8,
    Simd16,
}

impl Kernel {
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Scalar => "scalar",
            Kernel::Simd8 => "simd8",
            Kernel::Simd16 => "simd16",
        }
    }

    pub fn lanes(self) -> u32 {
        match self {
            Kernel::Scalar => 1,
            Kernel::Simd8 => 8,
            Kernel::Simd16 => 16,
        }
    }

    /// The kernel a choice runs on this build: `simd` is 16 lanes where
    /// `f32x16` is one register (AVX-512), 8 otherwise; `simd8` and `simd16`
    /// run on every build (without AVX-512, 16 lanes are two 8-lane halves:
    /// the same image, measured slower).
    pub fn resolve(choice: KernelChoice) -> Kernel {
        match choice {
            KernelChoice::Scalar => Kernel::Scalar,
            KernelChoice::Simd8 => Kernel::Simd8,
            KernelChoice::Simd if HAS_SIMD16 => Kernel::Simd16,
            KernelChoice::Simd => Kernel::Simd8,
            KernelChoice::Simd16 => Kernel::Simd16,
        }
    }
}

/// Whether `f32x16` is one register in this build (AVX-512F): then `simd` runs 16 lanes.
pub const HAS_SIMD16: bool = cfg!(target_feature = "avx512f");

/// The SIMD instruction set this binary was compiled for (`wide` picks its
/// implementation at compile time, from the build's `target-cpu` or
/// `target-feature` flags).
pub const fn isa() -> &'static str {
    if cfg!(all(target_feature = "avx512f", target_feature = "avx512vl", target_feature = "avx512bw")) {
        "AVX-512 (x86-64-v4)"
    } else if cfg!(all(target_feature = "avx2", target_feature = "fma")) {
        "AVX2+FMA (x86-64-v3)"
    } else if cfg!(target_feature = "avx") {
        "AVX"
    } else if cfg!(target_feature = "sse4.1") {
        "SSE4.1"
    } else if cfg!(target_feature = "sse2") {
        "SSE2"
    } else {
        "scalar fallback"
    }
}

/// The instruction set and the kernel `simd` runs, for `--version`.
pub fn build_description() -> String {
    let simd = if HAS_SIMD16 { "simd16 (f32x16)" } else { "simd8 (f32x8)" };
    format!("SIMD: {}, kernel simd = {simd}", isa())
}

/// The sky seen in unit direction `d`: horizon to zenith by `0.5 (d.y + 1)`.
#[inline(always)]
pub fn sky<R: Real>(s: &SkyColours, d: V3<R>) -> V3<R> {
    let a = R::splat(0.5) * (d.y + R::splat(1.0));
    V3::splat3(s.horizon) * (R::splat(1.0) - a) + V3::splat3(s.zenith) * a
}

/// What a ray leaving the scene in unit direction `d` sees: the constant
/// background, or the sky gradient.
#[inline(always)]
pub fn background<R: Real>(s: &SkyColours, d: V3<R>) -> V3<R> {
    match s.constant {
        Some(c) => V3::splat3(c),
        None => sky(s, d),
    }
}

/// Chapter 5's normal shading, `0.5 (n + 1)`.
#[inline(always)]
pub fn normal_colour<R: Real>(n: V3<R>) -> V3<R> {
    (n + V3::splat3([1.0, 1.0, 1.0])) * R::splat(0.5)
}

/// Chapter 1's gradient at pixel (x, y) (y = 0 is the top row).
pub fn gradient(x: u32, y: u32, width: u32, height: u32) -> [f32; 3] {
    let j = height - 1 - y;
    [x as f32 / width as f32, j as f32 / height as f32, 0.2]
}

/// The albedo of texture kind `kind` (not `Solid`) at the hit points `p`;
/// lane k hit primitive `hit(k)` (a hit index: a static sphere's or a
/// quad's, [`Hit`]) and reads row `row(k)` of the kind's table. One function for the
/// scalar kernel and the wavefront's texture passes.
#[inline(always)]
pub(crate) fn texture_albedo<R: Real>(
    prep: &Prepared,
    kind: TexKind,
    p: V3<R>,
    hit: impl Fn(usize) -> u32,
    row: impl Fn(usize) -> usize,
) -> V3<R> {
    let t = &prep.textures;
    match kind {
        TexKind::Checker => checker(p, |k| t.checker[row(k)]),
        TexKind::Noise => {
            let lattice = t.perlin.as_ref().expect("a scene with noise textures has a Perlin lattice");
            marble(p, R::from_fn(|k| t.noise[row(k)].scale), lattice)
        }
        TexKind::Image => {
            let (u, v) = surface_uv(prep, p, hit);
            image_texel(u, v, |k| &*t.image[row(k)])
        }
        TexKind::Solid => unreachable!("solid colours have no texture pass"),
    }
}

/// The texture coordinates of the hits at `p` (lane k on primitive
/// `hit(k)`): a sphere's from its outward normal `(p - c) / r`, a quad's
/// (alpha, beta). Both are computed for every lane, each from its lane's
/// primitive where it is of that kind, and one is chosen per lane.
#[inline(always)]
fn surface_uv<R: Real>(prep: &Prepared, p: V3<R>, hit: impl Fn(usize) -> u32) -> (R, R) {
    let (sp, qs) = (&prep.shapes.spheres, &prep.shapes.quads);
    let of_kind = |k: usize, kind: HitKind| Some(Hit::of(hit(k))).filter(|h| h.kind == kind).map(|h| h.index);
    let sphere = |k: usize| of_kind(k, HitKind::Sphere);
    // Image textures are on static spheres and quads only (`Scene::validate`
    // refuses them on moving spheres and meshes): any other lane reads
    // zeros.
    let quad = |k: usize| of_kind(k, HitKind::Quad).filter(|&i| i < qs.len).map(|i| &qs.rec[i]);
    let is_sphere = R::from_fn(|k| if sphere(k).is_some() { 1.0 } else { 0.0 }).gt(R::splat(0.5));
    let (su, sv) = if sp.len > 0 {
        let at = |a: &[f32], dflt: f32| R::from_fn(|k| sphere(k).map_or(dflt, |i| a[i]));
        let c = V3::new(at(&sp.cx, 0.0), at(&sp.cy, 0.0), at(&sp.cz, 0.0));
        sphere_uv((p - c) * (R::splat(1.0) / at(&sp.r, 1.0)))
    } else {
        (R::splat(0.0), R::splat(0.0))
    };
    let (qu, qv) = if qs.len > 0 {
        let v3 = |f: fn(&QuadRec) -> [f32; 3]| {
            let c = |a: usize| R::from_fn(|k| quad(k).map_or(0.0, |q| f(q)[a]));
            V3::new(c(0), c(1), c(2))
        };
        quad_uv(p, v3(|q| q.q), v3(|q| q.u), v3(|q| q.v), v3(|q| q.w))
    } else {
        (R::splat(0.0), R::splat(0.0))
    };
    (R::select(is_sphere, su, qu), R::select(is_sphere, sv, qv))
}
