//! A fuzzer over the whole input path, on stable Rust: bytes -> scene parse ->
//! validation -> a tiny render with both kernels. Inputs come from a corpus of
//! every preset exported as JSON and TOML, mutated at the byte and the token
//! level (numbers replaced by extreme values, vectors lengthened, BOMs,
//! invalid UTF-8, deep nesting, splices between files), and from a structured
//! generator of scenes with extreme but finite values. Every input must:
//!
//! - never panic;
//! - be refused with exit status 2 and a one-line message (at most 1,000
//!   bytes), or be accepted;
//! - when accepted, render with both kernels within a time bound, with no NaN
//!   or infinity in the image, the same image from both kernels, and either
//!   few rejected samples or a `check_finite` error (exit status 2);
//! - keep the process's peak memory bounded.
//!
//! Saved bench baselines go through the same mutations: parsing, the
//! sanity checks and the comparison must refuse (exit status 2, one line) or
//! compare without a panic and with finite figures.
//!
//! Partial films (`.rtfilm`) too: real shards and a whole film of a small
//! render get bit flips, cuts, inserted bytes, header fields set to extreme
//! values, changed data and versions (half the time with the checksum
//! recomputed, so the checks behind it are reached), and go through a
//! verified `merge` or a `--resume`: refused (exit status 2, one bounded
//! line) or merged, never a panic or an abort, each in under 10 seconds.
//!
//! `cargo test` runs it for 3 seconds a target; `.ci/run` for 15 more, alone
//! (`RTOW_FUZZ_SECS=15 cargo test --release --test suite fuzz::`); a long run:
//! `RTOW_FUZZ_SECS=3600 RTOW_FUZZ_SEED=7 cargo test --release --test suite fuzz:: -- --nocapture`.
//! The peak memory it bounds is its process's, so only in a dedicated run
//! (`RTOW_FUZZ_SECS` set, `fuzz::` alone): beside the suite's other tests it
//! would measure theirs.
//! A failure prints the seed and the input, and writes it to
//! `target/tmp/fuzz-failure.<ext>` to be replayed with `rtow render`.

use crate::common;
use rtow::scene::{self, Format};
use rtow::{Job, KernelChoice, Overrides, RenderOptions};
use std::path::Path;
use std::time::{Duration, Instant};

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        // xorshift64*
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[self.below(v.len())]
    }
}

/// Values that have broken float code before.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "1e-30",
    "-1e-30",
    "1e30",
    "1e20",
    "1e38",
    "3.4028235e38",
    "-3.4028235e38",
    "1e39",
    "1.17549435e-38",
    "1e-45",
    "1e-5",
    "1e6",
    "1000001",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "18446744073709551616",
    "100000000000000000000",
    "-5",
    "0.5",
    "179.99998",
    "180",
    "1e-4",
    "nan",
    "inf",
    "-inf",
    "NaN",
    "1979-05-27",
    "1979-05-27T07:32:00Z",
    "true",
    "\"1\"",
    "[]",
    "{}",
    "[1, 2, 3, 4]",
    "[1]",
];

/// Tokens spliced in anywhere.
const TOKENS: &[&str] = &[
    "[",
    "]",
    "{",
    "}",
    ",",
    ":",
    "=",
    "\"",
    "\n",
    "\u{feff}",
    "[[spheres]]\n",
    "[camera]\n",
    "\"spheres\": [",
    "\"radius\": ",
    "radius = ",
    "\\u0000",
    "\u{0}",
    "#",
    "'''",
    "\"\"\"",
];

fn corpus() -> Vec<(Vec<u8>, Format)> {
    let mut v = Vec::new();
    for p in scene::presets() {
        // Image textures read the generated map by its absolute name.
        let s = common::self_contained(&(p.build)());
        // A scene of hundreds of thousands of triangles takes most of a
        // second to prepare, the fuzzer's whole budget in a few executions:
        // the meshes' input path is fuzzed through the smaller mesh scenes.
        if s.generated_triangles() > 100_000 {
            continue;
        }
        for f in [Format::Json, Format::Toml] {
            v.push((scene::scene_to_string(&s, f).into_bytes(), f));
        }
    }
    v
}

fn is_num_byte(b: u8) -> bool {
    b.is_ascii_digit() || b == b'.' || b == b'-' || b == b'e' || b == b'E' || b == b'+'
}

/// One random mutation of `data` (corpus entries available for splicing).
fn mutate(rng: &mut Rng, data: &mut Vec<u8>, corpus: &[(Vec<u8>, Format)]) {
    let n = data.len();
    match rng.below(10) {
        // Replace a number by an extreme value.
        0..=2 => {
            let starts: Vec<usize> =
                (0..n).filter(|&i| data[i].is_ascii_digit() && (i == 0 || !is_num_byte(data[i - 1]))).collect();
            if let Some(&i) = starts.get(rng.below(starts.len())) {
                let mut j = i;
                while j < n && is_num_byte(data[j]) {
                    j += 1;
                }
                let start = if i > 0 && data[i - 1] == b'-' { i - 1 } else { i };
                data.splice(start..j, rng.pick(NUMBERS).bytes());
            }
        }
        3 => {
            let i = rng.below(n + 1);
            data.splice(i..i, rng.pick(TOKENS).bytes());
        }
        4 if n > 0 => {
            let i = rng.below(n);
            data[i] ^= 1 << rng.below(8);
        }
        5 if n > 0 => {
            let i = rng.below(n);
            let len = rng.below(64.min(n - i) + 1);
            data.drain(i..i + len);
        }
        6 if n > 0 => {
            // Duplicate a range (more spheres, repeated keys).
            let i = rng.below(n);
            let len = rng.below(512.min(n - i) + 1);
            let chunk: Vec<u8> = data[i..i + len].to_vec();
            let at = rng.below(n + 1);
            data.splice(at..at, chunk);
        }
        7 => {
            // Splice the tail of another corpus entry.
            let (other, _) = rng.pick(corpus);
            let i = rng.below(n + 1);
            let j = rng.below(other.len() + 1);
            data.truncate(i);
            data.extend_from_slice(&other[j..]);
        }
        8 => {
            // Deep nesting.
            let depth = 1 + rng.below(2000);
            let i = rng.below(n + 1);
            let open = if rng.below(2) == 0 { "[" } else { "{\"a\":" };
            data.splice(i..i, open.repeat(depth).into_bytes());
        }
        _ => {
            // Invalid UTF-8 or a BOM at the start.
            let bytes: &[u8] = if rng.below(2) == 0 { b"\xEF\xBB\xBF" } else { b"\xff\xfe" };
            let i = if rng.below(2) == 0 { 0 } else { rng.below(n + 1) };
            data.splice(i..i, bytes.iter().copied());
        }
    }
    data.truncate(256 << 10);
}

/// A scene from scratch, with extreme but finite values, as text.
fn generated(rng: &mut Rng) -> (Vec<u8>, Format) {
    let mut num = |rng: &mut Rng| -> String {
        match rng.below(4) {
            0 => rng.pick(NUMBERS[..22].as_ref()).to_string(),
            1 => format!("{}", (rng.next() as i64 as f64) / 2f64.powi(rng.below(120) as i32)),
            _ => format!("{:.3}", (rng.next() % 2000) as f64 / 100.0 - 10.0),
        }
    };
    let v3 =
        |rng: &mut Rng, num: &mut dyn FnMut(&mut Rng) -> String| format!("[{}, {}, {}]", num(rng), num(rng), num(rng));
    let mut spheres = Vec::new();
    for _ in 0..rng.below(6) {
        let mat = match rng.below(3) {
            0 => format!(r#"{{"type": "lambertian", "albedo": {}}}"#, v3(rng, &mut num)),
            1 => format!(r#"{{"type": "metal", "albedo": {}, "fuzz": {}}}"#, v3(rng, &mut num), num(rng)),
            _ => format!(r#"{{"type": "dielectric", "ior": {}}}"#, num(rng)),
        };
        spheres.push(format!(r#"{{"center": {}, "radius": {}, "material": {mat}}}"#, v3(rng, &mut num), num(rng)));
    }
    let mut cam = format!(r#""look_from": {}, "look_at": {}"#, v3(rng, &mut num), v3(rng, &mut num));
    for (key, p) in [("vup", 4), ("vfov_deg", 2), ("focus_dist", 3), ("aperture", 4), ("defocus_angle_deg", 4)] {
        if rng.below(p) == 0 {
            let val = if key == "vup" { v3(rng, &mut num) } else { num(rng) };
            cam += &format!(r#", "{key}": {val}"#);
        }
    }
    let sky = if rng.below(3) == 0 {
        format!(r#", "sky": {{"horizon": {}, "zenith": {}}}"#, v3(rng, &mut num), v3(rng, &mut num))
    } else {
        String::new()
    };
    let mode = *rng.pick(&["", r#""mode": "flat", "#, r#""mode": "normals", "#, r#""mode": "gradient", "#]);
    let json = format!(r#"{{{mode}"camera": {{{cam}}}, "spheres": [{}]{sky}}}"#, spheres.join(", "));
    // The same scene as TOML half the time, when it is valid JSON.
    if rng.below(2) == 0 {
        if let Ok(v) = serde_json::from_str::<serde_json::Value>(&json) {
            if let Ok(t) = toml::to_string(&v) {
                return (t.into_bytes(), Format::Toml);
            }
        }
    }
    (json.into_bytes(), Format::Json)
}

/// A refusal as every input path owes it: exit status 2 and one line of at
/// most 1,000 bytes.
fn refused(e: rtow::Error) -> Result<&'static str, String> {
    let msg = e.to_string();
    if e.exit_code() != 2 || msg.is_empty() || msg.lines().count() != 1 || msg.len() > 1000 {
        return Err(format!("bad refusal (exit {}): {msg:?}", e.exit_code()));
    }
    Ok("refused")
}

/// Runs one input through the whole path; `Err` describes a broken promise.
fn check(bytes: &[u8], format: Format) -> Result<&'static str, String> {
    let origin = Path::new(if format == Format::Json { "fuzz.json" } else { "fuzz.toml" });
    let scene = match scene::scene_from_bytes(bytes, format, origin) {
        Ok(s) => s,
        Err(e) => return refused(e),
    };
    let o = Overrides { width: Some(8), height: Some(5), spp: Some(2), max_depth: Some(6), ..Default::default() };
    let mut hashes = Vec::new();
    for kernel in [KernelChoice::Scalar, KernelChoice::Simd] {
        let t = Instant::now();
        let opts = RenderOptions { kernel, threads: Some(1), ..Default::default() };
        // Resolving the job checks the scene's values (and the tiny settings).
        let job = match Job::new(&scene, &o, &opts) {
            Ok(j) => j,
            Err(e) => return refused(e),
        };
        let r = match rtow::render(&job, None) {
            Ok(r) => r,
            Err(e) if e.exit_code() == 2 => return Ok("refused by render"),
            Err(e) => return Err(format!("render failed with exit {}: {e}", e.exit_code())),
        };
        if t.elapsed() > Duration::from_secs(10) {
            return Err(format!("{kernel:?} took {:?} for 80 samples", t.elapsed()));
        }
        if let Some(v) = r.image.data.iter().flatten().find(|v| !v.is_finite()) {
            return Err(format!("{kernel:?}: non-finite pixel value {v}"));
        }
        if let Err(e) = r.stats.check_finite() {
            if e.exit_code() != 2 {
                return Err(format!("check_finite exit {}", e.exit_code()));
            }
            return Ok("degenerate (exit 2)");
        }
        hashes.push(r.stats.image_hash.clone());
    }
    if hashes[0] != hashes[1] {
        return Err(format!("kernels disagree: {hashes:?}"));
    }
    Ok("rendered")
}

/// Runs one check; counts its kind of success, or returns why it failed (a panic included).
fn tally_outcome(
    tally: &mut std::collections::BTreeMap<&'static str, u64>,
    check: impl FnOnce() -> Result<&'static str, String> + std::panic::UnwindSafe,
) -> Option<String> {
    match std::panic::catch_unwind(check) {
        Ok(Ok(kind)) => {
            *tally.entry(kind).or_default() += 1;
            None
        }
        Ok(Err(why)) => Some(why),
        Err(_) => Some("panic".to_string()),
    }
}

/// The process's peak resident memory, when it bounds the fuzzer's: in a
/// dedicated run (`RTOW_FUZZ_SECS` set, `fuzz::` alone, as `.ci/run` runs it),
/// not beside the suite's other tests, whose own peak (about 620 MiB) it
/// would measure.
fn peak_rss_kib() -> Option<u64> {
    std::env::var_os("RTOW_FUZZ_SECS")?;
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Fails the run: writes the failing input to `name` in the tests' scratch
/// folder (to be replayed) and panics with `what`, the file's path and, for
/// text (`show`), its first 4,000 bytes.
fn fail(input: &[u8], name: &str, what: String, show: bool) -> ! {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::write(&path, input);
    let text = if show { format!(":\n{}", String::from_utf8_lossy(&input[..input.len().min(4000)])) } else { String::new() };
    panic!("{what}\ninput written to {}{text}", path.display());
}

/// How long each target runs (`RTOW_FUZZ_SECS`, 3 s) and from which seed
/// (`RTOW_FUZZ_SEED`, the clock's nanoseconds).
fn run_settings() -> (u64, u64) {
    let secs = std::env::var("RTOW_FUZZ_SECS").ok().and_then(|v| v.parse().ok()).unwrap_or(3);
    let seed = std::env::var("RTOW_FUZZ_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or_else(|| {
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(1, |d| d.as_nanos() as u64)
    });
    (secs, seed)
}

#[test]
fn fuzz_the_input_path() {
    let (secs, seed) = run_settings();
    let corpus = corpus();
    let mut rng = Rng(seed | 1);
    let start = Instant::now();
    let mut tally: std::collections::BTreeMap<&str, u64> = Default::default();
    let mut execs = 0u64;
    // Every corpus entry once, unchanged: they must render.
    for (bytes, f) in &corpus {
        assert_eq!(check(bytes, *f), Ok("rendered"), "{}", String::from_utf8_lossy(bytes));
    }
    while start.elapsed() < Duration::from_secs(secs) {
        let (input, format) = if rng.below(4) == 0 {
            generated(&mut rng)
        } else {
            let (base, f) = rng.pick(&corpus);
            let mut data = base.clone();
            for _ in 0..1 + rng.below(4) {
                mutate(&mut rng, &mut data, &corpus);
            }
            (data, *f)
        };
        let failure = tally_outcome(&mut tally, || check(&input, format));
        if let Some(why) = failure {
            let ext = if format == Format::Json { "json" } else { "toml" };
            fail(&input, &format!("fuzz-failure.{ext}"), format!("fuzz seed {seed}, execution {execs}: {why}"), true);
        }
        execs += 1;
    }
    let rss = peak_rss_kib();
    println!(
        "fuzz: seed {seed}, {execs} executions in {:.1} s: {tally:?}, peak RSS {rss:?} KiB",
        start.elapsed().as_secs_f64()
    );
    if let Some(kib) = rss {
        assert!(kib < 1 << 20, "peak RSS {kib} KiB: memory is not bounded");
    }
    assert!(execs > 0);
}

/// A real baseline (two kernels, two runs each) and the report it is compared with.
fn baseline_corpus() -> (Vec<u8>, rtow::instruments::bench::BenchReport, rtow::Settings, usize) {
    use rtow::instruments::bench::{self, BenchConfig, Gate};
    let scene = scene::preset("ch08-fuzz").unwrap();
    let o = Overrides { width: Some(12), height: Some(7), spp: Some(2), max_depth: Some(5), ..Default::default() };
    let job = Job::new(&scene, &o, &RenderOptions { threads: Some(1), ..Default::default() }).unwrap();
    let cfg = BenchConfig::new(&job, &[KernelChoice::Scalar, KernelChoice::Simd8], 2, 5.0, Gate::Time).unwrap();
    let report = bench::run(&cfg, "ch08-fuzz", |_, _, _| {}).unwrap();
    (report.to_json().into_bytes(), report, *job.settings(), job.threads())
}

/// One mutated baseline through load, check and compare; `Err` describes a broken promise.
fn check_baseline(
    bytes: &[u8],
    report: &rtow::instruments::bench::BenchReport,
    s: &rtow::Settings,
    threads: usize,
) -> Result<&'static str, String> {
    use rtow::instruments::bench::{compare, Baseline, Gate};
    let b = match Baseline::from_bytes(bytes, Path::new("fuzz-baseline.json")) {
        Ok(b) => b,
        Err(e) => return refused(e),
    };
    if let Err(e) = b.check("ch08-fuzz", s, threads, &[KernelChoice::Scalar, KernelChoice::Simd8]) {
        return refused(e);
    }
    for gate in [Gate::Time, Gate::Work] {
        for c in compare(report, &b, 5.0, gate) {
            let ci_ok = c.change_ci.is_none_or(|ci| ci.lo.is_finite() && ci.hi.is_finite() && ci.lo <= ci.hi);
            if !(c.change_percent.is_finite() && c.baseline_mrays > 0.0 && ci_ok) {
                return Err(format!("a comparison with impossible figures: {c:?}"));
            }
        }
    }
    Ok("compared")
}

#[test]
fn fuzz_the_baselines() {
    let (secs, seed) = run_settings();
    let (base, report, settings, threads) = baseline_corpus();
    assert_eq!(check_baseline(&base, &report, &settings, threads), Ok("compared"));
    let corpus = vec![(base.clone(), Format::Json)];
    let mut rng = Rng(seed | 1);
    let start = Instant::now();
    let mut tally: std::collections::BTreeMap<&str, u64> = Default::default();
    let mut execs = 0u64;
    while start.elapsed() < Duration::from_secs(secs) {
        let mut data = base.clone();
        for _ in 0..1 + rng.below(4) {
            mutate(&mut rng, &mut data, &corpus);
        }
        let failure = tally_outcome(&mut tally, || check_baseline(&data, &report, &settings, threads));
        if let Some(why) = failure {
            fail(&data, "fuzz-failure-baseline.json", format!("fuzz seed {seed}, baseline execution {execs}: {why}"), true);
        }
        execs += 1;
    }
    println!("fuzz baselines: seed {seed}, {execs} executions in {:.1} s: {tally:?}", start.elapsed().as_secs_f64());
    assert!(tally.get("refused").is_some_and(|&n| n > 0), "no mutation was refused: {tally:?}");
}

/// Real partial films of one small render: two shards by samples, two by
/// rows, and a whole render of half the samples (to resume); the job that
/// resumes it.
struct Films {
    dir: tempfile::TempDir,
    parts: Vec<(&'static str, Vec<u8>)>,
    source: scene::SceneSource,
    resume_job: Job,
}

fn film_corpus() -> Films {
    use rtow::shard::{self, FilmRequest, Split, SplitKind};
    let scene = scene::preset("final").unwrap();
    let o =
        |spp| Overrides { width: Some(8), height: Some(6), spp: Some(spp), max_depth: Some(6), ..Default::default() };
    let opts = RenderOptions { threads: Some(1), ..Default::default() };
    let job = Job::new(&scene, &o(4), &opts).unwrap();
    let film = |split| shard::render_part(&FilmRequest::new(&job, split, None).unwrap(), None).unwrap().1.to_bytes();
    let parts = vec![
        ("s1.rtfilm", film(Split { kind: SplitKind::Samples, shard: 1, of: 2 })),
        ("s2.rtfilm", film(Split { kind: SplitKind::Samples, shard: 2, of: 2 })),
        ("r1.rtfilm", film(Split { kind: SplitKind::Rows, shard: 1, of: 2 })),
        ("r2.rtfilm", film(Split { kind: SplitKind::Rows, shard: 2, of: 2 })),
        ("whole.rtfilm", film(Split::WHOLE)),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in &parts {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    let resume_job = Job::new(&scene, &o(8), &opts).unwrap();
    Films { dir, parts, source: scene::SceneSource::built(scene, "final"), resume_job }
}

/// Header fields edited to values that have broken readers before.
const FILM_FIELDS: &[&str] = &[
    "width",
    "height",
    "spp",
    "samples",
    "rows",
    "split",
    "sum_bytes",
    "scene_bytes",
    "fraction_bits",
    "film_exponent",
    "moments",
    "counters",
    "settings",
    "scene_hash",
    "key",
];

const FILM_VALUES: &[&str] = &[
    "0",
    "1",
    "2",
    "3",
    "7",
    "-1",
    "65535",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "1e300",
    "true",
    "null",
    "\"\"",
    "\"x\\ny\"",
    "[0, 0]",
    "[0, 4294967295]",
    "[4294967295, 0]",
    "{\"kind\": \"samples\", \"shard\": 2, \"of\": 2}",
    "{\"kind\": \"rows\", \"shard\": 1, \"of\": 4294967295}",
    "{\"rays\": 0, \"samples\": 0, \"rejected_samples\": 0}",
    "{\"seed\": \"0\"}",
];

/// A film with its header replaced by `text` (and its length fixed).
fn with_header(film: &[u8], text: &[u8]) -> Vec<u8> {
    let hlen = u32::from_le_bytes(film[12..16].try_into().unwrap()) as usize;
    let mut out = film[..12].to_vec();
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(text);
    out.extend_from_slice(film.get(16 + hlen..).unwrap_or_default());
    out
}

/// One random mutation of a film: a bit flip, a cut, bytes inserted, a
/// header field or a byte of the data changed; half the time the checksum is
/// recomputed (a film a bug writes), so that the checks behind it are reached.
fn mutate_film(rng: &mut Rng, film: &mut Vec<u8>, corpus: &[(Vec<u8>, Format)]) {
    let n = film.len();
    let hlen = film.get(12..16).map_or(0, |b| u32::from_le_bytes(b.try_into().unwrap()) as usize);
    match rng.below(7) {
        0 if n > 0 => {
            let i = rng.below(n);
            film[i] ^= 1 << rng.below(8);
        }
        1 => film.truncate(rng.below(n + 1)),
        2 => {
            let i = rng.below(n + 1);
            let len = rng.below(64);
            film.splice(i..i, (0..len).map(|_| rng.next() as u8));
        }
        3 | 4 if n >= 16 + hlen => {
            // A header field set to an extreme value, or the header's text mutated like a scene's.
            let text = film[16..16 + hlen].to_vec();
            let new = match serde_json::from_slice::<serde_json::Value>(&text) {
                Ok(mut h) if rng.below(2) == 0 => {
                    let text: &&str = rng.pick(FILM_VALUES);
                    let v: serde_json::Value = serde_json::from_str(text).unwrap();
                    h[*rng.pick(FILM_FIELDS)] = v;
                    serde_json::to_vec(&h).unwrap()
                }
                _ => {
                    let mut t = text;
                    mutate(rng, &mut t, corpus);
                    t
                }
            };
            *film = with_header(film, &new);
        }
        5 if n > 16 + hlen + 4 => {
            // A byte of the scene or the data.
            let i = 16 + hlen + rng.below(n - 16 - hlen - 4);
            film[i] = rng.next() as u8;
        }
        _ => {
            // The version.
            if n >= 12 {
                film[8..12].copy_from_slice(&(rng.below(4) as u32).to_le_bytes());
            }
        }
    }
    if rng.below(2) == 0 && film.len() >= 4 {
        let body = film.len() - 4;
        let crc = crc32fast::hash(&film[..body]);
        film[body..].copy_from_slice(&crc.to_le_bytes());
    }
}

/// One mutated film merged with the other shard of its split, or resumed;
/// `Err` describes a broken promise.
fn check_film(films: &Films, which: usize, bytes: &[u8]) -> Result<&'static str, String> {
    use rtow::files::{self, RenderFiles, RenderRequest};
    use rtow::shard::{Split, Verify};
    let d = films.dir.path();
    std::fs::write(d.join("fuzz.rtfilm"), bytes).unwrap();
    let t = Instant::now();
    let out = RenderFiles { output: d.join("out.png"), ..Default::default() };
    let verify = Verify { pixels: 8, seed: 1 };
    let result = if films.parts[which].0 == "whole.rtfilm" {
        let req = RenderRequest {
            source: &films.source,
            job: &films.resume_job,
            split: Split::WHOLE,
            resume: Some(d.join("fuzz.rtfilm")),
            verify,
            files: out,
            on_rejected: rtow::OnRejected::Warn,
            rounds: Default::default(),
            crop: None,
            aov: Default::default(),
        };
        files::render_to_files(&req, None).map(|_| "resumed")
    } else {
        // The other shard of the same split.
        let other = films.parts[which ^ 1].0;
        files::merge_to_files(&[d.join("fuzz.rtfilm"), d.join(other)], &out, verify, rtow::OnRejected::Warn)
            .map(|_| "merged")
    };
    if t.elapsed() > Duration::from_secs(10) {
        return Err(format!("took {:?}", t.elapsed()));
    }
    match result {
        Ok(kind) => Ok(kind),
        Err(e) => refused(e),
    }
}

#[test]
fn fuzz_the_films() {
    let (secs, seed) = run_settings();
    let films = film_corpus();
    for (i, (name, bytes)) in films.parts.iter().enumerate() {
        let ok = if *name == "whole.rtfilm" { "resumed" } else { "merged" };
        assert_eq!(check_film(&films, i, bytes), Ok(ok), "{name}");
    }
    let corpus: Vec<(Vec<u8>, Format)> = films.parts.iter().map(|(_, b)| (b.clone(), Format::Json)).collect();
    let mut rng = Rng(seed | 1);
    let start = Instant::now();
    let mut tally: std::collections::BTreeMap<&str, u64> = Default::default();
    let mut execs = 0u64;
    while start.elapsed() < Duration::from_secs(secs) {
        let which = rng.below(films.parts.len());
        let mut data = films.parts[which].1.clone();
        for _ in 0..1 + rng.below(3) {
            mutate_film(&mut rng, &mut data, &corpus);
        }
        let failure = tally_outcome(&mut tally, || check_film(&films, which, &data));
        if let Some(why) = failure {
            let what = format!("fuzz seed {seed}, film execution {execs} ({}): {why}", films.parts[which].0);
            fail(&data, "fuzz-failure.rtfilm", what, false);
        }
        execs += 1;
    }
    println!("fuzz films: seed {seed}, {execs} executions in {:.1} s: {tally:?}", start.elapsed().as_secs_f64());
    assert!(tally.get("refused").is_some_and(|&n| n > 0), "no mutation was refused: {tally:?}");
}
