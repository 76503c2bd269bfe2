//! Russian roulette and adaptive sampling: unbiasedness of the roulette,
//! bit-identical kernels with either on, adaptive decisions independent of
//! tiles and threads, and rays counted only where traced; the book's
//! mixture estimator and next-event estimation with MIS (`nee-mis`):
//! unbiased, less noisy where lights are small, the same bits in every
//! kernel.

use crate::common;

use common::job;
use rtow::instruments::probe::PathId;
use rtow::internals::kernel::scalar;
use rtow::internals::plan::Prepared;
use rtow::internals::sampling::ScalarStream;
use rtow::scene::{preset, Group, Material, Mesh, MeshShape, Scene, Shape};
use rtow::{
    render, Adaptive, EstimatorChoice, KernelChoice, Overrides, RenderOptions, Rendered, Roulette, Sampler, Settings,
};

fn settings(w: u32, h: u32, spp: u32, seed: u64) -> Settings {
    common::settings(w, h, spp, 50, seed)
}

fn run(scene: &str, s: Settings, opts: RenderOptions) -> Rendered {
    render(&job(&preset(scene).unwrap(), s, opts), None).unwrap()
}

fn opts(kernel: KernelChoice, rr: bool, adaptive: Option<Adaptive>) -> RenderOptions {
    // Roulette early, so that it decides much of the image.
    let roulette = rr.then_some(Roulette::new(2).unwrap());
    RenderOptions { kernel, threads: Some(2), tile: 16, roulette, adaptive, ..Default::default() }
}

fn assert_same(a: &Rendered, b: &Rendered, what: &str) {
    assert_eq!(a.stats.rays, b.stats.rays, "{what}: rays");
    assert_eq!(a.stats.samples, b.stats.samples, "{what}: samples");
    for (i, (p, q)) in a.image.data.iter().zip(&b.image.data).enumerate() {
        for k in 0..3 {
            assert_eq!(p[k].to_bits(), q[k].to_bits(), "{what}: pixel {i} channel {k}: {p:?} vs {q:?}");
        }
    }
}

/// Per pixel and channel: the mean and the variance of the mean, from `n`
/// paths traced one by one with the scalar kernel.
fn pixel_stats(prep: &Prepared, n: u32) -> Vec<[(f64, f64); 3]> {
    let s = prep.settings;
    let mut out = Vec::new();
    for y in 0..s.height {
        for x in 0..s.width {
            let pixel = (y * s.width + x) as u64;
            let mut m = [[0.0f64; 2]; 3];
            for sample in 0..n {
                let mut rng = ScalarStream::for_path(s.seed, pixel, sample as u64);
                let id = PathId { pixel: pixel as u32, sample };
                let (v, _) = scalar::trace(prep, x, y, id, &mut rng, &mut ());
                for k in 0..3 {
                    m[k][0] += v[k] as f64;
                    m[k][1] += v[k] as f64 * v[k] as f64;
                }
            }
            let n = n as f64;
            out.push(m.map(|[s1, s2]| {
                let mean = s1 / n;
                let var = ((s2 - s1 * s1 / n) / (n - 1.0)).max(0.0);
                (mean, var / n)
            }));
        }
    }
    out
}

/// Russian roulette must not change the expected image: plain and roulette
/// renders with independent seeds have the same mean ([`same_mean`]).
fn roulette_keeps_the_mean(scene: &str, w: u32, h: u32, n: u32, after: u32) {
    let sc = preset(scene).unwrap();
    let plain = job(&sc, settings(w, h, n, 11), RenderOptions::default());
    let with_rr = RenderOptions { roulette: Some(Roulette::new(after).unwrap()), ..Default::default() };
    let rr = job(&sc, settings(w, h, n, 12), with_rr);
    same_mean(scene, plain.prepared(), rr.prepared(), n);
}

/// Two jobs of one scene (other seeds, other estimators) render the same
/// expected image: `n` paths per pixel each, compared pixel by pixel (a
/// z-test per pixel and channel, Bonferroni-corrected to a 1e-3
/// family-wise level) and as a whole (the mean difference over all pixels,
/// |z| < 4).
fn same_mean(scene: &str, a: &Prepared, b: &Prepared, n: u32) {
    let a = pixel_stats(a, n);
    let b = pixel_stats(b, n);
    let tests = (a.len() * 3) as f64;
    // Two-sided z for 1e-3 / tests, by bisection on the normal tail.
    let tail = |z: f64| 0.5 * erfc(z / std::f64::consts::SQRT_2);
    let (mut lo, mut hi) = (0.0, 20.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if 2.0 * tail(mid) > 1e-3 / tests {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let z_crit = hi;
    let (mut sum_d, mut sum_v, mut worst) = (0.0, 0.0, 0.0f64);
    for (pa, pb) in a.iter().zip(&b) {
        for k in 0..3 {
            let d = pb[k].0 - pa[k].0;
            let v = pa[k].1 + pb[k].1;
            sum_d += d;
            sum_v += v;
            if v == 0.0 {
                assert_eq!(d, 0.0, "{scene}: noiseless pixel differs");
            } else {
                worst = worst.max(d.abs() / v.sqrt());
            }
        }
    }
    assert!(worst < z_crit, "{scene}: a pixel differs by {worst:.2} sigma (limit {z_crit:.2})");
    let z = sum_d / sum_v.sqrt();
    assert!(z.abs() < 4.0, "{scene}: the image mean differs by {z:.2} sigma");
}

/// The complementary error function (Numerical Recipes' erfcc, relative error < 1.2e-7).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.26551223
            + t * (1.00002368
                + t * (0.37409196
                    + t * (0.09678418
                        + t * (-0.18628806
                            + t * (0.27886807
                                + t * (-1.13520398 + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

#[test]
fn roulette_is_unbiased_on_diffuse_glass_and_metal() {
    // Early roulette (after the camera ray and after 2 rays) makes the test
    // sensitive: most of the image goes through the roulette. And the default.
    roulette_keeps_the_mean("ch07-diffuse", 24, 14, 512, 1);
    roulette_keeps_the_mean("ch09-glass", 24, 14, 512, 2);
    roulette_keeps_the_mean("ch09-glass", 24, 14, 256, rtow::ROULETTE_AFTER_RAYS);
}

#[test]
fn roulette_traces_fewer_rays_and_changes_the_noise() {
    let s = settings(40, 23, 8, 3);
    let plain = run("ch07-diffuse", s, opts(KernelChoice::Simd, false, None));
    let rr = run("ch07-diffuse", s, opts(KernelChoice::Simd, true, None));
    assert!(rr.stats.rays < plain.stats.rays, "{} vs {}", rr.stats.rays, plain.stats.rays);
    assert_ne!(rr.image, plain.image);
    assert_eq!(rr.stats.russian_roulette, Some(Roulette::new(2).unwrap()));
    assert_eq!(plain.stats.russian_roulette, None);
}

#[test]
fn roulette_scalar_and_simd_agree_bit_for_bit() {
    for (scene, s) in [("final", settings(40, 23, 8, 5)), ("ch09-glass", settings(48, 27, 16, 6))] {
        let a = run(scene, s, opts(KernelChoice::Scalar, true, None));
        let b = run(scene, s, opts(KernelChoice::Simd, true, None));
        assert_same(&a, &b, scene);
    }
    // The default start.
    let s = settings(40, 23, 8, 5);
    let dflt = |kernel| RenderOptions { roulette: Some(Roulette::default()), ..opts(kernel, true, None) };
    let a = run("ch09-glass", s, dflt(KernelChoice::Scalar));
    let b = run("ch09-glass", s, dflt(KernelChoice::Simd));
    assert_same(&a, &b, "default roulette start");
}

#[test]
fn adaptive_scalar_and_simd_agree_bit_for_bit_whatever_the_tiles() {
    let s = settings(40, 23, 128, 7);
    let ad = Some(Adaptive::new(0.05, 16).unwrap());
    let simd = run("final", s, opts(KernelChoice::Simd, false, ad));
    let px = 40 * 23;
    // Some pixels stopped early and some went on: the decisions did something.
    assert!(simd.stats.samples > px * 16 && simd.stats.samples < px * 128, "{}", simd.stats.samples);
    let scalar = run("final", s, RenderOptions { threads: Some(1), tile: 7, ..opts(KernelChoice::Scalar, false, ad) });
    assert_same(&simd, &scalar, "adaptive");
    let odd_tiles = run("final", s, RenderOptions { tile: 45, ..opts(KernelChoice::Simd, false, ad) });
    assert_same(&simd, &odd_tiles, "adaptive, 45-pixel tiles");
    // With roulette as well.
    let a = run("ch09-glass", s, opts(KernelChoice::Scalar, true, ad));
    let b = run("ch09-glass", s, opts(KernelChoice::Simd, true, ad));
    assert_same(&a, &b, "roulette + adaptive");
}

#[test]
fn adaptive_counts_only_what_it_traced() {
    // A threshold every pixel meets: all stop at the first decision point, so
    // the render is the 16-spp render, rays and all, though it was allowed 128.
    let all_stop = Some(Adaptive::new(1e9, 16).unwrap());
    for kernel in [KernelChoice::Scalar, KernelChoice::Simd] {
        let a = run("final", settings(24, 14, 128, 9), opts(kernel, false, all_stop));
        let b = run("final", settings(24, 14, 16, 9), opts(kernel, false, None));
        assert_same(&a, &b, kernel.name());
        assert_eq!(a.stats.samples, 24 * 14 * 16);
    }
    // Below the first decision point adaptive sampling changes nothing.
    let a = run(
        "ch07-diffuse",
        settings(24, 14, 12, 9),
        opts(KernelChoice::Simd, false, Some(Adaptive::new(1e-6, 16).unwrap())),
    );
    let b = run("ch07-diffuse", settings(24, 14, 12, 9), opts(KernelChoice::Simd, false, None));
    assert_same(&a, &b, "under min spp");
}

/// Adaptive sampling and roulette are valid by construction: the one check
/// names the setting.
#[test]
fn bad_adaptive_options_are_errors_naming_the_setting() {
    for (t, min, field) in
        [(f32::NAN, 16, "adaptive.threshold"), (-1.0, 16, "adaptive.threshold"), (0.1, 0, "adaptive.min_spp")]
    {
        let e = Adaptive::new(t, min).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{field}:")), "{e}");
    }
    assert!(Roulette::new(0).unwrap_err().to_string().starts_with("roulette.after_rays:"));
}

fn book(s: Settings) -> Settings {
    Settings { estimator: EstimatorChoice::Book, ..s }
}

/// ch07's scene with a `sample_toward` sphere around all of it: every
/// diffuse vertex lies inside the sphere (uniform directions, density 1 / 4 pi).
fn inside_a_sampled_sphere() -> Scene {
    let mut sc = preset("ch07-diffuse").unwrap();
    sc.sample_toward = vec![Shape::Sphere { center: [0.0, 0.0, -1.0], radius: 500.0 }];
    sc
}

/// The Rest of Your Life's room with its light enlarged to 400 x 400 and
/// the glass sphere made white, sampled toward both (vertices on the
/// sphere sample it from its surface). The bsdf estimator is the reference
/// for the z-test, and its variance must be estimable: with the book's small
/// light and glass sphere, lights seen through the glass (caustics) are rare
/// events for the cosine lobe, whose sample variance then underestimates
/// its error (docs/sampling.md).
fn large_light_room() -> Scene {
    let mut sc = preset("rol-cornell-box").unwrap();
    let (q, u, v) = ([78.0, 554.0, 92.0], [400.0, 0.0, 0.0], [0.0, 0.0, 400.0]);
    let light = sc.quads.iter_mut().find(|q| matches!(q.material, Material::DiffuseLight { .. })).unwrap();
    (light.q, light.u, light.v) = (q, u, v);
    sc.spheres[0].material = Material::Lambertian { albedo: [0.73; 3].into() };
    sc.sample_toward[0] = Shape::Quad { q, u, v };
    sc
}

/// nw-simple-light with its sphere light as an icosphere of 80 triangles
/// in a group (turned, and moved above its place): a mesh light, sampled
/// by area, beside the quad light. Larger than the book's sphere (radius
/// 3.5 instead of 2): the bsdf estimator, the z-tests' reference, must
/// reach it often enough from the far ground for its sample variance to
/// hold (at radius 2 and 256 paths, a corner pixel's bsdf mean came out at
/// 2% of its value, 0.014 at 65,536 paths under both estimators).
fn mesh_light() -> Scene {
    let mut sc = preset("nw-simple-light").unwrap();
    let at = sc.spheres.iter().position(|s| matches!(s.material, Material::DiffuseLight { .. })).unwrap();
    let s = sc.spheres.remove(at);
    let shape = MeshShape::Icosphere { center: [0.0; 3], radius: 3.5, level: 1 };
    let group = Group { rotate_y: 30.0, translate: [s.center[0], 8.0, s.center[2]], ..Group::default() };
    sc.groups.push(Group { meshes: vec![Mesh { shape, material: s.material }], ..group });
    sc.sample_toward.clear();
    sc
}

/// The book's mixture is unbiased: its expected image is the bsdf
/// estimator's, on quads, spheres and meshes as shapes (spheres seen from
/// outside and from inside), lambertian and isotropic vertices, a specular
/// material in the list (the glass sphere), one-sided and two-sided lights.
#[test]
fn the_book_estimator_keeps_the_mean() {
    let cases: [(&str, Scene, u32, u32, u32); 5] = [
        ("a mesh light", mesh_light(), 16, 9, 256),
        ("the book's room, a large light, a white sphere", large_light_room(), 14, 14, 384),
        ("nw-cornell-smoke", preset("nw-cornell-smoke").unwrap(), 10, 10, 256),
        ("nw-simple-light", preset("nw-simple-light").unwrap(), 16, 9, 256),
        ("inside a sampled sphere", inside_a_sampled_sphere(), 16, 9, 256),
    ];
    keeps_the_mean(cases, book, |j| j.plan().sample_toward > 0);
}

/// For each case (name, scene, width, height, paths per pixel): the scene
/// under `estimator`'s settings (checked by `runs`, say, that its samples
/// run) has the bsdf estimator's expected image ([`same_mean`]).
fn keeps_the_mean<const N: usize>(
    cases: [(&str, Scene, u32, u32, u32); N],
    estimator: fn(Settings) -> Settings,
    runs: fn(&rtow::Job) -> bool,
) {
    for (name, sc, w, h, n) in cases {
        let plain = job(&sc, settings(w, h, n, 11), RenderOptions::default());
        let other = job(&sc, estimator(settings(w, h, n, 12)), RenderOptions::default());
        assert!(runs(&other), "{name}: the estimator runs");
        same_mean(name, plain.prepared(), other.prepared(), n);
    }
}

/// `sc` rendered by the scalar kernel, simd8 and simd16 under `s`: the
/// same image bit for bit, the same rays and shadow rays, no sample
/// rejected; returns the scalar render.
fn same_in_every_kernel(name: &str, sc: &Scene, s: Settings) -> Rendered {
    let runs: Vec<Rendered> = [KernelChoice::Scalar, KernelChoice::Simd8, KernelChoice::Simd16]
        .into_iter()
        .map(|kernel| render(&job(sc, s, RenderOptions { kernel, ..opts(kernel, false, None) }), None).unwrap())
        .collect();
    assert_eq!(runs[0].stats.rejected_samples, 0, "{name}");
    for r in &runs[1..] {
        assert_same(&runs[0], r, &format!("{name} {:?} {}", s.sampler, r.stats.kernel));
        assert_eq!(runs[0].stats.shadow_rays, r.stats.shadow_rays, "{name}: shadow rays");
    }
    runs.into_iter().next().unwrap()
}

/// What the mixture is for: on the book's Cornell box (a small light) it
/// has far less variance than the cosine lobe alone at the same samples.
#[test]
fn the_book_estimator_is_less_noisy_where_the_light_is_small() {
    let sc = preset("rol-cornell-box").unwrap();
    let var = |s: Settings| {
        let j = job(&sc, s, RenderOptions::default());
        pixel_stats(j.prepared(), 256).iter().flat_map(|p| p.iter().map(|c| c.1)).collect::<Vec<f64>>()
    };
    let (plain, mixed) = (var(settings(12, 12, 256, 3)), var(book(settings(12, 12, 256, 3))));
    // The median over pixels and channels of the variance ratio (the light's
    // own edge pixels, the same under both, would dominate a sum).
    let mut ratio: Vec<f64> = mixed.iter().zip(&plain).filter(|(_, p)| **p > 0.0).map(|(m, p)| m / p).collect();
    ratio.sort_by(f64::total_cmp);
    let median = ratio[ratio.len() / 2];
    assert!(median < 0.25, "median variance ratio book / bsdf {median:.3}");
}

/// Every kernel, lane width and sampler renders the book estimator's image
/// bit for bit, ray counts included.
#[test]
fn the_book_estimator_is_bit_identical_across_kernels() {
    let scenes = ["rol-cornell-box", "rol-cornell-box-aluminium", "nw-cornell-smoke", "nw-simple-light", "nw-final"];
    for name in scenes {
        let sc = common::self_contained(&preset(name).unwrap());
        for sampler in [Sampler::Independent, Sampler::SOBOL] {
            let s = Settings { sampler, ..book(common::settings(24, 20, 3, 12, 4)) };
            let j = job(&sc, s, RenderOptions::default());
            assert!(j.plan().sample_toward > 0, "{name}");
            same_in_every_kernel(name, &sc, s);
        }
    }
}

/// Without anything to sample toward the book estimator is the bsdf
/// estimator, bit for bit, and the job says so; its identity names it, the
/// bsdf estimator's does not (identities from before estimators stay).
#[test]
fn the_book_estimator_without_lights_is_the_bsdf_estimator() {
    let sc = preset("final").unwrap();
    let s = settings(24, 14, 4, 8);
    let plain = job(&sc, s, RenderOptions::default());
    let mixed = job(&sc, book(s), RenderOptions::default());
    assert_eq!(mixed.plan().sample_toward, 0);
    assert!(
        mixed.warnings().iter().any(|w| w.to_string().contains("nothing to sample toward")),
        "{:?}",
        mixed.warnings()
    );
    assert_same(&render(&plain, None).unwrap(), &render(&mixed, None).unwrap(), "book without lights");
    assert!(!plain.identity().settings.contains_key("estimator"));
    assert_eq!(mixed.identity().settings.get("estimator").map(String::as_str), Some("book"));
}

/// More lights than the mixture evaluates per vertex: a clear error that
/// says what to do, not a slow render.
#[test]
fn too_many_lights_for_the_book_estimator_are_refused() {
    let mut sc = preset("nw-cornell-box-empty").unwrap();
    let light = sc.quads[2].clone();
    sc.quads.extend(std::iter::repeat_n(light, rtow::limits::MAX_SAMPLED_SHAPES));
    let e = rtow::Job::new(&sc, &Overrides::from(book(settings(8, 8, 1, 2))), &RenderOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("sample_toward") && e.contains("--estimator bsdf"), "{e}");
    assert!(rtow::Job::new(&sc, &Overrides::from(settings(8, 8, 1, 2)), &RenderOptions::default()).is_ok());
}

fn nee(s: Settings) -> Settings {
    Settings { estimator: EstimatorChoice::NeeMis, ..s }
}

/// nw-simple-light with its sphere light moving: a light the light samples
/// never reach (only scattered directions do, at full weight), beside a
/// sampled quad light.
fn moving_light() -> Scene {
    let mut sc = preset("nw-simple-light").unwrap();
    let s = sc.spheres.iter_mut().find(|s| matches!(s.material, Material::DiffuseLight { .. })).unwrap();
    s.center1 = Some([s.center[0] + 0.5, s.center[1], s.center[2]]);
    sc
}

/// Next-event estimation with MIS is unbiased: its expected image is the
/// bsdf estimator's, with a one-sided quad light (the large-light room),
/// media between vertices and lights (shadow rays' transmittance), sphere,
/// quad and mesh lights, two-sided ones, and a moving light nobody samples.
#[test]
fn the_nee_mis_estimator_keeps_the_mean() {
    let cases: [(&str, Scene, u32, u32, u32); 5] = [
        ("a mesh light", mesh_light(), 16, 9, 256),
        ("the book's room, a large light, a white sphere", large_light_room(), 14, 14, 384),
        // 1024 paths: the bsdf estimator's bright rare paths here (the
        // light through the smoke) make 256 too few for its sample variance.
        ("nw-cornell-smoke", preset("nw-cornell-smoke").unwrap(), 10, 10, 1024),
        ("nw-simple-light", preset("nw-simple-light").unwrap(), 16, 9, 256),
        ("a moving light", moving_light(), 16, 9, 256),
    ];
    keeps_the_mean(cases, nee, |j| j.plan().nee > 0);
}

/// What it is for: on the book's Cornell box it has less variance than the
/// book's mixture at the same samples (and far less than the cosine lobe).
#[test]
fn the_nee_mis_estimator_is_less_noisy_than_the_book_mixture() {
    let sc = preset("rol-cornell-box").unwrap();
    let var = |s: Settings| {
        let j = job(&sc, s, RenderOptions::default());
        pixel_stats(j.prepared(), 256).iter().flat_map(|p| p.iter().map(|c| c.1)).collect::<Vec<f64>>()
    };
    let (mixed, with_nee) = (var(book(settings(12, 12, 256, 3))), var(nee(settings(12, 12, 256, 3))));
    let mut ratio: Vec<f64> = with_nee.iter().zip(&mixed).filter(|(_, p)| **p > 0.0).map(|(m, p)| m / p).collect();
    ratio.sort_by(f64::total_cmp);
    let median = ratio[ratio.len() / 2];
    assert!(median < 0.8, "median variance ratio nee-mis / book {median:.3}");
}

/// Every kernel, lane width and sampler renders the nee-mis image bit for
/// bit, rays and shadow rays included: quads, spheres, media, textures,
/// moving spheres (nw-final) and a moving light.
#[test]
fn the_nee_mis_estimator_is_bit_identical_across_kernels() {
    let scenes = [
        ("rol-cornell-box", preset("rol-cornell-box").unwrap()),
        ("nw-cornell-smoke", preset("nw-cornell-smoke").unwrap()),
        ("nw-simple-light", preset("nw-simple-light").unwrap()),
        ("nw-final", preset("nw-final").unwrap()),
        ("a moving light", moving_light()),
    ];
    for (name, sc) in scenes {
        let sc = common::self_contained(&sc);
        for sampler in [Sampler::Independent, Sampler::SOBOL] {
            let s = Settings { sampler, ..nee(common::settings(24, 20, 3, 12, 4)) };
            let scalar = same_in_every_kernel(name, &sc, s);
            assert!(scalar.stats.shadow_rays > 0, "{name}: shadow rays traced");
        }
    }
}

/// Without lights nee-mis is the bsdf estimator, bit for bit, with a
/// warning; its identity names it. More lights than it samples are refused.
#[test]
fn the_nee_mis_estimator_without_lights_is_the_bsdf_estimator() {
    let sc = preset("final").unwrap();
    let s = settings(24, 14, 4, 8);
    let plain = job(&sc, s, RenderOptions::default());
    let with_nee = job(&sc, nee(s), RenderOptions::default());
    assert_eq!(with_nee.plan().nee, 0);
    assert!(
        with_nee.warnings().iter().any(|w| w.to_string().contains("no light to sample")),
        "{:?}",
        with_nee.warnings()
    );
    let r = render(&with_nee, None).unwrap();
    assert_same(&render(&plain, None).unwrap(), &r, "nee-mis without lights");
    assert_eq!(r.stats.shadow_rays, 0);
    assert_eq!(with_nee.identity().settings.get("estimator").map(String::as_str), Some("nee-mis"));
    let mut many = preset("nw-cornell-box-empty").unwrap();
    let light = many.quads[2].clone();
    many.quads.extend(std::iter::repeat_n(light, rtow::limits::MAX_SAMPLED_SHAPES));
    let e = rtow::Job::new(&many, &Overrides::from(nee(settings(8, 8, 1, 2))), &RenderOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("nee-mis") && e.contains("--estimator bsdf"), "{e}");
}

/// A mesh light is sampled, not only reached: both estimators that sample
/// lights count it, render it with less noise than the cosine lobe alone,
/// and render the same bits in every kernel, lane width and sampler.
#[test]
fn mesh_lights_are_sampled_by_book_and_nee_mis_alike_in_every_kernel() {
    let sc = mesh_light();
    let median_ratio = |s: Settings| {
        let var = |s: Settings| {
            let j = job(&sc, s, RenderOptions::default());
            pixel_stats(j.prepared(), 128).iter().flat_map(|p| p.iter().map(|c| c.1)).collect::<Vec<f64>>()
        };
        let (plain, other) = (var(settings(16, 9, 128, 5)), var(s));
        let mut r: Vec<f64> = other.iter().zip(&plain).filter(|(_, p)| **p > 0.0).map(|(o, p)| o / p).collect();
        r.sort_by(f64::total_cmp);
        r[r.len() / 2]
    };
    for (name, estimator) in [("book", book as fn(Settings) -> Settings), ("nee-mis", nee)] {
        let j = job(&sc, estimator(settings(8, 8, 1, 1)), RenderOptions::default());
        assert_eq!(j.plan().sample_toward + j.plan().nee, 2, "{name}: the quad and the mesh");
        let ratio = median_ratio(estimator(settings(16, 9, 128, 5)));
        assert!(ratio < 0.5, "{name}: median variance ratio against bsdf {ratio:.3}");
        for sampler in [Sampler::Independent, Sampler::SOBOL] {
            let s = Settings { sampler, ..estimator(common::settings(24, 20, 3, 12, 4)) };
            same_in_every_kernel(name, &sc, s);
        }
    }
}
