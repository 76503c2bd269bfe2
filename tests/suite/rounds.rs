//! Renders in rounds of samples: `--time-limit`, `--preview-every`, a
//! graceful stop on SIGINT / SIGTERM leaving a film, and `--resume FILM`
//! without a scene. Every image a round gives is exactly the render of its
//! sample count.

use crate::common::{failure, listing, rtow, BIN};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn stats(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn hash(v: &serde_json::Value) -> &str {
    v["image_hash"].as_str().unwrap()
}

const SIZE: [&str; 6] = ["--width", "48", "--height", "27", "--depth", "8"];

fn args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec!["render", "final"];
    v.extend_from_slice(&SIZE);
    v.extend_from_slice(extra);
    v
}

#[test]
fn a_time_limit_gives_exactly_the_render_of_the_samples_it_reached() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let t = Instant::now();
    rtow(d, &args(&["--spp", "1000000", "--time-limit", "1500ms", "-o", "a.png", "--stats-json", "a.json", "-q"])).ok();
    let took = t.elapsed();
    let a = stats(&d.join("a.json"));
    let reached = a["spp"].as_u64().unwrap();
    assert!((1..1_000_000).contains(&reached), "{reached} spp");
    assert_eq!(a["rounds"]["spp_requested"], 1_000_000);
    assert_eq!(a["rounds"]["stopped"], "time-limit");
    assert!(a["rounds"]["rounds"].as_u64().unwrap() >= 2, "{}", a["rounds"]);
    // Not a timing claim: a bound that only a broken limit breaks on a loaded machine.
    assert!(took < Duration::from_secs(30), "a 1.5 s limit took {took:?}");
    let spp = reached.to_string();
    rtow(d, &args(&["--spp", &spp, "--on-interrupt", "quit", "-o", "b.png", "--stats-json", "b.json", "-q"])).ok();
    let b = stats(&d.join("b.json"));
    assert!(b["rounds"].is_null(), "a render with --on-interrupt quit goes in one go");
    assert_eq!(hash(&a), hash(&b), "{reached} spp reached under the limit, then rendered in one go");
    assert_eq!(std::fs::read(d.join("a.png")).unwrap(), std::fs::read(d.join("b.png")).unwrap());
    assert_eq!(listing(d), ["a.json", "a.png", "b.json", "b.png"], "no film, lock or temporary left");
}

#[test]
fn rounds_and_previews_render_the_image_of_one_go_in_every_kernel() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    rtow(d, &args(&["--spp", "24", "--on-interrupt", "quit", "--stats-json", "one.json", "-o", "one.png", "-q"])).ok();
    let one = stats(&d.join("one.json"));
    for kernel in ["scalar", "simd8", "simd16"] {
        let json = format!("{kernel}.json");
        let png = format!("{kernel}.png");
        let r = rtow(
            d,
            &args(&["--spp", "24", "--kernel", kernel, "--preview-every", "1ms", "--stats-json", &json, "-o", &png]),
        );
        r.ok();
        let s = stats(&d.join(&json));
        assert_eq!(hash(&s), hash(&one), "{kernel} in rounds");
        assert_eq!(s["spp"], 24);
        assert!(s["rounds"]["stopped"].is_null());
        assert!(s["rounds"]["previews"].as_u64().unwrap() >= 1, "{}", s["rounds"]);
        assert!(r.stdout.contains("24 spp"), "{}", r.stdout);
        assert_eq!(std::fs::read(d.join(&png)).unwrap(), std::fs::read(d.join("one.png")).unwrap());
    }
}

/// Starts a long render of `final` in `d` to `a.png`, waits until it has
/// started rendering, then sends `sig`; returns the exit status and stderr.
fn interrupt(d: &Path, sig: &str, extra: &[&str]) -> (Option<i32>, String) {
    let mut a = args(&["--spp", "1000000", "-o", "a.png", "-q"]);
    a.extend_from_slice(extra);
    let child = Command::new(BIN).args(&a).current_dir(d).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    // The output's lock is taken before the render starts.
    let start = Instant::now();
    while !d.join("a.png.lock").exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "never started: {:?}", listing(d));
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(700));
    let kill = Command::new("kill").args([&format!("-{sig}"), &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[cfg(unix)]
#[test]
fn a_signal_leaves_a_film_that_resumes_to_exactly_the_image_of_one_go() {
    for (sig, code) in [("INT", 130), ("TERM", 143)] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("a.png"), b"the user's old image").unwrap();
        // Feature buffers asked for are outputs like the image: not written either.
        let (status, said) = interrupt(d, sig, if sig == "TERM" { &["--aov", "albedo,depth"] } else { &[] });
        assert_eq!(status, Some(code), "SIG{sig}: {said}");
        assert!(said.contains(&format!("SIG{sig}: stopped after")) && said.contains("a.rtfilm"), "{said}");
        assert_eq!(listing(d), ["a.png", "a.rtfilm"], "SIG{sig}: only the film is written");
        assert_eq!(std::fs::read(d.join("a.png")).unwrap(), b"the user's old image", "SIG{sig}");
        // The film holds a whole render of the samples done; resumed without
        // naming the scene (the film's own scene and settings), a few more.
        let r = rtow(d, &["merge", "a.rtfilm", "-o", "m.png", "--stats-json", "m.json", "-q"]);
        r.ok();
        let done = stats(&d.join("m.json"))["spp"].as_u64().unwrap();
        assert!(done >= 1, "{done}");
        let more = (done + 3).to_string();
        rtow(d, &["render", "--resume", "a.rtfilm", "--spp", &more, "-o", "r.png", "--stats-json", "r.json", "-q"])
            .ok();
        rtow(d, &args(&["--spp", &more, "--on-interrupt", "quit", "-o", "g.png", "--stats-json", "g.json", "-q"])).ok();
        assert_eq!(hash(&stats(&d.join("r.json"))), hash(&stats(&d.join("g.json"))), "SIG{sig}: resumed");
        // The film alone, without --spp: its own image.
        rtow(d, &["render", "--resume", "a.rtfilm", "--stats-json", "f.json", "-q"]).ok();
        assert!(d.join("a.png").exists());
        assert_eq!(hash(&stats(&d.join("f.json"))), hash(&stats(&d.join("m.json"))), "SIG{sig}: the film's image");
    }
}

#[cfg(unix)]
#[test]
fn with_on_interrupt_quit_a_signal_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (status, said) = interrupt(d, "INT", &["--on-interrupt", "quit"]);
    assert_eq!(status, Some(130), "{said}");
    assert!(said.contains("interrupted by SIGINT: no output was written"), "{said}");
    assert!(listing(d).is_empty(), "{:?}", listing(d));
}

#[test]
fn what_rounds_cannot_honour_is_refused_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&[&str], &str); 6] = [
        (&["--spp", "4", "--time-limit", "10s", "--shard", "1/2", "-o", "p.rtfilm"], "--time-limit"),
        (&["--spp", "128", "--time-limit", "10s", "--adaptive", "0.05"], "--time-limit"),
        (&["--spp", "4", "--preview-every", "1s", "-o", "p.rtfilm"], "--preview-every"),
        (&["--spp", "4", "--preview-every", "0s"], "--preview-every"),
        (&["--spp", "4", "--time-limit", "ten seconds"], "--time-limit"),
        (&["--spp", "4", "--on-interrupt", "later"], "--on-interrupt"),
    ];
    for (extra, flag) in cases {
        let r = rtow(d, &args(extra));
        let line = failure(&r, 2, flag);
        assert!(line.contains(flag), "{extra:?}: {line}");
    }
    let r = rtow(d, &["render", "ch01-gradient", "--time-limit", "1s"]);
    assert!(failure(&r, 2, "gradient").contains("--time-limit"));
    let r = rtow(d, &["render"]);
    assert_eq!(r.code, 2, "no scene and no film: {}", r.stderr);
    assert!(listing(d).is_empty(), "{:?}", listing(d));
}
