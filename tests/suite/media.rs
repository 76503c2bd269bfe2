//! Constant-density media (The Next Week's `constant_medium`): transmittance
//! along a chord against `exp(-density x length)`, a camera inside the
//! book's mist, a medium of density 0 that changes no bit, the smoke preset
//! bit for bit across kernels and samplers, and bad media named.

use crate::common;
use common::*;
use rtow::internals::sampling::layout;
use rtow::scene::{self, Background, Camera, Group, Material, Medium, MediumBoundary, Mode, Quad, Scene, Sky, Sphere};
use rtow::KernelChoice::{Scalar, Simd16, Simd8};
use rtow::{Image, Sampler, Settings};

fn empty_scene(camera: Camera) -> Scene {
    Scene {
        meshes: vec![],
        mode: Mode::Path,
        camera,
        spheres: vec![],
        quads: vec![],
        boxes: vec![],
        groups: vec![],
        media: vec![],
        sky: Sky::default(),
        background: Background::Constant([0.0; 3]),
        sample_toward: vec![],
        render: Default::default(),
    }
}

const LIGHT: Material = Material::DiffuseLight { emit: [1.0; 3], one_sided: false };

fn medium(boundary: MediumBoundary, density: f32, albedo: [f32; 3]) -> Medium {
    Medium { boundary, density, albedo }
}

/// The mean of every pixel's red channel.
fn mean(img: &Image) -> f64 {
    img.data.iter().map(|p| p[0] as f64).sum::<f64>() / img.data.len() as f64
}

/// Every camera ray crosses a black (albedo 0) medium along a chord of
/// length `len` before it reaches a light of radiance 1, and nothing else:
/// a sample is 1 when its free flight is longer than the chord (probability
/// `p = exp(-density len)`), else 0. Over `n` samples the mean is within
/// `6 sqrt(p (1 - p) / n)` of `p` (the free-flight values are independent:
/// hashed padding under Sobol, xoshiro for the independent sampler; the
/// binomial tail beyond 6 standard deviations is below 1e-8, whatever the
/// seed), plus `slack` for what the geometry adds (stated at each use), plus
/// the error of `ln` (2 ulp of a value below 20: a shift of the threshold
/// by 1e-5 relative, below 1e-5 in `p`).
fn assert_transmittance(sc: &Scene, density_len: f64, slack: f64, what: &str) {
    let p = (-density_len).exp();
    for sampler in [Sampler::SOBOL, Sampler::Independent] {
        for seed in [0, 7] {
            let s = Settings { sampler, ..settings(48, 48, 256, 2, seed) };
            let n = (48 * 48 * 256) as f64;
            let got = mean(&image(sc, s, Simd8));
            let bound = 6.0 * (p * (1.0 - p) / n).sqrt() + slack + 1e-5;
            eprintln!("{what}, {sampler} seed {seed}: mean {got:.5}, exp(-sigma len) = {p:.5}, bound {bound:.5}");
            assert!(
                (got - p).abs() <= bound,
                "{what}, {sampler} seed {seed}: mean {got}, exp(-sigma len) = {p}, bound {bound}"
            );
        }
    }
}

/// The camera at the centre of the book's mist (a sphere of radius 5000,
/// density 1e-4: the range where the book's `t + 0.0001` re-hit does
/// nothing in f32), inside a light sphere: every ray's chord starts at the
/// camera (t_in < 0, clamped to 0) and is exactly 5000 long (5000^2 and its
/// square root are exact in f32).
#[test]
fn a_camera_inside_the_mist_sees_exp_of_minus_density_times_radius() {
    let mut sc = empty_scene(Camera::looking([0.0; 3], [0.0, 0.0, -1.0], 90.0));
    sc.spheres = vec![Sphere { center1: None, center: [0.0; 3], radius: 6000.0, material: LIGHT }];
    sc.media = vec![medium(MediumBoundary::Sphere { center: [0.0; 3], radius: 5000.0 }, 1e-4, [0.0; 3])];
    assert_transmittance(&sc, 0.5, 0.0, "mist");
}

/// A slab 2 thick (the box |z| <= 1 of a group turned by 60 degrees about y,
/// moved to z = -5) seen along -z through a 0.01 degree field of view: the
/// central ray's chord is 2 / cos 60 = 4, but the light quad sits in the
/// slab's middle plane (z = -5), so the chord is clamped at the surface hit:
/// 2 long. Off-axis rays (at most 1.3e-4 rad off -z) see chords longer by
/// at most a relative `tan 60 x 1.3e-4 + 1e-8`, which moves `p` by less than
/// `0.5 x 2.3e-4 x p`: 1e-4 of slack.
#[test]
fn transmittance_through_a_turned_box_stops_at_the_surface() {
    let mut sc = empty_scene(Camera::looking([0.0; 3], [0.0, 0.0, -1.0], 0.01));
    sc.quads = vec![Quad { q: [-100.0, -100.0, -5.0], u: [200.0, 0.0, 0.0], v: [0.0, 200.0, 0.0], material: LIGHT }];
    let slab = MediumBoundary::Box { a: [-50.0, -50.0, -1.0], b: [50.0, 50.0, 1.0] };
    sc.groups = vec![Group {
        rotate_y: 60.0,
        translate: [0.0, 0.0, -5.0],
        media: vec![medium(slab, 0.25, [0.0; 3])],
        ..Group::default()
    }];
    assert_transmittance(&sc, 0.25 * 2.0, 1e-4, "turned slab");
}

/// The smoke preset, plus a glass sphere that is also a medium's boundary
/// (the book's subsurface sphere) overlapping the white smoke, and a mist
/// around everything: the same image from the scalar kernel and every lane
/// width, with either sampler.
#[test]
fn media_render_the_same_image_on_every_kernel() {
    let mut sc = scene::preset("nw-cornell-smoke").unwrap();
    let glass = Sphere {
        center1: None,
        center: [200.0, 120.0, 150.0],
        radius: 70.0,
        material: Material::Dielectric { ior: 1.5 },
    };
    sc.spheres.push(glass.clone());
    sc.media.push(medium(MediumBoundary::Sphere { center: glass.center, radius: 70.0 }, 0.2, [0.2, 0.4, 0.9]));
    sc.media.push(medium(MediumBoundary::Sphere { center: [278.0, 278.0, 0.0], radius: 5000.0 }, 1e-4, [1.0; 3]));
    for sampler in [Sampler::SOBOL, Sampler::Independent] {
        let s = Settings { sampler, ..settings(24, 24, 4, 12, 3) };
        let want = image(&sc, s, Scalar);
        assert!(mean(&want) > 0.0, "a dark image proves nothing");
        for k in [Simd8, Simd16] {
            assert_identical(&want, &image(&sc, s, k), &format!("{sampler} {k:?}"));
        }
    }
    let s = settings(20, 20, 2, 50, 1);
    let smoke = scene::preset("nw-cornell-smoke").unwrap();
    let want = image(&smoke, s, Scalar);
    for k in [Simd8, Simd16] {
        assert_identical(&want, &image(&smoke, s, k), &format!("nw-cornell-smoke {k:?}"));
    }
}

/// Media of density 0 (the smoke boxes, and a mist around the camera that
/// stays inside the room's extent) leave every bit of the Cornell box as it
/// was: their free flights are infinite, and their draws are at dimensions
/// of their own (under Sobol; the independent sampler's stream would shift).
#[test]
fn a_medium_of_density_zero_is_invisible() {
    let plain = scene::preset("nw-cornell-box").unwrap();
    let mut zero = plain.clone();
    let smoke = scene::preset("nw-cornell-smoke").unwrap();
    for (g, sg) in zero.groups.iter_mut().zip(&smoke.groups) {
        g.media = sg.media.iter().map(|m| Medium { density: 0.0, ..*m }).collect();
    }
    zero.media = vec![medium(MediumBoundary::Sphere { center: [278.0, 278.0, -500.0], radius: 300.0 }, 0.0, [1.0; 3])];
    let s = settings(24, 24, 4, 50, 5);
    for k in [Scalar, Simd8, Simd16] {
        assert_identical(&image(&plain, s, k), &image(&zero, s, k), &format!("density 0, {k:?}"));
    }
}

#[test]
fn the_free_flight_dimensions_are_their_own() {
    // Far above every bounce's dimensions, one per (medium, bounce), apart.
    assert_eq!(layout::free_flight(0, 0), 0x4000_1000);
    assert_eq!(layout::free_flight(3, 0), 0x4000_1003);
    assert_eq!(layout::free_flight(0, 1), 0x4000_1000 + (1 << 22));
    assert!(layout::roulette(1 << 20) < layout::free_flight(0, 0));
}

#[test]
fn the_smoke_preset_is_the_books() {
    let s = scene::preset("nw-cornell-smoke").unwrap();
    let flat = s.flatten();
    assert_eq!((flat.spheres.len(), flat.quads.len(), flat.media.len()), (0, 6, 2));
    assert_eq!(flat.media[0].albedo, [0.0; 3]);
    assert_eq!(flat.media[1].albedo, [1.0; 3]);
    assert!(flat.media.iter().all(|m| m.density == 0.01));
    assert_eq!(flat.quads[2].q, [113.0, 554.0, 127.0]);
    assert_eq!(flat.quads[2].material, Material::DiffuseLight { emit: [7.0; 3], one_sided: false });
    assert_eq!((s.render.width, s.render.samples_per_pixel, s.render.max_depth), (Some(600), Some(200), Some(50)));
}

#[test]
fn bad_media_are_named() {
    let base = scene::preset("nw-cornell-smoke").unwrap();
    let err = |f: &dyn Fn(&mut Scene)| {
        let mut sc = base.clone();
        f(&mut sc);
        sc.validate().unwrap_err().to_string()
    };
    assert!(err(&|s| s.groups[0].media[0].density = -0.5).contains("groups[0].media[0].density"));
    assert!(err(&|s| s.groups[0].media[0].density = f32::NAN).contains("groups[0].media[0].density"));
    assert!(err(&|s| s.groups[1].media[0].albedo = [0.0, -1.0, 0.0]).contains("groups[1].media[0].albedo"));
    let flat = MediumBoundary::Box { a: [0.0; 3], b: [1.0, 1.0, 0.0] };
    assert!(err(&|s| s.groups[1].media[0].boundary = flat).contains("groups[1].media[0].boundary.box.b"));
    let huge = MediumBoundary::Sphere { center: [0.0; 3], radius: 2e6 };
    assert!(err(&|s| s.media = vec![medium(huge, 1.0, [1.0; 3])]).contains("media[0].boundary.sphere.radius"));
    let far = Group { translate: [999_990.0, 0.0, 0.0], ..base.groups[0].clone() };
    assert!(err(&|s| s.groups.push(far.clone())).contains("groups[2].translate"));
    let one = medium(MediumBoundary::Sphere { center: [0.0; 3], radius: 1.0 }, 1.0, [1.0; 3]);
    let e = err(&|s| s.media = vec![one; rtow::limits::MAX_MEDIA - 1]);
    assert!(e.contains("media") && e.contains("at most 64"), "{e}");
}
