//! Flags shared by the commands, and their mapping onto the library's types
//! (the library knows nothing of clap).

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;
use rtow::estimator::{Adaptive, ADAPTIVE_MIN_SPP, ROULETTE_AFTER_RAYS};
use rtow::{AccelChoice, KernelChoice, Overrides, RenderOptions, Result, Scene, Settings};
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

pub fn accel_parser() -> impl TypedValueParser<Value = AccelChoice> {
    choice::<AccelChoice>(AccelChoice::NAMES)
}

/// Image settings shared by every command that renders.
#[derive(Args, Clone, Debug)]
pub struct ImageArgs {
    /// Image width in pixels [default: the scene's]
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels [default: the scene's]
    #[arg(long)]
    pub height: Option<u32>,
    /// Samples per pixel [default: the scene's]
    #[arg(long)]
    pub spp: Option<u32>,
    /// Maximum rays per path [default: the scene's, the book's 50]
    #[arg(long)]
    pub depth: Option<u32>,
    /// Seed of the random streams [default: the scene's, else 0]
    #[arg(long)]
    pub seed: Option<u64>,
    /// The book's final settings: 1200x675, 500 spp, depth 50 (flags given explicitly still win)
    #[arg(long)]
    pub book: bool,
    /// Worker threads [default: one per core]
    #[arg(long)]
    pub threads: Option<usize>,
    /// Tile edge in pixels
    #[arg(long, default_value_t = 16)]
    pub tile: u32,
    /// Closest-hit search: auto (by the plan), brute force, the BVH with packets, or one ray at a time
    #[arg(long, value_parser = accel_parser(), default_value = "auto")]
    pub accel: AccelChoice,
}

impl ImageArgs {
    pub fn overrides(&self) -> Overrides {
        Overrides {
            width: self.width,
            height: self.height,
            spp: self.spp,
            max_depth: self.depth,
            seed: self.seed,
            book: self.book,
        }
    }

    /// The settings of `scene` with these flags applied: resolved once, here.
    pub fn settings(&self, scene: &Scene) -> Settings {
        Settings::resolve(&scene.render, &self.overrides())
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
    #[arg(long, value_name = "N", default_value_t = ROULETTE_AFTER_RAYS)]
    pub rr_after: u32,
    /// Adaptive sampling: a pixel stops taking samples once the relative
    /// standard error of its mean is at most THRESHOLD (e.g. 0.02); --spp is the maximum.
    #[arg(long, value_name = "THRESHOLD")]
    pub adaptive: Option<f32>,
    /// Adaptive sampling decides after N, 2N, 4N, ... samples.
    #[arg(long, value_name = "N", default_value_t = ADAPTIVE_MIN_SPP)]
    pub adaptive_min: u32,
}

impl EstimatorArgs {
    pub fn adaptive(&self) -> Result<Option<Adaptive>> {
        self.adaptive.map(|t| Adaptive::new(t, self.adaptive_min)).transpose()
    }

    /// The render options of these flags, with the kernel and image flags.
    pub fn options(&self, kernel: KernelChoice, image: &ImageArgs) -> Result<RenderOptions> {
        let opts = RenderOptions {
            kernel,
            threads: image.threads,
            tile: image.tile,
            accel: image.accel,
            rr: self.rr,
            rr_after: self.rr_after,
            adaptive: self.adaptive()?,
        };
        opts.validate()?;
        Ok(opts)
    }
}

pub fn positive_f32(s: &str) -> std::result::Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        Ok(v) => Err(format!("must be a finite number > 0, got {v}")),
        Err(e) => Err(e.to_string()),
    }
}
