//! The settings a render runs with, resolved once by the job module from a
//! scene's render table and the caller's overrides: the image size, samples
//! per pixel, path depth, seed, sampler and estimator. Every one of them changes the
//! image; the kernels, the film and the statistics read them from here.

use crate::choice::EstimatorChoice;
use crate::error::{Error, Result};
use crate::limits::check_pixels;
use crate::sampling::Sampler;
use serde::Serialize;

/// rtow's defaults, where neither the scene nor an override says.
pub const DEFAULT_WIDTH: u32 = 400;
pub const DEFAULT_HEIGHT: u32 = 225;
pub const DEFAULT_SPP: u32 = 32;
/// The book's path depth.
pub const DEFAULT_MAX_DEPTH: u32 = 50;
pub const DEFAULT_SEED: u64 = 0;

/// The settings a render runs with, after the scene's and the overrides' values are merged.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// Rays per path at most (the camera ray counts).
    pub max_depth: u32,
    pub seed: u64,
    /// Independent streams or Owen-scrambled Sobol points.
    pub sampler: Sampler,
    /// How paths choose directions at diffuse vertices (`bsdf`, `book`):
    /// the noise changes, the expected image does not.
    pub estimator: EstimatorChoice,
}

impl Default for Settings {
    /// rtow's defaults: 400x225, 32 spp, depth 50, seed 0, Sobol.
    fn default() -> Self {
        Settings {
            width: DEFAULT_WIDTH,
            height: DEFAULT_HEIGHT,
            spp: DEFAULT_SPP,
            max_depth: DEFAULT_MAX_DEPTH,
            seed: DEFAULT_SEED,
            sampler: Sampler::default(),
            estimator: EstimatorChoice::default(),
        }
    }
}

impl Settings {
    /// The book's final settings (`--book`): 1200x675, 500 spp, depth 50.
    pub const BOOK: (u32, u32, u32, u32) = (1200, 675, 500, 50);

    /// Checks the ranges before anything is allocated; the error names the setting.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in
            [("width", self.width), ("height", self.height), ("spp", self.spp), ("max_depth", self.max_depth)]
        {
            if v == 0 {
                return Err(Error::invalid(name, "must be at least 1"));
            }
        }
        check_pixels("width x height", self.width, self.height)?;
        let px = self.width as u64 * self.height as u64;
        if px * self.spp as u64 > u32::MAX as u64 * 1024 {
            return Err(Error::invalid("spp", format!("{} samples per pixel at {px} pixels is too many", self.spp)));
        }
        Ok(())
    }
}
