//! A preset for every image of the three books (book one chapter by chapter,
//! The Next Week's and The Rest of Your Life's scenes), with the book's
//! physics, and the numerical stress scenes of `rtow stress`.

use super::{
    Background, BookTable, Camera, Group, Material, Medium, MediumBoundary, Mode, Quad, QuadBox, RenderTable, Scene,
    Shape, Sky, Sphere, Texture,
};
use crate::choice::EstimatorChoice;
use crate::real::Real;
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro128Plus;

pub struct Preset {
    pub name: &'static str,
    pub description: &'static str,
    /// Which list `rtow scenes` shows it in.
    pub group: PresetGroup,
    pub build: fn() -> Scene,
}

/// The lists of presets: the images of a book, or the scenes of `rtow stress`.
/// A later book adds its own group (and its presets' names their prefix).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PresetGroup {
    /// *Ray Tracing in One Weekend*, chapter by chapter.
    Weekend,
    /// *Ray Tracing: The Next Week* (names `nw-...`).
    NextWeek,
    /// *Ray Tracing: The Rest of Your Life* (names `rol-...`).
    RestOfYourLife,
    /// Past the books: triangle meshes (names `...-mesh`).
    Meshes,
    /// Numerical stress scenes (`rtow stress`), not images of a book.
    Stress,
}

impl PresetGroup {
    /// Every group, in the order `rtow scenes` lists them.
    pub const ALL: &'static [PresetGroup] = &[
        PresetGroup::Weekend,
        PresetGroup::NextWeek,
        PresetGroup::RestOfYourLife,
        PresetGroup::Meshes,
        PresetGroup::Stress,
    ];

    /// The heading `rtow scenes` gives the group.
    pub fn title(self) -> &'static str {
        match self {
            PresetGroup::Weekend => "Ray Tracing in One Weekend",
            PresetGroup::NextWeek => "Ray Tracing: The Next Week (v4)",
            PresetGroup::RestOfYourLife => "Ray Tracing: The Rest of Your Life (v4)",
            PresetGroup::Meshes => "Past the books: triangle meshes",
            PresetGroup::Stress => "Stress scenes (numerical robustness, for rtow stress)",
        }
    }
}

const fn lam(albedo: [f32; 3]) -> Material {
    Material::Lambertian { albedo: Texture::Solid(albedo) }
}
const fn lam_tex(albedo: Texture) -> Material {
    Material::Lambertian { albedo }
}
const fn metal(albedo: [f32; 3], fuzz: f32) -> Material {
    Material::Metal { albedo, fuzz }
}
const fn glass(ior: f32) -> Material {
    Material::Dielectric { ior }
}
const fn sphere(center: [f32; 3], radius: f32, material: Material) -> Sphere {
    Sphere { center, center1: None, radius, material }
}

fn settings(width: u32, height: u32, spp: u32, depth: u32) -> RenderTable {
    RenderTable {
        width: Some(width),
        height: Some(height),
        samples_per_pixel: Some(spp),
        max_depth: Some(depth),
        seed: None,
        sampler: None,
        estimator: None,
        book: None,
    }
}

/// The book's early camera: eye at the origin looking down -z, viewport 2 high
/// at focal length 1 (vfov 90), width from the image's aspect ratio.
fn origin_camera() -> Camera {
    Camera::looking([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], 90.0)
}

fn scene(mode: Mode, camera: Camera, spheres: Vec<Sphere>, render: RenderTable) -> Scene {
    Scene {
        mode,
        camera,
        spheres,
        quads: vec![],
        boxes: vec![],
        groups: vec![],
        media: vec![],
        meshes: vec![],
        sky: Sky::default(),
        background: Background::Sky,
        sample_toward: vec![],
        render,
    }
}

const SMALL: fn() -> RenderTable = || settings(400, 225, 1, 1);

fn ch01() -> Scene {
    scene(Mode::Gradient, origin_camera(), vec![], settings(1280, 720, 1, 1))
}
fn ch03() -> Scene {
    scene(Mode::Flat, origin_camera(), vec![], SMALL())
}
fn red_ball() -> Sphere {
    sphere([0.0, 0.0, -1.0], 0.5, lam([1.0, 0.0, 0.0]))
}
fn ground_100() -> Sphere {
    sphere([0.0, -100.5, -1.0], 100.0, lam([0.5, 0.5, 0.5]))
}
fn ch04() -> Scene {
    scene(Mode::Flat, origin_camera(), vec![red_ball()], SMALL())
}
fn ch05_normals() -> Scene {
    scene(Mode::Normals, origin_camera(), vec![red_ball()], SMALL())
}
fn ch05_ground() -> Scene {
    scene(Mode::Normals, origin_camera(), vec![red_ball(), ground_100()], SMALL())
}
fn ch06() -> Scene {
    scene(Mode::Normals, origin_camera(), vec![red_ball(), ground_100()], settings(400, 225, 100, 1))
}
fn ch07() -> Scene {
    let grey = lam([0.5, 0.5, 0.5]);
    let spheres = vec![sphere([0.0, 0.0, -1.0], 0.5, grey.clone()), sphere([0.0, -100.5, -1.0], 100.0, grey)];
    scene(Mode::Path, origin_camera(), spheres, settings(400, 225, 100, 50))
}
fn metals(center: [f32; 3], fuzz_left: f32, fuzz_right: f32) -> Vec<Sphere> {
    vec![
        sphere([0.0, 0.0, -1.0], 0.5, lam(center)),
        sphere([0.0, -100.5, -1.0], 100.0, lam([0.8, 0.8, 0.0])),
        sphere([1.0, 0.0, -1.0], 0.5, metal([0.8, 0.6, 0.2], fuzz_right)),
        sphere([-1.0, 0.0, -1.0], 0.5, metal([0.8, 0.8, 0.8], fuzz_left)),
    ]
}
fn ch08_metal() -> Scene {
    scene(Mode::Path, origin_camera(), metals([0.8, 0.3, 0.3], 0.0, 0.0), settings(400, 225, 100, 50))
}
fn ch08_fuzz() -> Scene {
    scene(Mode::Path, origin_camera(), metals([0.8, 0.3, 0.3], 0.3, 1.0), settings(400, 225, 100, 50))
}
/// Chapter 9's scene: a hollow glass ball on the left (a negative-radius sphere inside).
fn glass_scene() -> Vec<Sphere> {
    vec![
        sphere([0.0, 0.0, -1.0], 0.5, lam([0.1, 0.2, 0.5])),
        sphere([0.0, -100.5, -1.0], 100.0, lam([0.8, 0.8, 0.0])),
        sphere([1.0, 0.0, -1.0], 0.5, metal([0.8, 0.6, 0.2], 0.0)),
        sphere([-1.0, 0.0, -1.0], 0.5, glass(1.5)),
        sphere([-1.0, 0.0, -1.0], -0.45, glass(1.5)),
    ]
}
fn ch09() -> Scene {
    scene(Mode::Path, origin_camera(), glass_scene(), settings(400, 225, 100, 50))
}
fn ch10_wide() -> Scene {
    let r = std::f32::consts::FRAC_PI_4.cos();
    let spheres =
        vec![sphere([-r, 0.0, -1.0], r, lam([0.0, 0.0, 1.0])), sphere([r, 0.0, -1.0], r, lam([1.0, 0.0, 0.0]))];
    scene(Mode::Path, origin_camera(), spheres, settings(400, 225, 100, 50))
}
fn ch10_look(vfov: f32) -> Scene {
    let cam = Camera::looking([-2.0, 2.0, 1.0], [0.0, 0.0, -1.0], vfov);
    scene(Mode::Path, cam, glass_scene(), settings(400, 225, 100, 50))
}
fn ch11() -> Scene {
    let mut cam = Camera::looking([3.0, 3.0, 2.0], [0.0, 0.0, -1.0], 20.0);
    cam.aperture = Some(2.0);
    scene(Mode::Path, cam, glass_scene(), settings(400, 225, 100, 50))
}

/// The fixed seed of the final scene's sphere layout.
pub const FINAL_LAYOUT_SEED: u64 = 0x5EED_2016;

/// The book's final scene: a big ground sphere, a 22 x 22 grid of small random
/// spheres (80% lambertian, 15% metal, 5% glass) and three big spheres, laid out
/// from a fixed seed, seen through the book's thin-lens camera.
pub fn final_scene() -> Scene {
    let mut rng = Xoshiro128Plus::seed_from_u64(FINAL_LAYOUT_SEED);
    let mut rnd = || f32::unit_from_bits(rng.next_u32());
    let mut spheres = vec![sphere([0.0, -1000.0, 0.0], 1000.0, lam([0.5, 0.5, 0.5]))];
    for a in -11..11 {
        for b in -11..11 {
            let choose = rnd();
            let center = [a as f32 + 0.9 * rnd(), 0.2, b as f32 + 0.9 * rnd()];
            let d = [center[0] - 4.0, center[1] - 0.2, center[2]];
            if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() <= 0.9 {
                continue;
            }
            let material = if choose < 0.8 {
                let a: [f32; 3] = std::array::from_fn(|_| rnd());
                let b: [f32; 3] = std::array::from_fn(|_| rnd());
                lam(std::array::from_fn(|i| a[i] * b[i]))
            } else if choose < 0.95 {
                let albedo = std::array::from_fn(|_| 0.5 + 0.5 * rnd());
                metal(albedo, 0.5 * rnd())
            } else {
                glass(1.5)
            };
            spheres.push(sphere(center, 0.2, material));
        }
    }
    spheres.push(sphere([0.0, 1.0, 0.0], 1.0, glass(1.5)));
    spheres.push(sphere([-4.0, 1.0, 0.0], 1.0, lam([0.4, 0.2, 0.1])));
    spheres.push(sphere([4.0, 1.0, 0.0], 1.0, metal([0.7, 0.6, 0.5], 0.0)));
    let mut cam = Camera::looking([13.0, 2.0, 3.0], [0.0, 0.0, 0.0], 20.0);
    cam.defocus_angle_deg = Some(0.6);
    cam.focus_dist = Some(10.0);
    scene(Mode::Path, cam, spheres, settings(400, 225, 32, 50))
}

/// `s` with every length multiplied by `k`: sphere centres and radii, the
/// camera's position, target, focus distance and aperture. The defocus angle
/// and the field of view are angles and stay. The image is the same up to noise.
fn scaled(mut s: Scene, k: f32) -> Scene {
    for sp in &mut s.spheres {
        sp.center = sp.center.map(|x| x * k);
        sp.center1 = sp.center1.map(|c| c.map(|x| x * k));
        sp.radius *= k;
    }
    let c = &mut s.camera;
    c.look_from = c.look_from.map(|x| x * k);
    c.look_at = c.look_at.map(|x| x * k);
    c.focus_dist = c.focus_dist.map(|f| f * k);
    c.aperture = c.aperture.map(|a| a * k);
    s
}

/// Stress: the final scene 1000 times smaller (small spheres of radius 2e-4).
fn stress_final_small() -> Scene {
    scaled(final_scene(), 1e-3)
}

/// Stress: the final scene 1000 times larger (a ground of radius 1e6).
fn stress_final_large() -> Scene {
    scaled(final_scene(), 1e3)
}

/// Stress: chapter 9's scene scaled so that its spheres have radius 1e-4.
fn stress_tiny() -> Scene {
    scaled(ch09(), 2e-4)
}

const fn light(emit: [f32; 3]) -> Material {
    Material::DiffuseLight { emit, one_sided: false }
}
const fn quad(q: [f32; 3], u: [f32; 3], v: [f32; 3], material: Material) -> Quad {
    Quad { q, u, v, material }
}

/// A scene of The Next Week: a pinhole camera (vup +y), a constant background.
/// Its render table is the book's settings, which `--book` also renders.
fn next_week(camera: Camera, background: [f32; 3], render: RenderTable) -> Scene {
    let book = BookTable {
        width: render.width.expect("a preset's width"),
        height: render.height.expect("a preset's height"),
        samples_per_pixel: render.samples_per_pixel.expect("a preset's samples"),
        max_depth: render.max_depth.expect("a preset's depth"),
    };
    let render = RenderTable { book: Some(book), ..render };
    Scene { background: Background::Constant(background), ..scene(Mode::Path, camera, vec![], render) }
}

/// The Next Week's blue-grey background of its daylight scenes.
const NW_DAYLIGHT: [f32; 3] = [0.70, 0.80, 1.00];

/// The Next Week, `quads()`: five coloured quads, 400x400, 100 spp.
fn nw_quads() -> Scene {
    let mut s =
        next_week(Camera::looking([0.0, 0.0, 9.0], [0.0, 0.0, 0.0], 80.0), NW_DAYLIGHT, settings(400, 400, 100, 50));
    s.quads = vec![
        quad([-3.0, -2.0, 5.0], [0.0, 0.0, -4.0], [0.0, 4.0, 0.0], lam([1.0, 0.2, 0.2])),
        quad([-2.0, -2.0, 0.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0], lam([0.2, 1.0, 0.2])),
        quad([3.0, -2.0, 1.0], [0.0, 0.0, 4.0], [0.0, 4.0, 0.0], lam([0.2, 0.2, 1.0])),
        quad([-2.0, 3.0, 1.0], [4.0, 0.0, 0.0], [0.0, 0.0, 4.0], lam([1.0, 0.5, 0.0])),
        quad([-2.0, -3.0, 5.0], [4.0, 0.0, 0.0], [0.0, 0.0, -4.0], lam([0.2, 0.8, 0.8])),
    ];
    s
}

/// The Next Week's camera of its sphere scenes: vfov 20 from (13, 2, 3) to
/// the origin, no defocus, 16:9 at 400 wide, 100 spp, depth 50, daylight.
fn nw_daylight_spheres() -> Scene {
    next_week(Camera::looking([13.0, 2.0, 3.0], [0.0; 3], 20.0), NW_DAYLIGHT, settings(400, 225, 100, 50))
}

/// The Next Week, `bouncing_spheres()` (v4 `dev`): book one's final scene
/// on the 3-D checker ground (scale 0.32), its lambertian spheres moving up
/// by `U[0, 0.5]` over the shutter (the book's `center2 = center + (0,
/// random_double(0, .5), 0)`, drawn after the albedo as the book does), the
/// book's camera (vfov 20 from (13, 2, 3), defocus angle 0.02 degrees, focus
/// distance 10, as its code has it), daylight, 400x225, 100 spp, depth 50.
/// The layout comes from rtow's generator with the final scene's seed.
fn nw_bouncing_spheres() -> Scene {
    let mut rng = Xoshiro128Plus::seed_from_u64(FINAL_LAYOUT_SEED);
    let mut rnd = || f32::unit_from_bits(rng.next_u32());
    let checker = lam_tex(Texture::Checker { scale: 0.32, even: [0.2, 0.3, 0.1], odd: [0.9, 0.9, 0.9] });
    let mut spheres = vec![sphere([0.0, -1000.0, 0.0], 1000.0, checker)];
    for a in -11..11 {
        for b in -11..11 {
            let choose = rnd();
            let center = [a as f32 + 0.9 * rnd(), 0.2, b as f32 + 0.9 * rnd()];
            let d = [center[0] - 4.0, center[1] - 0.2, center[2]];
            if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() <= 0.9 {
                continue;
            }
            if choose < 0.8 {
                let a: [f32; 3] = std::array::from_fn(|_| rnd());
                let b: [f32; 3] = std::array::from_fn(|_| rnd());
                let material = lam(std::array::from_fn(|i| a[i] * b[i]));
                let center1 = Some([center[0], center[1] + 0.5 * rnd(), center[2]]);
                spheres.push(Sphere { center1, ..sphere(center, 0.2, material) });
            } else if choose < 0.95 {
                let albedo = std::array::from_fn(|_| 0.5 + 0.5 * rnd());
                spheres.push(sphere(center, 0.2, metal(albedo, 0.5 * rnd())));
            } else {
                spheres.push(sphere(center, 0.2, glass(1.5)));
            }
        }
    }
    spheres.push(sphere([0.0, 1.0, 0.0], 1.0, glass(1.5)));
    spheres.push(sphere([-4.0, 1.0, 0.0], 1.0, lam([0.4, 0.2, 0.1])));
    spheres.push(sphere([4.0, 1.0, 0.0], 1.0, metal([0.7, 0.6, 0.5], 0.0)));
    let mut s = nw_daylight_spheres();
    s.camera.defocus_angle_deg = Some(0.02);
    s.camera.focus_dist = Some(10.0);
    s.spheres = spheres;
    s
}

/// The Next Week, `checkered_spheres()`: two spheres of radius 10 at y = +-10
/// under the book's 3-D checker (scale 0.32, v4 `dev`).
fn nw_checkered_spheres() -> Scene {
    let mut s = nw_daylight_spheres();
    let checker = lam_tex(Texture::Checker { scale: 0.32, even: [0.2, 0.3, 0.1], odd: [0.9, 0.9, 0.9] });
    s.spheres = vec![sphere([0.0, -10.0, 0.0], 10.0, checker.clone()), sphere([0.0, 10.0, 0.0], 10.0, checker)];
    s
}

/// The Next Week, `earth()`: a globe of radius 2 under the book's
/// `image_texture("earthmap.jpg")`, seen from (0, 0, 12). The map is not part
/// of rtow: the render reads `earthmap.jpg` from the folder `RTOW_IMAGES`
/// names (`crate::job`), and says how to get it when it is not there.
fn nw_earth() -> Scene {
    let mut s = next_week(Camera::looking([0.0, 0.0, 12.0], [0.0; 3], 20.0), NW_DAYLIGHT, settings(400, 225, 100, 50));
    s.spheres = vec![sphere([0.0; 3], 2.0, lam_tex(Texture::Image { file: "earthmap.jpg".into() }))];
    s
}

/// The two marble spheres of `perlin_spheres()` and `simple_light()`: the
/// book's `noise_texture(4)`.
fn perlin_spheres() -> Vec<Sphere> {
    let marble = lam_tex(Texture::Noise { scale: 4.0 });
    vec![sphere([0.0, -1000.0, 0.0], 1000.0, marble.clone()), sphere([0.0, 2.0, 0.0], 2.0, marble)]
}

/// The Next Week, `perlin_spheres()`: a ground and a sphere of Perlin marble.
fn nw_perlin_spheres() -> Scene {
    let mut s = nw_daylight_spheres();
    s.spheres = perlin_spheres();
    s
}

/// The Next Week, `simple_light()`: the Perlin spheres lit by a sphere light
/// and a quad light, on black.
fn nw_simple_light() -> Scene {
    let mut s =
        next_week(Camera::looking([26.0, 3.0, 6.0], [0.0, 2.0, 0.0], 20.0), [0.0; 3], settings(400, 225, 100, 50));
    s.spheres = perlin_spheres();
    s.spheres.push(sphere([0.0, 7.0, 0.0], 2.0, light([4.0; 3])));
    s.quads = vec![quad([3.0, 1.0, -2.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], light([4.0; 3]))];
    s
}

const NW_RED: Material = lam([0.65, 0.05, 0.05]);
const NW_WHITE: Material = lam([0.73, 0.73, 0.73]);
const NW_GREEN: Material = lam([0.12, 0.45, 0.15]);

/// The Next Week's Cornell box without its boxes (its image 19): five walls
/// and a two-sided light of 15, 600x600, 200 spp, depth 50.
fn nw_cornell_box_empty() -> Scene {
    let cam = Camera::looking([278.0, 278.0, -800.0], [278.0, 278.0, 0.0], 40.0);
    let mut s = next_week(cam, [0.0; 3], settings(600, 600, 200, 50));
    s.quads = vec![
        quad([555.0, 0.0, 0.0], [0.0, 555.0, 0.0], [0.0, 0.0, 555.0], NW_GREEN),
        quad([0.0, 0.0, 0.0], [0.0, 555.0, 0.0], [0.0, 0.0, 555.0], NW_RED),
        quad([343.0, 554.0, 332.0], [-130.0, 0.0, 0.0], [0.0, 0.0, -105.0], light([15.0; 3])),
        quad([0.0, 0.0, 0.0], [555.0, 0.0, 0.0], [0.0, 0.0, 555.0], NW_WHITE),
        quad([555.0, 555.0, 555.0], [-555.0, 0.0, 0.0], [0.0, 0.0, -555.0], NW_WHITE),
        quad([0.0, 0.0, 555.0], [555.0, 0.0, 0.0], [0.0, 555.0, 0.0], NW_WHITE),
    ];
    s
}

/// The Next Week's Cornell box: the room and two white boxes, 165x330x165
/// under `rotate_y(15)` then `translate(265, 0, 295)`, 165^3 under
/// `rotate_y(-18)` then `translate(130, 0, 65)`.
fn nw_cornell_box() -> Scene {
    let mut s = nw_cornell_box_empty();
    let cube = |b: [f32; 3]| QuadBox { a: [0.0; 3], b, material: NW_WHITE };
    s.groups = vec![
        Group {
            rotate_y: 15.0,
            translate: [265.0, 0.0, 295.0],
            boxes: vec![cube([165.0, 330.0, 165.0])],
            ..Group::default()
        },
        Group { rotate_y: -18.0, translate: [130.0, 0.0, 65.0], boxes: vec![cube([165.0; 3])], ..Group::default() },
    ];
    s
}

/// The Rest of Your Life's Cornell box room: the walls re-oriented as its
/// code has them (every normal into the room) and its one-sided light of
/// 15 at (213, 554, 227) + (130, 0, 0), (0, 0, 105), facing down; 600x600,
/// 100 spp, depth 50. Its `lights` list (`sample_toward`, set by each
/// scene) is what `--estimator book`, the book's estimator, samples; by
/// default it renders with `nee-mis`, measured faster to every error here
/// (docs/sampling.md).
fn rol_room() -> Scene {
    let cam = Camera::looking([278.0, 278.0, -800.0], [278.0, 278.0, 0.0], 40.0);
    let mut s = next_week(cam, [0.0; 3], settings(600, 600, 100, 50));
    s.quads = vec![
        quad([555.0, 0.0, 0.0], [0.0, 0.0, 555.0], [0.0, 555.0, 0.0], NW_GREEN),
        quad([0.0, 0.0, 555.0], [0.0, 0.0, -555.0], [0.0, 555.0, 0.0], NW_RED),
        quad([0.0, 555.0, 0.0], [555.0, 0.0, 0.0], [0.0, 0.0, 555.0], NW_WHITE),
        quad([0.0, 0.0, 555.0], [555.0, 0.0, 0.0], [0.0, 0.0, -555.0], NW_WHITE),
        quad([555.0, 0.0, 555.0], [-555.0, 0.0, 0.0], [0.0, 555.0, 0.0], NW_WHITE),
        quad(
            [213.0, 554.0, 227.0],
            [130.0, 0.0, 0.0],
            [0.0, 0.0, 105.0],
            Material::DiffuseLight { emit: [15.0; 3], one_sided: true },
        ),
    ];
    s
}

/// The light of The Rest of Your Life's `lights` list: the ceiling light's
/// rectangle, written from its other corner (the same normal).
const ROL_LIGHT: Shape = Shape::Quad { q: [343.0, 554.0, 332.0], u: [-130.0, 0.0, 0.0], v: [0.0, 0.0, -105.0] };

/// The Rest of Your Life's tall box: white, 165x330x165 under `rotate_y(15)`
/// then `translate(265, 0, 295)`, of `material`.
fn rol_tall_box(material: Material) -> Group {
    Group {
        rotate_y: 15.0,
        translate: [265.0, 0.0, 295.0],
        boxes: vec![QuadBox { a: [0.0; 3], b: [165.0, 330.0, 165.0], material }],
        ..Group::default()
    }
}

/// The Rest of Your Life's final Cornell box (its image 3.14, `main.cc`):
/// the tall white box and a glass sphere of radius 90 at (190, 90, 190);
/// directions are sampled toward the light and the glass sphere.
fn rol_cornell_box() -> Scene {
    let mut s = rol_room();
    s.groups = vec![rol_tall_box(NW_WHITE)];
    s.spheres = vec![sphere([190.0, 90.0, 190.0], 90.0, glass(1.5))];
    s.sample_toward = vec![ROL_LIGHT, Shape::Sphere { center: [190.0, 90.0, 190.0], radius: 90.0 }];
    s
}

/// The Rest of Your Life's image 3.12: the tall box of aluminium
/// (`metal((0.8, 0.85, 0.88), 0)`), the short white box of The Next Week
/// (165^3 under `rotate_y(-18)` then `translate(130, 0, 65)`); directions
/// are sampled toward the light only.
fn rol_cornell_box_aluminium() -> Scene {
    let mut s = rol_room();
    s.groups = vec![
        rol_tall_box(metal([0.8, 0.85, 0.88], 0.0)),
        Group {
            rotate_y: -18.0,
            translate: [130.0, 0.0, 65.0],
            boxes: vec![QuadBox { a: [0.0; 3], b: [165.0; 3], material: NW_WHITE }],
            ..Group::default()
        },
    ];
    s.sample_toward = vec![ROL_LIGHT];
    s
}

/// The Next Week's `cornell_smoke()`: the room of [`nw_cornell_box`] with a
/// larger, dimmer light, `diffuse_light(7)` at (113, 554, 127) + (330, 0, 0),
/// (0, 0, 305), and its two boxes, turned and moved as there, as constant
/// media of density 0.01: the tall one black, the short one white.
fn nw_cornell_smoke() -> Scene {
    let mut s = nw_cornell_box_empty();
    s.quads[2] = quad([113.0, 554.0, 127.0], [330.0, 0.0, 0.0], [0.0, 0.0, 305.0], light([7.0; 3]));
    let smoke = |b: [f32; 3], albedo: [f32; 3]| Medium {
        boundary: MediumBoundary::Box { a: [0.0; 3], b },
        density: 0.01,
        albedo,
    };
    s.groups = vec![
        Group {
            rotate_y: 15.0,
            translate: [265.0, 0.0, 295.0],
            media: vec![smoke([165.0, 330.0, 165.0], [0.0; 3])],
            ..Group::default()
        },
        Group {
            rotate_y: -18.0,
            translate: [130.0, 0.0, 65.0],
            media: vec![smoke([165.0; 3], [1.0; 3])],
            ..Group::default()
        },
    ];
    s
}

/// The Next Week, `final_scene(400, 250, 4)` (v4 `dev`, the book's default
/// build: 400x400, 250 spp, depth 4; the book's image is `final_scene(800,
/// 10000, 40)`): a 20 x 20 ground of boxes of random height (2,400 quads),
/// a two-sided light, a moving sphere, glass, fuzzed metal, a glass sphere
/// filled with a blue medium, a mist over everything (the camera inside it),
/// the earth under `earthmap.jpg` (from `RTOW_IMAGES`), a marble sphere
/// (noise scale 0.2) and 1,000 spheres turned by 15 degrees and moved as one
/// group. Random heights and positions come from rtow's generator.
fn nw_final() -> Scene {
    let mut rng = Xoshiro128Plus::seed_from_u64(FINAL_LAYOUT_SEED);
    let mut rnd = || f32::unit_from_bits(rng.next_u32());
    let mut s = next_week(
        Camera::looking([478.0, 278.0, -600.0], [278.0, 278.0, 0.0], 40.0),
        [0.0; 3],
        settings(400, 400, 250, 4),
    );
    // `--book`: the book's image, `final_scene(800, 10000, 40)`.
    s.render.book = Some(BookTable { width: 800, height: 800, samples_per_pixel: 10_000, max_depth: 40 });
    // The book's mixture: measured faster to every error here than nee-mis,
    // whose shadow rays cross 2,400 boxes and the mist (docs/sampling.md).
    s.render.estimator = Some(EstimatorChoice::Book);
    let ground = lam([0.48, 0.83, 0.53]);
    for i in 0..20 {
        for j in 0..20 {
            let (x0, z0) = (-1000.0 + 100.0 * i as f32, -1000.0 + 100.0 * j as f32);
            let y1 = 1.0 + 100.0 * rnd();
            s.boxes.push(QuadBox { a: [x0, 0.0, z0], b: [x0 + 100.0, y1, z0 + 100.0], material: ground.clone() });
        }
    }
    s.quads = vec![quad([123.0, 554.0, 147.0], [300.0, 0.0, 0.0], [0.0, 0.0, 265.0], light([7.0; 3]))];
    let moving = sphere([400.0, 400.0, 200.0], 50.0, lam([0.7, 0.3, 0.1]));
    s.spheres = vec![
        Sphere { center1: Some([430.0, 400.0, 200.0]), ..moving },
        sphere([260.0, 150.0, 45.0], 50.0, glass(1.5)),
        sphere([0.0, 150.0, 145.0], 50.0, metal([0.8, 0.8, 0.9], 1.0)),
        sphere([360.0, 150.0, 145.0], 70.0, glass(1.5)),
        sphere([400.0, 200.0, 400.0], 100.0, lam_tex(Texture::Image { file: "earthmap.jpg".into() })),
        sphere([220.0, 280.0, 300.0], 80.0, lam_tex(Texture::Noise { scale: 0.2 })),
    ];
    s.media = vec![
        Medium {
            boundary: MediumBoundary::Sphere { center: [360.0, 150.0, 145.0], radius: 70.0 },
            density: 0.2,
            albedo: [0.2, 0.4, 0.9],
        },
        Medium {
            boundary: MediumBoundary::Sphere { center: [0.0; 3], radius: 5000.0 },
            density: 0.0001,
            albedo: [1.0; 3],
        },
    ];
    let white = lam([0.73, 0.73, 0.73]);
    let cloud = (0..1000).map(|_| sphere([165.0 * rnd(), 165.0 * rnd(), 165.0 * rnd()], 10.0, white.clone())).collect();
    s.groups = vec![Group { rotate_y: 15.0, translate: [-100.0, 270.0, 395.0], spheres: cloud, ..Group::default() }];
    s
}

/// The Next Week's image 20: the two boxes axis-aligned, not yet rotated.
fn nw_cornell_box_unrotated() -> Scene {
    let mut s = nw_cornell_box_empty();
    s.boxes = vec![
        QuadBox { a: [130.0, 0.0, 65.0], b: [295.0, 165.0, 230.0], material: NW_WHITE },
        QuadBox { a: [265.0, 0.0, 295.0], b: [430.0, 330.0, 460.0], material: NW_WHITE },
    ];
    s
}

/// Stress: a diffuse sphere of radius 1e6 seen from 1 unit above its top
/// (1e-6 of its radius), looking slightly down: a plane to the horizon.
fn stress_horizon() -> Scene {
    let ground = sphere([0.0, -1e6, 0.0], 1e6, lam([0.5, 0.5, 0.5]));
    let cam = Camera::looking([0.0, 1.0, 0.0], [0.0, 0.0, -20.0], 30.0);
    scene(Mode::Path, cam, vec![ground], settings(400, 225, 32, 50))
}

/// Stress: the final scene from 1e5 away along the book's line of sight, with
/// the field of view (about 0.0027 degrees) that frames the look-at plane as
/// the book does, the book's defocus angle and its focus plane.
fn stress_far_camera() -> Scene {
    let mut s = final_scene();
    let from = glam::DVec3::new(13.0, 2.0, 3.0);
    let book = from.length();
    let dist = 1e5;
    let vfov = 2.0 * (book * 10f64.to_radians().tan() / dist).atan().to_degrees();
    let c = &mut s.camera;
    c.look_from = (from / book * dist).to_array().map(|x| x as f32);
    c.look_at = [0.0; 3];
    c.vfov_deg = vfov as f32;
    c.focus_dist = Some((dist - (book - 10.0)) as f32);
    s
}

static PRESETS: &[Preset] = &[
    Preset {
        name: "ch01-gradient",
        description: "ch. 1: the first image, a red/green gradient (no rays)",
        group: PresetGroup::Weekend,
        build: ch01,
    },
    Preset {
        name: "ch03-sky",
        description: "ch. 3: camera rays and the white-to-blue sky",
        group: PresetGroup::Weekend,
        build: ch03,
    },
    Preset {
        name: "ch04-sphere",
        description: "ch. 4: a sphere hit test, drawn flat red over the sky",
        group: PresetGroup::Weekend,
        build: ch04,
    },
    Preset {
        name: "ch05-normals",
        description: "ch. 5: the sphere shaded by its surface normal",
        group: PresetGroup::Weekend,
        build: ch05_normals,
    },
    Preset {
        name: "ch05-ground",
        description: "ch. 5: normal shading of a list of hitables (sphere + ground)",
        group: PresetGroup::Weekend,
        build: ch05_ground,
    },
    Preset {
        name: "ch06-antialias",
        description: "ch. 6: the same, antialiased with 100 samples per pixel",
        group: PresetGroup::Weekend,
        build: ch06,
    },
    Preset {
        name: "ch07-diffuse",
        description: "ch. 7: Lambertian spheres reflecting half the light, gamma 2",
        group: PresetGroup::Weekend,
        build: ch07,
    },
    Preset {
        name: "ch08-metal",
        description: "ch. 8: two polished metal spheres beside a diffuse one",
        group: PresetGroup::Weekend,
        build: ch08_metal,
    },
    Preset {
        name: "ch08-fuzz",
        description: "ch. 8: the metal spheres with fuzz 0.3 (left) and 1.0 (right)",
        group: PresetGroup::Weekend,
        build: ch08_fuzz,
    },
    Preset {
        name: "ch09-glass",
        description: "ch. 9: a hollow glass ball (negative-radius inner sphere)",
        group: PresetGroup::Weekend,
        build: ch09,
    },
    Preset {
        name: "ch10-wide-fov",
        description: "ch. 10: two touching spheres seen with a 90 degree field of view",
        group: PresetGroup::Weekend,
        build: ch10_wide,
    },
    Preset {
        name: "ch10-look-from",
        description: "ch. 10: the glass scene from (-2,2,1) with vfov 90",
        group: PresetGroup::Weekend,
        build: || ch10_look(90.0),
    },
    Preset {
        name: "ch10-zoom",
        description: "ch. 10: the glass scene from (-2,2,1) with vfov 20",
        group: PresetGroup::Weekend,
        build: || ch10_look(20.0),
    },
    Preset {
        name: "ch11-defocus",
        description: "ch. 11: defocus blur, aperture 2.0 from (3,3,2)",
        group: PresetGroup::Weekend,
        build: ch11,
    },
    Preset {
        name: "final",
        description: "ch. 12: the book's random spheres (486 spheres, thin lens)",
        group: PresetGroup::Weekend,
        build: final_scene,
    },
    Preset {
        name: "nw-bouncing-spheres",
        description: "The Next Week: the random spheres on a checker, lambertians moving (motion blur)",
        group: PresetGroup::NextWeek,
        build: nw_bouncing_spheres,
    },
    Preset {
        name: "nw-checkered-spheres",
        description: "The Next Week: two spheres under the 3-D checker texture (scale 0.32)",
        group: PresetGroup::NextWeek,
        build: nw_checkered_spheres,
    },
    Preset {
        name: "nw-earth",
        description: "The Next Week: the globe under the book's earthmap.jpg (read from RTOW_IMAGES)",
        group: PresetGroup::NextWeek,
        build: nw_earth,
    },
    Preset {
        name: "nw-perlin-spheres",
        description: "The Next Week: a ground and a sphere of Perlin marble (noise scale 4)",
        group: PresetGroup::NextWeek,
        build: nw_perlin_spheres,
    },
    Preset {
        name: "nw-quads",
        description: "The Next Week: five coloured quads (400x400, 100 spp)",
        group: PresetGroup::NextWeek,
        build: nw_quads,
    },
    Preset {
        name: "nw-simple-light",
        description: "The Next Week: a sphere light and a quad light over the two Perlin marble spheres, on black",
        group: PresetGroup::NextWeek,
        build: nw_simple_light,
    },
    Preset {
        name: "nw-cornell-box",
        description: "The Next Week: the Cornell box, two rotated boxes (600x600, 200 spp)",
        group: PresetGroup::NextWeek,
        build: nw_cornell_box,
    },
    Preset {
        name: "nw-final",
        description:
            "The Next Week: its final scene at the book's default build (400x400, 250 spp, depth 4; needs RTOW_IMAGES)",
        group: PresetGroup::NextWeek,
        build: nw_final,
    },
    Preset {
        name: "nw-cornell-smoke",
        description: "The Next Week: the Cornell box's two boxes as smoke, one black, one white (600x600, 200 spp)",
        group: PresetGroup::NextWeek,
        build: nw_cornell_smoke,
    },
    Preset {
        name: "nw-cornell-box-empty",
        description: "The Next Week: the empty Cornell box (its image 19)",
        group: PresetGroup::NextWeek,
        build: nw_cornell_box_empty,
    },
    Preset {
        name: "nw-cornell-box-unrotated",
        description: "The Next Week: the Cornell box with its two boxes axis-aligned (its image 20)",
        group: PresetGroup::NextWeek,
        build: nw_cornell_box_unrotated,
    },
    Preset {
        name: "rol-cornell-box",
        description: "The Rest of Your Life: its final Cornell box, a glass sphere, sampled toward the light and the sphere (600x600, 100 spp)",
        group: PresetGroup::RestOfYourLife,
        build: rol_cornell_box,
    },
    Preset {
        name: "rol-cornell-box-aluminium",
        description: "The Rest of Your Life: the Cornell box with an aluminium box, sampled toward the light (its image 3.12)",
        group: PresetGroup::RestOfYourLife,
        build: rol_cornell_box_aluminium,
    },
    Preset {
        name: "final-mesh",
        description: "book one's final scene with every sphere an icosphere of level 3 (1,280 triangles a sphere)",
        group: PresetGroup::Meshes,
        build: || final_scene().tessellate(3).expect("level 3 is a valid level"),
    },
    Preset {
        name: "cornell-box-mesh",
        description: "The Rest of Your Life's Cornell box with its glass sphere an icosphere of level 4 (5,120 triangles)",
        group: PresetGroup::Meshes,
        build: || rol_cornell_box().tessellate(4).expect("level 4 is a valid level"),
    },
    Preset {
        name: "stress-final-small",
        description: "stress: the final scene scaled by 1e-3 (spheres of radius 2e-4)",
        group: PresetGroup::Stress,
        build: stress_final_small,
    },
    Preset {
        name: "stress-final-large",
        description: "stress: the final scene scaled by 1e3 (a ground of radius 1e6)",
        group: PresetGroup::Stress,
        build: stress_final_large,
    },
    Preset {
        name: "stress-horizon",
        description: "stress: a sphere of radius 1e6 seen from 1 above its surface",
        group: PresetGroup::Stress,
        build: stress_horizon,
    },
    Preset {
        name: "stress-tiny",
        description: "stress: ch. 9's scene with spheres of radius 1e-4",
        group: PresetGroup::Stress,
        build: stress_tiny,
    },
    Preset {
        name: "stress-far-camera",
        description: "stress: the final scene from 1e5 away, vfov 0.0027 degrees",
        group: PresetGroup::Stress,
        build: stress_far_camera,
    },
];

/// Every built-in scene, in chapter order.
pub fn presets() -> &'static [Preset] {
    PRESETS
}

/// The preset of that name.
pub fn preset(name: &str) -> Option<Scene> {
    PRESETS.iter().find(|p| p.name == name).map(|p| (p.build)())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_is_valid() {
        for p in presets() {
            (p.build)().validate().unwrap_or_else(|e| panic!("{}: {e}", p.name));
        }
    }

    #[test]
    fn the_final_scenes_description_counts_its_spheres() {
        let p = presets().iter().find(|p| p.name == "final").unwrap();
        let n = final_scene().spheres.len();
        assert!(p.description.contains(&format!("({n} spheres")), "{}: {n} spheres", p.description);
    }

    #[test]
    fn stress_presets_are_grouped_apart() {
        for p in presets() {
            assert_eq!(p.name.starts_with("stress-"), p.group == PresetGroup::Stress, "{}", p.name);
            assert_eq!(p.name.starts_with("nw-"), p.group == PresetGroup::NextWeek, "{}", p.name);
        }
    }

    #[test]
    fn the_cornell_box_has_the_books_primitives() {
        let s = nw_cornell_box();
        let flat = s.flatten();
        // Five walls, the light, and two boxes of six quads.
        assert_eq!((flat.spheres.len(), flat.quads.len()), (0, 6 + 12));
        assert_eq!(s.render.width, Some(600));
        assert_eq!(s.render.samples_per_pixel, Some(200));
        assert_eq!(s.background, Background::Constant([0.0; 3]));
    }

    #[test]
    fn final_scene_has_the_book_shape() {
        let s = final_scene();
        assert!(s.spheres.len() > 400 && s.spheres.len() <= 1 + 22 * 22 + 3, "{}", s.spheres.len());
        assert_eq!(s.spheres[0].radius, 1000.0);
        let kinds = |k| s.spheres.iter().filter(|sp| sp.material.type_name() == k).count();
        let small = (s.spheres.len() - 4) as f64;
        assert!((kinds("lambertian") as f64 - 2.0) / small > 0.7);
        assert!(kinds("metal") > 30 && kinds("dielectric") > 10);
    }
}
