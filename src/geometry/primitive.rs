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
use wide::f32x8;

/// One ray as a one-ray walk ([`super::Bvh::walk_one_wide`]) hands it to a
/// leaf: the ray, its [`Leaf::Setup`], and both again splat over 8 lanes
/// (for [`Leaf::test_lanes`]).
pub struct OneRay<L: Leaf> {
    pub o: V3<f32>,
    pub d: V3<f32>,
    pub time: f32,
    pub setup: L::Setup<f32>,
    pub o8: V3<f32x8>,
    pub d8: V3<f32x8>,
    pub setup8: L::Setup<f32x8>,
}

impl<L: Leaf> OneRay<L> {
    #[inline(always)]
    pub fn new(o: V3<f32>, d: V3<f32>, time: f32) -> Self {
        let splat = |v: V3<f32>| V3::new(f32x8::splat(v.x), f32x8::splat(v.y), f32x8::splat(v.z));
        let (o8, d8) = (splat(o), splat(d));
        OneRay { o, d, time, setup: L::setup(o, d), o8, d8, setup8: L::setup(o8, d8) }
    }
}

/// One primitive as a tree's leaf stores it: everything its test reads, its
/// hit index included, in one record (a leaf is one slice, bounds-checked
/// once).
pub trait Leaf: Copy + std::fmt::Debug {
    /// What the test reads of the rays beyond `o`, `d` and `time`, computed
    /// once per search ([`Leaf::setup`]), not once per primitive: the
    /// triangles' projection along each ray; `()` for the other kinds.
    type Setup<R: Real>: Copy;

    /// The rays' [`Leaf::Setup`].
    fn setup<R: Real>(o: V3<R>, d: V3<R>) -> Self::Setup<R>;

    /// The primitive against the rays `o + t d` at times `time` (only moving
    /// primitives read it), improving the closest hit (the tie rule is
    /// [`Closest::offer`]'s).
    fn test<R: Real, C: Counter>(
        &self,
        o: V3<R>,
        d: V3<R>,
        time: R,
        setup: &Self::Setup<R>,
        best: &mut Closest<R>,
        counter: &mut C,
    );

    /// The primitives of one leaf, each tested in turn.
    #[inline(always)]
    fn test_leaf<R: Real, C: Counter>(
        leaf: &[Self],
        o: V3<R>,
        d: V3<R>,
        time: R,
        setup: &Self::Setup<R>,
        best: &mut Closest<R>,
        counter: &mut C,
    ) {
        for p in leaf {
            p.test(o, d, time, setup, best, counter);
        }
    }

    /// A one-ray walk tests a node's leaves nearest first, each only while
    /// its box is entered before the closest hit so far (a leaf that is a
    /// whole search: an instance's mesh); by default in slot order, every
    /// leaf the node test entered.
    const LEAVES_NEAR_TO_FAR: bool = false;

    /// Sorts a leaf after the build (the quads: into runs of one form of
    /// the test). Nothing by default; a kind with [`Leaf::Lanes`] keeps the
    /// build's order ([`super::Bvh::build_lanes_only`] makes its lanes
    /// without leaf records to sort).
    fn arrange(_leaf: &mut [Self]) {}

    /// A tree's leaf records again as lanes (structure of arrays in leaf
    /// order, padded for whole 8-lane loads) for [`Leaf::test_lanes`]; `()`
    /// for a kind whose one-ray walk tests one primitive at a time.
    type Lanes: Clone + std::fmt::Debug + Default;

    /// The lanes of a tree's `len` leaf records, given in leaf order
    /// ([`Leaf::Lanes`]).
    fn lanes(_leaf: impl Iterator<Item = Self>, _len: usize) -> Self::Lanes {
        Self::Lanes::default()
    }

    /// The bytes the lanes hold on the heap (their arrays' capacities).
    fn lanes_bytes(_lanes: &Self::Lanes) -> usize {
        0
    }

    /// One ray against the primitives `start..start + count` of a tree's
    /// leaf records (`lanes` their [`Leaf::Lanes`]), improving `best`: by
    /// default one primitive at a time ([`Leaf::test_leaf`]); a kind with
    /// lanes tests 8 at once (the same bits per primitive). `ANY`: an
    /// any-hit query, which may stop at its first hit below `best.t`.
    #[inline(always)]
    fn test_lanes<C: Counter, const ANY: bool>(
        _lanes: &Self::Lanes,
        leaf: &[Self],
        start: usize,
        count: usize,
        ray: &OneRay<Self>,
        best: &mut Closest<f32>,
        counter: &mut C,
    ) {
        Self::test_leaf(&leaf[start..start + count], ray.o, ray.d, ray.time, &ray.setup, best, counter);
    }
}

/// A primitive kind as the searches see it.
pub trait Primitive {
    /// What a tree's leaf holds of one primitive.
    type Leaf: Leaf;

    /// The kind is searched on the kernels' general path only (`M`: a
    /// scene with moving spheres, whose test reads each ray's time, or with
    /// instanced meshes); a scene without such a kind skips its search at
    /// compile time.
    const GENERAL: bool = false;

    /// The kind's tree is walked one ray at a time, 8 child boxes per test
    /// ([`super::Bvh::walk_one_wide`]), in the packet kernels too: for big
    /// trees under incoherent rays (meshes), where a packet's walk enters
    /// every box any of its rays enters.
    const WALK_ONE_RAY: bool = false;

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
        let setup = Self::Leaf::setup(o, d);
        brute::<R, C, ANY>(self.count(), best, counter, |k, best, tally| {
            self.leaf(k).test(o, d, time, &setup, best, tally)
        });
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
