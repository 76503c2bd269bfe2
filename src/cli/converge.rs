//! `rtow converge`: run time against error.

use super::args::kernel_parser;
use super::{load, say};
use clap::Args;
use rtow::estimator::ADAPTIVE_MIN_SPP;
use rtow::tools::converge::{self, Event, Reference, Variant};
use rtow::{Error, KernelChoice, Overrides, Result, Settings};
use std::path::PathBuf;

#[derive(Args)]
pub struct ConvergeArgs {
    /// A preset name (see `rtow scenes`) or a scene file (.json / .toml).
    scene: String,
    /// Kernels to measure, comma separated.
    #[arg(long, value_delimiter = ',', value_parser = kernel_parser(), default_value = "simd")]
    kernels: Vec<KernelChoice>,
    /// Estimator variants, comma separated: plain, rr (roulette after the default number of rays),
    /// rr:N (after N rays), adaptive (threshold 0.02), adaptive:THRESHOLD, sobol (Owen-scrambled
    /// Sobol points; sobol-pixel, sobol-lens, sobol-bounce1 for part of the layout), or
    /// combinations such as sobol+rr+adaptive:0.05. The first kernel's first variant is the
    /// baseline. The reference is always rendered with independent sampling.
    #[arg(long, value_delimiter = ',', default_value = "plain,rr,adaptive")]
    variants: Vec<String>,
    /// Samples per pixel to measure, increasing (the maximum, for adaptive variants).
    #[arg(long, value_delimiter = ',', default_value = "4,16,64,256")]
    spp_list: Vec<u32>,
    /// A linear reference image (.exr or .pfm) of the same size.
    #[arg(long, value_name = "FILE", conflicts_with = "reference_spp")]
    reference: Option<PathBuf>,
    /// Render the reference with N samples per pixel (and a different seed)
    /// [default: 8 x the largest --spp-list value]
    #[arg(long, value_name = "N")]
    reference_spp: Option<u32>,
    /// Output folder for <scene>.csv, <scene>.md, <scene>.svg (and <scene>-reference.exr).
    #[arg(long, default_value = "converge")]
    out: PathBuf,
    /// Image width in pixels [default: the scene's]
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels [default: the scene's]
    #[arg(long)]
    height: Option<u32>,
    /// Maximum rays per path [default: the scene's]
    #[arg(long)]
    depth: Option<u32>,
    /// Seed of the measured renders (the reference uses a seed derived from it) [default: the scene's, else 0]
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads [default: one per core]
    #[arg(long)]
    threads: Option<usize>,
    /// Tile edge in pixels
    #[arg(long, default_value_t = 16)]
    tile: u32,
    /// Render every measurement N times, in N passes over all of them, and keep the fastest
    /// time (the image is the same).
    #[arg(long, value_name = "N", default_value_t = 1)]
    repeat: u32,
    /// Adaptive variants decide after N, 2N, 4N, ... samples.
    #[arg(long, value_name = "N", default_value_t = ADAPTIVE_MIN_SPP)]
    adaptive_min: u32,
    /// The sampler of the variants that name none (plain, rr, ...).
    #[arg(long, value_parser = super::args::sampler_parser(), default_value = "independent")]
    sampler: rtow::sampling::Sampler,
    /// Also report what every configuration needs to reach the error of the baseline at N spp
    /// (N from --spp-list).
    #[arg(long, value_name = "N")]
    at_spp: Option<u32>,
}

pub fn run(a: ConvergeArgs) -> Result<()> {
    let (scene, name) = load(&a.scene)?;
    let overrides =
        Overrides { width: a.width, height: a.height, max_depth: a.depth, seed: a.seed, ..Default::default() };
    let s = Settings::resolve(&scene.render, &overrides);
    let mut variants = a.variants.iter().map(|v| Variant::parse(v)).collect::<Result<Vec<_>>>()?;
    for v in &mut variants {
        if v.sampler == rtow::sampling::Sampler::Independent {
            v.sampler = a.sampler;
        }
    }
    let reference = match (&a.reference, a.reference_spp) {
        (Some(p), _) => Reference::File(p.clone()),
        (None, Some(n)) => Reference::Spp(n),
        (None, None) => {
            let max = a.spp_list.iter().copied().max().unwrap_or(1);
            Reference::Spp(max.checked_mul(8).ok_or_else(|| {
                Error::invalid("--spp-list", format!("{max} is too large for the default --reference-spp (8x)"))
            })?)
        }
    };
    let cfg = converge::Config {
        settings: s,
        kernels: a.kernels.clone(),
        variants,
        spp_list: a.spp_list.clone(),
        reference: reference.clone(),
        threads: a.threads,
        tile: a.tile,
        repeat: a.repeat,
        adaptive_min: a.adaptive_min,
        at_spp: a.at_spp,
    };
    cfg.validate()?;
    if a.out.exists() && !a.out.is_dir() {
        return Err(Error::Output { path: a.out.clone(), message: "--out must be a folder".into() });
    }
    say!("{name}: {}x{}, depth {}, seed {}", s.width, s.height, s.max_depth, s.seed);
    let px = s.width as f64 * s.height as f64;
    let mut header = false;
    let report = converge::run(&scene, &name, &cfg, |e| match e {
        Event::ReferenceStart(n) => say!("reference: {n} spp with seed {} ...", converge::reference_seed(s.seed)),
        Event::ReferenceDone { seconds } => say!("reference: done in {seconds:.2} s"),
        Event::Measured(r) => {
            if !std::mem::replace(&mut header, true) {
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
            let c = r.cells(px);
            say!(
                "  {:<6} {:<18} {:>6} {:>9} {:>9} {:>8} {:>10} {:>10} {:>10} {:>11}",
                c[0],
                c[1],
                c[2],
                c[3],
                c[4],
                c[5],
                c[6],
                c[7],
                c[8],
                c[9]
            )
        }
    })?;
    for l in report.comparison_lines().iter().chain(&report.reach_lines()) {
        say!("{l}");
    }
    for p in report.write(&a.out)? {
        say!("wrote {}", p.display());
    }
    let mismatches = report.kernel_mismatches();
    if !mismatches.is_empty() {
        return Err(Error::Input(format!("the kernels must agree bit for bit, but {}", mismatches.join("; "))));
    }
    Ok(())
}
