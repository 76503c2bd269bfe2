//! Ray-sphere intersection in the numerically robust form, for both widths.
//!
//! Rays have unit directions `d`. With `f = o - c`, the hit distances solve
//! `t^2 + 2 b t + c' = 0` with `b = f.d` and `c' = f.f - r^2`. Following Ray
//! Tracing Gems ch. 7 (Haines et al.), the discriminant is computed as
//! `r^2 - |f - b d|^2` instead of `b^2 - c'`: `f - b d` is the offset of the
//! centre from the ray's line, computed with a relative error of a few ulps, so
//! the hit/miss decision is accurate even when `|f| >> r` (the textbook
//! `b^2 - c'` loses all digits when `r / |f| < 2^-12`). The roots are then
//! `q = -(b + sign(b) sqrt(disc))` and `c' / q`, which never subtract nearly
//! equal numbers.
//!
//! Self-intersection is prevented by where a new ray starts, not by a magic
//! `t_min`: see [`surface`] and [`spawn`]. Hits must have `t > 0`.

use super::spheres::{Spheres, MISS};
use crate::real::{Mask, Real};
use crate::vec3::V3;
use wide::{f32x8, u32x8};

/// First half of the sphere test: `(disc, f, b)`; the ray misses when `disc < 0`.
#[inline(always)]
pub fn sphere_disc<R: Real>(o: V3<R>, d: V3<R>, c: V3<R>, r2: R) -> (R, V3<R>, R) {
    let f = o - c;
    let b = f.dot(d);
    let l = f - d * b;
    (r2 - l.dot(l), f, b)
}

/// Second half: the nearest root with `t > 0`, given `disc >= 0`; the mask says
/// whether there is one.
#[inline(always)]
pub fn sphere_t<R: Real>(disc: R, f: V3<R>, b: R, r2: R) -> (R::Mask, R) {
    let c = f.dot(f) - r2;
    let q = -(b + disc.sqrt().copysign(b));
    let t0 = c / q;
    let near = t0.min(q);
    let far = t0.max(q);
    let zero = R::splat(0.0);
    let t = R::select(near.gt(zero), near, far);
    (disc.ge(zero) & t.gt(zero), t)
}

/// The closest hit of one ray against every sphere (brute force), the scalar
/// reference. Ties go to the lowest sphere index. Returns `(MISS, inf)` on a miss.
#[inline]
pub fn closest_hit_scalar(s: &Spheres, o: V3<f32>, d: V3<f32>) -> (u32, f32) {
    let mut best_t = f32::INFINITY;
    let mut best = MISS;
    for i in 0..s.len {
        let c = V3::new(s.cx[i], s.cy[i], s.cz[i]);
        let (disc, f, b) = sphere_disc(o, d, c, s.r2[i]);
        if disc < 0.0 {
            continue;
        }
        let (hit, t) = sphere_t(disc, f, b, s.r2[i]);
        if hit && t < best_t {
            best_t = t;
            best = i as u32;
        }
    }
    (best, best_t)
}

/// The closest hits of 8 rays against every sphere: each sphere is broadcast
/// against the 8 rays. Same formulas and tie rule as [`closest_hit_scalar`],
/// so every lane gets the bits the scalar kernel gets.
#[inline]
pub fn closest_hit_x8(s: &Spheres, o: V3<f32x8>, d: V3<f32x8>) -> (u32x8, f32x8) {
    let mut best_t = f32x8::splat(f32::INFINITY);
    let mut best = u32x8::splat(MISS);
    for i in 0..s.len {
        let c = V3::new(f32x8::splat(s.cx[i]), f32x8::splat(s.cy[i]), f32x8::splat(s.cz[i]));
        let r2 = f32x8::splat(s.r2[i]);
        let (disc, f, b) = sphere_disc(o, d, c, r2);
        // Most spheres miss all 8 rays: skip the sqrt and divide for them
        // (one branch per packet, not per lane).
        let any = disc.ge(f32x8::splat(0.0));
        if !Mask::any(any) {
            continue;
        }
        let (hit, t) = sphere_t(disc, f, b, r2);
        let closer = hit & t.lt(best_t);
        best_t = closer.select(t, best_t);
        let m: u32x8 = bytemuck::cast(closer);
        best = m.select(u32x8::splat(i as u32), best);
    }
    (best, best_t)
}

/// What the shading needs to know about a hit.
#[derive(Clone, Copy, Debug)]
pub struct Surface<R: Real> {
    /// The hit point, re-projected onto the sphere.
    pub p: V3<R>,
    /// Unit normal facing against the ray (the book's `rec.normal`).
    pub n: V3<R>,
    /// The ray hit the outside (the side the signed radius's normal points to).
    pub front: R::Mask,
    /// Distance by which rays leaving `p` start off the surface (see [`spawn`]).
    pub offset: R,
}

/// `2^-20`: sixteen units of roundoff (`u = 2^-24`).
const OFFSET_ULPS: f32 = 1.0 / 1_048_576.0;

/// The surface at distance `t` along `o + t d` on the sphere `(c, r)`.
///
/// The hit point is re-projected onto the sphere, `p = c + |r| n` with
/// `n = normalize(o + t d - c)`, so its distance from the surface is bounded by
/// the rounding of that expression alone, whatever the error of `t`:
/// `| |p - c| - |r| | <= ~4u |r| + u |p|_inf` per component (u = 2^-24), and the
/// next ray's origin, `f = o - c` and `f.f - r^2` add at most a few more `u` of
/// `|r|` and `|p|_inf`. Offsetting new rays by `16 u (|r| + |p|_inf)` along the
/// normal therefore puts them on the intended side of the sphere for any scale
/// (a fixed epsilon fails both at r = 1e-4 and at r = 1e6). `rtow stress` measures it.
#[inline(always)]
pub fn surface<R: Real>(o: V3<R>, d: V3<R>, t: R, c: V3<R>, r: R) -> Surface<R> {
    let p_ray = o + d * t;
    let out = (p_ray - c).normalize();
    let p = c + out * r.abs();
    let n_signed = out * R::splat(1.0).copysign(r);
    let front = d.dot(n_signed).lt(R::splat(0.0));
    let n = V3::select(front, n_signed, -n_signed);
    let offset = (r.abs() + p.max_abs()) * R::splat(OFFSET_ULPS);
    Surface { p, n, front, offset }
}

/// The origin of a new ray leaving `s.p` in direction `dir`: pushed off the
/// surface by `s.offset` to the side `dir` points to.
#[inline(always)]
pub fn spawn<R: Real>(s: &Surface<R>, dir: V3<R>) -> V3<R> {
    let side = dir.dot(s.n).ge(R::splat(0.0));
    let off = R::select(side, s.offset, -s.offset);
    s.p + s.n * off
}
