//! `rtow bench --save / --baseline`: the regression test users run on a speedup.
//! Exit status 0 when throughput held and the image is the same; 1 when the
//! image changed or throughput fell by more than the tolerance.

use crate::common;

use common::{rtow, rtow_env, Run};
use std::path::Path;

fn bench(dir: &Path, extra: &[&str]) -> Run {
    bench_spp(dir, "2", extra)
}

fn bench_spp(dir: &Path, spp: &str, extra: &[&str]) -> Run {
    let mut args = vec!["bench", "ch05-ground", "--kernels", "scalar,simd"];
    args.extend(["--width", "24", "--height", "14", "--spp", spp, "--threads", "1"]);
    if !extra.contains(&"--repeat") {
        args.extend(["--repeat", "1"]);
    }
    args.extend_from_slice(extra);
    rtow(dir, &args)
}

/// A kernel entry of a baseline made `factor` times faster, consistently
/// (rate, median seconds and every run).
fn faster(k: &mut serde_json::Value, factor: f64) {
    let m = k["mrays_per_s"].as_f64().unwrap();
    k["mrays_per_s"] = (m * factor).into();
    let rays = k["rays"].as_f64().unwrap();
    k["seconds"] = (rays / (m * factor) / 1e6).into();
    let runs: Vec<f64> = k["runs_seconds"].as_array().unwrap().iter().map(|t| t.as_f64().unwrap() / factor).collect();
    let mut sorted = runs.clone();
    sorted.sort_by(f64::total_cmp);
    k["seconds"] = sorted[sorted.len() / 2].into();
    k["mrays_per_s"] = (rays / sorted[sorted.len() / 2] / 1e6).into();
    k["runs_seconds"] = runs.into();
}

fn edit(path: &Path, f: impl Fn(&mut serde_json::Value)) {
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    f(&mut v);
    std::fs::write(path, serde_json::to_string(&v).unwrap()).unwrap();
}

#[test]
fn baseline_catches_a_changed_image_and_a_slowdown() {
    let dir = tempfile::tempdir().unwrap();
    let saved = bench(dir.path(), &["--save", "base.json"]);
    assert!(saved.code == 0, "{}", saved.stderr);
    let base = dir.path().join("base.json");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&base).unwrap()).unwrap();
    let kernels = v["kernels"].as_array().unwrap();
    assert_eq!(kernels.len(), 2);
    assert_eq!(kernels[0]["image_hash"], kernels[1]["image_hash"], "scalar and SIMD images differ");
    // The speedup is the ratio of the two kernels' throughputs in this report.
    let (m0, m1) = (kernels[0]["mrays_per_s"].as_f64().unwrap(), kernels[1]["mrays_per_s"].as_f64().unwrap());
    assert!((kernels[1]["speedup"].as_f64().unwrap() - m1 / m0).abs() < 1e-9 * (m1 / m0));
    // Exact work counters are saved with each kernel.
    assert!(kernels[1]["work"]["sphere_tests"].as_u64().unwrap() > 0);

    // Same code: passes, and says the image is identical (tolerance 100%: timings of
    // sub-millisecond renders are noise; the slowdown verdict is tested below).
    let ok = bench(dir.path(), &["--baseline", "base.json", "--tolerance", "100"]);
    let out = ok.stdout.clone();
    assert_eq!(ok.code, 0, "{out}{}", ok.stderr);
    assert!(out.contains("identical") && !out.contains("REGRESSION"), "{out}");

    // A baseline with another image: exit 1, whatever the speed.
    let changed = dir.path().join("changed.json");
    std::fs::copy(&base, &changed).unwrap();
    edit(&changed, |v| v["kernels"][1]["image_hash"] = "0123456789abcdef".into());
    let r = bench(dir.path(), &["--baseline", "changed.json", "--tolerance", "100"]);
    assert_eq!(r.code, 1);
    assert!(r.stdout.contains("CHANGED"));

    // A baseline 1000x faster: this run is a slowdown beyond 5%: exit 1.
    let fast = dir.path().join("fast.json");
    std::fs::copy(&base, &fast).unwrap();
    edit(&fast, |v| faster(&mut v["kernels"][1], 1000.0));
    let r = bench(dir.path(), &["--baseline", "fast.json"]);
    assert_eq!(r.code, 1);
    assert!(r.stdout.contains("REGRESSION"));

    // A baseline whose algorithm did less work: same image, more work now:
    // exit 1 and said so, even with timings within any tolerance.
    let less = dir.path().join("less.json");
    std::fs::copy(&base, &less).unwrap();
    edit(&less, |v| {
        // Half the sphere tests, and so at most half the square roots.
        for k in ["sphere_tests", "roots"] {
            let n = v["kernels"][1]["work"][k].as_u64().unwrap();
            v["kernels"][1]["work"][k] = (n / 2).into();
        }
    });
    let r = bench(dir.path(), &["--baseline", "less.json", "--tolerance", "100"]);
    let out = r.stdout.clone();
    assert_eq!(r.code, 1, "{out}");
    assert!(out.contains("REGRESSION") && out.contains("work changed") && out.contains("image identical"), "{out}");

    // A baseline 1000x faster with the same work: a timing change only, labelled so.
    let r = bench(dir.path(), &["--baseline", "fast.json"]);
    assert!(r.stdout.contains("timing only"), "{}", r.stdout);

    // A baseline of other settings is an input error, not a verdict.
    let r = bench_spp(dir.path(), "3", &["--baseline", "base.json"]);
    let err = r.stderr;
    assert_eq!(r.code, 2, "{err}");
    assert!(err.contains("baseline settings"), "{err}");
}

#[test]
fn gate_work_passes_a_slowdown_and_a_baseline_of_other_threads_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    assert_eq!(bench(d, &["--repeat", "2", "--save", "base.json"]).code, 0);
    let fast = d.join("fast.json");
    std::fs::copy(d.join("base.json"), &fast).unwrap();
    edit(&fast, |v| faster(&mut v["kernels"][1], 1000.0));
    // Gated on time: a regression; gated on the work: the same image and work pass.
    let r = bench(d, &["--repeat", "2", "--baseline", "fast.json"]);
    assert_eq!(r.code, 1, "{}", r.stdout);
    assert!(r.stdout.contains("CI"), "a noise estimate from 2 runs a side: {}", r.stdout);
    let r = bench(d, &["--repeat", "2", "--baseline", "fast.json", "--gate", "work"]);
    assert_eq!(r.code, 0, "{}{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("timing only, slower") && r.stdout.contains("not gated"), "{}", r.stdout);
    // The same settings on another thread count: refused like other settings (exit 2).
    let mut args = vec!["bench", "ch05-ground", "--kernels", "scalar,simd", "--repeat", "1"];
    args.extend(["--width", "24", "--height", "14", "--spp", "2", "--threads", "2", "--baseline", "base.json"]);
    let r = rtow(d, &args);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("1 thread(s), this run on 2"), "{}", r.stderr);
}

#[test]
fn baselines_with_impossible_figures_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    assert_eq!(bench(d, &["--repeat", "2", "--save", "base.json"]).code, 0);
    type Edit = fn(&mut serde_json::Value);
    let cases: [(&str, Edit, &str); 8] = [
        ("zero rate", |k| k["mrays_per_s"] = 0.0.into(), "Mrays/s"),
        (
            "rate and time disagree",
            |k| k["mrays_per_s"] = (k["mrays_per_s"].as_f64().unwrap() * 2.0).into(),
            "disagree",
        ),
        ("negative time", |k| k["seconds"] = (-1.0).into(), "not a measurement"),
        ("no rays", |k| k["rays"] = 0.into(), "not a measurement"),
        ("a run of 0 s", |k| k["runs_seconds"][0] = 0.0.into(), "runs_seconds"),
        ("no threads", |k| k["threads"] = 0.into(), "thread"),
        ("bad hash", |k| k["image_hash"] = "xyz".into(), "image hash"),
        (
            "more roots than sphere tests",
            |k| k["work"]["roots"] = (k["work"]["sphere_tests"].as_u64().unwrap() + 1).into(),
            "work counters",
        ),
    ];
    for (what, f, needle) in cases {
        let path = d.join("bad.json");
        std::fs::copy(d.join("base.json"), &path).unwrap();
        edit(&path, |v| f(&mut v["kernels"][1]));
        let r = bench(d, &["--baseline", "bad.json"]);
        assert_eq!(r.code, 2, "{what}: {}", r.stderr);
        let line = r.stderr.trim();
        assert!(line.lines().count() == 1 && line.contains("bad.json") && line.contains(needle), "{what}: {line}");
    }
}

/// The verdicts on a real report whose run times are set to a known spread
/// (a render this small takes well under a millisecond, so on a loaded
/// machine its own times can differ tenfold, and no verdict on them is
/// certain): the same runs as a baseline are within noise (never a
/// regression); a baseline ten times faster is a regression gated on time and
/// passes gated on the work.
#[test]
fn the_verdict_knows_the_noise_of_the_runs() {
    use rtow::instruments::bench::{self, Baseline, BaselineVerdict, BenchConfig, Gate};
    let scene = rtow::scene::preset("ch07-diffuse").unwrap();
    let o = rtow::Overrides { width: Some(32), height: Some(18), spp: Some(2), ..Default::default() };
    let opts = rtow::RenderOptions { threads: Some(1), ..Default::default() };
    let job = rtow::Job::new(&scene, &o, &opts).unwrap();
    let cfg = BenchConfig::new(&job, &[rtow::KernelChoice::Simd8], 5, 0.0, Gate::Time).unwrap();
    let mut report = bench::run(&cfg, "ch07-diffuse", |_, _, _| {}).unwrap();
    assert_eq!(report.kernels[0].runs_seconds.len(), 5);
    // Runs spread by 30% around the measured median: noise, as on a busy machine.
    let median = report.kernels[0].stats.seconds;
    report.kernels[0].runs_seconds = [1.0, 1.12, 0.95, 1.3, 1.04].iter().map(|f| f * median).collect();
    let saved = |scale: f64| -> Baseline {
        let mut v: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
        faster(&mut v["kernels"][0], scale);
        Baseline::from_bytes(v.to_string().as_bytes(), Path::new("b.json")).unwrap()
    };
    let runs = &report.kernels[0].runs_seconds;
    let c = &bench::compare(&report, &saved(1.0), 0.0, Gate::Time)[0];
    let ci = c.change_ci.expect("5 runs a side give an interval");
    assert!((ci.level - (1.0 - 8.0 / 252.0)).abs() < 1e-12, "{ci:?}");
    assert!(ci.lo <= c.change_percent && c.change_percent <= ci.hi && !c.regressed, "{c:?}");
    assert!(runs.iter().any(|&t| t != runs[0]));
    assert_eq!(c.verdict, BaselineVerdict::WithinNoise, "{c:?}");
    let c = &bench::compare(&report, &saved(10.0), 5.0, Gate::Time)[0];
    assert!(c.regressed && c.verdict == BaselineVerdict::TimingOnly && c.change_ci.unwrap().hi < -5.0, "{c:?}");
    assert!(!bench::compare(&report, &saved(10.0), 5.0, Gate::Work)[0].regressed);
    let c = &bench::compare(&report, &saved(0.1), 5.0, Gate::Time)[0];
    assert!(!c.regressed && c.verdict == BaselineVerdict::TimingOnly && c.change_percent > 0.0, "{c:?}");
}

/// `--instructions`: callgrind counts each kernel's render loop; the same
/// build counts the same instructions; baselines compare exactly; without
/// valgrind the command says so before any work.
#[test]
fn instructions_are_counted_and_compared_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let args = |extra: &[&'static str]| -> Vec<&'static str> {
        let mut v = vec!["bench", "ch07-diffuse", "--kernels", "scalar,simd8", "--instructions", "--threads", "1"];
        v.extend(["--width", "16", "--height", "9", "--spp", "2", "--depth", "8"]);
        v.extend_from_slice(extra);
        v
    };
    let r = rtow_env(d, &args(&["--save", "i.json"]), &[("PATH", "/nonexistent")]);
    let line = common::failure(&r, 1, "no valgrind");
    assert!(line.contains("valgrind") && line.contains("install"), "{line}");
    assert!(!d.join("i.json").exists());
    if std::process::Command::new("valgrind").arg("--version").output().is_err() {
        eprintln!("valgrind is not installed: only the refusal was checked");
        return;
    }
    let line = common::failure(&rtow(d, &args(&["--save", "i.json", "--reason", "a\nb"])), 2, "two-line reason");
    assert!(line.contains("--reason") && line.contains("one line"), "{line}");
    let line = common::failure(&rtow(d, &args(&["--baseline", "i.json", "--max-rise", "-1"])), 2, "negative rise");
    assert!(line.contains("--max-rise"), "{line}");
    let r = rtow(d, &args(&["--save", "i.json", "--reason", "the first count"]));
    if r.code == 1 && r.stderr.contains("valgrind does not know") {
        eprintln!("valgrind cannot run this build: {}", r.stderr);
        return;
    }
    assert_eq!(r.code, 0, "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("i.json")).unwrap()).unwrap();
    assert_eq!(v["schema"], "rtow-instructions/1");
    assert_eq!(v["reason"], "the first count");
    let k = &v["kernels"];
    assert_eq!(k[0]["image_hash"], k[1]["image_hash"], "scalar and SIMD images differ");
    for e in k.as_array().unwrap() {
        let (n, rays) = (e["instructions"].as_u64().unwrap(), e["rays"].as_u64().unwrap());
        assert!(n > 10 * rays && e["process_instructions"].as_u64().unwrap() > n, "{e}");
        assert!((e["per_ray"].as_f64().unwrap() - n as f64 / rays as f64).abs() < 1e-9, "{e}");
    }
    // Counted again: exactly the same.
    let r = rtow(d, &args(&["--baseline", "i.json"]));
    assert_eq!(r.code, 0, "{}{}", r.stdout, r.stderr);
    assert_eq!(r.stdout.matches("ok (identical)").count(), 2, "{}", r.stdout);
    // A baseline one instruction leaner: a regression.
    edit(&d.join("i.json"), |v| {
        let n = v["kernels"][1]["instructions"].as_u64().unwrap();
        v["kernels"][1]["instructions"] = (n - 1).into();
    });
    let r = rtow(d, &args(&["--baseline", "i.json"]));
    assert_eq!(r.code, 1, "{}", r.stdout);
    assert!(r.stdout.contains("REGRESSION (+1 instructions, 0% allowed)"), "{}", r.stdout);
    assert!(r.stdout.contains("baseline: the first count"), "{}", r.stdout);
    // Within an allowed rise (the CI gate's 0.5%): passes, and says so.
    let r = rtow(d, &args(&["--baseline", "i.json", "--max-rise", "0.5"]));
    assert_eq!(r.code, 0, "{}", r.stdout);
    assert!(r.stdout.contains("ok (+1 instructions, within the 0.5% allowed)"), "{}", r.stdout);
    // A timing baseline is not an instruction baseline, and the other way round.
    assert_eq!(bench(d, &["--save", "t.json"]).code, 0);
    let line = common::failure(&rtow(d, &args(&["--baseline", "t.json"])), 2, "time baseline");
    assert!(line.contains("not an instruction baseline"), "{line}");
    let line = common::failure(&bench(d, &["--baseline", "i.json"]), 2, "instruction baseline");
    assert!(line.contains("holds instruction counts"), "{line}");
}

/// The instruction gate (`benches/instructions/gate`, run by `.ci/run`): a
/// committed baseline for each of the script's cases and a case for each
/// baseline, counted with the case's scene, settings and kernels, on one
/// thread of an x86-64-v3 build, each with a one-line reason.
#[test]
fn the_instruction_gate_has_a_baseline_for_each_case_each_with_a_reason() {
    use rtow::instruments::instructions::{check_reason, InstructionsBaseline};
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/instructions");
    let script = std::fs::read_to_string(dir.join("gate")).unwrap();
    let cases: Vec<Vec<&str>> = script
        .lines()
        .filter_map(|l| l.trim().strip_prefix('"').and_then(|l| l.strip_suffix('"')))
        .map(|l| l.split('|').collect::<Vec<_>>())
        .filter(|f| f.len() == 3)
        .collect();
    assert_eq!(cases.len(), 5, "the gate's cases: {cases:?}");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".json"))
        .collect();
    files.sort();
    let mut scenes: Vec<String> = cases.iter().map(|c| format!("{}.json", c[0])).collect();
    scenes.sort();
    assert_eq!(files, scenes, "one baseline per case");
    for c in &cases {
        let path = dir.join(format!("{}.json", c[0]));
        let b = InstructionsBaseline::from_bytes(&std::fs::read(&path).unwrap(), &path).unwrap();
        let reason = b.reason.as_deref().unwrap_or_else(|| panic!("{}: no reason", c[0]));
        check_reason(reason).unwrap();
        assert_eq!((b.scene.as_str(), b.threads), (c[0], 1));
        assert!(b.provenance.isa.contains("x86-64-v3"), "{}: {}", c[0], b.provenance.isa);
        let words: Vec<&str> = c[1].split_whitespace().collect();
        let value = |flag: &str| words[words.iter().position(|w| *w == flag).unwrap() + 1].to_string();
        let settings = [b.width.to_string(), b.height.to_string(), b.spp.to_string(), b.max_depth.to_string()];
        assert_eq!(settings.to_vec(), ["--width", "--height", "--spp", "--depth"].map(value).to_vec(), "{}", c[0]);
        let kernels: Vec<&str> = b.kernels.iter().map(|k| k.kernel.as_str()).collect();
        assert_eq!(kernels.join(","), c[2], "{}", c[0]);
        assert_eq!(b.estimator, Some(value("--estimator")), "{}", c[0]);
    }
}
