//! A bounding volume hierarchy over one primitive kind ([`Bvh`], generic
//! over the kind's [`Primitive`] and its [`Leaf`]): built with the surface
//! area heuristic (binned, binary) from the kind's padded boxes, then
//! collapsed to 8-wide nodes with leaves of up to 8 primitives. One walk,
//! written once ([`Bvh::walk`]), serves one ray (the scalar kernel) and
//! packets (the wavefront), closest hit and any hit; what differs between
//! one ray and a packet is [`Walker`]'s. The spheres have a second walk for
//! `--accel bvh-ray`, one ray against 8 child boxes and 8 leaf spheres at
//! once ([`Bvh::closest_hit_wide`]). The sections below are written for
//! spheres; every kind keeps the same rule (the leaf test is brute force's,
//! the boxes padded from the scene's extent), and a flat quad's box is thick
//! enough by that padding. The heuristic's costs are those of the walk the
//! tree is built for ([`Walk`], [`SahCost`]): the packet walk and the scalar
//! kernel test one child box and one leaf primitive at a time (small leaves
//! pay), the one-ray walk tests 8 child boxes and 8 leaf spheres at once
//! (`f32x8`; full leaves pay).
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

use super::hit::{Closest, MISS};
use super::primitive::{Leaf, OneRay, Primitive};
use super::slab::{slab, slab_ray, Aabb, EXIT_SCALE, PAD, PRUNE_SCALE};
use super::spheres::{sphere_disc, sphere_t, LeafSphere, Spheres};
use super::work::{Counter, Work, WorkTally};
use crate::real::{Real, Wide, MAX_LANES};
use crate::vec3::V3;
use std::mem::MaybeUninit;
use wide::f32x8;

/// Binary build depth beyond which splits are forced to the median, so the
/// tree stays shallow whatever the scene (and the traversal stack bounded).
const MAX_SAH_DEPTH: usize = 32;
/// Traversal stack: each 8-wide level pushes at most 7 more entries than it
/// pops, and the tree has at most MAX_SAH_DEPTH + 24 levels (2^24 spheres).
const STACK: usize = 7 * (MAX_SAH_DEPTH + 24) + 1;

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
    /// Bit `k` set where slot `k` is an inner node (`count[k] == 0`): the
    /// one-ray walks part the children a ray enters with one `and`.
    inner: u8,
}

const EMPTY: u8 = u8::MAX;

impl Node8 {
    const EMPTY: Node8 =
        Node8 { min: [[0.0; 8]; 3], max: [[0.0; 8]; 3], child: [0; 8], count: [EMPTY; 8], nkids: 0, inner: 0 };

    /// The number of children, known to the compiler to be at most 8 (so
    /// indexing the slot arrays below it needs no bounds check).
    #[inline(always)]
    fn kids(&self) -> usize {
        (self.nkids as usize).min(8)
    }

    /// One ray (`inv8`, `noi8` its [`slab_ray`] over 8 lanes) against the
    /// node's 8 boxes at once, its closest hit so far at `best`: the leaves
    /// and the inner nodes it enters (bit `k` for slot `k`; pruned as the
    /// module's bounds say) and each box's entry distance.
    #[inline(always)]
    fn enter8(&self, inv8: V3<f32x8>, noi8: V3<f32x8>, best: f32) -> (u32, u32, f32x8) {
        let bmin = V3::new(f32x8::new(self.min[0]), f32x8::new(self.min[1]), f32x8::new(self.min[2]));
        let bmax = V3::new(f32x8::new(self.max[0]), f32x8::new(self.max[1]), f32x8::new(self.max[2]));
        let (near, far) = slab(bmin, bmax, inv8, noi8, f32x8::splat(0.0));
        let ok = near.le(far * f32x8::splat(EXIT_SCALE)) & near.le(f32x8::splat(best * PRUNE_SCALE));
        // The empty slots (the last ones) hold zero boxes that a ray may enter.
        let live = ok.to_bitmask() & ((1u32 << self.kids()) - 1);
        let inner = u32::from(self.inner);
        (live & !inner, live & inner, near)
    }
}

/// The tree over one kind's primitives: its nodes and the primitives'
/// leaf records in leaf order; for spheres also their SoA in leaf order,
/// padded by 8 for whole loads (the one-ray walk's 8-wide leaf test).
#[derive(Clone, Debug)]
pub struct Bvh<L: Leaf> {
    nodes: Vec<Node8>,
    leaf: Vec<L>,
    /// The walk the tree was built for.
    walk: Walk,
    lanes: SphereLanes,
    /// The leaf records as lanes, for one-ray walks ([`Leaf::Lanes`]).
    wide: L::Lanes,
}

/// The spheres of a sphere tree in leaf order, as SoA (empty for other kinds).
#[derive(Clone, Debug, Default)]
struct SphereLanes {
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
    /// One ray against 8 child boxes, each leaf a whole search of its own
    /// (an instance: its mesh's walk), so leaves of one.
    Searches,
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
            // A leaf's test is a walk of many nodes: a split always pays.
            Walk::Searches => SahCost { inner: 0.01, per_test: 1 },
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
    centroid: &'a [[f32; 3]],
    nodes: Vec<BNode>,
}

/// Subtrees of at least this many primitives build their two halves in
/// parallel (each into nodes of its own, adopted after): the same tree,
/// node for node, as one thread builds.
const PARALLEL_BUILD: usize = 1 << 14;

impl<'a> Builder<'a> {
    fn bounds(&self, order: &[u32]) -> Aabb {
        let mut b = Aabb::EMPTY;
        for &i in order {
            b.grow(&self.boxes[i as usize]);
        }
        b
    }

    /// A builder of a subtree, with nodes of its own.
    fn fork(&self) -> Builder<'a> {
        Builder { cost: self.cost, boxes: self.boxes, centroid: self.centroid, nodes: Vec::new() }
    }

    /// Appends a forked builder's nodes (its subtree's root `root`);
    /// returns the root's index here.
    fn adopt(&mut self, nodes: Vec<BNode>, root: u32) -> u32 {
        let offset = self.nodes.len() as u32;
        for mut node in nodes {
            if node.count == 0 {
                node.left += offset;
                node.right += offset;
            }
            self.nodes.push(node);
        }
        root + offset
    }

    /// The binned SAH's cheapest split of `order` (within `bounds`):
    /// `(cost, axis, split position)`, or `None` when every centroid
    /// coincides.
    fn best_split(&self, order: &[u32], bounds: &Aabb) -> Option<(f32, usize, f32)> {
        let mut cb = Aabb::EMPTY;
        for &i in order.iter() {
            let c = self.centroid[i as usize];
            cb.grow(&Aabb { min: c, max: c });
        }
        let mut best: Option<(f32, usize, f32)> = None; // (cost, axis, split position)
        let area = bounds.area().max(f32::MIN_POSITIVE);
        // Every axis binned in one pass over the primitives (each read once).
        let scale: [f32; 3] = std::array::from_fn(|a| BINS as f32 / (cb.max[a] - cb.min[a]));
        let spread: [bool; 3] = std::array::from_fn(|a| cb.max[a] > cb.min[a]);
        let bin_of = |a: usize, c: f32| (((c - cb.min[a]) * scale[a]) as usize).min(BINS - 1);
        let mut bin_box = [[Aabb::EMPTY; BINS]; 3];
        let mut bin_n = [[0usize; BINS]; 3];
        for &i in order.iter() {
            let (c, bx) = (&self.centroid[i as usize], &self.boxes[i as usize]);
            for a in (0..3).filter(|&a| spread[a]) {
                let b = bin_of(a, c[a]);
                bin_box[a][b].grow(bx);
                bin_n[a][b] += 1;
            }
        }
        for axis in (0..3).filter(|&a| spread[a]) {
            let (bin_box, bin_n, scale, lo_c) = (&bin_box[axis], &bin_n[axis], scale[axis], cb.min[axis]);
            // The bins right of each split, swept once from the right (min
            // and max round nothing, so the boxes are the ones a sum of the
            // bins in any order gives), then the left side swept with the splits.
            let mut right = [(Aabb::EMPTY, 0usize); BINS];
            let mut acc = (Aabb::EMPTY, 0);
            for b in (1..BINS).rev() {
                acc.0.grow(&bin_box[b]);
                acc.1 += bin_n[b];
                right[b] = acc;
            }
            let (mut lb, mut ln) = (Aabb::EMPTY, 0);
            for split in 1..BINS {
                lb.grow(&bin_box[split - 1]);
                ln += bin_n[split - 1];
                let (rb, rn) = right[split];
                if ln == 0 || rn == 0 {
                    continue;
                }
                let cost = self.cost.inner + (lb.area() * self.cost.leaf(ln) + rb.area() * self.cost.leaf(rn)) / area;
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, lo_c + split as f32 / scale));
                }
            }
        }
        best
    }

    /// Builds the subtree over `order` (the primitives at `base..base +
    /// order.len()` of the build order); returns its node index.
    fn build(&mut self, order: &mut [u32], base: usize, depth: usize) -> u32 {
        let bounds = self.bounds(order);
        let n = order.len();
        let id = self.nodes.len() as u32;
        self.nodes.push(BNode { bounds, left: 0, right: 0, start: base as u32, count: n as u32 });
        let leaf_cost = self.cost.leaf(n);
        if n <= 1 {
            return id;
        }
        let best = self.best_split(order, &bounds);
        let mid = match best {
            _ if depth >= MAX_SAH_DEPTH && n > 8 => n / 2,
            Some((cost, axis, pos)) if n > 8 || cost < leaf_cost => {
                let cent = self.centroid;
                let slice = &mut *order;
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
        let (a, b) = order.split_at_mut(mid);
        let (left, right) = if n >= PARALLEL_BUILD {
            let (mut lb, mut rb) = (self.fork(), self.fork());
            let (l, r) = rayon::join(|| lb.build(a, base, depth + 1), || rb.build(b, base + mid, depth + 1));
            (self.adopt(lb.nodes, l), self.adopt(rb.nodes, r))
        } else {
            (self.build(a, base, depth + 1), self.build(b, base + mid, depth + 1))
        };
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
    let mut order: Vec<u32> = (0..n as u32).collect();
    let mut b = Builder { cost: SahCost::of(walk), boxes, centroid: &centroid, nodes: Vec::new() };
    if n > 0 {
        b.build(&mut order, 0, 0);
    }
    (b.nodes, order)
}

impl<L: Leaf> Bvh<L> {
    /// Builds the tree over `prims` for `walk`; `extent` bounds
    /// |coordinates| of every ray origin (the camera and its lens), from
    /// which the kind's [`Primitive::extent`] pads the boxes by
    /// `2 extent 2^-19` on every side (see the module's bounds).
    pub fn build<K: Primitive<Leaf = L> + Sync>(prims: &K, extent: f32, walk: Walk) -> Bvh<L> {
        let (mut bvh, order) = Bvh::nodes_of(prims, extent, walk);
        bvh.leaf = order.iter().map(|&k| prims.leaf(k as usize)).collect();
        drop(order);
        for node in 0..bvh.nodes.len() {
            for k in 0..bvh.nodes[node].kids() {
                let (start, count) = (bvh.nodes[node].child[k] as usize, bvh.nodes[node].count[k] as usize);
                if count != 0 {
                    L::arrange(&mut bvh.leaf[start..start + count]);
                }
            }
        }
        bvh.wide = L::lanes(bvh.leaf.iter().copied(), bvh.leaf.len());
        bvh
    }

    /// [`Bvh::build`] for a kind walked one ray at a time from its lanes
    /// alone ([`Primitive::WALK_ONE_RAY`], [`Leaf::Lanes`]): the lanes are
    /// made straight from the primitives in leaf order, and no leaf record
    /// is kept (the meshes' triangles: 56 bytes a triangle fewer, and never
    /// a second copy of them while the tree is built). Such a kind does not
    /// [`Leaf::arrange`]. The tree then serves [`Bvh::walk_one_wide`] alone.
    pub fn build_lanes_only<K: Primitive<Leaf = L> + Sync>(prims: &K, extent: f32, walk: Walk) -> Bvh<L> {
        let (mut bvh, order) = Bvh::nodes_of(prims, extent, walk);
        bvh.wide = L::lanes(order.iter().map(|&k| prims.leaf(k as usize)), order.len());
        bvh
    }

    /// The tree's nodes over `prims` (no leaf records yet) and the
    /// primitives' leaf order. The build's temporaries (boxes, centroids,
    /// the binary tree) are dropped before the leaves are made.
    fn nodes_of<K: Primitive<Leaf = L> + Sync>(prims: &K, extent: f32, walk: Walk) -> (Bvh<L>, Vec<u32>) {
        use rayon::prelude::*;
        let pad = 2.0 * prims.extent(extent) * PAD;
        let n = prims.count();
        let (bnodes, order) = {
            let boxes: Vec<Aabb> = (0..n).into_par_iter().map(|k| prims.bounds(k, pad)).collect();
            let centroid = (0..n).into_par_iter().map(|k| prims.centroid(k, pad)).collect();
            build_binary(&boxes, centroid, walk)
        };
        let mut bvh = Bvh {
            nodes: vec![Node8::EMPTY],
            leaf: Vec::new(),
            walk,
            lanes: SphereLanes::default(),
            wide: L::Lanes::default(),
        };
        if n > 0 {
            bvh.collapse(&bnodes, 0, 0);
        }
        bvh.nodes.shrink_to_fit();
        (bvh, order)
    }

    /// The tree's lanes ([`Leaf::Lanes`]), for a kind whose lanes hold
    /// more than its leaf records (the instances' meshes).
    pub(crate) fn lanes_mut(&mut self) -> &mut L::Lanes {
        &mut self.wide
    }

    /// The bytes the tree holds on the heap (its arrays' capacities): its
    /// nodes, its leaf records and its lanes.
    pub fn heap_bytes(&self) -> usize {
        let l = &self.lanes;
        let sphere_lanes = [&l.cx, &l.cy, &l.cz, &l.r2].iter().map(|a| a.capacity() * 4).sum::<usize>();
        self.nodes.capacity() * std::mem::size_of::<Node8>()
            + self.leaf.capacity() * std::mem::size_of::<L>()
            + sphere_lanes
            + l.index.capacity() * 4
            + L::lanes_bytes(&self.wide)
    }

    /// The walk the tree was built for.
    pub fn built_for(&self) -> Walk {
        self.walk
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
                self.nodes[at].inner |= 1 << slot;
                self.collapse(bn, k, child);
            } else {
                self.nodes[at].child[slot] = node.start;
                self.nodes[at].count[slot] = node.count as u8;
            }
        }
    }

    /// The one walk: the rays `o + t d` at times `time` (moving primitives'
    /// leaves read it) from `best` (lanes at `t = -inf` take no part),
    /// improving it: the closest hit, or (`ANY`) any hit below `best.t`, a
    /// lane that found one leaving (its `t` becomes `-inf`, its index is not
    /// `MISS`) and the walk stopping once every lane has left. A child is
    /// entered when any ray of the group enters its box; a leaf's primitives
    /// are each tested against the whole group, as in brute force.
    #[inline(always)]
    pub fn walk<R: Walker, C: Counter, const ANY: bool>(
        &self,
        o: V3<R>,
        d: V3<R>,
        time: R,
        mut best: Closest<R>,
        counter: &mut C,
    ) -> Closest<R> {
        let mut tally = WorkTally::<C>::new();
        let (inv, noi) = slab_ray(o, d);
        let setup = L::setup(o, d);
        let mut stack = Stack::new((0u32, R::root()));
        let exit = R::constant(EXIT_SCALE);
        let zero = R::constant(0.0);
        let prune = R::splat(PRUNE_SCALE);
        while let Some((ni, entry)) = stack.pop() {
            if R::pruned(entry, best.t) {
                continue;
            }
            tally.work(Work::Node, 1);
            let node = &self.nodes[ni as usize];
            let kids = node.kids();
            tally.work(Work::Box, kids as u32);
            for k in 0..kids {
                let bmin = V3::new(node.min[0][k], node.min[1][k], node.min[2][k]);
                let bmax = V3::new(node.max[0][k], node.max[1][k], node.max[2][k]);
                let (near, far) = slab(V3::splat3(bmin.to_array()), V3::splat3(bmax.to_array()), inv, noi, zero);
                if !R::enters(near, far * exit, best.t * prune) {
                    continue;
                }
                match node.count[k] {
                    0 => stack.push((node.child[k], R::entry(near))),
                    count => {
                        let (start, count) = (node.child[k] as usize, count as usize);
                        L::test_leaf(&self.leaf[start..start + count], o, d, time, &setup, &mut best, &mut tally);
                        if ANY && best.leave_found() {
                            tally.flush(counter);
                            return best;
                        }
                    }
                }
            }
        }
        tally.flush(counter);
        best
    }
}

/// How a group of rays walks a tree: the loop is written once
/// ([`Bvh::walk`]); what differs between one ray (`f32`) and a packet (a
/// [`Wide`] type) is here.
pub trait Walker: Real {
    /// What the stack keeps beside a node: one ray its entry distance (a
    /// node popped once the ray found a closer hit is skipped); a packet
    /// nothing (a node is entered for any ray, and rechecked box by box).
    type Entry: Copy;
    fn entry(near: Self) -> Self::Entry;
    /// The root's entry.
    fn root() -> Self::Entry;
    /// Whether a popped node is skipped.
    fn pruned(entry: Self::Entry, best: Self) -> bool;
    /// Whether the group enters a box it meets from `near` to `far` (its
    /// exit scaled up, see the module's bounds), given its closest hit so far
    /// (scaled up too): one ray decides by a branch per comparison, a packet
    /// by one mask over its lanes.
    fn enters(near: Self, far: Self, best: Self) -> bool;
    /// A constant the box loop reads. The packets' box loop needs every
    /// vector register on AVX2 (16): constants the compiler may rebuild are
    /// rebuilt inside it, one instruction each per box test. Opaque, they
    /// are kept in memory and read as the operands of the instructions that
    /// use them, for free.
    fn constant(x: f32) -> Self;
    /// The spheres' closest hits on a tree built for [`Walk::Wide8`]: each
    /// ray of a packet on its own ([`Bvh::closest_hit_wide`]); one ray walks
    /// it as any tree.
    fn closest_wide8<C: Counter>(
        bvh: &Bvh<LeafSphere>,
        o: V3<Self>,
        d: V3<Self>,
        best: &mut Closest<Self>,
        counter: &mut C,
    );
    /// A tree whose kind is walked one ray at a time
    /// ([`Primitive::WALK_ONE_RAY`]): [`Bvh::walk_one_wide`] for one ray,
    /// for each live lane of a packet (from the lane's closest hit so far).
    fn walk_one_ray<L: Leaf, C: Counter, const ANY: bool>(
        bvh: &Bvh<L>,
        o: V3<Self>,
        d: V3<Self>,
        time: Self,
        best: &mut Closest<Self>,
        counter: &mut C,
    );
}

impl Walker for f32 {
    type Entry = f32;
    #[inline(always)]
    fn entry(near: f32) -> f32 {
        near
    }
    #[inline(always)]
    fn root() -> f32 {
        0.0
    }
    #[inline(always)]
    fn pruned(entry: f32, best: f32) -> bool {
        entry > best * PRUNE_SCALE
    }
    #[inline(always)]
    fn enters(near: f32, far: f32, best: f32) -> bool {
        near <= far && near <= best
    }
    #[inline(always)]
    fn constant(x: f32) -> f32 {
        x
    }
    #[inline(always)]
    fn closest_wide8<C: Counter>(
        bvh: &Bvh<LeafSphere>,
        o: V3<f32>,
        d: V3<f32>,
        best: &mut Closest<f32>,
        counter: &mut C,
    ) {
        *best = bvh.walk::<f32, C, false>(o, d, 0.0, *best, counter);
    }
    /// Out of line, as `closest_wide8` (the scenes without meshes keep the
    /// search they had).
    #[inline(never)]
    fn walk_one_ray<L: Leaf, C: Counter, const ANY: bool>(
        bvh: &Bvh<L>,
        o: V3<f32>,
        d: V3<f32>,
        time: f32,
        best: &mut Closest<f32>,
        counter: &mut C,
    ) {
        *best = bvh.walk_one_wide::<C, ANY>(o, d, time, *best, counter);
    }
}

impl<W: Wide> Walker for W {
    type Entry = ();
    #[inline(always)]
    fn entry(_near: W) {}
    #[inline(always)]
    fn root() {}
    #[inline(always)]
    fn pruned(_entry: (), _best: W) -> bool {
        false
    }
    #[inline(always)]
    fn enters(near: W, far: W, best: W) -> bool {
        (near.le(far) & near.le(best)).any()
    }
    #[inline(always)]
    fn constant(x: f32) -> W {
        std::hint::black_box(W::splat(x))
    }
    /// Out of line: the rare walk (`--accel bvh-ray`) stays out of the
    /// packet walk's caller (inlined there, the final scene took 328.7
    /// instructions per ray instead of 317.0: callgrind, x86-64-v3, simd8).
    #[inline(never)]
    fn closest_wide8<C: Counter>(bvh: &Bvh<LeafSphere>, o: V3<W>, d: V3<W>, best: &mut Closest<W>, counter: &mut C) {
        let live = W::mask_bits(best.t.gt(W::splat(f32::NEG_INFINITY)));
        let (index, t) = bvh.closest_hits_one_by_one(o, d, live, counter);
        best.offer(W::mask_from_bits(live), t, index);
    }
    /// Out of line, as `closest_wide8`: inlined, the triangles' walk made
    /// the packet search of scenes without meshes 1-4% more instructions
    /// (the instruction gate).
    #[inline(never)]
    fn walk_one_ray<L: Leaf, C: Counter, const ANY: bool>(
        bvh: &Bvh<L>,
        o: V3<W>,
        d: V3<W>,
        time: W,
        best: &mut Closest<W>,
        counter: &mut C,
    ) {
        let mut m = W::mask_bits(best.t.gt(W::splat(f32::NEG_INFINITY)));
        let (mut index, mut t) = ([MISS; MAX_LANES], lanes_of(best.t));
        W::store_u(best.index, &mut index, 0);
        let [ox, oy, oz, dx, dy, dz, time] = [o.x, o.y, o.z, d.x, d.y, d.z, time].map(lanes_of);
        while m != 0 {
            let k = m.trailing_zeros() as usize & (MAX_LANES - 1);
            m &= m - 1;
            let (o, d) = (V3::new(ox[k], oy[k], oz[k]), V3::new(dx[k], dy[k], dz[k]));
            let b = bvh.walk_one_wide::<C, ANY>(o, d, time[k], Closest { t: t[k], index: index[k] }, counter);
            (index[k], t[k]) = (b.index, b.t);
        }
        *best = Closest { t: W::load(&t, 0), index: W::load_u(&index, 0) };
    }
}

impl<L: Leaf> Bvh<L> {
    /// One ray's walk with 8 child boxes per `f32x8` test, the leaves by
    /// the kind's own test (one primitive at a time): for big trees and
    /// incoherent rays (meshes), where a packet's walk enters the union of
    /// its rays' boxes. From `best`, improving it; with `ANY`, stopping at
    /// the first hit below `best.t`. The same answer as [`Bvh::walk`] and
    /// brute force, bit for bit: only which primitives are tested differs.
    #[inline(always)]
    pub fn walk_one_wide<C: Counter, const ANY: bool>(
        &self,
        o: V3<f32>,
        d: V3<f32>,
        time: f32,
        mut best: Closest<f32>,
        counter: &mut C,
    ) -> Closest<f32> {
        let mut tally = WorkTally::<C>::new();
        let ray = OneRay::<L>::new(o, d, time);
        self.walk8(o, d, &mut best, &mut tally, |start, cnt, best, tally| {
            L::test_lanes::<_, ANY>(&self.wide, &self.leaf, start, cnt, &ray, best, tally);
            ANY && best.index != MISS
        });
        tally.flush(counter);
        best
    }

    /// The one-ray walks' loop, written once ([`Bvh::walk_one_wide`],
    /// [`Bvh::closest_hit_wide`]): per node the ray against its 8 boxes at
    /// once; the leaves it enters first (they tighten `best.t`), each by
    /// `leaf(start, count, best, tally)`, which says whether to stop (an
    /// any-hit found); then the nearest inner child it enters is walked
    /// next, the others pushed to pop nearest first.
    #[inline(always)]
    fn walk8<C: Counter>(
        &self,
        o: V3<f32>,
        d: V3<f32>,
        best: &mut Closest<f32>,
        tally: &mut WorkTally<C>,
        mut leaf: impl FnMut(usize, usize, &mut Closest<f32>, &mut WorkTally<C>) -> bool,
    ) {
        let (inv, noi) = slab_ray(o, d);
        let (inv8, noi8) = (splat3(inv), splat3(noi));
        let mut stack = Stack::empty();
        let mut key = node_key(0, 0.0);
        loop {
            let (ni, entry) = node_of(key);
            if entry <= best.t * PRUNE_SCALE {
                tally.work(Work::Node, 1);
                tally.work(Work::Box, 8);
                let node = &self.nodes[ni as usize];
                let (mut leaves, inner, near) = node.enter8(inv8, noi8, best.t);
                if L::LEAVES_NEAR_TO_FAR {
                    if leaves_near_to_far(leaves, near, best, |k, best| {
                        leaf(node.child[k] as usize, node.count[k] as usize, best, tally)
                    }) {
                        return;
                    }
                    leaves = 0;
                }
                while leaves != 0 {
                    let k = leaves.trailing_zeros() as usize & 7;
                    leaves &= leaves - 1;
                    if leaf(node.child[k] as usize, node.count[k] as usize, best, tally) {
                        return;
                    }
                }
                if let Some(nearest) = stack.nearest_pushing_rest(inner, near, &node.child) {
                    key = nearest;
                    continue;
                }
            }
            match stack.pop() {
                Some(popped) => key = popped,
                None => return,
            }
        }
    }
}

impl<L: Leaf> Bvh<L> {
    /// Every leaf record whose box the line `o + t d` (`t >= 0`) enters,
    /// each once, in no particular order: not the closest hit but all of
    /// them (a light mesh's density sums over every triangle a direction
    /// meets, [`super::LightMesh`]). One ray, one box at a time; the tree
    /// must keep its leaf records (built by [`Bvh::build`], not
    /// [`Bvh::build_lanes_only`]).
    #[inline]
    pub fn visit(&self, o: V3<f32>, d: V3<f32>, mut f: impl FnMut(&L)) {
        if self.leaf.is_empty() {
            return;
        }
        let (inv, noi) = slab_ray(o, d);
        let mut stack = Stack::new(0u32);
        while let Some(ni) = stack.pop() {
            let node = &self.nodes[ni as usize];
            for k in 0..node.kids() {
                let bmin = V3::new(node.min[0][k], node.min[1][k], node.min[2][k]);
                let bmax = V3::new(node.max[0][k], node.max[1][k], node.max[2][k]);
                let (near, far) = slab(bmin, bmax, inv, noi, 0.0);
                if !(near <= far * EXIT_SCALE) {
                    continue;
                }
                match node.count[k] {
                    0 => stack.push(node.child[k]),
                    count => {
                        let start = node.child[k] as usize;
                        self.leaf[start..start + count as usize].iter().for_each(&mut f);
                    }
                }
            }
        }
    }
}

impl Bvh<LeafSphere> {
    /// The tree over `s` for `walk` ([`Bvh::build`]), with the spheres' SoA
    /// in leaf order for the one-ray walk ([`Bvh::closest_hit_wide`]).
    pub fn build_spheres(s: &Spheres, extent: f32, walk: Walk) -> Bvh<LeafSphere> {
        let mut bvh = Bvh::build(s, extent, walk);
        let l = &mut bvh.lanes;
        for leaf in &bvh.leaf {
            let i = leaf.index as usize;
            l.cx.push(s.cx[i]);
            l.cy.push(s.cy[i]);
            l.cz.push(s.cz[i]);
            l.r2.push(s.r2[i]);
            l.index.push(i as u32);
        }
        for _ in 0..8 {
            l.cx.push(0.0);
            l.cy.push(0.0);
            l.cz.push(0.0);
            l.r2.push(-1.0); // never hit
            l.index.push(MISS);
        }
        bvh
    }

    /// The closest hit of one ray: 8 child boxes, or 8 leaf spheres, per `f32x8` test.
    pub fn closest_hit_wide<C: Counter>(&self, o: V3<f32>, d: V3<f32>, counter: &mut C) -> (u32, f32) {
        let mut tally = WorkTally::<C>::new();
        let (o8, d8) = (splat3(o), splat3(d));
        let mut best = Closest::<f32>::none();
        self.walk8(o, d, &mut best, &mut tally, |start, cnt, best, tally| {
            self.leaf_wide(start, cnt, o8, d8, best, tally);
            false
        });
        tally.flush(counter);
        (best.index, best.t)
    }

    /// The closest hits of a packet's rays, each walking the tree on its own
    /// with [`Bvh::closest_hit_wide`] (`--accel bvh-ray`). Lanes not in `live` miss.
    pub fn closest_hits_one_by_one<W: Wide, C: Counter>(
        &self,
        o: V3<W>,
        d: V3<W>,
        live: u32,
        counter: &mut C,
    ) -> (W::U32, W) {
        let mut hit = [MISS; MAX_LANES];
        let mut t = [f32::INFINITY; MAX_LANES];
        let [ox, oy, oz, dx, dy, dz] = [o.x, o.y, o.z, d.x, d.y, d.z].map(lanes_of);
        let mut m = live;
        while m != 0 {
            let k = m.trailing_zeros() as usize & (MAX_LANES - 1);
            m &= m - 1;
            (hit[k], t[k]) = self.closest_hit_wide(V3::new(ox[k], oy[k], oz[k]), V3::new(dx[k], dy[k], dz[k]), counter);
        }
        (W::load_u(&hit, 0), W::load(&t, 0))
    }

    /// One ray against the up-to-8 spheres of a leaf at once (`f32x8` lanes are
    /// spheres here); hits are offered to `best` in lane order.
    #[inline(always)]
    fn leaf_wide<C: Counter>(
        &self,
        start: usize,
        cnt: usize,
        o: V3<f32x8>,
        d: V3<f32x8>,
        best: &mut Closest<f32>,
        counter: &mut C,
    ) {
        counter.work(Work::Sphere, cnt as u32);
        let ld = |v: &[f32]| f32x8::new(v[start..start + 8].try_into().unwrap());
        let c = V3::new(ld(&self.lanes.cx), ld(&self.lanes.cy), ld(&self.lanes.cz));
        let r2 = ld(&self.lanes.r2);
        let (disc, f, b) = sphere_disc(o, d, c, r2);
        let live = (1u32 << cnt) - 1;
        if disc.ge(f32x8::splat(0.0)).to_bitmask() & live == 0 {
            return;
        }
        counter.work(Work::Root, 1);
        let (hit, t) = sphere_t(disc, f, b, r2);
        let mut m = hit.to_bitmask() & live;
        let t = t.to_array();
        while m != 0 {
            let k = m.trailing_zeros() as usize;
            m &= m - 1;
            best.offer(true, t[k], self.lanes.index[start + k]);
        }
    }
}

/// The traversal stack (of nodes, of (node, entry distance), or of
/// [`node_key`]s). Uninitialized storage: filling 2 KiB per ray would cost
/// more than the walk.
struct Stack<T: Copy> {
    items: [MaybeUninit<T>; STACK],
    len: usize,
}

impl<T: Copy> Stack<T> {
    #[inline(always)]
    fn new(root: T) -> Self {
        let mut s = Stack::empty();
        s.push(root);
        s
    }
    #[inline(always)]
    fn empty() -> Self {
        Stack { items: [const { MaybeUninit::uninit() }; STACK], len: 0 }
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

/// A one-ray walk's stack entry: a node and the ray's entry distance into
/// its box, the distance in the high half, so that entries order as their
/// distances (non-negative floats order as their bits; the sign is cleared
/// for a `-0.0`), ties by node.
#[inline(always)]
fn node_key(node: u32, near: f32) -> u64 {
    (u64::from(near.to_bits() & 0x7fff_ffff) << 32) | u64::from(node)
}

/// The node and the entry distance of a [`node_key`].
#[inline(always)]
fn node_of(key: u64) -> (u32, f32) {
    (key as u32, f32::from_bits((key >> 32) as u32))
}

impl Stack<u64> {
    /// The inner children in `bits` (slot `k`: node `child[k]`, entered at
    /// `near[k]`) as [`node_key`]s: the nearest returned (`None` for no
    /// bits), the others pushed so that they pop nearest first. A lone
    /// child (the most common case) touches no stack; more are each
    /// inserted among the ones pushed before them (at most 8), with no sort
    /// and no call.
    #[inline(always)]
    fn nearest_pushing_rest(&mut self, mut bits: u32, near: f32x8, child: &[u32; 8]) -> Option<u64> {
        if bits == 0 {
            return None;
        }
        let near = near.to_array();
        if bits & (bits - 1) == 0 {
            let k = bits.trailing_zeros() as usize & 7;
            return Some(node_key(child[k], near[k]));
        }
        let base = self.len;
        while bits != 0 {
            let k = bits.trailing_zeros() as usize & 7;
            bits &= bits - 1;
            let key = node_key(child[k], near[k]);
            let mut j = self.len;
            while j > base {
                // SAFETY: every index below `len` was written by `new` or a push.
                let below = unsafe { self.items[j - 1].assume_init() };
                if below >= key {
                    break;
                }
                self.items[j].write(below);
                j -= 1;
            }
            self.items[j].write(key);
            self.len += 1;
        }
        self.pop()
    }
}

/// A node's leaves in `bits` (slot `k` entered at `near[k]`), nearest
/// first, each while its entry is within `best` (the walks' pruning rule):
/// `leaf(k, best)` for each, which says whether to stop (then `true`).
/// For kinds whose leaves are whole searches ([`Leaf::LEAVES_NEAR_TO_FAR`]).
#[inline(always)]
fn leaves_near_to_far(
    mut bits: u32,
    near: f32x8,
    best: &mut Closest<f32>,
    mut leaf: impl FnMut(usize, &mut Closest<f32>) -> bool,
) -> bool {
    let near = near.to_array();
    while bits != 0 {
        let mut k = bits.trailing_zeros() as usize & 7;
        let mut rest = bits & (bits - 1);
        while rest != 0 {
            let j = rest.trailing_zeros() as usize & 7;
            rest &= rest - 1;
            if near[j] < near[k] {
                k = j;
            }
        }
        bits &= !(1 << k);
        if near[k] > best.t * PRUNE_SCALE {
            return false;
        }
        if leaf(k, best) {
            return true;
        }
    }
    false
}

/// The lanes of `v` as an array (one store), for a packet's walks one ray
/// at a time.
#[inline(always)]
fn lanes_of<W: Wide>(v: W) -> [f32; MAX_LANES] {
    let mut a = [0.0; MAX_LANES];
    v.store(&mut a, 0);
    a
}

#[inline(always)]
fn splat3(v: V3<f32>) -> V3<f32x8> {
    V3::new(f32x8::splat(v.x), f32x8::splat(v.y), f32x8::splat(v.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inner children a one-ray walk enters come back nearest first
    /// (the nearest returned, the rest popping in order), ties by node, a
    /// `-0.0` entry as `0.0`, and what was on the stack before stays below.
    #[test]
    fn inner_children_pop_nearest_first() {
        let near = [3.0, -0.0, 7.5, 1.0, 3.0, 0.25, f32::INFINITY, 2.0];
        let child = [10, 11, 12, 13, 14, 15, 16, 17];
        for bits in [0u32, 1, 0b1000_0000, 0b1010_0110, 0b0101_1001, 0xff] {
            let mut stack = Stack::<u64>::empty();
            stack.push(node_key(99, 100.0));
            let mut want: Vec<(f32, u32)> =
                (0..8).filter(|k| bits >> k & 1 == 1).map(|k| (near[k].abs(), child[k])).collect();
            want.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut got = Vec::new();
            if let Some(first) = stack.nearest_pushing_rest(bits, f32x8::new(near), &child) {
                got.push(first);
            }
            while stack.len > 1 {
                got.push(stack.pop().expect("entries above the first"));
            }
            let got: Vec<(f32, u32)> = got.into_iter().map(|key| (node_of(key).1, node_of(key).0)).collect();
            assert_eq!(got, want, "bits {bits:#b}");
            assert_eq!(stack.pop().map(node_of), Some((99, 100.0)));
        }
    }
}
