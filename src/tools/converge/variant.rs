//! Estimator variants of `rtow converge`: plain, Russian roulette, adaptive sampling, or both.

use crate::error::{Error, Result};
use crate::estimator::ROULETTE_AFTER_RAYS;

/// The threshold of the `adaptive` variant when none is given (`adaptive:T`).
pub const DEFAULT_ADAPTIVE_THRESHOLD: f32 = 0.02;

/// An estimator variant: plain, Russian roulette, adaptive sampling, or both.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variant {
    /// Russian roulette from this many rays on.
    pub rr: Option<u32>,
    /// Relative error threshold of adaptive sampling.
    pub adaptive: Option<f32>,
}

impl Variant {
    pub const PLAIN: Variant = Variant { rr: None, adaptive: None };

    /// Parses `plain`, `rr`, `rr:N`, `adaptive`, `adaptive:T` or a
    /// `+`-joined combination such as `rr+adaptive:0.05`.
    pub fn parse(text: &str) -> Result<Variant> {
        let bad = |m: String| Error::invalid("--variants", m);
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
                    let n = match value {
                        None => ROULETTE_AFTER_RAYS,
                        Some(x) => match x.parse::<u32>() {
                            Ok(n) if n >= 1 => n,
                            _ => {
                                return Err(bad(format!(
                                    "'{text}': '{x}' is not a number of rays of at least 1 (rr:N)"
                                )))
                            }
                        },
                    };
                    v.rr = Some(n);
                }
                "adaptive" if v.adaptive.is_none() => {
                    let t = match value {
                        None => DEFAULT_ADAPTIVE_THRESHOLD,
                        Some(x) => x.parse::<f32>().unwrap_or(f32::NAN),
                    };
                    if !(t.is_finite() && t > 0.0) {
                        return Err(bad(format!(
                            "'{text}': the adaptive threshold must be a positive number (adaptive:THRESHOLD)"
                        )));
                    }
                    v.adaptive = Some(t);
                }
                _ => {
                    return Err(bad(format!(
                        "unknown or repeated variant '{part}' in '{text}' (use plain, rr, rr:N, adaptive, adaptive:THRESHOLD, or e.g. rr+adaptive:0.05)"
                    )))
                }
            }
        }
        Ok(v)
    }

    pub fn name(&self) -> String {
        let rr = match self.rr {
            Some(n) if n == ROULETTE_AFTER_RAYS => "rr".to_string(),
            Some(n) => format!("rr:{n}"),
            None => String::new(),
        };
        match (rr.as_str(), self.adaptive) {
            ("", None) => "plain".into(),
            (rr, None) => rr.into(),
            ("", Some(t)) => format!("adaptive:{t}"),
            (rr, Some(t)) => format!("{rr}+adaptive:{t}"),
        }
    }
}
