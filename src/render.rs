//! The render driver: a [`Job`] rendered on its kernel and lane width,
//! tiles over threads, with progress and statistics.

use crate::choice::{EstimatorChoice, Mode};
use crate::error::{Error, Result};
use crate::estimator::Adaptive;
use crate::film::accum::Scale;
use crate::film::aov::{Aovs, Features};
use crate::film::{Film, Image, TileFilm};
use crate::job::Job;
use crate::kernel::{first_hit, gradient, isa, scalar, wavefront, Kernel};
use crate::plan::{Plan, Prepared};
use crate::probe::{Observed, Probe, WorkCounters};
use crate::real::Wide;
use crate::rounds::Rounds;
use crate::sampling::{with_path_sampler, PathSampler, Sampler};
use rayon::prelude::*;
use serde::Serialize;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;
use wide::{f32x16, f32x8};

/// Progress reported after each finished tile.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    pub tiles_done: u64,
    pub tiles_total: u64,
    pub rays: u64,
}

/// What a render measured. `seconds` is the render alone; scene preparation is apart.
#[derive(Clone, Debug, Serialize)]
pub struct Stats {
    /// Rays traced for their closest hit (camera and scattered rays).
    pub rays: u64,
    /// Shadow rays (`nee-mis`'s light samples: any-hit queries), counted
    /// apart so that `mrays_per_s` stays comparable across estimators.
    pub shadow_rays: u64,
    /// Samples actually traced (fewer than width x height x spp with adaptive sampling).
    pub samples: u64,
    pub seconds: f64,
    pub prepare_seconds: f64,
    pub mrays_per_s: f64,
    /// Shadow rays per second, in millions (0 unless `nee-mis`).
    pub mshadow_rays_per_s: f64,
    pub kernel: &'static str,
    /// Lanes per packet: 1 (scalar), 8 or 16.
    pub lanes: u32,
    pub threads: usize,
    pub isa: &'static str,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub seed: u64,
    /// Russian roulette from this many rays on (`null`: off).
    pub russian_roulette: Option<crate::estimator::Roulette>,
    pub adaptive: Option<Adaptive>,
    /// `independent` or `sobol` (`sobol-pixel`, ... for partial layouts).
    pub sampler: Sampler,
    /// How paths chose directions at diffuse vertices (`bsdf`, `book`).
    pub estimator: EstimatorChoice,
    /// Samples kept out of the image: with a NaN or infinite component, or
    /// finite but outside the film's range (`rejected_out_of_range`).
    pub rejected_samples: u64,
    /// Of `rejected_samples`, the finite samples outside the film's range
    /// ([`Stats::film_range`]).
    pub rejected_out_of_range: u64,
    /// The film's fixed-point scale exponent (`plan.film_exponent`; 0 for every preset).
    pub film_exponent: u32,
    /// A sample is accepted when every channel's magnitude is below this.
    pub film_range: f64,
    /// Exact work counters and lane occupancy, when the render counted them.
    pub work: Option<WorkCounters>,
    pub image_hash: String,
    pub plan: Plan,
    /// A render in rounds ([`crate::rounds`]): what the rounds did (`spp`
    /// above is the samples they reached); `None` for a render in one go.
    pub rounds: Option<crate::rounds::RoundsReport>,
    /// The window rendered ([`render_crop`]; `width` and `height` are the
    /// whole image's); `None`: the whole image.
    pub crop: Option<Crop>,
    /// The feature buffers written (`--aov`); `None`: none asked for.
    pub aov: Option<AovReport>,
}

/// The feature buffers a render wrote ([`render_features`]).
#[derive(Clone, Debug, Serialize)]
pub struct AovReport {
    /// Their names (`albedo`, `normal`, `depth`).
    pub buffers: Vec<&'static str>,
    /// The time their first-hit pass took (apart from `seconds`).
    pub seconds: f64,
    /// Where they went: the EXR holding them as layers, or the PFM files beside the image.
    pub files: Vec<std::path::PathBuf>,
}

impl Stats {
    /// The samples rejected, by cause.
    pub fn rejected(&self) -> crate::limits::Rejected {
        crate::limits::Rejected {
            samples: self.samples,
            total: self.rejected_samples,
            out_of_range: self.rejected_out_of_range,
            range: self.film_range,
        }
    }

    /// An error (exit status 2) when more than
    /// [`MAX_REJECTED_FRACTION`](crate::limits::MAX_REJECTED_FRACTION) of the
    /// samples were rejected (NaN, infinite or out of the film's range): the
    /// image would be mostly black or wrong.
    pub fn check_finite(&self) -> Result<()> {
        self.rejected().check_fraction()
    }
}

pub struct Rendered {
    pub image: Image,
    pub stats: Stats,
}

/// The tiles of columns `cols` and rows `rows`, empty (of scale `scale`) or
/// starting from `start`'s accumulators.
fn tiles(
    cols: Range<u32>,
    rows: Range<u32>,
    edge: u32,
    moments: bool,
    scale: Scale,
    start: Option<&Film>,
) -> Vec<TileFilm> {
    let mut v = Vec::new();
    for y0 in rows.clone().step_by(edge as usize) {
        for x0 in cols.clone().step_by(edge as usize) {
            let (w, h) = (edge.min(cols.end - x0), edge.min(rows.end - y0));
            let t = match start {
                Some(f) => f.tile(x0, y0, w, h),
                None => TileFilm::new(x0, y0, w, h).scaled(scale),
            };
            v.push(if moments && t.sum_sq.is_empty() { t.with_moments() } else { t });
        }
    }
    v
}

/// The part of a render to do: a band of rows and a range of sample indices
/// (all of both by default), starting from an empty film or from `start`
/// (a resumed render). Every pixel's samples are the same whatever the
/// portion, so portions add up exactly ([`crate::film`]). The shard module
/// checks a portion against the job before it asks for it.
#[derive(Clone, Debug, Default)]
pub(crate) struct Portion<'a> {
    /// Rows `rows.start..rows.end` (`None`: every row).
    pub rows: Option<Range<u32>>,
    /// Sample indices (`None`: `0..spp`).
    pub samples: Option<Range<u32>>,
    /// Columns (`None`: every column); only without a film (`start`, or one kept).
    pub cols: Option<Range<u32>>,
    /// The accumulators to continue from (their rows include `rows`).
    pub start: Option<&'a Film>,
}

/// Renders `job`; `progress` is called after every tile.
pub fn render(job: &Job, progress: Option<&(dyn Fn(Progress) + Sync)>) -> Result<Rendered> {
    render_probed(job, progress, &|| ()).map(|(r, _)| r)
}

/// Renders a [`Portion`] of the image; also returns its accumulators (`None`
/// for a scene that traces no samples: the gradient). The image holds the
/// portion's rows (others are black); the statistics count this run's work.
pub(crate) fn render_portion(
    job: &Job,
    portion: Portion,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<(Rendered, Option<Film>)> {
    render_inner(job, portion, true, None, progress, &|| ()).map(|(r, _, f)| (r, f))
}

/// Renders a [`Portion`] of every row in the rounds `rounds` decides; returns
/// the image and accumulators of the samples the rounds reached, and the
/// end of those samples (the portion's end unless `rounds` stopped early).
/// With `counted`, the statistics carry the exact work counters.
pub(crate) fn render_rounds(
    job: &Job,
    portion: Portion,
    rounds: &mut (dyn Rounds + Send),
    counted: bool,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<(Rendered, Option<Film>)> {
    render_maybe_counted(job, portion, true, Some(rounds), counted, progress)
}

/// [`render_inner`] with the plain probe, or (`counted`) with the counting
/// one and its totals in `Stats::work`: the two probes every render has.
fn render_maybe_counted(
    job: &Job,
    portion: Portion,
    keep_film: bool,
    rounds: Option<&mut (dyn Rounds + Send)>,
    counted: bool,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<(Rendered, Option<Film>)> {
    if !counted {
        return render_inner(job, portion, keep_film, rounds, progress, &|| ()).map(|(r, _, f)| (r, f));
    }
    let (mut r, probes, f) = render_inner(job, portion, keep_film, rounds, progress, &Observed::counting)?;
    r.stats.work = Some(total_work(&probes));
    Ok((r, f))
}

fn total_work(probes: &[Observed]) -> WorkCounters {
    let mut w = WorkCounters::default();
    probes.iter().for_each(|p| w.merge(&p.work.total()));
    w
}

/// Renders the pixels `pixels` (x, y), each alone and from empty
/// accumulators, over the sample indices `samples`, with the scalar reference
/// kernel (every kernel renders the same bits): what a partial film of
/// those samples holds for them. The verified merge compares a part's data
/// with it. Runs on the current rayon pool; a scene that traces no samples
/// (the gradient) gives empty accumulators.
pub fn render_pixels(job: &Job, pixels: &[(u32, u32)], samples: Range<u32>) -> Vec<TileFilm> {
    let prep = job.prepared();
    let moments = prep.estimator.adaptive.is_some();
    let mut tiles: Vec<TileFilm> = pixels
        .iter()
        .map(|&(x, y)| {
            let t = TileFilm::new(x, y, 1, 1).scaled(prep.plan.film_scale());
            if moments {
                t.with_moments()
            } else {
                t
            }
        })
        .collect();
    if prep.plan.mode != Mode::Gradient {
        with_path_sampler!(prep.settings.sampler, sampler => {
            tiles.par_iter_mut().for_each(|t| {
                scalar::render_tile(prep, sampler, t, samples.clone(), &mut ());
            })
        });
    }
    tiles
}

/// The feature buffers `aovs` of `job`'s image (of the window `crop`),
/// each pixel the mean over its samples `0..spp` of its camera rays' first
/// hits ([`crate::kernel::first_hit`]): the same for every kernel.
pub fn render_features(job: &Job, crop: Option<&Crop>, spp: u32, aovs: Aovs) -> Features {
    let prep = job.prepared();
    let (w, h) = (prep.settings.width, prep.settings.height);
    let (cols, rows) = crop.map_or((0..w, 0..h), |c| (c.x.clone(), c.y.clone()));
    with_path_sampler!(prep.settings.sampler, sampler => {
        first_hit::features(prep, sampler, cols.clone(), rows.clone(), 0..spp, aovs)
    })
}

/// A window of the image, in pixels: columns `x` and rows `y` (pbrt's crop
/// window). Its pixels are bit for bit those of the whole render.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Crop {
    pub x: Range<u32>,
    pub y: Range<u32>,
}

impl Crop {
    /// `x0,x1,y0,y1`: columns `x0..x1` and rows `y0..y1` (ends excluded).
    pub fn parse(text: &str) -> Result<Crop> {
        let bad = || {
            Error::invalid(
                "crop",
                format!(
                    "'{}' is not x0,x1,y0,y1 (pixels; columns x0..x1 and rows y0..y1, ends excluded)",
                    crate::output::clip(text)
                ),
            )
        };
        let v: Vec<u32> = text
            .split(',')
            .map(|p| p.trim().parse::<u32>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| bad())?;
        match v[..] {
            [x0, x1, y0, y1] => Ok(Crop { x: x0..x1, y: y0..y1 }),
            _ => Err(bad()),
        }
    }

    /// Refuses a window that is empty or not inside a `width` x `height` image.
    pub fn check(&self, width: u32, height: u32) -> Result<()> {
        let (x, y) = (&self.x, &self.y);
        if x.is_empty() || y.is_empty() || x.end > width || y.end > height {
            return Err(Error::invalid(
                "crop",
                format!(
                    "columns {}..{} and rows {}..{} are not a window of the {width}x{height} image (each range \
                     non-empty, x1 <= {width}, y1 <= {height})",
                    x.start, x.end, y.start, y.end
                ),
            ));
        }
        Ok(())
    }
}

/// Renders the window `crop` of `job`'s image (checked: [`Crop::check`]):
/// an image of the window's size, its pixels bit for bit the whole render's.
/// With `counted`, the statistics carry the exact work counters; the
/// statistics' image hash is the window's.
pub fn render_crop(
    job: &Job,
    crop: &Crop,
    counted: bool,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<Rendered> {
    let s = job.settings();
    crop.check(s.width, s.height)?;
    let portion = Portion { rows: Some(crop.y.clone()), cols: Some(crop.x.clone()), ..Default::default() };
    let (mut r, _) = render_maybe_counted(job, portion, false, None, counted, progress)?;
    r.image = r.image.crop(crop.x.clone(), crop.y.clone());
    r.stats.image_hash = format!("{:016x}", r.image.hash());
    r.stats.crop = Some(crop.clone());
    Ok(r)
}

/// Renders with the exact work counters on (`Stats::work`).
pub fn render_counted(job: &Job, progress: Option<&(dyn Fn(Progress) + Sync)>) -> Result<Rendered> {
    let (mut r, probes) = render_probed(job, progress, &Observed::counting)?;
    r.stats.work = Some(total_work(&probes));
    Ok(r)
}

/// Renders with a probe per tile, made by `make`; returns the probes in tile order.
pub fn render_probed<P: Probe + Send>(
    job: &Job,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
    make: &(dyn Fn() -> P + Sync),
) -> Result<(Rendered, Vec<P>)> {
    render_inner(job, Portion::default(), false, None, progress, make).map(|(r, p, _)| (r, p))
}

/// The stack of a render's worker threads. An optimized build needs a few
/// hundred kilobytes; an unoptimized one (`cargo run` without `--release`)
/// gives each of the 16-lane kernel's temporaries a slot of its own and
/// overflowed rayon's default 2 MiB. Address space only: a thread's stack
/// takes memory as it is used.
pub const WORKER_STACK: usize = 16 << 20;

fn render_inner<P: Probe + Send>(
    job: &Job,
    portion: Portion,
    keep_film: bool,
    rounds: Option<&mut (dyn Rounds + Send)>,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
    make: &(dyn Fn() -> P + Sync),
) -> Result<(Rendered, Vec<P>, Option<Film>)> {
    let prep = job.prepared();
    let settings = *job.settings();
    let opts = job.options();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads.unwrap_or(0))
        .stack_size(WORKER_STACK)
        .build()
        .map_err(|e| Error::System(format!("cannot start {} worker threads: {e}", opts.threads.unwrap_or(0))))?;
    let threads = pool.current_num_threads();
    let t1 = Instant::now();
    let rows = portion.rows.clone().unwrap_or(0..settings.height);
    let cols = portion.cols.clone().unwrap_or(0..settings.width);
    debug_assert!(cols == (0..settings.width) || (!keep_film && portion.start.is_none()), "films hold whole rows");
    let samples = portion.samples.clone().unwrap_or(0..settings.spp);
    debug_assert!(rows.start <= rows.end && rows.end <= settings.height && samples.end <= settings.spp);
    debug_assert!(portion.start.is_none_or(|f| f.rows.start <= rows.start && f.rows.end >= rows.end));
    let work = Work { cols, rows, samples, start: portion.start, keep_film };
    let in_rounds = rounds.is_some();
    let out = pool.install(|| render_prepared(prep, job.kernel(), opts.tile, &work, rounds, progress, make))?;
    let seconds = t1.elapsed().as_secs_f64();
    let mut stats = Stats::new(job, &out, seconds, threads);
    if in_rounds {
        // Rounds that stopped early rendered the image of the samples they reached.
        stats.spp = out.reached;
    }
    Ok((Rendered { image: out.image, stats }, out.probes, out.film))
}

impl Stats {
    fn new<P>(job: &Job, out: &Finished<P>, seconds: f64, threads: usize) -> Stats {
        let s = job.settings();
        let kernel = job.kernel();
        Stats {
            rays: out.rays,
            shadow_rays: out.shadow_rays,
            samples: out.traced.unwrap_or(s.width as u64 * s.height as u64 * s.spp as u64),
            seconds,
            prepare_seconds: job.prepare_seconds(),
            mrays_per_s: out.rays as f64 / seconds / 1e6,
            mshadow_rays_per_s: out.shadow_rays as f64 / seconds / 1e6,
            kernel: kernel.name(),
            lanes: kernel.lanes(),
            threads,
            isa: isa(),
            width: s.width,
            height: s.height,
            spp: s.spp,
            max_depth: s.max_depth,
            seed: s.seed,
            russian_roulette: job.options().roulette,
            adaptive: job.options().adaptive,
            sampler: s.sampler,
            estimator: s.estimator,
            rejected_samples: out.rejected,
            rejected_out_of_range: out.rejected_out_of_range,
            film_exponent: job.plan().film_exponent,
            film_range: job.plan().film_scale().limit(),
            work: None,
            image_hash: format!("{:016x}", out.image.hash()),
            plan: job.plan().clone(),
            rounds: None,
            crop: None,
            aov: None,
        }
    }
}

/// What a render does: rows, sample indices, where the accumulators start,
/// and whether the caller wants them back.
struct Work<'a> {
    cols: Range<u32>,
    rows: Range<u32>,
    samples: Range<u32>,
    start: Option<&'a Film>,
    keep_film: bool,
}

/// A finished render's image, counts, probes and accumulators.
struct Finished<P> {
    image: Image,
    rays: u64,
    shadow_rays: u64,
    rejected: u64,
    rejected_out_of_range: u64,
    /// Samples traced (`None` when no sample is traced: the gradient).
    traced: Option<u64>,
    probes: Vec<P>,
    /// The accumulators of the rows rendered (`None` for the gradient).
    film: Option<Film>,
    /// The end of the sample indices rendered (the settings' spp for the gradient).
    reached: u32,
}

fn render_prepared<P: Probe + Send>(
    prep: &Prepared,
    kernel: Kernel,
    tile: u32,
    work: &Work,
    rounds: Option<&mut (dyn Rounds + Send)>,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
    make: &(dyn Fn() -> P + Sync),
) -> Result<Finished<P>> {
    let s = prep.settings;
    if prep.plan.mode == Mode::Gradient {
        return Ok(gradient_image(s.width, s.height, s.spp));
    }
    let moments = prep.estimator.adaptive.is_some();
    let scale = prep.plan.film_scale();
    debug_assert!(work.start.is_none_or(|f| f.scale == scale), "a film of another scale is refused before");
    let mut films = tiles(work.cols.clone(), work.rows.clone(), tile, moments, scale, work.start);
    let started: u64 = films.iter().flat_map(|t| &t.count).map(|&c| c as u64).sum();
    // Progress counts tiles, each once per sample of its round: a render in
    // rounds goes over every tile once a round.
    let samples = work.samples.clone();
    let per_tile = samples.len().max(1) as u64;
    let total = films.len() as u64 * per_tile;
    let done = AtomicU64::new(0);
    let rays = AtomicU64::new(0);
    let round = AtomicU64::new(per_tile);
    let report = |n: u64| {
        let k = round.load(Ordering::Relaxed);
        let d = done.fetch_add(k, Ordering::Relaxed) + k;
        let r = rays.fetch_add(n, Ordering::Relaxed) + n;
        if let Some(p) = progress {
            p(Progress { tiles_done: d, tiles_total: total, rays: r });
        }
    };
    // The one place the kernel and the sampler become types.
    let trace = |films: &mut [TileFilm], samples: Range<u32>| -> Vec<P> {
        with_path_sampler!(s.sampler, sampler => match kernel {
            Kernel::Scalar => scalar_tiles(prep, sampler, films, samples, &report, make),
            Kernel::Simd8 => wide_tiles::<f32x8, P, _>(prep, sampler, films, samples, &report, make),
            Kernel::Simd16 => wide_tiles::<f32x16, P, _>(prep, sampler, films, samples, &report, make),
        })
    };
    let (probes, reached) = match rounds {
        None => (trace(&mut films, samples.clone()), samples.end),
        Some(rounds) => in_rounds(&mut films, samples, rounds, &round, trace)?,
    };
    // The film is gathered only for a caller that wants it (a partial film):
    // a plain render writes the image straight from the tiles.
    let film = work.keep_film.then(|| Film::new(s.width, s.height, work.rows.clone(), moments).scaled(scale));
    let (image, film, c) = gather(films, Image::new(s.width, s.height), film);
    Ok(Finished {
        image,
        rays: rays.into_inner(),
        shadow_rays: c.shadow_rays,
        rejected: c.rejected,
        rejected_out_of_range: c.rejected_out_of_range,
        traced: Some(c.samples - started),
        probes,
        film,
        reached,
    })
}

/// What the tiles of a render hold, added up.
#[derive(Default)]
struct TileCounts {
    rejected: u64,
    rejected_out_of_range: u64,
    shadow_rays: u64,
    /// Every sample the tiles hold, accepted or rejected (resumed ones included).
    samples: u64,
}

/// The gradient (a scene that traces no samples), as a finished render.
fn gradient_image<P>(width: u32, height: u32, spp: u32) -> Finished<P> {
    let mut image = Image::new(width, height);
    for y in 0..height {
        for x in 0..width {
            image.data[(y * width + x) as usize] = gradient(x, y, width, height);
        }
    }
    Finished {
        image,
        rays: 0,
        shadow_rays: 0,
        rejected: 0,
        rejected_out_of_range: 0,
        traced: None,
        probes: Vec::new(),
        film: None,
        reached: spp,
    }
}

/// Traces `samples` in the rounds `rounds` decides (`round` holds the
/// samples of the round under way, for progress); returns the probes of
/// every round and the end of the samples reached.
fn in_rounds<P>(
    films: &mut [TileFilm],
    samples: Range<u32>,
    rounds: &mut (dyn Rounds + Send),
    round: &AtomicU64,
    trace: impl Fn(&mut [TileFilm], Range<u32>) -> Vec<P>,
) -> Result<(Vec<P>, u32)> {
    let mut probes = Vec::new();
    let mut reached = samples.start;
    while let Some(end) = rounds.next(reached, samples.end) {
        debug_assert!(reached < end && end <= samples.end);
        round.store((end - reached) as u64, Ordering::Relaxed);
        let t = Instant::now();
        probes.extend(trace(films, reached..end));
        reached = end;
        rounds.ended(films, reached, t.elapsed().as_secs_f64())?;
    }
    Ok((probes, reached))
}

/// The tiles into the image (through `film`, when the caller keeps one),
/// and their counts added up.
fn gather(films: Vec<TileFilm>, mut image: Image, mut film: Option<Film>) -> (Image, Option<Film>, TileCounts) {
    let mut c = TileCounts::default();
    // Tiles are dropped as they are copied: the peak stays near one film.
    for t in films {
        match &mut film {
            Some(f) => f.put_tile(&t),
            None => image.put_tile(&t),
        }
        c.rejected += t.rejected;
        c.rejected_out_of_range += t.rejected_out_of_range;
        c.shadow_rays += t.shadow_rays;
        c.samples += t.rejected + t.count.iter().map(|&n| n as u64).sum::<u64>();
    }
    if let Some(f) = &film {
        f.write_into(&mut image);
    }
    (image, film, c)
}

fn scalar_tiles<P: Probe + Send, S: PathSampler>(
    prep: &Prepared,
    sampler: S,
    films: &mut [TileFilm],
    samples: Range<u32>,
    report: &(dyn Fn(u64) + Sync),
    make: &(dyn Fn() -> P + Sync),
) -> Vec<P> {
    each_tile(
        films,
        report,
        make,
        || (),
        |_, tile, probe| scalar::render_tile(prep, sampler, tile, samples.clone(), probe),
    )
}

fn wide_tiles<W: Wide, P: Probe + Send, S: PathSampler>(
    prep: &Prepared,
    sampler: S,
    films: &mut [TileFilm],
    samples: Range<u32>,
    report: &(dyn Fn(u64) + Sync),
    make: &(dyn Fn() -> P + Sync),
) -> Vec<P> {
    each_tile(films, report, make, wavefront::Workspace::default, |ws, tile, probe| {
        wavefront::render_tile::<W, P, S>(prep, sampler, ws, tile, samples.clone(), probe)
    })
}

/// Renders every tile in parallel with `render` (a thread's state made once
/// by `init`), a probe per tile made by `make`; reports each tile's rays.
fn each_tile<P: Probe + Send, T>(
    films: &mut [TileFilm],
    report: &(dyn Fn(u64) + Sync),
    make: &(dyn Fn() -> P + Sync),
    init: impl Fn() -> T + Sync + Send,
    render: impl Fn(&mut T, &mut TileFilm, &mut P) -> u64 + Sync + Send,
) -> Vec<P> {
    films
        .par_iter_mut()
        .map_init(init, |state, tile| {
            let mut probe = make();
            report(tile_work(&render, state, tile, &mut probe));
            probe
        })
        .collect()
}

/// One tile through its kernel: the render loop. Kept out of line (one call
/// per tile costs nothing measurable) so that `rtow bench --instructions`
/// counts the render loop's instructions apart from the rest of the process
/// (`instruments::callgrind::RENDER_LOOP` names it).
#[inline(never)]
fn tile_work<T, P>(
    render: &impl Fn(&mut T, &mut TileFilm, &mut P) -> u64,
    state: &mut T,
    tile: &mut TileFilm,
    probe: &mut P,
) -> u64 {
    render(state, tile, probe)
}
