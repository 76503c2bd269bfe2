//! Triangles (meshes, in world space): their records, the watertight hit
//! test over [`Real`] (one formula for the scalar kernel and every lane
//! width), closest hit and any hit, and what a hit's surface reads.
//!
//! Triangle `i` of the scene's meshes is hit index `TRIANGLE_BASE + i`
//! ([`super::hit`]). A hit's surface is a flat surface: the quads' surface
//! and offset rule ([`super::quad_surface`]) on the triangle's plane (its
//! unit normal and offset, 16 bytes a triangle, [`Triangles::plane`]); its
//! material is its mesh's ([`Triangles::mesh`], 4 bytes a triangle). Only
//! the search and where the plane is read from differ from a quad's.
//!
//! # The test: inside by edge functions, `t` by the plane
//!
//! **Inside or outside** is decided as in Woop, Benthin and Wald (2013),
//! "Watertight ray/triangle intersection". Per ray, once per search
//! ([`Leaf::setup`]): the axis `kz` along which `|d|` is largest, the two
//! others `kx`, `ky` in cyclic order, and the shear `sx = d_kx / d_kz`,
//! `sy = d_ky / d_kz`. Per vertex `v`: `a = v - o`, projected along the ray
//! to `(a_kx - sx a_kz, a_ky - sy a_kz)`. The ray passes through the
//! projected triangle's inside when the three edge functions
//! `e(P, Q) = Q.x P.y - Q.y P.x` of its edges have one sign (zero counting as
//! either). Every operation is a single IEEE operation, no fused
//! multiply-add (so every build computes the same bits):
//!
//! * **A vertex is projected the same way in every triangle** that holds it
//!   (the same operations on the same floats), so two triangles that share
//!   an edge see the same two projected points.
//! * **An edge's function is exactly negated** in the triangle on its other
//!   side (`e(Q, P) = -e(P, Q)`: the two products commute exactly, and
//!   `x - y = -(y - x)` in IEEE arithmetic).
//! * **Its sign is right or zero**: rounding is monotonic, so
//!   `fl(a b) - fl(c d)` never has the sign opposite to `a b - c d`'s.
//!
//! So a ray through the inside of a closed mesh's surface, an edge or a
//! vertex passes the test of at least one triangle there: the mesh does not
//! leak (where the exact sign was lost to a zero both neighbours take the
//! ray, and the closest-hit rule decides). A ray in the triangle's plane
//! (`e` sums to 0) misses it.
//!
//! **The distance** is Woop's too: `t = (u a_kz + v b_kz + w c_kz) / ((u + v
//! + w) d_kz)` with `u, v, w` the edge functions (the hit's barycentric
//! weights, times their sum) and `a_kz, b_kz, c_kz` the vertices' unprojected
//! coordinates along `kz`: a weighted mean of the distances at which the ray
//! reaches the vertices' `kz` coordinates, so the hit lies in the triangle's
//! box up to a few units of roundoff of the vertices' distances, far inside
//! the tree's padding (brute force and the tree agree bit for bit). A hit
//! needs `0 < t < inf`.
//!
//! **Self-hits** are prevented by the plane, as for a quad: a hit also needs
//! the origin in front of the plane the ray goes toward, `(dn - n.o) (n.d) >
//! 0`, with the unit normal `n` and `dn = n.v0` computed in f64 and rounded
//! once. A new ray leaving the surface starts off the plane by the quads'
//! offset (`32u (|p|_inf + |dn|)`), far above the error of `dn - n.o` (about
//! `3u (|o| + |dn|)`), so it cannot find the triangle it leaves, however
//! large the triangle (the error of `t` grows with the triangle's size; the
//! plane's sign does not).

use super::hit::{Closest, MISS, TRIANGLE_BASE};
use super::primitive::{Leaf, OneRay, Primitive};
use super::quads::quad_surface;
use super::slab::Aabb;
use super::surface::Surface;
use super::work::{Counter, Work};
use crate::handle::Kind;
use crate::real::Real;
use crate::vec3::V3;
use wide::f32x8;

/// One triangle as a leaf holds it: its vertices (world space), its plane
/// (unit normal, `n.v0`) and its hit index.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct LeafTriangle {
    pub v: [[f32; 3]; 3],
    pub n: [f32; 3],
    pub dn: f32,
    pub index: u32,
}

/// Triangles in hit-index order, triangle `k` of hit index `base + k`:
/// their vertices while a search needs them (brute force, a tree's build),
/// their planes, and for the scene's meshes each triangle's mesh and each
/// mesh's material.
///
/// Memory: 36 bytes a triangle for its vertices (dropped once a tree holds
/// them, [`Triangles::release`]), 16 for its plane, and 4 for its mesh.
#[derive(Clone, Debug, Default)]
pub struct Triangles {
    v: Vec<[[f32; 3]; 3]>,
    /// Per triangle: its plane's unit normal and `n.v0` ([`plane`]), for
    /// the test's side of the plane and a hit's surface.
    pub plane: Vec<[f32; 4]>,
    /// Per triangle of the scene's meshes: its mesh, a row of the tables
    /// below (empty for triangles pushed without one: a light's or a shared
    /// mesh's, whose materials are kept elsewhere).
    pub mesh: Vec<u32>,
    /// Per mesh: its material's kind and row, and its shading record's
    /// material slots (albedo and parameter, as `super::Shade`'s).
    pub kind: Vec<Kind>,
    pub row: Vec<u32>,
    pub material: Vec<[f32; 4]>,
    /// The hit index of triangle 0.
    base: u32,
    len: usize,
}

impl Triangles {
    pub fn len(&self) -> usize {
        self.len
    }
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Appends the triangle `v` whose hit index is `index`: the first
    /// triangle's index is the base, the others follow it one by one. Its
    /// plane is computed from the f32 vertices in f64 ([`plane`]). A
    /// degenerate triangle (zero area) has no normal and is never hit.
    pub fn push(&mut self, v: [[f32; 3]; 3], index: u32) {
        if self.len == 0 {
            self.base = index;
        }
        assert_eq!(index, self.base.wrapping_add(self.len as u32), "consecutive hit indices");
        let (n, dn) = plane(v);
        self.v.push(v);
        self.plane.push([n[0], n[1], n[2], dn]);
        self.len += 1;
    }

    /// Appends the triangle `v` of the scene's mesh `mesh` (a row of
    /// [`Triangles::push_mesh`]); returns its hit index, `TRIANGLE_BASE +
    /// i` for the `i`-th.
    pub fn push_in(&mut self, v: [[f32; 3]; 3], mesh: u32) -> u32 {
        let index = TRIANGLE_BASE + self.len as u32;
        self.push(v, index);
        self.mesh.push(mesh);
        index
    }

    /// Appends a mesh of material kind `kind` and row `row`; returns its
    /// row (its shading slots, [`Triangles::material`], are filled when the
    /// scene is prepared).
    pub fn push_mesh(&mut self, kind: Kind, row: u32) -> u32 {
        self.kind.push(kind);
        self.row.push(row);
        self.material.push([0.0; 4]);
        self.kind.len() as u32 - 1
    }

    /// Room for `n` more triangles of the scene's meshes, exactly (a
    /// mesh's triangles are its largest allocation while its tree is
    /// built).
    pub fn reserve(&mut self, n: usize) {
        self.v.reserve_exact(n);
        self.plane.reserve_exact(n);
        self.mesh.reserve_exact(n);
    }

    /// Drops the vertices once a tree holds them (the tree is then the only
    /// search: brute force needs them); the planes and meshes stay, for
    /// the surfaces.
    pub fn release(&mut self) {
        self.v = Vec::new();
    }

    /// Takes the planes out (a shared mesh keeps them beside its tree).
    pub fn take_planes(&mut self) -> Vec<[f32; 4]> {
        std::mem::take(&mut self.plane)
    }

    /// The bytes the triangles hold on the heap (their arrays'
    /// capacities; a tree's are its own, [`super::Bvh::heap_bytes`]).
    pub fn heap_bytes(&self) -> usize {
        self.v.capacity() * std::mem::size_of::<[[f32; 3]; 3]>()
            + self.plane.capacity() * 16
            + self.mesh.capacity() * 4
            + self.kind.capacity()
            + self.row.capacity() * 4
            + self.material.capacity() * 16
    }

    /// Triangle `i`'s mesh material: kind and row.
    #[inline(always)]
    pub fn material_of(&self, i: usize) -> (Kind, u32) {
        let m = self.mesh[i] as usize;
        (self.kind[m], self.row[m])
    }

    /// The material kind of the triangle of hit index `h`; an index that is
    /// not one of these triangles' reads the last one's (a miss, whose
    /// value is not taken). Not for no triangles.
    #[inline(always)]
    pub fn kind_of_hit(&self, h: u32) -> Kind {
        let i = (h.wrapping_sub(self.base) as usize).min(self.len.saturating_sub(1));
        self.kind[self.mesh[i] as usize]
    }

    /// The surface of the hit on triangle `i` at `t` along the ray (`o`,
    /// `d`), as the quads' rule makes it on the triangle's plane.
    #[inline(always)]
    pub fn surface(&self, o: V3<f32>, d: V3<f32>, t: f32, i: usize) -> Surface<f32> {
        let [nx, ny, nz, dn] = self.plane[i];
        quad_surface(o, d, t, V3::new(nx, ny, nz), dn)
    }

    /// The shading record (`super::Shade`'s slots: the plane's unit normal
    /// and offset, the albedo, the parameter) of the triangle of hit index
    /// `h`; an index that is not one of these triangles' reads the last
    /// one's (a lane of another kind, whose value is not taken). Not for no
    /// triangles.
    #[inline(always)]
    pub fn shade_of(&self, h: u32) -> [f32; 8] {
        let i = (h.wrapping_sub(self.base) as usize).min(self.len.saturating_sub(1));
        let ([nx, ny, nz, dn], m) = (self.plane[i], self.mesh[i] as usize);
        let [a0, a1, a2, p] = self.material[m];
        [nx, ny, nz, dn, a0, a1, a2, p]
    }
}

/// The plane of the triangle `v`: its unit normal `unit((v1 - v0) x (v2 -
/// v0))` and `n.v0`, in f64 from the f32 vertices, each rounded once; zeros
/// for a degenerate triangle (no normal: every ray misses it, its surface
/// is never computed).
pub fn plane(v: [[f32; 3]; 3]) -> ([f32; 3], f32) {
    let d = |a: [f32; 3]| glam::DVec3::from_array(a.map(f64::from));
    let (v0, v1, v2) = (d(v[0]), d(v[1]), d(v[2]));
    let c = (v1 - v0).cross(v2 - v0);
    let len = c.length();
    if !(len > 0.0) || !len.is_finite() {
        return ([0.0; 3], 0.0);
    }
    let n = c / len;
    (n.to_array().map(|x| x as f32), n.dot(v0) as f32)
}

/// The rays' projection ([`Leaf::setup`]): which axis is `kz`, and the
/// shear.
#[derive(Clone, Copy, Debug)]
pub struct Projection<R: Real> {
    /// `kz` is x (then `kx`, `ky` are y, z).
    along_x: R::Mask,
    /// `kz` is y (then z, x); neither: `kz` is z (then x, y).
    along_y: R::Mask,
    sx: R,
    sy: R,
    /// `d_kz`.
    dz: R,
}

/// `(a_kx, a_ky, a_kz)` of `a` for the rays' axes.
#[inline(always)]
fn permute<R: Real>(along_x: R::Mask, along_y: R::Mask, a: V3<R>) -> (R, R, R) {
    let kx = R::select(along_x, a.y, R::select(along_y, a.z, a.x));
    let ky = R::select(along_x, a.z, R::select(along_y, a.x, a.y));
    let kz = R::select(along_x, a.x, R::select(along_y, a.y, a.z));
    (kx, ky, kz)
}

impl<R: Real> Projection<R> {
    /// The projection along `d` (a zero or NaN direction gives NaN shears:
    /// every test misses).
    #[inline(always)]
    pub fn new(d: V3<R>) -> Self {
        let (ax, ay, az) = (d.x.abs(), d.y.abs(), d.z.abs());
        let along_x = ax.ge(ay) & ax.ge(az);
        let along_y = !along_x & ay.ge(az);
        let (dx, dy, dz) = permute(along_x, along_y, d);
        Projection { along_x, along_y, sx: dx / dz, sy: dy / dz, dz }
    }

    /// A vertex relative to the origins, its axes permuted (`(x, y, z)`
    /// along `kx`, `ky`, `kz`), projected along the rays; and its
    /// coordinate along `kz`.
    #[inline(always)]
    fn point(&self, (x, y, z): (R, R, R)) -> ((R, R), R) {
        ((x - self.sx * z, y - self.sy * z), z)
    }
}

impl Projection<f32> {
    /// One ray's axes `[kx, ky, kz]` (as [`permute`] orders them), for
    /// loading a leaf's coordinates already permuted.
    #[inline(always)]
    fn axes(&self) -> [usize; 3] {
        match (self.along_x, self.along_y) {
            (true, _) => [1, 2, 0],
            (false, true) => [2, 0, 1],
            (false, false) => [0, 1, 2],
        }
    }
}

/// The edge function of the projected edge from `p` to `q`.
#[inline(always)]
fn edge<R: Real>(p: (R, R), q: (R, R)) -> R {
    q.0 * p.1 - q.1 * p.0
}

/// The triangle test: the hit mask and `t` of the rays `o + t d` (with
/// their projection `pr`) against `tri`, as the module describes.
#[inline(always)]
pub fn triangle_hit<R: Real>(o: V3<R>, d: V3<R>, pr: &Projection<R>, tri: &LeafTriangle) -> (R::Mask, R) {
    let [v0, v1, v2] = tri.v.map(V3::splat3);
    hit(o, d, pr, [v0, v1, v2], V3::splat3(tri.n), R::splat(tri.dn))
}

/// The test of [`triangle_hit`] with the triangle's values as lanes (one
/// triangle broadcast to a packet's rays, or a leaf's triangles, one a lane,
/// against one ray broadcast): the same operations, so the same bits.
#[inline(always)]
fn hit<R: Real>(o: V3<R>, d: V3<R>, pr: &Projection<R>, v: [V3<R>; 3], n: V3<R>, dn: R) -> (R::Mask, R) {
    hit_permuted(o, d, pr, v.map(|v| permute(pr.along_x, pr.along_y, v - o)), n, dn)
}

/// The test of [`hit`] from the vertices relative to the origins, already
/// permuted (the same values, in the same operations).
#[inline(always)]
fn hit_permuted<R: Real>(o: V3<R>, d: V3<R>, pr: &Projection<R>, p: [(R, R, R); 3], n: V3<R>, dn: R) -> (R::Mask, R) {
    let ((a, az), (b, bz), (c, cz)) = (pr.point(p[0]), pr.point(p[1]), pr.point(p[2]));
    let (u, v, w) = (edge(b, c), edge(c, a), edge(a, b));
    let zero = R::splat(0.0);
    let inside = (u.ge(zero) & v.ge(zero) & w.ge(zero)) | (u.le(zero) & v.le(zero) & w.le(zero));
    let det = u + v + w;
    let t = (u * az + v * bz + w * cz) / (det * pr.dz);
    let ahead = ((dn - n.dot(o)) * n.dot(d)).gt(zero);
    let hit = inside & ahead & t.gt(zero) & t.lt(R::splat(f32::INFINITY));
    (hit, t)
}

/// A tree's triangles as lanes, in leaf order, padded by 8 triangles no
/// ray hits (no normal), for the one-ray walk's test of a leaf's triangles
/// at once ([`Leaf::test_lanes`]).
#[derive(Clone, Debug, Default)]
pub struct TriangleLanes {
    /// [`SECTIONS`] arrays of `stride` floats, one a value of the test:
    /// vertex `k`'s coordinate `a` in section `3a + k`, the normal's
    /// coordinate `a` in `9 + a`, `n.v0` in 12. All of one length, so a
    /// leaf's 13 loads take one bounds check. (One allocation of all 13
    /// raised the process's peak memory by 20 bytes a triangle: the
    /// allocator maps it anew instead of reusing what the build freed.)
    sections: [Box<[f32]>; SECTIONS],
    /// The triangles, padding included: every section's length.
    stride: usize,
    index: Vec<u32>,
}

/// The sections of [`TriangleLanes`].
const SECTIONS: usize = 13;

impl TriangleLanes {
    /// Lanes `start..start + 8` of every section, checked once.
    #[inline(always)]
    fn window(&self, start: usize) -> Window<'_> {
        assert!(start + 8 <= self.stride, "8 lanes: the lanes are padded");
        Window { lanes: self, start }
    }
}

/// Lanes `start..start + 8` of [`TriangleLanes`], `start + 8 <= stride`.
struct Window<'a> {
    lanes: &'a TriangleLanes,
    start: usize,
}

impl Window<'_> {
    /// Section `s`'s 8 lanes (the check of `s` folds away: every caller's
    /// section is a constant, or bounded as in [`Window::along`]).
    #[inline(always)]
    fn ld(&self, s: usize) -> f32x8 {
        let section = &self.lanes.sections[s];
        debug_assert_eq!(section.len(), self.lanes.stride);
        // SAFETY: `start + 8 <= stride` (`window`), and every section is
        // `stride` long (`lanes`).
        f32x8::new(unsafe { section.as_ptr().add(self.start).cast::<[f32; 8]>().read() })
    }

    /// The three vertices' coordinates along axis `a` (sections `3a` to
    /// `3a + 2`): one product of the stride for the three loads.
    #[inline(always)]
    fn along(&self, a: usize) -> [f32x8; 3] {
        let first = 3 * a.min(2);
        [self.ld(first), self.ld(first + 1), self.ld(first + 2)]
    }
}

impl Leaf for LeafTriangle {
    type Setup<R: Real> = Projection<R>;
    type Lanes = TriangleLanes;

    fn lanes(leaf: impl Iterator<Item = Self>, len: usize) -> TriangleLanes {
        // Exactly their length: a mesh's lanes are most of its memory.
        let stride = len + 8;
        let mut sections: [Vec<f32>; SECTIONS] = std::array::from_fn(|_| Vec::with_capacity(stride));
        let mut index = Vec::with_capacity(stride);
        let pad = LeafTriangle { index: MISS, ..LeafTriangle::default() };
        for t in leaf.chain(std::iter::repeat_n(pad, 8)).take(stride) {
            let values: [f32; SECTIONS] = std::array::from_fn(|s| match s {
                0..9 => t.v[s % 3][s / 3],
                9..12 => t.n[s - 9],
                _ => t.dn,
            });
            for (section, x) in sections.iter_mut().zip(values) {
                section.push(x);
            }
            index.push(t.index);
        }
        assert_eq!(index.len(), stride, "{len} leaf records");
        TriangleLanes { sections: sections.map(Vec::into_boxed_slice), stride, index }
    }

    fn lanes_bytes(lanes: &TriangleLanes) -> usize {
        lanes.sections.iter().map(|s| s.len() * 4).sum::<usize>() + lanes.index.capacity() * 4
    }

    /// The leaf's triangles 8 at a time, the ray broadcast; hits offered in
    /// lane order (the tie rule does not depend on it). The ray's axes are
    /// one for all 8 lanes, so the coordinates are loaded in its order:
    /// the test's permutation (18 blends) is left to the loads' addresses.
    #[inline(always)]
    fn test_lanes<C: Counter, const ANY: bool>(
        lanes: &TriangleLanes,
        _leaf: &[Self],
        start: usize,
        count: usize,
        ray: &OneRay<Self>,
        best: &mut Closest<f32>,
        counter: &mut C,
    ) {
        counter.work(Work::Triangle, count as u32);
        let w = lanes.window(start);
        let [kx, ky, kz] = ray.setup.axes();
        let o = ray.o.to_array();
        let (ox, oy, oz) = (f32x8::splat(o[kx]), f32x8::splat(o[ky]), f32x8::splat(o[kz]));
        let (x, y, z) = (w.along(kx), w.along(ky), w.along(kz));
        let p = |k: usize| (x[k] - ox, y[k] - oy, z[k] - oz);
        let n = V3::new(w.ld(9), w.ld(10), w.ld(11));
        let (hit, t) = hit_permuted(ray.o8, ray.d8, &ray.setup8, [p(0), p(1), p(2)], n, w.ld(12));
        let mut m = hit.to_bitmask() & ((1u32 << count) - 1);
        if m == 0 {
            return;
        }
        let t = t.to_array();
        while m != 0 {
            let k = m.trailing_zeros() as usize;
            m &= m - 1;
            best.offer(true, t[k], lanes.index[start + k]);
        }
    }

    #[inline(always)]
    fn setup<R: Real>(_o: V3<R>, d: V3<R>) -> Projection<R> {
        Projection::new(d)
    }

    #[inline(always)]
    fn test<R: Real, C: Counter>(
        &self,
        o: V3<R>,
        d: V3<R>,
        _time: R,
        setup: &Projection<R>,
        best: &mut Closest<R>,
        counter: &mut C,
    ) {
        counter.work(Work::Triangle, 1);
        let (hit, t) = triangle_hit(o, d, setup, self);
        best.offer(hit, t, R::u_splat(self.index));
    }
}

impl Primitive for Triangles {
    type Leaf = LeafTriangle;
    const WALK_ONE_RAY: bool = true;

    fn count(&self) -> usize {
        self.len
    }

    #[inline(always)]
    fn leaf(&self, k: usize) -> LeafTriangle {
        let [nx, ny, nz, dn] = self.plane[k];
        LeafTriangle { v: self.v[k], n: [nx, ny, nz], dn, index: self.base.wrapping_add(k as u32) }
    }

    /// The vertices' box, padded: a flat triangle's box gets the padding's
    /// thickness, far above the rounding of the plane's `t` (the hit point
    /// lies within a few units of roundoff of the plane), so brute force and
    /// the tree agree bit for bit.
    fn bounds(&self, k: usize, pad: f32) -> Aabb {
        let v = &self.v[k];
        let min = std::array::from_fn(|a| v[0][a].min(v[1][a]).min(v[2][a]));
        let max = std::array::from_fn(|a| v[0][a].max(v[1][a]).max(v[2][a]));
        Aabb::padded(min, max, pad)
    }

    /// The triangles' own extent too: the largest vertex coordinate.
    fn extent(&self, extent: f32) -> f32 {
        self.v.iter().flatten().flatten().fold(extent.abs(), |m, x| m.max(x.abs()))
    }
}
