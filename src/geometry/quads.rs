//! Quads (The Next Week's parallelograms) as structure-of-arrays, their hit
//! test over [`Real`] (one formula for the scalar kernel and every lane
//! width), their surfaces and their shading records.
//!
//! # The hit
//!
//! A quad is the points `Q + a u + b v`, `a, b` in [0, 1], with the plane
//! normal `n = u x v` (not normalized), `D = n.Q` and `w = n / (n.n)` (the
//! book's). A ray `o + t d` meets the plane at `t = (D - n.o) / (n.d)` and
//! the point `p = o + t d` has the book's `a = w.((p - Q) x v)`, `b =
//! w.(u x (p - Q))`. It is a hit when `0 < t < inf` and `a, b` lie in
//! `[-eps, 1 + eps]`, `eps` the rounding band of this ray's test.
//!
//! rtow computes `a` and `b` as one dot product each, of the hit point with a
//! vector fixed per quad, centred and scaled into lengths: `a' = p.Ea - ka`
//! with `Ea = Ha (v x w)`, `ka = Ha (Q.(v x w) + 1/2)` is the signed distance
//! of `p` from the quad's centre line across `a`, `Ha = |u x v| / |v|` the
//! parallelogram's height across `a` (and `b'`, `Eb`, `kb`, `Hb` from `w x
//! u`), all of it computed in f64 when the scene is prepared. The range test
//! is `|a'| - tol <= Ha / 2` and `|b'| - tol <= Hb / 2`: 17 arithmetic
//! instructions from the hit point to the range test instead of 37, and
//! the edge tolerance `tol` ([`QuadRec::tolerance`]) computed per ray from
//! its own distances, never the scene's size.
//!
//! * No epsilon on `n.d`: a ray parallel to the plane has `n.d = 0`, so `t` is
//!   infinite or NaN and fails `0 < t < inf` (the book rejects `|n.d| < 1e-8`,
//!   which also rejects real grazing hits of large quads).
//! * **The tie rule at edges** is inclusive, widened by `tol`, a bound on the
//!   rounding error of `a'` and `b'` ([`QuadRec::tolerance`]): a ray through the edge
//!   shared by two faces of a box is a hit on at least one of them (rounding
//!   cannot open a gap between faces; light does not leak through a box's
//!   edges), and where both faces are hit the closest-hit rule decides
//!   (smaller `t`, then the lower index), as for any two primitives.
//! * Self-hits are prevented the way they are for spheres, by where a new ray
//!   starts ([`quad_surface`]), not by a `t_min`.

use super::hit::{Closest, QUAD_BASE};
use super::primitive::{Leaf, Primitive};
use super::slab::Aabb;
use super::spheres::Shade;
use super::surface::{Surface, OFFSET_ULPS};
use super::work::{Counter, Work, WorkTally};
use crate::handle::Kind;
use crate::real::Real;
use crate::vec3::V3;

/// One quad: first everything the hit test reads (brute force reads the
/// records in scene order, the BVH's leaves in leaf order), then its
/// parallelogram (bounds, texture coordinates, light sampling).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct QuadRec {
    /// `u x v`.
    pub n: [f32; 3],
    /// `n . q`.
    pub d: f32,
    /// `a`'s test: `|p . ea - ka| - tol <= ha` (see the module).
    pub ea: [f32; 3],
    pub ka: f32,
    /// `b`'s test: `|p . eb - kb| - tol <= hb`.
    pub eb: [f32; 3],
    pub kb: f32,
    /// The form of the test ([`quad_hit`]), by the exact zeros of `n`, `ea`
    /// and `eb`, whose terms it skips: `k` (0, 1, 2) when the quad's normal
    /// is along axis `k` (`n`, `ea` and `eb` are 0 in that component and `n`
    /// in the two others); `4 + k` when the quad stands upright about axis
    /// `k` (`n` and `ea` are 0 in component `k`, `eb` in the two others: the
    /// sides of a box turned about `k`); 3 otherwise.
    pub axis: u32,
    /// Half the parallelogram's heights across `a` and `b` (the accepted
    /// `|a'|`, `|b'|` before the tolerance).
    pub ha: f32,
    pub hb: f32,
    /// The tolerance's own term, `TOL (|Q|_inf + |u|_inf + |v|_inf)`
    /// ([`QuadRec::tolerance`]).
    pub kt: f32,
    pub q: [f32; 3],
    pub u: [f32; 3],
    pub v: [f32; 3],
    /// `n / (n . n)`.
    pub w: [f32; 3],
    /// The widest range the test accepts from a ray that starts, and hits,
    /// within the scene's extent (up to its own rounding): `a` in `[lo[0],
    /// hi[0]]`, `b` in `[lo[1], hi[1]]`. For the bounds ([`QuadRec::bounds`]).
    pub lo: [f32; 2],
    pub hi: [f32; 2],
}

/// The edge tolerance per unit of distance: `64u`, `u = 2^-24`.
pub const TOL: f32 = 64.0 / 16_777_216.0;

impl QuadRec {
    /// The edge tolerance, in length across an edge, of the test of a ray
    /// whose origin's largest coordinate is `o_max` (`|o|_inf`) at distance
    /// `t`: `TOL (|o|_inf + t) + kt`, i.e. `64u (|o|_inf + t + |Q|_inf +
    /// |u|_inf + |v|_inf)`.
    ///
    /// It bounds the rounding error of `a'` and `b'` (as lengths) with a
    /// margin of 4 or more for rays that are not grazing: the hit point
    /// `o + t d` is off by about `u (|o| + t)` per component, plus `t`'s own
    /// error, about `4u (|Q| + |o|) / cos` along the ray; `p.Ea - ka` adds
    /// about `3u |p| + u |ka|` (`|Ea| = 1`, `|ka| <~ |Q| + |u| + |v|`). It
    /// follows the ray and the quad: a 1 mm quad seen from nearby has a
    /// band of a few `1e-7`, whatever else the scene holds.
    #[inline(always)]
    pub fn tolerance<R: Real>(&self, o_max: R, t: R) -> R {
        t * R::splat(TOL) + (o_max * R::splat(TOL) + R::splat(self.kt))
    }

    /// The quad's axis-aligned bounds: its four corners widened by the edge
    /// tolerance (so the box covers every point the test can accept).
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let mut min = [f32::INFINITY; 3];
        let mut max = [f32::NEG_INFINITY; 3];
        for a in [self.lo[0] as f64, self.hi[0] as f64] {
            for b in [self.lo[1] as f64, self.hi[1] as f64] {
                for k in 0..3 {
                    let c = self.q[k] as f64 + a * self.u[k] as f64 + b * self.v[k] as f64;
                    // Rounded outwards.
                    min[k] = min[k].min(next_down(c));
                    max[k] = max[k].max(next_up(c));
                }
            }
        }
        (min, max)
    }
}

/// `x` rounded up to f32.
pub(super) fn next_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        f.next_up()
    } else {
        f
    }
}

/// `x` rounded down to f32.
pub(super) fn next_down(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) > x {
        f.next_down()
    } else {
        f
    }
}

/// Quads, structure of arrays, padded to a power of two (at least 8) with
/// quads no ray can hit, so a quad index masked with `len - 1` is in bounds.
/// Quad `i` is hit index `QUAD_BASE + i`.
#[derive(Clone, Debug, Default)]
pub struct Quads {
    pub rec: Vec<QuadRec>,
    /// Each quad's material, as a handle (`crate::handle`): its kind and
    /// row.
    pub kind: Vec<Kind>,
    pub row: Vec<u32>,
    /// The unit normal (`u x v / |u x v|`) and its product with a point of
    /// the plane, per quad, for the surface ([`quad_surface`]), in the
    /// shading record's first four slots.
    pub shade: Vec<Shade>,
    /// Number of real quads (the arrays are longer: padding).
    pub len: usize,
    /// The quads the quad searches test (brute force, the quad tree): all but
    /// the faces of cuboids ([`super::Cuboids`]), which are tested whole.
    pub loose: Vec<u32>,
}

impl Quads {
    /// Appends the quad `(q, u, v)` with its material's handle (`kind`,
    /// `row`); the shading record's material slots are filled by the caller.
    /// `extent` bounds every ray origin and hit point of the scene (for the
    /// bounds' widest band, not the test: [`QuadRec::tolerance`]).
    ///
    /// The test computes `a'` as `p.Ea - ka` (`Ea`, `ka` as the module says,
    /// from the exact `u x v` in f64, rounded once to f32). The f64 oracle's
    /// property test (`tests/suite/nextweek.rs`) checks hits and misses
    /// against it, edges and grazing rays included, from 1e-6 to 1e6.
    pub fn push(&mut self, q: [f32; 3], u: [f32; 3], v: [f32; 3], extent: f32, kind: Kind, row: u32) {
        let d3 = |a: [f32; 3]| glam::DVec3::from_array(a.map(f64::from));
        let (qd, ud, vd) = (d3(q), d3(u), d3(v));
        let nd = ud.cross(vd);
        let n = nd.to_array().map(|x| x as f32);
        let n32 = d3(n);
        let w = (n32 / n32.dot(n32)).to_array().map(|x| x as f32);
        // Heights across a (between the edges along v) and across b.
        let (height_a, height_b) = (nd.length() / vd.length(), nd.length() / ud.length());
        let inf = |a: [f32; 3]| a.iter().fold(0.0f64, |m, x| m.max(x.abs() as f64));
        let own = inf(q) + inf(u) + inf(v);
        let kt = TOL as f64 * own;
        // The widest band: origin and hit point within `extent`, so
        // `t <= 2 sqrt 3 extent`.
        let widest = TOL as f64 * (extent.abs() as f64 * (1.0 + 2.0 * 3f64.sqrt())) + kt;
        let (eps_a, eps_b) = (widest / height_a, widest / height_b);
        // a' = Ha ((p - Q).(v x w) - 1/2), b' = Hb ((p - Q).(w x u) - 1/2),
        // with the exact w: lengths from the centre lines.
        let wd = nd / nd.dot(nd);
        let (ad, bd) = (vd.cross(wd), wd.cross(ud));
        let f32s = |x: glam::DVec3| x.to_array().map(|c| c as f32);
        let mut rec = QuadRec {
            n,
            d: n32.dot(qd) as f32,
            ea: f32s(ad * height_a),
            ka: ((qd.dot(ad) + 0.5) * height_a) as f32,
            eb: f32s(bd * height_b),
            kb: ((qd.dot(bd) + 0.5) * height_b) as f32,
            axis: 3, // set below, from the rounded record
            ha: (0.5 * height_a) as f32,
            hb: (0.5 * height_b) as f32,
            kt: kt as f32,
            q,
            u,
            v,
            w,
            lo: [(-eps_a) as f32, (-eps_b) as f32],
            hi: [(1.0 + eps_a) as f32, (1.0 + eps_b) as f32],
        };
        rec.axis = normal_axis(&rec);
        if rec.axis == 3 {
            if let Some((k, swap)) = upright_axis(&rec) {
                // The test accepts |a| <= 1 and |b| <= 1 alike, and reads `ea`,
                // `ka`, `eb` and `kb` nowhere else: swapped, the edge along
                // axis k is `b`'s.
                if swap {
                    (rec.ea, rec.ka, rec.ha, rec.eb, rec.kb, rec.hb) = (rec.eb, rec.kb, rec.hb, rec.ea, rec.ka, rec.ha);
                }
                rec.axis = 4 + k as u32;
            }
        }
        let unit = nd.normalize();
        let dn = unit.dot(qd);
        let unit = unit.to_array().map(|x| x as f32);
        self.rec.push(rec);
        self.kind.push(kind);
        self.row.push(row);
        self.shade.push(Shade([unit[0], unit[1], unit[2], dn as f32, 0.0, 0.0, 0.0, 0.0]));
        self.loose.push(self.len as u32);
        self.len += 1;
    }

    /// For each `first`, quads `first..first + 6` are a cuboid's faces: the
    /// quad searches leave them to the cuboid's test. (One pass over the
    /// loose quads for all the cuboids: linear in the scene's size.)
    pub fn set_cuboid_faces(&mut self, firsts: impl IntoIterator<Item = u32>) {
        let mut face = vec![false; self.len];
        for first in firsts {
            face[first as usize..first as usize + 6].fill(true);
        }
        self.loose.retain(|&i| !face[i as usize]);
    }

    /// Pads to a power of two, at least 8, with quads no ray can hit (their
    /// `a` test is `|0 - 2| - tol <= -inf`, false for every finite `tol`; at
    /// `t = inf`, `a'` is NaN, see [`quad_hit`]).
    ///
    /// The last step of building: it also sorts the loose quads by the form
    /// of their test (those with a normal along x, y, z, then those upright
    /// about x, y, z, then the others), so that brute force tests them run
    /// by run as a tree's leaf does.
    pub fn pad(&mut self) {
        let rec = &self.rec;
        self.loose.sort_by_key(|i| (form_order(rec[*i as usize].axis), *i));
        let target = self.rec.len().max(8).next_power_of_two();
        while self.rec.len() < target {
            self.rec.push(QuadRec {
                ka: 2.0,
                ha: f32::NEG_INFINITY,
                axis: 1,
                lo: [1.0; 2],
                hi: [0.0; 2],
                n: [0.0, 1.0, 0.0],
                w: [0.0, 1.0, 0.0],
                ..QuadRec::default()
            });
        }
        while self.kind.len() < target {
            self.kind.push(Kind::Lambertian);
            self.row.push(0);
            self.shade.push(Shade::default());
        }
    }

    /// No quad.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// The axis `k` along which `r`'s normal lies, if `n`, `ea` and `eb` are
/// exactly 0 in component `k`'s two others (`n`) and in `k` (`ea`, `eb`);
/// else 3. Exact zeros: a quad whose edges lie in an axis plane (walls, and
/// the tops of boxes turned about y) has them from the exact cross products.
fn normal_axis(r: &QuadRec) -> u32 {
    (0..3)
        .find(|&k| {
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            r.n[i] == 0.0 && r.n[j] == 0.0 && r.n[k] != 0.0 && r.ea[k] == 0.0 && r.eb[k] == 0.0
        })
        .map_or(3, |k| k as u32)
}

/// The axis `k` a quad stands upright about, if `n` is exactly 0 in
/// component `k`, and one of `ea` and `eb` is exactly 0 in `k` and the other
/// exactly 0 in the two others; with `true` when that other is `ea`. (A box
/// turned about y has such sides: their edges are a vertical one, exactly
/// `(0, h, 0)`, and a horizontal one, 0 in y, and the cross products keep
/// those zeros.)
fn upright_axis(r: &QuadRec) -> Option<(usize, bool)> {
    let along = |e: &[f32; 3], k: usize| (0..3).all(|c| (c == k) == (e[c] != 0.0));
    (0..3).filter(|&k| r.n[k] == 0.0).find_map(|k| {
        if r.ea[k] == 0.0 && along(&r.eb, k) {
            Some((k, false))
        } else if r.eb[k] == 0.0 && along(&r.ea, k) {
            Some((k, true))
        } else {
            None
        }
    })
}

/// The quad test: the hit mask and `t` of the rays `o + t d` against `q`
/// (broadcast), as the module describes.
///
/// A hit needs `t > 0` and `|a'| - tol <= ha`, `|b'| - tol <= hb`. `t < inf` needs no test of its
/// own: at `t = inf` every component of `p = o + t d` is infinite or NaN
/// (`d_k t` is `+-inf`, or `0 inf = NaN`), so are `a` and `b` (sums of
/// products with them), and the range test fails; NaN fails every test.
///
/// A quad whose normal lies along an axis ([`QuadRec::axis`]) takes
/// [`quad_hit_axis`], one upright about an axis [`quad_hit_upright`]: each
/// skips the products with the record's zeros and computes the same mask
/// and, where it hits, the same `t`, bit for bit.
#[inline(always)]
pub fn quad_hit<R: Real>(o: V3<R>, d: V3<R>, q: &QuadRec) -> (R::Mask, R) {
    match q.axis {
        0 => quad_hit_axis::<R, 0>(o, d, q),
        1 => quad_hit_axis::<R, 1>(o, d, q),
        2 => quad_hit_axis::<R, 2>(o, d, q),
        4 => quad_hit_upright::<R, 0>(o, d, q),
        5 => quad_hit_upright::<R, 1>(o, d, q),
        6 => quad_hit_upright::<R, 2>(o, d, q),
        _ => quad_hit_general(o, d, q),
    }
}

/// The quad test for any quad: every term of every dot product.
#[inline(always)]
pub fn quad_hit_general<R: Real>(o: V3<R>, d: V3<R>, q: &QuadRec) -> (R::Mask, R) {
    let n = V3::splat3(q.n);
    let t = (R::splat(q.d) - n.dot(o)) / n.dot(d);
    let p = o + d * t;
    // `a` and `b` centred and scaled: the range test is |.| <= 1.
    let a = V3::splat3(q.ea).dot(p) - R::splat(q.ka);
    let b = V3::splat3(q.eb).dot(p) - R::splat(q.kb);
    (in_range(q, o, t, a, b), t)
}

/// A hit's test: `t > 0` and `|a'|, |b'|` within the half heights, widened
/// by this ray's tolerance ([`QuadRec::tolerance`]).
#[inline(always)]
fn in_range<R: Real>(q: &QuadRec, o: V3<R>, t: R, a: R, b: R) -> R::Mask {
    let tol = q.tolerance(o.max_abs(), t);
    t.gt(R::splat(0.0)) & (a.abs() - tol).le(R::splat(q.ha)) & (b.abs() - tol).le(R::splat(q.hb))
}

/// The two axes other than `k`, in order.
const fn others(k: usize) -> (usize, usize) {
    match k {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

/// The quad test for a quad whose normal lies along axis `K`
/// (`q.axis == K`): [`quad_hit_general`] without the products by the zeros.
///
/// The same bits: the dot products sum in the order `(x + y) + z`, and a
/// product by 0 of a finite value is `+-0`, which leaves a sum unchanged (or
/// changes the sign of a zero, which no test sees). So `n.o` is `n_K o_K`,
/// `n.d` is `n_K d_K` and `t` is the same; `a` and `b` are the same sums of
/// the two in-plane terms, in the same order, wherever `p_K` is finite. It
/// is wherever `t` is: `d_K t` is `(D - n_K o_K) / n_K` up to rounding. At
/// `t = +-inf` or NaN both tests miss (see [`quad_hit`]).
/// `tests/suite/nextweek.rs` checks the two against each other.
#[inline(always)]
pub fn quad_hit_axis<R: Real, const K: usize>(o: V3<R>, d: V3<R>, q: &QuadRec) -> (R::Mask, R) {
    let (i, j) = others(K);
    let ray = o;
    let (o, d) = ([o.x, o.y, o.z], [d.x, d.y, d.z]);
    let nk = R::splat(q.n[K]);
    let t = (R::splat(q.d) - nk * o[K]) / (nk * d[K]);
    let (pi, pj) = (o[i] + d[i] * t, o[j] + d[j] * t);
    let a = R::splat(q.ea[i]) * pi + R::splat(q.ea[j]) * pj - R::splat(q.ka);
    let b = R::splat(q.eb[i]) * pi + R::splat(q.eb[j]) * pj - R::splat(q.kb);
    (in_range(q, ray, t, a, b), t)
}

/// The quad test for a quad upright about axis `K` (`q.axis == 4 + K`):
/// [`quad_hit_general`] without the products by the zeros of `n` and `ea`
/// in component `K` and of `eb` in the two others. The same bits, by
/// [`quad_hit_axis`]'s argument: each dot product is the sum of its
/// remaining terms in the general order, and every component of `p` is
/// finite wherever `t` is.
#[inline(always)]
pub fn quad_hit_upright<R: Real, const K: usize>(o: V3<R>, d: V3<R>, q: &QuadRec) -> (R::Mask, R) {
    let (i, j) = others(K);
    let ray = o;
    let (o, d) = ([o.x, o.y, o.z], [d.x, d.y, d.z]);
    let (ni, nj) = (R::splat(q.n[i]), R::splat(q.n[j]));
    let t = (R::splat(q.d) - (ni * o[i] + nj * o[j])) / (ni * d[i] + nj * d[j]);
    let (pi, pj, pk) = (o[i] + d[i] * t, o[j] + d[j] * t, o[K] + d[K] * t);
    let a = R::splat(q.ea[i]) * pi + R::splat(q.ea[j]) * pj - R::splat(q.ka);
    let b = R::splat(q.eb[K]) * pk - R::splat(q.kb);
    (in_range(q, ray, t, a, b), t)
}

/// The surface at distance `t` along `o + t d` on the plane with unit normal
/// `nu` and offset `dn = nu . Q` (a quad's shading record).
///
/// The hit point is re-projected onto the plane, `p = p' - nu (nu.p' - dn)`,
/// so its distance from the plane is bounded by that expression's rounding
/// (about `3u |p|` from the dot and the subtraction, `u |dn|`, `u |p|` from the
/// product and the sum, and `|nu|` off 1 by a few u) whatever the error of
/// `t`. The next test decides the side from the sign of `D - n.o` (with an
/// error of about `3u (|o| + |dn|)` in distance), so a new ray starting at
/// `p +- offset nu` with `offset = 32u (|p|_inf + |dn|)` is on the intended
/// side (a margin above 2 on the `|p|` terms, `|p|_2 <= sqrt 3 |p|_inf`): it
/// cannot hit the quad it leaves.
#[inline(always)]
pub fn quad_surface<R: Real>(o: V3<R>, d: V3<R>, t: R, nu: V3<R>, dn: R) -> Surface<R> {
    let p_ray = o + d * t;
    let p = p_ray - nu * (nu.dot(p_ray) - dn);
    let front = d.dot(nu).lt(R::splat(0.0));
    let n = V3::select(front, nu, -nu);
    let offset = (p.max_abs() + dn.abs()) * R::splat(2.0 * OFFSET_ULPS);
    Surface { p, n, front, offset }
}

/// A run of quads of one form (`form`, their [`QuadRec::axis`]), each given
/// with its hit index, each tested with that form of the test, improving
/// `best`: the leaf test of the quad tree and of brute force. (With the form
/// chosen per quad, the compiler shares the forms' common end and moves the
/// closest hit between registers on every test; with one loop per form,
/// every form costs its loop's set-up.) The tie rule does not depend on the
/// order of the tests.
#[inline(always)]
pub fn test_quad_run<'a, R: Real, C: Counter>(
    best: &mut Closest<R>,
    form: u32,
    run: impl Iterator<Item = (&'a QuadRec, u32)>,
    o: V3<R>,
    d: V3<R>,
    counter: &mut C,
) {
    let mut offer = |(hit, t): (R::Mask, R), index: u32| {
        counter.work(Work::Quad, 1);
        best.offer(hit, t, R::u_splat(index));
    };
    match form {
        0 => run.for_each(|(q, i)| offer(quad_hit_axis::<R, 0>(o, d, q), i)),
        1 => run.for_each(|(q, i)| offer(quad_hit_axis::<R, 1>(o, d, q), i)),
        2 => run.for_each(|(q, i)| offer(quad_hit_axis::<R, 2>(o, d, q), i)),
        4 => run.for_each(|(q, i)| offer(quad_hit_upright::<R, 0>(o, d, q), i)),
        5 => run.for_each(|(q, i)| offer(quad_hit_upright::<R, 1>(o, d, q), i)),
        6 => run.for_each(|(q, i)| offer(quad_hit_upright::<R, 2>(o, d, q), i)),
        _ => run.for_each(|(q, i)| offer(quad_hit_general(o, d, q), i)),
    }
}

/// A leaf's quad: its record and its hit index (`QUAD_BASE + i`). A leaf's
/// quads are sorted by the form of their test ([`QuadRec::axis`]: those with
/// a normal along x, y, z, then those upright about x, y, z, then the
/// others), and the first record of each run of one form says how long the
/// run is (`run`), so that the leaf is tested in one loop per run, each with
/// its form of the test ([`Leaf::test_leaf`]).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct LeafQuad {
    rec: QuadRec,
    index: u32,
    /// In the first record of a run of quads of one form: the run's length.
    run: u32,
}

/// The order of the forms in a leaf and in brute force: the general form last.
fn form_order(axis: u32) -> u32 {
    if axis == 3 {
        7
    } else {
        axis
    }
}

impl Leaf for LeafQuad {
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
        counter.work(Work::Quad, 1);
        let (hit, t) = quad_hit(o, d, &self.rec);
        best.offer(hit, t, R::u_splat(self.index));
    }

    /// The leaf's quads run by run, one loop per run with its form of the
    /// test ([`test_quad_run`]).
    #[inline(always)]
    fn test_leaf<R: Real, C: Counter>(
        leaf: &[Self],
        o: V3<R>,
        d: V3<R>,
        _time: R,
        _setup: &(),
        best: &mut Closest<R>,
        counter: &mut C,
    ) {
        let mut rest = leaf;
        while let Some(first) = rest.first() {
            let (run, next) = rest.split_at((first.run as usize).clamp(1, rest.len()));
            debug_assert!(run.iter().all(|q| q.rec.axis == first.rec.axis));
            test_quad_run(best, first.rec.axis, run.iter().map(|q| (&q.rec, q.index)), o, d, counter);
            rest = next;
        }
    }

    /// Sorted by form (the general ones last), each run's length in its first record.
    fn arrange(leaf: &mut [Self]) {
        leaf.sort_by_key(|q| form_order(q.rec.axis));
        let mut start = 0;
        while start < leaf.len() {
            let form = leaf[start].rec.axis;
            let len = leaf[start..].iter().take_while(|q| q.rec.axis == form).count();
            leaf[start].run = len as u32;
            start += len;
        }
    }
}

/// The loose quads ([`Quads::loose`]): the cuboids' faces are in the
/// cuboids' search.
impl Primitive for Quads {
    type Leaf = LeafQuad;

    fn count(&self) -> usize {
        self.loose.len()
    }

    #[inline(always)]
    fn leaf(&self, k: usize) -> LeafQuad {
        let i = self.loose[k];
        LeafQuad { rec: self.rec[i as usize], index: QUAD_BASE + i, run: 0 }
    }

    /// The four corners widened by the edge tolerance ([`QuadRec::bounds`]),
    /// then padded: an axis-aligned quad's box is flat, and the padding
    /// gives it a thickness of `2^-17 extent`, well above what the quad
    /// test's rounding needs (the computed hit point lies within about
    /// `10u extent` of the plane, u = 2^-24) and the slab test's. So a flat
    /// box is entered by every ray the quad test can accept, and brute force
    /// and the tree agree bit for bit.
    fn bounds(&self, k: usize, pad: f32) -> Aabb {
        let (min, max) = self.rec[self.loose[k] as usize].bounds();
        Aabb::padded(min, max, pad)
    }

    /// Run by run of one form (the loose quads are sorted by form), as a
    /// tree's leaf is tested: a closure per quad, with the form chosen per
    /// quad, was compiled out of line (a call per quad test).
    #[inline(always)]
    fn brute<R: Real, C: Counter, const ANY: bool>(
        &self,
        o: V3<R>,
        d: V3<R>,
        _time: R,
        best: &mut Closest<R>,
        counter: &mut C,
    ) {
        let recs = &self.rec[..self.len];
        let mut tally = WorkTally::<C>::new();
        let mut rest = &self.loose[..];
        while let Some(&first) = rest.first() {
            let form = recs[first as usize].axis;
            let len = rest.iter().take_while(|&&i| recs[i as usize].axis == form).count();
            let (run, next) = rest.split_at(len);
            test_quad_run(best, form, run.iter().map(|&i| (&recs[i as usize], QUAD_BASE + i)), o, d, &mut tally);
            if ANY && best.leave_found() {
                break;
            }
            rest = next;
        }
        tally.flush(counter);
    }
}
