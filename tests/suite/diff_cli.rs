//! `rtow diff A B`, through the binary: exact figures on synthetic images,
//! thresholds and their exit status, region z-tests on tiny renders, and
//! damaged or mismatched inputs refused in one line.

use crate::common;

use common::{failure, rtow, Run};
use rtow::Image;
use std::path::Path;

/// `rtow diff args...` in `dir`.
fn diff(dir: &Path, args: &[&str]) -> Run {
    let mut all = vec!["diff"];
    all.extend_from_slice(args);
    rtow(dir, &all)
}

/// The JSON report at `dir/name`.
fn report(dir: &Path, name: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join(name)).unwrap()).unwrap()
}

/// A 12 x 8 image of smooth colours in [0, 1].
fn gradient() -> Image {
    let mut img = Image::new(12, 8);
    for (i, p) in img.data.iter_mut().enumerate() {
        let (x, y) = ((i % 12) as f32, (i / 12) as f32);
        *p = [x / 11.0, y / 7.0, 0.5];
    }
    img
}

#[test]
fn identical_images_differ_by_exactly_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let img = gradient();
    img.save(&d.join("a.pfm"), 2.0).unwrap();
    img.save(&d.join("b.exr"), 2.0).unwrap();
    img.save(&d.join("c.png"), 2.0).unwrap();
    for (a, b) in [("a.pfm", "b.exr"), ("c.png", "c.png"), ("a.pfm", "a.pfm")] {
        let r = diff(d, &[a, b, "--json", "r.json"]);
        r.ok();
        let j = report(d, "r.json");
        for k in ["mse", "rmse", "rel_mse"] {
            assert_eq!(j[k], 0.0, "{a} {b}: {k}");
        }
        assert_eq!((j["max_abs"]["value"].as_f64(), j["flip"]["mean"].as_f64()), (Some(0.0), Some(0.0)), "{a} {b}");
        assert_eq!(j["passed"], true);
        assert!(r.stdout.contains("MSE 0.000000e0"), "{}", r.stdout);
        assert!(r.stdout.contains("z-test: not run: A's noise is unknown"), "{}", r.stdout);
    }
    // A PNG against the linear image it was written from: FLIP compares the
    // 8-bit images a display shows, the same bytes; MSE only the rounding.
    let r = diff(d, &["c.png", "a.pfm", "--json", "r.json"]);
    r.ok();
    let j = report(d, "r.json");
    assert_eq!(j["flip"]["mean"], 0.0);
    let mse = j["mse"].as_f64().unwrap();
    assert!(mse > 0.0 && mse < 1e-4, "{mse}");
    assert_eq!((j["a"]["kind"].as_str(), j["b"]["kind"].as_str()), (Some("png"), Some("pfm")));
}

#[test]
fn a_known_difference_gives_its_known_figures_and_thresholds_trip_with_status_3() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let b = Image { width: 32, height: 32, data: vec![[0.5; 3]; 32 * 32] };
    let mut a = b.clone();
    // Four pixels' red off by 0.25 (exact in f32): MSE 4 * 0.0625 / 3072.
    for i in [33, 34, 65, 66] {
        a.data[i][0] = 0.75;
    }
    a.save(&d.join("a.pfm"), 1.0).unwrap();
    b.save(&d.join("b.pfm"), 1.0).unwrap();
    let r = diff(d, &["a.pfm", "b.pfm", "--json", "r.json", "--heatmap", "h.png"]);
    r.ok();
    let j = report(d, "r.json");
    assert_eq!(j["mse"].as_f64().unwrap(), 0.25 / 3072.0);
    let rel = 4.0 * 0.0625 / (0.25 + 0.01) / 3072.0;
    assert!((j["rel_mse"].as_f64().unwrap() - rel).abs() < 1e-15);
    assert_eq!(j["max_abs"], serde_json::json!({"value": 0.25, "x": 1, "y": 1, "channel": 0}));
    let flip = j["flip"]["mean"].as_f64().unwrap();
    assert!(flip > 0.0 && flip < 0.2, "{flip}");
    assert_eq!(j["schema"], "rtow-diff/1");
    assert!(j["provenance"]["rtow"].is_string());
    // The heatmap: the per-pixel FLIP, black beyond the filters' reach.
    let h = image::open(d.join("h.png")).unwrap().into_rgb8();
    assert_eq!(h.dimensions(), (32, 32));
    assert_eq!(h.get_pixel(31, 31).0, [0, 0, 4]);
    assert!(h.get_pixel(1, 1).0[0] > 50, "{:?}", h.get_pixel(1, 1));

    // Thresholds that hold: exit 0.
    let r = diff(d, &["a.pfm", "b.pfm", "--max-mse", "0.0001", "--max-flip", "0.5", "--max-rel-mse", "1"]);
    r.ok();
    assert!(r.stdout.contains("is within the limit 0.0001"), "{}", r.stdout);
    // Thresholds exceeded: exit 3, each named on stderr; the outputs are still written.
    std::fs::remove_file(d.join("r.json")).unwrap();
    let r = diff(
        d,
        &["a.pfm", "b.pfm", "--max-mse", "0.00005", "--max-flip", "0", "--max-rel-mse", "1", "--json", "r.json"],
    );
    assert_eq!(r.code, 3, "{}", r.stderr);
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(lines.len(), 2, "{}", r.stderr);
    assert!(lines[0].starts_with("exceeded: MSE is 0.0000813802083") && lines[0].ends_with("above --max-mse 0.00005"));
    assert!(lines[1].starts_with("exceeded: mean FLIP is") && lines[1].contains("above --max-flip 0"), "{}", lines[1]);
    let j = report(d, "r.json");
    assert_eq!(j["passed"], false);
    assert_eq!(j["checks"].as_array().unwrap().len(), 3);
    // -q: only the exceeded thresholds.
    let r = diff(d, &["a.pfm", "b.pfm", "--max-mse", "0.00005", "-q"]);
    assert_eq!((r.code, r.stdout.as_str(), r.stderr.lines().count()), (3, "", 1));
}

/// `rtow render scene --width 48 --height 32 --spp 16 --seed seed` plus `extra`, in `dir`.
fn render(dir: &Path, scene: &str, seed: &str, extra: &[&str]) {
    let mut args = vec!["render", scene, "--width", "48", "--height", "32", "--spp", "16", "--seed", seed, "-q"];
    args.extend_from_slice(extra);
    rtow(dir, &args).ok();
}

/// The z-test's count of |z| > 3 and its region-channels.
fn z_fails(j: &serde_json::Value) -> (u64, u64) {
    let z = &j["z_test"];
    (z["over"].as_u64().unwrap(), z["count"].as_u64().unwrap())
}

#[test]
fn independent_renders_of_one_scene_pass_the_z_tests_and_different_scenes_fail_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Films with moments: a threshold no pixel reaches keeps every sample
    // (adaptive sampling acts only with its first decision below --spp).
    for (scene, seed, name) in [("ch07-diffuse", "1", "a"), ("ch07-diffuse", "2", "b"), ("ch08-metal", "1", "m")] {
        render(d, scene, seed, &["--adaptive", "1e-6", "--adaptive-min", "8", "-o", &format!("{name}.rtfilm")]);
    }
    let r = diff(d, &["a.rtfilm", "b.rtfilm", "--json", "r.json", "--max-z-fails", "3"]);
    r.ok();
    let j = report(d, "r.json");
    let (over, count) = z_fails(&j);
    assert_eq!(count, 108);
    assert!(over <= 3, "{over} of {count} |z| > 3 between two seeds");
    assert_eq!(j["a"]["noise"], "moments");
    assert!(r.stdout.contains("z-test: 6x6 regions, 108 region-channels"), "{}", r.stdout);
    let r = diff(d, &["m.rtfilm", "b.rtfilm", "--json", "r.json", "--max-z-fails", "3", "--regions", "4"]);
    assert_eq!(r.code, 3, "{}", r.stderr);
    assert!(r.stderr.contains("above --max-z-fails 3"), "{}", r.stderr);
    let (over, count) = z_fails(&report(d, "r.json"));
    assert_eq!(count, 48);
    assert!(over > 20, "only {over} of {count} |z| > 3 between two scenes");

    // Two renders a side (linear images of other seeds).
    for (scene, seed, name) in [("ch07-diffuse", "3", "a1"), ("ch07-diffuse", "4", "a2"), ("ch07-diffuse", "5", "b1")]
        .into_iter()
        .chain([("ch07-diffuse", "6", "b2"), ("ch08-metal", "3", "m1"), ("ch08-metal", "4", "m2")])
    {
        render(d, scene, seed, &["-o", &format!("{name}.png"), "--float", &format!("{name}.pfm")]);
    }
    let r = diff(d, &["a1.pfm", "b1.pfm", "--a2", "a2.pfm", "--b2", "b2.pfm", "--json", "r.json"]);
    r.ok();
    let j = report(d, "r.json");
    let (over, _) = z_fails(&j);
    assert!(over <= 3, "{over} |z| > 3 between two pairs of seeds");
    assert_eq!(j["b"]["noise"], "two_renders");
    let rms = j["noise_check_a"][0].as_f64().unwrap();
    assert!(rms > 0.5 && rms < 1.6, "noise check {rms}");
    // A film's moments on one side, two renders on the other; against another scene.
    let r = diff(d, &["m1.pfm", "b.rtfilm", "--a2", "m2.pfm", "--json", "r.json"]);
    r.ok();
    let (over, _) = z_fails(&report(d, "r.json"));
    assert!(over > 30, "only {over} |z| > 3 between two scenes");
    // No noise on a side: the z-tests cannot run, and a threshold on them is bad input.
    let r = diff(d, &["a1.pfm", "b.rtfilm", "--max-z-fails", "0"]);
    let m = failure(&r, 2, "--max-z-fails without noise");
    assert!(m.contains("--max-z-fails: needs the z-tests, but A's noise is unknown"), "{m}");
    let r = diff(d, &["a1.pfm", "b1.pfm", "--a2", "a1.pfm"]);
    assert!(failure(&r, 2, "a second render that is the first").contains("needs another seed"));
}

#[test]
fn damaged_mismatched_and_unreadable_inputs_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let img = gradient();
    img.save(&d.join("g.pfm"), 1.0).unwrap();
    img.save(&d.join("g.png"), 2.0).unwrap();
    img.save(&d.join("g.exr"), 1.0).unwrap();
    Image::new(10, 8).save(&d.join("small.pfm"), 1.0).unwrap();
    render(d, "ch07-diffuse", "1", &["-o", "f.rtfilm"]);
    render(d, "ch07-diffuse", "1", &["--shard", "1/2", "--split", "rows", "-o", "r.rtfilm"]);
    let cut = |name: &str, to: &str, keep: f64| {
        let b = std::fs::read(d.join(name)).unwrap();
        std::fs::write(d.join(to), &b[..(b.len() as f64 * keep) as usize]).unwrap();
    };
    cut("g.png", "cut.png", 0.7);
    cut("g.png", "head.png", 0.1);
    cut("g.exr", "cut.exr", 0.6);
    cut("g.pfm", "cut.pfm", 0.9);
    cut("f.rtfilm", "cut.rtfilm", 0.5);
    let mut flipped = std::fs::read(d.join("g.png")).unwrap();
    let n = flipped.len();
    flipped[n / 2] ^= 0x20;
    std::fs::write(d.join("flipped.png"), flipped).unwrap();
    std::fs::write(d.join("text.png"), b"not an image at all").unwrap();
    std::fs::write(d.join("empty.exr"), b"").unwrap();
    std::fs::write(d.join("nan.pfm"), [b"PF\n1 1\n-1.0\n".as_slice(), &[0, 0, 0xc0, 0x7f], &[0; 8]].concat()).unwrap();
    std::fs::create_dir(d.join("folder.png")).unwrap();
    let cases: &[(&str, &[&str])] = &[
        ("cut.png", &["truncated or corrupt PNG"]),
        ("head.png", &["truncated or corrupt PNG"]),
        ("flipped.png", &["truncated or corrupt PNG"]),
        ("cut.exr", &["cut.exr"]),
        ("cut.pfm", &["PFM size does not match its header"]),
        ("cut.rtfilm", &["truncated"]),
        ("r.rtfilm", &["shard 1/2 by rows", "rows 0..16 only", "merge the shards first"]),
        ("text.png", &["is not a PNG, EXR, PFM (colour) or rtow partial film"]),
        ("empty.exr", &["is not a PNG, EXR, PFM"]),
        ("nan.pfm", &["pixel (0, 0) is not finite"]),
        ("folder.png", &["is a directory"]),
        ("missing.exr", &["cannot read missing.exr"]),
        ("small.pfm", &["sizes differ: g.pfm is 12x8, small.pfm is 10x8"]),
    ];
    for (bad, says) in cases {
        let m = failure(&diff(d, &["g.pfm", bad]), 2, bad);
        assert!(m.contains(bad), "{bad}: the file is not named: {m}");
        for s in *says {
            assert!(m.contains(s), "{bad}: {m}");
        }
    }
    // The same file is read whole both ways round.
    let m = failure(&diff(d, &["cut.rtfilm", "g.pfm"]), 2, "a cut film as A");
    assert!(m.starts_with("error: cut.rtfilm: truncated"), "{m}");
    // Flags and outputs (an input is never overwritten).
    let png = std::fs::read(d.join("g.png")).unwrap();
    for (args, says) in [
        (&["g.pfm", "g.png", "--gamma", "0"][..], "--gamma: must be a finite number > 0"),
        (&["g.pfm", "g.png", "--regions", "0"], "--regions: must be from 1 to 256"),
        (&["g.pfm", "g.png", "--max-flip", "-1"], "--max-flip: must be a finite number >= 0"),
        (&["g.pfm", "g.png", "--heatmap", "h.jpg"], "--heatmap: h.jpg: unsupported file type; use .png"),
        (&["g.pfm", "g.png", "--json", "g.png"], "it would be overwritten"),
    ] {
        let m = failure(&diff(d, args), 2, says);
        assert!(m.contains(says), "{args:?}: {m}");
    }
    assert_eq!(std::fs::read(d.join("g.png")).unwrap(), png);
    let m = failure(&diff(d, &["g.pfm", "g.png", "--json", "no/such/folder/r.json"]), 1, "an unwritable output");
    assert!(m.contains("cannot write no/such/folder/r.json"), "{m}");
}
