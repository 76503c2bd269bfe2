//! `--sampler` through the binary: render, scene files, bench and converge.
#![cfg(feature = "cli")]

use crate::common;

use common::{rtow, Run};
use rtow::{render, Job, KernelChoice, Overrides, RenderOptions, Sampler};
use std::path::Path;

fn ok(o: &Run) {
    o.ok();
}

fn stats(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap()
}

const SMALL: [&str; 9] = ["--width", "24", "--height", "14", "--spp", "4", "--seed", "3", "-q"];

#[test]
fn render_takes_the_sampler_from_the_flag_or_the_scene() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let args =
        |extra: &[&'static str]| [&["render", "ch07-diffuse", "--stats-json", "s.json"][..], &SMALL, extra].concat();
    ok(&rtow(dir, &args(&["--sampler", "independent"])));
    let v = stats(dir);
    assert_eq!(v["sampler"], "independent");
    let sc = rtow::scene::preset("ch07-diffuse").unwrap();
    let o = Overrides {
        width: Some(24),
        height: Some(14),
        spp: Some(4),
        seed: Some(3),
        sampler: Some(Sampler::Independent),
        ..Default::default()
    };
    let job = Job::new(&sc, &o, &RenderOptions { kernel: KernelChoice::Simd, ..Default::default() }).unwrap();
    let lib = render(&job, None).unwrap();
    assert_eq!(v["image_hash"], lib.stats.image_hash.as_str());
    ok(&rtow(dir, &args(&[])));
    assert_eq!(stats(dir)["sampler"], "sobol", "the default");

    // A scene file's render table names it; the flag wins.
    ok(&rtow(dir, &["export", "ch07-diffuse", "-o", "scene.json"]));
    let mut j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("scene.json")).unwrap()).unwrap();
    j["render"]["sampler"] = "independent".into();
    std::fs::write(dir.join("scene.json"), j.to_string()).unwrap();
    let file_args =
        |extra: &[&'static str]| [&["render", "scene.json", "--stats-json", "s.json"][..], &SMALL, extra].concat();
    ok(&rtow(dir, &file_args(&[])));
    assert_eq!(stats(dir)["sampler"], "independent");
    ok(&rtow(dir, &file_args(&["--sampler", "sobol"])));
    assert_eq!(stats(dir)["sampler"], "sobol");
}

#[test]
fn an_unknown_sampler_is_bad_input() {
    let d = tempfile::tempdir().unwrap();
    let o = rtow(d.path(), &[&["render", "ch07-diffuse", "--sampler", "halton"][..], &SMALL].concat());
    assert_eq!(o.code, 2, "{}", o.stderr);
    let err = o.stderr.clone();
    assert!(err.contains("independent") && err.contains("sobol"), "{err}");
    assert!(!d.path().join("ch07-diffuse.png").exists());
}

#[test]
fn bench_and_converge_measure_sobol() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let o = rtow(
        dir,
        &[
            "bench",
            "ch07-diffuse",
            "--width",
            "16",
            "--height",
            "9",
            "--spp",
            "2",
            "--repeat",
            "1",
            "--sampler",
            "sobol",
            "--json",
            "b.json",
        ],
    );
    ok(&o);
    let b: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("b.json")).unwrap()).unwrap();
    for k in b["kernels"].as_array().unwrap() {
        assert_eq!(k["sampler"], "sobol");
    }
    let o = rtow(
        dir,
        &[
            "converge",
            "ch07-diffuse",
            "--width",
            "16",
            "--height",
            "9",
            "--variants",
            "plain,sobol,sobol+rr",
            "--sampler",
            "independent",
            "--spp-list",
            "4,8",
            "--reference-spp",
            "64",
            "--out",
            "c",
        ],
    );
    ok(&o);
    let csv = std::fs::read_to_string(dir.join("c/ch07-diffuse.csv")).unwrap();
    assert!(csv.contains(",sobol,4,") && csv.contains(",sobol+rr,8,"), "{csv}");
    assert!(csv.contains(",plain,4,"), "--sampler independent: plain is independent sampling: {csv}");
    // Without --sampler, the variants that name none take render's default, Sobol.
    let args = ["converge", "ch07-diffuse", "--width", "16", "--height", "9", "--variants", "plain,rr"];
    let o = rtow(dir, &[&args[..], &["--spp-list", "4", "--reference-spp", "16", "--out", "d"]].concat());
    ok(&o);
    let csv = std::fs::read_to_string(dir.join("d/ch07-diffuse.csv")).unwrap();
    assert!(csv.contains(",sobol,4,") && csv.contains(",sobol+rr,4,") && !csv.contains(",plain,"), "{csv}");
    let o = rtow(dir, &[&args[..6], &["--variants", "plain,sobol", "--spp-list", "4", "--out", "e"]].concat());
    assert_eq!(o.code, 2, "{}", o.stderr);
    assert!(o.stderr.contains("listed twice") && o.stderr.contains("--sampler independent"), "{}", o.stderr);
}
