//! What a render runs with, resolved once: the image settings (scene defaults,
//! then flags) and the choices of how to render (kernel, accelerator,
//! estimator options). No CLI types here: the binary maps its flags onto these.

use crate::error::{Error, Result};
use crate::estimator::Adaptive;
use crate::limits::{MAX_PIXELS, MAX_TILE};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// The settings a render runs with, after scene defaults and flags are merged.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub seed: u64,
}

impl Settings {
    /// The book's final settings (`--book`): 1200x675, 500 spp, depth 50.
    pub const BOOK: (u32, u32, u32, u32) = (1200, 675, 500, 50);

    /// The settings of a scene (its `render` table, else rtow's defaults:
    /// 400x225, 32 spp, depth 50, seed 0), with `o` applied on top.
    pub fn resolve(scene: &RenderDefaults, o: &Overrides) -> Settings {
        let mut s = Settings {
            width: scene.width.unwrap_or(400),
            height: scene.height.unwrap_or(225),
            spp: scene.samples_per_pixel.unwrap_or(32),
            max_depth: scene.max_depth.unwrap_or(50),
            seed: scene.seed.unwrap_or(0),
        };
        if o.book {
            (s.width, s.height, s.spp, s.max_depth) = Settings::BOOK;
        }
        s.width = o.width.unwrap_or(s.width);
        s.height = o.height.unwrap_or(s.height);
        s.spp = o.spp.unwrap_or(s.spp);
        s.max_depth = o.max_depth.unwrap_or(s.max_depth);
        s.seed = o.seed.unwrap_or(s.seed);
        s
    }

    pub fn validate(&self) -> Result<()> {
        for (name, v) in
            [("width", self.width), ("height", self.height), ("spp", self.spp), ("max_depth", self.max_depth)]
        {
            if v == 0 {
                return Err(Error::invalid(name, "must be at least 1"));
            }
        }
        let px = self.width as u64 * self.height as u64;
        if px > MAX_PIXELS {
            return Err(Error::invalid(
                "width x height",
                format!("{}x{} = {px} pixels; at most {MAX_PIXELS} fit in memory", self.width, self.height),
            ));
        }
        if px * self.spp as u64 > u32::MAX as u64 * 1024 {
            return Err(Error::invalid("spp", format!("{} samples per pixel at {px} pixels is too many", self.spp)));
        }
        Ok(())
    }
}

/// Values given on the command line (or by a tool) that replace the scene's.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Overrides {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub seed: Option<u64>,
    /// The book's final settings; values given explicitly still win.
    pub book: bool,
}

/// Render settings a scene may carry (its `render` table); overrides replace them.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct RenderDefaults {
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "crate::scene::de::opt_u32")]
    pub width: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "crate::scene::de::opt_u32")]
    pub height: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "crate::scene::de::opt_u32")]
    pub samples_per_pixel: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "crate::scene::de::opt_u32")]
    pub max_depth: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "crate::scene::de::opt_u64")]
    pub seed: Option<u64>,
}

impl RenderDefaults {
    /// The same limits as [`Settings::validate`], naming the scene's fields
    /// (a flag may override a value, but a file that asks for 0 is wrong).
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
        if let (Some(w), Some(h)) = (self.width, self.height) {
            let px = w as u64 * h as u64;
            if px > MAX_PIXELS {
                return Err(Error::invalid(
                    "render.width x render.height",
                    format!("{w}x{h} = {px} pixels; at most {MAX_PIXELS} fit in memory"),
                ));
            }
        }
        Ok(())
    }
}

/// Names and parsing for the small choice enums below (the CLI lists `NAMES`).
macro_rules! choice {
    ($(#[$m:meta])* $name:ident { $($(#[$vm:meta])* $v:ident = $s:literal),+ $(,)? }) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
        pub enum $name { $($(#[$vm])* #[serde(rename = $s)] $v),+ }
        impl $name {
            pub const ALL: &'static [$name] = &[$($name::$v),+];
            pub const NAMES: &'static [&'static str] = &[$($s),+];
            pub fn name(self) -> &'static str {
                match self { $($name::$v => $s),+ }
            }
        }
        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }
        impl FromStr for $name {
            type Err = String;
            fn from_str(s: &str) -> std::result::Result<Self, String> {
                $name::ALL.iter().copied().find(|k| k.name() == s).ok_or_else(|| {
                    format!("'{s}' is not one of {}", $name::NAMES.join(", "))
                })
            }
        }
    };
}

choice!(
    /// Which kernel renders.
    KernelChoice {
        /// One path at a time: the reference.
        Scalar = "scalar",
        /// The wavefront kernel at the widest lane count this binary was built for.
        Simd = "simd",
        /// The wavefront kernel with 8 lanes (`f32x8`, the design's packets).
        Simd8 = "simd8",
        /// The wavefront kernel with 16 lanes (`f32x16`; AVX-512 builds only).
        Simd16 = "simd16",
    }
);

choice!(
    /// How closest hits are found.
    AccelChoice {
        /// Brute force below the measured crossover, BVH with packets above it.
        Auto = "auto",
        /// Every ray tests every sphere (a packet of rays per sphere in the SIMD kernel).
        Brute = "brute",
        /// The 8-wide BVH; the SIMD kernel walks it with packets of rays.
        Bvh = "bvh",
        /// The same BVH; the SIMD kernel walks it one ray at a time with 8-wide
        /// node and leaf tests (kept for comparison).
        BvhRay = "bvh-ray",
    }
);

/// How to render, beyond the image settings.
#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    pub kernel: KernelChoice,
    /// Worker threads; `None` = one per core.
    pub threads: Option<usize>,
    /// Tile edge in pixels (tiles are the unit of parallel work).
    pub tile: u32,
    /// Closest-hit search: brute force, BVH, or chosen by the plan.
    pub accel: AccelChoice,
    /// Russian roulette on the path throughput (unbiased; changes the noise).
    pub rr: bool,
    /// Roulette starts once a path has traced this many rays.
    pub rr_after: u32,
    /// Adaptive sampling: pixels stop once their relative error is low enough.
    pub adaptive: Option<Adaptive>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            kernel: KernelChoice::Simd,
            threads: None,
            tile: 16,
            accel: AccelChoice::Auto,
            rr: false,
            rr_after: crate::estimator::ROULETTE_AFTER_RAYS,
            adaptive: None,
        }
    }
}

impl RenderOptions {
    /// Checks every option before any work.
    pub fn validate(&self) -> Result<()> {
        crate::limits::check_threads(self.threads)?;
        if !(1..=MAX_TILE).contains(&self.tile) {
            return Err(Error::invalid("tile", format!("must be between 1 and {MAX_TILE} pixels")));
        }
        if let Some(a) = self.adaptive {
            Adaptive::new(a.threshold, a.min_spp)?;
        }
        if self.rr {
            crate::estimator::check_roulette_after(self.rr_after)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_win_over_the_book_which_wins_over_the_scene() {
        let scene = RenderDefaults { width: Some(100), samples_per_pixel: Some(7), ..Default::default() };
        let s = Settings::resolve(&scene, &Overrides::default());
        assert_eq!((s.width, s.height, s.spp, s.max_depth, s.seed), (100, 225, 7, 50, 0));
        let s = Settings::resolve(&scene, &Overrides { book: true, spp: Some(3), ..Default::default() });
        assert_eq!((s.width, s.height, s.spp, s.max_depth), (1200, 675, 3, 50));
    }

    #[test]
    fn choices_parse_their_names_and_list_them_on_error() {
        for k in KernelChoice::ALL {
            assert_eq!(k.name().parse::<KernelChoice>(), Ok(*k));
        }
        assert_eq!("bvh-ray".parse::<AccelChoice>(), Ok(AccelChoice::BvhRay));
        let e = "gpu".parse::<KernelChoice>().unwrap_err();
        assert!(e.contains("scalar, simd, simd8, simd16"), "{e}");
    }

    #[test]
    fn options_out_of_range_name_the_option() {
        let bad = RenderOptions { tile: 0, ..Default::default() };
        assert!(bad.validate().unwrap_err().to_string().starts_with("tile:"));
        let bad = RenderOptions { rr: true, rr_after: 0, ..Default::default() };
        assert!(bad.validate().unwrap_err().to_string().starts_with("--rr-after:"));
    }
}
