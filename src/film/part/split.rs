//! How a render is split into shards: by samples or by rows, part `k` of `n`.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// How a render is split into shards.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SplitKind {
    /// Not split: the whole image, every sample (a one-process render).
    None,
    /// Every shard covers the whole image for a range of sample indices.
    Samples,
    /// Every shard covers a band of whole rows with every sample.
    Rows,
}

impl SplitKind {
    /// The names a split can be given by (`none` is not one: it is no split).
    pub const NAMES: &'static [&'static str] = &["samples", "rows"];

    pub fn name(self) -> &'static str {
        match self {
            SplitKind::None => "none",
            SplitKind::Samples => "samples",
            SplitKind::Rows => "rows",
        }
    }
}

impl std::str::FromStr for SplitKind {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "samples" => Ok(SplitKind::Samples),
            "rows" => Ok(SplitKind::Rows),
            _ => Err(format!("'{s}' is not one of {}", SplitKind::NAMES.join(", "))),
        }
    }
}

/// Shard `shard` (from 1) of `of`, by `kind`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Split {
    pub kind: SplitKind,
    pub shard: u32,
    pub of: u32,
}

/// The `k`-th of `n` near-equal pieces of `0..total`.
fn piece(k: u32, n: u32, total: u32) -> Range<u32> {
    let at = |i: u32| (i as u64 * total as u64 / n as u64) as u32;
    at(k - 1)..at(k)
}

impl Split {
    /// The whole render.
    pub const WHOLE: Split = Split { kind: SplitKind::None, shard: 1, of: 1 };

    /// Parses `K/N`: shard K of N (the command line's `--shard`).
    pub fn parse(text: &str, kind: SplitKind) -> Result<Split> {
        let bad = |m: &str| Error::invalid("shard", format!("'{text}': {m}"));
        let (k, n) = text.split_once('/').ok_or_else(|| bad("expected K/N, e.g. 3/8"))?;
        let k: u32 = k.trim().parse().map_err(|_| bad("K must be a whole number"))?;
        let n: u32 = n.trim().parse().map_err(|_| bad("N must be a whole number"))?;
        if n == 0 || k == 0 || k > n {
            return Err(bad("K must be between 1 and N"));
        }
        Ok(Split { kind, shard: k, of: n })
    }

    /// Checks that every shard gets some work: at most `spp` shards by
    /// samples, at most `height` by rows.
    pub fn check(&self, spp: u32, height: u32) -> Result<()> {
        let (limit, what) = match self.kind {
            SplitKind::None => return Ok(()),
            SplitKind::Samples => (spp, "samples per pixel"),
            SplitKind::Rows => (height, "rows"),
        };
        if self.of > limit {
            return Err(Error::invalid(
                "shard",
                format!("{} shards by {:?} leave some empty: the render has only {limit} {what}", self.of, self.kind)
                    .to_lowercase(),
            ));
        }
        Ok(())
    }

    /// The sample indices this shard renders.
    pub fn samples(&self, spp: u32) -> Range<u32> {
        match self.kind {
            SplitKind::Samples => piece(self.shard, self.of, spp),
            _ => 0..spp,
        }
    }

    /// The rows this shard renders.
    pub fn rows(&self, height: u32) -> Range<u32> {
        match self.kind {
            SplitKind::Rows => piece(self.shard, self.of, height),
            _ => 0..height,
        }
    }

    /// E.g. "shard 2/4 by rows".
    pub fn describe(&self) -> String {
        match self.kind {
            SplitKind::None => "a whole render".into(),
            SplitKind::Samples => format!("shard {}/{} by samples", self.shard, self.of),
            SplitKind::Rows => format!("shard {}/{} by rows", self.shard, self.of),
        }
    }
}
