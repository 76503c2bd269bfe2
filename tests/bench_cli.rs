//! `rtow bench --save / --baseline`: the regression test users run on a speedup.
//! Exit status 0 when throughput held and the image is the same; 1 when the
//! image changed or throughput fell by more than the tolerance.

mod common;

use common::{rtow, Run};
use std::path::Path;

fn bench(dir: &Path, extra: &[&str]) -> Run {
    bench_spp(dir, "2", extra)
}

fn bench_spp(dir: &Path, spp: &str, extra: &[&str]) -> Run {
    let mut args = vec!["bench", "ch05-ground", "--kernels", "scalar,simd", "--repeat", "1"];
    args.extend(["--width", "24", "--height", "14", "--spp", spp, "--threads", "1"]);
    args.extend_from_slice(extra);
    rtow(dir, &args)
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
    edit(&fast, |v| {
        let m = v["kernels"][1]["mrays_per_s"].as_f64().unwrap();
        v["kernels"][1]["mrays_per_s"] = (m * 1000.0).into();
    });
    let r = bench(dir.path(), &["--baseline", "fast.json"]);
    assert_eq!(r.code, 1);
    assert!(r.stdout.contains("REGRESSION"));

    // A baseline whose algorithm did less work: same image, more work now:
    // exit 1 and said so, even with timings within any tolerance.
    let less = dir.path().join("less.json");
    std::fs::copy(&base, &less).unwrap();
    edit(&less, |v| {
        let n = v["kernels"][1]["work"]["sphere_tests"].as_u64().unwrap();
        v["kernels"][1]["work"]["sphere_tests"] = (n / 2).into();
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
