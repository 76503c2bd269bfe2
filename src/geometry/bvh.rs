//! A bounding volume hierarchy, one per primitive kind: static spheres
//! ([`Bvh`]), the quads that are not a box's face ([`QuadBvh`]), cuboids
//! ([`CuboidBvh`]) and moving spheres ([`MovingBvh`], each sphere's box the
//! union of its boxes at the shutter's two ends). One build and one set of
//! walks, generic over the leaf ([`LeafPrim`]): built with the surface area
//! heuristic (binned, binary), then collapsed to 8-wide nodes with leaves of
//! up to 8 primitives. Quad leaves are sorted into runs of one form of the
//! test. The sections below are written for spheres; every leaf kind keeps
//! the same rule (the leaf test is brute force's, the boxes padded from the
//! scene's extent), and a flat quad's box is thick enough by that padding. The heuristic's costs are those of the walk the tree is
//! built for ([`Walk`], [`SahCost`]): the packet walk and the scalar kernel
//! test one child box and one leaf sphere at a time (small leaves pay), the
//! one-ray walk tests 8 child boxes and 8 leaf spheres at once (`f32x8`; full
//! leaves pay).
//!
//! # Same closest hit as brute force, bit for bit
//!
//! Leaves use the very sphere test of brute force (`sphere_disc`/`sphere_t`),
//! so each sphere's `t` has the same bits; the tree only decides which spheres
//! are tested. The closest hit is the same as long as no box is pruned that
//! holds a sphere whose computed `t` is at most the best so far, and ties go to
//! the lowest sphere index (`t < best || t == best && i < best_i`). Pruning is
//! made conservative with two bounds:
//!
//! * The sphere test decides on rounded values: `f = o - c` is off by up to
//!   `u |f|` per component (u = 2^-24) and the computed hit point `o + t d` lies
//!   within about `8 u (|f| + |r|)` of the true sphere. Every box is therefore
//!   padded by `PAD * D`, where `D` bounds `|f| + |r|` for every ray of the
//!   scene (spheres' extent plus the camera's), `PAD = 2^-19 = 32 u`.
//! * The slab test's own rounding. A face's distance is computed as
//!   `b * (1/d) + (-(o * (1/d)))`, one fused multiply-add where the build has
//!   FMA (two roundings otherwise), with `-(o * (1/d))` computed once per ray
//!   or packet. Against the exact crossing of the face, that is the exact
//!   crossing of a face moved by at most `u |o|` (the rounding of `o * (1/d)`;
//!   without FMA also `u |b|`, the product's), at most `u D` in all, which the
//!   padding covers many times over (the sphere test needs `8 u D` of its
//!   `32 u D`), times a relative error of at most `3 u` (`1/d`, and the
//!   rounding of the sum, and of the product without FMA). So exits are scaled
//!   by `1 + 2 gamma_3` (Ize 2013, "Robust BVH ray traversal") and a box is
//!   pruned only when its entry exceeds `best * (1 + 2^-20)`.

use super::cuboids::{CuboidRec, Cuboids};
use super::intersect::{sphere_disc, sphere_t, Closest};
use super::moving::{centre_at, MovingSpheres, MOVING_BASE};
use super::quads::{next_down, next_up, QuadRec, Quads, QUAD_BASE};
use super::spheres::{Spheres, MISS};
use crate::probe::{Probe, Work, WorkTally};
use crate::real::{Real, Wide, MAX_LANES};
use crate::vec3::V3;
use std::mem::MaybeUninit;
use wide::f32x8;

const PAD: f32 = 1.0 / 524_288.0; // 2^-19
/// 1 + 2 gamma_3 with gamma_3 = 3u / (1 - 3u), rounded up.
const EXIT_SCALE: f32 = 1.0 + 2.0 * (3.0 / 16_777_216.0) * 1.000_001;
/// Prune a box only when its entry is beyond `best * PRUNE_SCALE`.
const PRUNE_SCALE: f32 = 1.0 + 1.0 / 1_048_576.0;
/// Directions components smaller than this are replaced by it (with their
/// sign) in the slab test, so that `0 * inf` never makes a NaN.
const TINY_DIR: f32 = 1e-30;
/// Binary build depth beyond which splits are forced to the median, so the
/// tree stays shallow whatever the scene (and the traversal stack bounded).
const MAX_SAH_DEPTH: usize = 32;
/// Traversal stack: each 8-wide level pushes at most 7 more entries than it
/// pops, and the tree has at most MAX_SAH_DEPTH + 24 levels (2^24 spheres).
const STACK: usize = 7 * (MAX_SAH_DEPTH + 24) + 1;

#[derive(Clone, Copy, Debug)]
struct Aabb {
    min: [f32; 3],
    max: [f32; 3],
}

impl Aabb {
    const EMPTY: Aabb = Aabb { min: [f32::INFINITY; 3], max: [f32::NEG_INFINITY; 3] };
    fn grow(&mut self, o: &Aabb) {
        for a in 0..3 {
            self.min[a] = self.min[a].min(o.min[a]);
            self.max[a] = self.max[a].max(o.max[a]);
        }
    }
    fn area(&self) -> f32 {
        let e: [f32; 3] = std::array::from_fn(|a| (self.max[a] - self.min[a]).max(0.0));
        2.0 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0])
    }
}

/// A node of the 8-wide tree: 8 child boxes in SoA, each an inner node, a
/// leaf (a run of up to 8 spheres in leaf order) or empty. The children fill
/// slots `0..nkids`; the empty slots are the last ones, so a walk that tests
/// one box at a time loops over `nkids` slots and never meets an empty one.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct Node8 {
    min: [[f32; 8]; 3],
    max: [[f32; 8]; 3],
    /// Inner: node index. Leaf: first sphere in leaf order.
    child: [u32; 8],
    /// 0: inner node; 1..=8: leaf with that many spheres; `EMPTY`: no child.
    count: [u8; 8],
    /// Children (non-empty slots, which come first), 1 to 8; 0 for the root of an empty tree.
    nkids: u8,
}

const EMPTY: u8 = u8::MAX;

impl Node8 {
    const EMPTY: Node8 = Node8 { min: [[0.0; 8]; 3], max: [[0.0; 8]; 3], child: [0; 8], count: [EMPTY; 8], nkids: 0 };

    /// The number of children, known to the compiler to be at most 8 (so
    /// indexing the slot arrays below it needs no bounds check).
    #[inline(always)]
    fn kids(&self) -> usize {
        (self.nkids as usize).min(8)
    }
}

/// A leaf's sphere as the one-box-at-a-time walks read it (scalar, packets):
/// everything the sphere test needs in one record, so a leaf is one slice,
/// bounds-checked once.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct LeafSphere {
    c: [f32; 3],
    r2: f32,
    /// The sphere's index in the scene (the tie rule's order).
    index: u32,
}

/// A leaf's quad: its record and its hit index (`QUAD_BASE + i`). A leaf's
/// quads are sorted by the form of their test ([`QuadRec::axis`]: those with
/// a normal along x, y, z, then those upright about x, y, z, then the
/// others), and the first record of each run of one form says how long the
/// run is (`run`), so that the leaf is tested in one loop per run, each with
/// its form of the test ([`LeafPrim::test_leaf`]).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct LeafQuad {
    rec: QuadRec,
    index: u32,
    /// In the first record of a run of quads of one form: the run's length.
    run: u32,
}

/// A leaf's cuboid (its record holds its faces' hit indices).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct LeafCuboid {
    rec: CuboidRec,
}

/// A leaf's moving sphere: its centre at time 0, motion, squared radius and
/// hit index (`MOVING_BASE + i`).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct LeafMoving {
    c0: [f32; 3],
    v: [f32; 3],
    r2: f32,
    index: u32,
}

/// A primitive kind stored in a tree's leaves: its test against a group of
/// rays at times `time` (only moving primitives read it), improving the
/// closest hit (the tie rule is [`Closest::offer`]'s).
pub trait LeafPrim: Copy + std::fmt::Debug {
    fn test<R: Real, P: Probe>(&self, o: V3<R>, d: V3<R>, time: R, best: &mut Closest<R>, probe: &mut P);

    /// The primitives of one leaf, each tested in turn.
    #[inline(always)]
    fn test_leaf<R: Real, P: Probe>(leaf: &[Self], o: V3<R>, d: V3<R>, time: R, best: &mut Closest<R>, probe: &mut P) {
        for s in leaf {
            s.test(o, d, time, best, probe);
        }
    }
}

impl LeafPrim for LeafSphere {
    #[inline(always)]
    fn test<R: Real, P: Probe>(&self, o: V3<R>, d: V3<R>, _time: R, best: &mut Closest<R>, probe: &mut P) {
        let c = V3::new(R::splat(self.c[0]), R::splat(self.c[1]), R::splat(self.c[2]));
        best.test(o, d, c, R::splat(self.r2), self.index, probe);
    }
}

impl LeafPrim for LeafQuad {
    #[inline(always)]
    fn test<R: Real, P: Probe>(&self, o: V3<R>, d: V3<R>, _time: R, best: &mut Closest<R>, probe: &mut P) {
        best.test_quad(o, d, &self.rec, self.index, probe);
    }

    /// The leaf's quads run by run, one loop per run with its form of the
    /// test (with the form chosen per quad, the compiler shares the forms'
    /// common end and moves the closest hit between registers on every test;
    /// with one loop per form, every form costs a leaf its loop's set-up).
    /// The tie rule does not depend on the order of the tests.
    #[inline(always)]
    fn test_leaf<R: Real, P: Probe>(leaf: &[Self], o: V3<R>, d: V3<R>, _time: R, best: &mut Closest<R>, probe: &mut P) {
        let mut rest = leaf;
        while let Some(first) = rest.first() {
            let (run, next) = rest.split_at((first.run as usize).clamp(1, rest.len()));
            debug_assert!(run.iter().all(|q| q.rec.axis == first.rec.axis));
            best.test_quad_run(first.rec.axis, run.iter().map(|q| (&q.rec, q.index)), o, d, probe);
            rest = next;
        }
    }
}

impl LeafPrim for LeafCuboid {
    #[inline(always)]
    fn test<R: Real, P: Probe>(&self, o: V3<R>, d: V3<R>, _time: R, best: &mut Closest<R>, probe: &mut P) {
        best.test_cuboid(o, d, &self.rec, probe);
    }
}

impl LeafPrim for LeafMoving {
    #[inline(always)]
    fn test<R: Real, P: Probe>(&self, o: V3<R>, d: V3<R>, time: R, best: &mut Closest<R>, probe: &mut P) {
        let c = centre_at(V3::splat3(self.c0), V3::splat3(self.v), time);
        best.test(o, d, c, R::splat(self.r2), self.index, probe);
    }
}

/// The tree over a scene's quads (one tree per primitive kind: a
/// sphere-only scene's walks are exactly what they were).
pub type QuadBvh = Bvh<LeafQuad>;

/// The tree over a scene's cuboids.
pub type CuboidBvh = Bvh<LeafCuboid>;

/// The tree over a scene's moving spheres, on their boxes over the shutter
/// interval (traversal ignores time; the leaves test at each ray's time).
pub type MovingBvh = Bvh<LeafMoving>;

/// The tree plus the spheres in leaf order: as records for the walks that
/// test one sphere at a time, and as SoA padded by 8 for whole loads (the
/// one-ray walk's 8-wide leaf test).
#[derive(Clone, Debug)]
pub struct Bvh<L = LeafSphere> {
    nodes: Vec<Node8>,
    leaf: Vec<L>,
    cx: Vec<f32>,
    cy: Vec<f32>,
    cz: Vec<f32>,
    r2: Vec<f32>,
    /// Original sphere index of each leaf-order slot.
    index: Vec<u32>,
}

/// A binary build node (temporary).
struct BNode {
    bounds: Aabb,
    /// Inner: children; leaf: `start..start+count` in the build order.
    left: u32,
    right: u32,
    start: u32,
    count: u32,
}

const BINS: usize = 16;

/// The walk a tree is built for. The two walks pay differently for a node and
/// for a leaf, so the surface area heuristic that shapes the tree weighs them
/// as the walk that uses it does ([`SahCost`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Walk {
    /// One box and one primitive at a time: the wavefront's packets (each
    /// child box, then each sphere of an entered leaf, broadcast against the
    /// packet) and the scalar kernel (one ray).
    OneByOne,
    /// One ray against 8 child boxes, then 8 leaf spheres, per `f32x8` test
    /// (`--accel bvh-ray`).
    Wide8,
}

/// The surface area heuristic's costs, in units of one primitive test of the
/// walk: a binary split costs `inner` plus, for each side, the probability
/// of entering it (area ratio) times the tests its primitives take.
#[derive(Clone, Copy, Debug)]
pub struct SahCost {
    /// The cost of a binary inner node (its share of the box tests).
    pub inner: f32,
    /// Primitives one test takes: 1 for the one-by-one walks, 8 for `Wide8`.
    /// With more primitive kinds (the next books' quads), a leaf's cost is the
    /// sum over its kinds of the kind's test cost times its tests.
    pub per_test: usize,
}

impl SahCost {
    /// The costs the walk pays, measured (docs/history.md, the instruction
    /// budget's first round: the tree's cost model per walk): for the one-by-one walks a binary inner node costs 3 sphere
    /// tests (a sweep of 1, 2, 3, 4 and 6 gave the packet walk 273, 243, 237,
    /// 239 and 249 traversal instructions per ray on the final scene); for the
    /// 8-wide walk half an 8-wide leaf test, as before.
    pub fn of(walk: Walk) -> SahCost {
        match walk {
            Walk::OneByOne => SahCost { inner: 3.0, per_test: 1 },
            Walk::Wide8 => SahCost { inner: 0.5, per_test: 8 },
        }
    }

    /// The cost of testing `n` primitives.
    #[inline]
    fn leaf(&self, n: usize) -> f32 {
        n.div_ceil(self.per_test) as f32
    }
}

struct Builder<'a> {
    cost: SahCost,
    boxes: &'a [Aabb],
    centroid: Vec<[f32; 3]>,
    order: Vec<u32>,
    nodes: Vec<BNode>,
}

impl Builder<'_> {
    fn bounds(&self, lo: usize, hi: usize) -> Aabb {
        let mut b = Aabb::EMPTY;
        for &i in &self.order[lo..hi] {
            b.grow(&self.boxes[i as usize]);
        }
        b
    }

    /// Builds the subtree over `order[lo..hi]`; returns its node index.
    fn build(&mut self, lo: usize, hi: usize, depth: usize) -> u32 {
        let bounds = self.bounds(lo, hi);
        let n = hi - lo;
        let id = self.nodes.len() as u32;
        self.nodes.push(BNode { bounds, left: 0, right: 0, start: lo as u32, count: n as u32 });
        let leaf_cost = self.cost.leaf(n);
        if n <= 1 {
            return id;
        }
        let mut cb = Aabb::EMPTY;
        for &i in &self.order[lo..hi] {
            let c = self.centroid[i as usize];
            cb.grow(&Aabb { min: c, max: c });
        }
        let mut best: Option<(f32, usize, f32)> = None; // (cost, axis, split position)
        let area = bounds.area().max(f32::MIN_POSITIVE);
        for axis in 0..3 {
            let (lo_c, hi_c) = (cb.min[axis], cb.max[axis]);
            if !(hi_c > lo_c) {
                continue;
            }
            let scale = BINS as f32 / (hi_c - lo_c);
            let bin_of = |c: f32| (((c - lo_c) * scale) as usize).min(BINS - 1);
            let mut bin_box = [Aabb::EMPTY; BINS];
            let mut bin_n = [0usize; BINS];
            for &i in &self.order[lo..hi] {
                let b = bin_of(self.centroid[i as usize][axis]);
                bin_box[b].grow(&self.boxes[i as usize]);
                bin_n[b] += 1;
            }
            for split in 1..BINS {
                let (mut lb, mut rb) = (Aabb::EMPTY, Aabb::EMPTY);
                let (mut ln, mut rn) = (0, 0);
                for b in 0..split {
                    lb.grow(&bin_box[b]);
                    ln += bin_n[b];
                }
                for b in split..BINS {
                    rb.grow(&bin_box[b]);
                    rn += bin_n[b];
                }
                if ln == 0 || rn == 0 {
                    continue;
                }
                let cost = self.cost.inner + (lb.area() * self.cost.leaf(ln) + rb.area() * self.cost.leaf(rn)) / area;
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, lo_c + split as f32 / scale));
                }
            }
        }
        let mid = match best {
            _ if depth >= MAX_SAH_DEPTH && n > 8 => n / 2,
            Some((cost, axis, pos)) if n > 8 || cost < leaf_cost => {
                let cent = &self.centroid;
                let slice = &mut self.order[lo..hi];
                let mut m = 0;
                for k in 0..slice.len() {
                    if cent[slice[k] as usize][axis] < pos {
                        slice.swap(k, m);
                        m += 1;
                    }
                }
                if m == 0 || m == n {
                    n / 2
                } else {
                    m
                }
            }
            // All centroids coincide: split in the middle if too many for a leaf.
            None if n > 8 => n / 2,
            _ => return id,
        };
        let left = self.build(lo, lo + mid, depth + 1);
        let right = self.build(lo + mid, hi, depth + 1);
        let node = &mut self.nodes[id as usize];
        node.left = left;
        node.right = right;
        node.count = 0;
        id
    }
}

/// The binary SAH tree over `boxes` (with centroids `centroid`) for `walk`:
/// its nodes and the primitives' order in its leaves.
fn build_binary(boxes: &[Aabb], centroid: Vec<[f32; 3]>, walk: Walk) -> (Vec<BNode>, Vec<u32>) {
    let n = boxes.len();
    let mut b = Builder { cost: SahCost::of(walk), boxes, centroid, order: (0..n as u32).collect(), nodes: Vec::new() };
    if n > 0 {
        b.build(0, n, 0);
    }
    (b.nodes, b.order)
}

impl Bvh {
    /// Builds the tree for the one-by-one walks (packets, scalar); `extent`
    /// bounds |coordinates| of every ray origin (the camera and its lens),
    /// used to pad the boxes.
    pub fn build(s: &Spheres, extent: f32) -> Bvh {
        Bvh::build_for(s, extent, Walk::OneByOne)
    }

    /// Builds the tree for `walk` (see [`Bvh::build`]).
    pub fn build_for(s: &Spheres, extent: f32, walk: Walk) -> Bvh {
        let n = s.len;
        let mut d = extent.abs();
        for i in 0..n {
            d = d.max(s.cx[i].abs().max(s.cy[i].abs()).max(s.cz[i].abs()) + s.r[i].abs());
        }
        let pad = 2.0 * d * PAD;
        let boxes: Vec<Aabb> = (0..n)
            .map(|i| {
                let c = [s.cx[i], s.cy[i], s.cz[i]];
                let r = s.r[i].abs();
                Aabb { min: c.map(|x| x - r - pad), max: c.map(|x| x + r + pad) }
            })
            .collect();
        let centroid = (0..n).map(|i| [s.cx[i], s.cy[i], s.cz[i]]).collect();
        let (bnodes, order) = build_binary(&boxes, centroid, walk);
        let mut bvh =
            Bvh { nodes: Vec::new(), leaf: vec![], cx: vec![], cy: vec![], cz: vec![], r2: vec![], index: vec![] };
        for &i in &order {
            let i = i as usize;
            bvh.leaf.push(LeafSphere { c: [s.cx[i], s.cy[i], s.cz[i]], r2: s.r2[i], index: i as u32 });
            bvh.cx.push(s.cx[i]);
            bvh.cy.push(s.cy[i]);
            bvh.cz.push(s.cz[i]);
            bvh.r2.push(s.r2[i]);
            bvh.index.push(i as u32);
        }
        for _ in 0..8 {
            bvh.cx.push(0.0);
            bvh.cy.push(0.0);
            bvh.cz.push(0.0);
            bvh.r2.push(-1.0); // never hit
            bvh.index.push(MISS);
        }
        bvh.nodes.push(Node8::EMPTY);
        if n > 0 {
            bvh.collapse(&bnodes, 0, 0);
        }
        bvh
    }
}

impl QuadBvh {
    /// Builds the tree over the quads for the one-by-one walks; `extent`
    /// bounds |coordinates| of every ray origin and every primitive.
    ///
    /// A quad's box covers its four corners widened by the edge tolerance
    /// ([`QuadRec::bounds`]), then padded by `2 * extent * 2^-19` on every
    /// side, as the spheres' boxes are: an axis-aligned quad's box is flat,
    /// and the padding gives it a thickness of `2^-17 extent`, well above
    /// what the quad test's rounding needs (the computed hit point lies within
    /// about `10u extent` of the plane, u = 2^-24) and the slab test's (see
    /// the module's bounds). So a flat box is entered by every ray the quad
    /// test can accept, and brute force and the tree agree bit for bit.
    ///
    /// The tree holds the loose quads ([`Quads::loose`]); the cuboids' faces
    /// are in the cuboids' search.
    pub fn build_quads(q: &Quads, extent: f32) -> QuadBvh {
        let pad = 2.0 * extent.abs() * PAD;
        let boxes: Vec<Aabb> = q
            .loose
            .iter()
            .map(|&i| {
                let (min, max) = q.rec[i as usize].bounds();
                Aabb { min: min.map(|x| x - pad), max: max.map(|x| x + pad) }
            })
            .collect();
        let mut bvh = Bvh::one_by_one(&boxes, |k| {
            let i = q.loose[k];
            LeafQuad { rec: q.rec[i as usize], index: QUAD_BASE + i, run: 0 }
        });
        // Each leaf's quads sorted by form (the general ones last), each
        // run's length in its first record.
        let leaves: Vec<(usize, usize)> = bvh
            .nodes
            .iter()
            .flat_map(|node| {
                (0..node.kids())
                    .filter(|&k| node.count[k] != 0)
                    .map(|k| (node.child[k] as usize, node.count[k] as usize))
            })
            .collect();
        for (start, count) in leaves {
            let leaf = &mut bvh.leaf[start..start + count];
            let order = |axis: u32| if axis == 3 { 7 } else { axis };
            leaf.sort_by_key(|q| order(q.rec.axis));
            let mut start = 0;
            while start < leaf.len() {
                let form = leaf[start].rec.axis;
                let len = leaf[start..].iter().take_while(|q| q.rec.axis == form).count();
                leaf[start].run = len as u32;
                start += len;
            }
        }
        bvh
    }
}

impl CuboidBvh {
    /// Builds the tree over the cuboids for the one-by-one walks. A cuboid's
    /// box is the union of its faces' ([`QuadRec::bounds`]: the four corners
    /// widened by the edge tolerance, rounded outwards), padded as the quads'
    /// are (`2 extent 2^-19` on every side): far more than the distance
    /// between the faces' planes and the slabs' (both rounded once from one
    /// box) and the slab test's rounding, so every ray the cuboid test takes
    /// enters the box, and brute force and the tree agree bit for bit.
    pub fn build_cuboids(c: &Cuboids, q: &Quads, extent: f32) -> CuboidBvh {
        let pad = 2.0 * extent.abs() * PAD;
        let boxes: Vec<Aabb> = c
            .rec
            .iter()
            .map(|r| {
                let mut b = Aabb::EMPTY;
                for face in r.faces.as_flattened() {
                    let (min, max) = q.rec[(face - QUAD_BASE) as usize].bounds();
                    b.grow(&Aabb { min: min.map(|x| x - pad), max: max.map(|x| x + pad) });
                }
                b
            })
            .collect();
        Bvh::one_by_one(&boxes, |i| LeafCuboid { rec: c.rec[i] })
    }
}

impl MovingBvh {
    /// Builds the tree over the moving spheres for the one-by-one walks;
    /// `extent` bounds |coordinates| of every ray origin and every primitive
    /// at every time. A sphere's box is the union of its boxes at `t = 0` and
    /// `t = 1` ([`MovingSpheres::bounds`]), rounded outwards and padded as the
    /// static spheres' are (`2 extent 2^-19` on every side): the centre a
    /// kernel computes, `c0 + t v` in f32, lies within `2u (|c0| + |v|)` of
    /// the exact segment, far inside the padding.
    pub fn build_moving(m: &MovingSpheres, extent: f32) -> MovingBvh {
        let n = m.len();
        let pad = 2.0 * extent.abs() * PAD;
        let boxes: Vec<Aabb> = (0..n)
            .map(|i| {
                let (lo, hi) = m.bounds(i);
                Aabb { min: lo.map(|x| next_down(x) - pad), max: hi.map(|x| next_up(x) + pad) }
            })
            .collect();
        Bvh::one_by_one(&boxes, |i| LeafMoving { c0: m.c0(i), v: m.v(i), r2: m.s.r2[i], index: MOVING_BASE + i as u32 })
    }
}

impl<L: LeafPrim> Bvh<L> {
    /// The tree for the one-by-one walks over primitives whose (padded)
    /// boxes are `boxes`, with leaf record `leaf(i)` for primitive `i`, in
    /// the build's order.
    fn one_by_one(boxes: &[Aabb], leaf: impl Fn(usize) -> L) -> Bvh<L> {
        let centroid = boxes.iter().map(|b| std::array::from_fn(|k| 0.5 * b.min[k] + 0.5 * b.max[k])).collect();
        let (bnodes, order) = build_binary(boxes, centroid, Walk::OneByOne);
        let leaf = order.iter().map(|&i| leaf(i as usize)).collect();
        let mut bvh =
            Bvh { nodes: vec![Node8::EMPTY], leaf, cx: vec![], cy: vec![], cz: vec![], r2: vec![], index: vec![] };
        if !boxes.is_empty() {
            bvh.collapse(&bnodes, 0, 0);
        }
        bvh
    }

    /// Fills node `at` with up to 8 descendants of binary node `root`.
    fn collapse(&mut self, bn: &[BNode], root: u32, at: usize) {
        let mut kids = vec![root];
        if bn[root as usize].count == 0 {
            kids = vec![bn[root as usize].left, bn[root as usize].right];
        }
        // Open the largest inner child until there are 8.
        while kids.len() < 8 {
            let open = kids
                .iter()
                .enumerate()
                .filter(|(_, &k)| bn[k as usize].count == 0)
                .max_by(|a, b| bn[*a.1 as usize].bounds.area().total_cmp(&bn[*b.1 as usize].bounds.area()));
            let Some((pos, &k)) = open else { break };
            kids.swap_remove(pos);
            kids.push(bn[k as usize].left);
            kids.push(bn[k as usize].right);
        }
        self.nodes[at].nkids = kids.len() as u8;
        for (slot, &k) in kids.iter().enumerate() {
            let node = &bn[k as usize];
            for a in 0..3 {
                self.nodes[at].min[a][slot] = node.bounds.min[a];
                self.nodes[at].max[a][slot] = node.bounds.max[a];
            }
            if node.count == 0 {
                let child = self.nodes.len();
                self.nodes.push(Node8::EMPTY);
                self.nodes[at].child[slot] = child as u32;
                self.nodes[at].count[slot] = 0;
                self.collapse(bn, k, child);
            } else {
                self.nodes[at].child[slot] = node.start;
                self.nodes[at].count[slot] = node.count as u8;
            }
        }
    }

    /// The spheres of a leaf (leaf-order slots `start..start + count`), each
    /// broadcast against the rays: the leaf test of the scalar and the packet
    /// walks (the sphere test and the tie rule are [`Closest::test`]'s).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn leaf<R: Real, P: Probe>(
        &self,
        start: usize,
        count: usize,
        o: V3<R>,
        d: V3<R>,
        time: R,
        best: &mut Closest<R>,
        probe: &mut P,
    ) {
        L::test_leaf(&self.leaf[start..start + count], o, d, time, best, probe);
    }

    /// The closest hit of one ray, one box and one sphere at a time (scalar kernel).
    #[inline(always)]
    pub fn closest_hit_scalar<P: Probe>(&self, o: V3<f32>, d: V3<f32>, probe: &mut P) -> (u32, f32) {
        let best = self.walk_scalar(o, d, Closest::<f32>::none(), probe);
        (best.index, best.t)
    }

    /// The scalar walk from `best` (a closest hit found so far, by another
    /// tree, say), returning the improved closest hit.
    #[inline(always)]
    pub fn walk_scalar<P: Probe>(&self, o: V3<f32>, d: V3<f32>, best: Closest<f32>, probe: &mut P) -> Closest<f32> {
        self.walk_scalar_at(o, d, 0.0, best, probe)
    }

    /// [`Bvh::walk_scalar`] for a ray at time `time` (moving primitives' leaves read it).
    #[inline(always)]
    pub fn walk_scalar_at<P: Probe>(
        &self,
        o: V3<f32>,
        d: V3<f32>,
        time: f32,
        best: Closest<f32>,
        probe: &mut P,
    ) -> Closest<f32> {
        self.walk_scalar_impl::<P, false>(o, d, time, best, probe)
    }

    /// Any hit of one ray below `best.t` (a shadow ray's length; `best`
    /// found none yet): the scalar walk, which stops at the first leaf that
    /// holds one (its index is then not `MISS`).
    #[inline(always)]
    pub fn any_hit_scalar_at<P: Probe>(
        &self,
        o: V3<f32>,
        d: V3<f32>,
        time: f32,
        best: Closest<f32>,
        probe: &mut P,
    ) -> Closest<f32> {
        self.walk_scalar_impl::<P, true>(o, d, time, best, probe)
    }

    /// The scalar walk: the closest hit, or (`ANY`) any hit, stopping early.
    #[inline(always)]
    fn walk_scalar_impl<P: Probe, const ANY: bool>(
        &self,
        o: V3<f32>,
        d: V3<f32>,
        time: f32,
        mut best: Closest<f32>,
        probe: &mut P,
    ) -> Closest<f32> {
        let mut tally = WorkTally::<P>::new();
        let (inv, noi) = slab_ray(o, d);
        let mut stack = Stack::new((0, 0.0));
        while let Some((ni, entry)) = stack.pop() {
            if entry > best.t * PRUNE_SCALE {
                continue;
            }
            tally.work(Work::Node, 1);
            let node = &self.nodes[ni as usize];
            for k in 0..node.kids() {
                tally.work(Work::Box, 1);
                let (near, far) = slab(
                    V3::new(node.min[0][k], node.min[1][k], node.min[2][k]),
                    V3::new(node.max[0][k], node.max[1][k], node.max[2][k]),
                    inv,
                    noi,
                    0.0,
                );
                if !(near <= far * EXIT_SCALE && near <= best.t * PRUNE_SCALE) {
                    continue;
                }
                match node.count[k] {
                    0 => stack.push((node.child[k], near)),
                    count => {
                        self.leaf(node.child[k] as usize, count as usize, o, d, time, &mut best, &mut tally);
                        if ANY && best.index != MISS {
                            tally.flush(probe);
                            return best;
                        }
                    }
                }
            }
        }
        tally.flush(probe);
        best
    }

    /// The closest hits of a packet of rays walking the tree together: a child
    /// is entered when any live ray (bit k of `live`) enters its box; a leaf's
    /// spheres are each broadcast against the packet, as in brute force.
    /// Lanes not in `live` return `MISS` with `t = -inf`: starting them at
    /// `best.t = -inf` keeps them out of every box (entries are at least 0)
    /// without a mask per box test.
    #[inline(always)]
    pub fn closest_hit_packet<W: Wide, P: Probe>(&self, o: V3<W>, d: V3<W>, live: u32, probe: &mut P) -> (W::U32, W) {
        let best = self.walk_packet(o, d, Closest::<W>::live(W::mask_from_bits(live)), probe);
        (best.index, best.t)
    }

    /// The packet walk from `best` (lanes at `t = -inf` take no part),
    /// returning the improved closest hit.
    #[inline(always)]
    pub fn walk_packet<W: Wide, P: Probe>(&self, o: V3<W>, d: V3<W>, best: Closest<W>, probe: &mut P) -> Closest<W> {
        self.walk_packet_at(o, d, W::splat(0.0), best, probe)
    }

    /// [`Bvh::walk_packet`] for rays at times `time` (moving primitives' leaves read it).
    #[inline(always)]
    pub fn walk_packet_at<W: Wide, P: Probe>(
        &self,
        o: V3<W>,
        d: V3<W>,
        time: W,
        best: Closest<W>,
        probe: &mut P,
    ) -> Closest<W> {
        self.walk_packet_impl::<W, P, false>(o, d, time, best, probe)
    }

    /// Any hit of each ray of a packet below its `best.t` (shadow rays'
    /// lengths; lanes at `-inf` take no part): the packet walk, in which a
    /// lane that found a hit leaves (its `t` becomes `-inf`, its index is
    /// not `MISS`), and which stops once every lane has left.
    #[inline(always)]
    pub fn any_hit_packet_at<W: Wide, P: Probe>(
        &self,
        o: V3<W>,
        d: V3<W>,
        time: W,
        best: Closest<W>,
        probe: &mut P,
    ) -> Closest<W> {
        self.walk_packet_impl::<W, P, true>(o, d, time, best, probe)
    }

    /// The packet walk: closest hits, or (`ANY`) any hits, stopping early.
    #[inline(always)]
    fn walk_packet_impl<W: Wide, P: Probe, const ANY: bool>(
        &self,
        o: V3<W>,
        d: V3<W>,
        time: W,
        mut best: Closest<W>,
        probe: &mut P,
    ) -> Closest<W> {
        let mut tally = WorkTally::<P>::new();
        let (inv, noi) = slab_ray(o, d);
        let mut stack = Stack::new(0u32);
        // The box loop needs every vector register on AVX2 (16): constants
        // the compiler may rebuild are rebuilt inside it, one instruction
        // each per box test. Opaque, they are kept in memory and read as the
        // operands of the instructions that use them, for free.
        let exit = std::hint::black_box(W::splat(EXIT_SCALE));
        let zero = std::hint::black_box(W::splat(0.0));
        let prune = W::splat(PRUNE_SCALE);
        while let Some(ni) = stack.pop() {
            tally.work(Work::Node, 1);
            let node = &self.nodes[ni as usize];
            let kids = node.kids();
            tally.work(Work::Box, kids as u32);
            for k in 0..kids {
                let bmin = V3::new(node.min[0][k], node.min[1][k], node.min[2][k]);
                let bmax = V3::new(node.max[0][k], node.max[1][k], node.max[2][k]);
                let (near, far) = slab(V3::splat3(bmin.to_array()), V3::splat3(bmax.to_array()), inv, noi, zero);
                let enter = near.le(far * exit) & near.le(best.t * prune);
                if !enter.any() {
                    continue;
                }
                match node.count[k] {
                    0 => stack.push(node.child[k]),
                    count => {
                        self.leaf(node.child[k] as usize, count as usize, o, d, time, &mut best, &mut tally);
                        if ANY && best.leave_found() {
                            tally.flush(probe);
                            return best;
                        }
                    }
                }
            }
        }
        tally.flush(probe);
        best
    }
}

impl Bvh {
    /// The closest hit of one ray: 8 child boxes, or 8 leaf spheres, per `f32x8` test.
    pub fn closest_hit_wide<P: Probe>(&self, o: V3<f32>, d: V3<f32>, probe: &mut P) -> (u32, f32) {
        let mut tally = WorkTally::<P>::new();
        let (inv, noi) = slab_ray(o, d);
        let (o8, d8) = (splat3(o), splat3(d));
        let (inv8, noi8) = (splat3(inv), splat3(noi));
        let mut best = Closest::<f32>::none();
        let mut stack = Stack::new((0, 0.0));
        while let Some((ni, entry)) = stack.pop() {
            if entry > best.t * PRUNE_SCALE {
                continue;
            }
            tally.work(Work::Node, 1);
            tally.work(Work::Box, 8);
            let node = &self.nodes[ni as usize];
            let bmin = V3::new(f32x8::new(node.min[0]), f32x8::new(node.min[1]), f32x8::new(node.min[2]));
            let bmax = V3::new(f32x8::new(node.max[0]), f32x8::new(node.max[1]), f32x8::new(node.max[2]));
            let (near, far) = slab(bmin, bmax, inv8, noi8, f32x8::splat(0.0));
            let ok = near.le(far * f32x8::splat(EXIT_SCALE)) & near.le(f32x8::splat(best.t * PRUNE_SCALE));
            // The empty slots (the last ones) hold zero boxes that a ray may enter.
            let mut mask = ok.to_bitmask() & ((1u32 << node.kids()) - 1);
            let near = near.to_array();
            // Leaves first (they tighten `best.t`), inner nodes pushed far-to-near.
            let mut inner: [(u32, f32); 8] = [(0, 0.0); 8];
            let mut ninner = 0;
            while mask != 0 {
                let k = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                match node.count[k] {
                    0 => {
                        inner[ninner] = (node.child[k], near[k]);
                        ninner += 1;
                    }
                    cnt => self.leaf_wide(node.child[k] as usize, cnt as usize, o8, d8, &mut best, &mut tally),
                }
            }
            inner[..ninner].sort_unstable_by(|a, b| b.1.total_cmp(&a.1));
            for &e in &inner[..ninner] {
                stack.push(e);
            }
        }
        tally.flush(probe);
        (best.index, best.t)
    }

    /// The closest hits of a packet's rays, each walking the tree on its own
    /// with [`Bvh::closest_hit_wide`] (`--accel bvh-ray`). Lanes not in `live` miss.
    pub fn closest_hits_one_by_one<W: Wide, P: Probe>(
        &self,
        o: V3<W>,
        d: V3<W>,
        live: u32,
        probe: &mut P,
    ) -> (W::U32, W) {
        let mut hit = [MISS; MAX_LANES];
        let mut t = [f32::INFINITY; MAX_LANES];
        let mut m = live;
        while m != 0 {
            let k = m.trailing_zeros() as usize;
            m &= m - 1;
            let lane = |v: V3<W>| V3::new(v.x.lane(k), v.y.lane(k), v.z.lane(k));
            (hit[k], t[k]) = self.closest_hit_wide(lane(o), lane(d), probe);
        }
        (W::u_from_fn(|k| hit[k]), W::from_fn(|k| t[k]))
    }

    /// One ray against the up-to-8 spheres of a leaf at once (`f32x8` lanes are
    /// spheres here); hits are offered to `best` in lane order.
    #[inline(always)]
    fn leaf_wide<P: Probe>(
        &self,
        start: usize,
        cnt: usize,
        o: V3<f32x8>,
        d: V3<f32x8>,
        best: &mut Closest<f32>,
        probe: &mut P,
    ) {
        probe.work(Work::Sphere, cnt as u32);
        let ld = |v: &[f32]| f32x8::new(v[start..start + 8].try_into().unwrap());
        let c = V3::new(ld(&self.cx), ld(&self.cy), ld(&self.cz));
        let r2 = ld(&self.r2);
        let (disc, f, b) = sphere_disc(o, d, c, r2);
        let live = (1u32 << cnt) - 1;
        if disc.ge(f32x8::splat(0.0)).to_bitmask() & live == 0 {
            return;
        }
        probe.work(Work::Root, 1);
        let (hit, t) = sphere_t(disc, f, b, r2);
        let mut m = hit.to_bitmask() & live;
        let t = t.to_array();
        while m != 0 {
            let k = m.trailing_zeros() as usize;
            m &= m - 1;
            best.offer(true, t[k], self.index[start + k]);
        }
    }
}

/// The traversal stack (of nodes, or of (node, entry distance)), starting
/// with the root. Uninitialized storage: filling 2 KiB per ray would cost
/// more than the walk.
struct Stack<T: Copy> {
    items: [MaybeUninit<T>; STACK],
    len: usize,
}

impl<T: Copy> Stack<T> {
    #[inline(always)]
    fn new(root: T) -> Self {
        let mut s = Stack { items: [const { MaybeUninit::uninit() }; STACK], len: 1 };
        s.items[0].write(root);
        s
    }
    #[inline(always)]
    fn push(&mut self, e: T) {
        self.items[self.len].write(e);
        self.len += 1;
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: every index below `len` was written by `new` or `push`.
        Some(unsafe { self.items[self.len].assume_init() })
    }
}

#[inline(always)]
fn splat3(v: V3<f32>) -> V3<f32x8> {
    V3::new(f32x8::splat(v.x), f32x8::splat(v.y), f32x8::splat(v.z))
}

/// `1 / x` per lane; components smaller than `TINY_DIR` are replaced by it
/// (with their sign), so the slab test never computes `0 * inf` (the
/// boxes' slab tests and the cuboids', [`super::cuboids`]).
#[inline(always)]
pub(super) fn inv_lanes<R: Real>(x: R) -> R {
    let tiny = R::splat(TINY_DIR);
    R::splat(1.0) / R::select(x.abs().lt(tiny), tiny.copysign(x), x)
}

/// What the slab test needs of the rays `o + t d`: `1/d` (see [`inv_lanes`])
/// and `-(o * (1/d))`.
#[inline(always)]
fn slab_ray<R: Real>(o: V3<R>, d: V3<R>) -> (V3<R>, V3<R>) {
    let inv = V3::new(inv_lanes(d.x), inv_lanes(d.y), inv_lanes(d.z));
    (inv, -o.mul_elem(inv))
}

/// Entry and exit distances of the rays through boxes, entry clamped at
/// `zero` (0, passed in so that a caller can make it opaque), given [`slab_ray`]'s `1/d` and `-(o * (1/d))`: each face's distance is one
/// fused multiply-add (see the module's error bounds).
#[inline(always)]
fn slab<R: Real>(bmin: V3<R>, bmax: V3<R>, inv: V3<R>, noi: V3<R>, zero: R) -> (R, R) {
    let face = |b: R, inv: R, noi: R| b.mul_add_bound(inv, noi);
    let t0 = V3::new(face(bmin.x, inv.x, noi.x), face(bmin.y, inv.y, noi.y), face(bmin.z, inv.z, noi.z));
    let t1 = V3::new(face(bmax.x, inv.x, noi.x), face(bmax.y, inv.y, noi.y), face(bmax.z, inv.z, noi.z));
    // No NaN can arise (|1/d| <= 1e30, finite coordinates) and the test only
    // needs to be conservative, so the one-instruction min/max do.
    let near = t0.x.fast_min(t1.x).fast_max(t0.y.fast_min(t1.y)).fast_max(t0.z.fast_min(t1.z)).fast_max(zero);
    let far = t0.x.fast_max(t1.x).fast_min(t0.y.fast_max(t1.y)).fast_min(t0.z.fast_max(t1.z));
    (near, far)
}
