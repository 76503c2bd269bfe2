//! Constant-density media (The Next Week's `constant_medium`): a convex
//! boundary (a sphere, or a box in its own frame), a density and an albedo.
//!
//! Media are not in the BVH and are not surfaces: after the closest surface
//! hit of a ray is known, [`sample_media`] computes each medium's chord
//! `[t_in, t_out]` analytically, clamps it to `[0, t_best]` and draws a
//! free-flight distance `-ln(1 - u) / density` with `u` from the sampler
//! dimension [`layout::free_flight`]`(depth, k)` (one per bounce and medium).
//! A medium sample strictly nearer than the best hit so far replaces it, with
//! hit index [`MEDIUM_BASE`]` + k`; media are offered in index order, so a
//! tie goes to the surface, then to the lower medium index. The nearest of
//! independent exponential samples is exponential in the sum of the
//! densities, so overlapping media (the book's mist around its subsurface
//! sphere) add up as they should.
//!
//! No random number is drawn inside intersection code, and the draws do not
//! depend on the traversal: every path draws one value per medium per bounce,
//! at fixed dimensions, so the scalar kernel and every lane width agree.
//!
//! The book's pitfalls with media are avoided by construction:
//! both ends of the chord come from one analytic computation, not from a
//! second boundary hit at `t + 0.0001` (a no-op in f32 at t = 5000, inside
//! the book's mist), and a ray that starts inside a medium (the camera in
//! the mist, a ray scattered inside) gets `t_in < 0`, clamped to 0.

use super::hit::MEDIUM_BASE;
use crate::math::ln;
use crate::real::Real;
use crate::sampling::{layout, Stream};
use crate::vec3::V3;

/// A medium's boundary, in f32, as the kernels read it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Boundary {
    /// Centre and squared radius.
    Sphere { c: [f32; 3], r2: f32 },
    /// A box in its own frame: its centre `c` in world space, its unit axes
    /// (world space), and its half sizes along them. The chord is the slab
    /// test of the ray expressed in that frame.
    Box { c: [f32; 3], axes: [[f32; 3]; 3], half: [f32; 3] },
}

/// The media of a scene, structure of arrays (empty for a scene without media,
/// which then runs no medium code).
#[derive(Clone, Debug, Default)]
pub struct Media {
    pub boundary: Vec<Boundary>,
    /// `-1 / density` (rounded once from f64; `-inf` for a density of 0, which
    /// never scatters).
    pub neg_inv_density: Vec<f32>,
    /// The density (shadow rays' transmittance, [`transmittance`]).
    pub density: Vec<f32>,
    pub albedo: Vec<[f32; 3]>,
}

impl Media {
    pub fn len(&self) -> usize {
        self.boundary.len()
    }
    pub fn is_empty(&self) -> bool {
        self.boundary.is_empty()
    }
    /// Adds a medium; a density of `-0.0` is `0.0` (else `-1 / density`
    /// would be `+inf`, a medium that scatters at once).
    pub fn push(&mut self, boundary: Boundary, density: f64, albedo: [f32; 3]) {
        let density = if density == 0.0 { 0.0 } else { density };
        self.boundary.push(boundary);
        self.neg_inv_density.push((-1.0 / density) as f32);
        self.density.push(density as f32);
        self.albedo.push(albedo);
    }
}

/// The chord `(t_in, t_out)` of the line `o + t d` (unit `d`) through a
/// boundary; empty (`t_in >= t_out`, or NaN) when the line misses it.
#[inline(always)]
pub fn chord<R: Real>(b: &Boundary, o: V3<R>, d: V3<R>) -> (R, R) {
    match *b {
        Boundary::Sphere { c, r2 } => {
            // The robust form of the sphere test (`spheres.rs`), both roots.
            let r2 = R::splat(r2);
            let g = V3::splat3(c) - o;
            let b = g.dot(d);
            let l = g - d * b;
            let disc = r2 - l.dot(l);
            let cc = g.dot(g) - r2;
            let q = b + disc.sqrt().copysign(b);
            let t0 = cc / q;
            let hit = disc.ge(R::splat(0.0));
            let (near, far) = (t0.min(q), t0.max(q));
            (R::select(hit, near, R::splat(f32::INFINITY)), R::select(hit, far, R::splat(f32::NEG_INFINITY)))
        }
        Boundary::Box { c, axes, half } => {
            let f = o - V3::splat3(c);
            let mut t_in = R::splat(f32::NEG_INFINITY);
            let mut t_out = R::splat(f32::INFINITY);
            for (a, h) in axes.iter().zip(half) {
                let a = V3::splat3(*a);
                let (ol, dl) = (f.dot(a), d.dot(a));
                let inv = R::splat(1.0) / dl;
                let t1 = (R::splat(-h) - ol) * inv;
                let t2 = (R::splat(h) - ol) * inv;
                t_in = t_in.max(t1.min(t2));
                t_out = t_out.min(t1.max(t2));
            }
            (t_in, t_out)
        }
    }
}

/// The nearest of the surface hit `(index, t)` (`t = inf` for a miss) and one
/// free-flight sample per medium, for rays `o + t d` (unit `d`) of bounce
/// `depth`. Draws one value per medium, at [`layout::free_flight`]`(depth, k)`,
/// whatever the ray meets. One function for the scalar kernel and every width.
#[inline(always)]
pub fn sample_media<R: Real, S: Stream<R>>(
    m: &Media,
    o: V3<R>,
    d: V3<R>,
    mut index: R::U32,
    mut t: R,
    depth: u32,
    rng: &mut S,
) -> (R::U32, R) {
    let zero = R::splat(0.0);
    let one = R::splat(1.0);
    for (k, b) in m.boundary.iter().enumerate() {
        let (t_in, t_out) = chord(b, o, d);
        rng.seek(layout::free_flight(depth, k as u32));
        let u = rng.next();
        // 1 - u is in (0, 1] (u on the 2^-24 grid below 1): exact, never 0.
        let dist = ln(one - u) * R::splat(m.neg_inv_density[k]);
        let tm = t_in.max(zero) + dist;
        let hit = tm.lt(t_out.min(t));
        t = R::select(hit, tm, t);
        index = R::u_select(hit, R::u_splat(MEDIUM_BASE + k as u32), index);
    }
    (index, t)
}

/// The transmittance of the media along the segments `o + t d`, `t` in
/// `[0, tmax]` (unit `d`): `exp(-sum density_k |chord_k clamped to it|)`,
/// the probability that a free flight crosses them, computed exactly
/// instead of drawn (the `nee-mis` estimator's shadow rays: no sampler
/// dimension, no extra noise). One function for every kernel and width.
#[inline(always)]
pub fn transmittance<R: Real>(m: &Media, o: V3<R>, d: V3<R>, tmax: R) -> R {
    let zero = R::splat(0.0);
    let mut depth = zero;
    for (b, &density) in m.boundary.iter().zip(&m.density) {
        let (t_in, t_out) = chord(b, o, d);
        let len = t_out.min(tmax) - t_in.max(zero);
        // A miss (an empty or NaN chord) crosses nothing.
        depth = depth + R::select(len.gt(zero), len, zero) * R::splat(density);
    }
    crate::math::exp_neg(depth)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chords_of_a_sphere_and_a_turned_box() {
        let s = Boundary::Sphere { c: [0.0, 0.0, 10.0], r2: 4.0 };
        let (a, b) = chord::<f32>(&s, V3::new(0.0, 0.0, 0.0), V3::new(0.0, 0.0, 1.0));
        assert_eq!((a, b), (8.0, 12.0));
        let (a, b) = chord::<f32>(&s, V3::new(0.0, 0.0, 10.0), V3::new(0.0, 0.0, 1.0));
        assert_eq!((a, b), (-2.0, 2.0));
        let (a, b) = chord::<f32>(&s, V3::new(0.0, 5.0, 0.0), V3::new(0.0, 0.0, 1.0));
        assert!(a.is_nan() || a >= b, "{a} {b}");
        let (c, s45) = (std::f32::consts::FRAC_1_SQRT_2, std::f32::consts::FRAC_1_SQRT_2);
        let bx = Boundary::Box {
            c: [0.0, 0.0, 0.0],
            axes: [[c, 0.0, -s45], [0.0, 1.0, 0.0], [s45, 0.0, c]],
            half: [1.0; 3],
        };
        // Along the box's diagonal in xz: from -sqrt 2 to sqrt 2 around the centre.
        let (a, b) = chord::<f32>(&bx, V3::new(-10.0, 0.0, 0.0), V3::new(1.0, 0.0, 0.0));
        assert!((a - (10.0 - 2f32.sqrt())).abs() < 1e-5 && (b - (10.0 + 2f32.sqrt())).abs() < 1e-5, "{a} {b}");
    }
}
