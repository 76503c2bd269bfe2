//! Instanced meshes: one mesh's triangles and tree, in the mesh's own frame,
//! placed by several groups (a turn about y, then a move) without a copy.
//!
//! A mesh two groups or more place (`crate::scene::Sharing` decides which)
//! is held once: its triangles in its own frame (an OBJ file's vertices
//! times the mesh's `scale`) and the tree over them ([`SharedMesh`]). Each
//! placement is an instance ([`LeafInstance`]): the turn's cosine and sine,
//! the move, and the hit index of its first triangle. The instances get a
//! tree of their own over their world-space boxes, walked one ray at a
//! time ([`Primitive::WALK_ONE_RAY`]); at an instance's leaf the ray is
//! moved into the mesh's frame and walks the mesh's tree, the triangles'
//! own one-ray walk and watertight test ([`super::triangles`]). The scalar
//! kernel and every lane of a packet run this same code, so they find the
//! same hits bit for bit.
//!
//! **Hit indices.** Triangle `k` of instance `i` is hit index
//! `INSTANCE_BASE + first_i + k`, `first_i` the triangles of the instances
//! before it: one index per placed triangle, as if flattened, without a
//! record per placed triangle (an index is decoded by a binary search over
//! the instances, once per hit).
//!
//! **Surfaces.** A hit's plane is the triangle's plane in the mesh's frame,
//! turned and moved to the world in f32 ([`Instances::surface`]); the hit
//! point and the side are the quads' rule ([`super::quad_surface`]) on
//! that plane. The ray found the triangle in the mesh's frame, where its
//! origin carries the rounding of the move: about `u` times the distance
//! from the frame's origin (`|o - T|`), which near the world's origin can
//! be far more than `u |o|`. So a new ray leaves an instanced triangle by
//! the quads' offset `32u (|p| + |n.p|)` plus `32u (|T| + |dn|)` (the move
//! and the plane's offset in the mesh's frame): it covers the rounding of
//! the move, the turn and the plane's side test (each a few `u` of
//! `|p| + |T|`), so a ray leaving a triangle never finds it again, however
//! far its instance sits from its frame's origin (`tests/suite/instances.rs`).

use super::bvh::{Bvh, Walk};
use super::hit::{Closest, INSTANCE_BASE, MISS};
use super::primitive::{Leaf, OneRay, Primitive};
use super::quads::quad_surface;
use super::slab::Aabb;
use super::surface::{Surface, OFFSET_ULPS};
use super::triangles::{LeafTriangle, Triangles};
use super::work::Counter;
use crate::handle::Kind;
use crate::real::Real;
use crate::vec3::V3;
use std::sync::Arc;

/// One mesh's triangles in its own frame and the tree over them. The
/// tree's hit indices are the triangles' places in the mesh (`0..len`).
#[derive(Clone, Debug)]
pub struct SharedMesh {
    tree: Bvh<LeafTriangle>,
    /// Per triangle: its plane's unit normal and `n.v0` in the mesh's frame
    /// ([`super::triangles::plane`]), for the surface of a hit.
    plane: Vec<[f32; 4]>,
    /// The vertices' box in the mesh's frame.
    bounds: Aabb,
}

impl SharedMesh {
    /// The mesh of triangles `tri` (vertices in its own frame), and its
    /// tree; `extent` bounds every coordinate of a ray moved into the
    /// frame (the tree's boxes are padded in proportion, as every tree's).
    pub fn new(tri: impl ExactSizeIterator<Item = [[f32; 3]; 3]>, extent: f32) -> SharedMesh {
        let mut t = Triangles::default();
        t.reserve(tri.len());
        let mut bounds = Aabb::EMPTY;
        for (k, v) in tri.enumerate() {
            for p in v {
                bounds.grow(&Aabb { min: p, max: p });
            }
            t.push(v, k as u32);
        }
        let tree = Bvh::build_lanes_only(&t, extent, Walk::Wide8);
        SharedMesh { tree, plane: t.take_planes(), bounds }
    }

    /// The number of triangles.
    pub fn len(&self) -> usize {
        self.plane.len()
    }

    pub fn is_empty(&self) -> bool {
        self.plane.is_empty()
    }
}

/// One placement of a shared mesh: the turn about y (`x' = cos x + sin z,
/// z' = -sin x + cos z`, the groups' rule) and the move, each rounded once
/// to f32, the hit index of its triangle 0, and which mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LeafInstance {
    pub cos: f32,
    pub sin: f32,
    pub t: [f32; 3],
    /// `INSTANCE_BASE + first`: the hit index of the instance's triangle 0.
    pub first: u32,
    pub mesh: u32,
}

impl LeafInstance {
    /// A point of the world in the mesh's frame: the move undone, then the turn.
    #[inline(always)]
    fn frame_point(&self, p: V3<f32>) -> V3<f32> {
        self.turn_back(V3::new(p.x - self.t[0], p.y - self.t[1], p.z - self.t[2]))
    }

    /// A direction of the world in the mesh's frame (the turn undone).
    #[inline(always)]
    fn turn_back(&self, v: V3<f32>) -> V3<f32> {
        let (c, s) = (self.cos, self.sin);
        V3::new(c * v.x - s * v.z, v.y, s * v.x + c * v.z)
    }

    /// A direction of the mesh's frame in the world (the turn).
    #[inline(always)]
    fn turn(&self, v: V3<f32>) -> V3<f32> {
        let (c, s) = (self.cos, self.sin);
        V3::new(c * v.x + s * v.z, v.y, c * v.z - s * v.x)
    }

    /// The ray `o + t d` (world) against the instance's mesh, improving
    /// `best`: the ray moved into the mesh's frame (its `t` is the world's:
    /// the turn keeps lengths) walks the mesh's tree; with `ANY`, to its
    /// first hit below `best.t`.
    #[inline(always)]
    fn search<C: Counter, const ANY: bool>(
        &self,
        mesh: &SharedMesh,
        o: V3<f32>,
        d: V3<f32>,
        best: &mut Closest<f32>,
        counter: &mut C,
    ) {
        let (ol, dl) = (self.frame_point(o), self.turn_back(d));
        let local = mesh.tree.walk_one_wide::<C, ANY>(ol, dl, 0.0, Closest { t: best.t, index: MISS }, counter);
        if local.index != MISS {
            best.offer(true, local.t, self.first + local.index);
        }
    }
}

/// An instance tree's leaves as the one-ray walk reads them: the instances
/// in leaf order, and the meshes they place.
#[derive(Clone, Debug, Default)]
pub struct InstanceLanes {
    rec: Vec<LeafInstance>,
    meshes: Arc<Vec<SharedMesh>>,
}

impl Leaf for LeafInstance {
    type Setup<R: Real> = ();
    type Lanes = InstanceLanes;
    /// An instance's leaf is a walk of its mesh's tree: the nearest first,
    /// whose hit can spare the others' walks.
    const LEAVES_NEAR_TO_FAR: bool = true;

    fn setup<R: Real>(_o: V3<R>, _d: V3<R>) {}

    /// An instance is searched from its tree's lanes, which hold its mesh
    /// ([`Leaf::test_lanes`]): [`Instances`] is always searched by its tree
    /// or by its own brute force ([`Primitive::brute`]), never by this
    /// test, which has no mesh to walk.
    fn test<R: Real, C: Counter>(
        &self,
        _o: V3<R>,
        _d: V3<R>,
        _time: R,
        _setup: &(),
        _best: &mut Closest<R>,
        _counter: &mut C,
    ) {
        unreachable!("an instance is searched with its mesh: Instances' tree or brute force")
    }

    fn lanes(leaf: impl Iterator<Item = Self>, len: usize) -> InstanceLanes {
        let mut rec = Vec::with_capacity(len);
        rec.extend(leaf);
        InstanceLanes { rec, meshes: Arc::default() }
    }

    #[inline(always)]
    fn test_lanes<C: Counter, const ANY: bool>(
        lanes: &InstanceLanes,
        _leaf: &[Self],
        start: usize,
        count: usize,
        ray: &OneRay<Self>,
        best: &mut Closest<f32>,
        counter: &mut C,
    ) {
        for inst in &lanes.rec[start..start + count] {
            inst.search::<C, ANY>(&lanes.meshes[inst.mesh as usize], ray.o, ray.d, best, counter);
            if ANY && best.index != MISS {
                return;
            }
        }
    }
}

/// The instances of a scene, in hit-index order, with the meshes they place
/// and each one's material (its handle and the wavefront's shading record's
/// material slots).
#[derive(Clone, Debug, Default)]
pub struct Instances {
    rec: Vec<LeafInstance>,
    meshes: Arc<Vec<SharedMesh>>,
    /// Each instance's box in the world (its mesh's box, turned and moved;
    /// unpadded).
    boxes: Vec<Aabb>,
    pub kind: Vec<Kind>,
    pub row: Vec<u32>,
    /// Each instance's material's albedo and parameter, the last four slots
    /// of a shading record (`super::Shade`).
    pub material: Vec<[f32; 4]>,
    /// The instanced triangles (every instance's), the hit indices' range.
    triangles: u32,
}

impl Instances {
    /// The instances over `meshes`, none placed yet.
    pub fn new(meshes: Vec<SharedMesh>) -> Instances {
        Instances { meshes: Arc::new(meshes), ..Instances::default() }
    }

    /// Places mesh `mesh` turned by `(cos, sin)` about y, then moved by `t`
    /// (f64, each rounded once), with its material's handle (`kind`, `row`).
    /// Instanced triangles number below `2^30` (the caller's bound).
    pub fn push(&mut self, mesh: usize, (cos, sin): (f64, f64), t: [f64; 3], kind: Kind, row: u32) {
        let m = &self.meshes[mesh];
        let leaf = LeafInstance {
            cos: cos as f32,
            sin: sin as f32,
            t: t.map(|x| x as f32),
            first: INSTANCE_BASE + self.triangles,
            mesh: mesh as u32,
        };
        let count = u32::try_from(m.len()).expect("a mesh's triangles are bounded");
        self.triangles = self.triangles.checked_add(count).filter(|&n| n <= 1 << 30).expect("bounded by the caller");
        // The box: the mesh's corners turned and moved in f64, rounded out.
        let mut b = Aabb::EMPTY;
        for c in 0..8 {
            let p: [f64; 3] =
                std::array::from_fn(|a| f64::from(if c >> a & 1 == 0 { m.bounds.min[a] } else { m.bounds.max[a] }));
            let w = [cos * p[0] + sin * p[2] + t[0], p[1] + t[1], -sin * p[0] + cos * p[2] + t[2]];
            b.grow(&Aabb { min: w.map(round_down), max: w.map(round_up) });
        }
        self.rec.push(leaf);
        self.boxes.push(b);
        self.kind.push(kind);
        self.row.push(row);
        self.material.push([0.0; 4]);
    }

    pub fn len(&self) -> usize {
        self.rec.len()
    }

    pub fn is_empty(&self) -> bool {
        self.rec.is_empty()
    }

    /// The instances' tree: over their world boxes, walked one ray at a
    /// time, each leaf's instances searched with their meshes.
    pub fn tree(&self, extent: f32) -> Bvh<LeafInstance> {
        let mut tree = Bvh::build_lanes_only(self, extent, Walk::Searches);
        tree.lanes_mut().meshes = self.meshes.clone();
        tree
    }

    /// The instance whose triangles hit index `h` (instanced) names, and
    /// the triangle's place in its mesh.
    #[inline]
    pub fn of(&self, h: u32) -> (usize, usize) {
        let i = self.rec.partition_point(|r| r.first <= h) - 1;
        (i, (h - self.rec[i].first) as usize)
    }

    /// The surface of instanced hit `h` at `t` along the world ray (`o`,
    /// `d`), and the instance: the triangle's plane turned and moved to the
    /// world, the quads' surface on it, and the offset of the module's
    /// rule.
    #[inline]
    pub fn surface(&self, o: V3<f32>, d: V3<f32>, t: f32, h: u32) -> (Surface<f32>, usize) {
        let (i, k) = self.of(h);
        let inst = &self.rec[i];
        let [nx, ny, nz, dn] = self.meshes[inst.mesh as usize].plane[k];
        let n = inst.turn(V3::new(nx, ny, nz));
        let dn_world = dn + (n.x * inst.t[0] + n.y * inst.t[1] + n.z * inst.t[2]);
        let mut srf = quad_surface(o, d, t, n, dn_world);
        let moved = inst.t[0].abs().max(inst.t[1].abs()).max(inst.t[2].abs());
        srf.offset += (moved + dn.abs()) * (2.0 * OFFSET_ULPS);
        (srf, i)
    }
}

/// `x` rounded to an f32 at most `x`.
fn round_down(x: f64) -> f32 {
    let r = x as f32;
    if f64::from(r) > x {
        r.next_down()
    } else {
        r
    }
}

/// `x` rounded to an f32 at least `x`.
fn round_up(x: f64) -> f32 {
    let r = x as f32;
    if f64::from(r) < x {
        r.next_up()
    } else {
        r
    }
}

impl Primitive for Instances {
    type Leaf = LeafInstance;
    const GENERAL: bool = true;
    const WALK_ONE_RAY: bool = true;

    fn count(&self) -> usize {
        self.rec.len()
    }

    fn leaf(&self, k: usize) -> LeafInstance {
        self.rec[k]
    }

    fn bounds(&self, k: usize, pad: f32) -> Aabb {
        Aabb::padded(self.boxes[k].min, self.boxes[k].max, pad)
    }

    fn extent(&self, extent: f32) -> f32 {
        self.boxes.iter().flat_map(|b| b.min.iter().chain(&b.max)).fold(extent.abs(), |m, x| m.max(x.abs()))
    }

    /// Brute force over the instances: each lane of `live` against every
    /// instance in index order (each instance's mesh by its tree), the
    /// lanes one at a time.
    fn brute<R: Real, C: Counter, const ANY: bool>(
        &self,
        o: V3<R>,
        d: V3<R>,
        _time: R,
        best: &mut Closest<R>,
        counter: &mut C,
    ) {
        // Lane by lane; a lane's offer changes that lane of `best` alone.
        for k in 0..R::LANES {
            let mut b = Closest { t: best.t.lane(k), index: R::lane_u(best.index, k) };
            if b.t == f32::NEG_INFINITY {
                continue;
            }
            let (o, d) = (o.lane(k), d.lane(k));
            for inst in &self.rec {
                inst.search::<C, ANY>(&self.meshes[inst.mesh as usize], o, d, &mut b, counter);
                if ANY && b.index != MISS {
                    break;
                }
            }
            if b.index != MISS {
                let lane = R::from_fn(|j| if j == k { 1.0 } else { 0.0 }).gt(R::splat(0.5));
                best.offer(lane, R::splat(b.t), R::u_splat(b.index));
            }
        }
    }
}
