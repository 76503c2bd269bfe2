//! Issue 11, "Hostile input": one test (or more) per class of input that broke
//! rtow, each of which fails on the code before the fix. The table of
//! docs/reliability.md maps every class to these tests.

use crate::common;

use common::{failure, listing, rtow, Run, BIN};
use rtow::scene::{self, Format};
use rtow::Error;
use std::path::Path;
use std::process::{Command, Stdio};

const SMALL: [&str; 7] = ["--width", "16", "--height", "9", "--spp", "1", "-q"];
const SENTINEL: &[u8] = b"old contents; a failed run must leave this file alone";

/// Exit status `code`, one `error:` line containing every needle, no panic.
fn fails(r: &Run, code: i32, needles: &[&str], what: &str) {
    let line = failure(r, code, what);
    for n in needles {
        assert!(line.contains(n), "{what}: {line:?} does not say {n:?}");
    }
}

fn export(dir: &Path, preset: &str, file: &str) -> String {
    let s = scene::preset(preset).unwrap();
    scene::save_scene(&s, &dir.join(file)).unwrap();
    std::fs::read_to_string(dir.join(file)).unwrap()
}

/// Runs `sh -c` with an address-space limit, so that a run that would need
/// more memory than `kib` fails its allocation (and aborts: exit 134) instead
/// of swapping the machine.
fn rtow_limited(dir: &Path, kib: u64, args: &str) -> Run {
    let script = format!("ulimit -v {kib} && exec \"{BIN}\" {args}");
    Command::new("sh").arg("-c").arg(script).current_dir(dir).output().expect("sh runs").into()
}

// ---------------------------------------------------------------------------
// 1. Memory is bounded by the input.

#[test]
fn class1_oversized_scene_files_are_refused_before_they_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (file, limit) in [("big.toml", rtow::limits::MAX_TOML_BYTES), ("big.json", rtow::limits::MAX_JSON_BYTES)] {
        // One unknown key holding a long array: just over the limit.
        let mut text =
            if file.ends_with("toml") { "[camera]\nbogus = [".to_string() } else { "{\"bogus\": [".to_string() };
        while (text.len() as u64) <= limit {
            text.push_str("1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,");
        }
        text.push_str("1]\n");
        if file.ends_with("json") {
            text.push('}');
        }
        std::fs::write(d.join(file), &text).unwrap();
        // 256 MiB of address space is far less than parsing it would take.
        let r = rtow_limited(d, 256 << 10, &format!("render {file} -o out.png"));
        fails(&r, 2, &[file, "too large", &limit.to_string()], file);
        assert_eq!(listing(d), [file], "{file}");
        std::fs::remove_file(d.join(file)).unwrap();
    }
}

#[test]
fn class1_a_toml_file_at_the_limit_parses_within_a_bounded_memory() {
    // The worst case for the TOML tree: short values, just under the limit.
    // It must be refused (unknown field) with exit status 2, inside 1.5 GiB of
    // address space, never abort on a failed allocation (exit 134).
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut text = "[camera]\nlook_from = [0, 0, 0]\nlook_at = [0, 0, -1]\nbogus = [".to_string();
    while (text.len() as u64) < rtow::limits::MAX_TOML_BYTES - 64 {
        text.push_str("1,");
    }
    text.push_str("1]\n");
    std::fs::write(d.join("wide.toml"), &text).unwrap();
    let r = rtow_limited(d, 3 << 19, "render wide.toml -o out.png");
    fails(&r, 2, &["camera.bogus"], "wide.toml");
}

#[test]
fn class1_the_sphere_limit_holds_while_parsing() {
    // More spheres than the limit, in a string (no file size check applies):
    // refused while reading, naming the limit, in both formats.
    let n = rtow::limits::MAX_SPHERES + 1;
    let one = r#"{"center":[0,0,-1],"radius":1,"material":{"type":"dielectric","ior":1.5}}"#;
    let mut json = String::with_capacity(n * (one.len() + 1) + 100);
    json.push_str(r#"{"camera":{"look_from":[0,0,0],"look_at":[0,0,-1]},"spheres":["#);
    for i in 0..n {
        if i > 0 {
            json.push(',');
        }
        json.push_str(one);
    }
    json.push_str("]}");
    let e = scene::scene_from_str(&json, Format::Json, Path::new("many.json")).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    assert!(e.to_string().contains("too many spheres"), "{e}");
    assert!(e.to_string().contains(&rtow::limits::MAX_SPHERES.to_string()), "{e}");
    // Through the loader the file size limit refuses it first.
    let e = scene::scene_from_bytes(json.as_bytes(), Format::Json, Path::new("many.json")).unwrap_err();
    assert!(e.to_string().contains("too large"), "{e}");
}

// ---------------------------------------------------------------------------
// 2. A run's outputs are one transaction.

#[test]
fn class2_an_output_may_not_be_an_input_or_another_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene_text = export(d, "ch07-diffuse", "scene.json");
    std::fs::write(d.join("a.png"), SENTINEL).unwrap();
    let base = |extra: &[&'static str]| {
        let mut v = vec!["render", "scene.json"];
        v.extend_from_slice(&SMALL);
        v.extend_from_slice(extra);
        v
    };
    let cases: Vec<(Vec<&str>, &[&str])> = vec![
        (base(&["-o", "a.png", "--stats-json", "scene.json"]), &["--stats-json", "scene.json", "overwritten"]),
        (base(&["-o", "a.png", "--stats-json", "./scene.json"]), &["overwritten"]),
        (base(&["-o", "a.png", "--stats-json", "a.png"]), &["--stats-json", "same file as -o"]),
        (base(&["-o", "a.png", "--float", "x.pfm", "--stats-json", "./x.pfm"]), &["same file as --float"]),
    ];
    for (args, needles) in cases {
        fails(&rtow(d, &args), 2, needles, &args.join(" "));
        assert_eq!(std::fs::read_to_string(d.join("scene.json")).unwrap(), scene_text);
        assert_eq!(std::fs::read(d.join("a.png")).unwrap(), SENTINEL);
        assert_eq!(listing(d), ["a.png", "scene.json"]);
    }
    // bench: --save onto the baseline it compares with.
    let r = rtow(d, &["bench", "ch04-sphere", "--repeat", "1", "--json", "b.json", "--save", "b.json"]);
    fails(&r, 2, &["--save", "same file as --json"], "bench");
}

#[cfg(unix)]
#[test]
fn class2_a_write_protected_output_is_refused() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("ro.png"), SENTINEL).unwrap();
    std::fs::set_permissions(d.join("ro.png"), std::fs::Permissions::from_mode(0o444)).unwrap();
    let mut args = vec!["render", "ch04-sphere", "-o", "ro.png"];
    args.extend_from_slice(&SMALL);
    fails(&rtow(d, &args), 1, &["ro.png", "write-protected"], "ro.png");
    assert_eq!(std::fs::read(d.join("ro.png")).unwrap(), SENTINEL);
    let r = rtow(d, &["export", "final", "-o", "ro.json"]);
    assert_eq!(r.code, 0);
    std::fs::set_permissions(d.join("ro.json"), std::fs::Permissions::from_mode(0o444)).unwrap();
    fails(&rtow(d, &["export", "final", "-o", "ro.json"]), 1, &["write-protected"], "export");
}

#[cfg(unix)]
#[test]
fn class2_a_signal_between_staging_and_commit_leaves_the_old_outputs_and_no_temporaries() {
    for (sig, code) in [("INT", 130), ("TERM", 143), ("HUP", 129)] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        for f in ["a.png", "a.pfm", "a.json"] {
            std::fs::write(d.join(f), SENTINEL).unwrap();
        }
        let mut args = vec!["render", "ch04-sphere", "-o", "a.png", "--float", "a.pfm", "--stats-json", "a.json"];
        args.extend_from_slice(&SMALL);
        let child = Command::new(BIN)
            .args(&args)
            .env("RTOW_TEST_PAUSE_BEFORE_COMMIT_MS", "20000")
            .current_dir(d)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Wait until all three outputs are staged.
        let start = std::time::Instant::now();
        while listing(d).iter().filter(|n| n.starts_with(".rtow-")).count() < 3 {
            assert!(start.elapsed().as_secs() < 60, "outputs never staged: {:?}", listing(d));
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        let kill = Command::new("kill").args([&format!("-{sig}"), &child.id().to_string()]).status().unwrap();
        assert!(kill.success());
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(code), "SIG{sig}: {:?}", out.status);
        // An interrupted run says so, in one line.
        let said = String::from_utf8_lossy(&out.stderr);
        assert_eq!(said.lines().count(), 1, "SIG{sig}: {said:?}");
        assert!(said.contains(&format!("interrupted by SIG{sig}: no output was written")), "SIG{sig}: {said:?}");
        assert_eq!(listing(d), ["a.json", "a.pfm", "a.png"], "SIG{sig}: temporaries left");
        for f in ["a.png", "a.pfm", "a.json"] {
            assert_eq!(std::fs::read(d.join(f)).unwrap(), SENTINEL, "SIG{sig}: {f} replaced");
        }
    }
}

// ---------------------------------------------------------------------------
// 3. Finite but degenerate scenes.

fn camera_json(camera: &str, spheres: &str) -> String {
    format!("{{\"camera\": {{{camera}}}, \"spheres\": [{spheres}]}}")
}

const LAM: &str =
    r#"{"center": [0, 0, -1], "radius": 0.5, "material": {"type": "lambertian", "albedo": [0.5, 0.5, 0.5]}}"#;

#[test]
fn class3_degenerate_cameras_and_spheres_are_refused() {
    let cases = [
        (camera_json(r#""look_from": [0, 0, 0], "look_at": [0, 0, -1e-30]"#, LAM), "camera.look_at"),
        (camera_json(r#""look_from": [3e38, 3e38, 3e38], "look_at": [0, 0, 0]"#, LAM), "camera.look_from"),
        (camera_json(r#""look_from": [0, 0, 1], "look_at": [-3e38, 0, 0]"#, LAM), "camera.look_at"),
        (
            camera_json(r#""look_from": [0, 0, 0], "look_at": [0, 0, -1], "focus_dist": 1e-30"#, LAM),
            "camera.focus_dist",
        ),
        (camera_json(r#""look_from": [0, 0, 0], "look_at": [0, 0, -1], "focus_dist": 1e30"#, LAM), "camera.focus_dist"),
        (camera_json(r#""look_from": [0, 0, 0], "look_at": [0, 0, -1], "aperture": 1e30"#, LAM), "camera.aperture"),
        (camera_json(r#""look_from": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 1e-30"#, LAM), "camera.vfov_deg"),
        (
            camera_json(
                r#""look_from": [0, 0, 0], "look_at": [0, 0, -1]"#,
                r#"{"center": [0, 0, -1], "radius": 1e20, "material": {"type": "dielectric", "ior": 1.5}}"#,
            ),
            "spheres[0].radius",
        ),
        (
            camera_json(
                r#""look_from": [0, 0, 0], "look_at": [0, 0, -1]"#,
                r#"{"center": [0, 0, -1], "radius": 1e-20, "material": {"type": "dielectric", "ior": 1.5}}"#,
            ),
            "spheres[0].radius",
        ),
        (
            camera_json(
                r#""look_from": [0, 0, 0], "look_at": [0, 0, -1]"#,
                r#"{"center": [0, 0, -3e38], "radius": 1, "material": {"type": "dielectric", "ior": 1.5}}"#,
            ),
            "spheres[0].center",
        ),
    ];
    for (text, field) in cases {
        let e = common::read_and_check(&text, Format::Json, "d.json").expect_err(&text);
        assert_eq!(e.exit_code(), 2, "{text}: {e}");
        assert!(matches!(&e, Error::Invalid { field: f, .. } if f == field), "{text}: {e}");
    }
}

#[test]
fn class3_every_accepted_edge_camera_renders_finite_images_with_both_kernels() {
    // The edges of the documented ranges are accepted and render no NaN.
    let l = rtow::limits::MAX_COORD;
    let cases = [
        camera_json(r#""look_from": [0, 0, 0], "look_at": [0, 0, -1e-6]"#, LAM),
        camera_json(&format!(r#""look_from": [{l}, {l}, {l}], "look_at": [-{l}, -{l}, -{l}], "aperture": 1000"#), LAM),
        camera_json(r#""look_from": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 179.99998"#, LAM),
    ];
    for text in cases {
        let s =
            scene::scene_from_str(&text, Format::Json, Path::new("e.json")).unwrap_or_else(|e| panic!("{text}: {e}"));
        for kernel in [rtow::KernelChoice::Scalar, rtow::KernelChoice::Simd] {
            let st = common::settings(16, 9, 2, 4, 1);
            let opts = rtow::RenderOptions { kernel, threads: Some(1), ..Default::default() };
            let r = rtow::render(&common::job(&s, st, opts), None).unwrap();
            assert!(r.image.data.iter().flatten().all(|v| v.is_finite()), "{text}");
            assert_eq!(r.stats.rejected_samples, 0, "{text}");
        }
    }
}

#[test]
fn class3_a_render_of_mostly_nonfinite_samples_fails_instead_of_writing_black() {
    // Valid by every per-field rule, but sky x albedo overflows f32: every
    // sample that hits the sphere is infinite.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = r#"{"camera": {"look_from": [0, 0, 0], "look_at": [0, 0, -1]},
      "spheres": [{"center": [0, 0, -1], "radius": 0.9, "material": {"type": "metal", "albedo": [3e38, 3e38, 3e38], "fuzz": 0}}],
      "sky": {"horizon": [3e38, 3e38, 3e38], "zenith": [3e38, 3e38, 3e38]}}"#;
    std::fs::write(d.join("hot.json"), text).unwrap();
    std::fs::write(d.join("hot.png"), SENTINEL).unwrap();
    for kernel in ["scalar", "simd"] {
        let mut args = vec!["render", "hot.json", "-o", "hot.png", "--kernel", kernel];
        args.extend_from_slice(&SMALL);
        fails(&rtow(d, &args), 2, &["NaN or infinite", "no image written"], kernel);
        assert_eq!(std::fs::read(d.join("hot.png")).unwrap(), SENTINEL);
        assert_eq!(listing(d), ["hot.json", "hot.png"]);
    }
}

// ---------------------------------------------------------------------------
// 4. Resource flags are bounded (also in tests/suite/cli.rs).

#[test]
fn class4_absurd_thread_counts_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let start = std::time::Instant::now();
    for n in ["100000000", "5000", "0"] {
        let mut args = vec!["render", "ch04-sphere", "-o", "x.png", "--threads", n];
        args.extend_from_slice(&SMALL);
        fails(&rtow(dir.path(), &args), 2, &["--threads"], n);
    }
    assert!(start.elapsed().as_secs() < 20, "took {:?}", start.elapsed());
    let s = scene::preset("ch04-sphere").unwrap();
    let opts = rtow::RenderOptions { threads: Some(usize::MAX), ..Default::default() };
    let e = rtow::Job::new(&s, &common::settings(4, 4, 1, 1, 0).into(), &opts);
    assert!(e.err().unwrap().to_string().contains(&rtow::limits::MAX_THREADS.to_string()));
}

// ---------------------------------------------------------------------------
// 5. Everything is validated before work.

#[test]
fn class5_bench_validates_outputs_and_baseline_before_measuring() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bench = ["bench", "ch04-sphere", "--width", "16", "--height", "9", "--spp", "1", "--repeat", "1"];
    let with = |extra: &[&'static str]| {
        let mut v = bench.to_vec();
        v.extend_from_slice(extra);
        v
    };
    // A measurement prints "run 1" to stderr; a failure up front prints only the error.
    fails(&rtow(d, &with(&["--save", "missing/b.json"])), 1, &["missing/b.json", "does not exist"], "save");
    let r = rtow(d, &with(&["--save", "b.json"]));
    assert_eq!(r.code, 0, "{}", r.stderr);
    // A baseline of another scene, or other settings, is refused before measuring.
    let other = ["bench", "ch05-normals", "--width", "16", "--height", "9", "--spp", "1", "--repeat", "1"];
    let mut args = other.to_vec();
    args.extend_from_slice(&["--baseline", "b.json"]);
    fails(&rtow(d, &args), 2, &["baseline is of scene 'ch04-sphere'"], "other scene");
    let mut args = bench.to_vec();
    args[7] = "2";
    args.extend_from_slice(&["--baseline", "b.json"]);
    fails(&rtow(d, &args), 2, &["baseline settings"], "other settings");
    fails(
        &rtow(d, &with(&["--baseline", "b.json", "--kernels", "simd", "--json", "missing/x.json"])),
        1,
        &["missing"],
        "json",
    );
}

// ---------------------------------------------------------------------------
// 6. Writing errors must never panic.

#[cfg(target_os = "linux")]
#[test]
fn class6_a_full_stderr_or_stdout_changes_no_exit_status() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let full = || std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
    let run = |args: &[&str], out_full: bool| {
        let mut c = Command::new(BIN);
        c.args(args).current_dir(d).stderr(full());
        if out_full {
            c.stdout(full());
        } else {
            c.stdout(Stdio::null());
        }
        c.status().unwrap().code()
    };
    assert_eq!(run(&["render", "missing.json"], false), Some(2), "an input error");
    assert_eq!(run(&["render", "ch04-sphere", "-o", "missing/x.png"], false), Some(1), "an output error");
    assert_eq!(
        run(&["bench", "ch04-sphere", "--width", "8", "--height", "8", "--spp", "1", "--repeat", "1"], true),
        Some(0)
    );
    let mut args = vec!["render", "ch04-sphere", "-o", "x.png", "--width", "8", "--height", "8", "--spp", "1"];
    assert_eq!(run(&args, true), Some(0), "a render with a summary line");
    args.push("--bogus");
    assert_eq!(run(&args, true), Some(2), "a usage error");
    assert_eq!(run(&["scenes"], true), Some(0));
}

// ---------------------------------------------------------------------------
// 7. Messages that help.

fn parse(text: &str, file: &str) -> Result<rtow::Scene, Error> {
    let f = Format::from_path(Path::new(file)).unwrap();
    scene::scene_from_bytes(text.as_bytes(), f, Path::new(file))
}

#[test]
fn class7_a_byte_order_mark_is_accepted_in_both_formats() {
    let dir = tempfile::tempdir().unwrap();
    for file in ["bom.json", "bom.toml"] {
        let text = format!("\u{feff}{}", export(dir.path(), "ch09-glass", file));
        assert_eq!(parse(&text, file).unwrap(), scene::preset("ch09-glass").unwrap(), "{file}");
    }
}

#[test]
fn class7_errors_say_what_is_wrong() {
    let cam = r#""camera": {"look_from": [0, 0, 0], "look_at": [0, 0, -1]}"#;
    let cases: Vec<(String, &str, &[&str])> = vec![
        (
            r#"{"camera": {"look_from": [0, 0, 0, 1], "look_at": [0, 0, -1]}}"#.into(),
            "v4.json",
            &["camera.look_from", "invalid length 4", "3 numbers", "line 1"],
        ),
        (
            r#"{"camera": {"look_from": [0, 0], "look_at": [0, 0, -1]}}"#.into(),
            "v2.json",
            &["camera.look_from", "invalid length 2", "3 numbers"],
        ),
        (
            "[camera]\nlook_from = [0, 0, 0]\nlook_at = [0, 0, -1, 5]\n".into(),
            "v4.toml",
            &["camera.look_at", "invalid length 4", "line 3"],
        ),
        (
            format!(r#"{{{cam}, "render": {{"width": 100000000000000000000}}}}"#),
            "wide.json",
            &["render.width", "too large", "0 to 4294967295"],
        ),
        (
            format!(r#"{{{cam}, "render": {{"width": 5000000000}}}}"#),
            "w5.json",
            &["render.width", "5000000000", "0 to 4294967295"],
        ),
        (format!(r#"{{{cam}, "render": {{"width": -3}}}}"#), "wneg.json", &["render.width", "-3"]),
        (
            "[camera]\nlook_from = [0, 0, 0]\nlook_at = [0, 0, -1]\nvfov_deg = 1979-05-27\n".into(),
            "date.toml",
            &["camera.vfov_deg", "datetime", "expected a number", "line 4"],
        ),
        (
            "[camera]\nlook_from = [0, 0, 1979-05-27T07:32:00Z]\nlook_at = [0, 0, -1]\n".into(),
            "date3.toml",
            &["camera.look_from", "datetime"],
        ),
        (
            "[camera]\nlook_from = [0, 0, 0]\nlook_at = [0, 0, -1]\n[render]\nwidth = 1979-05-27\n".into(),
            "dw.toml",
            &["render.width", "datetime"],
        ),
    ];
    for (text, file, needles) in cases {
        let e = parse(&text, file).expect_err(file);
        assert_eq!(e.exit_code(), 2, "{file}: {e}");
        let msg = e.to_string();
        for n in needles {
            assert!(msg.contains(n), "{file}: {msg:?} does not say {n:?}");
        }
        assert!(
            !msg.contains("trailing characters") && !msg.contains("floating point") && !msg.contains(", map"),
            "{file}: {msg}"
        );
    }
}

#[test]
fn class7_non_utf8_bytes_are_placed() {
    let e = scene::scene_from_bytes(b"{\n  \"camera\": \xff\n}", Format::Json, Path::new("b.json")).unwrap_err();
    assert!(e.to_string().contains("byte offset 14 (line 2, column 13)"), "{e}");
}

#[test]
fn class7_pfm_headers_with_bad_sizes_name_the_size() {
    let dir = tempfile::tempdir().unwrap();
    for (header, says) in [
        ("PF\n-4 2\n-1.0\n", "width -4"),
        ("PF\n4 -2\n-1.0\n", "height -2"),
        ("PF\n0 2\n-1.0\n", "width 0"),
        ("PF\nfour 2\n-1.0\n", "width 'four'"),
        ("PF\n4 2\n0\n", "scale"),
        ("PF\n99999 99999\n-1.0\n", "pixels"),
    ] {
        let p = dir.path().join("r.pfm");
        std::fs::write(&p, header).unwrap();
        let e = rtow::Image::load_float(&p).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains(says), "{header:?}: {e}");
    }
}
