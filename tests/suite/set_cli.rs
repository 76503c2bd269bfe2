//! `rtow render --set KEY=VALUE`, through the binary: an assignment renders
//! the scene a file edited the same way renders, for presets and files
//! alike; a film rendered with one is another scene's (no merge, no resume
//! with a film without it); malformed or wrong assignments, and unknown keys
//! in files, are refused in one line with the nearest key.

use crate::common;

use common::{failure, rtow, Run};
use rtow::scene::{preset, scene_to_string, Format, Material, Texture};
use std::path::Path;

const SMALL: [&str; 8] = ["--width", "16", "--height", "8", "--spp", "2", "--depth", "6"];

/// `rtow render SCENE -o OUT` at a small size, quietly, with `extra` flags.
fn render(dir: &Path, scene: &str, out: &str, extra: &[&str]) -> Run {
    let mut args = vec!["render", scene, "-q", "-o", out];
    args.extend_from_slice(&SMALL);
    args.extend_from_slice(extra);
    rtow(dir, &args)
}

fn ok(r: &Run, what: &str) {
    assert_eq!(r.code, 0, "{what}: stderr: {}", r.stderr);
}

fn bytes(dir: &Path, file: &str) -> Vec<u8> {
    std::fs::read(dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"))
}

const SETS: [&str; 6] = [
    "--set",
    "camera.vfov_deg=30",
    "--set",
    "spheres[1].material={\"type\": \"lambertian\", \"albedo\": [0.8, 0.1, 0.1]}",
    "--set",
    "spheres.2.radius=0.25",
];

/// The preset with the edits `SETS` makes, done on the value.
fn edited() -> rtow::Scene {
    let mut scene = preset("ch09-glass").unwrap();
    scene.camera.vfov_deg = 30.0;
    scene.spheres[1].material = Material::Lambertian { albedo: Texture::Solid([0.8, 0.1, 0.1]) };
    scene.spheres[2].radius = 0.25;
    scene
}

#[test]
fn a_set_renders_the_scene_an_edited_file_renders() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    assert!(preset("ch09-glass").unwrap().spheres.len() > 2, "the edits need three spheres");
    std::fs::write(d.join("edited.json"), scene_to_string(&edited(), Format::Json)).unwrap();
    std::fs::write(d.join("plain.toml"), scene_to_string(&preset("ch09-glass").unwrap(), Format::Toml)).unwrap();
    ok(&render(d, "edited.json", "file.png", &[]), "the edited file");
    ok(&render(d, "ch09-glass", "preset.png", &SETS), "the preset with --set");
    ok(&render(d, "plain.toml", "toml.png", &SETS), "the TOML file with --set");
    ok(&render(d, "ch09-glass", "plain.png", &[]), "the preset");
    assert_eq!(bytes(d, "preset.png"), bytes(d, "file.png"), "--set on a preset");
    assert_eq!(bytes(d, "toml.png"), bytes(d, "file.png"), "--set on a file");
    assert_ne!(bytes(d, "plain.png"), bytes(d, "file.png"), "the edits change the image");
    // Applied in order: a later assignment to the same key wins.
    ok(&render(d, "ch09-glass", "twice.png", &[&SETS[..], &["--set", "camera.vfov_deg=30"]].concat()), "twice");
    assert_eq!(bytes(d, "twice.png"), bytes(d, "file.png"));
    // The render table is the scene's: --set reaches it, a flag still wins.
    let r = rtow(d, &["render", "ch09-glass", "-o", "t.png", "--set", "render.width=12", "--set", "render.height=4"]);
    ok(&r, "render.width");
    let png = image::open(d.join("t.png")).unwrap();
    assert_eq!((png.width(), png.height()), (12, 4));
}

#[test]
fn a_film_rendered_with_a_set_is_another_scenes_film() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let shard = |k: &str, out: &str, sets: &[&str]| render(d, "ch09-glass", out, &[&["--shard", k], sets].concat());
    ok(&shard("1/2", "set-1.rtfilm", &SETS), "shard 1 with --set");
    ok(&shard("2/2", "set-2.rtfilm", &SETS), "shard 2 with --set");
    ok(&shard("2/2", "plain-2.rtfilm", &[]), "shard 2 without");
    ok(&rtow(d, &["merge", "set-1.rtfilm", "set-2.rtfilm", "-o", "merged.png", "-q"]), "merge with --set");
    let line = failure(&rtow(d, &["merge", "set-1.rtfilm", "plain-2.rtfilm", "-o", "mixed.png", "-q"]), 2, "mixed");
    assert!(line.contains("scene"), "{line}");
    assert!(!d.join("mixed.png").exists());
    // The merged image is the one-process render's with the same --set.
    ok(&render(d, "ch09-glass", "whole.png", &SETS), "one process");
    assert_eq!(bytes(d, "merged.png"), bytes(d, "whole.png"));
    // Resuming: only the same scene, so only with the same --set.
    ok(&render(d, "ch09-glass", "first.rtfilm", &SETS), "a film to resume");
    let resume = |sets: &[&str]| {
        let mut args = vec!["render", "ch09-glass", "-q", "-o", "resumed.png", "--resume", "first.rtfilm"];
        args.extend_from_slice(&["--width", "16", "--height", "8", "--spp", "4", "--depth", "6"]);
        args.extend_from_slice(sets);
        rtow(d, &args)
    };
    let line = failure(&resume(&[]), 2, "resume without --set");
    assert!(line.contains("first.rtfilm") && line.contains("scene"), "{line}");
    assert!(!d.join("resumed.png").exists());
    ok(&resume(&SETS), "resume with --set");
}

#[test]
fn a_wrong_set_is_refused_in_one_line_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let huge = format!("camera.vfov_deg={}", "9".repeat(100_000));
    let long_key = format!("{}=1", "a.".repeat(10_000));
    let cases: Vec<(String, Vec<&str>)> = vec![
        ("camera".into(), vec!["--set camera", "KEY=VALUE"]),
        ("=30".into(), vec!["the key is empty"]),
        ("camera..vfov_deg=30".into(), vec!["empty name"]),
        ("spheres[x].radius=1".into(), vec!["`x` is not an index"]),
        ("spheres[-1].radius=1".into(), vec!["`-1` is not an index"]),
        ("spheres[99999999999999999999999].radius=1".into(), vec!["is not an index"]),
        ("spheres.9999.radius=1".into(), vec!["index 9999 is out of range", "`spheres` has"]),
        ("camera.vfov_deg.x=1".into(), vec!["`camera.vfov_deg` is a number, not a table"]),
        ("camera.vfovv=30".into(), vec!["--set camera.vfovv=30: unknown field `vfovv`", "did you mean `vfov_deg`?"]),
        ("camra.vfov_deg=30".into(), vec!["unknown field `camra`", "did you mean `camera`?"]),
        ("render.spp=16".into(), vec!["unknown field `spp`", "did you mean `samples_per_pixel`?"]),
        ("spheres.0.material.type=lambertan".into(), vec!["did you mean `lambertian`?"]),
        ("spheres.0.material.type=metal".into(), vec!["spheres[0].material: missing field `fuzz`"]),
        ("spheres.0.radius=abc".into(), vec!["invalid type: string \"abc\", expected a number"]),
        ("camera.vfov_deg=NaN".into(), vec!["expected a number"]),
        ("camera.vfov_deg=1e999".into(), vec!["not JSON", "out of range"]),
        ("camera.vfov_deg=1e30".into(), vec!["camera.vfov_deg: must be"]),
        ("camera.vfov_deg=-5".into(), vec!["camera.vfov_deg: must be"]),
        ("render.width=99999999999999999999".into(), vec!["too large"]),
        ("render.samples_per_pixel=0".into(), vec!["render.samples_per_pixel: must be at least 1"]),
        ("spheres.0.radius=[1, 2".into(), vec!["not JSON"]),
        (huge, vec!["not JSON", "out of range"]),
        (long_key, vec!["longer than"]),
    ];
    for (set, needles) in cases {
        let r = render(d, "ch09-glass", "out.png", &["--set", &set]);
        let what = rtow::output::clip(&set);
        let line = failure(&r, 2, &what);
        assert!(line.len() < 1000, "{what}: {} bytes", line.len());
        for n in needles {
            assert!(line.contains(n), "{what}: {line:?} does not say {n:?}");
        }
        assert!(!d.join("out.png").exists(), "{what}: wrote the image");
    }
    // Every command that opens a scene through the shared flags takes --set.
    let r = rtow(d, &["bench", "ch09-glass", "--set", "camera.vfovv=1"]);
    assert!(failure(&r, 2, "bench").contains("did you mean `vfov_deg`?"));
}

#[test]
fn unknown_names_in_files_and_commands_get_the_nearest_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let json = scene_to_string(&preset("ch09-glass").unwrap(), Format::Json);
    std::fs::write(d.join("typo.json"), json.replacen("\"vfov_deg\"", "\"vfov_dg\"", 1)).unwrap();
    let toml = scene_to_string(&preset("ch09-glass").unwrap(), Format::Toml);
    std::fs::write(d.join("typo.toml"), toml.replacen("look_at", "lookat", 1)).unwrap();
    for (file, needle) in [("typo.json", "did you mean `vfov_deg`?"), ("typo.toml", "did you mean `look_at`?")] {
        let line = failure(&render(d, file, "out.png", &[]), 2, file);
        assert!(line.contains(file) && line.contains(needle), "{file}: {line}");
    }
    // Commands are clap's: a mistyped one gets its suggestion.
    let line = failure(&rtow(d, &["rendr", "final"]), 2, "rendr");
    assert!(line.contains("'render'"), "{line}");
}
