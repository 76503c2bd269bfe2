//! Scene files through the library: every kind of bad input is an error that
//! names the field (and its line and column where the parser can place it),
//! never a panic; writing scene files fails cleanly; valid scenes round-trip.

use crate::bad_input;
use crate::common;

use proptest::prelude::*;
use rtow::scene::{self, Camera, Format, Material, RenderTable, Scene, Sky, Sphere};
use rtow::{Error, Settings};
use std::path::Path;

fn format_of(file: &str) -> Format {
    Format::from_path(Path::new(file)).unwrap()
}

#[test]
fn every_bad_scene_is_an_input_error_naming_the_field() {
    for c in bad_input::cases() {
        let r = std::panic::catch_unwind(|| common::read_and_check(&c.text, format_of(c.file), c.file));
        let r = r.unwrap_or_else(|_| panic!("{}: panicked", c.file));
        let e = match r {
            Ok(s) => panic!("{}: accepted: {s:?}", c.file),
            Err(e) => e,
        };
        assert_eq!(e.exit_code(), 2, "{}: {e}", c.file);
        let msg = e.to_string();
        assert_eq!(msg.lines().count(), 1, "{}: not one line: {msg:?}", c.file);
        bad_input::check_message(&c, &msg);
        // Errors the parser finds carry the file name, and a position when it has one.
        if let Error::Parse { path, .. } = &e {
            assert_eq!(path, Path::new(c.file));
        } else {
            assert!(c.at.is_none(), "{}: a {:?} cannot carry a position", c.file, e);
        }
    }
}

#[test]
fn values_at_the_edges_of_their_ranges_are_accepted() {
    // Validation must not overreach: the limits themselves are valid.
    let json = r#"{
  "camera": {"look_from": [0, 0, 0], "look_at": [0, 0, -1e-6], "vfov_deg": 179.9, "defocus_angle_deg": 0},
  "spheres": [
    {"center": [0, 1, -1], "radius": 0.5, "material": {"type": "metal", "albedo": [0, 0, 0], "fuzz": 1}},
    {"center": [0, 1, -1], "radius": 0.5, "material": {"type": "metal", "albedo": [9, 9, 9], "fuzz": 0}}
  ],
  "render": {"width": 1, "height": 67108864, "samples_per_pixel": 1, "max_depth": 1}
}"#;
    let toml = "[camera]\nlook_from = [0, 0, 0]\nlook_at = [0, 0, -1]\nvup = [1e-3, 1, 0]\naperture = 0\n\n\
                [[spheres]]\ncenter = [0, 0, -1]\nradius = -1e-5\nmaterial = { type = \"dielectric\", ior = 1e-30 }\n\n\
                [[spheres]]\ncenter = [-1e6, 1e6, -1e6]\nradius = 1e6\nmaterial = { type = \"dielectric\", ior = 1.5 }\n";
    for (text, f) in [(json, "ok.json"), (toml, "ok.toml")] {
        common::read_and_check(text, format_of(f), f).unwrap_or_else(|e| panic!("{f}: {e}"));
    }
}

#[test]
fn load_scene_rejects_what_it_cannot_read() {
    let dir = tempfile::tempdir().unwrap();
    for (name, contents, says) in [
        ("scene.yaml", &b"camera: {}"[..], "unknown scene file type"),
        ("missing.json", &b""[..], "cannot read"),
        // Not UTF-8: the offending byte's offset, line and column.
        ("latin1.toml", &b"[camera]\n# caf\xe9\n"[..], "byte offset 14 (line 2, column 6)"),
    ] {
        let p = dir.path().join(name);
        if name != "missing.json" {
            std::fs::write(&p, contents).unwrap();
        }
        let e = scene::load_scene(&p).unwrap_err();
        assert_eq!(e.exit_code(), 2, "{e}");
        assert!(e.to_string().contains(says), "{e}");
        assert!(e.to_string().contains(name), "{e}");
    }
}

#[test]
fn settings_of_zero_or_too_large_name_the_setting() {
    let ok = Settings { width: 8, height: 4, spp: 1, max_depth: 1, seed: 0, ..Settings::default() };
    ok.validate().unwrap();
    let cases: [(Settings, &str); 6] = [
        (Settings { width: 0, ..ok }, "width"),
        (Settings { height: 0, ..ok }, "height"),
        (Settings { spp: 0, ..ok }, "spp"),
        (Settings { max_depth: 0, ..ok }, "max_depth"),
        (Settings { width: u32::MAX, height: u32::MAX, ..ok }, "width x height"),
        (Settings { width: 8192, height: 8192, spp: u32::MAX, ..ok }, "spp"),
    ];
    for (s, field) in cases {
        let e = s.validate().unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(matches!(&e, Error::Invalid { field: f, .. } if f == field), "{s:?}: {e}");
        // The library refuses before it allocates anything.
        let scene = scene::preset("ch04-sphere").unwrap();
        let e = rtow::Job::new(&scene, &s.into(), &Default::default()).expect_err("render refused");
        assert!(matches!(&e, Error::Invalid { field: f, .. } if f == field), "{e}");
    }
}

#[test]
fn saving_to_an_unwritable_path_is_an_output_error_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene::preset("ch09-glass").unwrap();
    std::fs::write(dir.path().join("plain"), b"").unwrap();
    for (target, says) in [
        ("no/such/folder/s.json", "does not exist"),
        ("plain/s.toml", "not a folder"),
        ("s.yaml", ".json or .toml"),
        ("s", ".json or .toml"),
    ] {
        let e = scene::save_scene(&s, &dir.path().join(target)).unwrap_err();
        // An unsupported extension is a usage error (2), an unwritable place an output error (1).
        let want = if says.starts_with(".json") { 2 } else { 1 };
        assert_eq!(e.exit_code(), want, "{target}: {e}");
        assert!(e.to_string().contains(says), "{target}: {e}");
    }
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left, ["plain"]);
}

#[test]
fn every_seed_round_trips_through_both_formats() {
    // TOML integers are i64 in the spec; the toml crate reads and writes the
    // whole u64 range, which is what a scene's seed needs.
    let dir = tempfile::tempdir().unwrap();
    let mut s = scene::preset("ch04-sphere").unwrap();
    for seed in [0, i64::MAX as u64, i64::MAX as u64 + 1, u64::MAX] {
        s.render.seed = Some(seed);
        for name in ["s.json", "s.toml"] {
            let p = dir.path().join(name);
            scene::save_scene(&s, &p).unwrap();
            assert_eq!(scene::load_scene(&p).unwrap(), s, "{name} {seed}");
        }
    }
}

fn finite() -> impl Strategy<Value = f32> {
    prop_oneof![
        -1e6f32..1e6,
        any::<f32>().prop_filter("finite", |x| x.is_finite()),
        Just(f32::MIN_POSITIVE / 4.0),
        Just(f32::MAX),
    ]
}

/// A finite float inside the world range (subnormal and -0 included).
fn coord() -> impl Strategy<Value = f32> {
    finite().prop_filter("in the world range", |x| x.abs() <= rtow::limits::MAX_COORD)
}

/// A radius inside the verified range, either sign.
fn radius() -> impl Strategy<Value = f32> {
    let (lo, hi) = (rtow::limits::MIN_RADIUS, rtow::limits::MAX_RADIUS);
    prop_oneof![lo..=hi, -hi..=-lo, Just(lo), Just(-hi)]
}

fn v3() -> impl Strategy<Value = [f32; 3]> {
    [coord(), coord(), coord()]
}

fn colour() -> impl Strategy<Value = [f32; 3]> {
    [0f32..=4.0, 0f32..=4.0, 0f32..=4.0]
}

fn material() -> impl Strategy<Value = Material> {
    prop_oneof![
        colour().prop_map(|albedo| Material::Lambertian { albedo: albedo.into() }),
        (colour(), 0f32..=1.0).prop_map(|(albedo, fuzz)| Material::Metal { albedo, fuzz }),
        (1e-3f32..10.0).prop_map(|ior| Material::Dielectric { ior }),
    ]
}

fn sphere() -> impl Strategy<Value = Sphere> {
    (v3(), radius(), material()).prop_map(|(center, radius, material)| Sphere {
        center,
        center1: None,
        radius,
        material,
    })
}

fn scene_strategy() -> impl Strategy<Value = Scene> {
    (
        (-100f32..100.0, -100f32..100.0, -100f32..100.0),
        1f32..179.0,
        prop::option::of(0f32..10.0),
        prop::option::of(1e-3f32..100.0),
        prop::collection::vec(sphere(), 0..6),
        (colour(), colour()),
        (prop::option::of(1u32..4096), prop::option::of(any::<u64>())),
    )
        .prop_map(|((x, y, z), vfov_deg, aperture, focus_dist, spheres, (horizon, zenith), (w, seed))| Scene {
            meshes: vec![],
            mode: Default::default(),
            camera: Camera {
                look_from: [x, y, z],
                look_at: [x + 1.0, y - 0.5, z + 2.0],
                vup: [0.0, 1.0, 0.0],
                vfov_deg,
                defocus_angle_deg: None,
                aperture,
                focus_dist,
            },
            spheres,
            quads: vec![],
            boxes: vec![],
            groups: vec![],
            media: vec![],
            sky: Sky { horizon, zenith },
            background: Default::default(),
            sample_toward: vec![],
            render: RenderTable { width: w, seed, ..Default::default() },
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Any valid scene, with any floats in range (subnormal, extreme, -0), is
    /// written and read back bit for bit in both formats (`-0.0` as `0.0`).
    #[test]
    fn valid_scenes_round_trip_exactly(s in scene_strategy()) {
        s.validate().unwrap();
        for format in [Format::Json, Format::Toml] {
            let text = scene::scene_to_string(&s, format);
            let back = scene::scene_from_str(&text, format, Path::new("p")).unwrap();
            prop_assert_eq!(&back, &s);
            // Bit for bit, except that `-0.0` reads as `0.0` (adding `+0.0`
            // changes no other value).
            let bits = |s: &Scene, z: f32| {
                s.spheres.iter().map(|p| (p.center.map(|c| (c + z).to_bits()), (p.radius + z).to_bits())).collect::<Vec<_>>()
            };
            prop_assert_eq!(bits(&back, -0.0), bits(&s, 0.0));
        }
    }

    /// A sphere outside the verified range (any finite float, huge ones
    /// included: `r^2` overflows f32 above ~1.8e19) is refused in both
    /// formats, naming the field, never rendered as a vanished sphere.
    #[test]
    fn out_of_range_spheres_are_refused_naming_the_field(s in scene_strategy(), c in finite(), r in finite()) {
        let mut s = s;
        s.spheres = vec![Sphere { center: [c, 0.0, 0.0], center1: None, radius: r, material: Material::Dielectric { ior: 1.5 } }];
        let lim = &rtow::limits::MAX_COORD;
        let ok_c = c.abs() <= *lim;
        let ok_r = (rtow::limits::MIN_RADIUS..=rtow::limits::MAX_RADIUS).contains(&r.abs());
        for format in [Format::Json, Format::Toml] {
            let text = scene::scene_to_string(&s, format);
            match common::read_and_check(&text, format, "p") {
                Ok(_) => prop_assert!(ok_c && ok_r, "accepted c {c} r {r}"),
                Err(e) => {
                    prop_assert!(!(ok_c && ok_r), "refused c {c} r {r}: {e}");
                    let field = if ok_c { "spheres[0].radius" } else { "spheres[0].center" };
                    prop_assert!(e.to_string().contains(field), "{e}");
                    prop_assert_eq!(e.exit_code(), 2);
                }
            }
        }
    }
}

/// `-0.0` anywhere in a scene file reads as `0.0` (no field gives a zero's
/// sign a meaning; a medium's density of `-0.0` rendered another image):
/// every preset with each zero written `-0.0` reads back to exactly the
/// preset, bit for bit (compared as written out again, where `-0.0` would
/// show).
#[test]
fn negative_zeros_read_as_zeros_in_every_field() {
    for p in scene::presets() {
        let s = (p.build)();
        let text = scene::scene_to_string(&s, Format::Json);
        // Every number token that is a float zero, as `-0.0`.
        let mut neg = String::with_capacity(text.len());
        let mut zeros = 0;
        let mut rest = text.as_str();
        while let Some(i) = rest.find(|c: char| c.is_ascii_digit() || c == '-') {
            let (head, tail) = rest.split_at(i);
            neg.push_str(head);
            let end = tail.find(|c: char| !(c.is_ascii_digit() || "-+.eE".contains(c))).unwrap_or(tail.len());
            let token = &tail[..end];
            // (Floats only: serde_json writes them with a point, integers without.)
            if token.contains('.') && token.parse::<f64>().is_ok_and(|v| v == 0.0) && !head.ends_with('"') {
                neg.push_str("-0.0");
                zeros += 1;
            } else {
                neg.push_str(token);
            }
            rest = &tail[end..];
        }
        neg.push_str(rest);
        let back =
            scene::scene_from_str(&neg, Format::Json, Path::new("p")).unwrap_or_else(|e| panic!("{}: {e}", p.name));
        assert_eq!(scene::scene_to_string(&back, Format::Json), text, "{}: {zeros} zeros written -0.0", p.name);
    }
}
