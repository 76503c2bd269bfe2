//! A render (or a merge of partial films) to its output files, as one
//! transaction: every input read and checked, every output checked, then the
//! work, then all outputs written together (see [`crate::output`]). What a
//! command-line run decides beyond its flags lives here: whether the run
//! renders a whole image or a partial film, whether it counts work for the
//! statistics, and the order of the checks.

use crate::choice::{EstimatorChoice, OnInterrupt, OnRejected};
use crate::error::{Error, Result};
use crate::estimator::{Adaptive, Estimator, Roulette};
use crate::film::aov::{self, Aovs, Features};
use crate::film::part::{self, is_part_path, Part, Split, SplitKind};
use crate::film::{Image, TileFilm};
use crate::job::Job;
use crate::output::{check_extension, Graceful, OutputId, Outputs};
use crate::plan::Plan;
use crate::probe::WorkCounters;
use crate::provenance::Provenance;
use crate::render::{render, render_counted, render_crop, render_features, AovReport, Crop, Progress, Rendered, Stats};
use crate::rounds::{Preview, RoundsReport, Schedule, Stopped};
use crate::sampling::Sampler;
use crate::scene::SceneSource;
use crate::settings::Settings;
use crate::shard::{self, FilmRequest};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The files a render or a merge writes.
#[derive(Clone, Debug, Default)]
pub struct RenderFiles {
    /// The image (`.png`, 8-bit, gamma encoded; `.exr` or `.pfm`, linear)
    /// or a partial film (`.rtfilm`).
    pub output: PathBuf,
    /// The linear image: `.pfm` or `.exr`.
    pub float: Option<PathBuf>,
    /// The statistics, as JSON.
    pub stats: Option<PathBuf>,
    /// The PNG gamma (default: the scene's, 2 for path tracing, 1 for the debug chapters).
    pub gamma: Option<f32>,
    /// What errors call the three files (default: `output`, `float`, `stats`).
    pub names: FileNames,
}

/// What errors call a run's files: the field names by default; a command
/// line names its flags.
#[derive(Clone, Copy, Debug)]
pub struct FileNames {
    pub output: &'static str,
    pub float: &'static str,
    pub stats: &'static str,
}

impl Default for FileNames {
    fn default() -> Self {
        FileNames { output: "output", float: "float", stats: "stats" }
    }
}

impl RenderFiles {
    fn check_types(&self) -> Result<()> {
        check_extension(&self.output, &["png", "exr", "pfm", part::EXTENSION], self.names.output)?;
        if let Some(f) = &self.float {
            check_extension(f, &["pfm", "exr"], self.names.float)?;
        }
        if let Some(g) = self.gamma {
            if !(g.is_finite() && g > 0.0) {
                return Err(Error::invalid("gamma", format!("must be a finite number > 0, got {g}")));
            }
        }
        Ok(())
    }

    /// Checks every file as an output of `outputs`.
    fn add_to(&self, outputs: &mut Outputs) -> Result<(OutputId, Option<OutputId>, Option<OutputId>)> {
        let n = &self.names;
        let out = outputs.add(&self.output, n.output)?;
        let float = self.float.as_deref().map(|f| outputs.add(f, n.float)).transpose()?;
        let stats = self.stats.as_deref().map(|f| outputs.add(f, n.stats)).transpose()?;
        Ok((out, float, stats))
    }

    /// Whether the output is a partial film.
    pub fn writes_film(&self) -> bool {
        is_part_path(&self.output)
    }
}

/// A render to files: the job, which piece of it (a shard, or all), a film
/// to resume from, and the files to write.
#[derive(Clone, Debug)]
pub struct RenderRequest<'a> {
    pub source: &'a SceneSource,
    pub job: &'a Job,
    /// [`Split::WHOLE`], or one shard (which writes a partial film).
    pub split: Split,
    /// A partial film of the first samples of this very render, to continue.
    pub resume: Option<PathBuf>,
    /// How the film to resume is checked by recomputation ([`shard::Verify`]).
    pub verify: shard::Verify,
    pub files: RenderFiles,
    /// Whether rejected samples fail the render (nothing written) or only
    /// warn (the caller prints [`Stats::rejected`]'s warning).
    pub on_rejected: OnRejected,
    /// A time limit, previews, and what a signal does.
    pub rounds: RoundsRequest,
    /// Only this window of the image (an image of its size, its pixels
    /// those of the whole render); rendered in one go, to an image.
    pub crop: Option<Crop>,
    /// Feature buffers to write beside the colour ([`crate::film::aov`]):
    /// layers of the EXR the run writes (the output, else `--float`), else
    /// PFM files beside the image.
    pub aov: Aovs,
}

/// Refuses what a crop cannot be combined with.
fn check_crop(req: &RenderRequest) -> Result<()> {
    let Some(c) = &req.crop else { return Ok(()) };
    let s = req.job.settings();
    c.check(s.width, s.height)?;
    let with = if req.split.kind != SplitKind::None {
        Some("--shard")
    } else if req.resume.is_some() {
        Some("--resume")
    } else if req.files.writes_film() {
        Some("a partial film output (.rtfilm)")
    } else if req.rounds.time_limit.is_some() {
        Some("--time-limit")
    } else if req.rounds.preview_every.is_some() {
        Some("--preview-every")
    } else {
        None
    };
    match with {
        Some(w) => Err(Error::invalid("crop", format!("renders a window in one go, to an image; not with {w}"))),
        None => Ok(()),
    }
}

/// How a whole render goes in rounds of samples ([`crate::rounds`]): with a
/// time limit or previews, and, by default, so that SIGINT, SIGTERM or
/// SIGHUP leave a film to resume ([`OnInterrupt::Film`]). Adaptive sampling,
/// shards and scenes that trace no samples render in one go (a time limit
/// or previews are refused for them).
#[derive(Clone, Copy, Debug, Default)]
pub struct RoundsRequest {
    /// Render whole rounds while the next one fits in this budget, then
    /// write the image of the samples reached (at least one per pixel).
    pub time_limit: Option<Duration>,
    /// Rewrite the output image (atomically, the lock kept) after the first
    /// round and then after a round once this much time has passed.
    pub preview_every: Option<Duration>,
    pub on_interrupt: OnInterrupt,
}

impl RoundsRequest {
    /// Whether the run asked for what only rounds give (a time limit, previews).
    fn asked(&self) -> bool {
        self.time_limit.is_some() || self.preview_every.is_some()
    }
}

/// Where a render stopped by a signal writes its film when its output is
/// an image: the output with the extension `.rtfilm` (a film output is
/// written itself).
pub fn interrupt_film_path(output: &Path) -> PathBuf {
    output.with_extension(part::EXTENSION)
}

/// Refuses a time limit or previews that this render cannot honour.
fn check_rounds(req: &RenderRequest) -> Result<()> {
    let r = &req.rounds;
    if !r.asked() {
        return Ok(());
    }
    let flag = if r.time_limit.is_some() { "time_limit" } else { "preview_every" };
    if req.split.kind != SplitKind::None {
        return Err(Error::invalid(flag, "a shard renders its piece whole; it needs a whole render"));
    }
    if req.job.options().adaptive.is_some() {
        return Err(Error::invalid(
            flag,
            "adaptive sampling decides at doubling sample counts, so it cannot stop between rounds: \
             drop one of the two",
        ));
    }
    if req.job.mode() == crate::choice::Mode::Gradient {
        return Err(Error::invalid(flag, "this scene traces no samples (a gradient): it renders at once"));
    }
    if r.preview_every.is_some() && req.files.writes_film() {
        return Err(Error::invalid(
            "preview_every",
            "previews an image: write a .png, .exr or .pfm (a film is written on an interrupt anyway)",
        ));
    }
    if let Some(t) = r.preview_every {
        if t.is_zero() {
            return Err(Error::invalid("preview_every", "must be longer than 0 s"));
        }
    }
    Ok(())
}

/// Renders `req` and writes its files; returns the statistics (the run's,
/// written to `files.stats` too). Bad input is refused (exit status 2), then
/// an output that cannot be written (1), before any rendering. A render that
/// rejected more than [`crate::limits::MAX_REJECTED_FRACTION`] of its
/// samples, or any under [`OnRejected::Error`], writes nothing (exit status 2).
pub fn render_to_files(req: &RenderRequest, progress: Option<&(dyn Fn(Progress) + Sync)>) -> Result<Stats> {
    let files = &req.files;
    check_request(req)?;
    let resume = match &req.resume {
        Some(p) => Some((p.clone(), Part::read(p)?)),
        None => None,
    };
    // Rounds: asked for, or so that a signal leaves a film.
    let graceful = req.rounds.on_interrupt == OnInterrupt::Film;
    let in_rounds = (req.rounds.asked() || graceful)
        && req.crop.is_none()
        && req.split.kind == SplitKind::None
        && req.job.options().adaptive.is_none()
        && req.job.mode() != crate::choice::Mode::Gradient;
    // A partial film (a shard, a resumed render, a whole render to resume
    // later, or one that a signal may stop) is checked against the job
    // once, here.
    let film = match files.writes_film() || resume.is_some() || in_rounds {
        true => Some(FilmRequest::new(req.job, req.split, resume)?),
        false => None,
    };
    let verified = match &film {
        Some(f) => shard::verify_film(f, req.verify)?,
        None => None,
    };
    let mut out = Planned::new(req, in_rounds && graceful)?;
    let mut r = match &film {
        Some(film) if in_rounds => match render_in_rounds(req, film, &mut out, graceful, progress)? {
            Ran::Done(r) => r,
            Ran::Stopped(stats) => return Ok(stats),
        },
        Some(film) => {
            let (r, part) = shard::render_part(film, progress)?;
            r.stats.rejected().check(req.on_rejected)?;
            out.stage_film(req, &part)?;
            r
        }
        None => {
            // Statistics come with the exact work counters (a counted render costs nothing measurable).
            let counted = files.stats.is_some();
            let r: Rendered = match &req.crop {
                Some(c) => render_crop(req.job, c, counted, progress)?,
                None if counted => render_counted(req.job, progress)?,
                None => render(req.job, progress)?,
            };
            r.stats.rejected().check(req.on_rejected)?;
            r
        }
    };
    let features = req.aov.any().then(|| features_of(req, &mut r.stats));
    out.stage_images(req, &r, features.as_ref())?;
    if let Some(id) = out.stats {
        let mut file = StatsFile::of_render(&r.stats, req.split);
        file.verified = verified;
        out.outputs.stage(id, json(&file).as_bytes())?;
    }
    out.outputs.commit()?;
    Ok(r.stats)
}

/// The checks of a request that need no file read.
fn check_request(req: &RenderRequest) -> Result<()> {
    req.files.check_types()?;
    if req.split.kind != SplitKind::None && !req.files.writes_film() {
        return Err(Error::invalid(
            "shard",
            format!(
                "a shard writes a partial film: write it to {}-{}.rtfilm, then merge the parts",
                req.source.name, req.split.shard
            ),
        ));
    }
    check_crop(req)?;
    check_rounds(req)?;
    check_aov(req)
}

/// Refuses feature buffers where no image is written.
fn check_aov(req: &RenderRequest) -> Result<()> {
    if !req.aov.any() {
        return Ok(());
    }
    if req.files.writes_film() {
        return Err(Error::invalid(
            "aov",
            "feature buffers come with an image: write a .png, .exr or .pfm (a partial film carries none)",
        ));
    }
    if req.job.mode() == crate::choice::Mode::Gradient {
        return Err(Error::invalid("aov", "this scene traces no rays (a gradient): it has no surfaces to describe"));
    }
    Ok(())
}

/// The EXR file that holds the feature buffers as layers: the output if it
/// is one, else `--float` if it is one; `None`: they go to PFM files.
fn layered_exr(files: &RenderFiles) -> Option<&Path> {
    let exr = |p: &Path| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    Some(files.output.as_path()).filter(|p| exr(p)).or(files.float.as_deref().filter(|p| exr(p)))
}

/// A render's outputs, checked: the transaction and which output is which.
struct Planned {
    outputs: Outputs,
    main: OutputId,
    float: Option<OutputId>,
    stats: Option<OutputId>,
    /// The film a signal leaves, when the output is not a film itself.
    interrupt: Option<(PathBuf, OutputId)>,
    /// The feature buffers' PFM files ([`aov::beside`] the output), in
    /// [`Aovs::names`] order.
    aov: Vec<OutputId>,
    gamma: f32,
}

impl Planned {
    /// The outputs are one transaction: checked now, written only when all
    /// of them are ready. The resume film was read whole before, so the
    /// output (and only the output) may replace it: a render continued in
    /// place; with `interruptible`, so may the film a signal leaves.
    fn new(req: &RenderRequest, interruptible: bool) -> Result<Planned> {
        let files = &req.files;
        let mut outputs = Outputs::new();
        if let Some(f) = req.source.file.as_ref().filter(|f| Some(*f) != req.resume.as_ref()) {
            outputs.input(f, "scene file");
        }
        let interrupt_path = (interruptible && !files.writes_film()).then(|| interrupt_film_path(&files.output));
        if let Some(p) = &req.resume {
            let by = if interrupt_path.as_deref() == Some(p.as_path()) { INTERRUPT_FILM } else { files.names.output };
            outputs.input_replaceable_by(p, "film being resumed", by);
        }
        let (main, float, stats) = files.add_to(&mut outputs)?;
        let interrupt = match interrupt_path {
            Some(p) => Some((p.clone(), outputs.add(&p, INTERRUPT_FILM)?)),
            None => None,
        };
        let mut aov = Vec::new();
        if layered_exr(files).is_none() {
            for name in req.aov.names() {
                aov.push(outputs.add(&aov::beside(&files.output, name), "aov")?);
            }
        }
        let gamma = files.gamma.unwrap_or(req.job.default_gamma());
        Ok(Planned { outputs, main, float, stats, interrupt, aov, gamma })
    }

    /// Stages the main output if it is a film.
    fn stage_film(&mut self, req: &RenderRequest, part: &Part) -> Result<()> {
        match req.files.writes_film() {
            true => self.outputs.stage(self.main, &part.to_bytes()),
            false => Ok(()),
        }
    }

    /// Stages the images: the output (unless a film) and `--float`, the
    /// feature buffers as layers of the one that is an EXR
    /// ([`layered_exr`]) or as PFM files beside the output.
    fn stage_images(&mut self, req: &RenderRequest, r: &Rendered, features: Option<&Features>) -> Result<()> {
        let files = &req.files;
        let layered = layered_exr(files);
        let bytes = |path: &Path, gamma: f32, name: &str| -> Result<Vec<u8>> {
            match features {
                Some(f) if layered == Some(path) => Ok(f.exr_bytes(&r.image)),
                _ => r.image.file_bytes(path, gamma, name),
            }
        };
        if !files.writes_film() {
            let b = bytes(&files.output, self.gamma, files.names.output)?;
            self.outputs.stage(self.main, &b)?;
        }
        if let (Some(id), Some(f)) = (self.float, &files.float) {
            let b = bytes(f, 1.0, files.names.float)?;
            self.outputs.stage(id, &b)?;
        }
        if let Some(f) = features.filter(|_| layered.is_none()) {
            for ((_, bytes), id) in f.pfm_files(&files.output).iter().zip(&self.aov) {
                self.outputs.stage(*id, bytes)?;
            }
        }
        Ok(())
    }
}

/// The feature buffers of the render `req` (of the samples it reached:
/// `stats.spp`), timed into `stats.aov`.
fn features_of(req: &RenderRequest, stats: &mut Stats) -> Features {
    let t = Instant::now();
    let f = render_features(req.job, req.crop.as_ref(), stats.spp, req.aov);
    let files = match layered_exr(&req.files) {
        Some(p) => vec![p.to_path_buf()],
        None => req.aov.names().into_iter().map(|name| aov::beside(&req.files.output, name)).collect(),
    };
    stats.aov = Some(AovReport { buffers: req.aov.names(), seconds: t.elapsed().as_secs_f64(), files });
    f
}

/// How a render in rounds ended.
enum Ran {
    /// With an image to write, as every render.
    Done(Rendered),
    /// Stopped by a signal: its film written, nothing else.
    Stopped(Stats),
}

/// A whole render in rounds ([`crate::rounds`]): previews published as it
/// goes; a stop by a signal writes only the film of the samples done.
fn render_in_rounds(
    req: &RenderRequest,
    film: &FilmRequest,
    out: &mut Planned,
    graceful: bool,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<Ran> {
    let files = &req.files;
    let (mut r, part, mut report) = {
        let _graceful = graceful.then(Graceful::enter);
        let (w, h) = (req.job.settings().width, req.job.settings().height);
        let (outputs, main, gamma) = (&mut out.outputs, out.main, out.gamma);
        let mut preview = |tiles: &[TileFilm]| -> Result<()> {
            let mut image = Image::new(w, h);
            tiles.iter().for_each(|t| image.put_tile(t));
            outputs.publish(main, &image.file_bytes(&files.output, gamma, files.names.output)?)
        };
        let rr = &req.rounds;
        let preview = rr.preview_every.map(|every| (every, &mut preview as Preview));
        let mut schedule = Schedule::new(req.job.settings().spp, rr.time_limit, preview, graceful);
        let (rendered, part) = shard::render_part_in(film, Some(&mut schedule), files.stats.is_some(), progress)?;
        (rendered, part, schedule.report())
    };
    r.stats.rejected().check(req.on_rejected)?;
    if report.stopped == Some(Stopped::Signal) {
        // Only the film of the samples done, and only if this run added any.
        let first = film.resume().map_or(0, |(_, p)| p.header.samples[1]);
        if part.header.spp <= first {
            return Err(Error::Interrupted {
                signal: report.signal_number,
                message: format!(
                    "interrupted by {} before a round of samples was done: no output was written",
                    report.signal.unwrap_or("a signal")
                ),
            });
        }
        let (path, id) = out.interrupt.clone().unwrap_or_else(|| (files.output.clone(), out.main));
        let aov = out.aov.iter().map(|&o| Some(o));
        for other in [Some(out.main), out.float, out.stats].into_iter().chain(aov).flatten().filter(|&o| o != id) {
            out.outputs.forget(other);
        }
        let mut outputs = std::mem::take(&mut out.outputs);
        outputs.stage(id, &part.to_bytes())?;
        outputs.commit()?;
        report.film = Some(path);
        r.stats.rounds = Some(report);
        return Ok(Ran::Stopped(r.stats));
    }
    if let Some((_, id)) = out.interrupt {
        out.outputs.forget(id);
    }
    out.stage_film(req, &part)?;
    r.stats.rounds = Some(report);
    Ok(Ran::Done(r))
}

/// What [`Outputs`] calls the film a signal leaves.
const INTERRUPT_FILM: &str = "the film written on an interrupt";

/// The schema of every statistics file rtow writes (`render --stats-json`
/// and `merge --stats-json`), named by its `schema` field; docs/figures.md
/// lists the fields. A merge fills what its parts carry: the render's
/// settings, counters and image; its seconds are the merge's; what only a
/// render knows (kernel, lanes, rate, work counters, plan) is `null`.
#[derive(Clone, Debug, Serialize)]
pub struct StatsFile {
    /// [`STATS_SCHEMA`].
    pub schema: &'static str,
    /// `render` or `merge`.
    pub command: &'static str,
    pub rays: u64,
    /// Render: shadow rays (`nee-mis`), apart from `rays`; merge: `null`.
    pub shadow_rays: Option<u64>,
    /// Samples traced (accepted and rejected).
    pub samples: u64,
    /// Render: the render alone (scene preparation apart). Merge: the whole
    /// merge (reading, merging, writing; see `merge`).
    pub seconds: f64,
    pub prepare_seconds: Option<f64>,
    pub mrays_per_s: Option<f64>,
    pub kernel: Option<&'static str>,
    pub lanes: Option<u32>,
    pub threads: usize,
    /// The instruction set of the build that wrote the file.
    pub isa: &'static str,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub seed: u64,
    pub russian_roulette: Option<Roulette>,
    pub adaptive: Option<Adaptive>,
    pub sampler: Sampler,
    pub estimator: EstimatorChoice,
    /// Samples left out of the image (NaN, infinite or out of the film's range).
    pub rejected_samples: u64,
    /// Of those, the samples with a NaN or infinite channel.
    pub rejected_non_finite: u64,
    /// Of those, the finite samples outside the film's range (`film_range`).
    pub rejected_out_of_range: u64,
    /// The film's fixed-point scale exponent (0 for every preset; see `film::accum`).
    pub film_exponent: u32,
    /// A sample is accepted when every channel's magnitude is below this.
    pub film_range: f64,
    pub work: Option<WorkCounters>,
    pub image_hash: String,
    pub plan: Option<Plan>,
    /// Render: the piece rendered (`none`: the whole image). Merge: the
    /// parts' split (`shard` 1 of `of` parts).
    pub split: Split,
    /// A merge's parts and the split of its seconds; `null` for a render.
    pub merge: Option<MergeTimes>,
    /// What was checked by recomputation (a merge's parts, a resumed film);
    /// `null` when nothing was.
    pub verified: Option<shard::Verified>,
    /// A render in rounds ([`crate::rounds`]): rounds, the samples asked
    /// for (`spp` is those reached) and why it stopped early (`null`: it did
    /// not); `null` for a render in one go and for a merge.
    pub rounds: Option<RoundsReport>,
    /// The window rendered (`render --crop`: `width` and `height` are the
    /// whole image's, the hash the window's); `null`: the whole image.
    pub crop: Option<Crop>,
    /// The feature buffers written (`render --aov`); `null`: none.
    pub aov: Option<AovReport>,
    pub provenance: Provenance,
}

/// The value of [`StatsFile::schema`].
pub const STATS_SCHEMA: &str = "rtow-stats/1";

/// What a merge spent its time on.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct MergeTimes {
    pub parts: usize,
    pub read_seconds: f64,
    pub merge_seconds: f64,
    pub write_seconds: f64,
}

impl StatsFile {
    /// A render's statistics, of the piece `split`.
    pub fn of_render(st: &Stats, split: Split) -> StatsFile {
        StatsFile {
            schema: STATS_SCHEMA,
            command: "render",
            rays: st.rays,
            shadow_rays: Some(st.shadow_rays),
            samples: st.samples,
            seconds: st.seconds,
            prepare_seconds: Some(st.prepare_seconds),
            mrays_per_s: Some(st.mrays_per_s),
            kernel: Some(st.kernel),
            lanes: Some(st.lanes),
            threads: st.threads,
            isa: st.isa,
            width: st.width,
            height: st.height,
            spp: st.spp,
            max_depth: st.max_depth,
            seed: st.seed,
            russian_roulette: st.russian_roulette,
            adaptive: st.adaptive,
            sampler: st.sampler,
            estimator: st.estimator,
            rejected_samples: st.rejected_samples,
            rejected_non_finite: st.rejected().non_finite(),
            rejected_out_of_range: st.rejected_out_of_range,
            film_exponent: st.film_exponent,
            film_range: st.film_range,
            work: st.work,
            image_hash: st.image_hash.clone(),
            plan: Some(st.plan.clone()),
            split,
            merge: None,
            verified: None,
            rounds: st.rounds.clone(),
            crop: st.crop.clone(),
            aov: st.aov.clone(),
            provenance: Provenance::collect(),
        }
    }

    /// A merge's statistics.
    pub fn of_merge(st: &MergeStats) -> StatsFile {
        StatsFile {
            schema: STATS_SCHEMA,
            command: "merge",
            rays: st.rays,
            shadow_rays: None,
            samples: st.samples,
            seconds: st.seconds,
            prepare_seconds: None,
            mrays_per_s: None,
            kernel: None,
            lanes: None,
            threads: st.threads,
            isa: crate::kernel::isa(),
            width: st.settings.width,
            height: st.settings.height,
            spp: st.settings.spp,
            max_depth: st.settings.max_depth,
            seed: st.settings.seed,
            russian_roulette: st.estimator.roulette,
            adaptive: st.estimator.adaptive,
            sampler: st.settings.sampler,
            estimator: st.settings.estimator,
            rejected_samples: st.rejected_samples,
            rejected_non_finite: st.rejected().non_finite(),
            rejected_out_of_range: st.rejected_out_of_range,
            film_exponent: st.film_exponent,
            film_range: st.rejected().range,
            work: None,
            image_hash: st.image_hash.clone(),
            plan: None,
            split: Split { kind: st.split, shard: 1, of: st.parts as u32 },
            merge: Some(MergeTimes {
                parts: st.parts,
                read_seconds: st.read_seconds,
                merge_seconds: st.merge_seconds,
                write_seconds: st.write_seconds,
            }),
            verified: Some(st.verified),
            rounds: None,
            crop: None,
            aov: None,
            provenance: Provenance::collect(),
        }
    }
}

/// Pretty JSON with a final newline.
fn json<T: Serialize>(v: &T) -> String {
    serde_json::to_string_pretty(v).expect("statistics serialize") + "\n"
}

/// What a merge did, and the settings of the render its parts are of.
#[derive(Clone, Debug, Serialize)]
pub struct MergeStats {
    pub parts: usize,
    pub split: SplitKind,
    /// The render's settings, as its parts' headers carry them.
    #[serde(flatten)]
    pub settings: Settings,
    /// Its roulette and adaptive sampling.
    #[serde(flatten)]
    pub estimator: Estimator,
    /// Worker threads of the merge.
    pub threads: usize,
    pub rays: u64,
    pub samples: u64,
    pub rejected_samples: u64,
    /// Of those, the finite samples out of the film's range.
    pub rejected_out_of_range: u64,
    /// The parts' film scale exponent.
    pub film_exponent: u32,
    pub read_seconds: f64,
    pub merge_seconds: f64,
    pub write_seconds: f64,
    pub seconds: f64,
    pub image_hash: String,
    /// What the verification checked (its seconds are part of `read_seconds`).
    pub verified: shard::Verified,
}

impl MergeStats {
    /// The samples the parts rejected, by cause.
    pub fn rejected(&self) -> crate::limits::Rejected {
        crate::limits::Rejected {
            samples: self.samples,
            total: self.rejected_samples,
            out_of_range: self.rejected_out_of_range,
            range: crate::film::accum::Scale::new(self.film_exponent).map_or(f64::INFINITY, |s| s.limit()),
        }
    }
}

/// Merges the partial films `parts` (every shard of one render) and writes
/// `files`: the image (bit for bit the one-process render's) or the whole
/// render's film (to resume later), the linear image, the statistics.
/// Every part is checked by recomputation as `verify` says ([`shard::Verify`]).
/// Parts that rejected samples are merged (their render said so) unless
/// `on_rejected` is [`OnRejected::Error`]: then nothing is written (exit status 2).
pub fn merge_to_files(
    parts: &[PathBuf],
    files: &RenderFiles,
    verify: shard::Verify,
    on_rejected: OnRejected,
) -> Result<MergeStats> {
    let t0 = Instant::now();
    files.check_types()?;
    verify.check()?;
    // The outputs are one transaction; no output may be one of the parts.
    let mut outputs = Outputs::new();
    for p in parts {
        outputs.input(p, "partial film");
    }
    let (out_id, float_id, stats_id) = files.add_to(&mut outputs)?;
    // Read (and check) every header, then stream the parts into one film.
    let shard::Merged { part: merged, split: split_kind, verified } = shard::merge_files(parts, verify)?;
    let c = &merged.header.counters;
    crate::limits::Rejected {
        samples: c.samples,
        total: c.rejected_samples,
        out_of_range: c.rejected_out_of_range,
        range: Part::scale(&merged.header).limit(),
    }
    .check(on_rejected)?;
    let read_seconds = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let image = merged.film.image();
    let merge_seconds = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    if files.writes_film() {
        outputs.stage(out_id, &merged.to_bytes())?;
    } else {
        let gamma = files.gamma.unwrap_or_else(|| shard::default_gamma(&merged));
        outputs.stage(out_id, &image.file_bytes(&files.output, gamma, files.names.output)?)?;
    }
    if let (Some(id), Some(f)) = (float_id, &files.float) {
        outputs.stage(id, &image.file_bytes(f, 1.0, files.names.float)?)?;
    }
    let h = &merged.header;
    let s = shard::RenderSettings::of(h).map_err(|m| Error::Input(format!("{}: {m}", parts[0].display())))?;
    let mut stats = MergeStats {
        parts: parts.len(),
        split: split_kind,
        settings: s.settings,
        estimator: s.estimator,
        threads: rayon::current_num_threads(),
        rays: h.counters.rays,
        samples: h.counters.samples,
        rejected_samples: h.counters.rejected_samples,
        rejected_out_of_range: h.counters.rejected_out_of_range,
        film_exponent: h.film_exponent,
        read_seconds,
        merge_seconds,
        write_seconds: 0.0,
        seconds: 0.0,
        image_hash: format!("{:016x}", image.hash()),
        verified,
    };
    stats.write_seconds = t2.elapsed().as_secs_f64();
    stats.seconds = t0.elapsed().as_secs_f64();
    if let Some(id) = stats_id {
        outputs.stage(id, json(&StatsFile::of_merge(&stats)).as_bytes())?;
    }
    outputs.commit()?;
    Ok(stats)
}

/// The default name of a render's output: `<scene name>.png`.
pub fn default_output(source: &SceneSource) -> PathBuf {
    Path::new(&format!("{}.png", source.name)).to_path_buf()
}
