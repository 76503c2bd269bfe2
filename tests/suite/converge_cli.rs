//! `rtow converge` and the estimator flags of `rtow render`, through the binary.

use crate::common;

use common::{rtow, Run};
use std::path::Path;

/// `rtow args...` in the package folder (the tests name their output folders).
fn run(args: &[&str]) -> Run {
    rtow(Path::new("."), args)
}

const SMALL: &[&str] = &["--width", "16", "--height", "9", "--threads", "1"];

#[test]
fn converge_writes_table_plot_and_reference_and_reuses_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out_s = out.to_str().unwrap();
    let mut args = vec![
        "converge",
        "ch07-diffuse",
        "--kernels",
        "scalar,simd",
        "--variants",
        "plain,rr,adaptive:0.3",
        "--adaptive-min",
        "2",
        "--spp-list",
        "1,4,16",
        "--reference-spp",
        "64",
        "--sampler",
        "independent",
        "--out",
        out_s,
    ];
    args.extend_from_slice(SMALL);
    let o = run(&args);
    assert!(o.code == 0, "{}", o.stderr.clone());
    let stdout = o.stdout.clone();
    assert!(stdout.contains("reference: 64 spp with seed"), "{stdout}");
    assert!(stdout.contains("simd/rr vs scalar/plain: equal error"), "{stdout}");
    assert!(stdout.contains("simd/rr vs simd/plain"), "{stdout}");

    let csv = std::fs::read_to_string(out.join("ch07-diffuse.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2 * 3 * 3, "{csv}");
    let col = |name: &str| csv.lines().next().unwrap().split(',').position(|c| c == name).unwrap();
    let (kernel, variant, spp, rmse, samples, hash) =
        (col("kernel"), col("variant"), col("spp"), col("rmse"), col("samples"), col("image_hash"));
    for r in &rows {
        // The kernels render the same image for the same variant and spp.
        let twin =
            rows.iter().find(|q| q[kernel] != r[kernel] && q[variant] == r[variant] && q[spp] == r[spp]).unwrap();
        assert_eq!(twin[hash], r[hash]);
        let e: f64 = r[rmse].parse().unwrap();
        assert!(e > 0.0 && e.is_finite());
    }
    // More samples, less error (1 vs 16 spp is far beyond the noise of the error itself).
    let err = |v: &str, s: &str| -> f64 {
        rows.iter().find(|r| r[kernel] == "simd" && r[variant] == v && r[spp] == s).unwrap()[rmse].parse().unwrap()
    };
    assert!(err("plain", "16") < 0.5 * err("plain", "1"));
    // The adaptive variant stopped some pixels before 16 samples.
    let ad16: u64 =
        rows.iter().find(|r| r[variant] == "adaptive:0.3" && r[spp] == "16").unwrap()[samples].parse().unwrap();
    assert!(ad16 < 16 * 9 * 16, "{ad16}");

    let md = std::fs::read_to_string(out.join("ch07-diffuse.md")).unwrap();
    assert!(md.contains("| kernel | variant | spp |") && md.contains("equal time"), "{md}");
    let svg = std::fs::read_to_string(out.join("ch07-diffuse.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("scalar/plain") && svg.contains("polyline"));
    let reference = out.join("ch07-diffuse-reference.exr");
    assert!(reference.exists());
    // The run's description and provenance beside the tables.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("ch07-diffuse.json")).unwrap()).unwrap();
    assert_eq!(json["schema"], "rtow-converge/1");
    assert_eq!(json["files"][0], "ch07-diffuse.csv");
    assert_eq!(json["provenance"]["isa"], rtow::isa());
    assert_eq!(json["provenance"]["command_line"][1], "converge");
    // The reference's own noise, from its two halves: at 64 spp against errors
    // at 16 spp it is a quarter or more of the smallest error, and said so.
    let noise = &json["reference_noise"];
    let (mse, smallest) = (noise["mse"].as_f64().unwrap(), noise["smallest_mse"].as_f64().unwrap());
    let rmse16 = err("plain", "16");
    assert!(mse > 0.0 && smallest > 0.0 && smallest <= rmse16 * rmse16 * (1.0 + 1e-9), "{noise} {rmse16}");
    assert!(mse > 0.1 * smallest, "{noise}");
    assert!(o.stderr.contains("warning: the reference's own noise"), "{}", o.stderr);
    assert!(md.contains("Reference noise:") && md.contains("Too noisy"), "{md}");

    // Again from the saved reference: the errors are the same as before.
    let again = dir.path().join("again");
    let mut args = vec![
        "converge",
        "ch07-diffuse",
        "--variants",
        "plain",
        "--spp-list",
        "1,4,16",
        "--reference",
        reference.to_str().unwrap(),
        "--repeat",
        "2",
        "--sampler",
        "independent",
        "--out",
        again.to_str().unwrap(),
    ];
    args.extend_from_slice(SMALL);
    let o = run(&args);
    assert!(o.code == 0, "{}", o.stderr.clone());
    assert!(!o.stdout.clone().contains("reference: 64 spp"));
    let csv2 = std::fs::read_to_string(again.join("ch07-diffuse.csv")).unwrap();
    for line in csv2.lines().skip(1) {
        let r: Vec<&str> = line.split(',').collect();
        let before = rows.iter().find(|q| q[kernel] == "simd" && q[variant] == "plain" && q[spp] == r[spp]).unwrap();
        assert_eq!(before[rmse], r[rmse]);
    }
    assert!(!again.join("ch07-diffuse-reference.exr").exists());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(again.join("ch07-diffuse.json")).unwrap()).unwrap();
    assert!(json["reference_noise"].is_null(), "a reference from a file has no known noise");
}

fn fails_naming(args: &[&str], flag: &str, code: i32) {
    let o = run(args);
    let err = o.stderr.clone();
    assert_eq!(o.code, code, "{args:?}: {err}");
    assert!(err.contains(flag), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn bad_flags_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let o = out.to_str().unwrap();
    let conv = |extra: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = ["converge", "ch07-diffuse", "--out", o, "--width", "8", "--height", "4"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let cases: Vec<(Vec<String>, &str)> = vec![
        (conv(&["--spp-list", "4,2"]), "--spp-list"),
        (conv(&["--spp-list", "0,2"]), "--spp-list"),
        (conv(&["--variants", "fast"]), "--variants"),
        (conv(&["--variants", "rr:0"]), "--variants"),
        (conv(&["--variants", "adaptive:-1"]), "--variants"),
        (conv(&["--variants", "plain,plain"]), "--variants"),
        (conv(&["--kernels", "gpu"]), "--kernels"),
        (conv(&["--reference-spp", "0"]), "--reference-spp"),
        (conv(&["--repeat", "0"]), "--repeat"),
        (conv(&["--variants", "adaptive", "--adaptive-min", "1"]), "--adaptive-min"),
        (conv(&["--reference", "missing.exr"]), "--reference"),
        (conv(&["--reference", "a.exr", "--reference-spp", "4"]), "--reference"),
        (conv(&["--width", "0"]), "width"),
    ];
    for (args, flag) in &cases {
        let a: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
        fails_naming(&a, flag, 2);
    }
    assert!(!out.exists(), "a failed run wrote {}", out.display());

    // A reference of the wrong size.
    let r = dir.path().join("r.pfm");
    rtow::Image::new(3, 2).save(&r, 1.0).unwrap();
    fails_naming(&to_refs(&conv(&["--reference", r.to_str().unwrap()])), "--reference", 2);

    // A float image whose header claims more pixels than fit anywhere.
    let huge = dir.path().join("huge.pfm");
    std::fs::write(&huge, b"PF\n100000 100000\n-1.0\n\0\0\0\0").unwrap();
    fails_naming(&to_refs(&conv(&["--reference", huge.to_str().unwrap()])), "--reference", 2);

    // --out that is a file.
    let f = dir.path().join("file");
    std::fs::write(&f, b"x").unwrap();
    let a = [
        "converge",
        "ch07-diffuse",
        "--out",
        f.to_str().unwrap(),
        "--width",
        "8",
        "--height",
        "4",
        "--spp-list",
        "1",
        "--reference-spp",
        "2",
    ];
    fails_naming(&a, "--out", 1);

    let png = dir.path().join("x.png");
    let p = png.to_str().unwrap();
    for (extra, flag) in [
        (vec!["--adaptive", "nan"], "--adaptive"),
        (vec!["--adaptive=-0.5"], "--adaptive"),
        (vec!["--adaptive", "0"], "--adaptive"),
        (vec!["--adaptive", "0.1", "--adaptive-min", "1"], "--adaptive-min"),
        (vec!["--adaptive", "lots"], "--adaptive"),
        (vec!["--rr", "--rr-after", "0"], "--rr-after"),
    ] {
        let mut a = vec!["render", "ch07-diffuse", "-o", p, "--width", "8", "--height", "4", "-q"];
        a.extend(extra);
        fails_naming(&a, flag, 2);
    }
    assert!(!Path::new(p).exists());
}

fn to_refs(v: &[String]) -> Vec<&str> {
    v.iter().map(|s| s.as_str()).collect()
}

#[test]
fn render_flags_report_the_estimator() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("s.json");
    let png = dir.path().join("x.png");
    let o = run(&[
        "render",
        "ch07-diffuse",
        "-o",
        png.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "9",
        "--spp",
        "64",
        "--rr",
        "--rr-after",
        "4",
        "--adaptive",
        "0.2",
        "--adaptive-min",
        "16",
        "-q",
        "--stats-json",
        json.to_str().unwrap(),
    ]);
    assert!(o.code == 0, "{}", o.stderr.clone());
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["russian_roulette"], 4);
    assert_eq!(v["adaptive"]["min_spp"], 16);
    let samples = v["samples"].as_u64().unwrap();
    assert!((16 * 9 * 16..16 * 9 * 64).contains(&samples), "{samples}");
}

#[test]
fn a_scene_without_noise_still_gets_its_outputs() {
    // Chapter 1's gradient traces no rays: every error is exactly 0.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g");
    let o = run(&[
        "converge",
        "ch01-gradient",
        "--width",
        "8",
        "--height",
        "4",
        "--spp-list",
        "1,2",
        "--reference-spp",
        "4",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.code == 0, "{}", o.stderr.clone());
    let svg = std::fs::read_to_string(out.join("ch01-gradient.svg")).unwrap();
    assert!(svg.contains("no measurement has a positive error"));
    assert!(out.join("ch01-gradient.csv").exists());
}
