//! `rtow diff A B`: how far image A is from the reference B.

use super::{say, tell};
use clap::Args;
use rtow::instruments::diff::{self, DiffSpec, Limits, DEFAULT_GAMMA, DEFAULT_REGIONS, DEFAULT_Z, EXIT_EXCEEDED};
use rtow::Result;
use std::path::PathBuf;

#[derive(Args)]
#[command(after_help = "Exit status: 0 the comparison ran and every --max-* threshold held; 1 an output could not be \
                        written; 2 bad input (a file unreadable, damaged, of another size; a bad flag); 3 a \
                        threshold was exceeded (each one named on stderr).")]
pub struct DiffArgs {
    /// The image to check: PNG, EXR, PFM or a partial film (.rtfilm, its mean).
    a: PathBuf,
    /// The reference, of the same size: PNG, EXR, PFM or a partial film.
    b: PathBuf,
    /// A second render of A with another seed: A's noise, for the region z-tests (a film rendered with
    /// --adaptive carries its own).
    #[arg(long, value_name = "FILE")]
    a2: Option<PathBuf>,
    /// A second render of B with another seed: B's noise, for the region z-tests.
    #[arg(long, value_name = "FILE")]
    b2: Option<PathBuf>,
    #[arg(long, allow_negative_numbers = true, help = gamma_help())]
    gamma: Option<f32>,
    #[arg(long, allow_negative_numbers = true, help = ppd_help())]
    ppd: Option<f32>,
    /// The region z-tests split the image into K x K regions.
    #[arg(long, value_name = "K", default_value_t = DEFAULT_REGIONS)]
    regions: usize,
    /// A region-channel fails the z-test when |z| is above T.
    #[arg(long, value_name = "T", allow_negative_numbers = true, default_value_t = DEFAULT_Z)]
    z: f64,
    /// Exit status 3 if the MSE is above X.
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    max_mse: Option<f64>,
    /// Exit status 3 if the relMSE is above X.
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    max_rel_mse: Option<f64>,
    /// Exit status 3 if the mean FLIP is above X.
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    max_flip: Option<f64>,
    /// Exit status 3 if more than N region-channels fail the z-test (needs both sides' noise).
    #[arg(long, value_name = "N")]
    max_z_fails: Option<usize>,
    /// Write every figure as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Write the per-pixel FLIP as a PNG heatmap (the magma ramp: black 0, pale yellow 1).
    #[arg(long, value_name = "FILE")]
    heatmap: Option<PathBuf>,
    /// No summary on stdout (exceeded thresholds are still named on stderr).
    #[arg(short, long)]
    quiet: bool,
}

/// `--gamma`'s help.
fn gamma_help() -> String {
    format!(
        "The gamma PNG inputs were encoded with: each byte b is linear light ((b + 0.5) / 256)^G [default: {:.1}, the \
         gamma rtow writes its PNGs with by default, as the book does]. Linear inputs are encoded with it for FLIP",
        DEFAULT_GAMMA
    )
}

/// `--ppd`'s help.
fn ppd_help() -> String {
    format!(
        "FLIP's pixels per degree of visual angle [default: {:.2}, FLIP's: a 0.7 m wide 4K monitor seen from 0.7 m]",
        diff::flip::DEFAULT_PPD
    )
}

impl DiffArgs {
    fn spec(&self) -> DiffSpec {
        DiffSpec {
            a2: self.a2.clone(),
            b2: self.b2.clone(),
            gamma: self.gamma.unwrap_or(DEFAULT_GAMMA),
            ppd: self.ppd.unwrap_or(diff::flip::DEFAULT_PPD),
            regions: self.regions,
            z: self.z,
            limits: Limits {
                max_mse: self.max_mse,
                max_rel_mse: self.max_rel_mse,
                max_flip: self.max_flip,
                max_z_fails: self.max_z_fails,
            },
            json: self.json.clone(),
            heatmap: self.heatmap.clone(),
            ..DiffSpec::new(&self.a, &self.b)
        }
    }
}

/// The exit status: 0, or [`EXIT_EXCEEDED`] when a threshold was exceeded.
pub fn run(a: DiffArgs) -> Result<u8> {
    let (report, _) = diff::run(&a.spec())?;
    if !a.quiet {
        for line in report.summary() {
            say!("{}", rtow::output::printable(&line));
        }
    }
    for c in report.exceeded() {
        let flag = super::args::flag_of(c.limit).unwrap_or(c.limit);
        tell!("exceeded: {} is {}, above {flag} {}", c.what, c.value, c.max);
    }
    Ok(if report.passed { 0 } else { EXIT_EXCEEDED })
}
