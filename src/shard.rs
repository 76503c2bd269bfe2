//! Past one machine: a render split into shards (by sample range or by rows),
//! written as partial films, merged back into exactly the one-process image,
//! and resumed from a film with fewer samples.
//!
//! Every path's samples are a pure function of (seed, pixel, sample) and the
//! film's sums are exact integers ([`crate::film::accum`]), so any split adds
//! up to the same bits. The partial film format is [`crate::film::part`].

use crate::error::{Error, Result};
use crate::film::part::{self, Identity, Part, PartCounters, Split, SplitKind};
use crate::plan::Mode;
use crate::render::{render_portion, Portion, Progress, Rendered};
use crate::scene::Scene;
use crate::settings::{RenderOptions, Settings};
use std::path::{Path, PathBuf};

pub use crate::film::part::{is_part_path, merge};

/// What makes this render's image: the scene and every setting that changes
/// it. The kernel, lane width, threads, tile size and accelerator do not
/// change the image and are not part of it; nor is the sample count (kept
/// apart, see [`Identity`]) except where it changes the samples themselves
/// (one sample per pixel goes through the pixel centres).
pub fn identity(scene: &Scene, settings: &Settings, opts: &RenderOptions) -> Identity {
    let scene_json = serde_json::to_vec(scene).expect("a scene serializes");
    let plan = crate::prepare::plan(scene, settings, opts.accel);
    let mut map = std::collections::BTreeMap::new();
    let mut set = |k: &str, v: String| {
        map.insert(k.to_string(), v);
    };
    // The mode is the scene's (already in its hash); merge takes the PNG gamma from it.
    set("mode", mode_name(scene.mode));
    set("max_depth", settings.max_depth.to_string());
    set("seed", settings.seed.to_string());
    set("pixel_jitter", plan.jitter.to_string());
    set("sampler", opts.sampler.name().to_string());
    set("russian_roulette", if opts.rr { format!("after {} rays", opts.rr_after) } else { "off".into() });
    set(
        "adaptive",
        match opts.adaptive {
            Some(a) => format!("threshold {} from {} spp", a.threshold, a.min_spp),
            None => "off".into(),
        },
    );
    Identity { scene_hash: part::fnv1a(&scene_json), width: settings.width, height: settings.height, settings: map }
}

fn mode_name(m: Mode) -> String {
    serde_json::to_value(m).ok().and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default()
}

/// The PNG gamma of a part's scene (its `mode` setting), as `rtow render` chooses it.
pub fn default_gamma(part: &Part) -> f32 {
    let mode = part.header.settings.get("mode").cloned().unwrap_or_default();
    serde_json::from_value::<Mode>(serde_json::Value::String(mode)).unwrap_or_default().default_gamma()
}

/// A render that writes (or continues) a partial film.
pub struct Job {
    /// Which shard ([`Split::WHOLE`]: all of it).
    pub split: Split,
    /// A film of the first samples of this very render, to continue.
    pub resume: Option<(PathBuf, Part)>,
}

/// Refuses what cannot give the exact image, before any work.
pub fn check(scene: &Scene, settings: &Settings, opts: &RenderOptions, job: &Job) -> Result<()> {
    job.split.check(settings.spp, settings.height)?;
    if scene.mode == Mode::Gradient {
        return Err(Error::Input(
            "this scene traces no samples (a gradient): it has no film to split, write or resume".into(),
        ));
    }
    if opts.adaptive.is_some() && job.split.kind == SplitKind::Samples && job.split.of > 1 {
        return Err(Error::invalid(
            "--split",
            "adaptive sampling decides from every sample a pixel has taken so far, so a shard of later \
             samples cannot know which pixels stopped: split adaptive renders by rows (--split rows)",
        ));
    }
    let Some((path, film)) = &job.resume else { return Ok(()) };
    let p = path.display();
    if job.split.kind != SplitKind::None {
        return Err(Error::invalid("--resume", "continues a whole render; it cannot be combined with --shard"));
    }
    if opts.adaptive.is_some() {
        return Err(Error::invalid(
            "--resume",
            "resuming adaptive sampling is not supported: the kernels would have to take the decision \
             at the resumed sample count first",
        ));
    }
    let h = &film.header;
    let id = identity(scene, settings, opts);
    let mine =
        Part::new(&id, settings.spp, Split::WHOLE, crate::film::Film::new(0, 0, 0..0, false), PartCounters::default());
    part::same_image(path, h, Path::new("this render"), &mine.header, "this render cannot continue it")?;
    if h.split.kind != SplitKind::None || h.rows != [0, h.height] || h.samples[0] != 0 {
        return Err(Error::Input(format!(
            "{p}: covers rows {}..{} and samples {}..{} ({}); --resume needs a whole render \
             (merge the shards first)",
            h.rows[0],
            h.rows[1],
            h.samples[0],
            h.samples[1],
            h.split.describe()
        )));
    }
    if h.samples[1] > settings.spp {
        return Err(Error::Input(format!(
            "{p}: already has {} samples per pixel, more than --spp {}",
            h.samples[1], settings.spp
        )));
    }
    Ok(())
}

/// Renders the job's portion (after [`check`]): the image (of this run's rows),
/// its statistics, and the partial film to write.
pub fn render_part(
    scene: &Scene,
    settings: Settings,
    opts: RenderOptions,
    job: &Job,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<(Rendered, Part)> {
    check(scene, &settings, &opts, job)?;
    let (start, mut counters) = match &job.resume {
        Some((_, p)) => (Some(&p.film), p.header.counters),
        None => (None, PartCounters::default()),
    };
    let first = job.resume.as_ref().map_or(0, |(_, p)| p.header.samples[1]);
    let samples = job.split.samples(settings.spp);
    let portion = Portion {
        rows: Some(job.split.rows(settings.height)),
        samples: Some(samples.start.max(first)..samples.end),
        start,
    };
    let (rendered, film) = render_portion(scene, settings, opts, portion, progress)?;
    let film = film.ok_or_else(|| Error::Input("this scene traces no samples: it has no film".into()))?;
    let st = &rendered.stats;
    counters.add(&PartCounters { rays: st.rays, samples: st.samples, rejected_samples: st.rejected_samples });
    let part = Part::new(&identity(scene, &settings, &opts), settings.spp, job.split, film, counters);
    Ok((rendered, part))
}
