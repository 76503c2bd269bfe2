//! Textures (The Next Week, part 2): the checker and Perlin marble against
//! f64 implementations of the book's code, every lane width computing the
//! scalar bits, textured scenes bit for bit across kernels, the plan, and
//! scene files (round trips, errors that name the field).

use crate::common;
use common::*;
use proptest::prelude::*;
use rtow::internals::math::SIN_MAX_ARG;
use rtow::internals::real::Real;
use rtow::internals::texture::{checker, marble, noise, turb, Checker, Perlin, TexKind, PERLIN_SEED};
use rtow::internals::vec3::V3;
use rtow::scene::{self, Background, Camera, Format, Material, Mode, Quad, Scene, Sky, Sphere, Texture};
use rtow::KernelChoice::{Scalar, Simd16, Simd8};
use rtow::{Overrides, RenderOptions, Sampler};
use std::path::Path;
use wide::{f32x16, f32x8};

/// `u = 2^-24`, the f32 unit roundoff.
const U: f64 = 1.0 / 16_777_216.0;

fn lattice() -> Perlin {
    Perlin::new(PERLIN_SEED)
}

/// The book's `perlin::noise` in f64, on the same lattice.
fn noise64(p: [f64; 3], l: &Perlin) -> f64 {
    let f = p.map(f64::floor);
    let (u, v, w) = (p[0] - f[0], p[1] - f[1], p[2] - f[2]);
    let c = f.map(|x| x as i64);
    let h = |t: f64| t * t * (3.0 - 2.0 * t);
    let (uu, vv, ww) = (h(u), h(v), h(w));
    let mut acc = 0.0;
    for i in 0..2i64 {
        for j in 0..2i64 {
            for k in 0..2i64 {
                let idx = l.perm[0][((c[0] + i) & 255) as usize]
                    ^ l.perm[1][((c[1] + j) & 255) as usize]
                    ^ l.perm[2][((c[2] + k) & 255) as usize];
                let g = l.ranvec[idx as usize].map(f64::from);
                let (fi, fj, fk) = (i as f64, j as f64, k as f64);
                let weight = (fi * uu + (1.0 - fi) * (1.0 - uu))
                    * (fj * vv + (1.0 - fj) * (1.0 - vv))
                    * (fk * ww + (1.0 - fk) * (1.0 - ww));
                acc += weight * (g[0] * (u - fi) + g[1] * (v - fj) + g[2] * (w - fk));
            }
        }
    }
    acc
}

fn turb64(p: [f64; 3], l: &Perlin) -> f64 {
    let (mut acc, mut weight, mut q) = (0.0, 1.0, p);
    for _ in 0..7 {
        acc += weight * noise64(q, l);
        weight *= 0.5;
        q = q.map(|x| 2.0 * x);
    }
    acc.abs()
}

/// The error bound of f32 `noise` against `noise64` of the same f32 point.
/// The cell and the fractions `u, v, w` are exact in both (`p - floor(p)`
/// is exact, and so are the offsets `u - i`); each Hermite weight carries 4
/// roundings, a corner's product of three weights 14, its dot product 5 on
/// terms of total size at most `sqrt 3` (unit gradients, offsets below 1)
/// and the product with it 1: at most `20u sqrt 3` per unit of weight, the
/// weights summing to 1; the 8 additions add at most `8u` times the partial
/// sums, each below `8 sqrt 3`. In all `84 sqrt 3 u` (8.7e-6); the gradients
/// are the same f32 table in both.
const NOISE_BOUND: f64 = 84.0 * 1.732_050_808 * U;

/// Turbulence: octave i is noise of `2^i p` (an exact scaling) weighted by
/// `2^-i` (exact), so the octaves' errors sum to below `2 NOISE_BOUND`; the 7
/// additions add `u` times partial sums below `2 * 8 sqrt 3` each.
const TURB_BOUND: f64 = 2.0 * NOISE_BOUND + 7.0 * 16.0 * 1.732_050_808 * U;

fn point() -> impl Strategy<Value = [f32; 3]> {
    prop::array::uniform3(-300.0f32..300.0)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4096, ..ProptestConfig::default() })]

    /// The checker picks the colour of the book's parity rule, evaluated in
    /// f64, for every point not within rounding of a cell boundary: the
    /// f32 `inv_scale p` is within `2u |p / scale|` of the exact quotient
    /// (`inv_scale`'s rounding and the product's), so points that far or
    /// further from an integer multiple of `scale` have the exact cell.
    #[test]
    fn the_checker_is_the_books_parity(p in point(), scale in 0.01f32..10.0) {
        let c = Checker { inv_scale: (1.0 / scale as f64) as f32, even: [1.0, 0.0, 0.0], odd: [0.0, 1.0, 0.0] };
        let q = p.map(|x| x as f64 / scale as f64);
        let margin = |x: f64| (x - x.round()).abs() > 4.0 * U * x.abs() + 1e-30;
        prop_assume!(q.iter().all(|&x| margin(x)));
        let sum: i64 = q.iter().map(|x| x.floor() as i64).sum();
        let got = checker(V3::new(p[0], p[1], p[2]), |_| c).to_array();
        prop_assert_eq!(got, if sum % 2 == 0 { c.even } else { c.odd });
    }

    #[test]
    fn noise_and_turbulence_are_within_their_bounds(p in point()) {
        let l = lattice();
        let p64 = p.map(f64::from);
        let v = V3::new(p[0], p[1], p[2]);
        let e = (noise(v, &l) as f64 - noise64(p64, &l)).abs();
        prop_assert!(e <= NOISE_BOUND, "noise error {:e} > {:e}", e, NOISE_BOUND);
        let e = (turb(v, &l) as f64 - turb64(p64, &l)).abs();
        prop_assert!(e <= TURB_BOUND, "turbulence error {:e} > {:e}", e, TURB_BOUND);
    }

    /// Marble: the argument `scale z + 10 turb` is off by the rounding of
    /// the product and the sum (`u` each, relative) and 10 times the
    /// turbulence's bound; the sine adds its own 2.5e-7 (below
    /// `SIN_MAX_ARG`) and is 1-Lipschitz; `0.5 (1 + s)` halves that and adds `u`.
    #[test]
    fn marble_is_within_its_bound(p in point(), scale in 0.0f32..100.0) {
        let l = lattice();
        let p64 = p.map(f64::from);
        let t = turb64(p64, &l);
        let arg = scale as f64 * p64[2] + 10.0 * t;
        prop_assume!(arg.abs() < SIN_MAX_ARG as f64 / 2.0);
        let want = 0.5 * (1.0 + arg.sin());
        let arg_err = 2.0 * U * (scale as f64 * p64[2]).abs() + 10.0 * TURB_BOUND + 2.0 * U * arg.abs() + 10.0 * U * t;
        let bound = 0.5 * (arg_err + 2.5e-7) + 2.0 * U;
        let got = marble(V3::new(p[0], p[1], p[2]), scale, &l).to_array();
        prop_assert!(got[0] == got[1] && got[1] == got[2]);
        prop_assert!((got[0] as f64 - want).abs() <= bound, "marble {} vs {} (bound {:e})", got[0], want, bound);
    }
}

/// Gradient noise vanishes on the lattice: at integer points every corner's
/// offset or weight is zero, exactly.
#[test]
fn noise_is_zero_at_lattice_points() {
    let l = lattice();
    for x in -5..5 {
        for y in -5..5 {
            for z in [-300, -1, 0, 7, 255, 256, 1000] {
                let p = V3::new(x as f32, y as f32, z as f32);
                assert_eq!(noise(p, &l), 0.0, "noise at ({x}, {y}, {z})");
            }
        }
    }
}

#[test]
fn the_lattice_is_seeded_permutations_and_unit_gradients() {
    let l = lattice();
    assert_eq!(l, lattice(), "the same seed gives the same lattice");
    assert_ne!(l, Perlin::new(PERLIN_SEED + 1));
    for p in &l.perm {
        let mut seen = [false; 256];
        p.iter().for_each(|&x| seen[x as usize] = true);
        assert!(seen.iter().all(|&s| s), "a permutation of 0..256");
        assert_ne!(p.iter().enumerate().filter(|&(i, &x)| i == x as usize).count(), 256, "shuffled");
    }
    for g in l.ranvec.iter() {
        let n = g.iter().map(|&x| x as f64 * x as f64).sum::<f64>().sqrt();
        assert!((n - 1.0).abs() <= 4.0 * U, "|g| = {n}");
    }
}

/// Every lane width computes the scalar bits, with a different table row
/// in each lane (as in a packet that hits two checkers).
#[test]
fn every_width_computes_the_scalar_texture_bits() {
    let l = lattice();
    let rows = [
        Checker { inv_scale: 1.0 / 0.32, even: [0.2, 0.3, 0.1], odd: [0.9, 0.9, 0.9] },
        Checker { inv_scale: 3.7, even: [1.0, 0.0, 0.5], odd: [0.0, 0.25, 1.0] },
    ];
    let mut s = 12345u64;
    let mut next = move || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((s >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 400.0
    };
    for _ in 0..2000 {
        let pts: Vec<[f32; 3]> = (0..16).map(|_| [next(), next(), next() * 0.01]).collect();
        let scale: Vec<f32> = (0..16).map(|k| k as f32 * 0.75).collect();
        let v16 =
            V3::new(f32x16::from_fn(|k| pts[k][0]), f32x16::from_fn(|k| pts[k][1]), f32x16::from_fn(|k| pts[k][2]));
        let v8 = V3::new(f32x8::from_fn(|k| pts[k][0]), f32x8::from_fn(|k| pts[k][1]), f32x8::from_fn(|k| pts[k][2]));
        let c16 = checker(v16, |k| rows[k % 2]);
        let c8 = checker(v8, |k| rows[k % 2]);
        let m16 = marble(v16, f32x16::from_fn(|k| scale[k]), &l);
        let m8 = marble(v8, f32x8::from_fn(|k| scale[k]), &l);
        for k in 0..16 {
            let p = V3::new(pts[k][0], pts[k][1], pts[k][2]);
            let want_c = checker(p, |_| rows[k % 2]).to_array().map(f32::to_bits);
            let want_m = marble(p, scale[k], &l).to_array().map(f32::to_bits);
            let lanes = |v: V3<f32x16>| [v.x.lane(k), v.y.lane(k), v.z.lane(k)].map(f32::to_bits);
            assert_eq!(lanes(c16), want_c, "checker at 16 lanes, {:?}", pts[k]);
            assert_eq!(lanes(m16), want_m, "marble at 16 lanes, {:?}", pts[k]);
            if k < 8 {
                let lanes8 = |v: V3<f32x8>| [v.x.lane(k), v.y.lane(k), v.z.lane(k)].map(f32::to_bits);
                assert_eq!(lanes8(c8), want_c, "checker at 8 lanes");
                assert_eq!(lanes8(m8), want_m, "marble at 8 lanes");
            }
        }
    }
}

fn lam(albedo: Texture) -> Material {
    Material::Lambertian { albedo }
}

fn checker_tex(scale: f32) -> Texture {
    Texture::Checker { scale, even: [0.2, 0.3, 0.1], odd: [0.9, 0.9, 0.9] }
}

/// Spheres and quads with solid, checker and noise albedos side by side (so
/// packets mix texture kinds, rows and primitive kinds), metal and glass
/// among them.
fn textured_scene() -> Scene {
    let sph = |center: [f32; 3], radius: f32, material: Material| Sphere { center, center1: None, radius, material };
    Scene {
        meshes: vec![],
        mode: Mode::Path,
        camera: Camera::looking([13.0, 2.0, 3.0], [0.0, 0.0, 0.0], 30.0),
        spheres: vec![
            sph([0.0, -1000.0, 0.0], 1000.0, lam(checker_tex(0.32))),
            sph([0.0, 1.0, 0.0], 1.0, lam(Texture::Noise { scale: 4.0 })),
            sph(
                [0.0, 1.0, 2.2],
                1.0,
                lam(Texture::Checker { scale: 0.1, even: [1.0, 0.0, 0.0], odd: [0.0, 0.0, 1.0] }),
            ),
            sph([0.0, 1.0, -2.2], 1.0, Material::Metal { albedo: [0.8, 0.8, 0.8], fuzz: 0.1 }),
            sph([2.0, 0.5, 1.0], 0.5, Material::Dielectric { ior: 1.5 }),
            sph([2.0, 0.5, -1.0], 0.5, lam([0.4, 0.2, 0.1].into())),
        ],
        quads: vec![
            Quad {
                q: [-3.0, 0.0, -3.0],
                u: [0.0, 0.0, 6.0],
                v: [0.0, 3.0, 0.0],
                material: lam(Texture::Noise { scale: 1.0 }),
            },
            Quad { q: [-2.0, 0.0, 3.5], u: [3.0, 0.0, 0.0], v: [0.0, 2.0, 0.0], material: lam(checker_tex(0.5)) },
        ],
        boxes: vec![],
        groups: vec![],
        media: vec![],
        sky: Sky::default(),
        background: Background::Sky,
        sample_toward: vec![],
        render: Default::default(),
    }
}

#[test]
fn textured_scenes_are_bit_identical_across_kernels_and_samplers() {
    let sc = textured_scene();
    for sampler in [Sampler::SOBOL, Sampler::Independent] {
        let s = rtow::Settings { sampler, ..settings(48, 27, 4, 8, 3) };
        let reference = image(&sc, s, Scalar);
        for kernel in [Simd8, Simd16] {
            assert_identical(&reference, &image(&sc, s, kernel), &format!("{kernel:?}, {sampler:?}"));
        }
        // Textures are seen: the image differs from the same scene in solid colours.
        let mut solid = sc.clone();
        for s in &mut solid.spheres {
            if let Material::Lambertian { albedo } = &mut s.material {
                *albedo = [0.5; 3].into();
            }
        }
        assert_ne!(reference.hash(), image(&solid, s, Simd8).hash());
    }
}

#[test]
fn the_plan_runs_texture_passes_only_for_textured_scenes() {
    let o = Overrides::from(settings(8, 8, 1, 4, 0));
    let job = rtow::Job::new(&textured_scene(), &o, &RenderOptions::default()).unwrap();
    assert_eq!(job.plan().textures.iter().collect::<Vec<_>>(), [TexKind::Checker, TexKind::Noise]);
    assert!(job.plan().explain().contains("texture passes: checker, noise"), "{}", job.plan().explain());
    for name in ["final", "nw-cornell-box", "ch07-diffuse"] {
        let job = rtow::Job::new(&scene::preset(name).unwrap(), &o, &RenderOptions::default()).unwrap();
        assert!(job.plan().textures.is_empty(), "{name}");
        assert!(!job.plan().explain().contains("texture"), "{name}");
    }
    // The debug modes shade flat colours: no texture pass.
    let flat = Scene { mode: Mode::Flat, ..textured_scene() };
    assert!(rtow::Job::new(&flat, &o, &RenderOptions::default()).unwrap().plan().textures.is_empty());
}

#[test]
fn textures_round_trip_through_scene_files() {
    let sc = textured_scene();
    for format in [Format::Json, Format::Toml] {
        let text = scene::scene_to_string(&sc, format);
        let back = scene::scene_from_str(&text, format, Path::new("t")).unwrap();
        assert_eq!(back, sc, "{format:?}:\n{text}");
    }
    // The book's way, and a colour is still a colour.
    let json = r#"{"camera": {"look_from": [0, 0, 1], "look_at": [0, 0, 0]}, "spheres": [
        {"center": [0, 0, 0], "radius": 1, "material": {"type": "lambertian",
         "albedo": {"type": "checker", "scale": 0.32, "even": [0.2, 0.3, 0.1], "odd": [0.9, 0.9, 0.9]}}},
        {"center": [0, 0, 0], "radius": 1, "material": {"type": "lambertian", "albedo": {"type": "noise", "scale": 4}}},
        {"center": [0, 0, 0], "radius": 1, "material": {"type": "lambertian", "albedo": [0.5, 0.5, 0.5]}}]}"#;
    let s = read_and_check(json, Format::Json, "t.json").unwrap();
    assert_eq!(s.spheres[0].material, lam(checker_tex(0.32)));
    assert_eq!(s.spheres[1].material, lam(Texture::Noise { scale: 4.0 }));
    assert_eq!(s.spheres[2].material, lam([0.5; 3].into()));
}

#[test]
fn bad_textures_are_refused_naming_the_field() {
    let with = |albedo: &str, kind: &str| {
        let json = format!(
            r#"{{"camera": {{"look_from": [0, 0, 1], "look_at": [0, 0, 0]}}, "spheres": [
            {{"center": [0, 0, 0], "radius": 1, "material": {{"type": "{kind}", "albedo": {albedo}, "fuzz": 0}}}}]}}"#
        );
        let json = if kind == "lambertian" { json.replace(r#", "fuzz": 0"#, "") } else { json };
        read_and_check(&json, Format::Json, "t.json").unwrap_err().to_string()
    };
    let cases = [
        (
            r#"{"type": "checker", "scale": 0, "even": [1, 1, 1], "odd": [0, 0, 0]}"#,
            "lambertian",
            "spheres[0].material.albedo.scale",
        ),
        (
            r#"{"type": "checker", "scale": 1, "even": [1, -1, 1], "odd": [0, 0, 0]}"#,
            "lambertian",
            "spheres[0].material.albedo.even",
        ),
        (r#"{"type": "checker", "scale": 1, "even": [1, 1, 1]}"#, "lambertian", "missing field `odd`"),
        (r#"{"type": "noise", "scale": 1, "odd": [0, 0, 0]}"#, "lambertian", "unknown field `odd`"),
        (r#"{"type": "noise", "scale": -1}"#, "lambertian", "spheres[0].material.albedo.scale"),
        (r#"{"type": "marble", "scale": 1}"#, "lambertian", "unknown variant `marble`"),
        (r#"{"type": "noise", "scale": 1, "turbulence": 7}"#, "lambertian", "unknown field `turbulence`"),
        (r#"{"type": "noise", "scale": 1}"#, "metal", "must be a colour"),
        (r#""red""#, "lambertian", "a colour [r, g, b] or a texture"),
    ];
    for (albedo, kind, want) in cases {
        let e = with(albedo, kind);
        assert!(e.contains(want), "{albedo}: {e}");
        assert!(!e.contains('\n'), "one line: {e}");
    }
}

/// The book's textured scenes, bit for bit: scalar, 8 and 16 lanes.
#[test]
fn the_textured_presets_are_bit_identical_across_kernels() {
    for name in ["nw-checkered-spheres", "nw-perlin-spheres", "nw-simple-light"] {
        let sc = scene::preset(name).unwrap();
        let s = settings(40, 24, 4, 12, 1);
        let reference = render_with(&sc, s, Scalar, 2, 16);
        assert_eq!(reference.stats.rejected_samples, 0, "{name}");
        for kernel in [Simd8, Simd16] {
            let other = render_with(&sc, s, kernel, 2, 16);
            assert_identical(&reference.image, &other.image, &format!("{name} {kernel:?}"));
            assert_eq!(reference.stats.rays, other.stats.rays, "{name}");
        }
    }
}
