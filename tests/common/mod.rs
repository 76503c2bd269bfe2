//! Helpers shared by the integration tests: jobs and renders through the
//! library, and the `rtow` binary run as a user runs it.
#![allow(dead_code)]

pub mod stats;

use rtow::scene::{Material, Texture};
use rtow::{render, AccelChoice, Image, Job, KernelChoice, Overrides, RenderOptions, Rendered, Scene, Settings};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

/// A folder of image textures generated for the tests (rtow ships none):
/// `earthmap.jpg`, a 64 x 32 JPEG of gradients, the name the `nw-earth`
/// preset reads from `RTOW_IMAGES`. It lives in cargo's folder for the
/// integration tests' files (under `target/`), so no test run leaves a
/// folder behind in the system's temporary folder; each test process writes
/// the same map under a name of its own, then renames it into place, so test
/// processes running at once each read a whole file.
pub fn test_images() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("test-images");
        std::fs::create_dir_all(&dir).expect("the tests' image folder");
        let map =
            image::RgbImage::from_fn(64, 32, |x, y| image::Rgb([(x * 4) as u8, (y * 8) as u8, ((x ^ y) * 7) as u8]));
        let part = dir.join(format!("earthmap.{}.jpg", std::process::id()));
        map.save(&part).expect("the test map is written");
        std::fs::rename(&part, dir.join("earthmap.jpg")).expect("the test map is put in place");
        dir
    })
}

/// `scene` with every image texture reading the generated map
/// ([`test_images`]) by its absolute name, so that it renders anywhere.
pub fn self_contained(scene: &Scene) -> Scene {
    let file = test_images().join("earthmap.jpg").to_string_lossy().into_owned();
    let mut s = scene.clone();
    let fix = |m: &mut Material| {
        if let Material::Lambertian { albedo: Texture::Image { file: f } } = m {
            f.clone_from(&file);
        }
    };
    s.spheres.iter_mut().for_each(|x| fix(&mut x.material));
    s.quads.iter_mut().for_each(|x| fix(&mut x.material));
    s.boxes.iter_mut().for_each(|x| fix(&mut x.material));
    for g in &mut s.groups {
        g.spheres.iter_mut().for_each(|x| fix(&mut x.material));
        g.quads.iter_mut().for_each(|x| fix(&mut x.material));
        g.boxes.iter_mut().for_each(|x| fix(&mut x.material));
    }
    s
}

/// Exactly these settings (Sobol sampler, rtow's default).
pub fn settings(width: u32, height: u32, spp: u32, max_depth: u32, seed: u64) -> Settings {
    Settings { width, height, spp, max_depth, seed, ..Settings::default() }
}

/// The job of `scene` with exactly the settings `s`.
pub fn job(scene: &Scene, s: Settings, opts: RenderOptions) -> Job {
    Job::new(scene, &Overrides::from(s), &opts).expect("a valid job")
}

pub fn render_with(scene: &Scene, s: Settings, kernel: KernelChoice, threads: usize, tile: u32) -> Rendered {
    render_accel(scene, s, kernel, threads, tile, AccelChoice::Auto)
}

pub fn render_accel(
    scene: &Scene,
    s: Settings,
    kernel: KernelChoice,
    threads: usize,
    tile: u32,
    accel: AccelChoice,
) -> Rendered {
    let opts = RenderOptions { kernel, threads: Some(threads), tile, accel, ..Default::default() };
    render(&job(scene, s, opts), None).expect("render")
}

pub fn image(scene: &Scene, s: Settings, kernel: KernelChoice) -> Image {
    render_with(scene, s, kernel, 2, 16).image
}

/// Asserts bit-identical images, naming the first differing pixel.
pub fn assert_identical(a: &Image, b: &Image, what: &str) {
    assert_eq!((a.width, a.height), (b.width, b.height), "{what}: sizes differ");
    for (i, (p, q)) in a.data.iter().zip(&b.data).enumerate() {
        let (pb, qb) = (p.map(f32::to_bits), q.map(f32::to_bits));
        assert!(pb == qb, "{what}: pixel ({}, {}) differs: {p:?} vs {q:?}", i as u32 % a.width, i as u32 / a.width);
    }
}

/// The `rtow` binary these tests were built with.
pub const BIN: &str = env!("CARGO_BIN_EXE_rtow");

/// What a run of `rtow` did.
pub struct Run {
    /// The exit status as a shell reports it: the code, or 128 + the signal that killed it.
    pub code: i32,
    /// The signal that killed it, if one did.
    pub signal: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

impl From<Output> for Run {
    fn from(out: Output) -> Run {
        use std::os::unix::process::ExitStatusExt;
        let signal = out.status.signal();
        Run {
            code: out.status.code().unwrap_or_else(|| 128 + signal.unwrap_or(0)),
            signal,
            stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
            stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        }
    }
}

impl Run {
    /// Asserts exit status 0.
    pub fn ok(&self) -> &Run {
        assert_eq!(self.code, 0, "exit status {} (stderr: {})", self.code, self.stderr);
        self
    }
}

/// Runs `rtow args...` in `dir`.
pub fn rtow(dir: &Path, args: &[&str]) -> Run {
    rtow_env(dir, args, &[])
}

/// Runs `rtow args...` in `dir` with extra environment variables.
pub fn rtow_env(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Run {
    Command::new(BIN).args(args).envs(env.iter().copied()).current_dir(dir).output().expect("rtow runs").into()
}

/// Asserts that the run failed with `code` and said so in exactly one
/// `error: ...` line on stderr, without a panic and with nothing on stdout;
/// returns that line.
pub fn failure(r: &Run, code: i32, what: &str) -> String {
    assert!(!r.stderr.contains("panicked"), "{what}: panic: {}", r.stderr);
    assert_eq!(r.code, code, "{what}: exit status (stderr: {})", r.stderr);
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{what}: stderr is not one line: {:?}", r.stderr);
    assert!(lines[0].starts_with("error: "), "{what}: {:?}", lines[0]);
    assert!(r.stdout.is_empty(), "{what}: stdout: {:?}", r.stdout);
    lines[0].to_string()
}

/// The names in `dir`, sorted (temporary files included: they start with `.rtow-`).
pub fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// The settings a scene asks for (its render table, else rtow's defaults).
pub fn scene_settings(scene: &Scene) -> Settings {
    Overrides::default().resolve(scene, &scene.flatten())
}

/// A scene file's text read and checked as a render of it is: parsed, then
/// resolved into a job (which checks every value); the first error.
pub fn read_and_check(text: &str, format: rtow::scene::Format, file: &str) -> rtow::Result<Scene> {
    let scene = rtow::scene::scene_from_str(text, format, Path::new(file))?;
    Job::new(&scene, &Overrides::default(), &RenderOptions::default())?;
    Ok(scene)
}
