//! Where the error lives: a variant's error split by path length and by
//! strategy (`rtow converge --split N`).
//!
//! A pixel's value is a sum of terms, each from one path length (segments
//! from the camera to the light or the background) and one [`Strategy`]. The
//! split renders a variant `seeds` times at N samples per pixel with
//! independent seeds (the first is the run's own seed, so its image is the one
//! converge measured), with the scalar reference kernel (every kernel renders
//! the same bits) and a probe that adds each term into its (length,
//! strategy) bucket of its pixel ([`Probe::contributed`]).
//!
//! Across the renders each bucket's pixel values vary: their variance,
//! averaged over pixels and channels, is the bucket's error at N spp. The
//! image's own variance across the renders is its MSE at N spp (the
//! estimators are unbiased); what the buckets' variances leave of it is twice
//! their covariances. The Sobol sampler is scrambled per seed, so the variance
//! across seeds is its true error, stratification included; it is not the
//! per-sample variance over N, which would miss it.
//!
//! Multiplied by the variant's measured seconds at N spp, a variance is an
//! MSE x seconds: the inverse of converge's efficiency, per bucket. Two
//! estimators' tables side by side say which lengths and strategies cost one
//! of them its time against the other.

use super::Variant;
use crate::choice::KernelChoice;
use crate::error::{Error, Result};
use crate::job::{Job, Overrides, RenderOptions};
use crate::probe::{Observed, PathEvents, PathId, Strategy};
use crate::render::render_probed;
use crate::sampling::mix64;
use crate::vec3::V3;
use std::collections::HashMap;
use std::fmt::Write as _;

/// Path lengths shown apart: 1 to `LENGTHS - 1`, and `LENGTHS` and longer together.
pub const LENGTHS: usize = 10;
const STRATEGIES: usize = Strategy::ALL.len();
const BUCKETS: usize = LENGTHS * STRATEGIES;

/// The largest image a split renders: it keeps 2 x 8 bytes per bucket,
/// channel and pixel (1,920 bytes a pixel), and its probes a sum of each.
pub const MAX_SPLIT_PIXELS: u64 = 40_000;

/// The most seeds a split renders.
pub const MAX_SPLIT_SEEDS: u32 = 1024;

fn bucket(length: u32, s: Strategy) -> usize {
    (length.clamp(1, LENGTHS as u32) as usize - 1) * STRATEGIES + s as usize
}

/// The label of length row `l` (0-based).
pub fn length_label(l: usize) -> String {
    if l + 1 == LENGTHS {
        format!("{LENGTHS}+")
    } else {
        format!("{}", l + 1)
    }
}

/// The probe: for every pixel its tile rendered, each bucket's sum over the
/// samples, per channel.
#[derive(Default)]
struct SplitProbe {
    sums: Sums,
}

/// Per pixel, each bucket's sum per channel.
type Sums = HashMap<u32, Box<[[f64; 3]; BUCKETS]>>;

impl PathEvents for SplitProbe {
    fn finish(self: Box<Self>) -> Box<dyn std::any::Any + Send> {
        Box::new(self.sums)
    }

    fn contributed(&mut self, id: PathId<f32>, length: u32, strategy: Strategy, c: V3<f32>) {
        let b = self.sums.entry(id.pixel).or_insert_with(|| Box::new([[0.0; 3]; BUCKETS]));
        let e = &mut b[bucket(length, strategy)];
        e[0] += c.x as f64;
        e[1] += c.y as f64;
        e[2] += c.z as f64;
    }
}

/// One variant's split.
#[derive(Clone, Debug)]
pub struct Split {
    pub variant: Variant,
    pub spp: u32,
    pub seeds: u32,
    /// The variant's render time at `spp` as converge measured it (its first kernel).
    pub seconds: f64,
    /// Per bucket (length-major: `length_row * 4 + strategy`): the mean of its pixel values.
    pub mean: Vec<f64>,
    /// Per bucket: the variance across seeds of its pixel values (mean over pixels and channels).
    pub var: Vec<f64>,
    /// The image's variance across seeds: its MSE at `spp`.
    pub total_var: f64,
    /// The largest difference between an image's pixel and the sum of its
    /// buckets, relative to the pixel (at least 1): rounding only, unless a
    /// term escaped the probe.
    pub unaccounted: f64,
}

/// The seed of a split's render `r`: the run's own for 0.
pub fn split_seed(seed: u64, r: u32) -> u64 {
    if r == 0 {
        seed
    } else {
        mix64(seed ^ mix64(0x5350_4C49_5400_0000 | r as u64))
    }
}

/// Checks a split's settings against the image size.
pub(super) fn check(width: u32, height: u32, seeds: u32) -> Result<()> {
    if !(2..=MAX_SPLIT_SEEDS).contains(&seeds) {
        return Err(Error::invalid("split_seeds", format!("must be from 2 to {MAX_SPLIT_SEEDS}, got {seeds}")));
    }
    let px = width as u64 * height as u64;
    if px > MAX_SPLIT_PIXELS {
        return Err(Error::invalid(
            "split",
            format!(
                "a {width}x{height} image has {px} pixels; the split keeps every bucket of every pixel and takes at most \
                 {MAX_SPLIT_PIXELS} (set a smaller --width and --height)"
            ),
        ));
    }
    Ok(())
}

/// The job of split render `r`: `job` (a measurement's) with the scalar
/// kernel and [`split_seed`].
fn replicate(job: &Job, r: u32) -> Result<Job> {
    let opts = RenderOptions { kernel: KernelChoice::Scalar, ..*job.options() };
    let o = Overrides { seed: Some(split_seed(job.settings().seed, r)), ..Overrides::from(*job.settings()) };
    job.with(&o, &opts)
}

/// Splits the error of `job` (a variant's measurement at `spp`, not
/// adaptive), rendered `seeds` times; `seconds` is its measured time.
/// `want_hash` is the measured image's hash, which the first render must
/// reproduce.
pub(super) fn split(job: &Job, variant: Variant, seeds: u32, seconds: f64, want_hash: &str) -> Result<Split> {
    let s = *job.settings();
    check(s.width, s.height, seeds)?;
    let px = s.width as usize * s.height as usize;
    let n = px * BUCKETS * 3;
    let (mut sum, mut sq) = (vec![0f64; n], vec![0f64; n]);
    let (mut tsum, mut tsq) = (vec![0f64; px * 3], vec![0f64; px * 3]);
    let mut unaccounted = 0f64;
    let inv = 1.0 / s.spp as f64;
    for r in 0..seeds {
        let j = replicate(job, r)?;
        let (rendered, probes) = render_probed(&j, None, &|| Observed::with(SplitProbe::default()))?;
        if r == 0 && rendered.stats.image_hash != want_hash {
            return Err(Error::Input(format!(
                "the split's scalar render of {} at {} spp is image {}, but converge measured {want_hash}: the kernels \
                 must agree bit for bit",
                variant.name(),
                s.spp,
                rendered.stats.image_hash
            )));
        }
        let mut found = vec![[0f64; 3]; px];
        for p in probes {
            let sums: Sums = p.finish();
            for (pixel, b) in sums {
                let base = pixel as usize * BUCKETS * 3;
                for (k, v) in b.iter().enumerate() {
                    for ch in 0..3 {
                        let x = v[ch] * inv;
                        sum[base + k * 3 + ch] += x;
                        sq[base + k * 3 + ch] += x * x;
                        found[pixel as usize][ch] += x;
                    }
                }
            }
        }
        for (i, (img, f)) in rendered.image.data.iter().zip(&found).enumerate() {
            for ch in 0..3 {
                let v = img[ch] as f64;
                tsum[i * 3 + ch] += v;
                tsq[i * 3 + ch] += v * v;
                unaccounted = unaccounted.max((v - f[ch]).abs() / v.abs().max(1.0));
            }
        }
    }
    let rs = seeds as f64;
    let var_of = |s: f64, q: f64| ((q - s * s / rs) / (rs - 1.0)).max(0.0);
    let values = (px * 3) as f64;
    let mut mean = vec![0f64; BUCKETS];
    let mut var = vec![0f64; BUCKETS];
    for i in 0..n {
        let k = (i / 3) % BUCKETS;
        mean[k] += sum[i] / rs;
        var[k] += var_of(sum[i], sq[i]);
    }
    mean.iter_mut().chain(var.iter_mut()).for_each(|x| *x /= values);
    let total_var = tsum.iter().zip(&tsq).map(|(&s, &q)| var_of(s, q)).sum::<f64>() / values;
    Ok(Split { variant, spp: s.spp, seeds, seconds, mean, var, total_var, unaccounted })
}

impl Split {
    /// The variance of length row `l`'s strategy `s`.
    pub fn var_of(&self, l: usize, s: Strategy) -> f64 {
        self.var[l * STRATEGIES + s as usize]
    }

    /// Length row `l`'s mean and variance, every strategy together (its
    /// strategies' covariances left out).
    pub fn by_length(&self, l: usize) -> (f64, f64) {
        let r = l * STRATEGIES..(l + 1) * STRATEGIES;
        (self.mean[r.clone()].iter().sum(), self.var[r].iter().sum())
    }

    /// The image's MSE that the buckets' variances do not account for: twice
    /// their covariances (negative when strategies compensate each other).
    pub fn covariance(&self) -> f64 {
        self.total_var - self.var.iter().sum::<f64>()
    }

    /// CSV rows: one per bucket with a term, then the covariance and the total.
    pub fn csv_rows(&self, scene: &str, out: &mut String) {
        let name = self.variant.name();
        let row = |out: &mut String, len: &str, strat: &str, mean: f64, var: f64| {
            let _ = writeln!(
                out,
                "{scene},{name},{},{},{len},{strat},{mean:.6e},{var:.6e},{:.6e},{:.6}",
                self.spp,
                self.seeds,
                var * self.seconds,
                self.seconds
            );
        };
        for l in 0..LENGTHS {
            for s in Strategy::ALL {
                let k = l * STRATEGIES + s as usize;
                if self.mean[k] != 0.0 || self.var[k] != 0.0 {
                    row(out, &length_label(l), s.name(), self.mean[k], self.var[k]);
                }
            }
        }
        row(out, "", "covariance", 0.0, self.covariance());
        row(out, "", "total", self.mean.iter().sum(), self.total_var);
    }

    /// A markdown table: variance by length (rows) and strategy (columns),
    /// with each length's mean and share of the MSE.
    pub fn markdown(&self) -> String {
        let used: Vec<Strategy> =
            Strategy::ALL.into_iter().filter(|&s| (0..LENGTHS).any(|l| self.var_of(l, s) > 0.0)).collect();
        let mut s = format!(
            "**{}** at {} spp, {} seeds: MSE {:.3e} (RMSE {:.5}), {:.3} s, MSE x s {:.3e}; terms the probe missed: \
             {:.1e} of a pixel at most\n\n",
            self.variant.name(),
            self.spp,
            self.seeds,
            self.total_var,
            self.total_var.sqrt(),
            self.seconds,
            self.total_var * self.seconds,
            self.unaccounted
        );
        s += "| length | mean |";
        for st in &used {
            let _ = write!(s, " {} |", st.name());
        }
        s += " variance | share of MSE |\n|---:|---:|";
        s += &"---:|".repeat(used.len() + 2);
        s += "\n";
        for l in 0..LENGTHS {
            let (m, v) = self.by_length(l);
            if m == 0.0 && v == 0.0 {
                continue;
            }
            let _ = write!(s, "| {} | {m:.4} |", length_label(l));
            for &st in &used {
                let _ = write!(s, " {:.2e} |", self.var_of(l, st));
            }
            let _ = writeln!(s, " {v:.2e} | {:.1}% |", 100.0 * v / self.total_var.max(f64::MIN_POSITIVE));
        }
        let c = self.covariance();
        let _ = writeln!(
            s,
            "| covariance | |{} {c:.2e} | {:.1}% |",
            " |".repeat(used.len()),
            100.0 * c / self.total_var.max(f64::MIN_POSITIVE)
        );
        s
    }
}

/// The variants' MSE x seconds by path length, side by side (variants as
/// columns): where one estimator's time against error goes compared with another's.
pub fn comparison_markdown(splits: &[Split]) -> String {
    let mut s = String::from("| length |");
    for sp in splits {
        let _ = write!(s, " {} |", sp.variant.name());
    }
    s += "\n|---:|";
    s += &"---:|".repeat(splits.len());
    s += "\n";
    for l in 0..LENGTHS {
        if splits.iter().all(|sp| sp.by_length(l).1 == 0.0) {
            continue;
        }
        let _ = write!(s, "| {} |", length_label(l));
        for sp in splits {
            let _ = write!(s, " {:.2e} |", sp.by_length(l).1 * sp.seconds);
        }
        s += "\n";
    }
    s += "| covariance |";
    for sp in splits {
        let _ = write!(s, " {:.2e} |", sp.covariance() * sp.seconds);
    }
    s += "\n| **all** |";
    for sp in splits {
        let _ = write!(s, " **{:.2e}** |", sp.total_var * sp.seconds);
    }
    s + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_and_seeds() {
        assert_eq!(bucket(1, Strategy::Background), 0);
        assert_eq!(bucket(0, Strategy::LightSample), 3);
        assert_eq!(bucket(2, Strategy::Specular), STRATEGIES + 1);
        assert_eq!(bucket(LENGTHS as u32, Strategy::Scattered), bucket(500, Strategy::Scattered));
        assert_eq!(length_label(0), "1");
        assert_eq!(length_label(LENGTHS - 1), format!("{LENGTHS}+"));
        assert_eq!(split_seed(7, 0), 7);
        let seeds: std::collections::HashSet<u64> = (0..100).map(|r| split_seed(7, r)).collect();
        assert_eq!(seeds.len(), 100);
        assert!(check(200, 200, 8).is_ok());
        assert!(check(201, 200, 8).unwrap_err().to_string().starts_with("split:"));
        assert!(check(10, 10, 1).unwrap_err().to_string().starts_with("split_seeds:"));
    }
}
