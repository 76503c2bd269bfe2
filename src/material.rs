//! The materials of each kind (the kernels keep one queue and one pass per
//! kind): book one's lambertian, metal and dielectric, The Next Week's
//! `diffuse_light` (emission, two-sided or one-sided, and the path ends) and
//! `isotropic` (the scattering inside a constant medium); the per-kind
//! material tables (a lambertian's albedo a colour or a texture reference),
//! which a primitive's material handle ([`Kind`] and a row, `crate::handle`)
//! indexes; and the scatter functions, at one lane and every width.
//!
//! Physics as in the book (v4), not the slips of the C# retelling this
//! project grew from (its Lambertian was the normal plus a normalized cube
//! sample): a true
//! Lambertian (normal + uniform unit vector, falling back to the normal when the
//! sum nearly vanishes), metal fuzz from a unit-sphere sample, dielectrics with
//! Snell refraction, total internal reflection and Schlick's reflectance drawn
//! against a uniform random number. All directions leave normalized.

use crate::handle::Kind;
use crate::real::Real;
use crate::sampling::{unit_vector, Stream};
use crate::texture::{TexKind, TexRef};
use crate::vec3::V3;

/// One table per material kind; a primitive's handle, (kind, row), indexes them.
#[derive(Clone, Debug, Default)]
pub struct MaterialTables {
    /// The albedo of a solid lambertian; for a textured one, the colour of
    /// the debug modes' flat shading (the checker's even colour, grey for noise).
    pub lambertian: Vec<[f32; 3]>,
    /// Each lambertian row's texture (`Solid`: the albedo above).
    pub lambertian_tex: Vec<TexRef>,
    /// (albedo, fuzz)
    pub metal: Vec<([f32; 3], f32)>,
    pub dielectric: Vec<f32>,
    /// (emitted radiance, one-sided)
    pub light: Vec<([f32; 3], bool)>,
}

impl MaterialTables {
    /// The colour of chapter 4's flat shading: the albedo, white for glass.
    pub fn flat_colour(&self, kind: Kind, row: u32) -> [f32; 3] {
        match kind {
            Kind::Lambertian => self.lambertian[row as usize],
            Kind::Metal => self.metal[row as usize].0,
            Kind::Dielectric => [1.0, 1.0, 1.0],
            Kind::DiffuseLight => self.light[row as usize].0,
            // No primitive has this kind (media are not shaded in the debug modes).
            Kind::Isotropic => [1.0; 3],
        }
    }

    /// What a shading record holds of material (`kind`, `row`): the albedo
    /// (white for a dielectric, the emitted radiance for a light) and one
    /// parameter (a metal's fuzz, a dielectric's index of refraction, 1 for a
    /// one-sided light, 1 for a textured lambertian, whose albedo a texture
    /// pass writes; 0 otherwise).
    pub fn record(&self, kind: Kind, row: u32) -> ([f32; 3], f32) {
        let row = row as usize;
        match kind {
            Kind::Lambertian => {
                let textured = self.lambertian_tex[row].kind != TexKind::Solid;
                (self.lambertian[row], if textured { 1.0 } else { 0.0 })
            }
            Kind::Metal => self.metal[row],
            Kind::Dielectric => ([1.0; 3], self.dielectric[row]),
            Kind::DiffuseLight => (self.light[row].0, if self.light[row].1 { 1.0 } else { 0.0 }),
            Kind::Isotropic => ([1.0; 3], 0.0),
        }
    }
}

/// Mirror `d` about `n`: `d - 2 (d.n) n`.
#[inline(always)]
pub fn reflect<R: Real>(d: V3<R>, n: V3<R>) -> V3<R> {
    d - n * (R::splat(2.0) * d.dot(n))
}

/// Lambertian: the new direction (cosine distributed about `n`). Draws 2.
#[inline(always)]
pub fn lambertian<R: Real, S: Stream<R>>(n: V3<R>, rng: &mut S) -> V3<R> {
    let s = n + unit_vector(rng);
    let tiny = R::splat(1e-8);
    let near_zero = s.x.abs().lt(tiny) & s.y.abs().lt(tiny) & s.z.abs().lt(tiny);
    V3::select(near_zero, n, s).normalize()
}

/// Metal: the new direction and whether the path survives (a fuzzed direction
/// below the surface is absorbed). Draws 2.
#[inline(always)]
pub fn metal<R: Real, S: Stream<R>>(d: V3<R>, n: V3<R>, fuzz: R, rng: &mut S) -> (V3<R>, R::Mask) {
    let dir = (reflect(d, n) + unit_vector(rng) * fuzz).normalize();
    (dir, dir.dot(n).gt(R::splat(0.0)))
}

/// Dielectric: the new direction (refracted or reflected). Draws 1.
///
/// `front` says the ray enters from outside (ratio 1/ior) or leaves (ior).
/// An ior of exactly 1 is no interface at all: the ray goes straight on
/// (Schlick's approximation would still reflect at grazing angles).
#[inline(always)]
pub fn dielectric<R: Real, S: Stream<R>>(d: V3<R>, n: V3<R>, front: R::Mask, ior: R, rng: &mut S) -> V3<R> {
    let one = R::splat(1.0);
    let ri = R::select(front, one / ior, ior);
    let cos = (-d.dot(n)).min(one);
    let sin = (one - cos * cos).max(R::splat(0.0)).sqrt();
    let cannot_refract = (ri * sin).gt(one);
    let r0 = (one - ri) / (one + ri);
    let r0 = r0 * r0;
    let x = one - cos;
    let x2 = x * x;
    let reflectance = r0 + (one - r0) * (x2 * x2 * x);
    let u = rng.next();
    let do_reflect = cannot_refract | reflectance.gt(u);
    let perp = (d + n * cos) * ri;
    let par = n * -(one - perp.length_squared()).abs().sqrt();
    let refracted = perp + par;
    let dir = V3::select(do_reflect, reflect(d, n), refracted).normalize();
    V3::select(ior.eq(one), d, dir)
}
