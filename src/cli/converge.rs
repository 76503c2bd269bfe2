//! `rtow converge`: run time against error.

use super::args::{kernel_parser, RunArgs, SetArgs, SizeArgs};
use super::{say, tell};
use clap::Args;
use rtow::instruments::converge::{self, ConvergeConfig, ConvergeSpec, Event, Reference, ReportFiles, Variant};
use rtow::output::check_extension;
use rtow::{Error, Job, KernelChoice, Result, Sampler, ADAPTIVE_MIN_SPP};
use std::path::PathBuf;

#[derive(Args)]
pub struct ConvergeArgs {
    /// A preset name (see `rtow scenes`) or a scene file (.json / .toml).
    scene: String,
    /// Kernels to measure, comma separated.
    #[arg(long, value_delimiter = ',', value_parser = kernel_parser(), default_value = "simd")]
    kernels: Vec<KernelChoice>,
    #[arg(long, value_delimiter = ',', default_value = "plain,rr,adaptive", help = variants_help())]
    variants: Vec<String>,
    /// Samples per pixel to measure, increasing (the maximum, for adaptive variants).
    #[arg(long, allow_hyphen_values = true, value_delimiter = ',', default_value = "4,16,64,256")]
    spp_list: Vec<u32>,
    /// A linear reference image (.exr or .pfm) of the same size.
    #[arg(long, value_name = "FILE", conflicts_with = "reference_spp")]
    reference: Option<PathBuf>,
    #[arg(long, allow_negative_numbers = true, value_name = "N", help = reference_spp_help())]
    reference_spp: Option<u32>,
    /// Output folder for <scene>.csv, <scene>.md, <scene>.svg (and <scene>-reference.exr).
    #[arg(long, default_value = "converge")]
    out: PathBuf,
    #[command(flatten)]
    set: SetArgs,
    #[command(flatten)]
    size: SizeArgs,
    #[command(flatten)]
    run: RunArgs,
    /// Render every measurement N times, in N passes over all of them, and keep the fastest
    /// time (the image is the same).
    #[arg(long, allow_negative_numbers = true, value_name = "N", default_value_t = 1)]
    repeat: u32,
    /// Adaptive variants decide after N, 2N, 4N, ... samples.
    #[arg(long, allow_negative_numbers = true, value_name = "N", default_value_t = ADAPTIVE_MIN_SPP)]
    adaptive_min: u32,
    /// The sampler of the variants that name none (plain, rr, ...) [default: render's, sobol]
    #[arg(long, value_parser = super::args::sampler_parser())]
    sampler: Option<Sampler>,
    /// Also report what every configuration needs to reach the error of the baseline at N spp
    /// (N from --spp-list).
    #[arg(long, allow_negative_numbers = true, value_name = "N")]
    at_spp: Option<u32>,
    /// Also split every variant's error at N spp (N from --spp-list) by path length and by strategy
    /// (background, specular, scattered, light sample): --split-seeds renders with the scalar kernel,
    /// written to <scene>.md and <scene>-split.csv
    #[arg(long, allow_negative_numbers = true, value_name = "N")]
    split: Option<u32>,
    /// The renders (independent seeds) of --split.
    #[arg(long, allow_negative_numbers = true, value_name = "R", default_value_t = converge::DEFAULT_SPLIT_SEEDS)]
    split_seeds: u32,
}

/// `--variants`' help, naming the library's defaults.
fn variants_help() -> String {
    format!(
        "Estimator variants, comma separated: plain, rr (roulette after {} rays), rr:N (after N rays), adaptive \
         (threshold {}), adaptive:THRESHOLD, sobol (Owen-scrambled Sobol points; sobol-pixel, sobol-lens, \
         sobol-bounce1 for part of the layout), bsdf, book or nee-mis (the direction estimator; default: the scene's), or \
         combinations such as sobol+rr+adaptive:0.05 or book+sobol. The first kernel's first variant is the \
         baseline. The reference is always rendered with independent sampling and the bsdf estimator",
        rtow::ROULETTE_AFTER_RAYS,
        converge::DEFAULT_ADAPTIVE_THRESHOLD
    )
}

/// `--reference-spp`'s help, naming the factor the library uses.
fn reference_spp_help() -> String {
    format!(
        "Render the reference with N samples per pixel (and a different seed) [default: {} x the largest \
         --spp-list value]",
        converge::REFERENCE_SPP_FACTOR
    )
}

pub fn run(a: ConvergeArgs) -> Result<()> {
    let source = a.set.open(&a.scene)?;
    let job = Job::from_source(&source, &a.size.overrides(), &a.run.options(KernelChoice::Simd))?;
    let name = &source.name;
    let s = *job.settings();
    let mut variants = a.variants.iter().map(|v| Variant::parse(v)).collect::<Result<Vec<_>>>()?;
    for v in &mut variants {
        if v.sampler == Sampler::Independent {
            v.sampler = a.sampler.unwrap_or_default();
        }
    }
    let reference = match (&a.reference, a.reference_spp) {
        (Some(p), _) => Reference::File(p.clone()),
        (None, Some(n)) => Reference::Spp(n),
        (None, None) => Reference::default_for(&a.spp_list)?,
    };
    let cfg = ConvergeConfig::new(ConvergeSpec {
        kernels: a.kernels.clone(),
        variants,
        spp_list: a.spp_list.clone(),
        reference,
        repeat: a.repeat,
        adaptive_min: a.adaptive_min,
        at_spp: a.at_spp,
        split: a.split,
        split_seeds: a.split_seeds,
    })?;
    // Every file the run writes is checked now, before any rendering, and
    // written together at the end.
    let mut inputs: Vec<(&std::path::Path, &str)> = Vec::new();
    if let Some(f) = &source.file {
        inputs.push((f, "scene file"));
    }
    if let Some(r) = &a.reference {
        check_extension(r, &["pfm", "exr"], "reference")?;
        inputs.push((r, "reference"));
    }
    let files = ReportFiles::check(&a.out, name, a.reference.is_none(), a.split.is_some(), &inputs)?;
    say!("{name}: {}x{}, depth {}, seed {}", s.width, s.height, s.max_depth, s.seed);
    let px = s.width as f64 * s.height as f64;
    let mut header = false;
    let report = converge::run(&job, name, &cfg, |e| show(e, px, &mut header))?;
    for l in report.comparison_lines().iter().chain(&report.reach_lines()) {
        say!("{l}");
    }
    for p in report.write(files)? {
        say!("wrote {}", p.display());
    }
    let mismatches = report.kernel_mismatches();
    if !mismatches.is_empty() {
        return Err(Error::Input(format!("the kernels must agree bit for bit, but {}", mismatches.join("; "))));
    }
    Ok(())
}

/// Prints a run's progress: the reference, then a table row per measurement.
fn show(e: Event, px: f64, header: &mut bool) {
    match e {
        Event::ReferenceStart { spp, seed } => say!("reference: {spp} spp with seed {seed} ..."),
        Event::ReferenceDone { seconds } => say!("reference: done in {seconds:.2} s"),
        Event::ReferenceNoise(n) => match n.warning() {
            Some(w) => tell!("warning: {w}"),
            None => say!("reference: its own noise is {:.1}% of the smallest error measured", 100.0 * n.share()),
        },
        Event::SplitStart { variant, spp, seeds } => {
            say!("split: {} at {spp} spp, {seeds} scalar renders ...", variant.name())
        }
        Event::SplitDone(sp) => {
            let c = sp.covariance();
            say!(
                "split: {}: MSE {:.3e}, of which {:.1}% covariance; largest length: {}",
                sp.variant.name(),
                sp.total_var,
                100.0 * c / sp.total_var.max(f64::MIN_POSITIVE),
                largest_length(sp)
            )
        }
        Event::Measured(r) => {
            if !std::mem::replace(header, true) {
                say!(
                    "  {:<6} {:<18} {:>6} {:>9} {:>9} {:>8} {:>10} {:>10} {:>10} {:>11}",
                    "kernel",
                    "variant",
                    "spp",
                    "seconds",
                    "Mrays/s",
                    "spp/px",
                    "RMSE",
                    "relMSE",
                    "signed err",
                    "efficiency"
                );
            }
            say!("  {}", r.cells(px).iter().enumerate().map(|(i, c)| pad(i, c)).collect::<Vec<_>>().join(" "));
        }
    }
}

/// The path length with the largest share of a split's variance.
fn largest_length(sp: &converge::Split) -> String {
    let (l, v) =
        (0..converge::LENGTHS).map(|l| (l, sp.by_length(l).1)).fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
    format!("{} ({:.1}% of the MSE)", converge::length_label(l), 100.0 * v / sp.total_var.max(f64::MIN_POSITIVE))
}

/// Cell `i` of a row, padded as the header is.
fn pad(i: usize, c: &str) -> String {
    const WIDTHS: [usize; 10] = [6, 18, 6, 9, 9, 8, 10, 10, 10, 11];
    if i < 2 {
        format!("{c:<w$}", w = WIDTHS[i])
    } else {
        format!("{c:>w$}", w = WIDTHS[i])
    }
}
