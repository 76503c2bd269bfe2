//! Estimator variants of `rtow converge`: plain, Russian roulette, adaptive
//! sampling, Sobol points, the direction estimator (`bsdf`, `book`), or
//! combinations.

use crate::choice::EstimatorChoice;
use crate::error::{Error, Result};
use crate::estimator::{Adaptive, Roulette, ROULETTE_AFTER_RAYS};
use crate::sampling::Sampler;

/// The threshold of the `adaptive` variant when none is given (`adaptive:T`).
pub const DEFAULT_ADAPTIVE_THRESHOLD: f32 = 0.02;

/// An estimator variant: plain, Russian roulette, adaptive sampling, or both.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variant {
    pub rr: Option<Roulette>,
    /// Relative error threshold of adaptive sampling.
    pub adaptive: Option<f32>,
    /// The sampler (`plain` is independent sampling).
    pub sampler: Sampler,
    /// The direction estimator (`None`: the scene's, as a render would take it).
    pub estimator: Option<EstimatorChoice>,
}

impl Variant {
    pub const PLAIN: Variant = Variant { rr: None, adaptive: None, sampler: Sampler::Independent, estimator: None };

    /// Parses `plain`, `rr`, `rr:N`, `adaptive`, `adaptive:T`, a sampler
    /// (`sobol`, or `sobol-pixel`, `sobol-lens`, `sobol-bounce1` for part of
    /// the layout on Sobol points), an estimator (`bsdf`, `book`) or a
    /// `+`-joined combination such as `sobol+rr+adaptive:0.05` or `book+sobol`.
    pub fn parse(text: &str) -> Result<Variant> {
        let bad = |m: String| Error::invalid("variants", m);
        let mut v = Variant::PLAIN;
        let text = text.trim();
        if text == "plain" {
            return Ok(v);
        }
        for part in text.split('+') {
            let part = part.trim();
            let (name, value) = match part.split_once(':') {
                Some((n, x)) => (n, Some(x)),
                None => (part, None),
            };
            match name {
                "rr" if v.rr.is_none() => {
                    v.rr = Some(match value {
                        None => Roulette::default(),
                        Some(x) => x.parse::<u32>().ok().and_then(|n| Roulette::new(n).ok()).ok_or_else(|| {
                            bad(format!("'{text}': '{x}' is not a number of rays of at least 1 (rr:N)"))
                        })?,
                    });
                }
                name if value.is_none() && v.sampler == Sampler::Independent && name.starts_with("sobol") => {
                    v.sampler = Sampler::parse(name).ok_or_else(|| {
                        bad(format!("'{text}': unknown sampler '{name}' (use one of {})", Sampler::NAMES[1..].join(", ")))
                    })?;
                }
                name if value.is_none() && v.estimator.is_none() && EstimatorChoice::NAMES.contains(&name) => {
                    v.estimator = Some(name.parse().map_err(bad)?);
                }
                "adaptive" if v.adaptive.is_none() => {
                    let t = match value {
                        None => DEFAULT_ADAPTIVE_THRESHOLD,
                        Some(x) => x.parse::<f32>().unwrap_or(f32::NAN),
                    };
                    if Adaptive::check_threshold(t).is_err() {
                        return Err(bad(format!(
                            "'{text}': the adaptive threshold must be a positive number (adaptive:THRESHOLD)"
                        )));
                    }
                    v.adaptive = Some(t);
                }
                _ => {
                    return Err(bad(format!(
                        "unknown or repeated variant '{part}' in '{text}' (use plain, rr, rr:N, adaptive, adaptive:THRESHOLD, sobol, bsdf, book, nee-mis, or e.g. sobol+rr+adaptive:0.05)"
                    )))
                }
            }
        }
        Ok(v)
    }

    pub fn name(&self) -> String {
        let rr = match self.rr {
            Some(r) if r.after_rays() == ROULETTE_AFTER_RAYS => "rr".to_string(),
            Some(r) => format!("rr:{}", r.after_rays()),
            None => String::new(),
        };
        let mut parts: Vec<String> = Vec::new();
        if let Some(e) = self.estimator {
            parts.push(e.name().into());
        }
        if self.sampler != Sampler::Independent {
            parts.push(self.sampler.name().into());
        }
        if !rr.is_empty() {
            parts.push(rr);
        }
        if let Some(t) = self.adaptive {
            parts.push(format!("adaptive:{t}"));
        }
        if parts.is_empty() {
            "plain".into()
        } else {
            parts.join("+")
        }
    }
}
