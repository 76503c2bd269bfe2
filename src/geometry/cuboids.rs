//! Cuboids: a scene's boxes (The Next Week's `box(a, b)`, turned and moved
//! by their groups) intersected whole, by one slab test in the box's own
//! frame, instead of face by face.
//!
//! A box is still six quads ([`super::Quads`]): they carry its materials,
//! shading records, light samples and bounds, and a cuboid's hit is the hit
//! index of the face it enters (or, from inside, leaves), so every pass after
//! the closest-hit search reads a quad. Only the search changes: six quad
//! tests (about 40 vector instructions and a divide each, with the closest
//! hit's update) become one test of about 100 and three divides (counted
//! from the source), and a box's faces never compete with each other under
//! the tie rule.
//!
//! # The test
//!
//! The box is its centre `c`, three unit axes `a_k` (world space) and half
//! sizes `h_k`, each rounded once from f64 ([`crate::scene::Flat`] keeps
//! them). For the ray `o + t d`, with `f = o - c`, each axis gives the
//! distances to its two faces, `(-h_k - f.a_k) / d.a_k` and
//! `(h_k - f.a_k) / d.a_k` (the reciprocal computed once, its divisor kept
//! away from 0 as the BVH's slab test keeps it, so no `0 * inf` arises and
//! every distance is finite or infinite, never NaN). The ray enters the box
//! at `t_in`, the largest of the three near distances, and leaves it at
//! `t_out`, the smallest of the far ones. It hits when `t_in <= t_out` and
//! `t_out > 0`: at `t_in` from outside, at `t_out` from inside (a ray
//! refracted into a glass box).
//!
//! * **The face** is that of the axis whose distance is `t_in` (or `t_out`),
//!   the first of x, y, z on a tie (an edge or a corner), on the side the
//!   ray comes from (or goes to). Its hit index is its quad's.
//! * **No leaks at edges.** The faces share their planes' distances: a ray
//!   that enters the box through an edge enters it through one of the two
//!   faces, whatever the rounding. A ray that only touches the box at an edge
//!   (`t_in = t_out` exactly) is a hit; a ray passing within rounding of an
//!   edge outside may miss it, where the quad test's widened edges would take
//!   it: a grazing ray that does not enter the box, either way.
//! * **Axis-aligned boxes** (the book's own `box(a, b)` outside a turned
//!   group: the ground of The Next Week's final scene) skip the axes. The
//!   general form's `1 / d.a_k` does not depend on the box when `a_k` is the
//!   unit axis `e_k`: it is computed once per search (the leaf's setup,
//!   [`Leaf::setup`], with the same operations) instead of once per box and
//!   axis. And `f.a_k` is `f_k` exactly (a product by 1 and sums with
//!   zeros), but for the sign of a zero, which `-h - f.a_k` and `h - f.a_k`
//!   do not keep when `h > 0`: a box takes the aligned form when its axes
//!   are the world's and every half size is positive. So both forms give the
//!   same hits, faces and `t`, bit for bit (`tests/suite/nextweek.rs`
//!   compares them, rays in the faces' planes included).
//! * **Self-hits** are prevented as for every quad, by where a new ray
//!   starts: the face's surface ([`super::quad_surface`]) offsets it by
//!   `32u (|p|_inf + |n.q|)`, far above the difference between the face's
//!   plane and the slab's (both rounded from one f64 box: a few units of
//!   roundoff of `|c| + |h|`) plus the test's rounding of `f.a_k` (about
//!   `3u |f|`). `tests/suite/nextweek.rs` checks it, and the hits against an
//!   f64 oracle.

use super::hit::{Closest, QUAD_BASE};
use super::primitive::{brute, Leaf, Primitive};
use super::quads::Quads;
use super::slab::{inv_lanes, Aabb};
use super::work::{Counter, Work};
use crate::real::{Mask, Real};
use crate::vec3::V3;

/// One box in its own frame, and the hit indices of its faces.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct CuboidRec {
    /// The centre (world space).
    pub c: [f32; 3],
    /// The unit axes (world space).
    pub axes: [[f32; 3]; 3],
    /// The half sizes along the axes.
    pub half: [f32; 3],
    /// The hit index (`QUAD_BASE + i`) of the face at `-half[k]` and at
    /// `+half[k]` along axis `k`.
    pub faces: [[u32; 2]; 3],
    /// The axes are the world's x, y and z, exactly, and every half size is
    /// positive (the test's aligned form; set by [`Cuboids::push`]).
    pub aligned: bool,
}

/// The scene's cuboids, in the order of their first faces.
#[derive(Clone, Debug, Default)]
pub struct Cuboids {
    pub rec: Vec<CuboidRec>,
    /// Some cuboid is axis-aligned: brute force then computes the aligned
    /// form's setup ([`cuboid_setup`]), which the other boxes do not read.
    any_aligned: bool,
    /// Per cuboid, the union of its faces' boxes ([`Cuboids::bound_faces`]).
    faces_box: Vec<Aabb>,
}

impl Cuboids {
    pub fn len(&self) -> usize {
        self.rec.len()
    }
    pub fn is_empty(&self) -> bool {
        self.rec.is_empty()
    }

    /// Appends the box of centre `c`, axes and half sizes (f64, rounded
    /// once), whose faces are the quads `first..first + 6` in the order the
    /// book's `box(a, b)` builds them ([`crate::scene::box_quads`]: front
    /// `+z`, right `+x`, back `-z`, left `-x`, top `+y`, bottom `-y`).
    pub fn push(&mut self, c: [f64; 3], axes: [[f64; 3]; 3], half: [f64; 3], first: u32) {
        let f = |v: [f64; 3]| v.map(|x| x as f32);
        let face = |k: u32| QUAD_BASE + first + k;
        let (axes, half) = (axes.map(f), f(half));
        let aligned = axes == WORLD_AXES && half.iter().all(|&h| h > 0.0);
        self.any_aligned |= aligned;
        self.rec.push(CuboidRec {
            c: f(c),
            axes,
            half,
            faces: [[face(3), face(1)], [face(5), face(4)], [face(2), face(0)]],
            aligned,
        });
    }

    /// Records each cuboid's box for a tree's build: the union of its faces'
    /// ([`super::QuadRec::bounds`]: the four corners widened by the edge
    /// tolerance, rounded outwards), from the quads that hold them.
    pub fn bound_faces(&mut self, q: &Quads) {
        self.faces_box = self
            .rec
            .iter()
            .map(|r| {
                let mut b = Aabb::EMPTY;
                for face in r.faces.as_flattened() {
                    let (min, max) = q.rec[(face - QUAD_BASE) as usize].bounds();
                    b.grow(&Aabb { min, max });
                }
                b
            })
            .collect();
    }
}

/// A cuboid against the rays ([`cuboid_hit_with`], `inv` their
/// [`cuboid_setup`]), improving `best`: its faces' hit indices enter the tie
/// rule as any quad's.
#[inline(always)]
pub fn test_cuboid<R: Real, C: Counter>(
    best: &mut Closest<R>,
    o: V3<R>,
    d: V3<R>,
    inv: &V3<R>,
    b: &CuboidRec,
    counter: &mut C,
) {
    counter.work(Work::Cuboid, 1);
    let (hit, t, index) = cuboid_hit_with(o, d, inv, b);
    best.offer(hit, t, index);
}

/// The world's axes: an aligned box's.
const WORLD_AXES: [[f32; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// What the aligned form of the test reads of the rays, once per search:
/// the general form's `1 / d.a_k` (as [`inv_lanes`] keeps it from 0) for
/// the world's axes, computed as it computes it (the dot product's sign of
/// zero included).
#[inline(always)]
pub fn cuboid_setup<R: Real>(d: V3<R>) -> V3<R> {
    let inv = |k: usize| inv_lanes(d.dot(V3::splat3(WORLD_AXES[k])));
    V3::new(inv(0), inv(1), inv(2))
}

/// A leaf's cuboid (its record holds its faces' hit indices).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct LeafCuboid {
    rec: CuboidRec,
}

impl Leaf for LeafCuboid {
    type Setup<R: Real> = V3<R>;
    type Lanes = ();
    #[inline(always)]
    fn setup<R: Real>(_o: V3<R>, d: V3<R>) -> V3<R> {
        cuboid_setup(d)
    }

    #[inline(always)]
    fn test<R: Real, C: Counter>(
        &self,
        o: V3<R>,
        d: V3<R>,
        _time: R,
        inv: &V3<R>,
        best: &mut Closest<R>,
        counter: &mut C,
    ) {
        test_cuboid(best, o, d, inv, &self.rec, counter);
    }
}

impl Primitive for Cuboids {
    type Leaf = LeafCuboid;

    fn count(&self) -> usize {
        self.rec.len()
    }

    #[inline(always)]
    fn leaf(&self, i: usize) -> LeafCuboid {
        LeafCuboid { rec: self.rec[i] }
    }

    /// The union of its faces' boxes ([`Cuboids::bound_faces`]), padded as
    /// the quads' are: far more than the distance between the faces' planes
    /// and the slabs' (both rounded once from one box) and the slab test's
    /// rounding, so every ray the cuboid test takes enters the box, and
    /// brute force and the tree agree bit for bit.
    fn bounds(&self, i: usize, pad: f32) -> Aabb {
        let b = self.faces_box[i];
        Aabb::padded(b.min, b.max, pad)
    }

    #[inline(always)]
    fn brute<R: Real, C: Counter, const ANY: bool>(
        &self,
        o: V3<R>,
        d: V3<R>,
        _time: R,
        best: &mut Closest<R>,
        counter: &mut C,
    ) {
        // (A few turned boxes, as the Cornell box's two: three divides per
        // search that no box reads were 0.8-1.6% of the box scenes' instructions.)
        let inv = if self.any_aligned { cuboid_setup(d) } else { V3::splat3([0.0; 3]) };
        brute::<R, C, ANY>(self.rec.len(), best, counter, |i, best, tally| {
            test_cuboid(best, o, d, &inv, &self.rec[i], tally)
        });
    }
}

/// The cuboid test: the hit mask, `t` and the hit index of the face, for the
/// rays `o + t d` against `b` (broadcast), as the module describes.
#[inline(always)]
pub fn cuboid_hit<R: Real>(o: V3<R>, d: V3<R>, b: &CuboidRec) -> (R::Mask, R, R::U32) {
    cuboid_hit_with(o, d, &cuboid_setup(d), b)
}

/// [`cuboid_hit`] given the rays' [`cuboid_setup`] (`inv`), which an aligned
/// box reads instead of its axes. The minima and maxima take one
/// instruction each: no distance is NaN, and the sign of a zero distance
/// (which is never a hit) is all they may change.
#[inline(always)]
pub fn cuboid_hit_with<R: Real>(o: V3<R>, d: V3<R>, inv: &V3<R>, b: &CuboidRec) -> (R::Mask, R, R::U32) {
    let f = o - V3::splat3(b.c);
    // Axis `k`'s entry and exit and whether the ray runs along it (then it
    // enters through the `-h` face), from `f.a_k` and `1 / d.a_k`.
    let slab = |k: usize, fa: R, r: R| {
        let h = R::splat(b.half[k]);
        let (t_lo, t_hi) = ((-h - fa) * r, (h - fa) * r);
        (t_lo.fast_min(t_hi), t_lo.fast_max(t_hi), r.gt(R::splat(0.0)))
    };
    if b.aligned {
        return cuboid_faces(b, slab(0, f.x, inv.x), slab(1, f.y, inv.y), slab(2, f.z, inv.z));
    }
    let axis = |k: usize| {
        let a = V3::splat3(b.axes[k]);
        slab(k, f.dot(a), inv_lanes(d.dot(a)))
    };
    cuboid_faces(b, axis(0), axis(1), axis(2))
}

/// The end of the cuboid test, from each axis's entry, exit and direction:
/// the hit, its `t` and its face.
#[inline(always)]
fn cuboid_faces<R: Real>(
    b: &CuboidRec,
    (nx, fx, px): (R, R, R::Mask),
    (ny, fy, py): (R, R, R::Mask),
    (nz, fz, pz): (R, R, R::Mask),
) -> (R::Mask, R, R::U32) {
    let t_in = nx.fast_max(ny).fast_max(nz);
    let t_out = fx.fast_min(fy).fast_min(fz);
    let zero = R::splat(0.0);
    let hit = t_in.le(t_out) & t_out.gt(zero);
    let outside = t_in.gt(zero);
    let u = |k: usize, side: usize| R::u_splat(b.faces[k][side]);
    // Entering: the face on the side the ray comes from.
    let side = |pos: R::Mask, k: usize| R::u_select(pos, u(k, 0), u(k, 1));
    let enter = R::u_select(nx.eq(t_in), side(px, 0), R::u_select(ny.eq(t_in), side(py, 1), side(pz, 2)));
    if (hit & !outside).any() {
        // From inside: the face the ray leaves by, on the side it goes to.
        let side = |pos: R::Mask, k: usize| R::u_select(pos, u(k, 1), u(k, 0));
        let leave = R::u_select(fx.eq(t_out), side(px, 0), R::u_select(fy.eq(t_out), side(py, 1), side(pz, 2)));
        let index = R::u_select(outside, enter, leave);
        return (hit, R::select(outside, t_in, t_out), index);
    }
    (hit, t_in, enter)
}
