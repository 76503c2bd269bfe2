//! Issue 37, class 3: bright emitters. The film's fixed point covers the
//! scene (a scale exponent chosen from its brightest emission before any
//! work), so a light up to f32::MAX renders where it is seen.

use crate::common;

use common::{failure, rtow, Run};
use rtow::film::accum::{Scale, HEADROOM_BITS, MAX_EXPONENT};
use rtow::scene::{self, Format};
use rtow::shard::Part;
use rtow::{Image, Job, Overrides, RenderOptions};
use std::path::Path;

/// A small sphere light of radiance `emit` (in every channel) above a grey
/// ground, on a black background: the light is seen straight on at the
/// centre of a 32x24 image, whose pixels (15..17, 11..13) it covers whole.
fn light_scene(emit: &str) -> String {
    format!(
        r#"{{"camera": {{"look_from": [0, 1, 6], "look_at": [0, 1, 0], "vup": [0, 1, 0], "vfov_deg": 40}},
  "spheres": [
    {{"center": [0, -1000, 0], "radius": 1000, "material": {{"type": "lambertian", "albedo": [0.5, 0.5, 0.5]}}}},
    {{"center": [0, 1, 0], "radius": 0.3, "material": {{"type": "diffuse_light", "emit": [{emit}, {emit}, {emit}]}}}}
  ],
  "background": [0, 0, 0]}}"#
    )
}

fn stats(dir: &Path, file: &str) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join(file)).unwrap()).unwrap()
}

fn ok(r: &Run, what: &str) {
    assert!(!r.stderr.contains("panicked"), "{what}: {}", r.stderr);
    assert_eq!(r.code, 0, "{what}: {}", r.stderr);
}

/// Lights of 1e30, f32::MAX / 2 and f32::MAX render with both kernels: no
/// sample rejected, the light's pixels exactly its radiance (not black), the
/// ground lit by it, the exponent the documented one, and no warning.
#[test]
fn lights_up_to_f32_max_render_bright_where_they_are_seen() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (emit, exponent) in [("1e30", 53), ("1.7014117e38", 80), ("3.4028235e38", MAX_EXPONENT)] {
        let value: f32 = emit.parse().unwrap();
        assert!(value.is_finite());
        std::fs::write(d.join("light.json"), light_scene(emit)).unwrap();
        let mut hashes = Vec::new();
        for kernel in ["scalar", "simd"] {
            let what = format!("{emit} {kernel}");
            let r = rtow(
                d,
                &[
                    "render",
                    "light.json",
                    "--width",
                    "32",
                    "--height",
                    "24",
                    "--spp",
                    "8",
                    "--kernel",
                    kernel,
                    "-q",
                    "-o",
                    "l.png",
                    "--float",
                    "l.pfm",
                    "--stats-json",
                    "l.json",
                ],
            );
            ok(&r, &what);
            assert_eq!(r.stderr, "", "{what}: no warning");
            let s = stats(d, "l.json");
            assert_eq!(s["rejected_samples"], 0, "{what}");
            assert_eq!(s["film_exponent"], exponent, "{what}");
            assert_eq!(s["plan"]["film_exponent"], exponent, "{what}");
            let range = s["film_range"].as_f64().unwrap();
            assert!(range > value as f64 * 2f64.powi(HEADROOM_BITS as i32), "{what}: {range:e}");
            hashes.push(s["image_hash"].as_str().unwrap().to_string());
            let img = Image::load_float(&d.join("l.pfm")).unwrap();
            for (x, y) in [(15, 11), (16, 11), (15, 12), (16, 12)] {
                assert_eq!(img.get(x, y), [value; 3], "{what}: the light at ({x}, {y})");
            }
            // The ground in front of it is lit, and every value is finite.
            let ground = img.get(16, 16)[0];
            assert!(ground > value * 1e-6 && ground < value, "{what}: {ground:e}");
            assert!(img.data.iter().flatten().all(|v| v.is_finite()), "{what}");
        }
        assert_eq!(hashes[0], hashes[1], "{emit}: the kernels render the same image");
    }
}

/// The exponent comes from what can be seen: emitters (in groups and boxes
/// too), the sky or the constant background that replaces it; in the flat
/// debug mode the colours a hit shows. An albedo is not an emission in
/// path tracing. Every preset keeps exponent 0 (and so its image).
#[test]
fn the_exponent_follows_the_brightest_emission() {
    let exponent = |text: &str| {
        let s = scene::scene_from_str(text, Format::Json, Path::new("e.json")).unwrap();
        Job::new(&s, &Overrides::default(), &RenderOptions::default()).unwrap().plan().film_exponent
    };
    let cam = r#""camera": {"look_from": [0, 0, 0], "look_at": [0, 0, -1]}"#;
    let ball = |m: &str| format!(r#""spheres": [{{"center": [0, 0, -1], "radius": 0.5, "material": {m}}}]"#);
    let light = |e: &str| format!(r#"{{"type": "diffuse_light", "emit": [0, {e}, 0]}}"#);
    let lam = |a: &str| format!(r#"{{"type": "lambertian", "albedo": [{a}, 0, 0]}}"#);
    let e30 = Scale::for_brightness(1e30f32 as f64).exponent();
    assert_eq!(e30, 53);
    let cases = [
        (format!("{{{cam}, {}}}", ball(&light("4"))), 0),
        (format!("{{{cam}, {}}}", ball(&light("1e30"))), e30),
        (format!("{{{cam}, {}, \"background\": [0, 0, 0]}}", ball(&light("1e30"))), e30),
        (format!("{{{cam}, {}, \"sky\": {{\"horizon\": [1, 1, 1], \"zenith\": [0, 1e30, 0]}}}}", ball(&lam("0.5"))), e30),
        (format!("{{{cam}, {}, \"background\": [1e30, 0, 0]}}", ball(&lam("0.5"))), e30),
        // The sky is not seen behind a constant background.
        (
            format!(
                "{{{cam}, {}, \"background\": [0, 0, 0], \"sky\": {{\"horizon\": [1e30, 1, 1], \"zenith\": [1, 1, 1]}}}}",
                ball(&lam("0.5"))
            ),
            0,
        ),
        // A light box in a group.
        (
            format!(
                "{{{cam}, \"groups\": [{{\"rotate_y\": 15, \"translate\": [0, 0, -3], \"boxes\": [{{\"a\": [0, 0, 0], \
                 \"b\": [1, 1, 1], \"material\": {}}}]}}]}}",
                light("1e30")
            ),
            e30,
        ),
        // A light quad.
        (
            format!(
                "{{{cam}, \"quads\": [{{\"q\": [0, 0, -2], \"u\": [1, 0, 0], \"v\": [0, 1, 0], \"material\": {}}}]}}",
                light("1e30")
            ),
            e30,
        ),
        // An albedo is not an emission in path tracing; in the flat mode it is what a hit shows.
        (format!("{{{cam}, {}}}", ball(&lam("1e30"))), 0),
        (format!("{{\"mode\": \"flat\", {cam}, {}}}", ball(&lam("1e30"))), e30),
        (format!("{{\"mode\": \"normals\", {cam}, {}}}", ball(&light("1e30"))), 0),
    ];
    for (text, want) in cases {
        assert_eq!(exponent(&text), want, "{text}");
    }
    for p in scene::presets() {
        let s = common::self_contained(&(p.build)());
        let job = Job::new(&s, &Overrides::default(), &RenderOptions::default()).unwrap();
        assert_eq!(job.plan().film_exponent, 0, "{}", p.name);
    }
}

/// A scaled render splits, merges and resumes to the same bits; its partial
/// films record the exponent, and a part of another exponent is refused,
/// naming the file.
#[test]
fn a_scaled_render_splits_merges_and_resumes_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("light.json"), light_scene("1e30")).unwrap();
    let base = ["render", "light.json", "--width", "24", "--height", "16", "--depth", "6", "-q"];
    let run = |extra: &[&str]| rtow(d, &[&base[..], extra].concat());
    ok(&run(&["--spp", "8", "-o", "whole.png", "--stats-json", "whole.json"]), "whole");
    let whole = stats(d, "whole.json")["image_hash"].clone();
    for k in 1..=2 {
        ok(&run(&["--spp", "8", "--shard", &format!("{k}/2"), "-o", &format!("p{k}.rtfilm")]), "shard");
    }
    let part = Part::read(&d.join("p1.rtfilm")).unwrap();
    assert_eq!(part.header.film_exponent, 53);
    ok(&rtow(d, &["merge", "p1.rtfilm", "p2.rtfilm", "-o", "m.png", "--stats-json", "m.json", "-q"]), "merge");
    let m = stats(d, "m.json");
    assert_eq!((&m["image_hash"], &m["film_exponent"], &m["rejected_samples"]), (&whole, &53.into(), &0.into()));
    ok(&run(&["--spp", "4", "-o", "half.rtfilm"]), "half");
    ok(&run(&["--spp", "8", "--resume", "half.rtfilm", "-o", "r.png", "--stats-json", "r.json"]), "resume");
    assert_eq!(stats(d, "r.json")["image_hash"], whole);
    // A part whose exponent was changed (checksum recomputed) is refused by
    // the merge, and a film of another exponent by the resume.
    let mut other = Part::read(&d.join("p2.rtfilm")).unwrap();
    other.header.film_exponent = 0;
    other.film.scale = Scale::UNIT;
    other.write(&d.join("p2-unit.rtfilm")).unwrap();
    let r = rtow(d, &["merge", "p1.rtfilm", "p2-unit.rtfilm", "-o", "x.png"]);
    let line = failure(&r, 2, "merge");
    assert!(line.contains("p2-unit.rtfilm") && line.contains("scale exponent 0") && line.contains("has 53"), "{line}");
    let mut half = Part::read(&d.join("half.rtfilm")).unwrap();
    half.header.film_exponent = 52;
    half.film.scale = Scale::new(52).unwrap();
    half.write(&d.join("half-52.rtfilm")).unwrap();
    let r = run(&["--spp", "8", "--resume", "half-52.rtfilm", "-o", "x.png"]);
    let line = failure(&r, 2, "resume");
    assert!(line.contains("half-52.rtfilm") && line.contains("scale exponent 52"), "{line}");
    assert!(!d.join("x.png").exists());
}
