//! `rtow merge`: partial films (the shards of one render) into the image, bit
//! for bit the one a single process renders with the same scene and settings.

use super::args::{OutputArgs, RejectedArgs, VerifyArgs};
use super::{say, tell};
use clap::Args;
use rtow::files;
use rtow::Result;
use std::path::PathBuf;

#[derive(Args)]
pub struct MergeArgs {
    /// The partial films (.rtfilm) of one render: every shard of its split, in any order.
    #[arg(required = true, value_name = "PART")]
    parts: Vec<PathBuf>,
    /// Output image by its extension: PNG (8-bit, gamma encoded), EXR or PFM
    /// (linear), or a partial film (.rtfilm) of the whole render (to resume
    /// it with more samples later).
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    files: OutputArgs,
    #[command(flatten)]
    verify: VerifyArgs,
    #[command(flatten)]
    rejected: RejectedArgs,
    /// No summary line (warnings are still printed).
    #[arg(short, long)]
    quiet: bool,
}

pub fn run(a: MergeArgs) -> Result<()> {
    let st =
        files::merge_to_files(&a.parts, &a.files.files(a.output.clone()), a.verify.verify(), a.rejected.on_rejected)?;
    if let Some(w) = st.rejected().warning() {
        tell!("warning: the parts' {w}");
    }
    if !a.quiet {
        say!(
            "merged {} part(s) ({}x{}, {} spp, split by {}) -> {}: {} rays, {} samples, image hash {}, in {:.3} s \
             (read {:.3} s, merge {:.3} s, write {:.3} s); {}",
            st.parts,
            st.settings.width,
            st.settings.height,
            st.settings.spp,
            st.split.name(),
            a.output.display(),
            st.rays,
            st.samples,
            st.image_hash,
            st.seconds,
            st.read_seconds,
            st.merge_seconds,
            st.write_seconds,
            super::args::verified(&st.verified)
        );
    }
    Ok(())
}
