//! The render driver: the kernel and lane width, tiles over threads, progress
//! and statistics.

use crate::error::{Error, Result};
use crate::estimator::{Adaptive, Estimator};
use crate::film::{Film, Image, TileFilm};
use crate::kernel::{gradient, scalar, wavefront};
use crate::plan::{Mode, Plan, Prepared};
use crate::prepare::prepare;
use crate::probe::{Probe, WorkCounters};
use crate::real::Wide;
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::settings::{KernelChoice, RenderOptions, Settings};
use rayon::prelude::*;
use serde::Serialize;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;
use wide::{f32x16, f32x8};

/// The kernel that runs, after `simd` was resolved to a lane width.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kernel {
    Scalar,
    Simd8,
    Simd16,
}

impl Kernel {
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Scalar => "scalar",
            Kernel::Simd8 => "simd8",
            Kernel::Simd16 => "simd16",
        }
    }

    pub fn lanes(self) -> u32 {
        match self {
            Kernel::Scalar => 1,
            Kernel::Simd8 => 8,
            Kernel::Simd16 => 16,
        }
    }

    /// The kernel a choice runs on this build: `simd` is 16 lanes where
    /// `f32x16` is one register (AVX-512), 8 otherwise; `simd8` and `simd16`
    /// run on every build (without AVX-512, 16 lanes are two 8-lane halves:
    /// the same image, measured slower). An `Err` is kept for builds that lack one.
    pub fn resolve(choice: KernelChoice) -> Result<Kernel> {
        match choice {
            KernelChoice::Scalar => Ok(Kernel::Scalar),
            KernelChoice::Simd8 => Ok(Kernel::Simd8),
            KernelChoice::Simd if HAS_SIMD16 => Ok(Kernel::Simd16),
            KernelChoice::Simd => Ok(Kernel::Simd8),
            KernelChoice::Simd16 => Ok(Kernel::Simd16),
        }
    }
}

/// Whether `f32x16` is one register in this build (AVX-512F): then `simd` runs 16 lanes.
pub const HAS_SIMD16: bool = cfg!(target_feature = "avx512f");

/// The SIMD instruction set this binary was compiled for (`wide` picks its
/// implementation at compile time).
pub const fn isa() -> &'static str {
    if cfg!(all(target_feature = "avx512f", target_feature = "avx512vl", target_feature = "avx512bw")) {
        "AVX-512 (x86-64-v4)"
    } else if cfg!(all(target_feature = "avx2", target_feature = "fma")) {
        "AVX2+FMA (x86-64-v3)"
    } else if cfg!(target_feature = "avx") {
        "AVX"
    } else if cfg!(target_feature = "sse4.1") {
        "SSE4.1"
    } else if cfg!(target_feature = "sse2") {
        "SSE2"
    } else {
        "scalar fallback"
    }
}

/// The instruction set and the kernel `simd` runs, for `--version`.
pub fn build_description() -> String {
    let simd = if HAS_SIMD16 { "simd16 (f32x16)" } else { "simd8 (f32x8)" };
    format!("SIMD: {}, kernel simd = {simd}", isa())
}

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
    pub rays: u64,
    /// Samples actually traced (fewer than width x height x spp with adaptive sampling).
    pub samples: u64,
    pub seconds: f64,
    pub prepare_seconds: f64,
    pub mrays_per_s: f64,
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
    pub russian_roulette: Option<u32>,
    pub adaptive: Option<Adaptive>,
    /// `independent` or `sobol` (`sobol-pixel`, ... for partial layouts).
    pub sampler: Sampler,
    /// Samples with a NaN or infinite component, kept out of the image.
    pub rejected_samples: u64,
    /// Exact work counters and lane occupancy, when the render counted them.
    pub work: Option<WorkCounters>,
    pub image_hash: String,
    pub plan: Plan,
}

impl Stats {
    /// An error (exit status 2) when more than
    /// [`MAX_REJECTED_FRACTION`](crate::limits::MAX_REJECTED_FRACTION) of the
    /// samples were NaN or infinite: the image would be mostly black or wrong.
    pub fn check_finite(&self) -> Result<()> {
        crate::limits::check_rejected(self.rejected_samples, self.samples)
    }
}

pub struct Rendered {
    pub image: Image,
    pub stats: Stats,
}

/// The tiles of rows `rows`, empty or starting from `start`'s accumulators.
fn tiles(width: u32, rows: Range<u32>, edge: u32, moments: bool, start: Option<&Film>) -> Vec<TileFilm> {
    let mut v = Vec::new();
    for y0 in rows.clone().step_by(edge as usize) {
        for x0 in (0..width).step_by(edge as usize) {
            let (w, h) = (edge.min(width - x0), edge.min(rows.end - y0));
            let t = match start {
                Some(f) => f.tile(x0, y0, w, h),
                None => TileFilm::new(x0, y0, w, h),
            };
            v.push(if moments && t.sum_sq.is_empty() { t.with_moments() } else { t });
        }
    }
    v
}

/// The part of a render to do: a band of rows and a range of sample indices
/// (all of both by default), starting from an empty film or from `start`
/// (a resumed render). Every pixel's samples are the same whatever the
/// portion, so portions add up exactly ([`crate::film`]).
#[derive(Clone, Debug, Default)]
pub struct Portion<'a> {
    /// Rows `rows.start..rows.end` (`None`: every row).
    pub rows: Option<Range<u32>>,
    /// Sample indices (`None`: `0..spp`).
    pub samples: Option<Range<u32>>,
    /// The accumulators to continue from (their rows must include `rows`).
    pub start: Option<&'a Film>,
}

/// Renders `scene` with `settings`; `progress` is called after every tile.
pub fn render(
    scene: &Scene,
    settings: Settings,
    opts: RenderOptions,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<Rendered> {
    render_probed(scene, settings, opts, progress, &|| ()).map(|(r, _)| r)
}

/// Renders a [`Portion`] of the image; also returns its accumulators (`None`
/// for a scene that traces no samples: the gradient). The image holds the
/// portion's rows (others are black); the statistics count this run's work.
pub fn render_portion(
    scene: &Scene,
    settings: Settings,
    opts: RenderOptions,
    portion: Portion,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<(Rendered, Option<Film>)> {
    render_inner(scene, settings, opts, portion, true, progress, &|| ()).map(|(r, _, f)| (r, f))
}

/// Renders with the exact work counters on (`Stats::work`).
pub fn render_counted(
    scene: &Scene,
    settings: Settings,
    opts: RenderOptions,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<Rendered> {
    let (mut r, probes) = render_probed(scene, settings, opts, progress, &WorkCounters::default)?;
    let mut w = WorkCounters::default();
    probes.iter().for_each(|p| w.merge(p));
    r.stats.work = Some(w);
    Ok(r)
}

/// Renders with a probe per tile, made by `make`; returns the probes in tile order.
pub fn render_probed<P: Probe + Send>(
    scene: &Scene,
    settings: Settings,
    opts: RenderOptions,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
    make: &(dyn Fn() -> P + Sync),
) -> Result<(Rendered, Vec<P>)> {
    render_inner(scene, settings, opts, Portion::default(), false, progress, make).map(|(r, p, _)| (r, p))
}

fn render_inner<P: Probe + Send>(
    scene: &Scene,
    settings: Settings,
    opts: RenderOptions,
    portion: Portion,
    keep_film: bool,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
    make: &(dyn Fn() -> P + Sync),
) -> Result<(Rendered, Vec<P>, Option<Film>)> {
    let t0 = Instant::now();
    opts.validate()?;
    let kernel = Kernel::resolve(opts.kernel)?;
    let russian_roulette = opts.rr.then_some(opts.rr_after);
    let estimator = Estimator { russian_roulette, adaptive: opts.adaptive, sampler: opts.sampler };
    let prep = prepare(scene, settings, opts.accel, estimator)?;
    let prepare_seconds = t0.elapsed().as_secs_f64();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads.unwrap_or(0))
        .build()
        .map_err(|e| Error::Input(format!("cannot start threads: {e}")))?;
    let threads = pool.current_num_threads();
    let t1 = Instant::now();
    let rows = portion.rows.clone().unwrap_or(0..settings.height);
    let samples = portion.samples.clone().unwrap_or(0..settings.spp);
    if rows.start > rows.end || rows.end > settings.height || samples.start > samples.end || samples.end > settings.spp
    {
        return Err(Error::Input(format!(
            "rows {rows:?} and samples {samples:?} are not inside a {}-row, {}-spp render",
            settings.height, settings.spp
        )));
    }
    if let Some(f) = portion.start {
        if f.width != settings.width
            || f.height != settings.height
            || f.rows.start > rows.start
            || f.rows.end < rows.end
        {
            return Err(Error::Input("the film to continue from does not cover the rows to render".into()));
        }
    }
    let job = Job { rows, samples, start: portion.start, keep_film };
    let out = pool.install(|| render_prepared(&prep, kernel, opts.tile, &job, progress, make));
    let seconds = t1.elapsed().as_secs_f64();
    let (w, h) = (settings.width, settings.height);
    let stats = Stats {
        rays: out.rays,
        samples: out.traced.unwrap_or(w as u64 * h as u64 * settings.spp as u64),
        seconds,
        prepare_seconds,
        mrays_per_s: out.rays as f64 / seconds / 1e6,
        kernel: kernel.name(),
        lanes: kernel.lanes(),
        threads,
        isa: isa(),
        width: w,
        height: h,
        spp: settings.spp,
        max_depth: settings.max_depth,
        seed: settings.seed,
        russian_roulette,
        adaptive: opts.adaptive,
        sampler: opts.sampler,
        rejected_samples: out.rejected,
        work: None,
        image_hash: format!("{:016x}", out.image.hash()),
        plan: prep.plan.clone(),
    };
    Ok((Rendered { image: out.image, stats }, out.probes, out.film))
}

struct Job<'a> {
    rows: Range<u32>,
    samples: Range<u32>,
    start: Option<&'a Film>,
    keep_film: bool,
}

struct Output<P> {
    image: Image,
    rays: u64,
    rejected: u64,
    /// Samples traced (`None` when no sample is traced: the gradient).
    traced: Option<u64>,
    probes: Vec<P>,
    /// The accumulators of the rows rendered (`None` for the gradient).
    film: Option<Film>,
}

fn render_prepared<P: Probe + Send>(
    prep: &Prepared,
    kernel: Kernel,
    tile: u32,
    job: &Job,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
    make: &(dyn Fn() -> P + Sync),
) -> Output<P> {
    let s = prep.settings;
    let mut image = Image::new(s.width, s.height);
    if prep.plan.mode == Mode::Gradient {
        for y in 0..s.height {
            for x in 0..s.width {
                image.data[(y * s.width + x) as usize] = gradient(x, y, s.width, s.height);
            }
        }
        return Output { image, rays: 0, rejected: 0, traced: None, probes: Vec::new(), film: None };
    }
    let moments = prep.estimator.adaptive.is_some();
    let mut films = tiles(s.width, job.rows.clone(), tile, moments, job.start);
    let started: u64 = films.iter().flat_map(|t| &t.count).map(|&c| c as u64).sum();
    let total = films.len() as u64;
    let done = AtomicU64::new(0);
    let rays = AtomicU64::new(0);
    let report = |n: u64| {
        let d = done.fetch_add(1, Ordering::Relaxed) + 1;
        let r = rays.fetch_add(n, Ordering::Relaxed) + n;
        if let Some(p) = progress {
            p(Progress { tiles_done: d, tiles_total: total, rays: r });
        }
    };
    let samples = job.samples.clone();
    let probes: Vec<P> = match kernel {
        Kernel::Scalar => films
            .par_iter_mut()
            .map(|tile| {
                let mut probe = make();
                report(scalar::render_tile(prep, tile, samples.clone(), &mut probe));
                probe
            })
            .collect(),
        Kernel::Simd8 => wide_tiles::<f32x8, P>(prep, &mut films, samples, &report, make),
        Kernel::Simd16 => wide_tiles::<f32x16, P>(prep, &mut films, samples, &report, make),
    };
    // The film is gathered only for a caller that wants it (a partial film):
    // a plain render writes the image straight from the tiles.
    let mut film = job.keep_film.then(|| Film::new(s.width, s.height, job.rows.clone(), moments));
    let mut rejected = 0;
    let mut traced = 0;
    // Tiles are dropped as they are copied: the peak stays near one film.
    for t in films {
        match &mut film {
            Some(f) => f.put_tile(&t),
            None => image.put_tile(&t),
        }
        rejected += t.rejected;
        traced += t.rejected + t.count.iter().map(|&c| c as u64).sum::<u64>();
    }
    if let Some(f) = &film {
        f.write_into(&mut image);
    }
    let traced = Some(traced - started);
    Output { image, rays: rays.into_inner(), rejected, traced, probes, film }
}

fn wide_tiles<W: Wide, P: Probe + Send>(
    prep: &Prepared,
    films: &mut [TileFilm],
    samples: std::ops::Range<u32>,
    report: &(dyn Fn(u64) + Sync),
    make: &(dyn Fn() -> P + Sync),
) -> Vec<P> {
    films
        .par_iter_mut()
        .map_init(wavefront::Workspace::default, |ws, tile| {
            let mut probe = make();
            report(wavefront::render_tile::<W, P>(prep, ws, tile, samples.clone(), &mut probe));
            probe
        })
        .collect()
}
