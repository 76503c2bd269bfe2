//! The one aggregate: every kind's primitives and, where the plan chose one,
//! its tree, with the closest-hit and any-hit searches over all of them,
//! written once for one ray and for packets ([`Walker`]).
//!
//! The kinds are searched in a fixed order, each improving the closest hit
//! of the ones before; the tie rule ([`Closest::offer`]) makes the answer
//! independent of that order. The spheres come first (the one kind with a
//! second walk, `--accel bvh-ray`); the others are registered in
//! `for_each_kind_after_spheres`, each searched only when it has
//! primitives, and a scene of spheres alone stops after them. Adding a kind
//! is its own file (its [`Primitive`] and [`super::Leaf`]), a field here and in
//! [`Trees`], and a line in that list.

use super::bvh::{Bvh, Walk, Walker};
use super::cuboids::{Cuboids, LeafCuboid};
use super::hit::Closest;
use super::instances::{Instances, LeafInstance};
use super::moving::{LeafMoving, MovingSpheres};
use super::primitive::Primitive;
use super::quads::{LeafQuad, Quads};
use super::smooth::Smooth;
use super::spheres::{LeafSphere, Spheres};
use super::triangles::{LeafTriangle, Triangles};
use super::work::Counter;
use crate::vec3::V3;

/// Every kind's primitives, and their trees.
#[derive(Clone, Debug, Default)]
pub struct Shapes {
    pub spheres: Spheres,
    /// The quads (a cuboid's faces among them; searched: the loose ones).
    pub quads: Quads,
    /// The boxes, each tested whole.
    pub cuboids: Cuboids,
    /// Spheres whose centre moves over the shutter interval.
    pub moving: MovingSpheres,
    /// The meshes' triangles (world space).
    pub triangles: Triangles,
    /// The meshes several groups place, each held once (its own frame).
    pub instances: Instances,
    /// The vertex normals of the triangles of meshes that give them
    /// (empty: every surface shades with its geometric normal).
    pub smooth: Smooth,
    /// Each kind's tree, where the plan chose one (else brute force).
    pub trees: Trees,
    /// Some kind beyond the spheres has primitives to search.
    others: bool,
    /// The scene's primitives are all triangles in world space.
    only_triangles: bool,
}

/// A tree per kind, or none (brute force).
#[derive(Clone, Debug, Default)]
pub struct Trees {
    pub spheres: Option<Bvh<LeafSphere>>,
    pub quads: Option<Bvh<LeafQuad>>,
    pub cuboids: Option<Bvh<LeafCuboid>>,
    pub moving: Option<Bvh<LeafMoving>>,
    pub triangles: Option<Bvh<LeafTriangle>>,
    pub instances: Option<Bvh<LeafInstance>>,
}

/// The kinds after the spheres, in their search order: `$body` once per
/// kind with `$prims` its primitives and `$tree` its tree (an `Option`).
macro_rules! for_each_kind_after_spheres {
    ($shapes:expr, |$prims:ident, $tree:ident| $body:expr) => {{
        {
            let ($prims, $tree) = (&$shapes.quads, $shapes.trees.quads.as_ref());
            $body;
        }
        {
            let ($prims, $tree) = (&$shapes.cuboids, $shapes.trees.cuboids.as_ref());
            $body;
        }
        {
            let ($prims, $tree) = (&$shapes.moving, $shapes.trees.moving.as_ref());
            $body;
        }
        {
            let ($prims, $tree) = (&$shapes.triangles, $shapes.trees.triangles.as_ref());
            $body;
        }
        {
            let ($prims, $tree) = (&$shapes.instances, $shapes.trees.instances.as_ref());
            $body;
        }
    }};
}

/// Which kinds get a tree, and the walk the spheres' is built for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TreeChoice {
    /// `None`: brute force over the spheres.
    pub spheres: Option<Walk>,
    pub quads: bool,
    pub cuboids: bool,
    pub moving: bool,
    pub triangles: bool,
}

impl Shapes {
    /// The aggregate over the primitives (padded, as the kernels read
    /// them), without trees; `cuboids` must have their faces' boxes
    /// ([`Cuboids::bound_faces`]) before a tree is built over them.
    pub fn new(
        spheres: Spheres,
        quads: Quads,
        cuboids: Cuboids,
        moving: MovingSpheres,
        triangles: Triangles,
        instances: Instances,
    ) -> Shapes {
        let others = quads.count() > 0
            || cuboids.count() > 0
            || moving.count() > 0
            || triangles.count() > 0
            || instances.count() > 0;
        let only_triangles = triangles.count() > 0
            && spheres.count() == 0
            && quads.count() == 0
            && cuboids.count() == 0
            && moving.count() == 0
            && instances.count() == 0;
        Shapes {
            spheres,
            quads,
            cuboids,
            moving,
            triangles,
            instances,
            smooth: Smooth::default(),
            trees: Trees::default(),
            others,
            only_triangles,
        }
    }

    /// The scene needs the kernels' general path (`M`): it has moving
    /// spheres (each path carries a time), or meshes (their triangles' and
    /// instances' hits are told apart from the quads'). The other scenes
    /// compile to a bounce without them.
    pub fn general(&self) -> bool {
        !self.moving.is_empty() || self.has_meshes()
    }

    /// The scene's primitives are all triangles in world space.
    pub fn only_triangles(&self) -> bool {
        self.only_triangles
    }

    /// The scene has triangles, in world space or instanced.
    pub fn has_meshes(&self) -> bool {
        !self.triangles.is_empty() || !self.instances.is_empty()
    }

    /// The bytes the scene's triangles (world space) hold on the heap once
    /// prepared: their planes and meshes, their vertex normals (smooth
    /// meshes) and their tree (its nodes and lanes; the vertices too while
    /// no tree holds them, brute force).
    pub fn triangle_bytes(&self) -> usize {
        self.triangles.heap_bytes()
            + self.smooth.rec.capacity() * std::mem::size_of::<[f32; 18]>()
            + self.trees.triangles.as_ref().map_or(0, Bvh::heap_bytes)
    }

    /// Builds the trees `choice` asks for; `extent` bounds every ray origin
    /// (see [`Bvh::build`]). The triangles' records are then held by their
    /// tree alone ([`Triangles::release`]). Instances always get their tree
    /// (over their boxes: a few per scene), whatever `choice` says: brute
    /// force over them ([`Instances`]' own) serves the tests.
    pub fn build_trees(&mut self, choice: TreeChoice, extent: f32) {
        let one = Walk::OneByOne;
        self.trees = Trees {
            spheres: choice.spheres.map(|walk| Bvh::build_spheres(&self.spheres, extent, walk)),
            quads: choice.quads.then(|| Bvh::build(&self.quads, extent, one)),
            cuboids: choice.cuboids.then(|| Bvh::build(&self.cuboids, extent, one)),
            moving: choice.moving.then(|| Bvh::build(&self.moving, extent, one)),
            // Walked one ray at a time (`Primitive::WALK_ONE_RAY`), 8 boxes
            // and 8 triangles a test, from the tree's lanes alone.
            triangles: choice.triangles.then(|| Bvh::build_lanes_only(&self.triangles, extent, Walk::Wide8)),
            instances: (!self.instances.is_empty()).then(|| self.instances.tree(extent)),
        };
        if self.trees.triangles.is_some() {
            self.triangles.release();
        }
    }

    /// The closest hits of the rays `o + t d` (one ray, or a packet; the
    /// lanes of `live` are searched, the others return `MISS` at
    /// `t = -inf`). `M`: the scene is on the general path
    /// ([`Shapes::general`]; `false` compiles to the search of a scene
    /// without moving spheres and instances); `time` gives the rays' times,
    /// called only when `M`.
    #[cfg_attr(not(feature = "phases"), inline(always))]
    #[cfg_attr(feature = "phases", inline(never))]
    pub fn closest<R: Walker, C: Counter, const M: bool>(
        &self,
        o: V3<R>,
        d: V3<R>,
        live: R::Mask,
        time: impl FnOnce() -> R,
        counter: &mut C,
    ) -> Closest<R> {
        let mut best = Closest::live(live);
        match &self.trees.spheres {
            Some(b) if R::LANES > 1 && b.built_for() == Walk::Wide8 => R::closest_wide8(b, o, d, &mut best, counter),
            Some(b) => best = b.walk::<R, C, false>(o, d, R::splat(0.0), best, counter),
            None => self.spheres.brute::<R, C, false>(o, d, R::splat(0.0), &mut best, counter),
        }
        if !M && !self.others {
            return best;
        }
        let time = if M { time() } else { R::splat(0.0) };
        for_each_kind_after_spheres!(self, |prims, tree| search::<_, R, C, M, false>(
            prims, tree, o, d, time, &mut best, counter
        ));
        best
    }

    /// Whether something lies on the segment `o + t d`, `0 < t < tmax`, of
    /// each ray of `live` (shadow rays; the other lanes are not occluded):
    /// any hit, each lane leaving the search at its first and each kind's
    /// search stopping once no lane is left. The same answer as one ray at a
    /// time, whatever the order: a hit below `tmax` is one whatever else was
    /// found. Media do not block (their transmittance is
    /// [`super::transmittance`]). `M` and `time` as for [`Shapes::closest`].
    #[inline(always)]
    pub fn occluded<R: Walker, C: Counter, const M: bool>(
        &self,
        o: V3<R>,
        d: V3<R>,
        tmax: R,
        live: R::Mask,
        time: impl FnOnce() -> R,
        counter: &mut C,
    ) -> R::Mask {
        let mut best = Closest::below(tmax, live);
        search::<_, R, C, M, true>(&self.spheres, self.trees.spheres.as_ref(), o, d, R::splat(0.0), &mut best, counter);
        if (!M && !self.others) || best.leave_found() {
            return best.found();
        }
        let time = if M { time() } else { R::splat(0.0) };
        for_each_kind_after_spheres!(self, |prims, tree| {
            search::<_, R, C, M, true>(prims, tree, o, d, time, &mut best, counter);
            if best.leave_found() {
                return best.found();
            }
        });
        best.found()
    }
}

/// One kind's search: its tree's walk, or brute force; nothing for a kind
/// without primitives, or a kind of the general path (moving spheres,
/// instances) in a scene without one (`M`).
#[inline(always)]
fn search<K: Primitive, R: Walker, C: Counter, const M: bool, const ANY: bool>(
    prims: &K,
    tree: Option<&Bvh<K::Leaf>>,
    o: V3<R>,
    d: V3<R>,
    time: R,
    best: &mut Closest<R>,
    counter: &mut C,
) {
    if (K::GENERAL && !M) || prims.count() == 0 {
        return;
    }
    if K::WALK_ONE_RAY {
        return search_one_ray::<K, R, C, ANY>(prims, tree, o, d, time, best, counter);
    }
    match tree {
        Some(b) => *best = b.walk::<R, C, ANY>(o, d, time, *best, counter),
        None => prims.brute::<R, C, ANY>(o, d, time, best, counter),
    }
}

/// The search of a kind walked one ray at a time ([`Primitive::WALK_ONE_RAY`]:
/// the meshes' triangles), its tree's or brute force's, out of line: inlined
/// into the closest-hit search, it made the scenes without meshes pay 1-4%
/// more instructions per ray (the instruction gate).
#[inline(never)]
fn search_one_ray<K: Primitive, R: Walker, C: Counter, const ANY: bool>(
    prims: &K,
    tree: Option<&Bvh<K::Leaf>>,
    o: V3<R>,
    d: V3<R>,
    time: R,
    best: &mut Closest<R>,
    counter: &mut C,
) {
    match tree {
        Some(b) => R::walk_one_ray::<K::Leaf, C, ANY>(b, o, d, time, best, counter),
        None => prims.brute::<R, C, ANY>(o, d, time, best, counter),
    }
}
