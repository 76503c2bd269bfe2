//! Physics: tests that a wrong renderer fails.

use crate::common;
use common::*;
use glam::DVec3;
use rtow::scene::{self, Camera, Material, Mode, Scene, Sky, Sphere};
use rtow::KernelChoice::{self, Scalar, Simd};

const KERNELS: [KernelChoice; 2] = [Scalar, Simd];

fn one_sphere(material: Material, sky: Sky) -> Scene {
    Scene {
        meshes: vec![],
        mode: Mode::Path,
        camera: Camera::looking([0.0, 0.0, 3.0], [0.0, 0.0, 0.0], 40.0),
        spheres: vec![Sphere { center: [0.0, 0.0, 0.0], center1: None, radius: 1.0, material }],
        quads: vec![],
        boxes: vec![],
        groups: vec![],
        media: vec![],
        sky,
        background: Default::default(),
        sample_toward: vec![],
        render: Default::default(),
    }
}

/// An albedo-1 diffuse sphere under a uniform white sky is white everywhere:
/// every path escapes with throughput 1. With max depth 2 a single re-hit of
/// the sphere (shadow acne) would turn a sample black.
#[test]
fn white_furnace() {
    let sc = one_sphere(Material::Lambertian { albedo: [1.0; 3].into() }, Sky::uniform([1.0; 3]));
    for kernel in KERNELS {
        for depth in [2, 50] {
            let img = image(&sc, settings(48, 32, 8, depth, 1), kernel);
            for p in &img.data {
                assert_eq!(*p, [1.0; 3], "{kernel:?} depth {depth}");
            }
        }
    }
}

/// A glass sphere of ior 1 is no interface: the image equals the empty sky's.
#[test]
fn glass_of_ior_one_is_invisible() {
    let sc = one_sphere(Material::Dielectric { ior: 1.0 }, Sky::default());
    let mut empty = sc.clone();
    empty.spheres.clear();
    for kernel in KERNELS {
        let s = settings(48, 32, 4, 50, 9);
        assert_identical(&image(&sc, s, kernel), &image(&empty, s, kernel), "ior 1");
    }
    // ...while ior 1.5 is visible.
    let glass = one_sphere(Material::Dielectric { ior: 1.5 }, Sky::default());
    let s = settings(48, 32, 4, 50, 9);
    assert_ne!(image(&glass, s, Simd).hash(), image(&empty, s, Simd).hash());
}

fn sky_f64(sky: &Sky, d: DVec3) -> DVec3 {
    let a = 0.5 * (d.normalize().y + 1.0);
    let h = DVec3::from_array(sky.horizon.map(f64::from));
    let z = DVec3::from_array(sky.zenith.map(f64::from));
    h * (1.0 - a) + z * a
}

/// The camera ray through a pixel centre, in f64 (the book's camera).
fn camera_ray(cam: &Camera, w: u32, h: u32, x: u32, y: u32) -> (DVec3, DVec3) {
    let from = DVec3::from_array(cam.look_from.map(f64::from));
    let at = DVec3::from_array(cam.look_at.map(f64::from));
    let vup = DVec3::from_array(cam.vup.map(f64::from));
    let focus = (from - at).length();
    let vh = 2.0 * (cam.vfov_deg as f64).to_radians().mul_add(0.5, 0.0).tan() * focus;
    let vw = vh * w as f64 / h as f64;
    let wv = (from - at).normalize();
    let u = vup.cross(wv).normalize();
    let v = wv.cross(u);
    let px = (x as f64 + 0.5) / w as f64 - 0.5;
    let py = 0.5 - (y as f64 + 0.5) / h as f64;
    let target = from - wv * focus + u * (px * vw) + v * (py * vh);
    (from, (target - from).normalize())
}

fn hit_f64(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<f64> {
    let f = o - c;
    let b = f.dot(d);
    let disc = b * b - (f.dot(f) - r * r);
    (disc >= 0.0).then(|| -b - disc.sqrt()).filter(|t| *t > 0.0)
}

/// A perfect mirror (albedo 1, fuzz 0) shows the reflected sky exactly.
#[test]
fn mirror_reflects_the_sky() {
    let sc = one_sphere(Material::Metal { albedo: [1.0; 3], fuzz: 0.0 }, Sky::default());
    let (w, h) = (40, 30);
    for kernel in KERNELS {
        let img = image(&sc, settings(w, h, 1, 50, 0), kernel);
        let mut mirrored = 0;
        for y in 0..h {
            for x in 0..w {
                let (o, d) = camera_ray(&sc.camera, w, h, x, y);
                let want = match hit_f64(o, d, DVec3::ZERO, 1.0) {
                    Some(t) => {
                        mirrored += 1;
                        let n = (o + d * t).normalize();
                        sky_f64(&sc.sky, d - 2.0 * d.dot(n) * n)
                    }
                    None => sky_f64(&sc.sky, d),
                };
                let got = DVec3::from_array(img.get(x, y).map(f64::from));
                assert!((got - want).abs().max_element() < 2e-5, "{kernel:?} ({x},{y}): {got} vs {want}");
            }
        }
        assert!(mirrored > 200, "the sphere covers part of the image");
    }
}

#[test]
fn ch01_gradient_pixels() {
    let sc = scene::preset("ch01-gradient").unwrap();
    let img = image(&sc, settings(200, 100, 1, 1, 0), Simd);
    for (x, y) in [(0, 0), (199, 99), (50, 25), (100, 0)] {
        let want = [x as f32 / 200.0, (99 - y) as f32 / 100.0, 0.2];
        assert_eq!(img.get(x, y), want, "({x},{y})");
    }
}

#[test]
fn ch03_sky_pixels() {
    let sc = scene::preset("ch03-sky").unwrap();
    let (w, h) = (64, 36);
    for kernel in KERNELS {
        let img = image(&sc, settings(w, h, 1, 1, 0), kernel);
        for (x, y) in [(0, 0), (63, 35), (32, 18), (10, 30)] {
            let want = sky_f64(&sc.sky, camera_ray(&sc.camera, w, h, x, y).1);
            let got = DVec3::from_array(img.get(x, y).map(f64::from));
            assert!((got - want).abs().max_element() < 1e-6, "({x},{y}): {got} vs {want}");
        }
    }
}

#[test]
fn ch04_and_ch05_pixels() {
    let (w, h) = (64, 36);
    let flat = scene::preset("ch04-sphere").unwrap();
    let normals = scene::preset("ch05-normals").unwrap();
    for kernel in KERNELS {
        let fi = image(&flat, settings(w, h, 1, 1, 0), kernel);
        let ni = image(&normals, settings(w, h, 1, 1, 0), kernel);
        for y in 0..h {
            for x in 0..w {
                let (o, d) = camera_ray(&flat.camera, w, h, x, y);
                let c = DVec3::new(0.0, 0.0, -1.0);
                let (want_flat, want_normal) = match hit_f64(o, d, c, 0.5) {
                    Some(t) => (DVec3::X, ((o + d * t - c) / 0.5 + DVec3::ONE) * 0.5),
                    None => (sky_f64(&flat.sky, d), sky_f64(&flat.sky, d)),
                };
                let got = DVec3::from_array(fi.get(x, y).map(f64::from));
                assert!((got - want_flat).abs().max_element() < 1e-6, "ch04 ({x},{y})");
                let got = DVec3::from_array(ni.get(x, y).map(f64::from));
                assert!((got - want_normal).abs().max_element() < 1e-5, "ch05 ({x},{y}): {got} {want_normal}");
            }
        }
        // The centre of the sphere faces the camera: normal (0, 0, 1).
        let c = ni.get(w / 2, h / 2);
        assert!((c[2] - 1.0).abs() < 1e-3 && (c[0] - 0.5).abs() < 0.05 && (c[1] - 0.5).abs() < 0.05);
    }
}

/// Chapter 7: the sky (top rows) is brighter than the grey diffuse ground
/// (bottom rows), which reflects at most half of the light it receives.
#[test]
fn ch07_is_darker_below_the_horizon() {
    let sc = scene::preset("ch07-diffuse").unwrap();
    let img = image(&sc, settings(32, 18, 16, 50, 3), Simd);
    let row_mean = |y: u32| (0..32).map(|x| img.get(x, y)[1]).sum::<f32>() / 32.0;
    assert!(row_mean(1) > row_mean(16) + 0.1);
}
