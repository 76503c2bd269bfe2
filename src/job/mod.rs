//! The bridge: a render job, resolved once.
//!
//! A [`Job`] reads both sides, the user's (a [`Scene`] with its render
//! table, plus [`Overrides`] and [`RenderOptions`]) and the kernels'
//! ([`Plan`], [`Prepared`]), so that neither side imports the other:
//!
//! ```text
//! scene + overrides + options --Job::new--> settings (resolved), kernel, plan (validated, once)
//!                              --prepared--> Prepared: SoA spheres, material tables, camera, BVH
//! ```
//!
//! Everything downstream reads the job: the render driver, shards and
//! resume, `--explain`, the statistics and the instruments. Nothing checks
//! again: `Job::new` is the one place where the scene, the settings and the
//! options are validated and the plan is decided. The scene is laid out for
//! the kernels the first time a render asks for it ([`Job::prepared`]), so a
//! caller can check its outputs between resolving and rendering.

mod images;
mod meshes;
mod prepare;

pub(crate) use images::Images;
pub use images::{images_folder, IMAGES_ENV};
// `rtow diff` checks the PNGs it reads as image textures are checked.
pub(crate) use images::png_chunks;

use crate::camera::PreparedCamera;
use crate::choice::{AccelChoice, EstimatorChoice, KernelChoice, Mode};
use crate::error::{Error, Result};
use crate::estimator::{Adaptive, Estimator, Roulette};
use crate::film::part::{Fnv1a, Identity};
use crate::kernel::Kernel;
use crate::limits::{self, MAX_TILE};
use crate::plan::{Plan, Prepared};
use crate::sampling::Sampler;
use crate::scene::{Flat, Scene, SceneSource};
use crate::settings::Settings;
use std::path::Path;
use std::sync::{Arc, OnceLock};
use std::time::Instant;

/// Tile edge in pixels by default (tiles are the unit of parallel work).
pub const DEFAULT_TILE: u32 = 16;

/// Values that replace the scene's render table (flags, or a library caller's choices).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Overrides {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub seed: Option<u64>,
    pub sampler: Option<Sampler>,
    /// How paths choose directions at diffuse vertices.
    pub estimator: Option<EstimatorChoice>,
    /// The book's settings: the scene's `render.book` (The Next Week's
    /// presets), else book one's final settings (1200x675, 500 spp, depth
    /// 50); values given explicitly still win.
    pub book: bool,
}

impl Overrides {
    /// The settings of `scene` (its render table), with these overrides on
    /// top: an override wins over `--book`, which wins over the table, which
    /// wins over rtow's defaults (the estimator's default is the scene's,
    /// [`Scene::default_estimator`], read from `flat`, the scene's
    /// [`Scene::flatten`]).
    pub fn resolve(&self, scene: &Scene, flat: &Flat) -> Settings {
        let table = &scene.render;
        let d = Settings::default();
        let mut s = Settings {
            width: table.width.unwrap_or(d.width),
            height: table.height.unwrap_or(d.height),
            spp: table.samples_per_pixel.unwrap_or(d.spp),
            max_depth: table.max_depth.unwrap_or(d.max_depth),
            seed: table.seed.unwrap_or(d.seed),
            sampler: table.sampler.unwrap_or(d.sampler),
            estimator: match (self.estimator, table.estimator) {
                (Some(e), _) | (None, Some(e)) => e,
                (None, None) => scene.default_estimator(flat),
            },
        };
        if self.book {
            (s.width, s.height, s.spp, s.max_depth) = match table.book {
                Some(b) => (b.width, b.height, b.samples_per_pixel, b.max_depth),
                None => Settings::BOOK,
            };
        }
        s.width = self.width.unwrap_or(s.width);
        s.height = self.height.unwrap_or(s.height);
        s.spp = self.spp.unwrap_or(s.spp);
        s.max_depth = self.max_depth.unwrap_or(s.max_depth);
        s.seed = self.seed.unwrap_or(s.seed);
        s.sampler = self.sampler.unwrap_or(s.sampler);
        s
    }
}

/// Exactly these settings, whatever the scene's table says.
impl Overrides {
    /// These overrides, with `base`'s values where these have none.
    pub fn or(&self, base: &Overrides) -> Overrides {
        Overrides {
            width: self.width.or(base.width),
            height: self.height.or(base.height),
            spp: self.spp.or(base.spp),
            max_depth: self.max_depth.or(base.max_depth),
            seed: self.seed.or(base.seed),
            sampler: self.sampler.or(base.sampler),
            estimator: self.estimator.or(base.estimator),
            book: self.book || base.book,
        }
    }
}

impl From<Settings> for Overrides {
    fn from(s: Settings) -> Overrides {
        Overrides {
            width: Some(s.width),
            height: Some(s.height),
            spp: Some(s.spp),
            max_depth: Some(s.max_depth),
            seed: Some(s.seed),
            sampler: Some(s.sampler),
            estimator: Some(s.estimator),
            book: false,
        }
    }
}

/// How to render. The kernel, threads, tile size and accelerator never change
/// the image; Russian roulette and adaptive sampling change its noise (not
/// its expected value) and are off by default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    pub kernel: KernelChoice,
    /// Worker threads; `None` = one per core.
    pub threads: Option<usize>,
    /// Tile edge in pixels (tiles are the unit of parallel work), at most [`MAX_TILE`].
    pub tile: u32,
    /// Closest-hit search: brute force, BVH, or chosen by the plan.
    pub accel: AccelChoice,
    pub roulette: Option<Roulette>,
    /// Pixels stop taking samples once their relative error is low enough.
    pub adaptive: Option<Adaptive>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            kernel: KernelChoice::Simd,
            threads: None,
            tile: DEFAULT_TILE,
            accel: AccelChoice::Auto,
            roulette: None,
            adaptive: None,
        }
    }
}

impl RenderOptions {
    /// Every option in range; the error names it (roulette and adaptive
    /// sampling are valid by construction).
    fn validate(&self) -> Result<()> {
        limits::check_threads(self.threads)?;
        if !(1..=MAX_TILE).contains(&self.tile) {
            return Err(Error::invalid(
                "tile",
                format!(
                    "must be between 1 and {MAX_TILE} pixels (a tile's paths must fit one wavefront workspace), got {}",
                    self.tile
                ),
            ));
        }
        Ok(())
    }

    /// The options that act on `settings`, and a warning for each one asked
    /// for that would not: adaptive sampling decides first after `min_spp`
    /// samples, so with `spp <= min_spp` it never stops a pixel and is off
    /// (the image is the one without it, bit for bit).
    fn effective(&self, settings: &Settings) -> (RenderOptions, Vec<Error>) {
        let mut run = *self;
        let mut warnings = Vec::new();
        if let Some(a) = self.adaptive {
            if settings.spp <= a.min_spp() {
                run.adaptive = None;
                warnings.push(Error::invalid(
                    "adaptive.min_spp",
                    format!(
                        "adaptive sampling decides first after {} samples per pixel, but this render takes only {}: \
                         it is off (the image is the one without it); ask for more than {} samples or decide earlier",
                        a.min_spp(),
                        settings.spp,
                        a.min_spp()
                    ),
                ));
            }
        }
        (run, warnings)
    }
}

/// A render job: a scene with its settings, options, kernel and plan,
/// resolved and validated once. Cheap to make (no geometry is built until
/// the first render asks for it); read by every render of it.
#[derive(Debug)]
pub struct Job {
    scene: Scene,
    scene_hash: u64,
    settings: Settings,
    /// The options that run (see [`Job::warnings`]) and those asked for.
    options: RenderOptions,
    requested: RenderOptions,
    warnings: Vec<Error>,
    kernel: Kernel,
    plan: Plan,
    /// The image textures' files, read when the job was resolved.
    images: Arc<Images>,
    /// The OBJ files' names and the hashes of their bytes (their meshes are
    /// in `flat`).
    mesh_files: Arc<MeshFiles>,
    /// The scene flattened into world-space primitives, once per scene
    /// (shared by the jobs derived from this one).
    flat: Arc<Flat>,
    /// The scene laid out for the kernels, built on first use; shared by a
    /// derived job whose settings, plan and estimator are this one's (another
    /// kernel, say), which then builds no tree of its own.
    prepared: Arc<OnceLock<(Prepared, f64)>>,
}

/// The OBJ files a job read: each name the scene gives, with the hash of the
/// file's bytes.
type MeshFiles = Vec<(String, u64)>;

/// What a derived job takes from the job it derives from instead of
/// reading or computing it again.
#[derive(Default)]
struct Known {
    images: Option<Arc<Images>>,
    /// The scene flattened, with its OBJ files' names and hashes.
    flat: Option<(Arc<Flat>, Arc<MeshFiles>)>,
}

impl Job {
    /// Resolves `scene` with `overrides` and `options`: checks the scene,
    /// the settings and the options (the first error names the field), and
    /// decides the plan.
    pub fn new(scene: &Scene, overrides: &Overrides, options: &RenderOptions) -> Result<Job> {
        Job::resolve(scene, None, overrides, options)
    }

    /// [`Job::new`] for a scene from a file or a preset: errors about the
    /// scene's values name its file.
    pub fn from_source(source: &SceneSource, overrides: &Overrides, options: &RenderOptions) -> Result<Job> {
        Job::resolve(&source.scene, source.file.as_deref(), overrides, options)
    }

    /// The same scene and options with other overrides (the instruments vary
    /// the sample count, the seed or the sampler).
    pub fn with_overrides(&self, overrides: &Overrides) -> Result<Job> {
        self.with(overrides, &self.requested)
    }

    /// The same scene and settings with other options (another kernel, say).
    pub fn with_options(&self, options: &RenderOptions) -> Result<Job> {
        self.with(&Overrides::from(self.settings), options)
    }

    /// The same scene (and its images, read once) with other overrides and options.
    pub fn with(&self, overrides: &Overrides, options: &RenderOptions) -> Result<Job> {
        let known =
            Known { images: Some(self.images.clone()), flat: Some((self.flat.clone(), self.mesh_files.clone())) };
        let mut job = Job::resolve_with(&self.scene, None, known, overrides, options)?;
        if (job.settings, &job.plan, job.estimator()) == (self.settings, &self.plan, self.estimator()) {
            job.prepared = self.prepared.clone();
        }
        Ok(job)
    }

    fn resolve(scene: &Scene, origin: Option<&Path>, overrides: &Overrides, options: &RenderOptions) -> Result<Job> {
        Job::resolve_with(scene, origin, Known::default(), overrides, options)
    }

    /// Resolves the job; reads the scene's images (beside `origin`, else in
    /// `RTOW_IMAGES`) and flattens it unless `known` already holds them.
    fn resolve_with(
        scene: &Scene,
        origin: Option<&Path>,
        known: Known,
        overrides: &Overrides,
        options: &RenderOptions,
    ) -> Result<Job> {
        let in_file = |e: Error| match origin {
            Some(path) => Error::InFile { path: path.to_path_buf(), error: Box::new(e) },
            None => e,
        };
        scene.validate().map_err(in_file)?;
        let view = prepare::view(&scene.camera);
        if scene.mode != Mode::Gradient {
            PreparedCamera::check(&view).map_err(in_file)?;
        }
        // The one flattening of the scene, its OBJ files read first: the
        // default estimator, the plan and the layout for the kernels all read it.
        let (flat, mesh_files) = match known.flat {
            Some(known) => known,
            None => {
                let objs = meshes::load(scene, origin).map_err(in_file)?;
                scene.validate_obj_meshes(&objs).map_err(in_file)?;
                let files = objs.iter().map(|m| (m.name.clone(), m.hash)).collect();
                (Arc::new(scene.flatten_with(&objs)), Arc::new(files))
            }
        };
        let settings = overrides.resolve(scene, &flat);
        settings.validate()?;
        options.validate()?;
        let requested = *options;
        let (options, mut warnings) = options.effective(&settings);
        let plan = prepare::plan(scene, &flat, &settings, options.accel);
        check_estimator(scene, &settings, &plan, &mut warnings)?;
        let images = match known.images {
            Some(i) => i,
            None => Arc::new(Images::load(scene, origin).map_err(in_file)?),
        };
        let mut hash = Fnv1a::default();
        // Writing into a hash cannot fail, and every scene value serializes.
        serde_json::to_writer(&mut hash, scene).expect("a scene serializes");
        Ok(Job {
            scene: scene.clone(),
            scene_hash: hash.0,
            settings,
            options,
            requested,
            warnings,
            kernel: Kernel::resolve(options.kernel),
            plan,
            images,
            mesh_files,
            flat,
            prepared: Arc::new(OnceLock::new()),
        })
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scene's canonical JSON: the bytes [`Job::scene_hash`] hashes,
    /// which a partial film embeds (so that a merge can render its pixels again).
    pub fn scene_json(&self) -> Vec<u8> {
        serde_json::to_vec(&self.scene).expect("a scene serializes")
    }

    /// The job of a scene given as canonical JSON (a partial film's embedded
    /// scene, read from `origin`), with `overrides` and `options`.
    pub fn from_scene_json(json: &[u8], origin: &Path, overrides: &Overrides, options: &RenderOptions) -> Result<Job> {
        // Not `scene_from_bytes`: the embedded scene is bounded by the film's
        // own limit (`film::part::MAX_SCENE_BYTES`), not a scene file's.
        let text = std::str::from_utf8(json)
            .map_err(|e| Error::Input(format!("{}: the embedded scene is not UTF-8: {e}", origin.display())))?;
        let scene = crate::scene::scene_from_str(text, crate::scene::Format::Json, origin)?;
        Job::resolve(&scene, Some(origin), overrides, options)
    }

    /// A hash of the scene's canonical JSON (what the film identity and the statistics name).
    pub fn scene_hash(&self) -> u64 {
        self.scene_hash
    }

    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The options that run: those asked for, less any that cannot act
    /// on these settings (each one named by [`Job::warnings`]).
    pub fn options(&self) -> &RenderOptions {
        &self.options
    }

    /// What was asked for but does not run, and why (an option that has no
    /// effect on these settings): a setting's name and a message, as
    /// [`Error::Invalid`], for the caller to show as a warning. The
    /// statistics report what ran.
    pub fn warnings(&self) -> &[Error] {
        &self.warnings
    }

    /// The worker threads a render of this job runs on (`None` in the
    /// options: one per core, or as `RAYON_NUM_THREADS` says).
    pub fn threads(&self) -> usize {
        self.options.threads.unwrap_or_else(rayon::current_num_threads)
    }

    /// The kernel that runs (`simd` resolved to this build's lane width).
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    pub fn mode(&self) -> Mode {
        self.scene.mode
    }

    /// The estimator's options as the kernels read them.
    pub fn estimator(&self) -> Estimator {
        Estimator { roulette: self.options.roulette, adaptive: self.options.adaptive }
    }

    /// The PNG gamma `rtow render` uses: 2 for path traced scenes, 1 for the debug chapters.
    pub fn default_gamma(&self) -> f32 {
        self.scene.mode.default_gamma()
    }

    /// What the plan decided, for people (`rtow render --explain`).
    pub fn explain(&self) -> String {
        self.plan.explain()
    }

    /// The scene laid out for the kernels (built on first use, then shared by
    /// every render of this job).
    pub fn prepared(&self) -> &Prepared {
        &self.prepared_timed().0
    }

    /// Seconds it took to lay the scene out (0 until the first render).
    pub fn prepare_seconds(&self) -> f64 {
        self.prepared.get().map_or(0.0, |p| p.1)
    }

    fn prepared_timed(&self) -> &(Prepared, f64) {
        self.prepared.get_or_init(|| {
            let t = Instant::now();
            let p = prepare::prepare(
                &self.scene,
                &self.flat,
                &self.images,
                self.settings,
                self.plan.clone(),
                self.estimator(),
            );
            (p, t.elapsed().as_secs_f64())
        })
    }

    /// What makes this render's image: the scene and every setting that
    /// changes it. The kernel, lane width, threads, tile size and accelerator
    /// do not change the image and are not part of it; nor is the sample count
    /// (kept apart, see [`Identity`]) except where it changes the samples
    /// themselves (one sample per pixel goes through the pixel centres).
    pub fn identity(&self) -> Identity {
        let s = &self.settings;
        let mut map = std::collections::BTreeMap::new();
        let mut set = |k: &str, v: String| {
            map.insert(k.to_string(), v);
        };
        // The mode is the scene's (already in its hash); merge takes the PNG gamma from it.
        set("mode", self.scene.mode.name().to_string());
        set("max_depth", s.max_depth.to_string());
        set("seed", s.seed.to_string());
        set("pixel_jitter", self.plan.jitter.to_string());
        set("sampler", s.sampler.name().to_string());
        // The default estimator is not written: every identity made before
        // estimators could be chosen stays the same.
        if s.estimator != EstimatorChoice::Bsdf {
            set("estimator", s.estimator.name().to_string());
        }
        set("russian_roulette", Roulette::describe(self.options.roulette));
        set("adaptive", Adaptive::describe(self.options.adaptive));
        // The bytes of the image textures (the scene names only their files).
        if !self.images.list.is_empty() {
            let list: Vec<String> = self.images.list.iter().map(|i| format!("{:016x} {}", i.hash, i.name)).collect();
            set("images", list.join(", "));
        }
        // The bytes of the OBJ files, likewise.
        if !self.mesh_files.is_empty() {
            let list: Vec<String> = self.mesh_files.iter().map(|(name, hash)| format!("{hash:016x} {name}")).collect();
            set("meshes", list.join(", "));
        }
        Identity { scene_hash: self.scene_hash, width: s.width, height: s.height, settings: map }
    }
}

/// Refuses an estimator that samples more shapes than it can (the error
/// names the setting), and warns of one with nothing to sample.
fn check_estimator(scene: &Scene, settings: &Settings, plan: &Plan, warnings: &mut Vec<Error>) -> Result<()> {
    if plan.sample_toward > limits::MAX_SAMPLED_SHAPES {
        return Err(Error::invalid(
            "estimator",
            format!(
                "the book estimator samples toward at most {} shapes, and this scene has {} lights; list the ones \
                 to sample toward in the scene's sample_toward, or use --estimator bsdf",
                limits::MAX_SAMPLED_SHAPES,
                plan.sample_toward
            ),
        ));
    }
    if plan.nee > limits::MAX_SAMPLED_SHAPES {
        return Err(Error::invalid(
            "estimator",
            format!(
                "the nee-mis estimator samples at most {} lights, and this scene has {}; use --estimator book \
                 with a sample_toward list of the important ones, or --estimator bsdf",
                limits::MAX_SAMPLED_SHAPES,
                plan.nee
            ),
        ));
    }
    if settings.estimator == EstimatorChoice::NeeMis && scene.mode == Mode::Path && plan.nee == 0 {
        warnings.push(Error::invalid(
            "estimator",
            "the nee-mis estimator has no light to sample (the scene has no static diffuse_light sphere or \
             quad): every direction comes from the materials, as under bsdf",
        ));
    }
    if settings.estimator == EstimatorChoice::Book && scene.mode == Mode::Path && plan.sample_toward == 0 {
        warnings.push(Error::invalid(
            "estimator",
            "the book estimator has nothing to sample toward (the scene has no lights and no sample_toward \
             list): every direction comes from the materials, as under bsdf",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{preset, RenderTable};

    /// A derived job that only runs another kernel shares the scene as laid
    /// out (trees included), built once; one whose settings or options change
    /// what the kernels read lays it out anew.
    #[test]
    fn derived_jobs_share_the_prepared_scene_when_it_is_theirs() {
        let small = Overrides { width: Some(32), height: Some(18), spp: Some(1), ..Default::default() };
        let job = Job::new(&preset("final").unwrap(), &small, &RenderOptions::default()).unwrap();
        let scalar = job.with_options(&RenderOptions { kernel: KernelChoice::Scalar, ..Default::default() }).unwrap();
        assert!(std::ptr::eq(job.prepared(), scalar.prepared()), "another kernel: the same prepared scene");
        assert!(Arc::ptr_eq(&job.flat, &scalar.flat), "one flattening per scene");
        let wider = job.with(&Overrides { width: Some(64), ..small }, &RenderOptions::default()).unwrap();
        assert!(!std::ptr::eq(job.prepared(), wider.prepared()), "another size: its own camera");
        assert_eq!(wider.prepared().settings.width, 64);
        let roulette = RenderOptions { roulette: Some(Roulette::new(3).unwrap()), ..Default::default() };
        let rr = job.with_options(&roulette).unwrap();
        assert!(!std::ptr::eq(job.prepared(), rr.prepared()), "another estimator: its own");
        assert!(rr.prepared().estimator.roulette.is_some());
    }

    /// A job flattens its scene once, whatever reads the flattened scene
    /// (the default estimator, the plan, the layout); a derived job and its
    /// layout flatten nothing.
    #[test]
    fn a_job_flattens_its_scene_once() {
        use crate::scene::FLATTENED;
        let count = |f: &dyn Fn()| {
            let before = FLATTENED.with(|n| n.get());
            f();
            FLATTENED.with(|n| n.get()) - before
        };
        let small = Overrides { width: Some(16), height: Some(16), spp: Some(1), ..Default::default() };
        for name in ["nw-cornell-box", "nw-cornell-smoke", "final", "ch05-normals"] {
            let scene = preset(name).unwrap();
            let job = std::cell::OnceCell::new();
            let made = count(&|| {
                let j = Job::new(&scene, &small, &RenderOptions::default()).unwrap();
                let _ = j.prepared();
                job.set(j).unwrap();
            });
            assert_eq!(made, 1, "{name}: one flattening per job");
            let job = job.get().unwrap();
            let derived = count(&|| {
                let wider = job.with(&Overrides { width: Some(24), ..small }, &RenderOptions::default()).unwrap();
                let _ = wider.prepared();
                let scalar = RenderOptions { kernel: KernelChoice::Scalar, ..Default::default() };
                let _ = job.with_options(&scalar).unwrap().prepared();
            });
            assert_eq!(derived, 0, "{name}: derived jobs share the flattened scene");
        }
    }

    #[test]
    fn flags_win_over_the_book_which_wins_over_the_scene() {
        let render = RenderTable { width: Some(100), samples_per_pixel: Some(7), ..Default::default() };
        let scene = Scene { render, ..preset("ch07-diffuse").unwrap() };
        let flat = scene.flatten();
        let s = Overrides::default().resolve(&scene, &flat);
        assert_eq!((s.width, s.height, s.spp, s.max_depth, s.seed), (100, 225, 7, 50, 0));
        let s = Overrides { book: true, spp: Some(3), ..Default::default() }.resolve(&scene, &flat);
        assert_eq!((s.width, s.height, s.spp, s.max_depth), (1200, 675, 3, 50));
    }

    #[test]
    fn scenes_with_lights_take_the_nee_mis_estimator_unless_told_otherwise() {
        let resolve = |o: &Overrides, scene: &Scene| o.resolve(scene, &scene.flatten()).estimator;
        let est = |name: &str, o: &Overrides| resolve(o, &preset(name).unwrap());
        let none = Overrides::default();
        for lit in ["nw-cornell-box", "nw-simple-light", "nw-cornell-smoke", "rol-cornell-box"] {
            assert_eq!(est(lit, &none), EstimatorChoice::NeeMis, "{lit}");
        }
        // Its render table says book (measured faster there).
        assert_eq!(est("nw-final", &none), EstimatorChoice::Book);
        // A sample_toward list and no light: book.
        let mut listed = preset("ch07-diffuse").unwrap();
        listed.sample_toward = vec![crate::scene::Shape::Sphere { center: [0.0, 0.0, -1.0], radius: 0.5 }];
        assert_eq!(resolve(&none, &listed), EstimatorChoice::Book);
        for unlit in ["final", "ch07-diffuse", "nw-quads", "nw-earth", "ch05-normals"] {
            assert_eq!(est(unlit, &none), EstimatorChoice::Bsdf, "{unlit}");
        }
        let bsdf = Overrides { estimator: Some(EstimatorChoice::Bsdf), ..Default::default() };
        assert_eq!(est("nw-cornell-box", &bsdf), EstimatorChoice::Bsdf);
        let mut table_says = preset("nw-cornell-box").unwrap();
        table_says.render.estimator = Some(EstimatorChoice::Bsdf);
        assert_eq!(resolve(&none, &table_says), EstimatorChoice::Bsdf);
        // More lights than the mixture takes: bsdf, not an error.
        let mut many = preset("nw-cornell-box-empty").unwrap();
        let light = many.quads[2].clone();
        many.quads.extend(std::iter::repeat_n(light, limits::MAX_SAMPLED_SHAPES));
        assert_eq!(resolve(&none, &many), EstimatorChoice::Bsdf);
    }

    #[test]
    fn the_scene_tables_sampler_is_resolved_unless_overridden() {
        let mut scene = preset("ch07-diffuse").unwrap();
        scene.render.sampler = Some(Sampler::Independent);
        let job = Job::new(&scene, &Overrides::default(), &RenderOptions::default()).unwrap();
        assert_eq!(job.settings().sampler, Sampler::Independent);
        let o = Overrides { sampler: Some(Sampler::SOBOL), ..Default::default() };
        assert_eq!(Job::new(&scene, &o, &RenderOptions::default()).unwrap().settings().sampler, Sampler::SOBOL);
        scene.render.sampler = None;
        assert_eq!(
            Job::new(&scene, &Overrides::default(), &RenderOptions::default()).unwrap().settings().sampler,
            Sampler::default()
        );
    }

    #[test]
    fn options_out_of_range_name_the_option() {
        let scene = preset("ch04-sphere").unwrap();
        let refuse = |o: RenderOptions| Job::new(&scene, &Overrides::default(), &o).unwrap_err().to_string();
        assert!(refuse(RenderOptions { tile: 0, ..Default::default() }).starts_with("tile:"));
        assert!(refuse(RenderOptions { threads: Some(0), ..Default::default() }).starts_with("threads:"));
    }

    #[test]
    fn adaptive_sampling_that_cannot_act_is_off_and_says_so() {
        let scene = preset("ch07-diffuse").unwrap();
        let opts = RenderOptions { adaptive: Some(Adaptive::new(0.05, 16).unwrap()), ..Default::default() };
        for (spp, on) in [(8, false), (16, false), (17, true)] {
            let o = Overrides { spp: Some(spp), ..Default::default() };
            let job = Job::new(&scene, &o, &opts).unwrap();
            assert_eq!(job.options().adaptive.is_some(), on, "spp {spp}");
            assert_eq!(job.warnings().len(), usize::from(!on), "spp {spp}");
            if !on {
                let w = job.warnings()[0].to_string();
                assert!(w.starts_with("adaptive.min_spp:") && w.contains(&format!("takes only {spp}:")), "{w}");
                assert_eq!(job.identity().settings["adaptive"], "off");
            }
            // Another sample count starts again from what was asked for.
            let more = job.with_overrides(&Overrides { spp: Some(64), ..Default::default() }).unwrap();
            assert!(more.options().adaptive.is_some() && more.warnings().is_empty());
        }
    }

    #[test]
    fn scene_errors_name_the_file_they_came_from() {
        let mut scene = preset("ch04-sphere").unwrap();
        scene.spheres[0].radius = 0.0;
        let src = SceneSource { scene, name: "x".into(), file: Some("x.json".into()) };
        let e = Job::from_source(&src, &Overrides::default(), &RenderOptions::default()).unwrap_err();
        assert_eq!(e.to_string(), "x.json: spheres[0].radius: must not be 0");
        assert_eq!(e.exit_code(), 2);
        assert!(matches!(e.root(), Error::Invalid { field, .. } if field == "spheres[0].radius"));
    }
}
