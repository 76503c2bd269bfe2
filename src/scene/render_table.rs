//! A scene's render table: the settings a scene file asks for. Every field
//! is optional; overrides (flags, or a library caller's) win over it and
//! rtow's defaults fill what neither gives (`crate::job` resolves them).

use super::de;
use crate::choice::EstimatorChoice;
use crate::error::{Error, Result};
use crate::limits::check_pixels;
use crate::sampling::Sampler;
use serde::{Deserialize, Serialize};

/// Render settings a scene may carry (its `render` table).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct RenderTable {
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "de::opt_u32")]
    pub width: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "de::opt_u32")]
    pub height: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "de::opt_u32")]
    pub samples_per_pixel: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "de::opt_u32")]
    pub max_depth: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "de::opt_u64")]
    pub seed: Option<u64>,
    /// The sampler (`independent`, `sobol`, ...); an override replaces it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sampler: Option<Sampler>,
    /// How paths choose their directions at diffuse vertices (`bsdf`,
    /// `book`); an override replaces it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator: Option<EstimatorChoice>,
    /// What `--book` renders for this scene (The Next Week's presets: their
    /// book's image); without it, `--book` is book one's final settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub book: Option<BookTable>,
}

/// A scene's book settings (`render.book`): size, samples and depth.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct BookTable {
    #[serde(deserialize_with = "de::u32")]
    pub width: u32,
    #[serde(deserialize_with = "de::u32")]
    pub height: u32,
    #[serde(deserialize_with = "de::u32")]
    pub samples_per_pixel: u32,
    #[serde(deserialize_with = "de::u32")]
    pub max_depth: u32,
}

impl RenderTable {
    /// The same limits as the resolved settings' check, naming the scene's
    /// fields (an override may replace a value, but a file that asks for 0 is wrong).
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("render.width", self.width),
            ("render.height", self.height),
            ("render.samples_per_pixel", self.samples_per_pixel),
            ("render.max_depth", self.max_depth),
        ] {
            if v == Some(0) {
                return Err(Error::invalid(name, "must be at least 1"));
            }
        }
        if let Some(b) = self.book {
            for (name, v) in [
                ("render.book.width", b.width),
                ("render.book.height", b.height),
                ("render.book.samples_per_pixel", b.samples_per_pixel),
                ("render.book.max_depth", b.max_depth),
            ] {
                if v == 0 {
                    return Err(Error::invalid(name, "must be at least 1"));
                }
            }
            check_pixels("render.book.width x render.book.height", b.width, b.height)?;
        }
        if let (Some(w), Some(h)) = (self.width, self.height) {
            check_pixels("render.width x render.height", w, h)?;
        }
        Ok(())
    }
}
