//! A bounding volume hierarchy over spheres: built with the surface area
//! heuristic (binned, binary), then collapsed to 8-wide nodes so one ray tests
//! 8 child boxes at once (`f32x8`), and leaves of up to 8 spheres that one ray
//! tests at once. The scalar kernel walks the same tree one box at a time.
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
//! * The slab test's own rounding: entry and exit distances carry at most
//!   `3 u` relative error, so exits are scaled by `1 + 2 gamma_3` (Ize 2013,
//!   "Robust BVH ray traversal") and a box is pruned only when its entry
//!   exceeds `best * (1 + 2^-20)`.

use super::intersect::{sphere_disc, sphere_t, Closest};
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
/// leaf (a run of up to 8 spheres in leaf order) or empty.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct Node8 {
    min: [[f32; 8]; 3],
    max: [[f32; 8]; 3],
    /// Inner: node index. Leaf: first sphere in leaf order.
    child: [u32; 8],
    /// 0: inner node; 1..=8: leaf with that many spheres; `EMPTY`: no child.
    count: [u8; 8],
}

const EMPTY: u8 = u8::MAX;

/// The tree plus the spheres in leaf order (SoA, padded by 8 for whole loads).
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node8>,
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

struct Builder<'a> {
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
        // Cost model: a leaf of up to 8 spheres costs one 8-wide sphere test (1.0);
        // an inner level costs one 8-wide box test (0.5) plus its children by area.
        let leaf_cost = n.div_ceil(8) as f32;
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
                let cost = 0.5 + (lb.area() * ln.div_ceil(8) as f32 + rb.area() * rn.div_ceil(8) as f32) / area;
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

impl Bvh {
    /// Builds the tree; `extent` bounds |coordinates| of every ray origin
    /// (the camera and its lens), used to pad the boxes.
    pub fn build(s: &Spheres, extent: f32) -> Bvh {
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
        let mut b = Builder { boxes: &boxes, centroid, order: (0..n as u32).collect(), nodes: Vec::new() };
        if n > 0 {
            b.build(0, n, 0);
        }
        let mut bvh = Bvh { nodes: Vec::new(), cx: vec![], cy: vec![], cz: vec![], r2: vec![], index: vec![] };
        for &i in &b.order {
            let i = i as usize;
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
        bvh.nodes.push(Node8 { min: [[0.0; 8]; 3], max: [[0.0; 8]; 3], child: [0; 8], count: [EMPTY; 8] });
        if n > 0 {
            bvh.collapse(&b.nodes, 0, 0);
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
        for (slot, &k) in kids.iter().enumerate() {
            let node = &bn[k as usize];
            for a in 0..3 {
                self.nodes[at].min[a][slot] = node.bounds.min[a];
                self.nodes[at].max[a][slot] = node.bounds.max[a];
            }
            if node.count == 0 {
                let child = self.nodes.len();
                self.nodes.push(Node8 { min: [[0.0; 8]; 3], max: [[0.0; 8]; 3], child: [0; 8], count: [EMPTY; 8] });
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
    fn leaf<R: Real, P: Probe>(
        &self,
        start: usize,
        count: usize,
        o: V3<R>,
        d: V3<R>,
        best: &mut Closest<R>,
        probe: &mut P,
    ) {
        for j in start..start + count {
            let c = V3::new(R::splat(self.cx[j]), R::splat(self.cy[j]), R::splat(self.cz[j]));
            best.test(o, d, c, R::splat(self.r2[j]), self.index[j], probe);
        }
    }

    /// The closest hit of one ray, one box and one sphere at a time (scalar kernel).
    pub fn closest_hit_scalar<P: Probe>(&self, o: V3<f32>, d: V3<f32>, probe: &mut P) -> (u32, f32) {
        let mut tally = WorkTally::<P>::new();
        let inv = inv_dir(d);
        let mut best = Closest::<f32>::none();
        let mut stack = Stack::new();
        while let Some((ni, entry)) = stack.pop() {
            if entry > best.t * PRUNE_SCALE {
                continue;
            }
            tally.work(Work::Node, 1);
            let node = &self.nodes[ni as usize];
            for k in 0..8 {
                if node.count[k] == EMPTY {
                    continue;
                }
                tally.work(Work::Box, 1);
                let (near, far) = slab(
                    V3::new(node.min[0][k], node.min[1][k], node.min[2][k]),
                    V3::new(node.max[0][k], node.max[1][k], node.max[2][k]),
                    o,
                    inv,
                );
                if !(near <= far * EXIT_SCALE && near <= best.t * PRUNE_SCALE) {
                    continue;
                }
                match node.count[k] {
                    0 => stack.push((node.child[k], near)),
                    count => self.leaf(node.child[k] as usize, count as usize, o, d, &mut best, &mut tally),
                }
            }
        }
        tally.flush(probe);
        (best.index, best.t)
    }

    /// The closest hit of one ray: 8 child boxes, or 8 leaf spheres, per `f32x8` test.
    pub fn closest_hit_wide<P: Probe>(&self, o: V3<f32>, d: V3<f32>, probe: &mut P) -> (u32, f32) {
        let mut tally = WorkTally::<P>::new();
        let inv = inv_dir(d);
        let (o8, d8) = (splat3(o), splat3(d));
        let inv8 = splat3(inv);
        let mut best = Closest::<f32>::none();
        let mut stack = Stack::new();
        while let Some((ni, entry)) = stack.pop() {
            if entry > best.t * PRUNE_SCALE {
                continue;
            }
            tally.work(Work::Node, 1);
            tally.work(Work::Box, 8);
            let node = &self.nodes[ni as usize];
            let bmin = V3::new(f32x8::new(node.min[0]), f32x8::new(node.min[1]), f32x8::new(node.min[2]));
            let bmax = V3::new(f32x8::new(node.max[0]), f32x8::new(node.max[1]), f32x8::new(node.max[2]));
            let (near, far) = slab(bmin, bmax, o8, inv8);
            let ok = near.le(far * f32x8::splat(EXIT_SCALE)) & near.le(f32x8::splat(best.t * PRUNE_SCALE));
            let mut mask = ok.to_bitmask();
            let near = near.to_array();
            // Leaves first (they tighten `best.t`), inner nodes pushed far-to-near.
            let mut inner: [(u32, f32); 8] = [(0, 0.0); 8];
            let mut ninner = 0;
            while mask != 0 {
                let k = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                match node.count[k] {
                    EMPTY => {}
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

    /// The closest hits of a packet of rays walking the tree together: a child
    /// is entered when any live ray (bit k of `live`) enters its box; a leaf's
    /// spheres are each broadcast against the packet, as in brute force.
    pub fn closest_hit_packet<W: Wide, P: Probe>(&self, o: V3<W>, d: V3<W>, live: u32, probe: &mut P) -> (W::U32, W) {
        let mut tally = WorkTally::<P>::new();
        let inv = inv_dir(d);
        let live_mask = W::mask_from_bits(live);
        let mut best = Closest::<W>::none();
        let mut stack = Stack::new();
        let exit = W::splat(EXIT_SCALE);
        let prune = W::splat(PRUNE_SCALE);
        while let Some((ni, _)) = stack.pop() {
            tally.work(Work::Node, 1);
            let node = &self.nodes[ni as usize];
            for k in 0..8 {
                let count = node.count[k];
                if count == EMPTY {
                    continue;
                }
                tally.work(Work::Box, 1);
                let bmin = V3::new(node.min[0][k], node.min[1][k], node.min[2][k]);
                let bmax = V3::new(node.max[0][k], node.max[1][k], node.max[2][k]);
                let (near, far) = slab(V3::splat3(bmin.to_array()), V3::splat3(bmax.to_array()), o, inv);
                let enter = near.le(far * exit) & near.le(best.t * prune) & live_mask;
                if !enter.any() {
                    continue;
                }
                if count == 0 {
                    stack.push((node.child[k], 0.0));
                    continue;
                }
                self.leaf(node.child[k] as usize, count as usize, o, d, &mut best, &mut tally);
            }
        }
        tally.flush(probe);
        (best.index, best.t)
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

/// The traversal stack of (node, entry distance), starting with the root.
/// Uninitialized storage: filling 2 KiB per ray would cost more than the walk.
struct Stack {
    items: [MaybeUninit<(u32, f32)>; STACK],
    len: usize,
}

impl Stack {
    #[inline(always)]
    fn new() -> Self {
        let mut s = Stack { items: [const { MaybeUninit::uninit() }; STACK], len: 1 };
        s.items[0].write((0, 0.0));
        s
    }
    #[inline(always)]
    fn push(&mut self, e: (u32, f32)) {
        self.items[self.len].write(e);
        self.len += 1;
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, f32)> {
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
/// (with their sign), so the slab test never computes `0 * inf`.
#[inline(always)]
fn inv_lanes<R: Real>(x: R) -> R {
    let tiny = R::splat(TINY_DIR);
    R::splat(1.0) / R::select(x.abs().lt(tiny), tiny.copysign(x), x)
}

#[inline(always)]
fn inv_dir<R: Real>(d: V3<R>) -> V3<R> {
    V3::new(inv_lanes(d.x), inv_lanes(d.y), inv_lanes(d.z))
}

/// Entry and exit distances of the ray `o + t d` (given `1/d`) through boxes,
/// entry clamped at 0.
#[inline(always)]
fn slab<R: Real>(bmin: V3<R>, bmax: V3<R>, o: V3<R>, inv: V3<R>) -> (R, R) {
    let t0 = (bmin - o).mul_elem(inv);
    let t1 = (bmax - o).mul_elem(inv);
    // No NaN can arise (|1/d| <= 1e30, finite coordinates) and the test only
    // needs to be conservative, so the one-instruction min/max do.
    let near = t0.x.fast_min(t1.x).fast_max(t0.y.fast_min(t1.y)).fast_max(t0.z.fast_min(t1.z)).fast_max(R::splat(0.0));
    let far = t0.x.fast_max(t1.x).fast_min(t0.y.fast_max(t1.y)).fast_min(t0.z.fast_max(t1.z));
    (near, far)
}
