//! Spheres as structure-of-arrays, padded to a power of two (at least 8),
//! their shading records, and the ray-sphere test in its numerically robust
//! form, at one lane and every width: the static spheres' primitive kind
//! ([`Primitive`]; moving spheres reuse the test, `moving.rs`).
//!
//! # The sphere test
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
//! `t_min`: see [`surface`] and [`spawn`](super::spawn). Hits must have `t > 0`.
//!
//! # Error bounds
//!
//! `u = 2^-24` (f32 unit roundoff). For one ray and one sphere let `h` be the
//! distance of the centre from the ray's line, `disc = r^2 - h^2`, and
//! `eta = ||d| - 1|` (a few `u` for directions from `normalize`). First-order
//! bounds, term by term (their f64 implementations are `tools::stress::Truth`, which
//! `rtow stress` checks on every ray it traces):
//!
//! * **Discriminant.** The computed `l = f - (f.d) d` is within
//!   `D = (5u + 2 eta)|f| + u h` of the exact perpendicular `f - (f.d^) d^`: `u|f|`
//!   from rounding `f`, `u|f| + u|l|` from the product and the difference, and
//!   `3u|f| + 2 eta |f|` from the dot and from `|d| != 1`; those last two lie
//!   along `d`, orthogonal to `l`, and enter `|l|^2` only squared. Hence
//!   `|disc~ - disc| <= u r^2 + 3u (h + D)^2 + 4u h |f| + 2u h^2 + D^2 + u |disc|`,
//!   which near tangency is about `u (6 r^2 + 4 r |f|) + (5u |f|)^2`. A ray whose
//!   exact `|disc|` exceeds this bound gets the right hit/miss answer; the rays
//!   inside it pass within about `2u |f| + 3u r` (plus the squared term) of
//!   tangency, the rounding band. (The textbook `b^2 - 4ac` errs by ~`8u |f|^2`.)
//! * **Inside or outside.** `c'` is computed within `5u |f|^2 + u r^2 + u |c'|`:
//!   only an origin closer than about `2.5u (|f| + r)` to the surface can be
//!   taken for the wrong side (then the root at `t ~ 0` may be kept or skipped).
//! * **Hit point.** Writing the computed root as an exact root for perturbed
//!   inputs, the point `o + t d` lies within
//!   `(9u + 4 eta)|f| + (7u + 2 eta) r` of the sphere, plus the rounding of `t`
//!   itself: `u (|f| + 2r)` for the root returned as `q`, and
//!   `E / |q| + 3u t` for the root returned as `c' / q`, where
//!   `E = (9u + 6 eta)|f|^2 + 2u r^2 + u|c'| + 2u h |f| + 5u h^2 + u |disc|` is the
//!   inconsistency between `c'` and `b^2 - disc`. For an origin far outside
//!   this is about `21u |f|`: relative to the radius, `21u (|f| / r)`. (A sphere
//!   1e6 radii away is measured hit to 0.22 r; rounding `t` alone costs 0.06 r.)
//!   The bound grows without limit when `|q| -> 0`, i.e. for an origin on the
//!   surface and a tangent direction, where both roots meet at `t = 0` and the
//!   returned `t` is meaningless (`rtow stress` measures such hits up to a few
//!   radii away). Rendering never asks that question: [`spawn`](super::spawn) moves every new
//!   origin off the surface by more than the bound on `c'`.

use super::hit::Closest;
use super::primitive::{Leaf, Primitive};
use super::slab::Aabb;
use super::surface::{Surface, OFFSET_ULPS};
use super::work::{Counter, Work};
use crate::handle::Kind;
use crate::real::{Mask, Real};
use crate::vec3::V3;

#[derive(Clone, Debug, Default)]
pub struct Spheres {
    pub cx: Vec<f32>,
    pub cy: Vec<f32>,
    pub cz: Vec<f32>,
    /// Signed radius (negative: normal flipped inwards).
    pub r: Vec<f32>,
    /// `r * r`; padding has -1, which no ray can hit (disc = -1 - |l|^2 < 0).
    pub r2: Vec<f32>,
    /// The kind of each sphere's material (with `row`, the material's
    /// handle: `crate::handle`).
    pub kind: Vec<Kind>,
    /// The row of each sphere's material in its kind's table.
    pub row: Vec<u32>,
    /// Number of real spheres; the arrays are longer (padding).
    pub len: usize,
    /// Per sphere (padding included), what shading reads: [`Shade`]. Filled
    /// when the scene is laid out for the kernels (`job::prepare`), after
    /// [`Spheres::pad`], once the materials are known; empty before.
    pub shade: Vec<Shade>,
}

/// What shading reads of a hit sphere, in one aligned 32-byte record, so
/// that a packet's records load as one vector each and transpose into lanes
/// ([`crate::real::Wide::gather_rows8`]): the centre, the signed radius and
/// the material's parameters: the albedo (white for a dielectric) and the
/// fuzz of a metal or the index of refraction of a dielectric (0 for a
/// lambertian). The values are copies of the scene's f32s, so shading from
/// them computes what shading from the SoA arrays and the material tables does.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub struct Shade(pub [f32; 8]);

impl Shade {
    pub const CX: usize = 0;
    pub const CY: usize = 1;
    pub const CZ: usize = 2;
    pub const R: usize = 3;
    pub const ALBEDO: usize = 4;
    /// The metal's fuzz, the dielectric's index of refraction.
    pub const PARAM: usize = 7;
}

impl AsRef<[f32; 8]> for Shade {
    #[inline(always)]
    fn as_ref(&self) -> &[f32; 8] {
        &self.0
    }
}

impl Spheres {
    /// Appends a sphere: centre, signed radius, and its material's handle (kind, row).
    pub fn push(&mut self, center: [f32; 3], radius: f32, kind: Kind, row: u32) {
        self.cx.push(center[0]);
        self.cy.push(center[1]);
        self.cz.push(center[2]);
        self.r.push(radius);
        self.r2.push(radius * radius);
        self.kind.push(kind);
        self.row.push(row);
        self.len += 1;
    }

    /// Pads the arrays to a power of two, at least 8, with spheres no ray can
    /// hit: a sphere index masked with `len - 1` is then in bounds by
    /// construction, and for the real spheres' indices the mask changes
    /// nothing (the wavefront's lookups by hit index need no bounds checks).
    pub fn pad(&mut self) {
        let target = self.cx.len().max(8).next_power_of_two();
        while self.cx.len() < target {
            let n = self.len;
            self.push([0.0; 3], 0.0, Kind::Lambertian, 0);
            self.r2[n] = -1.0;
            self.len = n;
        }
    }

    /// One sphere (tests and the stress sweeps).
    pub fn one(center: [f32; 3], radius: f32) -> Spheres {
        let mut s = Spheres::default();
        s.push(center, radius, Kind::Lambertian, 0);
        s.pad();
        s
    }

    /// Moves sphere `i` (tests and the stress sweeps).
    pub fn set(&mut self, i: usize, center: [f32; 3], radius: f32) {
        (self.cx[i], self.cy[i], self.cz[i]) = (center[0], center[1], center[2]);
        self.r[i] = radius;
        self.r2[i] = radius * radius;
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// First half of the sphere test: `(disc, g, b')` with `g = c - o = -f` and
/// `b' = g.d = -b`; the ray misses when `disc < 0`.
///
/// Computed from `g` rather than `f`: rounding is symmetric under negation,
/// so `g`, `b'` and `l' = g - b' d` are exactly `-f`, `-b` and `-l`, the
/// discriminant and the roots are bit for bit those of the `f` form (as the
/// module's bounds state them), and `c - o` takes the centre as the operand
/// that varies (the origin can stay where it is).
#[inline(always)]
pub fn sphere_disc<R: Real>(o: V3<R>, d: V3<R>, c: V3<R>, r2: R) -> (R, V3<R>, R) {
    let g = c - o;
    let b = g.dot(d);
    let l = g - d * b;
    (r2 - l.dot(l), g, b)
}

/// Second half, from [`sphere_disc`]'s `(disc, g, b')`: the nearest root with
/// `t > 0`, given `disc >= 0`; the mask says whether there is one. With
/// `b = -b'`, `q = -(b + sign(b) sqrt(disc)) = b' + sign(b') sqrt(disc)` exactly.
#[inline(always)]
pub fn sphere_t<R: Real>(disc: R, g: V3<R>, b: R, r2: R) -> (R::Mask, R) {
    let c = g.dot(g) - r2;
    let q = b + disc.sqrt().copysign(b);
    let t0 = c / q;
    let near = t0.min(q);
    let far = t0.max(q);
    let zero = R::splat(0.0);
    let t = R::select(near.gt(zero), near, far);
    (disc.ge(zero) & t.gt(zero), t)
}

/// Sphere `index` (centre `c`, squared radius `r2`, both broadcast) against
/// the rays `o + t d`, improving `best`: the leaf test of brute force and of
/// every tree walk (moving spheres' too, at the centre of each lane's time).
/// Most spheres miss every ray: their square root and divide are skipped
/// (one branch per group of rays, not per lane).
#[inline(always)]
pub fn test_sphere<R: Real, C: Counter>(
    best: &mut Closest<R>,
    o: V3<R>,
    d: V3<R>,
    c: V3<R>,
    r2: R,
    index: u32,
    counter: &mut C,
) {
    counter.work(Work::Sphere, 1);
    let (disc, f, b) = sphere_disc(o, d, c, r2);
    if !disc.ge(R::splat(0.0)).any() {
        return;
    }
    counter.work(Work::Root, 1);
    let (hit, t) = sphere_t(disc, f, b, r2);
    best.offer(hit, t, R::u_splat(index));
}

/// A leaf's sphere: everything the sphere test needs in one record.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct LeafSphere {
    c: [f32; 3],
    r2: f32,
    /// The sphere's index in the scene (its hit index: the tie rule's order).
    pub(super) index: u32,
}

impl Leaf for LeafSphere {
    type Setup<R: Real> = ();
    type Lanes = ();
    #[inline(always)]
    fn setup<R: Real>(_o: V3<R>, _d: V3<R>) {}

    #[inline(always)]
    fn test<R: Real, C: Counter>(
        &self,
        o: V3<R>,
        d: V3<R>,
        _time: R,
        _setup: &(),
        best: &mut Closest<R>,
        counter: &mut C,
    ) {
        let c = V3::new(R::splat(self.c[0]), R::splat(self.c[1]), R::splat(self.c[2]));
        test_sphere(best, o, d, c, R::splat(self.r2), self.index, counter);
    }
}

impl Primitive for Spheres {
    type Leaf = LeafSphere;

    fn count(&self) -> usize {
        self.len
    }

    #[inline(always)]
    fn leaf(&self, i: usize) -> LeafSphere {
        LeafSphere { c: [self.cx[i], self.cy[i], self.cz[i]], r2: self.r2[i], index: i as u32 }
    }

    fn bounds(&self, i: usize, pad: f32) -> Aabb {
        let r = self.r[i].abs();
        let c = [self.cx[i], self.cy[i], self.cz[i]];
        Aabb::padded(c.map(|x| x - r), c.map(|x| x + r), pad)
    }

    /// The centre.
    fn centroid(&self, i: usize, _pad: f32) -> [f32; 3] {
        [self.cx[i], self.cy[i], self.cz[i]]
    }

    /// The spheres' own extent too: the largest `|c|_inf + |r|`.
    fn extent(&self, extent: f32) -> f32 {
        (0..self.len).fold(extent.abs(), |d, i| {
            d.max(self.cx[i].abs().max(self.cy[i].abs()).max(self.cz[i].abs()) + self.r[i].abs())
        })
    }
}

/// The surface at distance `t` along `o + t d` on the sphere `(c, r)`.
///
/// The hit point is re-projected onto the sphere, `p = c + |r| n` with
/// `n = normalize(o + t d - c)`, so its distance from the surface is bounded by
/// the rounding of that expression alone, whatever the error of `t`: `|n|` is
/// `1 +- 4.5u` (dot `3u`, halved by the square root, plus the root, the division
/// and the product), the product by `|r|` adds `u`, and the sum with `c` adds
/// `u |p_i|` per component, so `| |p - c| - |r| | <= 5.5u |r| + u |p|_2`.
/// (If `o + t d` rounds onto `c` itself, which happens when the sphere is smaller
/// than the f32 spacing of its coordinates, `n = -d`: the point facing the ray.)
///
/// # The offset
///
/// A new ray starts at `p +- offset n` (see [`spawn`](super::spawn)). Its origin must be on
/// the intended side of the sphere *as the next intersection test sees it*:
/// the test's inside/outside decision (the sign of `c' = |f|^2 - r^2`) errs by
/// at most `5u |f|^2 + u r^2`, i.e. `3u |r|` in distance at `|f| ~ |r|`; the
/// re-projected `p` is off by `5.5u |r| + u |p|_2`; the rounding of `p +- offset n`
/// adds `u |p|_2`. The total is below `8.5u |r| + 2 sqrt(3) u |p|_inf`, so
///
/// `offset = 16u (|r| + |p|_inf)`
///
/// keeps every origin on its side with a margin of 1.9 on the radius term and
/// 4.6 on the position term (it also keeps outgoing grazing rays clear of the
/// rounding band of the discriminant, which needs `offset > 5.5u |r|`). A fixed
/// epsilon fails both at r = 1e-4 and at r = 1e6. `rtow stress` measures it:
/// zero re-hits over spheres of radius 1e-4 .. 1e4 placed 1e-4 .. 1e6 away,
/// still zero at half this offset, entering rays falling short from a quarter,
/// and each term alone failing (docs/stability.md, "Stress tests").
///
/// The rule has a floor: the offset must stay below `|r|`, or a ray entering the
/// sphere may be pushed through it. That holds while `|p|_inf < (1 / 16u - 1) |r|`,
/// about `1e6 |r|`; beyond, the sphere spans fewer than 16 f32 spacings of its own
/// coordinates and no offset can both prevent re-hits (`> 3.5u |p|_inf`) and keep
/// entering rays inside (`< 2|r|`) much longer.
#[inline(always)]
pub fn surface<R: Real>(o: V3<R>, d: V3<R>, t: R, c: V3<R>, r: R) -> Surface<R> {
    let p_ray = o + d * t;
    let v = p_ray - c;
    // `normalize`, with the degenerate case (v rounded to zero) answered by -d.
    let len2 = v.length_squared();
    let out = V3::select(len2.gt(R::splat(0.0)), v * (R::splat(1.0) / len2.sqrt()), -d);
    let p = c + out * r.abs();
    let n_signed = out * R::splat(1.0).copysign(r);
    let front = d.dot(n_signed).lt(R::splat(0.0));
    let n = V3::select(front, n_signed, -n_signed);
    let offset = (r.abs() + p.max_abs()) * R::splat(OFFSET_ULPS);
    Surface { p, n, front, offset }
}
