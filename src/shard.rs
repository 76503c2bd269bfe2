//! Past one machine: a render split into shards (by sample range or by rows),
//! written as partial films, merged back into exactly the one-process image,
//! and resumed from a film with fewer samples.
//!
//! Every path's samples are a pure function of (seed, pixel, sample) and the
//! film's sums are exact integers ([`crate::film::accum`]), so any split adds
//! up to the same bits. The partial film format is [`crate::film::part`].

use crate::choice::Mode;
use crate::error::{Error, Result};
use crate::film::part::{self, PartCounters};
use crate::film::Film;
use crate::job::Job;
use crate::render::{render_portion, Portion, Progress, Rendered};
use std::path::{Path, PathBuf};

pub use crate::film::part::{is_part_path, merge, Header, Identity, Part, Split, SplitKind};

/// The PNG gamma of a part's scene (its `mode` setting), as `rtow render` chooses it.
pub fn default_gamma(part: &Part) -> f32 {
    let mode = part.header.settings.get("mode").cloned().unwrap_or_default();
    serde_json::from_value::<Mode>(serde_json::Value::String(mode)).unwrap_or_default().default_gamma()
}

/// A render that writes (or continues) a partial film.
pub struct FilmRequest {
    /// Which shard ([`Split::WHOLE`]: all of it).
    pub split: Split,
    /// A film of the first samples of this very render, to continue.
    pub resume: Option<(PathBuf, Part)>,
}

/// Refuses what cannot give the exact image, before any work.
pub fn check(job: &Job, req: &FilmRequest) -> Result<()> {
    let settings = job.settings();
    let opts = job.options();
    req.split.check(settings.spp, settings.height)?;
    if job.mode() == Mode::Gradient {
        return Err(Error::Input(
            "this scene traces no samples (a gradient): it has no film to split, write or resume".into(),
        ));
    }
    if opts.adaptive.is_some() && req.split.kind == SplitKind::Samples && req.split.of > 1 {
        return Err(Error::invalid(
            "split",
            "adaptive sampling decides from every sample a pixel has taken so far, so a shard of later \
             samples cannot know which pixels stopped: split adaptive renders by rows",
        ));
    }
    let Some((path, film)) = &req.resume else { return Ok(()) };
    let p = path.display();
    if req.split.kind != SplitKind::None {
        return Err(Error::invalid("resume", "continues a whole render; it cannot be combined with a shard"));
    }
    if opts.adaptive.is_some() {
        return Err(Error::invalid(
            "resume",
            "resuming adaptive sampling is not supported: the kernels would have to take the decision \
             at the resumed sample count first",
        ));
    }
    let h = &film.header;
    let mine = Part::new(
        &job.identity(),
        settings.spp,
        Split::WHOLE,
        crate::film::Film::new(0, 0, 0..0, false),
        PartCounters::default(),
    );
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
            "{p}: already has {} samples per pixel, more than the {} to render",
            h.samples[1], settings.spp
        )));
    }
    Ok(())
}

/// Renders the request's portion of `job` (after [`check`]): the image (of
/// this run's rows), its statistics, and the partial film to write.
pub fn render_part(
    job: &Job,
    req: &FilmRequest,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<(Rendered, Part)> {
    check(job, req)?;
    let settings = job.settings();
    let (start, mut counters) = match &req.resume {
        Some((_, p)) => (Some(&p.film), p.header.counters),
        None => (None, PartCounters::default()),
    };
    let first = req.resume.as_ref().map_or(0, |(_, p)| p.header.samples[1]);
    let samples = req.split.samples(settings.spp);
    let portion = Portion {
        rows: Some(req.split.rows(settings.height)),
        samples: Some(samples.start.max(first)..samples.end),
        start,
    };
    let (rendered, film) = render_portion(job, portion, progress)?;
    let film = film.ok_or_else(|| Error::Input("this scene traces no samples: it has no film".into()))?;
    let st = &rendered.stats;
    counters.add(&PartCounters { rays: st.rays, samples: st.samples, rejected_samples: st.rejected_samples });
    let part = Part::new(&job.identity(), settings.spp, req.split, film, counters);
    Ok((rendered, part))
}

/// Merges the partial films at `paths` (every shard of one render) into the
/// whole render's film, streaming: every header is read and checked first
/// (a few hundred bytes per part), then the set (same render, same split,
/// no duplicate, none missing, as [`merge`]), then the parts are read one at
/// a time in bounded pieces and added into one accumulator. Memory: one
/// image's accumulators and a 64 KiB buffer, whatever the number of parts.
/// Every refusal names the file (exit status 2).
pub fn merge_files(paths: &[PathBuf]) -> Result<Merged> {
    let mut headers = Vec::with_capacity(paths.len());
    for p in paths {
        let reader = Part::open(p)?;
        // Each part is read twice (its header now, its data later).
        if !std::fs::metadata(p).is_ok_and(|m| m.is_file()) {
            return Err(Error::Input(format!(
                "{}: not a regular file; merge reads each part twice (its header first), so give a file, \
                 not a pipe",
                p.display()
            )));
        }
        headers.push(reader.header().clone());
    }
    let set: Vec<(&Path, &Header)> = paths.iter().map(PathBuf::as_path).zip(&headers).collect();
    if let Err((blamed, e)) = part::check_set(&set) {
        // A header that differs because its file is corrupted is reported as corrupted.
        if let Some(i) = blamed {
            if part::checksum_ok(&paths[i]) == Some(false) {
                return Err(Error::Input(format!(
                    "{}: corrupted: its checksum does not match its contents",
                    paths[i].display()
                )));
            }
        }
        return Err(e);
    }
    let h0 = &headers[0];
    let moments = headers.iter().all(|h| h.moments);
    let mut film = Film::new(h0.width, h0.height, 0..h0.height, moments);
    for (p, h) in paths.iter().zip(&headers) {
        let reader = Part::open(p)?;
        if reader.header() != h {
            return Err(Error::Input(format!("{}: changed while the parts were merged", p.display())));
        }
        let offset = h.rows[0] as usize * h.width as usize;
        let mut overflow = false;
        reader.read_pixels(|i, px| overflow |= film.add_pixel(offset + i, px).is_none())?;
        if overflow {
            return Err(Error::Input(format!("{}: overlaps the other parts (a pixel's count overflows)", p.display())));
        }
    }
    let header = part::merged_header(&headers.iter().collect::<Vec<_>>(), &film);
    Ok(Merged { part: Part { header, film }, split: h0.split.kind })
}

/// What [`merge_files`] produced.
pub struct Merged {
    /// The whole render's film.
    pub part: Part,
    /// How the parts were split.
    pub split: SplitKind,
}
