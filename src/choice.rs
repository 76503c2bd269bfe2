//! The named choices of a render, spoken alike by scene files, the command
//! line, the library's options and the kernels' plan: what the renderer
//! computes ([`Mode`]), which kernel runs ([`KernelChoice`]), how closest
//! hits are found ([`AccelChoice`]) and how a path chooses its directions
//! ([`EstimatorChoice`]). A foundation module: it imports nothing
//! of the crate, so both sides of the bridge (`scene/` and the kernels) can
//! name these without importing each other.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Names and parsing for a small choice enum: `ALL`, `NAMES`, `name()`,
/// `Display`, `FromStr` (an unknown name lists the known ones) and `Serialize`.
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

/// The name of `names` most similar to `word` (Jaro-Winkler, as the command
/// line's own suggestions), if similar enough: what every "did you mean" says.
pub fn nearest<'a>(word: &str, names: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    names
        .map(|name| (strsim::jaro_winkler(word, name), name))
        .filter(|&(similarity, _)| similarity > 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, name)| name)
}

/// What the renderer computes for each camera ray.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub enum Mode {
    /// Chapter 1: no rays; r = x / width, g = (rows from the bottom) / height, b = 0.2.
    Gradient,
    /// Chapters 3-4: the sky where a camera ray misses, the hit material's colour where it hits.
    Flat,
    /// Chapters 5-6: 0.5 * (n + 1) of the outward normal where a camera ray hits.
    Normals,
    /// Chapter 7 on: the path tracer.
    #[default]
    Path,
}

impl Mode {
    /// The book writes the debug images without gamma and the path traced ones with gamma 2.
    pub fn default_gamma(self) -> f32 {
        match self {
            Mode::Path => 2.0,
            Mode::Gradient | Mode::Flat | Mode::Normals => 1.0,
        }
    }

    /// The mode's name as scene files write it.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Gradient => "gradient",
            Mode::Flat => "flat",
            Mode::Normals => "normals",
            Mode::Path => "path",
        }
    }
}

choice!(
    /// What a run does when its film rejected samples (NaN, infinite, or out
    /// of the film's range): in any case it says so on stderr and in its
    /// statistics. More than `limits::MAX_REJECTED_FRACTION` of the samples
    /// always fail the run.
    #[derive(Default)]
    OnRejected {
        /// Write the outputs, with one warning line naming the count.
        #[default]
        Warn = "warn",
        /// Fail (exit status 2) and write nothing.
        Error = "error",
    }
);

choice!(
    /// What a render does on SIGINT, SIGTERM or SIGHUP.
    #[derive(Default)]
    OnInterrupt {
        /// Finish the round of samples under way, write a film of the samples
        /// done (to resume), exit with 128 + the signal.
        #[default]
        Film = "film",
        /// Stop at once, write nothing (exit with 128 + the signal).
        Quit = "quit",
    }
);

choice!(
    /// Which kernel renders.
    KernelChoice {
        /// One path at a time: the reference.
        Scalar = "scalar",
        /// The wavefront kernel at the widest lane count this binary was built for.
        Simd = "simd",
        /// The wavefront kernel with 8 lanes (`f32x8`, the design's packets).
        Simd8 = "simd8",
        /// The wavefront kernel with 16 lanes (`f32x16`: one register on AVX-512 builds,
        /// two 8-lane halves elsewhere).
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

choice!(
    /// How a path chooses its next direction at a diffuse vertex (a
    /// lambertian surface or a medium's isotropic scattering). Both are
    /// unbiased: they change the noise, not the expected image. Specular
    /// materials (metal, dielectric) sample their own direction under both.
    #[derive(Default)]
    EstimatorChoice {
        /// The material's own density only: the cosine lobe, a uniform sphere in a medium.
        #[default]
        Bsdf = "bsdf",
        /// The Rest of Your Life's one-sample mixture: half the directions
        /// from the material's density, half toward the scene's important
        /// shapes (its `sample_toward` list, else its lights), weighted by
        /// the mixture's density.
        Book = "book",
        /// Next-event estimation with multiple importance sampling: at
        /// every diffuse vertex a shadow ray toward a point on one of the
        /// scene's lights, and the scattered direction as under `bsdf`; the
        /// two are weighted by the power heuristic (pbrt's and Mitsuba's
        /// path tracer).
        NeeMis = "nee-mis",
    }
);

impl<'de> Deserialize<'de> for EstimatorChoice {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn choices_parse_their_names_and_list_them_on_error() {
        for k in KernelChoice::ALL {
            assert_eq!(k.name().parse::<KernelChoice>(), Ok(*k));
        }
        assert_eq!("bvh-ray".parse::<AccelChoice>(), Ok(AccelChoice::BvhRay));
        for e in EstimatorChoice::ALL {
            assert_eq!(e.name().parse::<EstimatorChoice>(), Ok(*e));
            assert_eq!(serde_json::from_value::<EstimatorChoice>(serde_json::to_value(e).unwrap()).unwrap(), *e);
        }
        let e = serde_json::from_str::<EstimatorChoice>("\"mis\"").unwrap_err().to_string();
        assert!(e.contains("bsdf, book"), "{e}");
        let e = "gpu".parse::<KernelChoice>().unwrap_err();
        assert!(e.contains("scalar, simd, simd8, simd16"), "{e}");
    }

    #[test]
    fn mode_names_are_the_serialized_names() {
        for m in [Mode::Gradient, Mode::Flat, Mode::Normals, Mode::Path] {
            assert_eq!(serde_json::to_value(m).unwrap(), serde_json::Value::String(m.name().into()));
        }
    }
}
