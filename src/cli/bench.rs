//! `rtow bench`: rays/s and work per ray of each kernel; baselines.

use super::args::{kernel_parser, ImageArgs};
use super::{load, say, tell};
use clap::Args;
use rtow::output::Outputs;
use rtow::tools::bench::{self, Baseline, Verdict};
use rtow::{Error, KernelChoice, Result};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct BenchArgs {
    /// A preset name or a scene file.
    #[arg(default_value = "final")]
    scene: String,
    /// Kernels to measure, in order (simd: the widest this build has).
    #[arg(long, value_delimiter = ',', value_parser = kernel_parser(), default_value = "scalar,simd")]
    kernels: Vec<KernelChoice>,
    #[command(flatten)]
    image: ImageArgs,
    /// Timed renders per kernel; the median-time one is reported (plus one render with the work counters on).
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Write the report as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Save the report as a baseline for later runs.
    #[arg(long, value_name = "FILE")]
    save: Option<PathBuf>,
    /// Compare with a saved baseline: exit status 1 if the image changed, the work
    /// per ray grew, or throughput fell by more than the tolerance.
    #[arg(long, value_name = "FILE")]
    baseline: Option<PathBuf>,
    /// Allowed throughput drop against the baseline, in percent.
    #[arg(long, default_value_t = 5.0)]
    tolerance: f64,
    /// Instead of timing: the traversal work per packet at each ray depth (how
    /// coherence is lost bounce by bounce), for each kernel, from one counted render.
    #[arg(long)]
    by_depth: bool,
}

/// Ok(false): a regression against the baseline (exit status 1).
pub fn run(a: BenchArgs) -> Result<bool> {
    rtow::limits::check_threads(a.image.threads)?;
    let (scene, name) = load(&a.scene)?;
    let s = a.image.settings(&scene);
    if a.image.tile != 16 {
        return Err(Error::invalid("--tile", "rtow bench uses the default tile size"));
    }
    if !(a.tolerance >= 0.0) {
        return Err(Error::invalid("--tolerance", "must be a percentage >= 0"));
    }
    let cfg = bench::Config {
        settings: s,
        kernels: a.kernels.clone(),
        threads: a.image.threads,
        accel: a.image.accel,
        repeat: a.repeat,
    };
    // Everything is checked before anything is measured.
    cfg.validate()?;
    let baseline = a.baseline.as_deref().map(Baseline::load).transpose()?;
    if let Some(b) = &baseline {
        b.check(&name, &s, &a.kernels)?;
    }
    // The outputs are one transaction: distinct from each other and from the
    // inputs, checked now, written together after the measurements.
    let mut outputs = Outputs::new();
    if rtow::scene::preset(&a.scene).is_none() {
        outputs.input(Path::new(&a.scene), "scene file");
    }
    if let Some(b) = &a.baseline {
        outputs.input(b, "baseline");
    }
    let mut ids = Vec::new();
    for (path, flag) in [(&a.json, "--json"), (&a.save, "--save")] {
        if let Some(p) = path {
            ids.push(outputs.add(p, flag)?);
        }
    }
    if a.by_depth {
        for &k in &a.kernels {
            say!("{}:", rtow::Kernel::resolve(k)?.name());
            say!("{}", bench::depth_table(&bench::work_by_depth(&scene, &cfg, k)?).trim_end());
        }
        return Ok(true);
    }
    tell!(
        "bench {name}: {}x{} {} spp depth {} seed {}, {} repetition(s) per kernel, built for {}",
        s.width,
        s.height,
        s.spp,
        s.max_depth,
        s.seed,
        a.repeat,
        rtow::isa()
    );
    let report = bench::run(&scene, &name, &cfg, |k, i, st| {
        tell!("  {} run {}: {:.3} s, {:.2} Mrays/s", k.name(), i + 1, st.seconds, st.mrays_per_s)
    })?;
    say!("{}", report.table().trim_end_matches('\n'));
    let json = report.to_json();
    for id in ids {
        outputs.stage(id, json.as_bytes())?;
    }
    outputs.commit()?;
    let mut ok = true;
    if let Some(b) = &baseline {
        for c in bench::compare(&report, b, a.tolerance) {
            let work = match c.work_change_percent {
                None => "work: not in the baseline".to_string(),
                Some(0.0) => "work identical".to_string(),
                Some(w) => format!("work {w:+.2}%"),
            };
            say!(
                "{:<7} baseline {:.2} Mrays/s -> {:.2} Mrays/s ({:+.1}%), image {}, {work}: {}{}",
                c.kernel,
                c.baseline_mrays,
                c.mrays,
                c.change_percent,
                if c.image_same { "identical" } else { "CHANGED" },
                if c.regressed { "REGRESSION" } else { "ok" },
                match c.verdict {
                    Verdict::Same => "",
                    Verdict::TimingOnly => " (timing only: same image and work)",
                    Verdict::Work => " (the algorithm's work changed)",
                    Verdict::Image => " (the image changed)",
                }
            );
            ok &= !c.regressed;
        }
    }
    Ok(ok)
}
