//! Issue 17, "Trust nothing": the classes of input and circumstance that a
//! distributed or batch run meets (outputs named as inputs, concurrent runs,
//! hang-ups, file-size limits, references that are not linear light,
//! unbounded or unnamed error messages). Each test fails on the code before
//! the fix; docs/reliability.md maps every class to its test.

use crate::common;

use common::{failure, listing, rtow, rtow_env, BIN};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const SMALL: [&str; 7] = ["--width", "16", "--height", "9", "--spp", "2", "-q"];
const SENTINEL: &[u8] = b"old contents; a failed run must leave this file alone";

fn args<'a>(head: &[&'a str]) -> Vec<&'a str> {
    let mut v = head.to_vec();
    v.extend_from_slice(&SMALL);
    v
}

/// Exit status `code`, one `error:` line containing every needle.
fn fails(r: &common::Run, code: i32, needles: &[&str], what: &str) -> String {
    let line = failure(r, code, what);
    for n in needles {
        assert!(line.contains(n), "{what}: {line:?} does not say {n:?}");
    }
    line
}

// ---------------------------------------------------------------------------
// An output may never be an input of the same run.

#[test]
fn trust1_no_output_but_the_image_may_replace_the_film_being_resumed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let base = ["render", "ch09-glass", "--width", "16", "--height", "9", "-q"];
    let mut first = base.to_vec();
    first.extend_from_slice(&["--spp", "2", "-o", "w.rtfilm"]);
    rtow(d, &first).ok();
    let film = std::fs::read(d.join("w.rtfilm")).unwrap();
    std::os::unix::fs::symlink(d.join("w.rtfilm"), d.join("link.json")).unwrap();
    std::os::unix::fs::symlink(d.join("w.rtfilm"), d.join("link.pfm")).unwrap();
    for (flag, path) in [("--stats-json", "w.rtfilm"), ("--stats-json", "./link.json"), ("--float", "link.pfm")] {
        let mut a = base.to_vec();
        a.extend_from_slice(&["--spp", "4", "--resume", "w.rtfilm", "-o", "w4.rtfilm", flag, path]);
        fails(&rtow(d, &a), 2, &[flag, "film being resumed"], &format!("{flag} {path}"));
        assert_eq!(std::fs::read(d.join("w.rtfilm")).unwrap(), film, "{flag} {path}: the film was changed");
    }
    // The film itself may be continued in place.
    let mut a = base.to_vec();
    a.extend_from_slice(&["--spp", "4", "--resume", "w.rtfilm", "-o", "w.rtfilm"]);
    rtow(d, &a).ok();
    assert_ne!(std::fs::read(d.join("w.rtfilm")).unwrap(), film);
}

// ---------------------------------------------------------------------------
// Concurrent runs on the same outputs are refused, never mixed.

/// Starts a render writing `outputs` that holds its staged files (and its
/// locks) for `ms` milliseconds; returns once they are staged.
fn held_render(d: &Path, outputs: &[&str], ms: u64) -> std::process::Child {
    let mut a = vec!["render", "ch04-sphere", "-o", outputs[0]];
    for (flag, f) in ["--float", "--stats-json"].iter().zip(&outputs[1..]) {
        a.extend_from_slice(&[flag, f]);
    }
    a.extend_from_slice(&SMALL);
    let child = Command::new(BIN)
        .args(&a)
        .env("RTOW_TEST_PAUSE_BEFORE_COMMIT_MS", ms.to_string())
        .current_dir(d)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while listing(d).iter().filter(|n| n.starts_with(".rtow-")).count() < outputs.len() {
        assert!(start.elapsed() < Duration::from_secs(60), "outputs never staged: {:?}", listing(d));
        std::thread::sleep(Duration::from_millis(10));
    }
    child
}

#[test]
fn trust2_a_second_run_on_the_same_outputs_is_refused_and_the_first_writes_all_of_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let first = held_render(d, &["a.png", "a.pfm", "a.json"], 3000);
    assert!(listing(d).contains(&"a.png.lock".to_string()), "{:?}", listing(d));
    // Another run writing one of the same files, under another spelling, is refused at once.
    let r = rtow(d, &args(&["render", "ch09-glass", "-o", "b.png", "--float", "./a.pfm"]));
    fails(&r, 1, &["a.pfm", "another run is writing it", "a.pfm.lock"], "second run");
    let out = first.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(listing(d), ["a.json", "a.pfm", "a.png"], "locks or temporaries left");
    // The statistics are the first run's: its scene, not the second's.
    let stats = std::fs::read_to_string(d.join("a.json")).unwrap();
    assert!(stats.contains("ch04-sphere"), "{stats}");
}

#[test]
fn trust2_a_lock_left_by_a_dead_process_of_this_host_is_taken_over_and_another_hosts_is_not() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap();
    // A process id above the kernel's maximum runs nowhere.
    std::fs::write(d.join("a.png.lock"), format!("4294967295 {}", host.trim())).unwrap();
    rtow(d, &args(&["render", "ch04-sphere", "-o", "a.png"])).ok();
    assert_eq!(listing(d), ["a.png"]);
    std::fs::write(d.join("a.png.lock"), "12 some-other-node").unwrap();
    std::fs::write(d.join("a.png"), SENTINEL).unwrap();
    let r = rtow(d, &args(&["render", "ch04-sphere", "-o", "a.png"]));
    fails(&r, 1, &["another run is writing it", "some-other-node", "remove the lock file"], "foreign lock");
    assert_eq!(std::fs::read(d.join("a.png")).unwrap(), SENTINEL);
}

// ---------------------------------------------------------------------------
// Signals and limits of batch systems.

#[test]
fn trust3_a_file_size_limit_is_an_ordinary_write_error_with_cleanup() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("big.png"), SENTINEL).unwrap();
    // 20 blocks (10 KiB in sh's 512-byte blocks): the 256x256 float image is 786 KiB.
    let script = format!(
        "ulimit -f 20 && exec \"{BIN}\" render ch04-sphere --width 256 --height 256 --spp 1 -q -o big.png --float big.pfm"
    );
    let r: common::Run = Command::new("sh").arg("-c").arg(script).current_dir(d).output().unwrap().into();
    assert_eq!(r.signal, None, "killed by a signal: {:?}", r.signal);
    fails(&r, 1, &["File too large"], "ulimit -f");
    assert_eq!(listing(d), ["big.png"], "temporaries or locks left");
    assert_eq!(std::fs::read(d.join("big.png")).unwrap(), SENTINEL);
}

// ---------------------------------------------------------------------------
// converge: one transaction, checked before any rendering; a linear reference.

#[test]
fn trust4_converge_checks_its_whole_set_of_files_before_rendering_and_writes_all_or_none() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("cv")).unwrap();
    std::fs::write(d.join("cv/ch09-glass.csv"), SENTINEL).unwrap();
    // One of the files cannot be written (a folder is in its way): refused
    // before anything is rendered (a render this large would take minutes).
    std::fs::create_dir(d.join("cv/ch09-glass.json")).unwrap();
    let start = Instant::now();
    let r = rtow(d, &["converge", "ch09-glass", "--spp-list", "1024", "--out", "cv"]);
    fails(&r, 1, &["ch09-glass.json", "is a directory"], "converge");
    assert!(start.elapsed() < Duration::from_secs(60), "rendered before checking its outputs");
    assert_eq!(listing(&d.join("cv")), ["ch09-glass.csv", "ch09-glass.json"]);
    assert_eq!(std::fs::read(d.join("cv/ch09-glass.csv")).unwrap(), SENTINEL);
    // A folder under a file: refused, and no folder made.
    std::fs::write(d.join("file"), b"").unwrap();
    fails(&rtow(d, &["converge", "final", "--out", "file/cv"]), 1, &["not a folder"], "file/cv");
    // A missing folder is made, filled all at once.
    let small = ["--width", "16", "--height", "9", "--spp-list", "1,2", "--variants", "plain"];
    let mut a = vec!["converge", "ch09-glass", "--out", "new"];
    a.extend_from_slice(&small);
    rtow(d, &a).ok();
    let files = listing(&d.join("new"));
    for ext in ["csv", "md", "json"] {
        assert!(files.contains(&format!("ch09-glass.{ext}")), "{files:?}");
    }
    assert!(files.contains(&"ch09-glass-reference.exr".to_string()), "{files:?}");
    assert!(!files.iter().any(|f| f.starts_with('.') || f.ends_with(".lock")), "{files:?}");
}

#[test]
fn trust5_a_converge_reference_must_be_a_linear_float_image_of_the_size() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    rtow(d, &["render", "ch09-glass", "--width", "16", "--height", "9", "--spp", "2", "-q", "-o", "r.png"]).ok();
    std::fs::copy(d.join("r.png"), d.join("disguised.exr")).unwrap();
    let small = ["--width", "16", "--height", "9", "--spp-list", "1,2", "--variants", "plain", "--out", "cv"];
    for (reference, says) in
        [("r.png", "use .pfm or .exr"), ("disguised.exr", "not a linear float image"), ("wrong.pfm", "16x9")]
    {
        if reference == "wrong.pfm" {
            rtow(
                d,
                &["render", "ch09-glass", "--width", "8", "--height", "8", "--spp", "1", "-q", "--float", "wrong.pfm"],
            )
            .ok();
        }
        let mut a = vec!["converge", "ch09-glass", "--reference", reference];
        a.extend_from_slice(&small);
        let r = rtow(d, &a);
        assert_eq!(r.code, 2, "{reference}: {}", r.stderr);
        assert!(r.stderr.contains(says), "{reference}: {:?} does not say {says:?}", r.stderr);
        assert!(!d.join("cv").exists(), "{reference}: outputs made for a refused run");
    }
}

// ---------------------------------------------------------------------------
// Messages: bounded, naming the file and the field.

#[test]
fn trust6_messages_quote_a_bounded_part_of_the_input_and_name_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let long = "x".repeat(20 << 20);
    let json = format!(
        r#"{{"spheres": [{{"center": [0, 0, -1], "radius": 0.5, "material": {{"type": "{long}", "albedo": [1, 1, 1]}}}}]}}"#
    );
    std::fs::write(d.join("long.json"), json).unwrap();
    let line = fails(&rtow(d, &["render", "long.json"]), 2, &["long.json", "spheres[0].material"], "long");
    assert!(line.len() < 1000, "an error line of {} bytes", line.len());

    std::fs::write(d.join("dup.toml"), "[camera]\nvfov_deg = 20\nvfov_deg = 30\n").unwrap();
    fails(&rtow(d, &["render", "dup.toml"]), 2, &["dup.toml", "duplicate key `camera.vfov_deg`", "line 3"], "dup");

    let big = r#"{"camera": {"look_from": [0, 0, 0], "look_at": [0, 0, -1], "vup": [0, 1, 0], "vfov_deg": 90},
        "spheres": [{"center": [0, 0, 1e39], "radius": 0.5, "material": {"type": "lambertian", "albedo": [1, 1, 1]}}]}"#;
    std::fs::write(d.join("big.json"), big).unwrap();
    fails(&rtow(d, &["render", "big.json"]), 2, &["big.json", "spheres[0].center[2]", "too large for f32"], "f32");
    let r = rtow_env(d, &["render", "big.json"], &[]);
    assert!(!r.stderr.contains("got inf"), "{}", r.stderr);
}
