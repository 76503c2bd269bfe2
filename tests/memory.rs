//! Peak memory of `rtow merge`, in a test binary of its own: a child's
//! `ru_maxrss` (wait4) counts the resident set of its parent at the time it
//! was spawned (Linux keeps the larger of the old and new high-water marks at
//! exec), so the parent must stay small. Inside the integration suite, whose
//! other tests render in-process, the merge measured 180 MB instead of 20.

mod common;

use rtow::render;
use rtow::scene::preset;
use rtow::shard::{self, FilmRequest, Split, SplitKind};
use rtow::{KernelChoice, RenderOptions};
use std::collections::BTreeMap;
use std::path::Path;

fn hash_in(path: &Path) -> String {
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["image_hash"].as_str().unwrap().to_string()
}

/// Runs `rtow` with `args` in `dir`; its exit status and peak resident memory (KiB).
// The child is reaped by wait4 (which also reports its rusage), not by `Child::wait`.
#[allow(clippy::zombie_processes)]
fn rtow_peak_rss(dir: &Path, args: &[String]) -> (i32, u64) {
    let child = std::process::Command::new(common::BIN)
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
    let scene = preset("ch07-diffuse").unwrap();
    let s = common::settings(192, 108, 100, 3, 1);
    let o = RenderOptions { kernel: KernelChoice::Simd, threads: Some(2), tile: 16, ..Default::default() };
    let j = common::job(&scene, s, o);
    let mut names = BTreeMap::new();
    for n in [2u32, 100] {
        let v: Vec<String> = (1..=n)
            .map(|k| {
                let split = Split { kind: SplitKind::Samples, shard: k, of: n };
                let (_, p) = shard::render_part(&j, &FilmRequest { split, resume: None }, None).unwrap();
                let name = format!("n{n}-{k}.rtfilm");
                p.write(&d.join(&name)).unwrap();
                name
            })
            .collect();
        names.insert(n, v);
    }
    let one = render(&j, None).unwrap();
    let mut peak = BTreeMap::new();
    for (n, parts) in &names {
        let mut args = vec!["merge".to_string()];
        args.extend(parts.iter().cloned());
        args.extend(["-o", "out.png", "--stats-json", "out.json"].map(String::from));
        let (code, kib) = rtow_peak_rss(d, &args);
        assert_eq!(code, 0, "merge of {n} parts");
        assert_eq!(hash_in(&d.join("out.json")), format!("{:016x}", one.image.hash()), "{n} parts");
        peak.insert(*n, kib);
    }
    println!("peak RSS of merge: {peak:?} KiB");
    // One accumulator (1.1 MB) and one part at a time, whatever the number of parts.
    assert!(peak[&100] < peak[&2] + 8 * 1024, "merge memory grows with the parts: {peak:?} KiB");
    assert!(peak[&100] < 64 * 1024, "merge of 100 parts of 192x108 peaks at {} KiB", peak[&100]);
}
