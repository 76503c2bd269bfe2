//! One estimator: the SIMD wavefront kernel reproduces the scalar reference
//! kernel bit for bit, on every preset and on random scenes; and images do not
//! depend on thread count or tile size.

use crate::common;
use common::*;
use proptest::prelude::*;
use rtow::scene::{self, Background, Camera, Group, Material, Mode, Quad, QuadBox, Scene, Sky, Sphere};
use rtow::KernelChoice::{self, Scalar, Simd, Simd16, Simd8};
use rtow::{AccelChoice, EstimatorChoice, Kernel, RenderOptions, Settings};

/// Every SIMD kernel this build has (8 lanes; 16 on AVX-512 builds), with
/// every accelerator, against the scalar kernel with brute force.
fn others() -> Vec<(KernelChoice, AccelChoice)> {
    let mut v = vec![(Scalar, AccelChoice::Bvh)];
    for k in [Simd8, Simd16].into_iter() {
        for a in [AccelChoice::Brute, AccelChoice::Bvh, AccelChoice::BvhRay] {
            v.push((k, a));
        }
    }
    v
}

#[test]
fn simd_is_the_widest_kernel_of_the_build() {
    let widest = if rtow::HAS_SIMD16 { Kernel::Simd16 } else { Kernel::Simd8 };
    assert_eq!(Kernel::resolve(Simd), widest);
    // Every build has both widths (16 lanes are two 8-lane halves without AVX-512).
    assert_eq!(Kernel::resolve(Simd16), Kernel::Simd16);
    assert_eq!(Kernel::resolve(Simd8), Kernel::Simd8);
}

#[test]
fn every_preset_is_bit_identical_across_kernels() {
    // CI's baseline instruction set runs the kernel tests unoptimized
    // (`--cfg rtow_kernel_tests`, .ci/run), where brute force over a mesh
    // of 5,120 triangles takes minutes and the tree of one of hundreds of
    // thousands a few seconds a render: there every mesh's reference is the
    // scalar tree, and the big meshes are left out (the trees find brute
    // force's hits bit for bit: tests/suite/kernels/triangles.rs, unoptimized
    // too); every other build runs them all.
    let quick = cfg!(rtow_kernel_tests);
    for p in scene::presets() {
        let sc = self_contained(&(p.build)());
        let d = scene_settings(&sc);
        // Small images, the preset's own depth and estimator, a few samples (jitter on).
        let s = Settings { estimator: d.estimator, ..settings(40, 24, 3, d.max_depth, 11) };
        // Brute force over a mesh of hundreds of thousands of triangles takes
        // minutes even optimized: there the scalar tree is the reference.
        let triangles = sc.generated_triangles();
        if quick && triangles > 10_000 {
            continue;
        }
        let big = triangles > if quick { 0 } else { 10_000 };
        let reference = if big { AccelChoice::Bvh } else { AccelChoice::Brute };
        let a = render_accel(&sc, s, Scalar, 2, 16, reference);
        for (kernel, accel) in others().into_iter().filter(|&(_, a)| !big || a != AccelChoice::Brute) {
            let b = render_accel(&sc, s, kernel, 2, 16, accel);
            assert_identical(&a.image, &b.image, &format!("{} {kernel:?} {accel:?}", p.name));
            assert_eq!(a.stats.rays, b.stats.rays, "{}: ray counts differ", p.name);
        }
        assert_eq!(a.stats.rejected_samples, 0, "{}", p.name);
        // The tools' counting probe (`--stats-json`, `rtow bench`'s work)
        // renders the same image.
        for kernel in [Scalar, Simd] {
            let opts = RenderOptions { kernel, threads: Some(2), tile: 16, accel: reference, ..Default::default() };
            let counted = rtow::render_counted(&job(&sc, s, opts), None).expect("render");
            assert_identical(&a.image, &counted.image, &format!("{} {kernel:?} counted", p.name));
        }
        // 1 spp takes pixel centres (no jitter): also identical.
        let s1 = settings(24, 16, 1, d.max_depth, 3);
        assert_identical(&image(&sc, s1, Scalar), &image(&sc, s1, Simd), p.name);
    }
}

#[test]
fn images_do_not_depend_on_threads_or_tiles() {
    let sc = scene::final_scene();
    let s = settings(37, 21, 2, 50, 5);
    for kernel in [Scalar, Simd8, Simd] {
        let base = render_with(&sc, s, kernel, 1, 16).image;
        for (threads, tile) in [(2, 16), (1, 7), (2, 5), (2, 45)] {
            let other = render_with(&sc, s, kernel, threads, tile).image;
            assert_identical(&base, &other, &format!("{kernel:?} threads {threads} tile {tile}"));
        }
    }
}

#[test]
fn different_seeds_give_different_noise() {
    let sc = scene::preset("ch07-diffuse").unwrap();
    let a = image(&sc, settings(16, 9, 2, 10, 1), Simd);
    let b = image(&sc, settings(16, 9, 2, 10, 2), Simd);
    assert_ne!(a.hash(), b.hash());
}

fn arb_material() -> impl Strategy<Value = Material> {
    let col = prop::array::uniform3(0.0f32..1.0);
    prop_oneof![
        col.clone().prop_map(|albedo| Material::Lambertian { albedo: albedo.into() }),
        (col, 0.0f32..=1.0).prop_map(|(albedo, fuzz)| Material::Metal { albedo, fuzz }),
        prop_oneof![Just(1.0f32), Just(1.5f32), 0.3f32..3.0].prop_map(|ior| Material::Dielectric { ior }),
    ]
}

fn arb_sphere() -> impl Strategy<Value = Sphere> {
    (prop::array::uniform3(-4.0f32..4.0), prop_oneof![0.05f32..2.0, -2.0f32..-0.05], arb_material())
        .prop_map(|(center, radius, material)| Sphere { center, center1: None, radius, material })
}

fn arb_scene() -> impl Strategy<Value = Scene> {
    (
        prop::collection::vec(arb_sphere(), 0..60),
        prop::array::uniform3(-8.0f32..8.0),
        10.0f32..120.0,
        prop_oneof![Just(None), (0.0f32..5.0).prop_map(Some)],
        prop_oneof![Just(Mode::Path), Just(Mode::Path), Just(Mode::Normals), Just(Mode::Flat)],
    )
        .prop_filter("camera must not sit at its target", |(_, from, _, _, _)| {
            from.iter().map(|x| x * x).sum::<f32>() > 0.5
        })
        .prop_map(|(spheres, from, vfov, defocus, mode)| {
            let mut camera = Camera::looking(from, [0.0, 0.0, 0.0], vfov);
            camera.defocus_angle_deg = defocus;
            Scene {
                meshes: vec![],
                mode,
                camera,
                spheres,
                quads: vec![],
                boxes: vec![],
                groups: vec![],
                media: vec![],
                sky: Sky::default(),
                background: Default::default(),
                sample_toward: vec![],
                render: Default::default(),
            }
        })
        .prop_filter("valid scene (vup not parallel)", |s| s.validate().is_ok())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn random_scenes_are_bit_identical_across_kernels(sc in arb_scene(), seed in 0u64..1000, spp in 1u32..4) {
        let s = settings(19, 11, spp, 12, seed);
        let a = render_accel(&sc, s, Scalar, 1, 8, AccelChoice::Brute);
        prop_assert_eq!(a.stats.rejected_samples, 0);
        for (kernel, accel) in others() {
            let b = render_accel(&sc, s, kernel, 1, 8, accel);
            assert_identical(&a.image, &b.image, &format!("random scene, {kernel:?} {accel:?}"));
            prop_assert_eq!(a.stats.rays, b.stats.rays);
            prop_assert_eq!(b.stats.rejected_samples, 0);
        }
    }
}

/// Materials of both books: the three of book one and lights (one- or two-sided).
fn arb_nw_material() -> impl Strategy<Value = Material> {
    prop_oneof![
        3 => arb_material(),
        1 => (prop::array::uniform3(0.0f32..4.0), any::<bool>()).prop_map(|(emit, one_sided)| Material::DiffuseLight { emit, one_sided }),
    ]
}

fn arb_quad() -> impl Strategy<Value = Quad> {
    (
        prop::array::uniform3(-4.0f32..4.0),
        prop_oneof![
            // Axis-aligned (flat bounding boxes) or any orientation.
            (0usize..3, 0.2f32..3.0, 0.2f32..3.0).prop_map(|(axis, a, b)| {
                let mut u = [0.0; 3];
                let mut v = [0.0; 3];
                u[(axis + 1) % 3] = a;
                v[(axis + 2) % 3] = b;
                (u, v)
            }),
            (prop::array::uniform3(-3.0f32..3.0), prop::array::uniform3(-3.0f32..3.0)),
        ],
        arb_nw_material(),
    )
        .prop_map(|(q, (u, v), material)| Quad { q, u, v, material })
}

fn arb_group() -> impl Strategy<Value = Group> {
    (
        prop_oneof![Just(0.0f32), -180.0f32..180.0],
        prop::array::uniform3(-3.0f32..3.0),
        prop::collection::vec(
            (prop::array::uniform3(-2.0f32..2.0), prop::array::uniform3(0.2f32..2.0), arb_nw_material())
                .prop_map(|(a, size, material)| QuadBox { a, b: std::array::from_fn(|k| a[k] + size[k]), material }),
            1..3,
        ),
        prop::collection::vec(arb_sphere(), 0..3),
    )
        .prop_map(|(rotate_y, translate, boxes, spheres)| Group {
            meshes: vec![],
            rotate_y,
            translate,
            boxes,
            spheres,
            quads: vec![],
            media: vec![],
        })
}

/// Scenes of both books: spheres, quads, boxes turned and moved by groups,
/// lights, and the sky or a constant background. Enough quads for their
/// own tree sometimes (the crossover is 16).
fn arb_mixed_scene() -> impl Strategy<Value = Scene> {
    (
        prop::collection::vec(arb_sphere(), 0..12),
        prop::collection::vec(arb_quad(), 0..24),
        prop::collection::vec(arb_group(), 0..3),
        prop::array::uniform3(-8.0f32..8.0),
        prop_oneof![Just(Background::Sky), prop::array::uniform3(0.0f32..1.0).prop_map(Background::Constant)],
        prop_oneof![Just(Mode::Path), Just(Mode::Path), Just(Mode::Path), Just(Mode::Normals), Just(Mode::Flat)],
    )
        .prop_filter("camera must not sit at its target", |(_, _, _, from, _, _)| {
            from.iter().map(|x| x * x).sum::<f32>() > 0.5
        })
        .prop_map(|(spheres, quads, groups, from, background, mode)| Scene {
            meshes: vec![],
            mode,
            camera: Camera::looking(from, [0.0, 0.0, 0.0], 70.0),
            spheres,
            quads,
            boxes: vec![],
            groups,
            media: vec![],
            sky: Sky::default(),
            background,
            sample_toward: vec![],
            render: Default::default(),
        })
        .prop_filter("valid scene", |s| s.validate().is_ok())
}

/// A shadow ray: origin, unit direction, length.
type ShadowRay = (rtow::internals::vec3::V3<f32>, rtow::internals::vec3::V3<f32>, f32);

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    /// Quads, boxes, instances, lights and backgrounds, under every
    /// estimator (the book's samples toward the scene's lights, nee-mis's
    /// shadow rays through brute force or the trees, one ray or a packet at
    /// a time): every kernel and accelerator renders the scalar brute-force
    /// image bit for bit, and traces as many rays and shadow rays.
    #[test]
    fn mixed_scenes_are_bit_identical_across_kernels(
        sc in arb_mixed_scene(),
        seed in 0u64..1000,
        spp in 1u32..4,
        which in 0usize..3,
    ) {
        let estimator = EstimatorChoice::ALL[which];
        let s = Settings { estimator, ..settings(19, 11, spp, 12, seed) };
        let a = render_accel(&sc, s, Scalar, 1, 8, AccelChoice::Brute);
        prop_assert_eq!(a.stats.rejected_samples, 0);
        for (kernel, accel) in others() {
            let b = render_accel(&sc, s, kernel, 1, 8, accel);
            assert_identical(&a.image, &b.image, &format!("mixed scene, {estimator:?} {kernel:?} {accel:?}"));
            prop_assert_eq!(a.stats.rays, b.stats.rays);
            prop_assert_eq!(a.stats.shadow_rays, b.stats.shadow_rays);
        }
    }

    /// Shadow rays' any-hit queries answer what the closest hit says: a
    /// ray is blocked exactly when its closest hit is nearer than its
    /// length, for one ray at a time and for packets, with brute force and
    /// with the trees, whatever else the packet holds.
    #[test]
    fn any_hit_queries_agree_with_the_closest_hit(
        sc in arb_mixed_scene(),
        rays in proptest::collection::vec(
            ([-3.0f32..3.0, -3.0f32..3.0, -3.0f32..3.0], [-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0], 0.0f32..8.0),
            8,
        ),
    ) {
        use rtow::internals::real::Real;
        use rtow::internals::vec3::V3;
        use wide::f32x8;
        let rays: Vec<_> = rays
            .into_iter()
            .filter_map(|(o, d, tmax)| {
                let d = V3::<f32>::from_array(d);
                let len = d.length_squared().sqrt();
                (len > 0.1).then(|| (V3::from_array(o), d * (1.0 / len), tmax))
            })
            .collect();
        prop_assume!(!rays.is_empty());
        for accel in [AccelChoice::Brute, AccelChoice::Bvh] {
            let opts = rtow::RenderOptions { accel, ..Default::default() };
            let j = job(&sc, settings(8, 8, 1, 4, 1), opts);
            let prep = j.prepared();
            let moving = !prep.shapes.moving.is_empty();
            let want: Vec<bool> = rays
                .iter()
                .map(|&(o, d, tmax)| {
                    let (_, t) = if moving {
                        { let b = prep.shapes.closest::<f32, (), true>(o, d, true, || 0.25, &mut ()); (b.index, b.t) }
                    } else {
                        { let b = prep.shapes.closest::<f32, (), false>(o, d, true, || 0.25, &mut ()); (b.index, b.t) }
                    };
                    t < tmax
                })
                .collect();
            for (k, &(o, d, tmax)) in rays.iter().enumerate() {
                let got = if moving {
                    prep.shapes.occluded::<f32, (), true>(o, d, tmax, true, || 0.25, &mut ())
                } else {
                    prep.shapes.occluded::<f32, (), false>(o, d, tmax, true, || 0.25, &mut ())
                };
                prop_assert_eq!(got, want[k], "one ray, {:?}", accel);
            }
            let lane = |f: &dyn Fn(&ShadowRay) -> f32| f32x8::from_fn(|k| f(&rays[k % rays.len()]));
            let o = V3::new(lane(&|r| r.0.x), lane(&|r| r.0.y), lane(&|r| r.0.z));
            let d = V3::new(lane(&|r| r.1.x), lane(&|r| r.1.y), lane(&|r| r.1.z));
            let tmax = lane(&|r| r.2);
            let live = (1u32 << rays.len()) - 1;
            let time = || f32x8::splat(0.25);
            let got = if moving {
                prep.shapes.occluded::<f32x8, (), true>(o, d, tmax, <f32x8 as rtow::internals::real::Wide>::mask_from_bits(live), time, &mut ())
            } else {
                prep.shapes.occluded::<f32x8, (), false>(o, d, tmax, <f32x8 as rtow::internals::real::Wide>::mask_from_bits(live), time, &mut ())
            };
            let bits = f32x8::mask_bits(got);
            for (k, &w) in want.iter().enumerate() {
                prop_assert_eq!(bits >> k & 1 == 1, w, "packet lane {}, {:?}", k, accel);
            }
            prop_assert_eq!(bits >> rays.len(), 0, "lanes that are not live are not blocked");
        }
    }
}

/// The feature buffers' pass (`render --aov`) traces its camera rays in
/// packets of 8; each pixel's mean is, bit for bit, that of the scalar
/// kernel's first hits of the same samples (one ray at a time), on every
/// preset: moving spheres, textures, quads, media, meshes, lights.
#[test]
fn the_feature_buffers_packets_give_the_scalar_first_hits() {
    use rtow::film::aov::Aovs;
    use rtow::internals::kernel::first_hit::{features, first_hit};
    use rtow::internals::sampling::Sobol;
    for p in scene::presets() {
        let sc = self_contained(&(p.build)());
        if sc.generated_triangles() > 10_000 {
            continue; // the trees' hits are brute force's bit for bit (triangles.rs)
        }
        let d = scene_settings(&sc);
        // 11 samples: a full packet and a short one per pixel.
        let (w, h, spp) = (13, 7, 11);
        let s = Settings { estimator: d.estimator, ..settings(w, h, spp, d.max_depth, 5) };
        let job = job(&sc, s, Default::default());
        let prep = job.prepared();
        let rtow::Sampler::Sobol { dims } = prep.settings.sampler else {
            panic!("{}: the default sampler is Sobol", p.name)
        };
        let sampler = Sobol { dims };
        let all = Aovs { albedo: true, normal: true, depth: true };
        let f = features(prep, sampler, 2..w, 1..h, 0..spp, all);
        for y in 1..h {
            for x in 2..w {
                let hits: Vec<_> = (0..spp).map(|k| first_hit(prep, sampler, x, y, k)).collect();
                let n = spp as f64;
                let mean3 = |g: fn(&rtow::internals::kernel::first_hit::FirstHit) -> [f32; 3]| {
                    let mut a = [0f64; 3];
                    hits.iter().for_each(|h| (0..3).for_each(|c| a[c] += g(h)[c] as f64));
                    a.map(|v| (v / n) as f32)
                };
                let depth = (hits.iter().map(|h| h.depth as f64).sum::<f64>() / n) as f32;
                let i = ((y - 1) * (w - 2) + x - 2) as usize;
                let at = |img: &Option<rtow::Image>| img.as_ref().unwrap().data[i].map(f32::to_bits);
                let what = format!("{} ({x}, {y})", p.name);
                assert_eq!(at(&f.albedo), mean3(|h| h.albedo).map(f32::to_bits), "{what}: albedo");
                assert_eq!(at(&f.normal), mean3(|h| h.normal).map(f32::to_bits), "{what}: normal");
                assert_eq!(f.depth.as_ref().unwrap()[i].to_bits(), depth.to_bits(), "{what}: depth");
            }
        }
    }
}
