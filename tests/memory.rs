//! Peak memory of `rtow merge`, in a test binary of its own: a child's
//! `ru_maxrss` (wait4) counts the resident set of its parent at the time it
//! was spawned (Linux keeps the larger of the old and new high-water marks at
//! exec), so the parent must stay small. Inside the integration suite, whose
//! other tests render in-process, the merge measured 180 MB instead of 20.
//!
//! Everything here runs the binary, and this file uses nothing of the
//! library: a test binary that links the library re-optimizes all of it at
//! link time under the release profile's LTO (94 s on 2 cores, for these
//! few lines, when the parts were rendered in-process).

use std::collections::BTreeMap;
use std::path::Path;

const BIN: &str = env!("CARGO_BIN_EXE_rtow");

fn hash_in(path: &Path) -> String {
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["image_hash"].as_str().unwrap().to_string()
}

/// Runs `rtow` with `args` in `dir`; its exit status and peak resident memory (KiB).
// The child is reaped by wait4 (which also reports its rusage), not by `Child::wait`.
#[allow(clippy::zombie_processes)]
fn rtow_peak_rss(dir: &Path, args: &[String]) -> (i32, u64) {
    let child = std::process::Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("rtow starts");
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: a zeroed rusage is a valid value, and wait4 writes only into
    // the two locals it is given, for a child of this process.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let waited = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(waited, pid, "wait4 failed");
    let code = if libc::WIFEXITED(status) { libc::WEXITSTATUS(status) } else { 128 + libc::WTERMSIG(status) };
    (code, usage.ru_maxrss as u64)
}

#[test]
fn merge_memory_does_not_grow_with_the_number_of_parts() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 192x108 with 100 samples per pixel, in 100 parts (and in 2): each part
    // holds the whole image (1.1 MB of accumulators), so a merge that held
    // every part would need over 100 MB.
    let render = |extra: &[&str]| {
        let mut args: Vec<String> = "render ch07-diffuse --width 192 --height 108 --spp 100 --depth 3 --seed 1 \
                                     --kernel simd --threads 2 --tile 16 -q"
            .split_whitespace()
            .map(String::from)
            .collect();
        args.extend(extra.iter().map(|a| a.to_string()));
        let out = std::process::Command::new(BIN).args(&args).current_dir(d).output().expect("rtow starts");
        assert!(out.status.success(), "rtow {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    };
    let mut names = BTreeMap::new();
    for n in [2u32, 100] {
        let v: Vec<String> = (1..=n)
            .map(|k| {
                let name = format!("n{n}-{k}.rtfilm");
                render(&["--shard", &format!("{k}/{n}"), "-o", &name]);
                name
            })
            .collect();
        names.insert(n, v);
    }
    render(&["-o", "one.png", "--stats-json", "one.json"]);
    let one = hash_in(&d.join("one.json"));
    let mut peak = BTreeMap::new();
    for (n, parts) in &names {
        let mut args = vec!["merge".to_string()];
        args.extend(parts.iter().cloned());
        args.extend(["-o", "out.png", "--stats-json", "out.json"].map(String::from));
        let (code, kib) = rtow_peak_rss(d, &args);
        assert_eq!(code, 0, "merge of {n} parts");
        assert_eq!(hash_in(&d.join("out.json")), one, "{n} parts");
        peak.insert(*n, kib);
    }
    println!("peak RSS of merge: {peak:?} KiB");
    // One accumulator (1.1 MB) and one part at a time, whatever the number of parts.
    assert!(peak[&100] < peak[&2] + 8 * 1024, "merge memory grows with the parts: {peak:?} KiB");
    assert!(peak[&100] < 64 * 1024, "merge of 100 parts of 192x108 peaks at {} KiB", peak[&100]);
}

/// Writes a `w` x `h` 8-bit RGB PNG whose row `y` is `row(y)`, a row at a
/// time: stored (uncompressed) deflate blocks, so this process never holds
/// more than a row, and the children it measures do not inherit a large
/// resident set (an image built in memory and encoded would add tens of MB
/// to every measurement in this binary, the merge's included).
fn write_png(path: &Path, w: u32, h: u32, row: impl Fn(u32) -> Vec<u8>) {
    use std::io::Write;
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    f.write_all(b"\x89PNG\r\n\x1a\n").unwrap();
    let mut chunk = |kind: &[u8], data: &[u8]| {
        let mut crc = crc32fast::Hasher::new();
        crc.update(kind);
        crc.update(data);
        f.write_all(&(data.len() as u32).to_be_bytes()).unwrap();
        f.write_all(kind).unwrap();
        f.write_all(data).unwrap();
        f.write_all(&crc.finalize().to_be_bytes()).unwrap();
    };
    let mut ihdr = w.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    chunk(b"IHDR", &ihdr);
    // One IDAT chunk per row: the zlib header first, a stored block of the
    // row (filter byte 0 and its pixels), the Adler-32 of all rows last.
    let (mut a, mut b) = (1u32, 0u32);
    for y in 0..h {
        let mut raw = vec![0u8];
        raw.extend(row(y));
        assert_eq!(raw.len(), 1 + 3 * w as usize);
        for &x in &raw {
            a = (a + x as u32) % 65521;
            b = (b + a) % 65521;
        }
        let mut data = if y == 0 { vec![0x78, 0x01] } else { vec![] };
        let len = raw.len() as u16;
        data.push((y + 1 == h) as u8);
        data.extend_from_slice(&len.to_le_bytes());
        data.extend_from_slice(&(!len).to_le_bytes());
        data.extend_from_slice(&raw);
        if y + 1 == h {
            data.extend_from_slice(&((b << 16) | a).to_be_bytes());
        }
        chunk(b"IDAT", &data);
    }
    chunk(b"IEND", &[]);
    f.flush().unwrap();
}

/// Issue 37, class 5: one file under many names is decoded once. A 2048 x
/// 2048 PNG (48 MiB as a texture) under 64 names (links, `./`, `..`, its
/// absolute path) peaks as it does under one name (decoded once per name it
/// peaked at 3.0 GiB, 3,166,672 KiB against 67,792 under one name; a 4096 x
/// 4096 map so named aborted on allocation). Distinct files over the scene's
/// budget of texels (limits::MAX_TOTAL_TEXELS) are refused from their
/// headers, before anything is decoded.
#[test]
fn one_image_under_many_names_is_decoded_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("maps")).unwrap();
    write_png(&d.join("maps/map.png"), 2048, 2048, |y| {
        (0..2048u32).flat_map(|x| [(x / 8) as u8, (y / 8) as u8, 128]).collect()
    });
    let mut names = vec![
        "maps/map.png".to_string(),
        "./maps/map.png".into(),
        "maps/./map.png".into(),
        "maps/../maps/map.png".into(),
        d.join("maps/map.png").to_string_lossy().into_owned(),
    ];
    for k in 0..30 {
        std::os::unix::fs::symlink("maps/map.png", d.join(format!("link{k}.png"))).unwrap();
        std::fs::hard_link(d.join("maps/map.png"), d.join(format!("hard{k}.png"))).unwrap();
        names.extend([format!("link{k}.png"), format!("hard{k}.png")]);
    }
    names.truncate(64);
    // A scene file of 64 quads, quad k under `name(k)`, rendered at 8 x 8, 1 sample.
    let scene = |file: &str, name: &dyn Fn(usize) -> String| {
        let quads: Vec<String> = (0..64)
            .map(|k| {
                format!(
                    r#"{{"q": [{}, 0, 0], "u": [0.015625, 0, 0], "v": [0, 1, 0], "material": {{"type": "lambertian", "albedo": {{"type": "image", "file": {}}}}}}}"#,
                    k as f32 / 64.0,
                    serde_json::to_string(&name(k)).unwrap()
                )
            })
            .collect();
        let text = format!(
            r#"{{"camera": {{"look_from": [0.5, 0.5, 2], "look_at": [0.5, 0.5, 0], "vfov_deg": 30}}, "quads": [{}],
                "render": {{"width": 8, "height": 8, "samples_per_pixel": 1}}}}"#,
            quads.join(", ")
        );
        std::fs::write(d.join(file), text).unwrap();
    };
    scene("one.json", &|_| "maps/map.png".to_string());
    scene("many.json", &|k| names[k].clone());
    let args = |file: &str, out: &str| ["render", file, "-o", out, "-q"].map(String::from).to_vec();
    let (code, one) = rtow_peak_rss(d, &args("one.json", "one.png"));
    assert_eq!(code, 0, "one name");
    let (code, many) = rtow_peak_rss(d, &args("many.json", "many.png"));
    assert_eq!(code, 0, "64 names");
    assert_eq!(std::fs::read(d.join("one.png")).unwrap(), std::fs::read(d.join("many.png")).unwrap());
    // Three distinct 4096 x 4096 files (2^24 texels each, 192 MiB as
    // textures) against a budget of 2^25: refused before any is decoded.
    for k in 0..3u8 {
        write_png(&d.join(format!("big{k}.png")), 4096, 4096, |_| [k, 0, 0].repeat(4096));
    }
    scene("big.json", &|k| format!("big{}.png", k % 3));
    let (code, big) = rtow_peak_rss(d, &args("big.json", "big.png"));
    assert_eq!(code, 2, "over the budget of texels");
    println!("peak RSS: one name {one} KiB, 64 names {many} KiB, three files over the budget {big} KiB");
    // The texture (48 MiB) once, whatever the names; the refusal decodes nothing.
    assert!(many < one + 8 * 1024, "64 names of one file peak at {many} KiB, one name at {one} KiB");
    assert!(many < 160 * 1024, "64 names of one 2048 x 2048 file peak at {many} KiB");
    assert!(big < 96 * 1024, "a refusal over the budget peaks at {big} KiB");
}

/// What a triangle costs at its peak: book one's final scene with its spheres
/// as icospheres of level 2 and of level 3 (155,520 and 622,080 triangles),
/// peak memory of the whole render, per triangle added. The difference
/// leaves out what does not grow with the mesh (the binary, the image, and
/// this test process's own resident set, which a child's peak counts). The
/// peak is while the triangles' tree is built: a triangle's vertices (36
/// bytes, dropped after the build), its plane and mesh (20 bytes), the
/// tree's lanes (56 bytes) and nodes, and the flattened meshes the scene
/// holds. 147 bytes measured (216 while a triangle's shading was a planar
/// record among the quads', 348 before the tree's build made its lanes
/// without leaf records and the arrays were sized exactly).
#[test]
fn a_mesh_triangle_costs_a_bounded_number_of_bytes_at_the_peak() {
    let dir = tempfile::tempdir().unwrap();
    let peak = |level: u32| {
        let args =
            format!("render final --tessellate {level} --width 32 --height 18 --spp 1 --threads 2 -o l{level}.png -q");
        let (code, kib) = rtow_peak_rss(dir.path(), &args.split(' ').map(String::from).collect::<Vec<_>>());
        assert_eq!(code, 0, "tessellate {level}");
        kib
    };
    let (two, three) = (peak(2), peak(3));
    let per_triangle = (three.saturating_sub(two) * 1024) as f64 / (622_080 - 155_520) as f64;
    println!("peak RSS: level 2 {two} KiB, level 3 {three} KiB: {per_triangle:.1} bytes a triangle");
    assert!(per_triangle < 170.0, "a triangle costs {per_triangle:.1} bytes at the peak ({two} and {three} KiB)");
}
