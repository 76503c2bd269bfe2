//! Past one machine: a render split into shards (by sample range or by rows),
//! written as partial films, merged back into exactly the one-process image,
//! and resumed from a film with fewer samples.
//!
//! Every path's samples are a pure function of (seed, pixel, sample) and the
//! film's sums are exact integers ([`crate::film::accum`]), so any split adds
//! up to the same bits. The partial film format is [`crate::film::part`].

use crate::choice::{EstimatorChoice, KernelChoice, Mode};
use crate::error::{Error, Result};
use crate::estimator::{Adaptive, Estimator, Roulette};
use crate::film::part::{self, PartCounters, Pixel};
use crate::film::Film;
use crate::job::{Job, Overrides, RenderOptions};
use crate::render::{render_pixels, render_portion, render_rounds, Portion, Progress, Rendered};
use crate::rounds::Rounds;
use crate::settings::Settings;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use crate::film::part::{is_part_path, merge, Header, Identity, Part, Split, SplitKind};

/// The PNG gamma of a part's scene (its `mode` setting), as `rtow render` chooses it.
pub fn default_gamma(part: &Part) -> f32 {
    let mode = part.header.settings.get("mode").cloned().unwrap_or_default();
    serde_json::from_value::<Mode>(serde_json::Value::String(mode)).unwrap_or_default().default_gamma()
}

/// A render that writes (or continues) a partial film, checked against its
/// job once, when it is made ([`FilmRequest::new`]): what cannot give the
/// exact image is refused before any work, and [`render_part`] checks nothing again.
pub struct FilmRequest<'a> {
    job: &'a Job,
    split: Split,
    resume: Option<(PathBuf, Part)>,
}

impl<'a> FilmRequest<'a> {
    /// The shard `split` of `job` ([`Split::WHOLE`]: all of it), continuing
    /// `resume` (a film of the first samples of this very render, read from
    /// its path) if given; refuses what cannot give the exact image.
    pub fn new(job: &'a Job, split: Split, resume: Option<(PathBuf, Part)>) -> Result<FilmRequest<'a>> {
        check(job, split, resume.as_ref())?;
        Ok(FilmRequest { job, split, resume })
    }

    pub fn job(&self) -> &'a Job {
        self.job
    }

    pub fn split(&self) -> Split {
        self.split
    }

    /// The film continued, and the path it was read from.
    pub fn resume(&self) -> Option<(&Path, &Part)> {
        self.resume.as_ref().map(|(p, f)| (p.as_path(), f))
    }
}

/// Refuses what cannot give the exact image, before any work.
fn check(job: &Job, split: Split, resume: Option<&(PathBuf, Part)>) -> Result<()> {
    let settings = job.settings();
    let opts = job.options();
    split.check(settings.spp, settings.height)?;
    if job.mode() == Mode::Gradient {
        return Err(Error::Input(
            "this scene traces no samples (a gradient): it has no film to split, write or resume".into(),
        ));
    }
    if opts.adaptive.is_some() && split.kind == SplitKind::Samples && split.of > 1 {
        return Err(Error::invalid(
            "split",
            "adaptive sampling decides from every sample a pixel has taken so far, so a shard of later \
             samples cannot know which pixels stopped: split adaptive renders by rows",
        ));
    }
    let Some((path, film)) = resume else { return Ok(()) };
    let p = path.display();
    if split.kind != SplitKind::None {
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
        Vec::new(),
        settings.spp,
        Split::WHOLE,
        crate::film::Film::new(0, 0, 0..0, false).scaled(job.plan().film_scale()),
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

/// A render to continue, read from its partial film alone.
pub struct FilmScene {
    /// The film's embedded scene, named after the film (files it names are
    /// found beside the film).
    pub source: crate::scene::SceneSource,
    /// The settings its header records (`spp`: the samples it holds).
    pub settings: Settings,
    /// Its roulette and adaptive sampling.
    pub estimator: Estimator,
}

/// The scene and settings of the render a partial film is of: what
/// `render --resume FILM` continues when it is given no scene. The film's
/// data is checked when it is resumed.
pub fn scene_of_film(path: &Path) -> Result<FilmScene> {
    let part = Part::read(path)?;
    let s = RenderSettings::of(&part.header).map_err(|m| Error::Input(format!("{}: {m}", path.display())))?;
    let text = std::str::from_utf8(&part.scene)
        .map_err(|e| Error::Input(format!("{}: the embedded scene is not UTF-8: {e}", path.display())))?;
    let scene = crate::scene::scene_from_str(text, crate::scene::Format::Json, path)?;
    let name = path.file_stem().map_or_else(|| "film".into(), |s| s.to_string_lossy().into_owned());
    let source = crate::scene::SceneSource { scene, name, file: Some(path.to_path_buf()) };
    Ok(FilmScene { source, settings: s.settings, estimator: s.estimator })
}

/// Renders the request's portion of its job (checked when the request was
/// made): the image (of this run's rows), its statistics, and the partial
/// film to write.
pub fn render_part(req: &FilmRequest, progress: Option<&(dyn Fn(Progress) + Sync)>) -> Result<(Rendered, Part)> {
    render_part_in(req, None, false, progress)
}

/// [`render_part`], in the rounds of samples `rounds` decides when given
/// (a whole render: [`crate::rounds`]): the film is then of the samples the
/// rounds reached, a whole render of that many samples per pixel. With
/// `counted`, the statistics carry the exact work counters.
pub(crate) fn render_part_in(
    req: &FilmRequest,
    rounds: Option<&mut (dyn Rounds + Send)>,
    counted: bool,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<(Rendered, Part)> {
    let job = req.job;
    let settings = job.settings();
    let (start, mut counters) = match &req.resume {
        Some((_, p)) => (Some(&p.film), p.header.counters),
        None => (None, PartCounters::default()),
    };
    let first = req.resume.as_ref().map_or(0, |(_, p)| p.header.samples[1]);
    let samples = req.split.samples(settings.spp);
    let portion = Portion {
        cols: None,
        rows: Some(req.split.rows(settings.height)),
        samples: Some(samples.start.max(first)..samples.end),
        start,
    };
    let in_rounds = rounds.is_some();
    let (rendered, film) = match rounds {
        None => render_portion(job, portion, progress)?,
        Some(rounds) => {
            debug_assert!(req.split.kind == SplitKind::None, "only a whole render goes in rounds");
            render_rounds(job, portion, rounds, counted, progress)?
        }
    };
    let film = film.ok_or_else(|| Error::Input("this scene traces no samples: it has no film".into()))?;
    let st = &rendered.stats;
    counters.add(&PartCounters {
        rays: st.rays,
        samples: st.samples,
        rejected_samples: st.rejected_samples,
        rejected_out_of_range: st.rejected_out_of_range,
    });
    // Rounds that stopped early: a whole render of the samples reached.
    let spp = if in_rounds { rendered.stats.spp } else { settings.spp };
    let part = Part::new(&job.identity(), job.scene_json(), spp, req.split, film, counters);
    Ok((rendered, part))
}

/// Merges the partial films at `paths` (every shard of one render) into the
/// whole render's film, streaming: every header is read and checked first
/// (a few hundred bytes per part), then the set (same render, same split,
/// no duplicate, none missing, as [`merge`]), then the parts are read one at
/// a time in bounded pieces and added into one accumulator. Memory: one
/// image's accumulators and a 64 KiB buffer, whatever the number of parts.
/// Every refusal names the file (exit status 2).
///
/// With `verify.pixels > 0`, each part's data is checked by recomputation
/// (see [`Verify`]): the first part's embedded scene and the header's
/// settings make a job, and `verify.pixels` pixels of every part, drawn from
/// `verify.seed`, are rendered again over the part's samples and compared
/// bit for bit with the part's data.
pub fn merge_files(paths: &[PathBuf], verify: Verify) -> Result<Merged> {
    verify.check()?;
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
    let mut film = Film::new(h0.width, h0.height, 0..h0.height, moments).scaled(Part::scale(h0));
    let mut report = Verified { pixels_per_part: verify.pixels, seed: verify.seed, pixels: 0, seconds: 0.0 };
    let mut job: Option<Job> = None;
    let mut scene0 = Vec::new();
    for (k, (p, h)) in paths.iter().zip(&headers).enumerate() {
        let reader = Part::open(p)?;
        if reader.header() != h {
            return Err(Error::Input(format!("{}: changed while the parts were merged", p.display())));
        }
        let offset = h.rows[0] as usize * h.width as usize;
        let chosen = verify.choose(h);
        let mut stored = Vec::with_capacity(chosen.len());
        let mut overflow = false;
        let (_, scene) = reader.read_pixels(|i, px| {
            overflow |= film.add_pixel(offset + i, px).is_none();
            if chosen.get(stored.len()) == Some(&i) {
                stored.push(*px);
            }
        })?;
        if overflow {
            return Err(Error::Input(format!("{}: overlaps the other parts (a pixel's count overflows)", p.display())));
        }
        if !chosen.is_empty() {
            let t = Instant::now();
            if job.is_none() {
                job = Some(verification_job(p, h, &scene)?);
            }
            let job = job.as_ref().expect("made above");
            check_pixels(job, p, h, &chosen, &stored, verify)?;
            report.pixels += chosen.len() as u64;
            report.seconds += t.elapsed().as_secs_f64();
        }
        if k == 0 {
            scene0 = scene;
        }
    }
    let header = part::merged_header(&headers.iter().collect::<Vec<_>>(), &film);
    Ok(Merged { part: Part { header, film, scene: scene0 }, split: h0.split.kind, verified: report })
}

/// How a merge (or a resume) checks the data of a partial film by
/// recomputation. Every sample is a pure function of (seed, pixel, sample),
/// so a part's data for a pixel is known without trusting the part: render
/// the pixel again over the part's samples (from its embedded scene and
/// settings) and compare the sample count, the exact sums and (with
/// adaptive sampling) the sums of squares, bit for bit. `pixels` pixels of
/// each part are checked (all of them if the part has fewer; 0: none), drawn
/// at random from `seed` (reported, so a run can be repeated).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Verify {
    pub pixels: u32,
    pub seed: u64,
}

impl Verify {
    /// Pixels per part checked by default: a few milliseconds of rendering
    /// per part at the book's settings (docs/shards.md measures the cost).
    pub const DEFAULT_PIXELS: u32 = 64;
    /// No verification.
    pub const OFF: Verify = Verify { pixels: 0, seed: 0 };
    /// Most pixels per part: the pixels checked are held in memory (about
    /// 300 bytes each); a part checked whole is better rendered again.
    pub const MAX_PIXELS: u32 = 1 << 16;

    /// Refuses more pixels per part than [`Verify::MAX_PIXELS`].
    pub fn check(&self) -> Result<()> {
        if self.pixels > Self::MAX_PIXELS {
            return Err(Error::invalid(
                "verify",
                format!("{} pixels per part is too many; at most {}", self.pixels, Self::MAX_PIXELS),
            ));
        }
        Ok(())
    }

    /// `pixels` per part, from a seed drawn at random (from the standard
    /// library's per-process random keys).
    pub fn with_random_seed(pixels: u32) -> Verify {
        use std::hash::{BuildHasher, Hasher};
        let mut h = std::collections::hash_map::RandomState::new().build_hasher();
        h.write_u128(std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos()));
        Verify { pixels, seed: h.finish() }
    }

    /// The pixels of a part with header `h` to check: indices into its rows
    /// (row-major), sorted, distinct; drawn from the seed and the shard.
    pub fn choose(&self, h: &Header) -> Vec<usize> {
        let n = h.width as u64 * (h.rows[1] - h.rows[0]) as u64;
        let k = self.pixels as u64;
        if k >= n {
            return (0..n as usize).collect();
        }
        // SplitMix64 from the seed and the shard; Floyd's sampling of k of n.
        let mut state = self.seed ^ (h.split.shard as u64).wrapping_mul(0xd1b5_4a32_d192_ed03);
        let mut next = || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        };
        let mut set = std::collections::BTreeSet::new();
        for j in n - k..n {
            let t = next() % (j + 1);
            if !set.insert(t) {
                set.insert(j);
            }
        }
        set.into_iter().map(|i| i as usize).collect()
    }
}

/// What a verification checked.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Verified {
    /// Pixels asked for per part (`--verify`).
    pub pixels_per_part: u32,
    /// The seed they were drawn from (`--verify-seed`).
    pub seed: u64,
    /// Pixels rendered again and compared, over all parts.
    pub pixels: u64,
    /// Seconds spent on it (the embedded scene laid out, the pixels rendered).
    pub seconds: f64,
}

/// The job that renders the pixels of a part `p` (header `h`) again: its
/// embedded scene with the header's settings, on the scalar reference
/// kernel. It must have the part's image key: a part of another rtow
/// version (which may render differently) cannot be verified.
fn verification_job(p: &Path, h: &Header, scene: &[u8]) -> Result<Job> {
    let s = RenderSettings::of(h).map_err(|m| Error::Input(format!("{}: {m}", p.display())))?;
    let overrides = Overrides::from(s.settings);
    let options = RenderOptions {
        kernel: KernelChoice::Scalar,
        roulette: s.estimator.roulette,
        adaptive: s.estimator.adaptive,
        ..Default::default()
    };
    let cannot = |why: String| {
        Error::Input(format!(
            "{}: cannot render it again to verify it: {why}; merge with --verify 0 to trust it",
            p.display()
        ))
    };
    let job = Job::from_scene_json(scene, p, &overrides, &options)
        .map_err(|e| cannot(part::quoted_to(&e.to_string(), 300)))?;
    let now = job.identity();
    if format!("{:016x}", now.key()) != h.key {
        let version = env!("CARGO_PKG_VERSION");
        let changed = part::INPUT_FILES
            .iter()
            .map(|&(setting, _)| (setting, now.settings.get(setting), h.settings.get(setting)))
            .find(|(_, now, then)| now != then);
        return Err(cannot(if h.rtow != version {
            format!(
                "it was written by rtow {}, and this is rtow {version}, which may render it differently",
                part::quoted(&h.rtow)
            )
        } else if let Some((setting, now, then)) = changed {
            part::files_changed(setting, now, then, "read now", "it was rendered with")
        } else {
            format!(
                "its image key {} is not the one this rtow ({version}) gives its scene and settings",
                part::quoted(&h.key)
            )
        }));
    }
    if job.mode() == Mode::Gradient {
        return Err(cannot("its scene traces no samples".into()));
    }
    if job.plan().film_exponent != h.film_exponent {
        return Err(cannot(format!(
            "its film has scale exponent {}, but this rtow gives its scene {}",
            h.film_exponent,
            job.plan().film_exponent
        )));
    }
    Ok(job)
}

/// Renders the pixels `chosen` of the part `p` (header `h`) again with `job`
/// over the part's samples and compares them with `stored`, the part's data
/// for them; refuses the part (exit status 2), naming the first pixel that
/// differs.
fn check_pixels(job: &Job, p: &Path, h: &Header, chosen: &[usize], stored: &[Pixel], v: Verify) -> Result<()> {
    let adaptive = job.options().adaptive.is_some();
    if h.moments != adaptive {
        return Err(Error::Input(format!(
            "{}: {} sums of squares, but it was rendered with adaptive = {}",
            p.display(),
            if h.moments { "has" } else { "has no" },
            h.settings.get("adaptive").map_or("(unset)".into(), |a| part::quoted(a))
        )));
    }
    let w = h.width as usize;
    let coords: Vec<(u32, u32)> = chosen.iter().map(|&i| ((i % w) as u32, h.rows[0] + (i / w) as u32)).collect();
    let fresh = render_pixels(job, &coords, h.samples[0]..h.samples[1]);
    for ((t, s), (x, y)) in fresh.iter().zip(stored).zip(&coords) {
        let sq = |v: [f64; 3]| v.map(f64::to_bits);
        let same = t.count[0] == s.count && t.sum[0] == s.sum && (!adaptive || sq(t.sum_sq[0]) == sq(s.sum_sq));
        if !same {
            let mean = |sum: [i128; 3], n: u32| Part::scale(h).mean(sum, n);
            return Err(Error::Input(format!(
                "{}: pixel ({x}, {y}) is not what its scene renders over samples {}..{}: the part holds {} samples \
                 of mean {:?}, rendering it again gives {} of mean {:?} (verified with --verify-seed {}); the part \
                 was rendered differently or its data was changed",
                p.display(),
                h.samples[0],
                h.samples[1],
                s.count,
                mean(s.sum, s.count),
                t.count[0],
                mean(t.sum[0], t.count[0]),
                v.seed
            )));
        }
    }
    Ok(())
}

/// Checks the film a request resumes (already checked, when the request
/// was made, to be a whole render of its job's image) by recomputation, as
/// a merge checks its parts ([`Verify`]); `None` if it resumes none.
pub fn verify_film(req: &FilmRequest, verify: Verify) -> Result<Option<Verified>> {
    let Some((path, film)) = req.resume() else { return Ok(None) };
    let job = req.job;
    verify.check()?;
    let h = &film.header;
    let chosen = verify.choose(h);
    let t = Instant::now();
    if !chosen.is_empty() {
        let w = h.width as usize;
        let stored: Vec<Pixel> = chosen
            .iter()
            .map(|&i| Pixel {
                count: film.film.count[i],
                sum: film.film.sum[i],
                sum_sq: film.film.sum_sq.get(i).copied().unwrap_or_default(),
            })
            .collect();
        debug_assert!(chosen.iter().all(|&i| i < w * (h.rows[1] - h.rows[0]) as usize));
        check_pixels(job, path, h, &chosen, &stored, verify)?;
    }
    Ok(Some(Verified {
        pixels_per_part: verify.pixels,
        seed: verify.seed,
        pixels: chosen.len() as u64,
        seconds: t.elapsed().as_secs_f64(),
    }))
}

/// What [`merge_files`] produced.
pub struct Merged {
    /// The whole render's film.
    pub part: Part,
    /// How the parts were split.
    pub split: SplitKind,
    /// What the verification checked.
    pub verified: Verified,
}

/// The settings a partial film's header carries: the render's [`Settings`]
/// (its size and sample count are the header's own fields) and its
/// estimator options.
pub struct RenderSettings {
    /// The estimator is `bsdf` where the header names none (the identity
    /// leaves the default out).
    pub settings: Settings,
    pub estimator: Estimator,
}

impl RenderSettings {
    pub fn of(h: &Header) -> std::result::Result<RenderSettings, String> {
        let get = |k: &str| h.settings.get(k).map(String::as_str).ok_or(format!("the header has no setting '{k}'"));
        let bad = |k: &str, v: &str| format!("the header's {k} '{}' is not one rtow writes", part::quoted(v));
        let (d, s, sm, rr, ad) =
            (get("max_depth")?, get("seed")?, get("sampler")?, get("russian_roulette")?, get("adaptive")?);
        let settings = Settings {
            width: h.width,
            height: h.height,
            spp: h.spp,
            max_depth: d.parse().map_err(|_| bad("max_depth", d))?,
            seed: s.parse().map_err(|_| bad("seed", s))?,
            sampler: sm.parse().map_err(|_| bad("sampler", sm))?,
            estimator: match h.settings.get("estimator") {
                None => EstimatorChoice::Bsdf,
                Some(e) => e.parse().map_err(|_| bad("estimator", e))?,
            },
        };
        let estimator = Estimator {
            roulette: Roulette::from_description(rr).ok_or_else(|| bad("russian_roulette", rr))?,
            adaptive: Adaptive::from_description(ad).ok_or_else(|| bad("adaptive", ad))?,
        };
        Ok(RenderSettings { settings, estimator })
    }
}
