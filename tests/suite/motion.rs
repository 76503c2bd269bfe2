//! Motion blur (The Next Week, part 2): moving spheres against the static
//! sphere test (bit for bit) and an f64 oracle (within a derived bound), every
//! walk against brute force at per-lane times, the path's time kept by its
//! scattered rays, `nw-bouncing-spheres` bit for bit across kernels and
//! samplers, and bad input named.

use crate::common;
use common::*;
use glam::DVec3;
use proptest::prelude::*;
use rtow::internals::geometry::{
    centre_at, closest_brute, Bvh, Closest, LeafMoving, MovingSpheres, Primitive, Spheres, Walk, MISS, MOVING_BASE,
};
use rtow::internals::handle::Kind;
use rtow::internals::real::{Real, Wide};
use rtow::internals::vec3::V3;
use rtow::scene::{self, Background, Camera, Format, Material, Mode, Scene, Sky, Sphere};
use rtow::KernelChoice::{Scalar, Simd16, Simd8};
use rtow::{AccelChoice, Sampler};
use std::path::Path;
use wide::{f32x16, f32x8};

/// f32's unit roundoff.
const U: f64 = 1.0 / 16_777_216.0;

fn d3(v: [f32; 3]) -> DVec3 {
    DVec3::from_array(v.map(f64::from))
}

fn moving(list: &[([f32; 3], [f32; 3], f32)]) -> MovingSpheres {
    let mut m = MovingSpheres::default();
    for &(c0, c1, r) in list {
        m.push(c0, c1, r, Kind::Lambertian, 0);
    }
    m.pad();
    m
}

/// A ray from outside the sphere `(c, r)`, at distance `dist` (at least
/// `2r`) from its centre, in direction `dir` (any), aimed at a point `aim`
/// (in units of `r/2`, each coordinate in [-1, 1] scaled by `1/sqrt 3`) off the
/// centre: it passes within `r/2` of the centre, so it hits at an incidence
/// whose cosine is at least `sqrt(3)/2`. The direction is rounded from f64.
fn ray_at(c: DVec3, r: f64, dist: f64, dir: DVec3, aim: DVec3) -> (V3<f32>, V3<f32>) {
    let dir = if dir.length() < 1e-3 { DVec3::Z } else { dir.normalize() };
    let o = (c + dir * dist).to_array().map(|x| x as f32);
    let target = c + aim * (0.5 * r / 3f64.sqrt());
    let d = (target - d3(o)).normalize().to_array().map(|x| x as f32);
    (V3::from_array(o), V3::from_array(d))
}

/// The f64 hit distance of the ray `o + s d` (its f32 values, exactly) with
/// the sphere `(c, r)`, from outside: the smaller root.
fn oracle(o: V3<f32>, d: V3<f32>, c: DVec3, r: f64) -> Option<f64> {
    let (o, d) = (d3(o.to_array()), d3(d.to_array()));
    let f = o - c;
    let (a, b, cc) = (d.dot(d), f.dot(d), f.dot(f) - r * r);
    let disc = b * b - a * cc;
    (disc >= 0.0).then(|| (-b - disc.sqrt()) / a)
}

fn v3s(lo: f32, hi: f32) -> impl Strategy<Value = [f32; 3]> {
    [lo..hi, lo..hi, lo..hi]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// The hit of a moving sphere at time `t` is the hit of the static sphere
    /// at `c(t) = c0 + t v` as the kernels compute it (the same bits), and lies
    /// within a derived bound of the exact hit of the exact moving sphere.
    ///
    /// The bound: the centre is rounded by at most `delta = 2u (|c0| + |v|)`
    /// (per component `u |v_k t|` for the product and `u |c_k(t)|` for the
    /// sum). The static test puts the hit point within
    /// `(9u + 4 eta)|f| + (7u + 2 eta) r` of its sphere and rounds the root
    /// (returned as `c' / q` from outside) by `E / |q| + 3u t`, where
    /// `E <= (17.75u + 6 eta)|f|^2` for these rays (`|f| >= 2r`, `h <= r/2`,
    /// so `|q| >= 0.968 |f|`, `E / |q| <= (18.4u + 6.2 eta)|f|`): the module
    /// bounds of `geometry/spheres.rs`, first order. A distance `e` off the
    /// sphere moves the hit along the ray by at most `e / cos`, `cos >= sqrt(3)/2`.
    /// The first-order bound is doubled for the second-order terms (of
    /// relative size `u`).
    #[test]
    fn a_moving_sphere_is_the_static_sphere_at_its_centre_then(
        c0 in v3s(-100.0, 100.0),
        v in v3s(-10.0, 10.0),
        r in 0.1f32..10.0,
        bits in any::<u32>(),
        dist in 2.0f64..100.0,
        dir in v3s(-1.0, 1.0),
        aim in v3s(-1.0, 1.0),
    ) {
        let t = f32::unit_from_bits(bits);
        let c1: [f32; 3] = std::array::from_fn(|k| c0[k] + v[k]);
        let m = moving(&[(c0, c1, r)]);
        let vel = m.v(0);
        let c = centre_at(V3::from_array(c0), V3::from_array(vel), t);
        prop_assert_eq!(c.to_array(), m.centre(0, t).to_array());
        // The exact centre (the f32 values of c0, v and t, in f64).
        let exact_c = d3(c0) + d3(vel) * t as f64;
        let (o, d) = ray_at(exact_c, r as f64, dist * r as f64, d3(dir), d3(aim));
        let mut best = Closest::<f32>::none();
        m.brute::<_, _, false>(o, d, t, &mut best, &mut ());
        let (si, st) = closest_brute(&Spheres::one(c.to_array(), r), o, d, 0.0, &mut ());
        prop_assert_eq!(si, 0);
        prop_assert_eq!(best.index, MOVING_BASE);
        prop_assert_eq!(best.t.to_bits(), st.to_bits(), "the static sphere at c(t)");
        let want = oracle(o, d, exact_c, r as f64).expect("aimed within r/2 of the centre");
        let f = (d3(o.to_array()) - d3(c.to_array())).length();
        let eta = (d3(d.to_array()).length() - 1.0).abs();
        let delta = 2.0 * U * (d3(c0).length() + d3(vel).length());
        let cos = 3f64.sqrt() / 2.0;
        let first = ((9.0 * U + 4.0 * eta) * f + (7.0 * U + 2.0 * eta) * r as f64 + delta) / cos
            + (18.4 * U + 6.2 * eta) * f
            + 3.0 * U * want;
        let err = (st as f64 - want).abs();
        prop_assert!(err <= 2.0 * first, "t {} against {}: error {:e} above {:e}", st, want, err, 2.0 * first);
    }

    /// Many moving spheres: the tree over the shutter interval finds brute
    /// force's closest hit (same sphere, same bits) at every time, one ray at
    /// a time and in packets whose lanes have different times.
    #[test]
    fn the_moving_tree_finds_brute_forces_hit_at_every_time(
        list in prop::collection::vec((v3s(-20.0, 20.0), v3s(-5.0, 5.0), 0.05f32..3.0), 1..120),
        rays in prop::collection::vec((v3s(-40.0, 40.0), v3s(-1.0, 1.0), any::<u32>()), 1..40),
    ) {
        let list: Vec<_> =
            list.iter().map(|&(c0, v, r)| (c0, std::array::from_fn(|k| c0[k] + v[k]), r)).collect();
        let m = moving(&list);
        let bvh = Bvh::build(&m, 60.0, Walk::OneByOne);
        let rays: Vec<_> = rays
            .iter()
            .map(|&(o, d, bits)| {
                let d = d3(d);
                let d = if d.length() < 1e-3 { DVec3::Z } else { d.normalize() };
                (V3::from_array(o), V3::from_array(d.to_array().map(|x| x as f32)), f32::unit_from_bits(bits))
            })
            .collect();
        let brute = |o, d, t| {
            let mut best = Closest::<f32>::none();
            m.brute::<_, _, false>(o, d, t, &mut best, &mut ());
            (best.index, best.t.to_bits())
        };
        for &(o, d, t) in &rays {
            let mut tree = Closest::<f32>::none();
            tree = bvh.walk::<f32, (), false>(o, d, t, tree, &mut ());
            prop_assert_eq!(brute(o, d, t), (tree.index, tree.t.to_bits()));
        }
        packets::<f32x8>(&bvh, &rays, &brute)?;
        packets::<f32x16>(&bvh, &rays, &brute)?;
    }
}

fn packets<W: Wide>(
    bvh: &Bvh<LeafMoving>,
    rays: &[(V3<f32>, V3<f32>, f32)],
    brute: &dyn Fn(V3<f32>, V3<f32>, f32) -> (u32, u32),
) -> Result<(), TestCaseError> {
    for chunk in rays.chunks(W::LANES) {
        let at = |k: usize| chunk[k.min(chunk.len() - 1)];
        let lanes = |f: &dyn Fn(usize) -> f32| W::from_fn(f);
        let o = V3::new(lanes(&|k| at(k).0.x), lanes(&|k| at(k).0.y), lanes(&|k| at(k).0.z));
        let d = V3::new(lanes(&|k| at(k).1.x), lanes(&|k| at(k).1.y), lanes(&|k| at(k).1.z));
        let t = lanes(&|k| at(k).2);
        let mut best = Closest::<W>::none();
        best = bvh.walk::<W, (), false>(o, d, t, best, &mut ());
        for (k, &(o, d, t)) in chunk.iter().enumerate() {
            prop_assert_eq!(brute(o, d, t), (W::lane_u(best.index, k), best.t.lane(k).to_bits()), "lane {}", k);
        }
    }
    Ok(())
}

/// At time 0 a moving sphere is exactly its first centre; a sphere that
/// does not move (`center1 = center`) is hit where the static one is.
#[test]
fn time_zero_and_zero_motion_are_the_static_sphere() {
    let c0 = [1.5f32, -2.25, 7.0];
    let m = moving(&[(c0, [4.0, 0.5, -3.0], 1.25), (c0, c0, 1.25)]);
    assert_eq!(m.centre(0, 0.0).to_array(), c0);
    assert_eq!(m.centre(1, 0.75).to_array(), c0);
    let s = Spheres::one(c0, 1.25);
    let (o, d) = (V3::new(0.0f32, 0.0, -20.0), V3::new(0.0f32, 0.0, 1.0));
    let mut a = Closest::<f32>::none();
    moving(&[(c0, c0, 1.25)]).brute::<_, _, false>(o, V3::new(0.05, -0.1, 1.0).normalize(), 0.3, &mut a, &mut ());
    let (_, st) = closest_brute(&s, o, V3::new(0.05, -0.1, 1.0).normalize(), 0.0, &mut ());
    assert_eq!(a.t.to_bits(), st.to_bits());
    let mut miss = Closest::<f32>::none();
    m.brute::<_, _, false>(o, d, 0.0, &mut miss, &mut ());
    assert_eq!(miss.index, MISS);
}

/// A camera inside a closed lambertian sphere that moves (its centre goes
/// from the origin to (3, 0, 0) over the shutter; the camera at (0.5, 0, 0)
/// is inside it at every time), under a white background: a path that keeps
/// its time never leaves the sphere (every ray starts inside it at that time
/// and hits it), so the image is exactly black. Were a scattered ray traced
/// at another time (redrawn, or 0), a point on the sphere's leading side at
/// time t lies outside the sphere of any earlier time, and rays leaving it
/// would escape to the white background.
#[test]
fn scattered_rays_keep_their_paths_time() {
    let mut sc = Scene {
        meshes: vec![],
        mode: Mode::Path,
        camera: Camera::looking([0.5, 0.0, 0.0], [0.5, 0.0, -1.0], 90.0),
        spheres: vec![Sphere {
            center: [0.0; 3],
            center1: Some([3.0, 0.0, 0.0]),
            radius: 4.0,
            material: Material::Lambertian { albedo: [0.9, 0.9, 0.9].into() },
        }],
        quads: vec![],
        boxes: vec![],
        groups: vec![],
        media: vec![],
        sky: Sky::default(),
        background: Background::Constant([1.0; 3]),
        sample_toward: vec![],
        render: Default::default(),
    };
    for sampler in [Sampler::SOBOL, Sampler::Independent] {
        let s = rtow::Settings { sampler, ..settings(24, 24, 8, 12, 3) };
        for kernel in [Scalar, Simd8, Simd16] {
            let img = image(&sc, s, kernel);
            let lit = img.data.iter().filter(|p| p.iter().any(|&x| x != 0.0)).count();
            assert_eq!(lit, 0, "{kernel:?} {sampler}: {lit} pixels saw the background");
        }
    }
    // The test can see the background: from outside the sphere, it shows.
    sc.camera = Camera::looking([0.5, 0.0, 12.0], [0.5, 0.0, 0.0], 90.0);
    let img = image(&sc, settings(24, 24, 4, 12, 3), Simd8);
    assert!(img.data.iter().any(|p| p[0] > 0.5), "outside, the background shows");
}

/// `nw-bouncing-spheres` at a small size: the same image with the scalar
/// kernel, 8 and 16 lanes, brute force and the trees, with either sampler;
/// and its lambertian spheres really move (the image differs from the same
/// scene at rest).
#[test]
fn bouncing_spheres_are_bit_identical_across_kernels_and_samplers() {
    let sc = scene::preset("nw-bouncing-spheres").unwrap();
    let flat = sc.flatten();
    let moving = flat.spheres.iter().filter(|s| s.center1.is_some()).count();
    assert!(moving > 300 && moving < flat.spheres.len(), "{moving} of {}", flat.spheres.len());
    for sampler in [Sampler::SOBOL, Sampler::Independent] {
        let s = rtow::Settings { sampler, ..settings(48, 27, 4, 50, 1) };
        let reference = render_accel(&sc, s, Scalar, 2, 16, AccelChoice::Auto);
        assert_eq!(reference.stats.rejected_samples, 0);
        for (kernel, accel) in [
            (Scalar, AccelChoice::Brute),
            (Simd8, AccelChoice::Auto),
            (Simd8, AccelChoice::Brute),
            (Simd16, AccelChoice::Auto),
        ] {
            let other = render_accel(&sc, s, kernel, 2, 16, accel);
            assert_identical(&reference.image, &other.image, &format!("{kernel:?} {accel:?} {sampler}"));
            assert_eq!(reference.stats.rays, other.stats.rays);
        }
        let mut still = sc.clone();
        still.spheres.iter_mut().for_each(|s| s.center1 = None);
        assert_ne!(image(&still, s, Simd8).hash(), reference.image.hash(), "{sampler}");
    }
}

/// `center1` is read, written back by `rtow export`, and checked.
#[test]
fn center1_round_trips_and_is_checked() {
    let json = r#"{"camera": {"look_from": [0,0,5], "look_at": [0,0,0]},
        "spheres": [{"center": [0,0,0], "center1": [0,0.5,0], "radius": 1,
                     "material": {"type": "lambertian", "albedo": [0.5,0.5,0.5]}}]}"#;
    let sc = scene::scene_from_str(json, Format::Json, Path::new("x.json")).unwrap();
    sc.validate().unwrap();
    assert_eq!(sc.spheres[0].center1, Some([0.0, 0.5, 0.0]));
    for format in [Format::Json, Format::Toml] {
        let text = scene::scene_to_string(&sc, format);
        assert!(text.contains("center1"), "{text}");
        assert_eq!(scene::scene_from_str(&text, format, Path::new("x")).unwrap(), sc);
    }
    // A static sphere writes no center1.
    let mut still = sc.clone();
    still.spheres[0].center1 = None;
    assert!(!scene::scene_to_string(&still, Format::Json).contains("center1"));
    let err = |c1: [f32; 3]| {
        let mut bad = sc.clone();
        bad.spheres[0].center1 = Some(c1);
        bad.validate().unwrap_err().to_string()
    };
    assert!(err([f32::NAN, 0.0, 0.0]).contains("spheres[0].center1"));
    assert!(err([0.0, f32::INFINITY, 0.0]).contains("spheres[0].center1"));
    assert!(err([0.0, 0.0, 2e6]).contains("spheres[0].center1"));
}
