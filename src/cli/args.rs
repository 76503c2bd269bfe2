//! Flags shared by the commands, and their mapping onto the library's types
//! (the library knows nothing of clap; this module decides nothing).

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;
use rtow::scene::Assignment;
use rtow::{
    AccelChoice, Adaptive, EstimatorChoice, KernelChoice, Mode, OnRejected, Overrides, RenderOptions, Result, Roulette,
    Sampler, SceneSource, Settings, ADAPTIVE_MIN_SPP, DEFAULT_TILE, ROULETTE_AFTER_RAYS,
};
use std::path::PathBuf;
use std::str::FromStr;

/// A clap parser for one of the library's choice enums, listing its names.
pub fn choice<T: FromStr<Err = String> + Clone + Send + Sync + 'static>(
    names: &'static [&'static str],
) -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(names).map(|s| s.parse::<T>().expect("a listed name parses"))
}

pub fn kernel_parser() -> impl TypedValueParser<Value = KernelChoice> {
    choice::<KernelChoice>(KernelChoice::NAMES)
}

pub fn sampler_parser() -> impl TypedValueParser<Value = Sampler> {
    choice::<Sampler>(Sampler::NAMES)
}

/// Image size, depth and seed: what every rendering command can set.
#[derive(Args, Clone, Debug)]
pub struct SizeArgs {
    /// Image width in pixels [default: the scene's]
    #[arg(long, allow_negative_numbers = true)]
    pub width: Option<u32>,
    /// Image height in pixels [default: the scene's]
    #[arg(long, allow_negative_numbers = true)]
    pub height: Option<u32>,
    #[arg(long, allow_negative_numbers = true, help = depth_help())]
    pub depth: Option<u32>,
    #[arg(long, allow_negative_numbers = true, help = seed_help())]
    pub seed: Option<u64>,
}

/// Values of the scene set from the command line (`--set KEY=VALUE`).
#[derive(Args, Clone, Debug)]
pub struct SetArgs {
    /// Set a value of the scene, preset or file, before anything else: KEY is a dotted path into
    /// the scene file's structure (camera.vfov_deg, spheres.3.radius or spheres[3].radius,
    /// render.samples_per_pixel), VALUE is JSON (a bare word is a string: lambertian).
    /// Repeatable, applied in order; `rtow schema` lists every key
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

impl SetArgs {
    /// The scene `spec` names (a preset or a scene file) with the assignments applied.
    pub fn open(&self, spec: &str) -> Result<SceneSource> {
        // Every assignment is checked before the scene is read: a typo in
        // the last one is reported before a large file is parsed.
        let assignments = self.assignments()?;
        let mut source = SceneSource::open(spec)?;
        source.scene = rtow::scene::apply_assignments(&source.scene, &assignments)?;
        Ok(source)
    }

    /// The assignments, parsed.
    fn assignments(&self) -> Result<Vec<Assignment>> {
        self.set.iter().map(|a| Assignment::parse(a)).collect()
    }

    /// `source` (a scene not opened by name: a film's) with the assignments applied.
    pub fn apply(&self, mut source: SceneSource) -> Result<SceneSource> {
        if !self.set.is_empty() {
            source.scene = rtow::scene::apply_assignments(&source.scene, &self.assignments()?)?;
        }
        Ok(source)
    }
}

/// The image settings a render may override: size, depth, seed, samples, sampler.
#[derive(Args, Clone, Debug)]
pub struct ImageArgs {
    #[command(flatten)]
    pub set: SetArgs,
    #[command(flatten)]
    pub size: SizeArgs,
    /// Samples per pixel [default: the scene's]
    #[arg(long, allow_negative_numbers = true)]
    pub spp: Option<u32>,
    #[arg(long, help = book_help())]
    pub book: bool,
    #[arg(long, value_parser = sampler_parser(), help = sampler_help())]
    pub sampler: Option<Sampler>,
    /// Directions at diffuse vertices: bsdf (the material's density), book (The Rest of Your Life's
    /// mixture: half toward the scene's sample_toward shapes, else its lights), nee-mis (a shadow ray
    /// toward a light sample at every diffuse vertex, weighted against the scattered direction by
    /// the power heuristic) [default: the scene's render.estimator, else by the scene]
    #[arg(long, value_parser = choice::<EstimatorChoice>(EstimatorChoice::NAMES))]
    pub estimator: Option<EstimatorChoice>,
    /// Render every static sphere as a closed icosphere triangle mesh of level N (20*4^N triangles a
    /// sphere, 0 to 7), with the sphere's material
    #[arg(long, value_name = "N")]
    pub tessellate: Option<u32>,
}

impl ImageArgs {
    /// The scene `spec` names (a preset or a scene file), with the `--set`
    /// assignments, tessellated if asked.
    pub fn open(&self, spec: &str) -> Result<SceneSource> {
        let mut source = self.set.open(spec)?;
        if let Some(level) = self.tessellate {
            source.scene = source.scene.tessellate(level)?;
        }
        Ok(source)
    }
}

/// `--depth`'s help, naming the library's default.
fn depth_help() -> String {
    format!("Maximum rays per path [default: the scene's, else {}, the book's]", Settings::default().max_depth)
}

/// `--seed`'s help, naming the library's default.
fn seed_help() -> String {
    format!("Seed of the random streams [default: the scene's, else {}]", Settings::default().seed)
}

/// `--book`'s help, from the library's book settings.
fn book_help() -> String {
    let (w, h, spp, depth) = Settings::BOOK;
    format!(
        "The book's settings for the scene: The Next Week's presets their book's (nw-final: 800x800, 10000 spp, \
         depth 40), other scenes book one's final {w}x{h}, {spp} spp, depth {depth} (flags given explicitly still win)"
    )
}

/// `--sampler`'s help, naming the default the library uses.
fn sampler_help() -> String {
    format!(
        "Random decisions from Owen-scrambled Sobol points or independent streams (sobol-pixel, sobol-lens, \
         sobol-bounce1: only those dimensions on Sobol points) [default: the scene's render.sampler, else {}]",
        Sampler::default()
    )
}

/// Worker threads, tile size and accelerator: how to render, never what.
#[derive(Args, Clone, Debug)]
pub struct RunArgs {
    /// Worker threads [default: one per core]
    #[arg(long, allow_negative_numbers = true)]
    pub threads: Option<usize>,
    #[arg(long, allow_negative_numbers = true, default_value_t = DEFAULT_TILE, help = tile_help())]
    pub tile: u32,
    /// Closest-hit search: auto (by the plan), brute force, the BVH with packets, or one ray at a time
    #[arg(long, value_parser = choice::<AccelChoice>(AccelChoice::NAMES), default_value = "auto")]
    pub accel: AccelChoice,
}

/// `--tile`'s help, from the library's bound.
fn tile_help() -> String {
    let max = rtow::limits::MAX_TILE;
    format!(
        "Tile edge in pixels (tiles are the unit of parallel work), at most {max}: the wavefront traces a tile's \
         pixels together, one sample each, and its workspace holds {} paths, so {max}x{max} = {} pixels is the \
         largest square tile",
        rtow::internals::kernel::wavefront::MAX_PATHS,
        max * max
    )
}

impl RunArgs {
    pub fn options(&self, kernel: KernelChoice) -> RenderOptions {
        RenderOptions { kernel, threads: self.threads, tile: self.tile, accel: self.accel, ..Default::default() }
    }
}

/// Russian roulette and adaptive sampling (both off by default).
#[derive(Args, Clone, Debug)]
pub struct EstimatorArgs {
    /// Russian roulette: after a few bounces a path survives with probability
    /// min(1, max throughput component) and is reweighted (unbiased; changes the noise).
    #[arg(long)]
    pub rr: bool,
    /// With --rr: the roulette starts once a path has traced N rays.
    #[arg(long, allow_negative_numbers = true, value_name = "N", default_value_t = ROULETTE_AFTER_RAYS, requires = "rr")]
    pub rr_after: u32,
    /// Adaptive sampling: a pixel stops taking samples once the relative
    /// standard error of its mean is at most THRESHOLD (e.g. 0.02); --spp is the maximum.
    #[arg(long, allow_negative_numbers = true, value_name = "THRESHOLD")]
    pub adaptive: Option<f32>,
    /// Adaptive sampling decides after N, 2N, 4N, ... samples.
    #[arg(long, allow_negative_numbers = true, value_name = "N", default_value_t = ADAPTIVE_MIN_SPP, requires = "adaptive")]
    pub adaptive_min: u32,
}

impl EstimatorArgs {
    /// `base` with these estimator options.
    pub fn options(&self, base: RenderOptions) -> Result<RenderOptions> {
        let roulette = if self.rr { Some(Roulette::new(self.rr_after)?) } else { None };
        let adaptive = self.adaptive.map(|t| Adaptive::new(t, self.adaptive_min)).transpose()?;
        Ok(RenderOptions { roulette, adaptive, ..base })
    }
}

/// The files a render or a merge writes.
#[derive(Args, Clone, Debug)]
pub struct OutputArgs {
    /// Also write the linear image: .pfm or .exr.
    #[arg(long, value_name = "FILE")]
    pub float: Option<PathBuf>,
    /// Write statistics as JSON (with the exact work counters: node visits,
    /// box and sphere tests, square roots, lane occupancy).
    #[arg(long, value_name = "FILE")]
    pub stats_json: Option<PathBuf>,
    #[arg(long, allow_negative_numbers = true, help = gamma_help())]
    pub gamma: Option<f32>,
}

/// `--gamma`'s help, from the gamma the library gives each kind of scene.
fn gamma_help() -> String {
    format!(
        "PNG gamma [default: {} for path traced scenes, {} for the debug chapters, as in the book]",
        Mode::Path.default_gamma(),
        Mode::Normals.default_gamma()
    )
}

impl OutputArgs {
    pub fn files(&self, output: PathBuf) -> rtow::files::RenderFiles {
        rtow::files::RenderFiles {
            output,
            float: self.float.clone(),
            stats: self.stats_json.clone(),
            gamma: self.gamma,
            names: rtow::files::FileNames { output: "-o", float: "--float", stats: "--stats-json" },
        }
    }
}

impl SizeArgs {
    pub fn overrides(&self) -> Overrides {
        Overrides {
            width: self.width,
            height: self.height,
            max_depth: self.depth,
            seed: self.seed,
            ..Overrides::default()
        }
    }
}

impl ImageArgs {
    pub fn overrides(&self) -> Overrides {
        Overrides {
            spp: self.spp,
            book: self.book,
            sampler: self.sampler,
            estimator: self.estimator,
            ..self.size.overrides()
        }
    }
}

/// The flag that sets a library setting, for messages (`threads` -> `--threads`).
pub fn flag_of(field: &str) -> Option<&'static str> {
    Some(match field {
        "width" => "--width",
        "height" => "--height",
        "spp" => "--spp",
        "max_depth" => "--depth",
        "estimator" => "--estimator",
        "threads" => "--threads",
        "tile" => "--tile",
        "roulette.after_rays" => "--rr-after",
        "adaptive.threshold" => "--adaptive",
        "adaptive.min_spp" => "--adaptive-min",
        "shard" => "--shard",
        "split" => "--split",
        "resume" => "--resume",
        "time_limit" => "--time-limit",
        "preview_every" => "--preview-every",
        "crop" => "--crop",
        "aov" => "--aov",
        "trace_pixel" => "--trace-pixel",
        "trace_samples" => "--trace-samples",
        "gamma" => "--gamma",
        "kernels" => "--kernels",
        "variants" => "--variants",
        "spp_list" => "--spp-list",
        "reference" => "--reference",
        "reference_spp" => "--reference-spp",
        "repeat" => "--repeat",
        "at_spp" => "--at-spp",
        "adaptive_min" => "--adaptive-min",
        "tolerance" => "--tolerance",
        "ppd" => "--ppd",
        "regions" => "--regions",
        "z" => "--z",
        "max_mse" => "--max-mse",
        "max_rel_mse" => "--max-rel-mse",
        "max_flip" => "--max-flip",
        "max_z_fails" => "--max-z-fails",
        "json" => "--json",
        "heatmap" => "--heatmap",
        _ => return None,
    })
}

/// What a render or a merge does when samples were rejected.
#[derive(Args, Clone, Debug)]
pub struct RejectedArgs {
    /// When the film rejects samples (NaN, infinite, or finite but out of the
    /// film's range): warn (write the outputs; one warning line on stderr,
    /// even with -q, and the counts by cause in --stats-json) or error (exit
    /// status 2, nothing written). More than 0.1% of the samples rejected
    /// always fails.
    #[arg(long, value_parser = choice::<OnRejected>(OnRejected::NAMES), default_value = "warn")]
    pub on_rejected: OnRejected,
}

/// How `merge` and `render --resume` check partial films by recomputation.
#[derive(Args)]
pub struct VerifyArgs {
    /// Pixels of each partial film rendered again and compared bit for bit
    /// with its data (a film that differs is refused); 0 trusts the films.
    #[arg(long, value_name = "N", default_value_t = rtow::shard::Verify::DEFAULT_PIXELS)]
    verify: u32,
    /// The seed the checked pixels are drawn from [default: random, reported].
    #[arg(long, value_name = "S")]
    verify_seed: Option<u64>,
}

impl VerifyArgs {
    pub fn verify(&self) -> rtow::shard::Verify {
        match self.verify_seed {
            Some(seed) => rtow::shard::Verify { pixels: self.verify, seed },
            None => rtow::shard::Verify::with_random_seed(self.verify),
        }
    }
}

/// E.g. "verified 1024 pixels (--verify 64 --verify-seed 7) in 0.012 s".
pub fn verified(v: &rtow::shard::Verified) -> String {
    if v.pixels_per_part == 0 {
        return "not verified (--verify 0)".into();
    }
    format!(
        "verified {} pixels (--verify {} --verify-seed {}) in {:.3} s",
        v.pixels, v.pixels_per_part, v.seed, v.seconds
    )
}
