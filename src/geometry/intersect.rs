//! Closest-hit and any-hit searches by brute force for every primitive kind
//! (spheres, quads run by run of one form of the test, cuboids, moving
//! spheres at each lane's time), the closest hit's tie rule ([`Closest`]:
//! the smallest `t`, ties to the lowest hit index, across kinds), the hit
//! surface and where a new ray starts; and the ray-sphere test in its
//! numerically robust form, at one lane and every width. The any-hit forms
//! serve `nee-mis`'s shadow rays. The quad and cuboid tests themselves are
//! in `quads.rs` and `cuboids.rs`; their bounds are stated there.
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
//! `t_min`: see [`surface`] and [`spawn`]. Hits must have `t > 0`.
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
//!   radii away). Rendering never asks that question: [`spawn`] moves every new
//!   origin off the surface by more than the bound on `c'`.

use super::cuboids::{cuboid_hit, CuboidRec, Cuboids};
use super::moving::{centre_at, MovingSpheres, MOVING_BASE};
use super::quads::{quad_hit, quad_hit_axis, quad_hit_general, quad_hit_upright, QuadRec, Quads, QUAD_BASE};
use super::spheres::{Spheres, MISS};
use crate::probe::{Probe, Work, WorkTally};
use crate::real::{Mask, Real};
use crate::vec3::V3;

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

/// The closest hit found so far by a group of rays (one, or a packet), and
/// the rule every traversal uses to replace it: a hit is taken when it is
/// closer, or equally close on a sphere of lower index. With this rule the
/// answer does not depend on the order in which spheres are tested, so brute
/// force and every BVH walk find the same sphere, bit for bit.
#[derive(Clone, Copy, Debug)]
pub struct Closest<R: Real> {
    pub t: R,
    pub index: R::U32,
}

impl<R: Real> Closest<R> {
    #[inline(always)]
    pub fn none() -> Self {
        Closest { t: R::splat(f32::INFINITY), index: R::u_splat(MISS) }
    }

    /// No hit yet in the lanes of `live`; `t = -inf` in the others, which no
    /// hit can improve and no box entry (never below 0) can reach.
    #[inline(always)]
    pub fn live(live: R::Mask) -> Self {
        Closest { t: R::select(live, R::splat(f32::INFINITY), R::splat(f32::NEG_INFINITY)), index: R::u_splat(MISS) }
    }

    /// Any-hit queries: the lanes that found a hit leave the search (their
    /// `t` becomes `-inf`, which no box entry reaches); true once no lane
    /// searches.
    #[inline(always)]
    pub fn leave_found(&mut self) -> bool {
        let found = !R::u_eq(self.index, R::u_splat(MISS));
        self.t = R::select(found, R::splat(f32::NEG_INFINITY), self.t);
        !self.t.gt(R::splat(f32::NEG_INFINITY)).any()
    }

    /// Takes the lanes of `hit` whose `t` beats the current one (ties: lower index).
    #[inline(always)]
    pub fn offer(&mut self, hit: R::Mask, t: R, index: R::U32) {
        let closer = hit & (t.lt(self.t) | (t.eq(self.t) & R::u_lt(index, self.index)));
        self.t = R::select(closer, t, self.t);
        self.index = R::u_select(closer, index, self.index);
    }

    /// Sphere `index` (centre `c`, squared radius `r2`, both broadcast) against
    /// the rays `o + t d`: the leaf test of brute force and of every BVH walk.
    /// Most spheres miss every ray: their square root and divide are skipped
    /// (one branch per group of rays, not per lane).
    #[inline(always)]
    pub fn test<P: Probe>(&mut self, o: V3<R>, d: V3<R>, c: V3<R>, r2: R, index: u32, probe: &mut P) {
        probe.work(Work::Sphere, 1);
        let (disc, f, b) = sphere_disc(o, d, c, r2);
        if !disc.ge(R::splat(0.0)).any() {
            return;
        }
        probe.work(Work::Root, 1);
        let (hit, t) = sphere_t(disc, f, b, r2);
        self.offer(hit, t, R::u_splat(index));
    }
}

impl<R: Real> Closest<R> {
    /// Quad `index` (its hit index, `QUAD_BASE + i`) against the rays: the
    /// leaf test of brute force and of the quad BVH's walks.
    #[inline(always)]
    pub fn test_quad<P: Probe>(&mut self, o: V3<R>, d: V3<R>, q: &QuadRec, index: u32, probe: &mut P) {
        self.offer_quad(quad_hit(o, d, q), index, probe);
    }

    /// Takes the result `(hit, t)` of quad `index`'s test: [`quad_hit`], or
    /// the form of it the quad's [`QuadRec::axis`] names (the quad BVH's
    /// leaves call the forms directly, one loop per run of one form).
    #[inline(always)]
    pub fn offer_quad<P: Probe>(&mut self, (hit, t): (R::Mask, R), index: u32, probe: &mut P) {
        probe.work(Work::Quad, 1);
        self.offer(hit, t, R::u_splat(index));
    }

    /// A run of quads of one form (`form`, their [`QuadRec::axis`]), each
    /// given with its hit index, each tested with that form of the test: the
    /// leaf test of the quad tree and of brute force. (With the form chosen
    /// per quad, the compiler shares the forms' common end and moves the
    /// closest hit between registers on every test; with one loop per form,
    /// every form costs its loop's set-up.) The tie rule does not depend on
    /// the order of the tests.
    #[inline(always)]
    pub fn test_quad_run<'a, P: Probe>(
        &mut self,
        form: u32,
        run: impl Iterator<Item = (&'a QuadRec, u32)>,
        o: V3<R>,
        d: V3<R>,
        probe: &mut P,
    ) {
        match form {
            0 => run.for_each(|(q, i)| self.offer_quad(quad_hit_axis::<R, 0>(o, d, q), i, probe)),
            1 => run.for_each(|(q, i)| self.offer_quad(quad_hit_axis::<R, 1>(o, d, q), i, probe)),
            2 => run.for_each(|(q, i)| self.offer_quad(quad_hit_axis::<R, 2>(o, d, q), i, probe)),
            4 => run.for_each(|(q, i)| self.offer_quad(quad_hit_upright::<R, 0>(o, d, q), i, probe)),
            5 => run.for_each(|(q, i)| self.offer_quad(quad_hit_upright::<R, 1>(o, d, q), i, probe)),
            6 => run.for_each(|(q, i)| self.offer_quad(quad_hit_upright::<R, 2>(o, d, q), i, probe)),
            _ => run.for_each(|(q, i)| self.offer_quad(quad_hit_general(o, d, q), i, probe)),
        }
    }

    /// A cuboid against the rays ([`cuboid_hit`]): its faces' hit indices
    /// enter the tie rule as any quad's.
    #[inline(always)]
    pub fn test_cuboid<P: Probe>(&mut self, o: V3<R>, d: V3<R>, b: &CuboidRec, probe: &mut P) {
        probe.work(Work::Cuboid, 1);
        let (hit, t, index) = cuboid_hit(o, d, b);
        self.offer(hit, t, index);
    }
}

/// Every moving sphere at the rays' times `time` against the rays (brute
/// force), improving `best`: the centre per lane ([`centre_at`]), then the
/// static sphere test.
#[inline]
pub fn closest_moving_hit<R: Real, P: Probe>(
    m: &MovingSpheres,
    o: V3<R>,
    d: V3<R>,
    time: R,
    best: &mut Closest<R>,
    probe: &mut P,
) {
    moving_brute::<R, P, false>(m, o, d, time, best, probe)
}

/// Every quad against the rays (brute force), improving `best`.
#[inline]
pub fn closest_quad_hit<R: Real, P: Probe>(q: &Quads, o: V3<R>, d: V3<R>, best: &mut Closest<R>, probe: &mut P) {
    quads_brute::<R, P, false>(q, o, d, best, probe)
}

/// The brute-force loop of the closest-hit searches and (`ANY`) of the
/// any-hit queries: `test(i, ..)` for each of `n` primitives in index
/// order, stopping once every lane found a hit ([`Closest::leave_found`]).
#[inline(always)]
fn brute<R: Real, P: Probe, const ANY: bool>(
    n: usize,
    best: &mut Closest<R>,
    probe: &mut P,
    mut test: impl FnMut(usize, &mut Closest<R>, &mut WorkTally<P>),
) {
    let mut tally = WorkTally::<P>::new();
    for i in 0..n {
        test(i, best, &mut tally);
        if ANY && best.leave_found() {
            break;
        }
    }
    tally.flush(probe);
}

/// [`brute`] over the static spheres.
#[inline(always)]
fn spheres_brute<R: Real, P: Probe, const ANY: bool>(
    s: &Spheres,
    o: V3<R>,
    d: V3<R>,
    best: &mut Closest<R>,
    probe: &mut P,
) {
    brute::<R, P, ANY>(s.len, best, probe, |i, best, tally| {
        let c = V3::new(R::splat(s.cx[i]), R::splat(s.cy[i]), R::splat(s.cz[i]));
        best.test(o, d, c, R::splat(s.r2[i]), i as u32, tally);
    });
}

/// [`brute`] over the quads.
#[inline(always)]
fn quads_brute<R: Real, P: Probe, const ANY: bool>(
    q: &Quads,
    o: V3<R>,
    d: V3<R>,
    best: &mut Closest<R>,
    probe: &mut P,
) {
    // Run by run of one form (the loose quads are sorted by form), as a
    // tree's leaf is tested: a closure per quad, with the form chosen per
    // quad, was compiled out of line (a call per quad test).
    let recs = &q.rec[..q.len];
    let mut tally = WorkTally::<P>::new();
    let mut rest = &q.loose[..];
    while let Some(&first) = rest.first() {
        let form = recs[first as usize].axis;
        let len = rest.iter().take_while(|&&i| recs[i as usize].axis == form).count();
        let (run, next) = rest.split_at(len);
        best.test_quad_run(form, run.iter().map(|&i| (&recs[i as usize], QUAD_BASE + i)), o, d, &mut tally);
        if ANY && best.leave_found() {
            break;
        }
        rest = next;
    }
    tally.flush(probe);
}

/// [`brute`] over the cuboids.
#[inline(always)]
fn cuboids_brute<R: Real, P: Probe, const ANY: bool>(
    c: &Cuboids,
    o: V3<R>,
    d: V3<R>,
    best: &mut Closest<R>,
    probe: &mut P,
) {
    brute::<R, P, ANY>(c.len(), best, probe, |i, best, tally| best.test_cuboid(o, d, &c.rec[i], tally));
}

/// Every cuboid against the rays (brute force), improving `best`.
#[inline]
pub fn closest_cuboid_hit<R: Real, P: Probe>(c: &Cuboids, o: V3<R>, d: V3<R>, best: &mut Closest<R>, probe: &mut P) {
    cuboids_brute::<R, P, false>(c, o, d, best, probe)
}

/// Any hit of the rays below `best.t` among the cuboids (brute force).
#[inline]
pub fn any_cuboid_hit<R: Real, P: Probe>(c: &Cuboids, o: V3<R>, d: V3<R>, best: &mut Closest<R>, probe: &mut P) {
    cuboids_brute::<R, P, true>(c, o, d, best, probe)
}

/// [`brute`] over the moving spheres at the rays' times.
#[inline(always)]
fn moving_brute<R: Real, P: Probe, const ANY: bool>(
    m: &MovingSpheres,
    o: V3<R>,
    d: V3<R>,
    time: R,
    best: &mut Closest<R>,
    probe: &mut P,
) {
    brute::<R, P, ANY>(m.len(), best, probe, |i, best, tally| {
        let c = centre_at(V3::splat3(m.c0(i)), V3::splat3(m.v(i)), time);
        best.test(o, d, c, R::splat(m.s.r2[i]), MOVING_BASE + i as u32, tally);
    });
}

/// The closest hits of a group of rays (one ray: the scalar kernel; a packet:
/// the wavefront) against every sphere (brute force): each sphere broadcast
/// against the rays. Returns `(MISS, inf)` in lanes that miss.
#[inline]
pub fn closest_hit<R: Real, P: Probe>(s: &Spheres, o: V3<R>, d: V3<R>, probe: &mut P) -> (R::U32, R) {
    let mut best = Closest::none();
    spheres_brute::<R, P, false>(s, o, d, &mut best, probe);
    (best.index, best.t)
}

/// Any hit of the rays below `best.t` (shadow rays) among the spheres
/// (brute force): as [`closest_hit`], stopping once every lane found one.
#[inline]
pub fn any_sphere_hit<R: Real, P: Probe>(s: &Spheres, o: V3<R>, d: V3<R>, best: &mut Closest<R>, probe: &mut P) {
    spheres_brute::<R, P, true>(s, o, d, best, probe)
}

/// Any hit of the rays below `best.t` among the quads (brute force).
#[inline]
pub fn any_quad_hit<R: Real, P: Probe>(q: &Quads, o: V3<R>, d: V3<R>, best: &mut Closest<R>, probe: &mut P) {
    quads_brute::<R, P, true>(q, o, d, best, probe)
}

/// Any hit of the rays below `best.t` among the moving spheres at `time` (brute force).
#[inline]
pub fn any_moving_hit<R: Real, P: Probe>(
    m: &MovingSpheres,
    o: V3<R>,
    d: V3<R>,
    time: R,
    best: &mut Closest<R>,
    probe: &mut P,
) {
    moving_brute::<R, P, true>(m, o, d, time, best, probe)
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
pub const OFFSET_ULPS: f32 = 1.0 / 1_048_576.0;

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
/// A new ray starts at `p +- offset n` (see [`spawn`]). Its origin must be on
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

/// The origin of a new ray leaving `s.p` in direction `dir`: pushed off the
/// surface by `s.offset` to the side `dir` points to.
#[inline(always)]
pub fn spawn<R: Real>(s: &Surface<R>, dir: V3<R>) -> V3<R> {
    let side = dir.dot(s.n).ge(R::splat(0.0));
    let off = R::select(side, s.offset, -s.offset);
    s.p + s.n * off
}
