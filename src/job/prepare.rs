//! From a validated scene to what the kernels read: the [`Plan`] (what the
//! scene needs), SoA primitives, per-kind material tables, the primitives'
//! shading records (their geometry and their materials' parameters, side by
//! side), the camera and, when the plan chose it, the trees. The scene's types are read here and nowhere
//! on the kernel side.

use super::Images;
use crate::camera::{PreparedCamera, View};
use crate::choice::{AccelChoice, EstimatorChoice, Mode};
use crate::estimator::Estimator;
use crate::film::accum::Scale;
use crate::geometry::{
    Boundary, Cuboids, Emitters, Instances, LightMesh, LightQuad, LightSphere, Lights, Media, MovingSpheres, Quads,
    Shade, Shapes, SharedMesh, Smooth, Spheres, TreeChoice, Triangles, Walk, TRIANGLE_BASE,
};
use crate::handle::Kind;
use crate::material::MaterialTables;
use crate::plan::{Accel, KindSet, Plan, Prepared, SkyColours};
use crate::sampling::layout::Bounces;
use crate::scene::{Background, Camera, Flat, FlatBoundary, FlatMesh, Material, Scene, Shape, Texture};
use crate::settings::Settings;
use crate::texture::{Checker, Noise, Perlin, TexKind, TexRef, TexSet, TextureTables, PERLIN_SEED};
use glam::DVec3;

/// With at least this many spheres `auto` builds a BVH. Measured with
/// `rtow bench` on random scenes (docs/performance.md, "Brute force against the BVH").
pub const BVH_CROSSOVER: usize = 16;

/// The closest-hit search for `spheres` spheres: brute force below the
/// crossover (and where no ray is traced), the BVH above it, or as forced.
pub(super) fn choose_accel(choice: AccelChoice, spheres: usize, mode: Mode) -> Accel {
    if spheres == 0 || mode == Mode::Gradient {
        return Accel::Brute;
    }
    match choice {
        AccelChoice::Brute => Accel::Brute,
        AccelChoice::Bvh => Accel::BvhPackets,
        AccelChoice::BvhRay => Accel::BvhRays,
        AccelChoice::Auto if spheres >= BVH_CROSSOVER => Accel::BvhPackets,
        AccelChoice::Auto => Accel::Brute,
    }
}

/// The material kind of a scene material (each kind gets a wavefront queue).
fn kind(m: &Material) -> Kind {
    match m {
        Material::Lambertian { .. } => Kind::Lambertian,
        Material::Metal { .. } => Kind::Metal,
        Material::Dielectric { .. } => Kind::Dielectric,
        Material::DiffuseLight { .. } => Kind::DiffuseLight,
    }
}

/// The texture kind of a lambertian's albedo.
fn tex_kind(t: &Texture) -> TexKind {
    match t {
        Texture::Solid(_) => TexKind::Solid,
        Texture::Checker { .. } => TexKind::Checker,
        Texture::Noise { .. } => TexKind::Noise,
        Texture::Image { .. } => TexKind::Image,
    }
}

/// The closest-hit search over `quads` quads, or over `quads` moving spheres
/// (none: no search at all): brute force below the crossover, a tree of
/// their own above it.
fn choose_quad_accel(choice: AccelChoice, quads: usize, mode: Mode) -> Option<Accel> {
    (quads > 0).then(|| match choose_accel(choice, quads, mode) {
        Accel::Brute => Accel::Brute,
        _ => Accel::BvhPackets,
    })
}

/// The plan (cheap: no geometry is built).
pub(super) fn plan(scene: &Scene, flat: &Flat, settings: &Settings, accel: AccelChoice) -> Plan {
    let sample_toward = match (scene.mode, settings.estimator) {
        (Mode::Path, EstimatorChoice::Book) => scene.sampled_count(flat),
        _ => 0,
    };
    let nee = match (scene.mode, settings.estimator) {
        (Mode::Path, EstimatorChoice::NeeMis) => Scene::emitter_count(flat),
        _ => 0,
    };
    let kinds: KindSet = match scene.mode {
        Mode::Path => {
            let media = (!flat.media.is_empty()).then_some(Kind::Isotropic);
            flat.materials().map(kind).chain(media).collect()
        }
        Mode::Gradient | Mode::Flat | Mode::Normals => KindSet::default(),
    };
    // Texture passes run for path tracing only (the debug modes shade flat colours).
    let mut textures = TexSet::default();
    if scene.mode == Mode::Path {
        for m in flat.materials() {
            if let Material::Lambertian { albedo } = m {
                if tex_kind(albedo) != TexKind::Solid {
                    textures.insert(tex_kind(albedo));
                }
            }
        }
    }
    Plan {
        mode: scene.mode,
        kinds,
        textures,
        lens: scene.camera.lens_radius() > 0.0 && scene.mode != Mode::Gradient,
        jitter: settings.spp > 1,
        accel: choose_accel(accel, flat.spheres.iter().filter(|s| s.center1.is_none()).count(), scene.mode),
        quads: choose_quad_accel(accel, flat.quads.len() - 6 * flat.cuboids.len(), scene.mode),
        cuboids: choose_quad_accel(accel, flat.cuboids.len(), scene.mode),
        moving: choose_quad_accel(accel, flat.spheres.iter().filter(|s| s.center1.is_some()).count(), scene.mode),
        triangles: choose_quad_accel(accel, flat.triangle_count(), scene.mode),
        instances: if scene.mode == Mode::Gradient { 0 } else { flat.instances.len() },
        shared_meshes: if scene.mode == Mode::Gradient { 0 } else { flat.shared.len() },
        sample_toward,
        nee,
        film_exponent: Scale::for_brightness(brightest(scene, flat) as f64).exponent(),
    }
}

/// The largest channel of any radiance a sample can carry at a throughput
/// of at most 1, from which the film's scale is chosen ([`Scale::for_brightness`]):
/// what rays that leave the scene see (the sky's two colours, of which the
/// gradient is a blend, or the constant background), and, in path tracing,
/// every emitter's radiance (`diffuse_light` spheres, moving spheres, quads
/// and boxes, in groups too; lights have no textures); in the flat debug
/// mode, every colour a hit can show (albedos, both checker colours,
/// emitted radiance); 1 in the normals mode (`0.5 (n + 1)`). The gradient
/// traces no samples. Every value is finite and at least 0 (validated).
pub(crate) fn brightest(scene: &Scene, flat: &Flat) -> f32 {
    let max3 = |c: [f32; 3]| c[0].max(c[1]).max(c[2]);
    let background = match scene.background {
        Background::Sky => max3(scene.sky.horizon).max(max3(scene.sky.zenith)),
        Background::Constant(c) => max3(c),
    };
    let materials = || flat.materials();
    let surfaces = match scene.mode {
        Mode::Gradient => return 0.0,
        Mode::Normals => 1.0,
        Mode::Path => materials()
            .map(|m| match *m {
                Material::DiffuseLight { emit, .. } => max3(emit),
                _ => 0.0,
            })
            .fold(0.0, f32::max),
        Mode::Flat => materials()
            .map(|m| match *m {
                Material::DiffuseLight { emit: c, .. } | Material::Metal { albedo: c, .. } => max3(c),
                Material::Lambertian { albedo: Texture::Solid(c) } => max3(c),
                Material::Lambertian { albedo: Texture::Checker { even, odd, .. } } => max3(even).max(max3(odd)),
                // Noise and image textures (8-bit texels) are at most 1, glass is white.
                Material::Lambertian { .. } | Material::Dielectric { .. } => 1.0,
            })
            .fold(0.0, f32::max),
    };
    background.max(surfaces)
}

/// The scene's camera in f64.
pub(super) fn view(c: &Camera) -> View {
    let v = |a: [f32; 3]| DVec3::from_array(a.map(f64::from));
    View {
        look_from: v(c.look_from),
        look_at: v(c.look_at),
        vup: v(c.vup),
        vfov_deg: c.vfov_deg as f64,
        focus_dist: c.focus_distance(),
        lens_radius: c.lens_radius(),
    }
}

/// Lays a validated scene out for the kernels, as `plan` says.
pub(super) fn prepare(
    scene: &Scene,
    flat: &Flat,
    images: &Images,
    settings: Settings,
    plan: Plan,
    estimator: Estimator,
) -> Prepared {
    let view = view(&scene.camera);
    let extent = extent(scene, flat, &view, &plan);
    let mut tables = Tables { images, materials: MaterialTables::default(), textures: TextureTables::default() };
    let (spheres, moving) = spheres(flat, &mut tables);
    let (quads, cuboids) = quads(flat, extent, &mut tables);
    let (triangles, smooth, placed) = triangles(flat, &mut tables);
    let instances = if plan.instances > 0 { instances(flat, extent, &mut tables) } else { Instances::default() };
    let Tables { materials, textures, .. } = tables;
    let media = if plan.kinds.contains(Kind::Isotropic) { media(flat) } else { Media::default() };
    let kinds = Kinds { spheres, quads, cuboids, moving, triangles, instances };
    let mut shapes = shapes(kinds, &materials, &plan, extent);
    shapes.smooth = smooth;
    let camera =
        PreparedCamera { lens: plan.lens, ..PreparedCamera::new(&view, settings.width, settings.height, plan.jitter) };
    let mut lights = Lights::default();
    // The light mesh `flat.meshes[at]`, and its material's row.
    let light_mesh = |(at, m): (usize, &FlatMesh)| {
        let v: Vec<_> = (0..m.triangles.len()).map(|k| m.triangle(k)).collect();
        (LightMesh::new(&v, placed[at].first, extent), placed[at].row)
    };
    if plan.sample_toward > 0 {
        for shape in scene.sampled_shapes(flat) {
            match shape {
                Shape::Quad { q, u, v } => lights.quads.push(LightQuad::new(q, u, v)),
                Shape::Sphere { center, radius } => lights.spheres.push(LightSphere { c: center, r: radius.abs() }),
            }
        }
        lights.meshes = scene.sampled_meshes(flat).map(|m| light_mesh(m).0).collect();
    }
    let emitters = if plan.nee > 0 {
        emitters(&shapes.spheres, &shapes.quads, &materials, Scene::light_meshes(flat).map(light_mesh))
    } else {
        Emitters::default()
    };
    debug_assert_eq!(emitters.len(), plan.nee);
    Prepared {
        plan,
        settings,
        shapes,
        materials,
        textures,
        camera,
        sky: SkyColours {
            horizon: scene.sky.horizon,
            zenith: scene.sky.zenith,
            constant: match scene.background {
                Background::Sky => None,
                Background::Constant(c) => Some(c),
            },
        },
        media,
        estimator,
        bounces: if lights.is_empty() && emitters.is_empty() { Bounces::BSDF } else { Bounces::BOOK },
        lights,
        emitters,
    }
}

/// The material and texture tables, filled as the primitives are laid out
/// (a material's row is its place in its kind's table, in scene order).
struct Tables<'a> {
    images: &'a Images,
    materials: MaterialTables,
    textures: TextureTables,
}

impl Tables<'_> {
    /// Appends material `m` to its kind's table (a lambertian's texture to
    /// its kind's); returns its row.
    fn row_of(&mut self, m: &Material) -> u32 {
        let (materials, textures) = (&mut self.materials, &mut self.textures);
        match *m {
            Material::Lambertian { ref albedo } => {
                let (flat, tex) = match *albedo {
                    Texture::Solid(c) => (c, TexRef::default()),
                    Texture::Checker { scale, even, odd } => {
                        let c = Checker { inv_scale: (1.0 / scale as f64) as f32, even, odd };
                        (even, TexRef { kind: TexKind::Checker, row: push(&mut textures.checker, c) })
                    }
                    Texture::Noise { scale } => {
                        if textures.perlin.is_none() {
                            textures.perlin = Some(Perlin::new(PERLIN_SEED));
                        }
                        ([0.5; 3], TexRef { kind: TexKind::Noise, row: push(&mut textures.noise, Noise { scale }) })
                    }
                    Texture::Image { ref file } => {
                        let img = self.images.get(file).expect("a job reads every image its scene names").clone();
                        // The flat colour (debug modes): the image's first texel.
                        (img.texels[0], TexRef { kind: TexKind::Image, row: push(&mut textures.image, img) })
                    }
                };
                materials.lambertian_tex.push(tex);
                push(&mut materials.lambertian, flat)
            }
            Material::Metal { albedo, fuzz } => push(&mut materials.metal, (albedo, fuzz)),
            Material::Dielectric { ior } => push(&mut materials.dielectric, ior),
            Material::DiffuseLight { emit, one_sided } => push(&mut materials.light, (emit, one_sided)),
        }
    }
}

/// A bound on every coordinate of every ray origin and every primitive:
/// the camera's eye and lens, the spheres (a moving one's centres at times
/// 0 and 1: every centre between lies within both's range), the media
/// where paths are traced (their scattering points are ray origins anywhere
/// inside them; none for a density of 0, which then changes nothing) and
/// the quads' corners. The quads' edge tolerance and every tree's boxes are
/// scaled by it.
fn extent(scene: &Scene, flat: &Flat, view: &View, plan: &Plan) -> f32 {
    let inf = |c: &[f32; 3]| c.iter().fold(0.0f32, |m, x| m.max(x.abs()));
    let mut extent = inf(&scene.camera.look_from) + view.lens_radius as f32;
    for s in &flat.spheres {
        for c in [Some(s.center), s.center1].into_iter().flatten() {
            extent = extent.max(inf(&c) + s.radius.abs());
        }
    }
    if plan.kinds.contains(Kind::Isotropic) {
        for m in flat.media.iter().filter(|m| m.density > 0.0) {
            extent = extent.max(m.boundary.reach() as f32);
        }
    }
    for q in &flat.quads {
        for (a, b) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
            for k in 0..3 {
                extent = extent.max((q.q[k] + a * q.u[k] + b * q.v[k]).abs());
            }
        }
    }
    for m in &flat.meshes {
        extent = m.positions.iter().fold(extent, |e, p| e.max(inf(p)));
    }
    let reach: Vec<f64> = flat.shared.iter().map(|m| m.positions.iter().fold(0.0f64, |r, p| r.max(norm(p)))).collect();
    for i in &flat.instances {
        // The turn about y keeps a point's distance from the y axis.
        extent = extent.max((reach[i.mesh] + i.translate.iter().fold(0.0f64, |m, x| m.max(x.abs()))) as f32);
    }
    extent
}

/// The length of `p` (f64), at least its largest coordinate's magnitude.
fn norm(p: &[f32; 3]) -> f64 {
    p.iter().map(|&x| f64::from(x) * f64::from(x)).sum::<f64>().sqrt() * (1.0 + 1e-15)
}

/// The shared meshes (each in its own frame, with its tree) and their
/// instances, in group order, with their materials' rows. A mesh's tree is
/// padded for rays moved into its frame: their coordinates reach at most
/// `extent` plus its instances' largest move, turned (a factor up to
/// `sqrt 2`).
fn instances(flat: &Flat, extent: f32, tables: &mut Tables) -> Instances {
    // Each mesh's largest move, in one pass over the instances.
    let mut moved = vec![0.0f64; flat.shared.len()];
    for i in &flat.instances {
        moved[i.mesh] = i.translate.iter().fold(moved[i.mesh], |r, x| r.max(x.abs()));
    }
    let meshes = flat
        .shared
        .iter()
        .zip(moved)
        .map(|(m, moved)| SharedMesh::new((0..m.triangles.len()).map(|t| m.triangle(t)), 2.0 * (extent + moved as f32)))
        .collect();
    let mut instances = Instances::new(meshes);
    for i in &flat.instances {
        let (kind, row) = (kind(&i.material), tables.row_of(&i.material));
        instances.push(i.mesh, (i.cos, i.sin), i.translate, kind, row);
    }
    instances
}

/// The static and the moving spheres, in scene order, with their materials' rows.
fn spheres(flat: &Flat, tables: &mut Tables) -> (Spheres, MovingSpheres) {
    let (mut spheres, mut moving) = (Spheres::default(), MovingSpheres::default());
    for s in &flat.spheres {
        match s.center1 {
            None => spheres.push(s.center, s.radius, kind(&s.material), tables.row_of(&s.material)),
            Some(c1) => moving.push(s.center, c1, s.radius, kind(&s.material), tables.row_of(&s.material)),
        }
    }
    (spheres, moving)
}

/// The quads, with their materials' rows, and the boxes among them as cuboids.
fn quads(flat: &Flat, extent: f32, tables: &mut Tables) -> (Quads, Cuboids) {
    let mut quads = Quads::default();
    for q in &flat.quads {
        quads.push(q.q, q.u, q.v, extent, kind(&q.material), tables.row_of(&q.material));
    }
    let mut cuboids = Cuboids::default();
    for c in &flat.cuboids {
        cuboids.push(c.center, c.axes, c.half, c.first as u32);
    }
    quads.set_cuboid_faces(flat.cuboids.iter().map(|c| c.first as u32));
    cuboids.bound_faces(&quads);
    (quads, cuboids)
}

/// The meshes' triangles, in mesh order (hit indices `TRIANGLE_BASE + i`),
/// each with its mesh's material; and, when some mesh gives vertex normals,
/// every triangle's smooth-shading record (flat for the other meshes).
fn triangles(flat: &Flat, tables: &mut Tables) -> (Triangles, Smooth, Vec<Placed>) {
    let mut triangles = Triangles::default();
    let mut smooth = Smooth::default();
    let mut placed = Vec::with_capacity(flat.meshes.len());
    let smooth_meshes = flat.meshes.iter().any(|m| m.normals.is_some());
    // Every array exactly as long as it will be: at a mesh's scale a
    // doubling Vec would hold up to twice its triangles' records.
    let count: usize = flat.meshes.iter().map(|m| m.triangles.len()).sum();
    triangles.reserve(count);
    if smooth_meshes {
        smooth.reserve(count);
    }
    for m in &flat.meshes {
        let (kind, row) = (kind(&m.material), tables.row_of(&m.material));
        let mesh = triangles.push_mesh(kind, row);
        placed.push(Placed { first: TRIANGLE_BASE + triangles.len() as u32, row });
        for k in 0..m.triangles.len() {
            let v = m.triangle(k);
            triangles.push_in(v, mesh);
            match m.triangle_normals(k) {
                Some(n) => smooth.push(v, n),
                None if smooth_meshes => smooth.push_flat(),
                None => {}
            }
        }
    }
    (triangles, smooth, placed)
}

/// Where a mesh's triangles went: the hit index of its first, and its
/// material's row.
struct Placed {
    first: u32,
    row: u32,
}

/// The constant media (where paths are traced).
fn media(flat: &Flat) -> Media {
    let mut media = Media::default();
    let f = |v: [f64; 3]| v.map(|x| x as f32);
    for m in &flat.media {
        let boundary = match m.boundary {
            FlatBoundary::Sphere { center, radius } => {
                Boundary::Sphere { c: f(center), r2: (radius as f32) * (radius as f32) }
            }
            FlatBoundary::Box { center, axes, half } => {
                Boundary::Box { c: f(center), axes: axes.map(f), half: f(half) }
            }
        };
        media.push(boundary, m.density as f64, m.albedo);
    }
    media
}

/// The primitives padded, with their shading records and the trees the
/// plan chose, as the one aggregate the kernels search. Ray origins lie
/// within the camera's lens of the eye, or on a primitive (`extent`; the
/// spheres' tree pads by their own extent too); the spheres' tree is shaped
/// for the walk that uses it (`geometry::bvh::SahCost`).
fn shapes(kinds: Kinds, materials: &MaterialTables, plan: &Plan, extent: f32) -> Shapes {
    let Kinds { mut spheres, mut quads, cuboids, mut moving, mut triangles, mut instances } = kinds;
    spheres.pad();
    quads.pad();
    moving.pad();
    // The wavefront's per-primitive shading records (geometry::Shade).
    shade_spheres(&mut spheres, materials);
    shade_spheres(&mut moving.s, materials);
    for i in 0..quads.len {
        let (albedo, param) = materials.record(quads.kind[i], quads.row[i]);
        quads.shade[i].0[4..].copy_from_slice(&[albedo[0], albedo[1], albedo[2], param]);
    }
    for m in 0..triangles.kind.len() {
        let (albedo, param) = materials.record(triangles.kind[m], triangles.row[m]);
        triangles.material[m] = [albedo[0], albedo[1], albedo[2], param];
    }
    for i in 0..instances.len() {
        let (albedo, param) = materials.record(instances.kind[i], instances.row[i]);
        instances.material[i] = [albedo[0], albedo[1], albedo[2], param];
    }
    let mut shapes = Shapes::new(spheres, quads, cuboids, moving, triangles, instances);
    let tree = |a: Option<Accel>| a.is_some_and(|a| a != Accel::Brute);
    let choice = TreeChoice {
        spheres: match plan.accel {
            Accel::Brute => None,
            Accel::BvhPackets => Some(Walk::OneByOne),
            Accel::BvhRays => Some(Walk::Wide8),
        },
        quads: tree(plan.quads),
        cuboids: tree(plan.cuboids),
        moving: tree(plan.moving),
        triangles: tree(plan.triangles),
    };
    shapes.build_trees(choice, extent);
    shapes
}

/// Every kind's primitives, before padding and trees.
struct Kinds {
    spheres: Spheres,
    quads: Quads,
    cuboids: Cuboids,
    moving: MovingSpheres,
    triangles: Triangles,
    instances: Instances,
}

/// Fills the spheres' shading records ([`Spheres::shade`], after
/// [`Spheres::pad`]): each sphere's centre and signed radius, and its
/// material's albedo and parameter ([`MaterialTables::record`]); the
/// padding's material slots are 0.
fn shade_spheres(s: &mut Spheres, m: &MaterialTables) {
    s.shade = (0..s.cx.len())
        .map(|i| {
            let (albedo, param) = if i < s.len { m.record(s.kind[i], s.row[i]) } else { ([0.0; 3], 0.0) };
            let [a0, a1, a2] = albedo;
            Shade([s.cx[i], s.cy[i], s.cz[i], s.r[i], a0, a1, a2, param])
        })
        .collect();
}

/// Appends to a material table; returns the row.
fn push<T>(table: &mut Vec<T>, v: T) -> u32 {
    table.push(v);
    table.len() as u32 - 1
}

/// The lights `nee-mis` samples, from the prepared primitives: the static
/// quads, then the static spheres, of the light kind, in primitive order (as
/// [`Scene::emitter_shapes`] lists them), then the light meshes (with their
/// rows), with their rows' radiance.
fn emitters(
    spheres: &Spheres,
    quads: &Quads,
    materials: &MaterialTables,
    meshes: impl Iterator<Item = (LightMesh, u32)>,
) -> Emitters {
    let mut e = Emitters { of_row: vec![Emitters::UNSAMPLED; materials.light.len()], ..Emitters::default() };
    let add = |e: &mut Emitters, row: u32| {
        let (emit, one_sided) = materials.light[row as usize];
        e.of_row[row as usize] = (e.emit.len()) as u32;
        e.emit.push(emit);
        e.one_sided.push(one_sided);
    };
    for i in 0..quads.len {
        if quads.kind[i] == Kind::DiffuseLight {
            let r = &quads.rec[i];
            e.shapes.quads.push(LightQuad::new(r.q, r.u, r.v));
            add(&mut e, quads.row[i]);
        }
    }
    for i in 0..spheres.len {
        if spheres.kind[i] == Kind::DiffuseLight {
            e.shapes
                .spheres
                .push(LightSphere { c: [spheres.cx[i], spheres.cy[i], spheres.cz[i]], r: spheres.r[i].abs() });
            add(&mut e, spheres.row[i]);
        }
    }
    for (mesh, row) in meshes {
        e.shapes.meshes.push(mesh);
        add(&mut e, row);
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::job::{Job, Overrides, RenderOptions};
    use crate::scene::preset;

    fn settings(spp: u32) -> Settings {
        Settings { width: 40, height: 20, spp, max_depth: 5, ..Settings::default() }
    }

    #[test]
    fn the_plan_takes_only_the_kinds_a_scene_uses() {
        let ch07 = preset("ch07-diffuse").unwrap();
        let p = plan(&ch07, &ch07.flatten(), &settings(4), AccelChoice::Auto);
        assert_eq!(p.kinds.iter().collect::<Vec<_>>(), [Kind::Lambertian]);
        let fin = preset("final").unwrap();
        let p = plan(&fin, &fin.flatten(), &settings(4), AccelChoice::Auto);
        assert_eq!(p.kinds.iter().collect::<Vec<_>>(), [Kind::Lambertian, Kind::Metal, Kind::Dielectric]);
        assert_eq!(p.quads, None);
        let cornell = preset("nw-cornell-box").unwrap();
        let p = plan(&cornell, &cornell.flatten(), &settings(4), AccelChoice::Auto);
        assert_eq!(p.kinds.iter().collect::<Vec<_>>(), [Kind::Lambertian, Kind::DiffuseLight]);
        // Six walls and the light (below the crossover) and two boxes, tested whole.
        assert_eq!((p.quads, p.cuboids), (Some(Accel::Brute), Some(Accel::Brute)));
        let p = plan(&cornell, &cornell.flatten(), &settings(4), AccelChoice::Bvh);
        assert_eq!((p.quads, p.cuboids), (Some(Accel::BvhPackets), Some(Accel::BvhPackets)));
        // The book's final scene: its one light quad, and 400 ground boxes in a tree of their own.
        let nw = preset("nw-final").unwrap();
        let p = plan(&nw, &nw.flatten(), &settings(4), AccelChoice::Auto);
        assert_eq!((p.quads, p.cuboids), (Some(Accel::Brute), Some(Accel::BvhPackets)));
        assert_eq!(plan(&fin, &fin.flatten(), &settings(4), AccelChoice::Auto).cuboids, None);
        let normals = preset("ch05-normals").unwrap();
        assert!(plan(&normals, &normals.flatten(), &settings(4), AccelChoice::Auto).kinds.is_empty());
    }

    #[test]
    fn pinhole_or_lens_and_jitter_follow_the_scene() {
        let fin = preset("final").unwrap();
        assert!(plan(&fin, &fin.flatten(), &settings(4), AccelChoice::Auto).lens);
        let ch10 = preset("ch10-wide-fov").unwrap();
        let p = plan(&ch10, &ch10.flatten(), &settings(1), AccelChoice::Auto);
        assert!(!p.lens && !p.jitter);
        assert!(plan(&ch10, &ch10.flatten(), &settings(2), AccelChoice::Auto).jitter);
    }

    #[test]
    fn brute_force_below_the_crossover_bvh_above_it() {
        assert_eq!(choose_accel(AccelChoice::Auto, BVH_CROSSOVER - 1, Mode::Path), Accel::Brute);
        assert_eq!(choose_accel(AccelChoice::Auto, BVH_CROSSOVER, Mode::Path), Accel::BvhPackets);
        assert_eq!(choose_accel(AccelChoice::Bvh, 1, Mode::Path), Accel::BvhPackets);
        assert_eq!(choose_accel(AccelChoice::BvhRay, 1, Mode::Path), Accel::BvhRays);
        assert_eq!(choose_accel(AccelChoice::Brute, 1000, Mode::Path), Accel::Brute);
        assert_eq!(choose_accel(AccelChoice::Bvh, 0, Mode::Path), Accel::Brute);
        assert_eq!(choose_accel(AccelChoice::Bvh, 100, Mode::Gradient), Accel::Brute);
        let fin = preset("final").unwrap();
        let o = Overrides::from(settings(2));
        let auto = Job::new(&fin, &o, &RenderOptions::default()).unwrap();
        assert!(auto.prepared().shapes.trees.spheres.is_some());
        let brute = RenderOptions { accel: AccelChoice::Brute, ..Default::default() };
        assert!(Job::new(&fin, &o, &brute).unwrap().prepared().shapes.trees.spheres.is_none());
    }
}
