//! `rtow merge`: partial films (the shards of one render) into the image, bit
//! for bit the one a single process renders with the same scene and settings.

use super::args::positive_f32;
use super::say;
use clap::Args;
use rayon::prelude::*;
use rtow::film::part::{self, is_part_path, Part};
use rtow::output::{check_extension, image_bytes, Outputs};
use rtow::Result;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct MergeArgs {
    /// The partial films (.rtfilm) of one render: every shard of its split, in any order.
    #[arg(required = true, value_name = "PART")]
    parts: Vec<PathBuf>,
    /// Output PNG (8-bit, gamma encoded), or a partial film (.rtfilm) of the
    /// whole render (to resume it with more samples later).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the linear image: .pfm or .exr.
    #[arg(long, value_name = "FILE")]
    float: Option<PathBuf>,
    /// Write statistics as JSON: the parts, the summed counters, the image hash, the time taken.
    #[arg(long, value_name = "FILE")]
    stats_json: Option<PathBuf>,
    /// PNG gamma [default: the scene's, as rtow render chooses it]
    #[arg(long, value_parser = positive_f32)]
    gamma: Option<f32>,
    /// No summary line.
    #[arg(short, long)]
    quiet: bool,
}

pub fn run(a: MergeArgs) -> Result<()> {
    let t0 = Instant::now();
    let film_out = is_part_path(&a.output);
    check_extension(&a.output, &["png", "rtfilm"], "-o")?;
    if let Some(f) = &a.float {
        check_extension(f, &["pfm", "exr"], "--float")?;
    }
    // The outputs are one transaction (see `rtow::output`); no output may be one of the parts.
    let mut outputs = Outputs::new();
    for p in &a.parts {
        outputs.input(p, "partial film");
    }
    let out_id = outputs.add(&a.output, "-o")?;
    let float_id = a.float.as_deref().map(|f| outputs.add(f, "--float")).transpose()?;
    let stats_id = a.stats_json.as_deref().map(|j| outputs.add(j, "--stats-json")).transpose()?;
    // Read (and check) every part; the first failure in the order given is reported.
    let read: Vec<Result<Part>> = a.parts.par_iter().map(|p| Part::read(p)).collect();
    let mut parts = Vec::with_capacity(read.len());
    for (p, r) in a.parts.iter().zip(read) {
        parts.push((p.clone(), r?));
    }
    let read_seconds = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let merged = part::merge(&parts)?;
    let image = merged.film.image();
    let merge_seconds = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    if film_out {
        outputs.stage(out_id, &merged.to_bytes())?;
    } else {
        let gamma = a.gamma.unwrap_or_else(|| rtow::shard::default_gamma(&merged));
        outputs.stage(out_id, &image_bytes(&image, &a.output, gamma)?)?;
    }
    if let (Some(id), Some(f)) = (float_id, &a.float) {
        outputs.stage(id, &image_bytes(&image, f, 1.0)?)?;
    }
    let h = &merged.header;
    let split = parts[0].1.header.split;
    let hash = format!("{:016x}", image.hash());
    let mut stats = serde_json::json!({
        "parts": a.parts.len(),
        "split": split.kind,
        "width": h.width,
        "height": h.height,
        "spp": h.spp,
        "rays": h.counters.rays,
        "samples": h.counters.samples,
        "rejected_samples": h.counters.rejected_samples,
        "read_seconds": read_seconds,
        "merge_seconds": merge_seconds,
        "image_hash": hash,
    });
    let write_seconds = t2.elapsed().as_secs_f64();
    stats["write_seconds"] = write_seconds.into();
    stats["seconds"] = t0.elapsed().as_secs_f64().into();
    if let Some(id) = stats_id {
        let text = serde_json::to_string_pretty(&stats).expect("stats serialize") + "\n";
        outputs.stage(id, text.as_bytes())?;
    }
    outputs.commit()?;
    if !a.quiet {
        say!(
            "merged {} part(s) ({}x{}, {} spp, split by {}) -> {}: {} rays, {} samples, image hash {hash}, in {:.3} s \
             (read {:.3} s, merge {:.3} s, write {:.3} s)",
            a.parts.len(),
            h.width,
            h.height,
            h.spp,
            serde_json::to_value(split.kind).ok().and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default(),
            a.output.display(),
            h.counters.rays,
            h.counters.samples,
            t0.elapsed().as_secs_f64(),
            read_seconds,
            merge_seconds,
            write_seconds
        );
    }
    if h.counters.rejected_samples > 0 && !a.quiet {
        say!("{} samples were rejected (NaN, Inf or out of range) in the parts", h.counters.rejected_samples);
    }
    Ok(())
}
