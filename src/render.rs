//! The render driver: tiles, threads, progress and statistics.

use crate::error::Result;
use crate::estimator::{Adaptive, Estimator};
use crate::film::{Image, TileFilm};
use crate::kernel::{gradient, scalar, wavefront, Counters, KernelKind};
use crate::plan::{AccelChoice, Plan, Prepared, Settings};
use crate::scene::{Mode, Scene};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// How to render, beyond the image settings.
#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    pub kernel: KernelKind,
    /// Worker threads; `None` = one per core.
    pub threads: Option<usize>,
    /// Tile edge in pixels (tiles are the unit of parallel work).
    pub tile: u32,
    /// Closest-hit search: brute force, BVH, or chosen by the plan.
    pub accel: AccelChoice,
    /// Russian roulette on the path throughput (unbiased; changes the noise).
    pub rr: bool,
    /// Roulette starts once a path has traced this many rays.
    pub rr_after: u32,
    /// Adaptive sampling: pixels stop once their relative error is low enough.
    pub adaptive: Option<Adaptive>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            kernel: KernelKind::Simd,
            threads: None,
            tile: 16,
            accel: AccelChoice::Auto,
            rr: false,
            rr_after: crate::estimator::ROULETTE_AFTER_RAYS,
            adaptive: None,
        }
    }
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
    /// Samples with a NaN or infinite component, kept out of the image.
    pub rejected_samples: u64,
    /// Active lanes / issued lanes in intersection and scatter (SIMD kernel; none for scalar).
    pub isect_occupancy: Option<f64>,
    pub scatter_occupancy: Option<f64>,
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

/// The SIMD instruction set this binary was compiled for (`wide` picks its
/// implementation at compile time).
pub const fn isa() -> &'static str {
    if cfg!(all(target_feature = "avx2", target_feature = "fma")) {
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

fn tiles(width: u32, height: u32, edge: u32, moments: bool) -> Vec<TileFilm> {
    let mut v = Vec::new();
    for y0 in (0..height).step_by(edge as usize) {
        for x0 in (0..width).step_by(edge as usize) {
            let t = TileFilm::new(x0, y0, edge.min(width - x0), edge.min(height - y0));
            v.push(if moments { t.with_moments() } else { t });
        }
    }
    v
}

/// Renders `scene` with `settings`; `progress` is called after every tile.
pub fn render(
    scene: &Scene,
    settings: Settings,
    opts: RenderOptions,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> Result<Rendered> {
    crate::limits::check_threads(opts.threads)?;
    let t0 = Instant::now();
    let mut prep = Prepared::new(scene, settings, opts.accel)?;
    if !(1..=45).contains(&opts.tile) {
        return Err(crate::error::Error::invalid("tile", "must be between 1 and 45 pixels"));
    }
    if let Some(a) = opts.adaptive {
        Adaptive::new(a.threshold, a.min_spp)?;
    }
    if opts.rr {
        crate::estimator::check_roulette_after(opts.rr_after)?;
    }
    let russian_roulette = opts.rr.then_some(opts.rr_after);
    prep.estimator = Estimator { russian_roulette, adaptive: opts.adaptive };
    let prepare_seconds = t0.elapsed().as_secs_f64();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads.unwrap_or(0))
        .build()
        .map_err(|e| crate::error::Error::Input(format!("cannot start threads: {e}")))?;
    let threads = pool.current_num_threads();
    let t1 = Instant::now();
    let (image, counters, rejected, traced) = pool.install(|| render_prepared(&prep, opts, progress));
    let seconds = t1.elapsed().as_secs_f64();
    let (w, h) = (settings.width, settings.height);
    let occ = |a: u64, l: u64| (l > 0).then(|| a as f64 / l as f64);
    let stats = Stats {
        rays: counters.rays,
        samples: traced.unwrap_or(w as u64 * h as u64 * settings.spp as u64),
        seconds,
        prepare_seconds,
        mrays_per_s: counters.rays as f64 / seconds / 1e6,
        kernel: opts.kernel.name(),
        threads,
        isa: isa(),
        width: w,
        height: h,
        spp: settings.spp,
        max_depth: settings.max_depth,
        seed: settings.seed,
        russian_roulette,
        adaptive: opts.adaptive,
        rejected_samples: rejected,
        isect_occupancy: occ(counters.isect_active, counters.isect_lanes),
        scatter_occupancy: occ(counters.scatter_active, counters.scatter_lanes),
        image_hash: format!("{:016x}", image.hash()),
        plan: prep.plan.clone(),
    };
    Ok(Rendered { image, stats })
}

/// The image, the counters, the rejected samples and the samples traced (`None`
/// when no sample is traced: the gradient).
fn render_prepared(
    prep: &Prepared,
    opts: RenderOptions,
    progress: Option<&(dyn Fn(Progress) + Sync)>,
) -> (Image, Counters, u64, Option<u64>) {
    let s = prep.settings;
    let mut image = Image::new(s.width, s.height);
    if prep.plan.mode == Mode::Gradient {
        for y in 0..s.height {
            for x in 0..s.width {
                image.data[(y * s.width + x) as usize] = gradient(x, y, s.width, s.height);
            }
        }
        return (image, Counters::default(), 0, None);
    }
    let mut films = tiles(s.width, s.height, opts.tile, prep.estimator.adaptive.is_some());
    let total = films.len() as u64;
    let done = AtomicU64::new(0);
    let rays = AtomicU64::new(0);
    let report = |c: &Counters| {
        let d = done.fetch_add(1, Ordering::Relaxed) + 1;
        let r = rays.fetch_add(c.rays, Ordering::Relaxed) + c.rays;
        if let Some(p) = progress {
            p(Progress { tiles_done: d, tiles_total: total, rays: r });
        }
    };
    let counters: Counters = match opts.kernel {
        KernelKind::Scalar => films
            .par_iter_mut()
            .map(|tile| {
                let mut c = Counters::default();
                scalar::render_tile(prep, tile, &mut c);
                report(&c);
                c
            })
            .reduce(Counters::default, |mut a, b| {
                a.merge(&b);
                a
            }),
        KernelKind::Simd => films
            .par_iter_mut()
            .map_init(wavefront::Workspace::default, |ws, tile| {
                let mut c = Counters::default();
                wavefront::render_tile(prep, ws, tile, &mut c);
                report(&c);
                c
            })
            .reduce(Counters::default, |mut a, b| {
                a.merge(&b);
                a
            }),
    };
    let mut rejected = 0;
    let mut traced = 0;
    for t in &films {
        image.put_tile(t);
        rejected += t.rejected;
        traced += t.rejected + t.count.iter().map(|&c| c as u64).sum::<u64>();
    }
    (image, counters, rejected, Some(traced))
}
