//! The `rtow` binary: bad input exits 2 and unwritable outputs exit 1, each
//! with one `error: ...` line and without touching any output; exported scenes
//! render the identical image; `--version`, `scenes` and `--stats-json` say
//! what they promise.

use crate::bad_input;
use crate::common;

use common::{failure, listing, rtow, rtow_env, self_contained, test_images, Run};
use rtow::scene;
use rtow::{Image, Job, KernelChoice, Overrides, RenderOptions};

/// A small render: a few milliseconds for any preset.
const SMALL: [&str; 7] = ["--width", "32", "--height", "18", "--spp", "2", "-q"];
/// What an output that must survive a failed run holds.
const SENTINEL: &[u8] = b"not an image; a failed run must leave this file alone";

fn success(r: &Run, what: &str) {
    assert_eq!(r.code, 0, "{what}: exit status (stderr: {})", r.stderr);
}

#[test]
fn every_bad_scene_file_exits_2_naming_the_field_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("keep.png"), SENTINEL).unwrap();
    for c in bad_input::cases() {
        std::fs::write(d.join(c.file), &c.text).unwrap();
        let r = rtow(d, &["render", c.file, "-o", "keep.png", "--float", "new.pfm", "--stats-json", "new.json"]);
        let line = failure(&r, 2, c.file);
        bad_input::check_message(&c, &line);
        assert_eq!(std::fs::read(d.join("keep.png")).unwrap(), SENTINEL, "{}", c.file);
        let mut want = vec![c.file.to_string(), "keep.png".to_string()];
        want.sort();
        assert_eq!(listing(d), want, "{}: files left behind", c.file);
        std::fs::remove_file(d.join(c.file)).unwrap();
    }
}

#[test]
fn bad_arguments_exit_2_naming_the_argument_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("keep.png"), SENTINEL).unwrap();
    let render = |extra: &[&'static str]| -> Vec<&'static str> {
        let mut v = vec!["render", "ch07-diffuse", "-q", "-o", "keep.png", "--stats-json", "new.json"];
        v.extend_from_slice(extra);
        v
    };
    let cases: Vec<(Vec<&str>, &[&str])> = vec![
        (render(&["--width", "0"]), &["width: must be at least 1"]),
        (render(&["--height", "0"]), &["height: must be at least 1"]),
        (render(&["--spp", "0"]), &["spp: must be at least 1"]),
        (render(&["--depth", "0"]), &["--depth: must be at least 1"]),
        (render(&["--width", "100000", "--height", "100000"]), &["width x height", "memory"]),
        (render(&["--width", "8192", "--height", "8192", "--spp", "4000000000"]), &["spp: 4000000000"]),
        (render(&["--width", "-5"]), &["'-5'"]),
        (render(&["--width", "wide"]), &["--width", "'wide'"]),
        (render(&["--kernel", "gpu"]), &["--kernel", "'gpu'", "scalar", "simd"]),
        (render(&["--gamma", "nan"]), &["--gamma", "> 0"]),
        (render(&["--gamma=-2.2"]), &["--gamma", "> 0"]),
        (render(&["--gamma", "0"]), &["--gamma", "> 0"]),
        (render(&["--tile", "0"]), &["tile"]),
        (render(&["--bogus"]), &["--bogus"]),
        // An unsupported output type is a usage error naming the supported ones (issue 11, class 7).
        (vec!["render", "ch07-diffuse", "-q", "-o", "out.jpg"], &["-o", "out.jpg", ".png"]),
        (render(&["--float", "out.tiff"]), &["--float", "out.tiff", ".pfm or .exr"]),
        (vec!["export", "final", "-o", "final.yaml"], &["final.yaml", ".json or .toml"]),
        // Absurd resource flags are refused up front with the bound (class 4).
        (render(&["--threads", "100000000"]), &["--threads", "1024"]),
        (vec!["bench", "ch07-diffuse", "--threads", "5000"], &["--threads", "1024"]),
        (vec!["stress", "--quick", "--threads", "5000"], &["--threads", "1024"]),
        // Bad input is reported before any output path is looked at.
        (vec!["render", "ch07-diffuse", "-q", "--width", "0", "-o", "missing/out.png"], &["width"]),
        (vec!["render", "no-such-preset", "-o", "keep.png"], &["unknown scene 'no-such-preset'"]),
        (vec!["render", "missing.json", "-o", "keep.png"], &["cannot read missing.json"]),
        (vec!["render", "scene.yaml", "-o", "keep.png"], &["scene.yaml", "unknown scene file type"]),
        (vec!["render"], &["<SCENE>"]),
        (vec!["export", "no-such-preset", "-o", "new.json"], &["unknown preset 'no-such-preset'"]),
        // A mistyped preset: the nearest name.
        (vec!["render", "fnal", "-o", "keep.png"], &["unknown scene 'fnal'", "did you mean 'final'?"]),
        (vec!["export", "nw-cornel-box", "-o", "new.json"], &["did you mean 'nw-cornell-box'?"]),
        (vec!["export", "final"], &["--output"]),
        // Meshes: a scene without any written as OBJ, a level too fine.
        (vec!["export", "final", "-o", "final.obj"], &["no meshes", "--tessellate"]),
        (render(&["--tessellate", "8"]), &["--tessellate", "at most 7"]),
        (vec!["paint"], &["'paint'"]),
    ];
    for (args, needles) in cases {
        let what = args.join(" ");
        let line = failure(&rtow(d, &args), 2, &what);
        for n in needles {
            assert!(line.contains(n), "{what}: {line:?} does not say {n:?}");
        }
        assert_eq!(std::fs::read(d.join("keep.png")).unwrap(), SENTINEL, "{what}");
        assert_eq!(listing(d), ["keep.png"], "{what}: files left behind");
    }
}

/// `rtow export` writes a scene's meshes as OBJ, every triangle in world
/// space: a preset's mesh, and any scene's spheres tessellated.
#[test]
fn export_writes_meshes_as_obj() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let count = |file: &str, prefix: &str| {
        std::fs::read_to_string(d.join(file)).unwrap().lines().filter(|l| l.starts_with(prefix)).count()
    };
    success(&rtow(d, &["export", "cornell-box-mesh", "-o", "box.obj"]), "export cornell-box-mesh");
    assert_eq!((count("box.obj", "o "), count("box.obj", "f "), count("box.obj", "v ")), (1, 5120, 2562));
    success(&rtow(d, &["export", "ch09-glass", "--tessellate", "1", "-o", "glass.obj"]), "export --tessellate 1");
    let spheres = scene::preset("ch09-glass").unwrap().spheres.len();
    assert_eq!((count("glass.obj", "o "), count("glass.obj", "f ")), (spheres, 80 * spheres));
}

#[test]
fn unwritable_outputs_exit_1_before_rendering_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("keep.png"), SENTINEL).unwrap();
    std::fs::write(d.join("plain"), b"").unwrap();
    std::fs::create_dir(d.join("dir.png")).unwrap();
    let render = |extra: &[&'static str]| -> Vec<&'static str> {
        let mut v = vec!["render", "ch08-fuzz"];
        v.extend_from_slice(&SMALL);
        v.extend_from_slice(extra);
        v
    };
    let cases: Vec<(Vec<&str>, &[&str])> = vec![
        (render(&["-o", "missing/out.png"]), &["missing/out.png", "does not exist"]),
        (render(&["-o", "plain/out.png"]), &["plain/out.png", "not a folder"]),
        (render(&["-o", "dir.png"]), &["dir.png", "is a directory"]),
        // A later output that cannot be written stops the run before the
        // image is written, so no run leaves some of its outputs behind.
        (render(&["-o", "keep.png", "--float", "missing/out.pfm"]), &["missing/out.pfm", "does not exist"]),
        (
            render(&["-o", "keep.png", "--float", "plain/x.exr", "--stats-json", "s.json"]),
            &["plain/x.exr", "not a folder"],
        ),
        (render(&["-o", "keep.png", "--stats-json", "missing/stats.json"]), &["missing/stats.json", "does not exist"]),
        (render(&["-o", "keep.png", "--stats-json", "dir.png"]), &["dir.png", "is a directory"]),
        (vec!["export", "final", "-o", "missing/final.json"], &["missing/final.json", "does not exist"]),
        (vec!["export", "final", "-o", "plain/final.toml"], &["plain/final.toml"]),
    ];
    for (args, needles) in cases {
        let what = args.join(" ");
        let line = failure(&rtow(d, &args), 1, &what);
        assert!(line.starts_with("error: cannot write "), "{what}: {line}");
        assert!(!line.contains(".rtow-"), "{what}: the temporary name leaked: {line}");
        for n in needles {
            assert!(line.contains(n), "{what}: {line:?} does not say {n:?}");
        }
        assert_eq!(std::fs::read(d.join("keep.png")).unwrap(), SENTINEL, "{what}");
        assert_eq!(listing(d), ["dir.png", "keep.png", "plain"], "{what}: files left behind");
        assert_eq!(listing(&d.join("dir.png")), Vec::<String>::new(), "{what}");
    }
}

/// The `SMALL` flags as the library's overrides.
fn small_settings() -> Overrides {
    Overrides { width: Some(32), height: Some(18), spp: Some(2), ..Default::default() }
}

fn render_lib(scene: &scene::Scene, o: Overrides, kernel: KernelChoice) -> rtow::Rendered {
    let opts = RenderOptions { kernel, ..Default::default() };
    rtow::render(&Job::new(scene, &o, &opts).unwrap(), None).unwrap()
}

#[test]
fn a_render_writes_exactly_its_outputs_and_they_match_the_library() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let preset = scene::preset("ch08-fuzz").unwrap();
    let s = Overrides { max_depth: Some(7), seed: Some(12345), ..small_settings() };
    let lib = render_lib(&preset, s, KernelChoice::Scalar);
    // Twice: once creating the outputs, once replacing them.
    for round in 0..2 {
        let r = rtow(
            d,
            &[
                "render",
                "ch08-fuzz",
                "--width",
                "32",
                "--height",
                "18",
                "--spp",
                "2",
                "--depth",
                "7",
                "--seed",
                "12345",
                "--kernel",
                "scalar",
                "-o",
                "out.png",
                "--float",
                "out.pfm",
                "--stats-json",
                "stats.json",
            ],
        );
        success(&r, "render");
        assert!(r.stdout.contains("out.png"), "round {round}: summary line: {:?}", r.stdout);
        assert_eq!(listing(d), ["out.pfm", "out.png", "stats.json"], "round {round}");
        let png = image::open(d.join("out.png")).unwrap().into_rgb8();
        assert_eq!(png.dimensions(), (32, 18));
        assert_eq!(png.into_raw(), lib.image.to_rgb8(preset.mode.default_gamma()));
        assert_eq!(Image::load_float(&d.join("out.pfm")).unwrap(), lib.image);
        let stats: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("stats.json")).unwrap()).unwrap();
        assert_eq!(stats["image_hash"], lib.stats.image_hash.as_str());
    }
}

#[test]
fn stats_json_reports_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for kernel in ["scalar", "simd"] {
        let r = rtow(
            d,
            &[
                "render",
                "ch07-diffuse",
                "--width",
                "24",
                "--height",
                "10",
                "--spp",
                "3",
                "--depth",
                "9",
                "--seed",
                "77",
                "--threads",
                "2",
                "--kernel",
                kernel,
                "-q",
                "-o",
                "out.png",
                "--stats-json",
                "stats.json",
            ],
        );
        success(&r, kernel);
        assert_eq!(r.stdout, "", "-q prints nothing");
        let text = std::fs::read_to_string(d.join("stats.json")).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let o = v.as_object().unwrap_or_else(|| panic!("not an object: {text}"));
        for key in [
            "rays",
            "samples",
            "seconds",
            "mrays_per_s",
            "kernel",
            "threads",
            "isa",
            "width",
            "height",
            "spp",
            "max_depth",
            "seed",
            "lanes",
            "work",
            "image_hash",
        ] {
            assert!(o.contains_key(key), "{kernel}: no {key} in {text}");
        }
        let u = |k: &str| v[k].as_u64().unwrap_or_else(|| panic!("{k} is not an integer: {text}"));
        let f = |k: &str| v[k].as_f64().unwrap_or_else(|| panic!("{k} is not a number: {text}"));
        let resolved = rtow::Kernel::resolve(kernel.parse().unwrap());
        assert_eq!(v["kernel"], resolved.name());
        assert_eq!(u("lanes"), resolved.lanes() as u64);
        assert_eq!(v["isa"], rtow::isa());
        assert_eq!((u("width"), u("height"), u("spp")), (24, 10, 3));
        assert_eq!((u("max_depth"), u("seed"), u("threads")), (9, 77, 2));
        assert_eq!(u("samples"), 24 * 10 * 3);
        // Every sample casts its camera ray; no path casts more than max_depth.
        assert!(u("rays") >= u("samples") && u("rays") <= u("samples") * 9, "{text}");
        assert!(f("seconds") > 0.0, "{text}");
        // The work counters: every ray is one active lane of an intersection
        // packet (SIMD), and visits at least one node or tests at least one sphere.
        let w = |k: &str| v["work"][k].as_u64().unwrap_or_else(|| panic!("work.{k}: {text}"));
        if resolved != rtow::Kernel::Scalar {
            assert_eq!(w("isect_active"), u("rays"), "{text}");
            assert!(w("isect_lanes") >= w("isect_active"), "{text}");
        }
        assert!(w("sphere_tests") > 0 && w("roots") <= w("sphere_tests"), "{text}");
    }
}

#[test]
fn version_names_the_simd_instruction_set() {
    let dir = tempfile::tempdir().unwrap();
    for flag in ["--version", "-V"] {
        let r = rtow(dir.path(), &[flag]);
        success(&r, flag);
        assert!(r.stdout.contains(env!("CARGO_PKG_VERSION")), "{:?}", r.stdout);
        assert!(r.stdout.contains(rtow::isa()), "{:?} lacks {:?}", r.stdout, rtow::isa());
        // The commit the build came from, or that it is not known.
        let commit =
            rtow::provenance::commit().map_or("commit unknown".to_string(), |c| format!("commit {}", &c[..12]));
        assert!(r.stdout.contains(&commit), "{:?} lacks {commit:?}", r.stdout);
    }
}

#[test]
fn scenes_lists_every_preset_under_its_group() {
    let dir = tempfile::tempdir().unwrap();
    let r = rtow(dir.path(), &["scenes"]);
    success(&r, "scenes");
    // A heading per group, then its presets, indented; a blank line between groups.
    let lines: Vec<&str> = r.stdout.lines().filter(|l| l.starts_with("  ")).collect();
    assert_eq!(lines.len(), scene::presets().len(), "{}", r.stdout);
    let mut want: Vec<&scene::Preset> = Vec::new();
    for &g in scene::PresetGroup::ALL {
        want.extend(scene::presets().iter().filter(|p| p.group == g));
    }
    for (p, line) in want.iter().zip(&lines) {
        assert_eq!(line.split_whitespace().next(), Some(p.name), "{line}");
        assert!(line.contains(p.description), "{line}");
    }
    let headings: Vec<&str> = r.stdout.lines().filter(|l| l.ends_with(':') && !l.starts_with(' ')).collect();
    let titles: Vec<String> = scene::PresetGroup::ALL.iter().map(|g| format!("{}:", g.title())).collect();
    assert_eq!(headings, titles, "{}", r.stdout);
    // The book's list holds no stress scene.
    let book = r.stdout.split("\n\n").next().unwrap();
    assert!(book.contains("final") && !book.contains("stress-"), "{book}");
}

#[test]
fn help_states_the_defaults_the_library_uses() {
    let dir = tempfile::tempdir().unwrap();
    let help = |cmd: &str| {
        let r = rtow(dir.path(), &[cmd, "--help"]);
        success(&r, cmd);
        r.stdout.split_whitespace().collect::<Vec<_>>().join(" ")
    };
    let render = help("render");
    let d = rtow::Settings::default();
    let (w, h, spp, depth) = rtow::Settings::BOOK;
    for want in [
        format!("else {}, the book's]", d.max_depth),
        format!("else {}]", d.seed),
        format!("else {}]", d.sampler),
        format!("{w}x{h}, {spp} spp, depth {depth}"),
        format!("[default: {}]", rtow::DEFAULT_TILE),
        format!("at most {}", rtow::limits::MAX_TILE),
        format!("[default: {}]", rtow::ROULETTE_AFTER_RAYS),
        format!("[default: {}]", rtow::ADAPTIVE_MIN_SPP),
        format!(
            "[default: {} for path traced scenes, {} for the debug",
            rtow::Mode::Path.default_gamma(),
            rtow::Mode::Normals.default_gamma()
        ),
    ] {
        assert!(render.contains(&want), "render --help lacks {want:?}: {render}");
    }
    let bench = help("bench");
    use rtow::instruments::bench::{DEFAULT_REPEAT, DEFAULT_TOLERANCE};
    for want in [format!("[default: {DEFAULT_REPEAT}]"), format!("[default: {DEFAULT_TOLERANCE}]")] {
        assert!(bench.contains(&want), "bench --help lacks {want:?}: {bench}");
    }
    let converge = help("converge");
    let want = format!("adaptive (threshold {})", rtow::instruments::converge::DEFAULT_ADAPTIVE_THRESHOLD);
    assert!(converge.contains(&want), "converge --help lacks {want:?}");
}

#[test]
fn negative_numbers_reach_the_checks_of_their_flags() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&[&str], &str); 6] = [
        (&["render", "ch07-diffuse", "--gamma", "-1", "-o", "a.png"], "--gamma: must be a finite number > 0, got -1"),
        (&["render", "ch07-diffuse", "--adaptive", "-0.5", "-o", "a.png"], "--adaptive: the relative error threshold"),
        (&["bench", "ch07-diffuse", "--tolerance", "-3"], "--tolerance: must be a percentage >= 0, got -3"),
        (&["render", "ch07-diffuse", "--seed", "-1", "-o", "a.png"], "invalid value '-1' for '--seed <SEED>'"),
        (&["render", "ch07-diffuse", "--threads", "-2", "-o", "a.png"], "invalid value '-2' for '--threads"),
        (&["converge", "ch07-diffuse", "--spp-list", "-4,16"], "invalid value '-4' for '--spp-list"),
    ];
    for (args, want) in cases {
        let line = failure(&rtow(d, args), 2, &args.join(" "));
        assert!(line.contains(want), "{}: {line}", args.join(" "));
    }
}

#[test]
fn adaptive_sampling_that_cannot_act_warns_and_the_stats_say_it_was_off() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut args = vec!["render", "ch07-diffuse", "--adaptive", "0.05", "--adaptive-min", "4", "--spp", "4"];
    args.extend(["--width", "16", "--height", "9", "-q", "-o", "a.png", "--stats-json", "a.json"]);
    let r = rtow(d, &args);
    success(&r, "adaptive");
    assert!(r.stderr.starts_with("warning: --adaptive-min: adaptive sampling decides first after 4"), "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("a.json")).unwrap()).unwrap();
    assert!(v["adaptive"].is_null(), "{v}");
    // One more sample and it runs, without a word.
    args[7] = "5";
    let r = rtow(d, &args);
    success(&r, "adaptive on");
    assert_eq!(r.stderr, "");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("a.json")).unwrap()).unwrap();
    assert_eq!(v["adaptive"]["min_spp"], 4, "{v}");
}

#[test]
fn completions_and_the_manual_page_are_generated() {
    let dir = tempfile::tempdir().unwrap();
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let r = rtow(dir.path(), &["completions", shell]);
        success(&r, shell);
        assert!(r.stdout.contains("rtow") && r.stdout.contains("render") && r.stdout.contains("stats-json"), "{shell}");
    }
    let r = rtow(dir.path(), &["man"]);
    success(&r, "man");
    assert!(r.stdout.contains(".TH rtow 1") && r.stdout.contains("render"), "{}", &r.stdout[..200.min(r.stdout.len())]);
    failure(&rtow(dir.path(), &["completions", "cmd.exe"]), 2, "an unknown shell");
}

/// Every statistics file says what was run, on what, by which build; a
/// merge's has the same fields as a render's, its settings from the parts.
#[test]
fn statistics_files_carry_their_provenance_in_one_schema() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let size = ["--width", "24", "--height", "14", "--spp", "4", "--depth", "6", "--seed", "9", "-q"];
    let run = |extra: &[&str]| success(&rtow(d, &[&["render", "ch08-fuzz"][..], &size, extra].concat()), "render");
    run(&["--threads", "1", "-o", "one.png", "--stats-json", "one.json"]);
    run(&["--shard", "1/2", "--rr", "-o", "p1.rtfilm"]);
    run(&["--shard", "2/2", "--rr", "-o", "p2.rtfilm"]);
    run(&["--rr", "-o", "rr.png", "--stats-json", "rr.json"]);
    success(&rtow(d, &["merge", "p1.rtfilm", "p2.rtfilm", "-o", "m.png", "--stats-json", "m.json", "-q"]), "merge");
    let read =
        |f: &str| -> serde_json::Value { serde_json::from_str(&std::fs::read_to_string(d.join(f)).unwrap()).unwrap() };
    let (one, rr, m) = (read("one.json"), read("rr.json"), read("m.json"));
    let keys = |v: &serde_json::Value| v.as_object().unwrap().keys().cloned().collect::<Vec<_>>();
    assert_eq!(keys(&one), keys(&m), "one schema for render and merge");
    assert_eq!((one["schema"].as_str(), m["schema"].as_str()), (Some("rtow-stats/1"), Some("rtow-stats/1")));
    assert_eq!((one["command"].as_str(), m["command"].as_str()), (Some("render"), Some("merge")));
    // The merge's settings are the parts': those of the one-process render with --rr.
    for k in [
        "width",
        "height",
        "spp",
        "max_depth",
        "seed",
        "sampler",
        "russian_roulette",
        "adaptive",
        "rays",
        "samples",
        "image_hash",
    ] {
        assert_eq!(m[k], rr[k], "{k}");
    }
    assert_eq!(m["russian_roulette"], rtow::ROULETTE_AFTER_RAYS);
    assert!(m["kernel"].is_null() && m["work"].is_null() && m["mrays_per_s"].is_null());
    assert_eq!(m["merge"]["parts"], 2);
    assert_eq!(m["split"]["kind"], "samples");
    assert_eq!(one["split"]["kind"], "none");
    assert_eq!(one["threads"], 1);
    for v in [&one, &m] {
        let p = &v["provenance"];
        assert_eq!(p["rtow"], env!("CARGO_PKG_VERSION"));
        assert_eq!(p["isa"], rtow::isa());
        assert!(p["rustc"].as_str().unwrap().starts_with("rustc "), "{p}");
        assert!(p["logical_cores"].as_u64().unwrap() >= 1 && p["available_cores"].as_u64().unwrap() >= 1);
        assert!(p["date_utc"].as_str().unwrap().ends_with('Z'), "{p}");
        assert_eq!(p["command_line"][1], v["command"], "{p}");
        assert!(p["commit"].is_null() || p["commit"].as_str().unwrap().len() == 40, "{p}");
        assert!(matches!(p["simd_lanes"].as_u64(), Some(8 | 16)), "{p}");
    }
    assert!(one["provenance"]["command_line"].as_array().unwrap().iter().any(|a| a == "one.json"));
}

/// `rtow export` writes every preset in both formats; the file loads back as
/// the preset and renders the identical image through the library with both
/// kernels, and through the binary (same PNG, same image hash).
#[test]
fn exported_presets_render_the_identical_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let kernels = [(KernelChoice::Scalar, "scalar"), (KernelChoice::Simd, "simd")];
    let cli_render = |spec: &str, kernel: &str| -> (Vec<u8>, serde_json::Value) {
        let mut args = vec!["render", spec, "--kernel", kernel, "-o", "cli.png", "--stats-json", "cli.json"];
        args.extend_from_slice(&SMALL);
        // Presets that name image files read them from RTOW_IMAGES (generated maps).
        let images = test_images().to_str().unwrap();
        success(&rtow_env(d, &args, &[("RTOW_IMAGES", images)]), &format!("render {spec} --kernel {kernel}"));
        let stats = serde_json::from_str(&std::fs::read_to_string(d.join("cli.json")).unwrap()).unwrap();
        (std::fs::read(d.join("cli.png")).unwrap(), stats)
    };
    for p in scene::presets() {
        let preset = (p.build)();
        let s = small_settings();
        let want: Vec<Image> = kernels.iter().map(|&(k, _)| render_lib(&self_contained(&preset), s, k).image).collect();
        let want_cli: Vec<_> = kernels.iter().map(|&(_, k)| cli_render(p.name, k)).collect();
        for ext in ["json", "toml"] {
            let file = format!("{}.{ext}", p.name);
            let r = rtow(d, &["export", p.name, "-o", &file]);
            success(&r, &file);
            assert!(r.stdout.is_empty() && r.stderr.is_empty(), "{file}: {:?} {:?}", r.stdout, r.stderr);
            let loaded = scene::load_scene(&d.join(&file)).unwrap_or_else(|e| panic!("{file}: {e}"));
            assert_eq!(loaded, preset, "{file}");
            for (i, &(kernel, name)) in kernels.iter().enumerate() {
                let got = render_lib(&self_contained(&loaded), small_settings(), kernel).image;
                assert!(got == want[i], "{file}: {name} kernel renders a different image");
                let (png, stats) = cli_render(&file, name);
                assert!(png == want_cli[i].0, "{file}: {name}: the binary writes a different PNG");
                assert_eq!(stats["image_hash"], want_cli[i].1["image_hash"], "{file} {name}");
            }
        }
    }
}

#[test]
fn explain_prints_the_plan_the_render_uses() {
    let dir = tempfile::tempdir().unwrap();
    let small = ["--width", "16", "--height", "9", "--spp", "2", "--depth", "3", "-q"];
    let r = rtow(dir.path(), &[&["render", "final", "--explain", "-o", "a.png"][..], &small].concat());
    success(&r, "explain final");
    assert!(r.stdout.contains("material passes: lambertian, metal, dielectric"), "{}", r.stdout);
    assert!(r.stdout.contains("thin-lens") && r.stdout.contains("jittered"), "{}", r.stdout);
    assert!(r.stdout.contains("bvh8, packets"), "{}", r.stdout);
    let r = rtow(
        dir.path(),
        &[&["render", "ch08-metal", "--explain", "--accel", "brute", "-o", "b.png"][..], &small].concat(),
    );
    success(&r, "explain ch08");
    assert!(r.stdout.contains("material passes: lambertian, metal;"), "{}", r.stdout);
    assert!(r.stdout.contains("pinhole") && r.stdout.contains("brute force"), "{}", r.stdout);
}

#[test]
fn book_sets_the_books_settings_and_explicit_flags_win() {
    let dir = tempfile::tempdir().unwrap();
    let r = rtow(
        dir.path(),
        &["render", "final", "--book", "--spp", "1", "--depth", "2", "-q", "-o", "b.png", "--stats-json", "s.json"],
    );
    success(&r, "--book");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("s.json")).unwrap()).unwrap();
    assert_eq!((v["width"].as_u64(), v["height"].as_u64()), (Some(1200), Some(675)), "--book size");
    assert_eq!((v["spp"].as_u64(), v["max_depth"].as_u64()), (Some(1), Some(2)), "explicit flags win");
}
