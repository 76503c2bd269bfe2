//! Issue 37, class 3: bright emitters. The film's fixed point covers the
//! scene (a scale exponent chosen from its brightest emission before any
//! work), so a light up to f32::MAX renders where it is seen; and a sample
//! the film still rejects is never left out silently: one warning line on
//! stderr (even with -q), the counts by cause in the statistics, and
//! `--on-rejected error` to fail instead.

use crate::common;

use common::{failure, listing, rtow, Run};
use rtow::film::accum::{Scale, HEADROOM_BITS, MAX_EXPONENT};
use rtow::scene::{self, Format};
use rtow::shard::Part;
use rtow::{Image, Job, Overrides, RenderOptions};
use std::path::Path;

const SENTINEL: &[u8] = b"old contents; a failed run must leave this file alone";

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

/// A tiny mirror of albedo `albedo` under a sky of `sky`, seen by 4 of the
/// 40,000 pixel centres of a 200x200 image at 1 spp: below the 0.1% that fails
/// a render. With albedo 1e30 (no emitter: exponent 0) its samples are finite
/// and out of the film's range; with 3e38 under a sky of 2 they overflow f32.
fn mirror_scene(albedo: &str, sky: &str) -> String {
    format!(
        r#"{{"camera": {{"look_from": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 90}},
  "sky": {{"horizon": [{sky}, {sky}, {sky}], "zenith": [{sky}, {sky}, {sky}]}},
  "spheres": [{{"center": [0, 0, -1], "radius": 0.015,
    "material": {{"type": "metal", "albedo": [{albedo}, {albedo}, {albedo}], "fuzz": 0}}}}]}}"#
    )
}

const MIRROR_SIZE: [&str; 6] = ["--width", "200", "--height", "200", "--spp", "1"];

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

/// The number in "warning: N of ..." and that the line is the only one.
fn warned(r: &Run, what: &str) -> (u64, String) {
    ok(r, what);
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{what}: {:?}", r.stderr);
    let line = lines[0].strip_prefix("warning: ").unwrap_or_else(|| panic!("{what}: {:?}", lines[0]));
    let line = line.strip_prefix("the parts' ").unwrap_or(line);
    let n = line.split(' ').next().unwrap().replace(',', "").parse().unwrap();
    assert!(lines[0].ends_with("and left out of the image"), "{what}: {:?}", lines[0]);
    (n, lines[0].to_string())
}

/// A few rejected samples (below the 0.1% that fails a render) are reported
/// by cause on stderr even with -q, and in the statistics; a finite sample is
/// never called NaN or infinite. Both kernels, a render and a merge.
#[test]
fn rejected_samples_are_reported_even_with_q_by_cause() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("hot.json"), mirror_scene("1e30", "1")).unwrap();
    std::fs::write(d.join("inf.json"), mirror_scene("3e38", "2")).unwrap();
    for (scene, finite) in [("hot.json", true), ("inf.json", false)] {
        for kernel in ["scalar", "simd"] {
            let what = format!("{scene} {kernel}");
            let mut args = vec!["render", scene, "-q", "-o", "x.png", "--stats-json", "x.json", "--kernel", kernel];
            args.extend_from_slice(&MIRROR_SIZE);
            let (n, line) = warned(&rtow(d, &args), &what);
            assert!(n > 0 && line.contains(&format!("{n} of 40,000 samples")), "{what}: {line}");
            let s = stats(d, "x.json");
            assert_eq!(s["rejected_samples"], n, "{what}");
            assert_eq!(s["film_exponent"], 0, "{what}");
            if finite {
                assert_eq!((&s["rejected_out_of_range"], &s["rejected_non_finite"]), (&n.into(), &0.into()));
                assert!(line.contains("finite but out of the film's range: |x| >= 9.223e18"), "{what}: {line}");
                assert!(!line.contains("NaN") && !line.contains("infinite"), "{what}: {line}");
            } else {
                assert_eq!((&s["rejected_out_of_range"], &s["rejected_non_finite"]), (&0.into(), &n.into()));
                assert!(line.contains("NaN or infinite") && !line.contains("range"), "{what}: {line}");
            }
            // The summary line says it too.
            let r = rtow(d, &args.iter().filter(|&&a| a != "-q").copied().collect::<Vec<_>>());
            assert!(r.stdout.contains(&format!("{n} samples rejected")), "{what}: {}", r.stdout);
        }
        // Shards carry the counts; their merge reports them the same way.
        for k in 1..=2 {
            let shard = format!("{k}/2");
            let out = format!("p{k}.rtfilm");
            let mut args = vec!["render", scene, "-q", "--shard", &shard, "--split", "rows", "-o", &out];
            args.extend_from_slice(&MIRROR_SIZE);
            ok(&rtow(d, &args), "shard");
        }
        let (n, line) = warned(&rtow(d, &["merge", "p1.rtfilm", "p2.rtfilm", "-q", "-o", "m.png"]), "merge");
        assert!(line.starts_with("warning: the parts' ") && n > 0, "{line}");
        assert_eq!(line.contains("NaN"), !finite, "{line}");
    }
}

/// `--on-rejected error`: a render (or a merge) that rejected any sample
/// fails with exit status 2 and one error line, and writes nothing: not the
/// image, the float image or the statistics, and an old file stays as it was.
#[test]
fn the_error_policy_fails_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("hot.json"), mirror_scene("1e30", "1")).unwrap();
    std::fs::write(d.join("x.png"), SENTINEL).unwrap();
    for kernel in ["scalar", "simd"] {
        let mut args = vec!["render", "hot.json", "-q", "--on-rejected", "error", "--kernel", kernel];
        args.extend_from_slice(&["-o", "x.png", "--float", "x.pfm", "--stats-json", "x.json"]);
        args.extend_from_slice(&MIRROR_SIZE);
        let line = failure(&rtow(d, &args), 2, kernel);
        assert!(line.contains("--on-rejected error: nothing written"), "{line}");
        assert!(line.contains("finite but out of the film's range") && !line.contains("NaN"), "{line}");
        assert_eq!(std::fs::read(d.join("x.png")).unwrap(), SENTINEL);
        assert_eq!(listing(d), ["hot.json", "x.png"]);
        // A shard too.
        let mut args = vec!["render", "hot.json", "--on-rejected", "error", "--shard", "1/1", "-o", "p.rtfilm"];
        args.extend_from_slice(&MIRROR_SIZE);
        failure(&rtow(d, &args), 2, kernel);
        assert_eq!(listing(d), ["hot.json", "x.png"]);
    }
    // The default policy writes the image (and warns); `warn` is the default.
    let mut args = vec!["render", "hot.json", "-q", "--on-rejected", "warn", "-o", "x.png"];
    args.extend_from_slice(&MIRROR_SIZE);
    warned(&rtow(d, &args), "warn");
    assert_ne!(std::fs::read(d.join("x.png")).unwrap(), SENTINEL);
    // A merge of parts that rejected samples.
    let mut args = vec!["render", "hot.json", "-q", "--shard", "1/1", "-o", "p.rtfilm"];
    args.extend_from_slice(&MIRROR_SIZE);
    warned(&rtow(d, &args), "shard");
    let r = rtow(d, &["merge", "p.rtfilm", "-o", "m.png", "--stats-json", "m.json", "--on-rejected", "error"]);
    let line = failure(&r, 2, "merge");
    assert!(line.contains("--on-rejected error: nothing written"), "{line}");
    assert!(!d.join("m.png").exists() && !d.join("m.json").exists());
}
