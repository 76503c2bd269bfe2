//! Shards, merge and resume: any split of a render, by samples or by rows,
//! merges into exactly the one-process image (every kernel, any threads and
//! tiles); a resumed render is exactly the render with more samples; and
//! `rtow merge` refuses, with exit status 2 naming the file, everything that
//! would not give that image.

use crate::common;

use common::{job, rtow, Run};
use rtow::film::part;
use rtow::scene::{preset, Scene};
use rtow::shard::{self, FilmRequest, Part, Split, SplitKind};
use rtow::{render, Adaptive, EstimatorChoice, Job, KernelChoice, RenderOptions, Settings};
use std::path::{Path, PathBuf};

fn kernels() -> Vec<KernelChoice> {
    let mut k = vec![KernelChoice::Scalar, KernelChoice::Simd8];
    if rtow::HAS_SIMD16 {
        k.push(KernelChoice::Simd16);
    }
    k
}

fn opts(kernel: KernelChoice, threads: usize, tile: u32) -> RenderOptions {
    RenderOptions { kernel, threads: Some(threads), tile, ..Default::default() }
}

fn settings(spp: u32) -> Settings {
    common::settings(37, 21, spp, 12, 3)
}

/// The whole of `job` into a partial film, resuming `resume` (named by its path) if given.
fn whole(job: &Job, resume: Option<(&str, Part)>) -> rtow::Result<(rtow::Rendered, Part)> {
    let resume = resume.map(|(p, f)| (PathBuf::from(p), f));
    shard::render_part(&FilmRequest::new(job, Split::WHOLE, resume)?, None)
}

/// Renders shard `k` of `n` and passes it through its file bytes.
fn shard_part(scene: &Scene, s: Settings, o: RenderOptions, split: Split) -> (PathBuf, Part) {
    let job = job(scene, s, o);
    let (_, p) = shard::render_part(&FilmRequest::new(&job, split, None).unwrap(), None).expect("shard renders");
    let name = PathBuf::from(format!("part-{}.rtfilm", split.shard));
    let back = Part::from_bytes(&p.to_bytes(), &name).expect("reads back");
    assert_eq!(back, p);
    (name, back)
}

#[test]
fn any_split_merges_into_the_one_process_image() {
    for name in ["final", "ch09-glass", "nw-simple-light", "nw-bouncing-spheres"] {
        let scene = preset(name).unwrap();
        let s = settings(7);
        let one = render(&job(&scene, s, opts(KernelChoice::Simd, 2, 16)), None).unwrap();
        for (i, kernel) in kernels().into_iter().enumerate() {
            for (kind, ns) in [(SplitKind::Samples, &[1u32, 2, 3, 7][..]), (SplitKind::Rows, &[2, 5, 21][..])] {
                for &n in ns {
                    // Shards run with different threads and tiles, as on different machines.
                    let mut parts: Vec<_> = (1..=n)
                        .map(|k| {
                            let o = opts(kernel, 1 + (k as usize % 2), [16, 5, 1, 45][(k as usize + i) % 4]);
                            shard_part(&scene, s, o, Split { kind, shard: k, of: n })
                        })
                        .collect();
                    parts.rotate_left(n as usize / 2);
                    let merged = part::merge(&parts).unwrap();
                    let image = merged.film.image();
                    assert_eq!(
                        image.hash(),
                        one.image.hash(),
                        "{name} {kernel:?}: {n} shards by {kind:?} merge into another image"
                    );
                    assert_eq!(image, one.image);
                    assert_eq!(merged.header.counters.rays, one.stats.rays, "{name} {kernel:?} {kind:?} {n}");
                    assert_eq!(merged.header.counters.samples, one.stats.samples);
                }
            }
        }
    }
}

#[test]
fn the_image_does_not_depend_on_threads_tiles_or_kernel() {
    let scene = preset("final").unwrap();
    let s = settings(5);
    let reference = render(&job(&scene, s, opts(KernelChoice::Scalar, 1, 16)), None).unwrap().image;
    for kernel in kernels() {
        for (threads, tile) in [(1, 1), (2, 7), (2, 45), (1, 16)] {
            let img = render(&job(&scene, s, opts(kernel, threads, tile)), None).unwrap().image;
            assert_eq!(img, reference, "{kernel:?}, {threads} threads, tile {tile}");
        }
    }
}

#[test]
fn a_resumed_render_is_the_render_with_more_samples() {
    let scene = preset("final").unwrap();
    for kernel in kernels() {
        let o = opts(kernel, 2, 16);
        let full = render(&job(&scene, settings(13), o), None).unwrap();
        for first in [2, 4, 13] {
            let (_, done) = whole(&job(&scene, settings(first), o), None).unwrap();
            let done = Part::from_bytes(&done.to_bytes(), Path::new("done.rtfilm")).unwrap();
            let (r, film) = whole(&job(&scene, settings(13), o), Some(("done.rtfilm", done))).unwrap();
            assert_eq!(r.image, full.image, "{kernel:?}: resumed from {first} spp");
            assert_eq!(film.header.counters.rays, full.stats.rays);
            assert_eq!(film.header.samples, [0, 13]);
        }
    }
    // One sample per pixel goes through pixel centres, so it is not the start
    // of a jittered render: resuming it is refused.
    let (_, one) = whole(&job(&scene, settings(1), opts(KernelChoice::Simd, 2, 16)), None).unwrap();
    let eight = job(&scene, settings(8), opts(KernelChoice::Simd, 2, 16));
    let resume = Some((PathBuf::from("one.rtfilm"), one));
    let e = FilmRequest::new(&eight, Split::WHOLE, resume).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("one.rtfilm") && e.contains("pixel_jitter"), "{e}");
}

/// Every estimator keeps shards, merge and resume exact (the images, with the
/// light samples' contributions, and the ray counts; parts do not carry
/// shadow-ray counts), and parts of different estimators never merge:
/// the book's box, which both light-sampling estimators can sample.
#[test]
fn every_estimator_shards_merges_and_resumes_exactly() {
    let scene = preset("rol-cornell-box").unwrap();
    let with = |spp: u32, estimator: EstimatorChoice| Settings { estimator, ..settings(spp) };
    let mut parts_of = Vec::new();
    for estimator in EstimatorChoice::ALL.iter().copied() {
        let s = with(7, estimator);
        let one = render(&job(&scene, s, opts(KernelChoice::Simd, 2, 16)), None).unwrap();
        for kernel in kernels() {
            for split in
                [Split { kind: SplitKind::Samples, shard: 0, of: 3 }, Split { kind: SplitKind::Rows, shard: 0, of: 2 }]
            {
                let parts: Vec<_> = (1..=split.of)
                    .map(|k| shard_part(&scene, s, opts(kernel, 1 + k as usize % 2, 5), Split { shard: k, ..split }))
                    .collect();
                let merged = part::merge(&parts).unwrap();
                assert_eq!(merged.film.image(), one.image, "{estimator:?} {kernel:?} {split:?}");
                assert_eq!(merged.header.counters.rays, one.stats.rays);
                if kernel == KernelChoice::Scalar && split.kind == SplitKind::Samples {
                    parts_of.push(parts);
                }
            }
            // Resumed from 3 samples, the 7-sample render.
            let (_, done) = whole(&job(&scene, with(3, estimator), opts(kernel, 2, 16)), None).unwrap();
            let (r, _) = whole(&job(&scene, s, opts(kernel, 2, 16)), Some(("done.rtfilm", done))).unwrap();
            assert_eq!(r.image, one.image, "{estimator:?} {kernel:?}: resumed");
        }
    }
    // Shard 1 of one estimator beside shards 2 and 3 of another: refused.
    assert_eq!(parts_of.len(), EstimatorChoice::ALL.len());
    for a in 0..parts_of.len() {
        let b = (a + 1) % parts_of.len();
        let mixed = [parts_of[a][0].clone(), parts_of[b][1].clone(), parts_of[b][2].clone()];
        let e = part::merge(&mixed).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("part-1.rtfilm"), "{e}");
    }
}

#[test]
fn adaptive_renders_split_by_rows_exactly_and_refuse_sample_splits() {
    let scene = preset("ch09-glass").unwrap();
    let s = settings(64);
    let o = RenderOptions { adaptive: Some(Adaptive::new(0.2, 8).unwrap()), ..opts(KernelChoice::Simd, 2, 16) };
    let one = render(&job(&scene, s, o), None).unwrap();
    assert!(one.stats.samples < 37 * 21 * 64, "some pixels stop early");
    let parts: Vec<_> =
        (1..=3).map(|k| shard_part(&scene, s, o, Split { kind: SplitKind::Rows, shard: k, of: 3 })).collect();
    assert!(parts[0].1.header.moments);
    let merged = part::merge(&parts).unwrap();
    assert_eq!(merged.film.image(), one.image);
    assert_eq!(merged.header.counters.samples, one.stats.samples);
    let halves = Split { kind: SplitKind::Samples, shard: 1, of: 2 };
    let e = FilmRequest::new(&job(&scene, s, o), halves, None).map(|_| ()).unwrap_err().to_string();
    assert!(e.starts_with("split:") && e.contains("split adaptive renders by rows"), "{e}");
}

// The command line.

fn ok(r: &Run) {
    assert_eq!(r.code, 0, "stderr: {}", r.stderr);
}

/// Exit status 2, one `error:` line naming `file`, and no output written.
fn refused(dir: &Path, args: &[&str], file: &str) -> String {
    let r = rtow(dir, args);
    assert!(!r.stderr.contains("panicked"), "{args:?}: {}", r.stderr);
    assert_eq!(r.code, 2, "{args:?}: {}", r.stderr);
    assert_eq!(r.stderr.lines().count(), 1, "{args:?}: {}", r.stderr);
    assert!(r.stderr.starts_with("error: ") && r.stderr.contains(file), "{args:?}: {} does not name {file}", r.stderr);
    assert!(!dir.join("out.png").exists(), "{args:?} wrote an output");
    r.stderr
}

const SMALL: [&str; 8] = ["--width", "40", "--height", "24", "--spp", "6", "--depth", "10"];

fn hash_in(path: &Path) -> String {
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["image_hash"].as_str().unwrap().to_string()
}

#[test]
fn rtow_merge_writes_the_one_process_image_and_resume_continues() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let run = |extra: &[&str]| {
        let mut a = vec!["render", "final", "-q"];
        a.extend_from_slice(&SMALL);
        a.extend_from_slice(extra);
        rtow(d, &a)
    };
    ok(&run(&["-o", "one.png", "--stats-json", "one.json", "--float", "one.pfm"]));
    for k in 1..=3 {
        ok(&run(&["--shard", &format!("{k}/3"), "-o", &format!("s{k}.rtfilm")]));
        ok(&run(&[
            "--split",
            "rows",
            "--kernel",
            "scalar",
            "--shard",
            &format!("{k}/3"),
            "-o",
            &format!("r{k}.rtfilm"),
        ]));
    }
    // A shard rerun writes the identical file.
    let before = std::fs::read(d.join("s2.rtfilm")).unwrap();
    ok(&run(&["--shard", "2/3", "--threads", "1", "--tile", "3", "-o", "s2.rtfilm"]));
    assert_eq!(std::fs::read(d.join("s2.rtfilm")).unwrap(), before);
    for (parts, out) in [(["s3.rtfilm", "s1.rtfilm", "s2.rtfilm"], "m"), (["r1.rtfilm", "r2.rtfilm", "r3.rtfilm"], "r")]
    {
        let (png, json, pfm) = (format!("{out}.png"), format!("{out}.json"), format!("{out}.pfm"));
        let mut a = vec!["merge"];
        a.extend_from_slice(&parts);
        a.extend_from_slice(&["-o", &png, "--stats-json", &json, "--float", &pfm]);
        let r = rtow(d, &a);
        ok(&r);
        assert!(r.stdout.contains("merged 3 part(s)"), "{}", r.stdout);
        assert_eq!(hash_in(&d.join(&json)), hash_in(&d.join("one.json")));
        assert_eq!(std::fs::read(d.join(&png)).unwrap(), std::fs::read(d.join("one.png")).unwrap());
        assert_eq!(std::fs::read(d.join(&pfm)).unwrap(), std::fs::read(d.join("one.pfm")).unwrap());
    }
    // Resume: from a render's own film, and from merged shards written as a film.
    let mut a = vec!["render", "final", "-q"];
    a.extend_from_slice(&SMALL[..4]);
    a.extend_from_slice(&["--spp", "2", "--depth", "10", "-o", "two.rtfilm"]);
    ok(&rtow(d, &a));
    ok(&rtow(d, &["merge", "s1.rtfilm", "s2.rtfilm", "s3.rtfilm", "-o", "six.rtfilm", "-q"]));
    ok(&run(&["--resume", "two.rtfilm", "-o", "resumed.png", "--stats-json", "resumed.json"]));
    assert_eq!(hash_in(&d.join("resumed.json")), hash_in(&d.join("one.json")));
    let mut a = vec!["render", "final", "-q"];
    a.extend_from_slice(&SMALL[..4]);
    a.extend_from_slice(&["--spp", "9", "--depth", "10", "--resume", "six.rtfilm", "-o", "nine.png"]);
    ok(&rtow(d, &a));
}

#[test]
fn rtow_merge_refuses_what_would_not_be_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let render = |extra: &[&str]| {
        let mut a = vec!["render", "final", "-q"];
        a.extend_from_slice(&SMALL);
        a.extend_from_slice(extra);
        ok(&rtow(d, &a));
    };
    for k in 1..=4 {
        render(&["--shard", &format!("{k}/4"), "-o", &format!("p{k}.rtfilm")]);
    }
    render(&["--shard", "2/4", "--seed", "9", "-o", "seed9.rtfilm"]);
    render(&["--shard", "2/4", "--rr", "-o", "rr.rtfilm"]);
    render(&["--shard", "2/4", "--sampler", "sobol-pixel", "-o", "sampler.rtfilm"]);
    render(&["--shard", "2/4", "--split", "rows", "-o", "rows2.rtfilm"]);
    render(&["--shard", "2/5", "-o", "of5.rtfilm"]);
    let mut a = vec!["render", "ch09-glass", "-q"];
    a.extend_from_slice(&SMALL);
    a.extend_from_slice(&["--shard", "2/4", "-o", "glass2.rtfilm"]);
    ok(&rtow(d, &a));
    let good = std::fs::read(d.join("p2.rtfilm")).unwrap();
    std::fs::write(d.join("truncated.rtfilm"), &good[..good.len() - 100]).unwrap();
    let mut bad = good.clone();
    let at = bad.len() - 50;
    bad[at] ^= 1;
    std::fs::write(d.join("corrupt.rtfilm"), &bad).unwrap();
    let mut future = good.clone();
    future[8..12].copy_from_slice(&(part::VERSION + 1).to_le_bytes());
    std::fs::write(d.join("future.rtfilm"), &future).unwrap();
    std::fs::write(d.join("empty.rtfilm"), b"").unwrap();

    let merge =
        |second: &str| refused(d, &["merge", "p1.rtfilm", second, "p3.rtfilm", "p4.rtfilm", "-o", "out.png"], second);
    assert!(merge("seed9.rtfilm").contains("seed = 9"));
    assert!(merge("rr.rtfilm").contains("russian_roulette = after"));
    assert!(merge("sampler.rtfilm").contains("sampler = sobol-pixel"));
    assert!(merge("glass2.rtfilm").contains("different scene"));
    assert!(merge("rows2.rtfilm").contains("by rows"));
    assert!(merge("of5.rtfilm").contains("2/5"));
    assert!(merge("truncated.rtfilm").contains("truncated"));
    assert!(merge("corrupt.rtfilm").contains("corrupted"));
    assert!(merge("future.rtfilm").contains("newer"));
    assert!(merge("empty.rtfilm").contains("not an rtow partial film"));
    assert!(merge("missing.rtfilm").contains("cannot read"));
    // Duplicates (the same shard twice, under another name too) and missing shards.
    std::fs::copy(d.join("p3.rtfilm"), d.join("copy3.rtfilm")).unwrap();
    let e = refused(
        d,
        &["merge", "p1.rtfilm", "p2.rtfilm", "p3.rtfilm", "copy3.rtfilm", "p4.rtfilm", "-o", "out.png"],
        "copy3.rtfilm",
    );
    assert!(e.contains("duplicate") && e.contains("p3.rtfilm"), "{e}");
    let e = refused(d, &["merge", "p1.rtfilm", "p3.rtfilm", "-o", "out.png"], "p1.rtfilm");
    assert!(e.contains("missing shards 2, 4 of 4"), "{e}");
    // Render-side refusals: a shard to a PNG, adaptive with a sample split, a resume of another render.
    let mut a = vec!["render", "final"];
    a.extend_from_slice(&SMALL);
    let with = |extra: &[&'static str]| -> Vec<&'static str> { [a.as_slice(), extra].concat() };
    refused(d, &with(&["--shard", "1/2", "-o", "out.png"]), "--shard");
    // (--adaptive-min 2: with 6 samples adaptive sampling can act, so it is on.)
    refused(
        d,
        &with(&["--shard", "1/2", "--adaptive", "0.1", "--adaptive-min", "2", "-o", "out.rtfilm"]),
        "split adaptive renders by rows",
    );
    refused(d, &with(&["--shard", "3/2", "-o", "out.rtfilm"]), "--shard");
    refused(d, &with(&["--seed", "1", "--resume", "p1.rtfilm", "-o", "out.png"]), "p1.rtfilm");
    let e = refused(d, &["render", "ch01-gradient", "--width", "8", "--height", "8", "-o", "out.rtfilm"], "no film");
    assert!(e.contains("gradient"), "{e}");
    assert!(!d.join("out.rtfilm").exists());
}

// Issue 17: bounded by design, and a merge that streams.

/// Runs `rtow` with `args` in `dir` under an address-space limit of `kib`
/// KiB, so that a run that would need more memory fails its allocation
/// (exit 134) instead of swapping the machine.
fn rtow_limited(dir: &Path, kib: u64, args: &str) -> Run {
    let script = format!("ulimit -v {kib} && exec \"{}\" {args}", common::BIN);
    std::process::Command::new("sh").arg("-c").arg(script).current_dir(dir).output().expect("sh runs").into()
}

/// A film's preamble and header, with the header edited by `edit`.
fn edited_header(film: &[u8], edit: impl Fn(&mut serde_json::Value)) -> Vec<u8> {
    let hlen = u32::from_le_bytes(film[12..16].try_into().unwrap()) as usize;
    let mut h: serde_json::Value = serde_json::from_slice(&film[16..16 + hlen]).unwrap();
    edit(&mut h);
    let text = serde_json::to_vec(&h).unwrap();
    let mut out = film[..12].to_vec();
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(&text);
    out
}

#[test]
fn a_part_is_refused_after_reading_at_most_its_header() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ok(&rtow(d, &["render", "final", "-q", "--width", "8", "--height", "6", "--spp", "2", "-o", "w.rtfilm"]));
    let good = std::fs::read(d.join("w.rtfilm")).unwrap();
    let sparse = |name: &str, head: &[u8], len: u64| {
        let f = std::fs::File::create(d.join(name)).unwrap();
        std::io::Write::write_all(&mut &f, head).unwrap();
        f.set_len(len).unwrap();
    };
    // 1 GiB of zeros; a real header followed by 1 GiB; a header that claims
    // 2^27 pixels, in a 4 GiB file (under the largest film read). Each file is
    // sparse: nothing is written to the disk.
    sparse("zeros.rtfilm", b"", 1 << 30);
    sparse("long.rtfilm", &edited_header(&good, |_| {}), 1 << 30);
    let huge = edited_header(&good, |h| {
        let (w, hh) = (1u64 << 14, 1u64 << 13);
        h["width"] = w.into();
        h["height"] = hh.into();
        h["rows"] = serde_json::json!([0, hh]);
        h["counters"]["samples"] = (w * hh * 2).into();
    });
    sparse("huge.rtfilm", &huge, 4 << 30);
    // 256 MiB of address space: reading any of them whole would abort (exit 134).
    for (file, needle) in [
        ("zeros.rtfilm", "not an rtow partial film"),
        ("long.rtfilm", "the header says"),
        ("huge.rtfilm", "134217728 pixels, more than the 67108864"),
    ] {
        for cmd in [
            format!("merge {file} -o out.png"),
            format!("render final --width 8 --height 6 --spp 4 --resume {file} -o out.png"),
        ] {
            let r = rtow_limited(d, 256 << 10, &cmd);
            assert_eq!(r.code, 2, "{cmd}: {}", r.stderr);
            assert_eq!(r.stderr.lines().count(), 1, "{cmd}: {}", r.stderr);
            assert!(r.stderr.contains(file) && r.stderr.contains(needle), "{cmd}: {}", r.stderr);
        }
    }
}

// Issue 17: a verified merge.

/// `film` with its header edited by `edit`, its data edited by `data`
/// (given the data's offset and the bytes per pixel), and its checksum
/// recomputed: a film a bug or a hand could write.
fn rewritten(film: &[u8], edit: impl Fn(&mut serde_json::Value), data: impl Fn(&mut [u8], usize, usize)) -> Vec<u8> {
    let hlen = u32::from_le_bytes(film[12..16].try_into().unwrap()) as usize;
    let h: serde_json::Value = serde_json::from_slice(&film[16..16 + hlen]).unwrap();
    let scene = h["scene_bytes"].as_u64().unwrap() as usize;
    let pixel = 4 + 3 * h["sum_bytes"].as_u64().unwrap() as usize + if h["moments"] == true { 24 } else { 0 };
    let mut rest = film[16 + hlen..film.len() - 4].to_vec();
    data(&mut rest, scene, pixel);
    let mut out = edited_header(film, edit);
    out.extend_from_slice(&rest);
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

#[test]
fn merge_and_resume_verify_the_films_by_rendering_them_again() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let small = ["--width", "8", "--height", "6", "--depth", "8", "-q"];
    let run = |extra: &[&str]| rtow(d, &[&["render", "final"][..], &small, extra].concat());
    for k in 1..=4 {
        ok(&run(&["--spp", "8", "--shard", &format!("{k}/4"), "-o", &format!("p{k}.rtfilm")]));
    }
    ok(&run(&["--spp", "4", "-o", "four.rtfilm"]));
    let read = |f: &str| std::fs::read(d.join(f)).unwrap();
    let write = |f: &str, b: &[u8]| std::fs::write(d.join(f), b).unwrap();
    let all = |first: &str, second: &str| {
        ["merge", "p1.rtfilm", first, second, "p4.rtfilm", "-o", "out.png", "--verify", "100"].map(String::from)
    };
    let merge = |first: &str, second: &str, blamed: &str| {
        let a = all(first, second);
        refused(d, &a.iter().map(String::as_str).collect::<Vec<_>>(), blamed)
    };
    // Parts 2 and 3 swap their claims (shard and sample range, each of 2
    // samples): the headers agree with each other and with the data's sample
    // counts; only rendering their pixels again tells.
    let claim = |from: u32, to: u32| {
        rewritten(
            &read(&format!("p{from}.rtfilm")),
            |h| {
                h["split"]["shard"] = to.into();
                h["samples"] = serde_json::json!([2 * (to - 1), 2 * to]);
            },
            |_, _, _| {},
        )
    };
    write("as3.rtfilm", &claim(2, 3));
    write("as2.rtfilm", &claim(3, 2));
    let e = merge("as2.rtfilm", "as3.rtfilm", "as2.rtfilm");
    assert!(e.contains("pixel (") && e.contains("not what its scene renders over samples 2..4"), "{e}");
    // Without verification the swap goes through, silently (the image differs).
    let a = all("as2.rtfilm", "as3.rtfilm");
    let mut a: Vec<&str> = a.iter().map(String::as_str).collect();
    (a[6], a[8]) = ("swapped.png", "0");
    ok(&rtow(d, &a));
    // A claim of another number of samples disagrees with the data's counts.
    write(
        "more.rtfilm",
        &rewritten(
            &read("p2.rtfilm"),
            |h| {
                h["spp"] = 16.into();
                h["samples"] = serde_json::json!([4, 8]);
            },
            |_, _, _| {},
        ),
    );
    assert!(merge("more.rtfilm", "p3.rtfilm", "more.rtfilm").contains("samples counted"));
    // One sum of pixel 10, (2, 1), changed in its lowest byte.
    let touch = |f: &str| rewritten(&read(f), |_| {}, |data, scene, pixel| data[scene + 10 * pixel + 4] ^= 0x40);
    write("touched.rtfilm", &touch("p3.rtfilm"));
    let e = merge("p2.rtfilm", "touched.rtfilm", "touched.rtfilm");
    assert!(e.contains("pixel (2, 1)") && e.contains("--verify-seed"), "{e}");
    write("four-touched.rtfilm", &touch("four.rtfilm"));
    let e = refused(
        d,
        &[
            &["render", "final"][..],
            &small,
            &["--spp", "8", "--resume", "four-touched.rtfilm", "--verify", "48", "-o", "out.png"],
        ]
        .concat(),
        "four-touched.rtfilm",
    );
    assert!(e.contains("pixel (2, 1)"), "{e}");
    ok(&run(&["--spp", "8", "--resume", "four.rtfilm", "--verify", "48", "-o", "resumed.png"]));
    // The film of an rtow that embedded no scene (format version 1).
    let mut v1 = read("p2.rtfilm");
    v1[8..12].copy_from_slice(&1u32.to_le_bytes());
    write("v1.rtfilm", &v1);
    assert!(merge("v1.rtfilm", "p3.rtfilm", "v1.rtfilm").contains("format version 1 is older"));
    // The pixels checked are held in memory: their number is bounded.
    let e = refused(
        d,
        &["merge", "p1.rtfilm", "p2.rtfilm", "p3.rtfilm", "p4.rtfilm", "-o", "out.png", "--verify", "100000"],
        "verify",
    );
    assert!(e.contains("at most 65536"), "{e}");
    // The seed is reported, and the same seed checks the same pixels.
    let a = all("p2.rtfilm", "p3.rtfilm");
    let mut a: Vec<&str> = a.iter().map(String::as_str).collect();
    (a[6], a[8]) = ("verified.png", "5");
    a.extend(["--verify-seed", "77", "--stats-json", "m.json"]);
    let r = rtow(d, &a);
    ok(&r);
    assert!(r.stdout.contains("verified 20 pixels (--verify 5 --verify-seed 77)"), "{}", r.stdout);
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("m.json")).unwrap()).unwrap();
    assert_eq!(v["verified"]["seed"], 77);
    assert_eq!(v["verified"]["pixels"], 20);
}
