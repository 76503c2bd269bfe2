//! The primitive abstraction: what a kind of primitive gives the searches.
//!
//! A kind is stored as structure of arrays in its own file and implements
//! [`Primitive`]: how many primitives a search covers, each one's box for a
//! tree's build, its record in a tree's leaf ([`Leaf`]: the test itself,
//! over [`Real`], so one formula serves the scalar kernel and every lane
//! width), and brute force over all of them. The tree ([`super::bvh`]) and
//! the one aggregate over every kind ([`super::shapes`]) are written once
//! against these two traits.

use super::hit::Closest;
use super::slab::Aabb;
use super::work::{Counter, WorkTally};
use crate::real::Real;
use crate::vec3::V3;

/// One primitive as a tree's leaf stores it: everything its test reads, its
/// hit index included, in one record (a leaf is one slice, bounds-checked
/// once).
pub trait Leaf: Copy + std::fmt::Debug {
    /// The primitive against the rays `o + t d` at times `time` (only moving
    /// primitives read it), improving the closest hit (the tie rule is
    /// [`Closest::offer`]'s).
    fn test<R: Real, C: Counter>(&self, o: V3<R>, d: V3<R>, time: R, best: &mut Closest<R>, counter: &mut C);

    /// The primitives of one leaf, each tested in turn.
    #[inline(always)]
    fn test_leaf<R: Real, C: Counter>(
        leaf: &[Self],
        o: V3<R>,
        d: V3<R>,
        time: R,
        best: &mut Closest<R>,
        counter: &mut C,
    ) {
        for p in leaf {
            p.test(o, d, time, best, counter);
        }
    }

    /// Sorts a leaf after the build (the quads: into runs of one form of
    /// the test). Nothing by default.
    fn arrange(_leaf: &mut [Self]) {}
}

/// A primitive kind as the searches see it.
pub trait Primitive {
    /// What a tree's leaf holds of one primitive.
    type Leaf: Leaf;

    /// The primitives move: their test reads each ray's time, and a scene
    /// without motion skips them at compile time.
    const TIMED: bool = false;

    /// The primitives a search covers (padding excluded).
    fn count(&self) -> usize;

    /// Primitive `k`'s leaf record.
    fn leaf(&self, k: usize) -> Self::Leaf;

    /// Primitive `k`'s box (every hit the test can accept inside it),
    /// padded by `pad` on every side.
    fn bounds(&self, k: usize, pad: f32) -> Aabb;

    /// Where a tree's build sorts primitive `k`: its box's centre by default.
    fn centroid(&self, k: usize, pad: f32) -> [f32; 3] {
        self.bounds(k, pad).centre()
    }

    /// A bound on the coordinates of every ray and primitive, from the
    /// scene's `extent` (which bounds the rays' origins): the boxes are
    /// padded in proportion to it.
    fn extent(&self, extent: f32) -> f32 {
        extent.abs()
    }

    /// Brute force: every primitive against the rays in index order,
    /// improving `best`; with `ANY`, stopping once every lane found a hit
    /// ([`Closest::leave_found`]).
    #[inline(always)]
    fn brute<R: Real, C: Counter, const ANY: bool>(
        &self,
        o: V3<R>,
        d: V3<R>,
        time: R,
        best: &mut Closest<R>,
        counter: &mut C,
    ) {
        brute::<R, C, ANY>(self.count(), best, counter, |k, best, tally| self.leaf(k).test(o, d, time, best, tally));
    }
}

/// The closest hit over one kind alone, by brute force from no hit (tests
/// and tools): `(hit index, t)`, `(MISS, inf)` in the lanes that miss.
#[inline]
pub fn closest_brute<K: Primitive, R: Real, C: Counter>(
    prims: &K,
    o: V3<R>,
    d: V3<R>,
    time: R,
    counter: &mut C,
) -> (R::U32, R) {
    let mut best = Closest::none();
    prims.brute::<R, C, false>(o, d, time, &mut best, counter);
    (best.index, best.t)
}

/// The brute-force loop of the closest-hit searches and (`ANY`) of the
/// any-hit queries: `test(k, ..)` for each of `n` primitives in index
/// order, stopping once every lane found a hit ([`Closest::leave_found`]).
#[inline(always)]
pub fn brute<R: Real, C: Counter, const ANY: bool>(
    n: usize,
    best: &mut Closest<R>,
    counter: &mut C,
    mut test: impl FnMut(usize, &mut Closest<R>, &mut WorkTally<C>),
) {
    let mut tally = WorkTally::<C>::new();
    for k in 0..n {
        test(k, best, &mut tally);
        if ANY && best.leave_found() {
            break;
        }
    }
    tally.flush(counter);
}
