//! Instances flattened into world-space primitives: boxes become their six
//! quads, groups apply `rotate_y` then `translate` (the book's instance order)
//! to their members, once, in f64, each result rounded to f32 once.
//!
//! Flattening avoids the book's known instance pitfalls by construction (the
//! issue numbers are those of the books' repository,
//! RayTracing/raytracing.github.io): there is no object space at render time, so the front face is
//! decided in world space only (#965), the rotation is applied once with the
//! book's sign, `x' = cos x + sin z, z' = -sin x + cos z` (#544), and the
//! bounding box of a rotated box is that of its world-space quads, each
//! covering its four corners (#749, #1402).

use super::{
    Group, Material, Medium, MediumBoundary, Mesh, MeshShape, Mode, ObjMesh, ObjMeshes, Quad, QuadBox, Scene, Shape,
    Sphere,
};
use crate::choice::EstimatorChoice;
use std::collections::HashMap;
use std::sync::Arc;

/// A scene's primitives in world space, in the one global order the
/// closest-hit tie rule uses: spheres (the scene's, then each group's), then
/// quads (the scene's, the scene's boxes, then each group's quads and boxes).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Flat {
    pub spheres: Vec<Sphere>,
    pub quads: Vec<Quad>,
    /// The media (the scene's, then each group's), in the order of their
    /// hit indices and sampler dimensions.
    pub media: Vec<FlatMedium>,
    /// The boxes, each in its own frame, with the index of its first face in
    /// `quads` (its six faces follow, in [`box_quads`]'s order).
    pub cuboids: Vec<FlatCuboid>,
    /// The meshes (the scene's, then each group's), their vertices in world
    /// space; their triangles come after every quad in the tie order.
    pub meshes: Vec<FlatMesh>,
    /// The meshes several groups place ([`Sharing`]), each once, in its own
    /// frame.
    pub shared: Vec<FlatShared>,
    /// Each group's placement of a shared mesh, in group order; their
    /// triangles come after every moving sphere in the tie order.
    pub instances: Vec<FlatInstance>,
}

/// A mesh several groups place, held once: its vertices in its own frame
/// (an OBJ file's times the mesh's `scale`, each rounded once to f32) and
/// its triangles.
#[derive(Clone, Debug, PartialEq)]
pub struct FlatShared {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Arc<Vec<[u32; 3]>>,
}

impl FlatShared {
    /// Triangle `k`'s vertices (the mesh's frame).
    pub fn triangle(&self, k: usize) -> [[f32; 3]; 3] {
        self.triangles[k].map(|i| self.positions[i as usize])
    }
}

/// A group's placement of shared mesh `mesh`: its turn about y (`cos`,
/// `sin`, the groups' rule) and its move, in f64, and its material.
#[derive(Clone, Debug, PartialEq)]
pub struct FlatInstance {
    pub mesh: usize,
    pub cos: f64,
    pub sin: f64,
    pub translate: [f64; 3],
    pub material: Material,
}

/// Which meshes are instanced: an OBJ mesh (one file read, one `scale`)
/// that two groups or more place, flat shaded (its file gives no vertex
/// normals) and not a light, is held once in its own frame and placed by
/// each group (`geometry::instances`); every other mesh is flattened into
/// world space. The scene's own meshes (outside groups) are flattened.
pub struct Sharing {
    /// Placements per mesh key ([`Sharing::key`]).
    placed: HashMap<(usize, u32), usize>,
}

impl Sharing {
    /// The placements of the scene's group meshes that could be shared.
    pub fn of(scene: &Scene, objs: &ObjMeshes) -> Sharing {
        let mut placed = HashMap::new();
        for g in &scene.groups {
            for m in &g.meshes {
                if let Some(key) = Sharing::key(m, objs) {
                    *placed.entry(key).or_insert(0) += 1;
                }
            }
        }
        Sharing { placed }
    }

    /// The key of a group's mesh that could be shared: its file's read
    /// (shared by every name of one file) and its scale's bits.
    fn key(m: &Mesh, objs: &ObjMeshes) -> Option<(usize, u32)> {
        let MeshShape::Obj { ref file, scale } = m.shape else { return None };
        let obj = objs.get(file)?;
        let light = matches!(m.material, Material::DiffuseLight { .. });
        (obj.normals.is_none() && !light).then(|| (Arc::as_ptr(&obj.positions) as usize, scale.to_bits()))
    }

    /// Whether a group's mesh `m` is instanced, and if so its key.
    pub fn shared(&self, m: &Mesh, objs: &ObjMeshes) -> Option<(usize, u32)> {
        Sharing::key(m, objs).filter(|k| self.placed[k] >= 2)
    }
}

/// A mesh in world space: its vertices (each rounded once to f32 from f64),
/// its triangles (vertex indices; shared by the meshes of one topology, an
/// icosphere level's) and its material.
#[derive(Clone, Debug, PartialEq)]
pub struct FlatMesh {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Arc<Vec<[u32; 3]>>,
    /// A unit normal per position (world space), for smooth shading: an
    /// OBJ file's, turned by its group; `None` for flat shading.
    pub normals: Option<Vec<[f32; 3]>>,
    pub material: Material,
}

impl FlatMesh {
    /// Triangle `k`'s vertices.
    pub fn triangle(&self, k: usize) -> [[f32; 3]; 3] {
        self.triangles[k].map(|i| self.positions[i as usize])
    }

    /// Triangle `k`'s vertex normals, if the mesh has them.
    pub fn triangle_normals(&self, k: usize) -> Option<[[f32; 3]; 3]> {
        self.normals.as_ref().map(|n| self.triangles[k].map(|i| n[i as usize]))
    }
}

/// A box in world space: its centre, its three unit axes (the box's x, y and
/// z turned by its group) and its half sizes along them, in f64 (the kernel
/// side rounds them once), and the index of its first face among the quads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatCuboid {
    pub center: [f64; 3],
    pub axes: [[f64; 3]; 3],
    pub half: [f64; 3],
    pub first: usize,
}

/// A medium in world space; its boundary in f64 (the kernel side rounds it once).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatMedium {
    pub boundary: FlatBoundary,
    pub density: f32,
    pub albedo: [f32; 3],
}

/// A medium's boundary in world space: a sphere, or a box in its own frame
/// (its centre, its three unit axes in world space and its half sizes along
/// them), so that its chord is an exact slab test in that frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FlatBoundary {
    Sphere { center: [f64; 3], radius: f64 },
    Box { center: [f64; 3], axes: [[f64; 3]; 3], half: [f64; 3] },
}

impl FlatBoundary {
    /// The largest absolute coordinate of a point of the boundary (at most; for extents).
    pub fn reach(&self) -> f64 {
        match self {
            FlatBoundary::Sphere { center, radius } => center.iter().fold(0.0f64, |m, x| m.max(x.abs())) + radius.abs(),
            FlatBoundary::Box { center, half, .. } => {
                center.iter().fold(0.0f64, |m, x| m.max(x.abs())) + half.iter().map(|h| h.abs()).sum::<f64>()
            }
        }
    }
}

/// `rotate_y` (degrees) then `translate`, in f64.
#[derive(Clone, Copy, Debug)]
struct Transform {
    cos: f64,
    sin: f64,
    t: [f64; 3],
}

impl Transform {
    const IDENTITY: Transform = Transform { cos: 1.0, sin: 0.0, t: [0.0; 3] };

    fn of(g: &Group) -> Transform {
        let (sin, cos) = match g.rotate_y {
            // Exact for the right angles (sin_cos(pi/2) is not exactly (1, 0)).
            a if a.rem_euclid(90.0) == 0.0 => match (a.rem_euclid(360.0) / 90.0) as u32 {
                0 => (0.0, 1.0),
                1 => (1.0, 0.0),
                2 => (0.0, -1.0),
                _ => (-1.0, 0.0),
            },
            a => (a as f64).to_radians().sin_cos(),
        };
        Transform { cos, sin, t: g.translate.map(f64::from) }
    }

    /// A direction (no translation).
    fn vector(&self, v: [f64; 3]) -> [f64; 3] {
        [self.cos * v[0] + self.sin * v[2], v[1], -self.sin * v[0] + self.cos * v[2]]
    }

    /// Unit axis `i` (x, y, z), turned.
    fn axis(&self, i: usize) -> [f64; 3] {
        self.vector(std::array::from_fn(|j| if i == j { 1.0 } else { 0.0 }))
    }

    fn point(&self, p: [f64; 3]) -> [f64; 3] {
        let r = self.vector(p);
        [r[0] + self.t[0], r[1] + self.t[1], r[2] + self.t[2]]
    }
}

fn f64s(v: [f32; 3]) -> [f64; 3] {
    v.map(f64::from)
}

fn f32s(v: [f64; 3]) -> [f32; 3] {
    v.map(|x| x as f32)
}

/// A quad given in f64 (corner, edges), transformed and rounded.
fn quad(t: &Transform, q: [f64; 3], u: [f64; 3], v: [f64; 3], material: Material) -> Quad {
    Quad { q: f32s(t.point(q)), u: f32s(t.vector(u)), v: f32s(t.vector(v)), material }
}

/// The six faces of the box, as the book's `box(a, b, mat)` (v4) builds
/// them: front, right, back, left, top, bottom, each facing outwards.
pub fn box_quads(b: &QuadBox) -> [([f64; 3], [f64; 3], [f64; 3]); 6] {
    let (a, c) = (f64s(b.a), f64s(b.b));
    let min: [f64; 3] = std::array::from_fn(|i| a[i].min(c[i]));
    let max: [f64; 3] = std::array::from_fn(|i| a[i].max(c[i]));
    let dx = [max[0] - min[0], 0.0, 0.0];
    let dy = [0.0, max[1] - min[1], 0.0];
    let dz = [0.0, 0.0, max[2] - min[2]];
    let neg = |v: [f64; 3]| v.map(|x| -x);
    [
        ([min[0], min[1], max[2]], dx, dy),
        ([max[0], min[1], max[2]], neg(dz), dy),
        ([max[0], min[1], min[2]], neg(dx), dy),
        ([min[0], min[1], min[2]], dz, dy),
        ([min[0], max[1], max[2]], dx, neg(dz)),
        ([min[0], min[1], min[2]], dx, dz),
    ]
}

/// A medium under transform `t`.
fn medium(t: &Transform, m: &Medium) -> FlatMedium {
    let boundary = match m.boundary {
        MediumBoundary::Sphere { center, radius } => {
            FlatBoundary::Sphere { center: t.point(f64s(center)), radius: radius as f64 }
        }
        MediumBoundary::Box { a, b } => {
            let (a, b) = (f64s(a), f64s(b));
            let centre: [f64; 3] = std::array::from_fn(|i| 0.5 * (a[i] + b[i]));
            let half: [f64; 3] = std::array::from_fn(|i| 0.5 * (a[i] - b[i]).abs());
            FlatBoundary::Box { center: t.point(centre), axes: [t.axis(0), t.axis(1), t.axis(2)], half }
        }
    };
    FlatMedium { boundary, density: m.density, albedo: m.albedo }
}

/// A unit icosphere: its vertices (f64) and its triangles (shared by every
/// mesh placed from it).
struct UnitIcosphere {
    unit: Vec<[f64; 3]>,
    triangles: Arc<Vec<[u32; 3]>>,
}

/// The unit icospheres of the levels a scene uses, each made once.
#[derive(Default)]
struct Icospheres(HashMap<u32, UnitIcosphere>);

impl Icospheres {
    fn of(&mut self, level: u32) -> &UnitIcosphere {
        self.0.entry(level).or_insert_with(|| {
            let (unit, t) = crate::mesh::icosphere::unit_icosphere(level)
                .expect("a scene's icosphere levels are validated before it is flattened");
            UnitIcosphere { unit, triangles: Arc::new(t) }
        })
    }
}

/// A mesh under transform `t` (`None`: the identity, the vertices as the
/// mesh's own definition rounds them); an OBJ mesh's from `objs`.
fn mesh(t: Option<&Transform>, m: &Mesh, icospheres: &mut Icospheres, objs: &ObjMeshes) -> FlatMesh {
    match m.shape {
        MeshShape::Icosphere { center, radius, level } => {
            let UnitIcosphere { unit, triangles } = icospheres.of(level);
            let positions = match t {
                None => crate::mesh::icosphere::place(unit, center, radius),
                Some(t) => {
                    let (c, r) = (f64s(center), radius as f64);
                    unit.iter().map(|u| f32s(t.point(std::array::from_fn(|i| c[i] + r * u[i])))).collect()
                }
            };
            FlatMesh { positions, triangles: triangles.clone(), normals: None, material: m.material.clone() }
        }
        MeshShape::Obj { ref file, scale } => {
            let obj = objs.get(file).expect("Scene::flatten_with: every OBJ file the scene names is read first");
            let s = scale as f64;
            let positions = match (t, scale == 1.0) {
                (None, true) => obj.positions.to_vec(),
                (None, false) => obj.positions.iter().map(|p| f32s(f64s(*p).map(|x| s * x))).collect(),
                (Some(t), _) => obj.positions.iter().map(|p| f32s(t.point(f64s(*p).map(|x| s * x)))).collect(),
            };
            // Normals turn with the group (a uniform scale leaves them be),
            // normalized in f64; a zero normal stays zero.
            let turn = t.copied().unwrap_or(Transform::IDENTITY);
            let normals = obj.normals.as_ref().map(|ns| {
                ns.iter()
                    .map(|n| {
                        // (From f32 values: no square underflows in f64.)
                        let v = turn.vector(f64s(*n));
                        if v == [0.0; 3] {
                            [0.0; 3]
                        } else {
                            f32s(crate::mesh::unit(v))
                        }
                    })
                    .collect()
            });
            FlatMesh { positions, triangles: obj.triangles.clone(), normals, material: m.material.clone() }
        }
    }
}

/// The largest absolute coordinate the OBJ mesh `obj` reaches, multiplied by
/// `scale` and moved by `group` (at most: the corners of its bounds).
pub(super) fn obj_reach(group: Option<&Group>, scale: f32, obj: &ObjMesh) -> f64 {
    let t = group.map_or(Transform::IDENTITY, Transform::of);
    let (lo, hi) = (f64s(obj.bounds.0), f64s(obj.bounds.1));
    (0..8)
        .map(|c: usize| {
            let corner: [f64; 3] = std::array::from_fn(|i| scale as f64 * if c >> i & 1 == 0 { lo[i] } else { hi[i] });
            t.point(corner).iter().fold(0.0f64, |m, x| m.max(x.abs()))
        })
        .fold(0.0, f64::max)
}

impl Flat {
    fn add_media(&mut self, t: &Transform, media: &[Medium]) {
        self.media.extend(media.iter().map(|m| medium(t, m)));
    }

    fn add_meshes(&mut self, t: Option<&Transform>, meshes: &[Mesh], icospheres: &mut Icospheres, objs: &ObjMeshes) {
        self.meshes.extend(meshes.iter().map(|m| mesh(t, m, icospheres, objs)));
    }

    /// Places the shared OBJ mesh `m` (its [`Sharing`] key `key`) by
    /// transform `t`, its vertices made in its own frame the first time
    /// (`shared`: key to place in `self.shared`).
    fn add_instance(
        &mut self,
        t: &Transform,
        m: &Mesh,
        key: (usize, u32),
        shared: &mut HashMap<(usize, u32), usize>,
        objs: &ObjMeshes,
    ) {
        let MeshShape::Obj { ref file, scale } = m.shape else { unreachable!("only OBJ meshes are shared") };
        let mesh = *shared.entry(key).or_insert_with(|| {
            let obj = objs.get(file).expect("Scene::flatten_with: every OBJ file the scene names is read first");
            let s = scale as f64;
            let positions = match scale == 1.0 {
                true => obj.positions.to_vec(),
                false => obj.positions.iter().map(|p| f32s(f64s(*p).map(|x| s * x))).collect(),
            };
            self.shared.push(FlatShared { positions, triangles: obj.triangles.clone() });
            self.shared.len() - 1
        });
        let (cos, sin, translate) = (t.cos, t.sin, t.t);
        self.instances.push(FlatInstance { mesh, cos, sin, translate, material: m.material.clone() });
    }

    /// Every primitive's material: the spheres', the quads', the meshes',
    /// the instances'.
    pub fn materials(&self) -> impl Iterator<Item = &Material> {
        let spheres = self.spheres.iter().map(|s| &s.material);
        spheres
            .chain(self.quads.iter().map(|q| &q.material))
            .chain(self.meshes.iter().map(|m| &m.material))
            .chain(self.instances.iter().map(|i| &i.material))
    }

    /// The triangles the instances place, every instance's counted (their
    /// hit indices' range).
    pub fn instanced_triangles(&self) -> u64 {
        self.instances.iter().map(|i| self.shared[i.mesh].triangles.len() as u64).sum()
    }

    /// The number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.triangles.len()).sum()
    }

    fn add(&mut self, t: &Transform, spheres: &[Sphere], quads: &[Quad], boxes: &[QuadBox]) {
        for s in spheres {
            let center1 = s.center1.map(|c| f32s(t.point(f64s(c))));
            self.spheres.push(Sphere {
                center: f32s(t.point(f64s(s.center))),
                center1,
                radius: s.radius,
                material: s.material.clone(),
            });
        }
        for q in quads {
            self.quads.push(quad(t, f64s(q.q), f64s(q.u), f64s(q.v), q.material.clone()));
        }
        for b in boxes {
            let (lo, hi) = (f64s(b.a), f64s(b.b));
            let center: [f64; 3] = std::array::from_fn(|i| 0.5 * (lo[i] + hi[i]));
            self.cuboids.push(FlatCuboid {
                center: t.point(center),
                axes: [t.axis(0), t.axis(1), t.axis(2)],
                half: std::array::from_fn(|i| 0.5 * (lo[i] - hi[i]).abs()),
                first: self.quads.len(),
            });
            for (q, u, v) in box_quads(b) {
                self.quads.push(quad(t, q, u, v, b.material.clone()));
            }
        }
    }
}

#[cfg(test)]
thread_local! {
    /// How many times this thread flattened a scene (tests count a job's flattenings).
    pub(crate) static FLATTENED: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// One group's members in world space, but its meshes ([`mesh_reach`]
/// bounds them).
pub(super) fn group(g: &Group) -> Flat {
    let mut flat = Flat::default();
    flat.add(&Transform::of(g), &g.spheres, &g.quads, &g.boxes);
    flat.add_media(&Transform::of(g), &g.media);
    flat
}

/// The largest absolute coordinate a mesh of group `g` reaches once moved
/// (at most; its vertices are not made); `None` for an OBJ mesh, whose
/// reach is checked once its file is read ([`obj_reach`]).
pub(super) fn mesh_reach(g: &Group, m: &Mesh) -> Option<f64> {
    match m.shape {
        MeshShape::Icosphere { center, radius, .. } => {
            let c = Transform::of(g).point(f64s(center));
            Some(c.iter().fold(0.0f64, |m, x| m.max(x.abs())) + (radius as f64).abs())
        }
        MeshShape::Obj { .. } => None,
    }
}

impl Scene {
    /// The spheres and quads the `book` estimator samples toward: the
    /// scene's `sample_toward` list, else its lights' (static spheres and
    /// quads of `diffuse_light`, groups' included, in world space, from
    /// `flat`, this scene's [`Scene::flatten`]). Without a `sample_toward`
    /// list the light meshes are sampled too, after them
    /// ([`Scene::sampled_count`]).
    pub fn sampled_shapes(&self, flat: &Flat) -> Vec<Shape> {
        if !self.sample_toward.is_empty() {
            return self.sample_toward.clone();
        }
        Scene::emitter_shapes(flat)
    }

    /// The light meshes the `book` estimator samples toward: none with a
    /// `sample_toward` list, else the scene's ([`Scene::light_meshes`]).
    pub fn sampled_meshes<'a>(&self, flat: &'a Flat) -> impl Iterator<Item = (usize, &'a FlatMesh)> {
        let all = self.sample_toward.is_empty();
        Scene::light_meshes(flat).filter(move |_| all)
    }

    /// How many shapes the `book` estimator samples toward: the spheres and
    /// quads of [`Scene::sampled_shapes`] and the meshes of
    /// [`Scene::sampled_meshes`]. Possibly more than
    /// [`crate::limits::MAX_SAMPLED_SHAPES`]: a render job refuses that.
    pub fn sampled_count(&self, flat: &Flat) -> usize {
        self.sampled_shapes(flat).len() + self.sampled_meshes(flat).count()
    }

    /// How many lights the `nee-mis` estimator samples: the spheres and
    /// quads of [`Scene::emitter_shapes`] and the meshes of
    /// [`Scene::light_meshes`], each one light.
    pub fn emitter_count(flat: &Flat) -> usize {
        Scene::emitter_shapes(flat).len() + Scene::light_meshes(flat).count()
    }

    /// The meshes of `diffuse_light` (groups' included, in world space, in
    /// `flat`'s order), each with its place in `flat.meshes`: lights sampled
    /// by area, after the quads and spheres.
    pub fn light_meshes(flat: &Flat) -> impl Iterator<Item = (usize, &FlatMesh)> {
        flat.meshes.iter().enumerate().filter(|(_, m)| matches!(m.material, Material::DiffuseLight { .. }))
    }

    /// The scene's static spheres and quads of `diffuse_light` (groups'
    /// included, in world space, from `flat`), quads first: lights that can
    /// be sampled, with the light meshes ([`Scene::light_meshes`]). Moving
    /// lights are reached by scattered directions only.
    pub fn emitter_shapes(flat: &Flat) -> Vec<Shape> {
        let light = |m: &Material| matches!(m, Material::DiffuseLight { .. });
        let quads = flat.quads.iter().filter(|q| light(&q.material)).map(|q| Shape::Quad { q: q.q, u: q.u, v: q.v });
        let spheres = flat
            .spheres
            .iter()
            .filter(|s| s.center1.is_none() && light(&s.material))
            .map(|s| Shape::Sphere { center: s.center, radius: s.radius });
        quads.chain(spheres).collect()
    }

    /// The estimator a render of this scene takes when neither its render
    /// table nor an override names one: `nee-mis` for a path-traced scene
    /// with lights (at most [`crate::limits::MAX_SAMPLED_SHAPES`] static
    /// ones), measured the fastest to `bsdf`'s error on four of the five
    /// scenes with lights measured (docs/sampling.md; `nw-final`, the fifth,
    /// names `book` in its render table); `book` for one with a
    /// `sample_toward` list and no lights to sample; `bsdf` for the others
    /// (book one's scenes, lit by the sky, keep their images). `flat` is
    /// this scene's [`Scene::flatten`], which the caller made once for
    /// everything it reads.
    pub fn default_estimator(&self, flat: &Flat) -> EstimatorChoice {
        if self.mode != Mode::Path {
            return EstimatorChoice::Bsdf;
        }
        let fits = |n: usize| n > 0 && n <= crate::limits::MAX_SAMPLED_SHAPES;
        if fits(Scene::emitter_count(flat)) {
            EstimatorChoice::NeeMis
        } else if fits(self.sampled_count(flat)) {
            EstimatorChoice::Book
        } else {
            EstimatorChoice::Bsdf
        }
    }

    /// The scene's primitives in world space (see [`Flat`]); a scene without
    /// quads, boxes or groups gives back its spheres unchanged.
    ///
    /// # Panics
    /// When the scene has OBJ meshes: their files are read first (a render
    /// job does), and [`Scene::flatten_with`] flattens with them.
    pub fn flatten(&self) -> Flat {
        self.flatten_with(&ObjMeshes::default())
    }

    /// [`Scene::flatten`] with the meshes of the scene's OBJ files.
    ///
    /// # Panics
    /// When `objs` lacks a file the scene names.
    pub fn flatten_with(&self, objs: &ObjMeshes) -> Flat {
        #[cfg(test)]
        FLATTENED.with(|n| n.set(n.get() + 1));
        let mut flat = Flat::default();
        flat.add(&Transform::IDENTITY, &self.spheres, &self.quads, &self.boxes);
        for g in &self.groups {
            flat.add(&Transform::of(g), &g.spheres, &g.quads, &g.boxes);
        }
        flat.add_media(&Transform::IDENTITY, &self.media);
        for g in &self.groups {
            flat.add_media(&Transform::of(g), &g.media);
        }
        let mut icospheres = Icospheres::default();
        flat.add_meshes(None, &self.meshes, &mut icospheres, objs);
        let sharing = Sharing::of(self, objs);
        let mut shared = HashMap::new();
        for g in &self.groups {
            let t = Transform::of(g);
            for m in &g.meshes {
                match sharing.shared(m, objs) {
                    Some(key) => flat.add_instance(&t, m, key, &mut shared, objs),
                    None => flat.meshes.push(mesh(Some(&t), m, &mut icospheres, objs)),
                }
            }
        }
        flat
    }

    /// Every mesh: the scene's, then each group's (`None` for the scene's own).
    pub(crate) fn all_meshes(&self) -> impl Iterator<Item = (Option<usize>, usize, &Mesh)> {
        let own = self.meshes.iter().enumerate().map(|(i, m)| (None, i, m));
        own.chain(
            self.groups
                .iter()
                .enumerate()
                .flat_map(|(g, group)| group.meshes.iter().enumerate().map(move |(i, m)| (Some(g), i, m))),
        )
    }

    /// The number of triangles known without reading a file: the
    /// icospheres' ([`MeshShape::generated_triangles`]).
    pub fn generated_triangles(&self) -> u64 {
        self.all_meshes().map(|(_, _, m)| m.shape.generated_triangles()).sum()
    }

    /// The OBJ files the scene's meshes name, each once, in the order the
    /// scene first names them, with the first field that names it
    /// (`groups[g].meshes[i].shape.obj.file`).
    pub fn obj_file_fields(&self) -> Vec<(&str, String)> {
        let mut seen = std::collections::HashSet::new();
        let mut names = Vec::new();
        for (g, i, m) in self.all_meshes() {
            if let MeshShape::Obj { file, .. } = &m.shape {
                if seen.insert(file.as_str()) {
                    let prefix = g.map_or_else(String::new, |g| format!("groups[{g}]."));
                    names.push((file.as_str(), format!("{prefix}meshes[{i}].shape.obj.file")));
                }
            }
        }
        names
    }

    /// The image files the scene's textures name, each once, in the order
    /// the scene first names them.
    pub fn image_files(&self) -> Vec<&str> {
        self.image_file_fields().into_iter().map(|(name, _)| name).collect()
    }

    /// [`Scene::image_files`], each with the first field that names it
    /// (`spheres[3].material.albedo.file`, `groups[0].boxes[1].material.albedo.file`).
    pub fn image_file_fields(&self) -> Vec<(&str, String)> {
        fn add<'a>(
            names: &mut Vec<(&'a str, String)>,
            seen: &mut std::collections::HashSet<&'a str>,
            prefix: &str,
            (spheres, quads, boxes): (&'a [Sphere], &'a [Quad], &'a [QuadBox]),
        ) {
            let materials = spheres.iter().enumerate().map(|(i, s)| ("spheres", i, &s.material));
            let materials = materials.chain(quads.iter().enumerate().map(|(i, q)| ("quads", i, &q.material)));
            let materials = materials.chain(boxes.iter().enumerate().map(|(i, b)| ("boxes", i, &b.material)));
            for (list, i, m) in materials {
                if let Material::Lambertian { albedo: super::Texture::Image { file } } = m {
                    if seen.insert(file) {
                        names.push((file, format!("{prefix}{list}[{i}].material.albedo.file")));
                    }
                }
            }
        }
        let (mut names, mut seen) = (Vec::new(), std::collections::HashSet::new());
        add(&mut names, &mut seen, "", (&self.spheres, &self.quads, &self.boxes));
        for (g, group) in self.groups.iter().enumerate() {
            add(&mut names, &mut seen, &format!("groups[{g}]."), (&group.spheres, &group.quads, &group.boxes));
        }
        names
    }

    /// The number of media [`Scene::flatten`] gives (the scene's and its groups').
    pub fn media_count(&self) -> usize {
        self.media.len() + self.groups.iter().map(|g| g.media.len()).sum::<usize>()
    }

    /// The number of spheres and of quads [`Scene::flatten`] gives (without flattening).
    pub fn primitive_counts(&self) -> (usize, usize) {
        let mut s = self.spheres.len();
        let mut q = self.quads.len() + 6 * self.boxes.len();
        for g in &self.groups {
            s += g.spheres.len();
            q += g.quads.len() + 6 * g.boxes.len();
        }
        (s, q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn white() -> Material {
        Material::Lambertian { albedo: [0.73; 3].into() }
    }

    #[test]
    fn a_box_is_six_outward_faces_covering_its_corners() {
        let b = QuadBox { a: [1.0, 2.0, 3.0], b: [0.0, 0.0, 0.0], material: white() };
        let faces = box_quads(&b);
        let centre = [0.5, 1.0, 1.5];
        for (q, u, v) in faces {
            let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            let mid: [f64; 3] = std::array::from_fn(|i| q[i] + 0.5 * (u[i] + v[i]) - centre[i]);
            assert!(n.iter().zip(mid).map(|(a, b)| a * b).sum::<f64>() > 0.0, "{q:?} faces inwards");
            for (a, bb) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                let p: [f64; 3] = std::array::from_fn(|i| q[i] + a * u[i] + bb * v[i]);
                assert!(p.iter().zip([1.0, 2.0, 3.0]).all(|(&x, m)| x == 0.0 || x == m), "{p:?}");
            }
        }
    }

    #[test]
    fn groups_rotate_then_translate_as_the_book() {
        let g = Group {
            rotate_y: 90.0,
            translate: [10.0, 0.0, 0.0],
            spheres: vec![Sphere { center: [1.0, 0.0, 0.0], center1: None, radius: 1.0, material: white() }],
            ..Group::default()
        };
        let t = Transform::of(&g);
        // x' = cos x + sin z, z' = -sin x + cos z: (1, 0, 0) turns to (0, 0, -1).
        assert_eq!(t.point([1.0, 0.0, 0.0]), [10.0, 0.0, -1.0]);
        let mut scene = crate::scene::preset("ch04-sphere").unwrap();
        scene.groups.push(g);
        let flat = scene.flatten();
        assert_eq!(flat.spheres.last().unwrap().center, [10.0, 0.0, -1.0]);
        assert_eq!(scene.primitive_counts(), (flat.spheres.len(), flat.quads.len()));
    }
}
