//! The SIMD wavefront path tracer, generic over the lane width `W` (`f32x8`,
//! or `f32x16` on AVX-512 builds).
//!
//! A tile's paths for a batch of samples are generated together, then advanced
//! one bounce at a time, all in structure-of-arrays:
//!
//! ```text
//! generate camera rays (W at a time)
//! loop until no path is alive or max_depth rays were traced:
//!     intersect: W contiguous rays per packet (brute force or the BVH, as planned)
//!     misses:    W contiguous paths at a time, throughput x background (sky or constant) -> results
//!                (no pass under a black background: a miss adds nothing)
//!     classify:  each path that hit joins the queue of its hit's material kind,
//!                but a packet of contiguous paths whose hits share a kind
//!                (three quarters of its lanes at least; scenes without
//!                moving spheres or media, bsdf estimator) is scattered where
//!                it is, without a queue
//!     light pass (scenes with lights): throughput x emission -> the result; the path ends
//!     texture passes (scenes with textures): one per texture kind, over the
//!         lambertian hits of that kind, writing each path's albedo
//!     one scatter pass per material kind the scene uses (W paths at a time, gathered);
//!         under nee-mis the diffuse passes also append a shadow ray per path
//!         toward a light sample to the shadow queue
//!     compaction: survivors are appended to the next bounce's arrays
//!     shadow pass (nee-mis): W contiguous shadow rays per packet, any-hit
//!         (each lane leaves at its first blocker), the unblocked ones'
//!         radiance added to their paths' results
//! add results to the film in sample order
//! ```
//!
//! Lane k of every packet computes exactly what the scalar kernel computes for
//! that path: the formulas are the width-generic ones, the random values are
//! the same (the sampler's stream run lane-wise: xoshiro128+ for the
//! independent sampler, the Sobol generator for `sobol`, with the dimension of
//! each draw set by the bounce, which every path of a pass shares), and the
//! closest-hit tie rule is the same.
//! Memory is bounded: a workspace holds at most `MAX_PATHS` paths.

use super::{background, normal_colour, texture_albedo};
use crate::choice::Mode;
use crate::estimator::{
    book_mixture, cosine_pdf, mis_bsdf, next_event, roulette, roulette_applies, shadow_tmax, ISOTROPIC_PDF,
};
use crate::film::TileFilm;
use crate::geometry::{
    centre_at, quad_surface, sample_media, spawn, surface, transmittance, Shade, Surface, MEDIUM_BASE, MISS,
    MOVING_BASE, QUAD_BASE,
};
use crate::material::{dielectric, emission, lambertian, metal, Kind};
use crate::plan::{KindSet, Prepared};
use crate::probe::{PathId, Probe, Stage};
use crate::real::{U32Lanes, Wide, MAX_LANES};
use crate::sampling::layout::{self, Bounces};
use crate::sampling::{unit_vector, PathSampler, Stream};
use crate::texture::TexKind;
use crate::vec3::V3;
use std::ops::Range;

/// Paths in flight per workspace (per thread), at most.
pub const MAX_PATHS: usize = 2048;

/// The length of every per-path array: a power of two with room past
/// `MAX_PATHS` for a packet of any width, so that
/// - the last packet can be loaded and stored whole (its extra lanes are
///   computed, never used), and compaction may write a packet past the kept
///   lanes;
/// - an index masked with `CAP - 1` is in bounds by construction: the gathers
///   by queued index, the loads and stores at a packet's start and the queue
///   and result writes need no bounds check ([`Wide::gather_pow2`]). Every
///   index is below `MAX_PATHS` where it is used, so the mask never changes one
///   (debug builds assert it where the index comes from memory).
const CAP: usize = 4096;
const MASK: usize = CAP - 1;
const _: () = assert!(CAP.is_power_of_two() && CAP >= MAX_PATHS + MAX_LANES);

/// A per-path array.
type Arr<T> = Box<[T; CAP]>;

fn arr<T: Copy + std::fmt::Debug>(x: T) -> Arr<T> {
    vec![x; CAP].into_boxed_slice().try_into().unwrap()
}

/// The miss queue's index (after one queue per material kind). Misses are
/// shaded by their own pass over contiguous paths (`shade_misses`): the
/// one-path-at-a-time classification of scenes with quads fills this queue
/// (branch-free) and nothing reads it.
const MISS_QUEUE: usize = Kind::ALL.len();

/// The texture queues' count: one per texture kind with a pass (`TexKind as usize - 1`).
const TEX_QUEUES: usize = TexKind::PASSES.len();

/// Path state, structure of arrays.
struct Paths {
    o: [Arr<f32>; 3],
    d: [Arr<f32>; 3],
    thr: [Arr<f32>; 3],
    rng: [Arr<u32>; 4],
    /// Index of the path's result: `sample_in_batch * active_pixels + active_index`.
    slot: Arr<u32>,
    /// The path's time (motion blur): written and read only for a scene
    /// with moving spheres.
    time: Arr<f32>,
    /// The density its last direction was drawn with (0: the camera's or a
    /// specular one): written and read only under `nee-mis`.
    pdf: Arr<f32>,
    len: usize,
}

impl Paths {
    fn new() -> Self {
        let f = || arr(0.0f32);
        let u = || arr(0u32);
        Paths {
            o: [f(), f(), f()],
            d: [f(), f(), f()],
            thr: [f(), f(), f()],
            rng: [u(), u(), u(), u()],
            slot: u(),
            time: f(),
            pdf: f(),
            len: 0,
        }
    }

    /// Appends the lanes of `alive` (a bitmask) of a packet: SIMD stream
    /// compaction. `time`: the paths' times, for a scene with moving
    /// spheres; `pdf`: their directions' densities, under `nee-mis`.
    #[cfg_attr(not(feature = "phases"), inline(always))]
    #[cfg_attr(feature = "phases", inline(never))]
    #[allow(clippy::too_many_arguments)]
    fn append<W: Wide, S: PathSampler>(
        &mut self,
        alive: u32,
        o: V3<W>,
        d: V3<W>,
        thr: V3<W>,
        rng: [W::U; 4],
        slot: W::U,
        time: Option<W>,
        pdf: Option<W>,
    ) {
        let at = self.len;
        debug_assert!(at <= MAX_PATHS);
        let put = |v: &mut Arr<f32>, x: W| compress_f32(v, x, alive, at);
        for (a, (ov, dv, tv)) in [(o.x, d.x, thr.x), (o.y, d.y, thr.y), (o.z, d.z, thr.z)].into_iter().enumerate() {
            put(&mut self.o[a], ov);
            put(&mut self.d[a], dv);
            put(&mut self.thr[a], tv);
        }
        for (w, words) in rng.into_iter().enumerate().take(S::WORDS) {
            W::compress_store_u_pow2(words, alive, &mut self.rng[w], at);
        }
        if let Some(t) = time {
            put(&mut self.time, t);
        }
        if let Some(p) = pdf {
            put(&mut self.pdf, p);
        }
        self.len = at + W::compress_store_u_pow2(slot, alive, &mut self.slot, at);
    }

    #[inline(always)]
    fn v3<W: Wide>(v: &[Arr<f32>; 3], i: usize) -> V3<W> {
        V3::new(W::load_pow2(&v[0], i), W::load_pow2(&v[1], i), W::load_pow2(&v[2], i))
    }

    /// The sampler streams of a packet's paths (their `S::WORDS` words each).
    #[inline(always)]
    fn rng<W: Wide, S: PathSampler>(&self, sampler: S, at: impl Packet<W>) -> S::Lanes<W> {
        sampler.lanes::<W>(std::array::from_fn(|w| if w < S::WORDS { at.u(&self.rng[w]) } else { W::u_splat(0) }))
    }

    /// Stores the streams of the run of paths at `i` back.
    #[inline(always)]
    fn store_rng<W: Wide, S: PathSampler>(&mut self, rng: &S::Lanes<W>, i: usize) {
        for (w, words) in S::lane_words::<W>(rng).into_iter().enumerate().take(S::WORDS) {
            W::store_u_pow2(words, &mut self.rng[w], i);
        }
    }
}

/// Stores the lanes of `keep` (a bitmask) of `x` at `v[at..]`, in lane
/// order (SIMD stream compaction of a per-path f32 array).
#[inline(always)]
fn compress_f32<W: Wide>(v: &mut Arr<f32>, x: W, keep: u32, at: usize) -> usize {
    let v: &mut [u32; CAP] = bytemuck::cast_slice_mut(&mut v[..]).try_into().unwrap();
    W::compress_store_u_pow2(x.to_bits(), keep, v, at)
}

/// The shadow rays of a bounce (`nee-mis`), structure of arrays: at most
/// one per path, appended by the diffuse scatter passes, traced by the
/// shadow pass.
struct Shadows {
    o: [Arr<f32>; 3],
    d: [Arr<f32>; 3],
    tmax: Arr<f32>,
    /// What each carries to its path's result if nothing blocks it.
    c: [Arr<f32>; 3],
    slot: Arr<u32>,
    /// Scenes with moving spheres: the path's time.
    time: Arr<f32>,
    len: usize,
}

impl Shadows {
    fn new() -> Self {
        let f = || arr(0.0f32);
        Shadows {
            o: [f(), f(), f()],
            d: [f(), f(), f()],
            tmax: f(),
            c: [f(), f(), f()],
            slot: arr(0),
            time: f(),
            len: 0,
        }
    }

    /// Appends the lanes of `keep` (a bitmask): SIMD stream compaction.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn append<W: Wide>(&mut self, keep: u32, o: V3<W>, d: V3<W>, tmax: W, c: V3<W>, slot: W::U32, time: Option<W>) {
        let at = self.len;
        debug_assert!(at + keep.count_ones() as usize <= MAX_PATHS);
        let put = |v: &mut Arr<f32>, x: W| compress_f32(v, x, keep, at);
        for (a, (ov, dv, cv)) in [(o.x, d.x, c.x), (o.y, d.y, c.y), (o.z, d.z, c.z)].into_iter().enumerate() {
            put(&mut self.o[a], ov);
            put(&mut self.d[a], dv);
            put(&mut self.c[a], cv);
        }
        put(&mut self.tmax, tmax);
        if let Some(t) = time {
            put(&mut self.time, t);
        }
        self.len = at + W::compress_store_u_pow2(slot, keep, &mut self.slot, at);
    }
}

/// Where a packet's W paths are in `cur`, and which of its lanes are real
/// (`live`, a bitmask): W queued indices, read by gathers ([`Queued`]), or W
/// contiguous indices, read by whole-vector loads ([`Run`]). The scatter
/// passes are written once over both.
trait Packet<W: Wide>: Copy {
    /// The packet's lanes of a per-path array.
    fn f(self, v: &Arr<f32>) -> W;
    fn u(self, v: &Arr<u32>) -> W::U32;
    fn v3(self, v: &[Arr<f32>; 3]) -> V3<W> {
        V3::new(self.f(&v[0]), self.f(&v[1]), self.f(&v[2]))
    }
    /// The paths' indices (probes, and the passes that write lane by lane).
    fn idx(self) -> W::Idx;
    /// The real lanes.
    fn live(self) -> u32;
}

/// W queued indices, masked below `CAP` (the last packet of a queue padded
/// with a real path's index), and the real lanes.
struct Queued<W: Wide> {
    idx: W::Idx,
    live: u32,
}

impl<W: Wide> Clone for Queued<W> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<W: Wide> Copy for Queued<W> {}

impl<W: Wide> Packet<W> for Queued<W> {
    #[inline(always)]
    fn f(self, v: &Arr<f32>) -> W {
        W::gather_pow2(v, &self.idx)
    }
    #[inline(always)]
    fn u(self, v: &Arr<u32>) -> W::U32 {
        W::gather_u_pow2(v, &self.idx)
    }
    #[inline(always)]
    fn idx(self) -> W::Idx {
        self.idx
    }
    #[inline(always)]
    fn live(self) -> u32 {
        self.live
    }
}

/// The W contiguous paths `i..i + W` (`i` a multiple of W below
/// `MAX_PATHS`), of which the lanes `live` are real: a packet scattered
/// where the classification found it, without a queue. Lanes outside `live`
/// (misses, or past the bounce's last path) hold stale values: they compute
/// what they compute and nothing of theirs is written.
#[derive(Clone, Copy)]
struct Run {
    i: usize,
    live: u32,
}

impl<W: Wide> Packet<W> for Run {
    #[inline(always)]
    fn f(self, v: &Arr<f32>) -> W {
        W::load_pow2(v, self.i)
    }
    #[inline(always)]
    fn u(self, v: &Arr<u32>) -> W::U32 {
        W::load_u_pow2(v, self.i)
    }
    #[inline(always)]
    fn idx(self) -> W::Idx {
        index_run::<W>(self.i)
    }
    #[inline(always)]
    fn live(self) -> u32 {
        self.live
    }
}

/// Bits `0..n` set.
#[inline(always)]
fn low_bits(n: usize) -> u32 {
    if n >= 32 {
        u32::MAX
    } else {
        (1u32 << n) - 1
    }
}

/// A thread's wavefront state, reused across tiles (no allocation per tile).
pub struct Workspace {
    cur: Paths,
    next: Paths,
    hit: Arr<u32>,
    t: Arr<f32>,
    /// Indices into `cur`, one queue per material kind (by `Kind as usize`) and one for
    /// misses (filled from the front each bounce).
    queue: Option<[Arr<u32>; MISS_QUEUE + 1]>,
    /// Each path's colour, by its slot.
    result: Arr<[f32; 3]>,
    /// The bounce's shadow rays (`nee-mis`), and how many the tile traced.
    shadows: Shadows,
    shadow_rays: u64,
    /// Scenes with textures: the albedo of each textured lambertian hit, by
    /// its index in `cur`, written by the texture passes, read by the
    /// lambertian pass; and the texture queues.
    albedo: [Arr<f32>; 3],
    tex_queue: Option<[Arr<u32>; TEX_QUEUES]>,
    /// The tile's pixels (row-major local indices) that still take samples.
    active: Vec<u32>,
    /// Per active pixel, for the camera rays of a round: its coordinates and
    /// what its paths' sampler state words share ([`PathSampler::pixel_words`]).
    pixel_xy: Vec<[f32; 2]>,
    pixel_words: Vec<[u32; 4]>,
    /// Probes only: the image index of each active pixel, and the batch's first sample.
    pixel: Vec<u32>,
    batch_start: u32,
}

impl Default for Workspace {
    fn default() -> Self {
        Workspace {
            cur: Paths::new(),
            next: Paths::new(),
            hit: arr(0),
            t: arr(0.0),
            queue: Some(std::array::from_fn(|_| arr(0))),
            result: arr([0.0; 3]),
            shadows: Shadows::new(),
            shadow_rays: 0,
            albedo: [arr(0.0), arr(0.0), arr(0.0)],
            tex_queue: Some(std::array::from_fn(|_| arr(0))),
            active: Vec::with_capacity(MAX_PATHS),
            pixel_xy: Vec::with_capacity(MAX_PATHS),
            pixel_words: Vec::with_capacity(MAX_PATHS),
            pixel: Vec::with_capacity(MAX_PATHS),
            batch_start: 0,
        }
    }
}

impl Workspace {
    /// The path ids of the paths whose `cur` indices are `idx` (probes only).
    fn ids<W: Wide>(&self, idx: &W::Idx) -> PathId<W> {
        let na = self.active.len() as u32;
        let slot = |k: usize| self.cur.slot[idx.as_ref()[k] as usize & MASK];
        PathId {
            pixel: W::u_from_fn(|k| self.pixel[(slot(k) % na) as usize]),
            sample: W::u_from_fn(|k| self.batch_start + slot(k) / na),
        }
    }
}

/// Renders samples `samples` of every pixel of `tile` (at most `MAX_PATHS`
/// pixels), with the paths' values drawn by `sampler`; returns the rays traced.
///
/// Samples are rendered in rounds that end at the adaptive decision points
/// (one round without adaptive sampling). After each round, pixels whose error
/// estimate is low enough leave the active list; the next round traces only
/// the others, so fewer active pixels get more samples per batch and the
/// packets stay full.
///
/// The kernel is instantiated twice: for a scene with moving spheres (each
/// path carries a time) and for one without (`M = false`), which compiles to
/// the bounce it ran before motion blur existed; the choice is made here,
/// once per tile.
pub fn render_tile<W: Wide, P: Probe, S: PathSampler>(
    prep: &Prepared,
    sampler: S,
    ws: &mut Workspace,
    tile: &mut TileFilm,
    samples: Range<u32>,
    probe: &mut P,
) -> u64 {
    if prep.moving.is_empty() {
        render_tile_in::<W, P, S, false>(prep, sampler, ws, tile, samples, probe)
    } else {
        render_tile_in::<W, P, S, true>(prep, sampler, ws, tile, samples, probe)
    }
}

/// [`render_tile`] for a scene with moving spheres (`M`) or without.
fn render_tile_in<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    prep: &Prepared,
    sampler: S,
    ws: &mut Workspace,
    tile: &mut TileFilm,
    samples: Range<u32>,
    probe: &mut P,
) -> u64 {
    let px = tile.sum.len();
    assert!(px <= MAX_PATHS, "tile of {px} pixels exceeds the wavefront's {MAX_PATHS} paths");
    let est = &prep.estimator;
    ws.active.clear();
    ws.active.extend(0..px as u32);
    ws.shadow_rays = 0;
    let mut rays = 0;
    let mut done = samples.start;
    while done < samples.end && !ws.active.is_empty() {
        let end = est.round_end(done, samples.end);
        rays += render_round::<W, P, S, M>(prep, sampler, ws, tile, done, end, probe);
        done = end;
        if let (true, Some(a)) = (done < samples.end, est.adaptive) {
            ws.active.retain(|&l| !a.converged(tile, l as usize));
        }
    }
    tile.shadow_rays += ws.shadow_rays;
    rays
}

/// Samples `s0..s1` of every active pixel, in batches of at most `MAX_PATHS` paths.
fn render_round<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    prep: &Prepared,
    sampler: S,
    ws: &mut Workspace,
    tile: &mut TileFilm,
    s0: u32,
    s1: u32,
    probe: &mut P,
) -> u64 {
    let na = ws.active.len();
    let batch = (MAX_PATHS / na).max(1) as u32;
    // What the camera rays of every sample of a pixel share, once per round
    // (and, for probes, the pixel's image index).
    let st = &prep.settings;
    ws.pixel_xy.clear();
    ws.pixel_words.clear();
    ws.pixel.clear();
    for &l in &ws.active {
        let (x, y) = tile.pixel_of(l as usize);
        let pixel = y * st.width + x;
        ws.pixel_xy.push([x as f32, y as f32]);
        ws.pixel_words.push(sampler.pixel_words(st.seed, pixel as u64));
        if P::PATHS {
            ws.pixel.push(pixel);
        }
    }
    let mut rays = 0;
    let mut b0 = s0;
    while b0 < s1 {
        let b1 = (b0 + batch).min(s1);
        let n = (b1 - b0) as usize * na;
        ws.result[..n].fill([0.0; 3]);
        ws.batch_start = b0;
        generate::<W, P, S, M>(prep, sampler, ws, b0, b1, probe);
        for depth in 0..prep.settings.max_depth {
            if ws.cur.len == 0 {
                break;
            }
            rays += bounce::<W, P, S, M>(prep, sampler, ws, depth, probe);
        }
        tile.add_rounds(&ws.active, &ws.result[..n]);
        b0 = b1;
    }
    rays
}

/// Camera rays for samples `s0..s1` of every active pixel of the tile, W at a time.
/// Path `slot` is sample `s0 + slot / na` of active pixel `slot % na`.
#[cfg_attr(feature = "phases", inline(never))]
fn generate<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    prep: &Prepared,
    sampler: S,
    ws: &mut Workspace,
    s0: u32,
    s1: u32,
    probe: &mut P,
) {
    let na = ws.active.len();
    let n = (s1 - s0) as usize * na;
    let p = &mut ws.cur;
    // Pixel coordinates ride in the throughput arrays until the rays exist.
    // Path `slot` is sample `s0 + slot / na` of active pixel `slot % na`:
    // counted out, without a division.
    let mut slot = 0;
    for sample in s0..s1 {
        for (&[x, y], &pw) in ws.pixel_xy.iter().zip(&ws.pixel_words) {
            let state = sampler.words_at(pw, sample);
            for (w, word) in state.into_iter().enumerate().take(S::WORDS) {
                p.rng[w][slot & MASK] = word;
            }
            p.thr[0][slot & MASK] = x;
            p.thr[1][slot & MASK] = y;
            p.slot[slot & MASK] = slot as u32;
            slot += 1;
        }
    }
    debug_assert_eq!(slot, n);
    p.len = n;
    for i in (0..n).step_by(W::LANES) {
        let p = &mut ws.cur;
        let mut rng = p.rng::<W, S>(sampler, Run { i, live: low_bits(n - i) });
        let (o, d) = prep.camera.ray(W::load_pow2(&p.thr[0], i), W::load_pow2(&p.thr[1], i), &mut rng);
        if M {
            // The path's time, after its camera ray, as the scalar kernel draws it.
            rng.seek(layout::TIME);
            let time: W = rng.next();
            time.store_pow2(&mut ws.cur.time, i);
        }
        let o = if P::PATHS {
            let idx: W::Idx = index_run::<W>(i);
            let id = ws.ids::<W>(&idx);
            probe.camera(id, o, d, low_bits(n - i))
        } else {
            o
        };
        let p = &mut ws.cur;
        for (a, (oa, da)) in [(o.x, d.x), (o.y, d.y), (o.z, d.z)].into_iter().enumerate() {
            oa.store_pow2(&mut p.o[a], i);
            da.store_pow2(&mut p.d[a], i);
            W::splat(1.0).store_pow2(&mut p.thr[a], i);
        }
        if prep.plan.nee > 0 {
            W::splat(0.0).store_pow2(&mut p.pdf, i);
        }
        p.store_rng::<W, S>(&rng, i);
    }
}

/// The indices `i..i + LANES`.
#[inline(always)]
fn index_run<W: Wide>(i: usize) -> W::Idx {
    let mut idx = W::Idx::default();
    for (k, v) in idx.as_mut().iter_mut().enumerate() {
        *v = (i + k) as u32;
    }
    idx
}

/// One bounce of every live path: intersect and shade misses, classify, scatter.
/// `depth` counts the rays each path has traced before this bounce (0: camera
/// rays). Returns the rays traced. (Inlined, as the compiler chose to before
/// the light pass made it larger.)
#[cfg_attr(not(feature = "phases"), inline(always))]
fn bounce<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    prep: &Prepared,
    sampler: S,
    ws: &mut Workspace,
    depth: u32,
    probe: &mut P,
) -> u64 {
    let n = ws.cur.len;
    probe.rays(depth, n as u32);
    intersect::<W, P, M>(prep, ws, n, probe);
    if !prep.media.is_empty() {
        medium_pass::<W, S>(prep, sampler, ws, n, depth);
    }
    let nee = prep.plan.nee > 0;
    // A black background adds nothing to a path that misses (`is_black`).
    let shade = !prep.sky.is_black();
    if nee {
        if shade {
            shade_misses::<W, true>(prep, ws, n);
        }
        ws.shadows.len = 0;
    } else if shade {
        shade_misses::<W, false>(prep, ws, n);
    }
    let mut len = [0usize; MISS_QUEUE + 1];
    let mut queues = ws.queue.take().expect("the queues are put back after every bounce");
    ws.next.len = 0;
    // The sphere and quad arrays have a power-of-two length above every hit
    // index (`Spheres::pad`, `Quads::pad`). Quads' hit indices are
    // `QUAD_BASE + i`, above every sphere's and below `MISS`.
    let kind_mask = prep.spheres.kind.len().wrapping_sub(1);
    let quad_mask = prep.quads.kind.len().wrapping_sub(1);
    let moving_mask = prep.moving.s.kind.len().wrapping_sub(1);
    debug_assert!(prep.spheres.kind.len().is_power_of_two() && prep.quads.kind.len().is_power_of_two());
    // A scene without moving spheres or media classifies W paths at a time:
    // the packet's material kinds (one lookup per lane, in the spheres' or
    // the quads' table); a packet whose hits share a kind
    // that has a plain scatter pass is scattered where it is; the others'
    // lanes are compressed onto their kinds' queues, in path order as one
    // path at a time would append them. Misses (shaded above) join no queue.
    if !M && prep.media.is_empty() {
        // The path tracer queues only the kinds it has passes for (the plan's);
        // the debug modes shade every kind.
        let path = prep.plan.mode == Mode::Path;
        let kinds = if path { prep.plan.kinds } else { KindSet::all() };
        // The kinds whose pass is `scatter` alone: not lights, not a
        // lambertian whose texture passes must run first.
        let in_place = Kind::SURFACES.map(|k| {
            path && Dirs::of(prep) == Dirs::Bsdf
                && prep.plan.kinds.contains(k)
                && match k {
                    Kind::Lambertian => prep.plan.textures.is_empty(),
                    Kind::Metal | Kind::Dielectric => true,
                    Kind::DiffuseLight | Kind::Isotropic => false,
                }
        });
        // Compiled apart for a scene with quads: a sphere-only scene's
        // packets read one kind table, with no test per lane.
        macro_rules! classify {
            ($quads:literal) => {
                classify_packets::<W, P, S, M, $quads>(
                    prep,
                    sampler,
                    ws,
                    n,
                    depth,
                    kinds,
                    in_place,
                    &mut queues,
                    &mut len,
                    probe,
                )
            };
        }
        let placed = if prep.quads.is_empty() { classify!(false) } else { classify!(true) };
        debug_assert!(
            ws.hit[..n].iter().filter(|&&h| h != MISS).count() == len.iter().sum::<usize>() + placed,
            "the plan left out a kind that was hit"
        );
    } else {
        for (i, &h) in ws.hit[..n].iter().enumerate() {
            // Hit indices in order: spheres, quads, moving spheres, media,
            // MISS (two tests for a sphere or a quad, as before media existed;
            // moving spheres only in a scene that has them).
            let q = if h < QUAD_BASE {
                prep.spheres.kind[h as usize & kind_mask] as usize
            } else if h < MEDIUM_BASE {
                if !M || h < MOVING_BASE {
                    prep.quads.kind[(h - QUAD_BASE) as usize & quad_mask] as usize
                } else {
                    prep.moving.s.kind[(h - MOVING_BASE) as usize & moving_mask] as usize
                }
            } else if h == MISS {
                MISS_QUEUE
            } else {
                Kind::Isotropic as usize
            };
            queues[q][len[q] & MASK] = i as u32;
            len[q] += 1;
        }
    }
    for kind in Kind::ALL {
        let (q, qlen) = (&queues[kind as usize], len[kind as usize]);
        match prep.plan.mode {
            Mode::Path if kind == Kind::DiffuseLight && prep.plan.kinds.contains(kind) => {
                for_packets::<W, P>(q, qlen, probe, |at, probe| {
                    let Hits { srf, albedo: emit, param, .. } = surfaces::<W, P, M>(prep, ws, at, probe);
                    let one_sided = param.gt(W::splat(0.0));
                    let c = at.v3(&ws.cur.thr).mul_elem(emission(emit, one_sided, srf.front));
                    if nee {
                        write_results::<W, true>(ws, at, c * light_weight::<W, M>(prep, ws, at));
                    } else {
                        write_results::<W, false>(ws, at, c);
                    }
                });
            }
            Mode::Path if kind == Kind::Isotropic && prep.plan.kinds.contains(kind) => {
                isotropic_pass::<W, P, S, M>(prep, sampler, ws, q, qlen, depth, probe);
            }
            Mode::Path if kind == Kind::Lambertian && !prep.plan.textures.is_empty() => {
                textured_lambertian_pass::<W, P, S, M>(prep, sampler, ws, q, qlen, depth, probe);
            }
            // The book and nee-mis estimators' passes apart: the bsdf
            // estimator's are the ones it always ran (the same instructions
            // per ray).
            Mode::Path if prep.plan.kinds.contains(kind) && prep.plan.sample_toward > 0 => {
                for_packets::<W, P>(q, qlen, probe, |at, probe| {
                    scatter::<W, P, S, M>(prep, sampler, ws, kind, depth, at, false, Dirs::Book, probe)
                });
            }
            Mode::Path if prep.plan.kinds.contains(kind) && nee => {
                for_packets::<W, P>(q, qlen, probe, |at, probe| {
                    scatter::<W, P, S, M>(prep, sampler, ws, kind, depth, at, false, Dirs::Nee, probe)
                });
            }
            Mode::Path if prep.plan.kinds.contains(kind) => {
                for_packets::<W, P>(q, qlen, probe, |at, probe| {
                    scatter::<W, P, S, M>(prep, sampler, ws, kind, depth, at, false, Dirs::Bsdf, probe)
                });
            }
            Mode::Path => debug_assert!(qlen == 0, "the plan left out a kind that was hit"),
            mode @ (Mode::Flat | Mode::Normals | Mode::Gradient) => {
                for_packets::<W, P>(q, qlen, probe, |at, probe| debug_shade::<W, P, M>(prep, ws, mode, at, probe));
            }
        }
    }
    ws.queue = Some(queues);
    if nee && ws.shadows.len > 0 {
        shadow_pass::<W, P, M>(prep, ws, probe);
    }
    std::mem::swap(&mut ws.cur, &mut ws.next);
    n as u64
}

/// The classification of a scene of spheres and quads (no moving spheres, no
/// media), W paths at a time: the packet's material kinds (one lookup per
/// lane in the spheres' or, for a quad's hit index, the quads' kind table,
/// each a power of two long above every index it is read at). A packet whose
/// hits all share a kind of `in_place` (by `Kind as usize`), and that has
/// at least three quarters of its lanes hit, is scattered where it is (the
/// bsdf estimator's pass), its paths read by whole-vector loads (a [`Run`]):
/// the image does not depend on the order in which paths join the next
/// bounce, only the packets' make-up does. Any other packet's hit lanes are compressed,
/// per kind in `kinds`, onto that kind's queue, in path order as one path at
/// a time would append them. Misses join no queue (their pass is
/// `shade_misses`). The surface kinds are a constant each (the loop over
/// them is unrolled), so each queue's length stays in a register and a kind
/// the scene does not have costs one predictable branch. Returns the number
/// of hits scattered in place (debug builds; 0 otherwise).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn classify_packets<W: Wide, P: Probe, S: PathSampler, const M: bool, const Q: bool>(
    prep: &Prepared,
    sampler: S,
    ws: &mut Workspace,
    n: usize,
    depth: u32,
    kinds: KindSet,
    in_place: [bool; Kind::SURFACES.len()],
    queues: &mut [Arr<u32>; MISS_QUEUE + 1],
    len: &mut [usize; MISS_QUEUE + 1],
    probe: &mut P,
) -> usize {
    const SURF: usize = Kind::SURFACES.len();
    // The fewest hits a packet scattered in place has: its lanes' arithmetic
    // is a whole packet's whatever their number, so an emptier one costs
    // more than the queue it saves (measured: docs/history.md, the fifth round).
    let full_enough = W::LANES * 3 / 4;
    let kind_of = &prep.spheres.kind[..];
    let kind_mask = kind_of.len().wrapping_sub(1);
    // `Q`: the scene has quads (a sphere-only scene reads one table; the
    // quads' may be empty).
    debug_assert_eq!(Q, !prep.quads.is_empty());
    let quad_kind = &prep.quads.kind[..];
    let quad_mask = quad_kind.len().wrapping_sub(1);
    let only_quads = prep.spheres.is_empty();
    debug_assert!(quad_kind.len() as u32 <= QUAD_BASE);
    let want: [bool; SURF] = Kind::SURFACES.map(|k| kinds.contains(k));
    let mut lens: [usize; SURF] = Kind::SURFACES.map(|k| len[k as usize]);
    let iota = W::u_from_fn(|k| k as u32);
    // In place: the bsdf estimator's passes only (book one's scenes, and
    // any other scene this classification serves, rendered with it); under
    // the book and nee-mis estimators every packet is queued, as before.
    debug_assert!(Dirs::of(prep) == Dirs::Bsdf || !in_place.contains(&true));
    let mut placed = 0;
    for i in (0..n).step_by(W::LANES) {
        let hit = W::load_u_pow2(&ws.hit, i);
        let hits = W::mask_bits(W::u_lt(hit, W::u_splat(MISS))) & low_bits(n - i);
        let kind = if Q && only_quads {
            // Every hit is a quad's: its index masked into the quads' table
            // (`QUAD_BASE` is above the mask), without the test per lane.
            W::u_from_fn(|k| quad_kind[W::lane_u(hit, k) as usize & quad_mask] as u32)
        } else if Q {
            // Misses (MISS is above every quad's index) read some quad's
            // kind; their lanes are not in `hits`.
            W::u_from_fn(|k| {
                let h = W::lane_u(hit, k);
                if h < QUAD_BASE {
                    kind_of[h as usize & kind_mask] as u32
                } else {
                    quad_kind[(h - QUAD_BASE) as usize & quad_mask] as u32
                }
            })
        } else {
            W::u_from_fn(|k| kind_of[W::lane_u(hit, k) as usize & kind_mask] as u32)
        };
        if hits != 0 {
            let first = W::lane_u(kind, hits.trailing_zeros() as usize & (W::LANES - 1));
            let same = W::mask_bits(W::u_eq(kind, W::u_splat(first))) & hits;
            if same == hits && hits.count_ones() as usize >= full_enough && in_place[first as usize & (SURF - 1)] {
                probe.lanes(Stage::Scatter, hits.count_ones(), W::LANES as u32);
                if cfg!(debug_assertions) {
                    placed += hits.count_ones() as usize;
                }
                let run = Run { i, live: hits };
                // The kind a literal in each arm: each scatter is compiled for its kind.
                const LAMBERTIAN: u32 = Kind::Lambertian as u32;
                const METAL: u32 = Kind::Metal as u32;
                let bsdf = Dirs::Bsdf;
                match first {
                    LAMBERTIAN => {
                        scatter::<W, P, S, M>(prep, sampler, ws, Kind::Lambertian, depth, run, false, bsdf, probe)
                    }
                    METAL => scatter::<W, P, S, M>(prep, sampler, ws, Kind::Metal, depth, run, false, bsdf, probe),
                    _ => {
                        debug_assert_eq!(first, Kind::Dielectric as u32);
                        scatter::<W, P, S, M>(prep, sampler, ws, Kind::Dielectric, depth, run, false, bsdf, probe)
                    }
                }
                continue;
            }
        }
        let idx = iota.wrapping_add(W::u_splat(i as u32));
        for s in 0..SURF {
            if want[s] {
                let k = Kind::SURFACES[s];
                let keep = W::mask_bits(W::u_eq(kind, W::u_splat(k as u32))) & hits;
                lens[s] += W::compress_store_u_pow2(idx, keep, &mut queues[k as usize], lens[s]);
            }
        }
    }
    for (s, k) in Kind::SURFACES.into_iter().enumerate() {
        len[k as usize] = lens[s];
    }
    placed
}

/// How a diffuse vertex chooses its direction: the estimator of the render,
/// a literal at each scatter pass's call, so that each is compiled apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Dirs {
    /// The material's density (`bsdf`).
    Bsdf,
    /// The book's mixture.
    Book,
    /// The material's density, and a light sample on the shadow queue (`nee-mis`).
    Nee,
}

impl Dirs {
    /// The plan's.
    fn of(prep: &Prepared) -> Self {
        if prep.plan.sample_toward > 0 {
            Dirs::Book
        } else if prep.plan.nee > 0 {
            Dirs::Nee
        } else {
            Dirs::Bsdf
        }
    }
}

/// The power heuristic's weight of the lights a packet of queued paths hit
/// (`nee-mis`): each lane's light density in its path's direction from the
/// ray's origin, against the density its direction was drawn with.
#[inline(never)]
fn light_weight<W: Wide, const M: bool>(prep: &Prepared, ws: &Workspace, at: Queued<W>) -> W {
    let hit = at.u(&ws.hit);
    let e = &prep.emitters;
    let shape = W::u_from_fn(|k| e.of_row[material_row::<M>(prep, W::lane_u(hit, k))]);
    let o = at.v3(&ws.cur.o);
    let d = at.v3(&ws.cur.d);
    mis_bsdf(at.f(&ws.cur.pdf), e.pdf_of(o, d, shape))
}

/// The shadow rays of the bounce (`nee-mis`), W contiguous rays per packet:
/// any-hit queries ([`Prepared::occluded`]); what an unblocked one carries
/// (times the media's transmittance, in a scene with media) is added to its
/// path's result. Out of line: it runs once per bounce.
#[inline(never)]
fn shadow_pass<W: Wide, P: Probe, const M: bool>(prep: &Prepared, ws: &mut Workspace, probe: &mut P) {
    let n = ws.shadows.len;
    for i in (0..n).step_by(W::LANES) {
        let sh = &ws.shadows;
        let live = low_bits((n - i).min(W::LANES));
        let (o, d) = (Paths::v3::<W>(&sh.o, i), Paths::v3::<W>(&sh.d, i));
        let tmax = W::load_pow2(&sh.tmax, i);
        let blocked = prep.occluded::<W, P, M>(o, d, tmax, live, || W::load_pow2(&sh.time, i), probe);
        probe.lanes(Stage::Intersect, live.count_ones(), W::LANES as u32);
        let c = Paths::v3::<W>(&sh.c, i);
        let c = if prep.media.is_empty() { c } else { c * transmittance(&prep.media, o, d, tmax) };
        let lanes = live & !W::mask_bits(blocked);
        let slot = W::load_u_pow2(&sh.slot, i);
        write_lanes::<W, true>(&mut ws.result, slot, lanes, c);
    }
    ws.shadow_rays += n as u64;
}

/// The closest hits of the first `n` paths, W contiguous rays per packet,
/// into `ws.hit` and `ws.t`. (Out of line, once per bounce: the traversal's
/// code then does not depend on what the rest of the bounce inlines.)
#[cfg_attr(not(feature = "phases"), inline(never))]
fn intersect<W: Wide, P: Probe, const M: bool>(prep: &Prepared, ws: &mut Workspace, n: usize, probe: &mut P) {
    for i in (0..n).step_by(W::LANES) {
        let live = (n - i).min(W::LANES);
        let (o, d) = (Paths::v3::<W>(&ws.cur.o, i), Paths::v3::<W>(&ws.cur.d, i));
        let time = &ws.cur.time;
        let (hit, t) = prep.closest_hits::<W, P, M>(o, d, low_bits(live), || W::load_pow2(time, i), probe);
        W::store_u_pow2(hit, &mut ws.hit, i);
        t.store_pow2(&mut ws.t, i);
        probe.lanes(Stage::Intersect, live as u32, W::LANES as u32);
        if P::PATHS {
            let idx = index_run::<W>(i);
            probe.traced(ws.ids::<W>(&idx), o, d, hit, t, low_bits(live));
        }
    }
}

/// Scenes with media: the first `n` paths' closest hits become the nearest
/// of the surface and a free-flight sample per medium
/// ([`crate::geometry::media`]), W contiguous paths at a time. Every path
/// draws (its sampler state is stored back), as the scalar kernel's does.
#[inline(never)]
fn medium_pass<W: Wide, S: PathSampler>(prep: &Prepared, sampler: S, ws: &mut Workspace, n: usize, depth: u32) {
    for i in (0..n).step_by(W::LANES) {
        let p = &mut ws.cur;
        let mut rng = p.rng::<W, S>(sampler, Run { i, live: low_bits(n - i) });
        let (o, d) = (Paths::v3::<W>(&p.o, i), Paths::v3::<W>(&p.d, i));
        let (hit, t) = (W::load_u_pow2(&ws.hit, i), W::load_pow2(&ws.t, i));
        let (hit, t) = sample_media(&prep.media, o, d, hit, t, depth, &mut rng);
        W::store_u_pow2(hit, &mut ws.hit, i);
        t.store_pow2(&mut ws.t, i);
        p.store_rng::<W, S>(&rng, i);
    }
}

/// The isotropic queue (paths that stopped inside a medium): a uniform
/// direction from the bounce's two scattering dimensions, the throughput
/// times the medium's albedo, and the new ray from the stopping point
/// `o + t d` (inside the medium: no surface, no offset).
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn isotropic_pass<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    prep: &Prepared,
    sampler: S,
    ws: &mut Workspace,
    queue: &Arr<u32>,
    len: usize,
    depth: u32,
    probe: &mut P,
) {
    let m = &prep.media;
    for_packets::<W, P>(queue, len, probe, |at, _| {
        let cur = &ws.cur;
        let hit = at.u(&ws.hit);
        let k = |j: usize| W::lane_u(hit, j).wrapping_sub(MEDIUM_BASE) as usize;
        let albedo = V3::new(
            W::from_fn(|j| m.albedo[k(j)][0]),
            W::from_fn(|j| m.albedo[k(j)][1]),
            W::from_fn(|j| m.albedo[k(j)][2]),
        );
        let d = at.v3(&cur.d);
        let p = at.v3(&cur.o) + d * at.f(&ws.t);
        let mut rng = cur.rng::<W, S>(sampler, at);
        rng.seek(prep.bounces.scatter(depth));
        let dir = unit_vector(&mut rng);
        let thr = at.v3(&cur.thr);
        let nee = prep.plan.nee > 0;
        let (dir, albedo) = if prep.plan.sample_toward == 0 {
            if nee && depth + 1 < prep.settings.max_depth {
                let (ld, t, carry) =
                    next_event(&prep.emitters, p, |_| W::splat(ISOTROPIC_PDF), prep.bounces.light(depth), &mut rng);
                let c = thr.mul_elem(albedo.mul_elem(carry));
                queue_shadow::<W, M>(ws, at, Shadow { o: p, d: ld, tmax: shadow_tmax(t, W::splat(0.0)), c });
            }
            (dir, albedo)
        } else {
            let (dir, w) =
                book_mixture(&prep.lights, p, dir, |_| W::splat(ISOTROPIC_PDF), prep.bounces.light(depth), &mut rng);
            (dir, albedo * w)
        };
        let thr = thr.mul_elem(albedo);
        let all = W::mask_from_bits(u32::MAX);
        let pdf = nee.then(|| W::splat(ISOTROPIC_PDF));
        continue_paths::<W, S, M>(prep, ws, at, depth, prep.bounces, rng, thr, all, p, dir, pdf);
    });
}

/// The misses of the first `n` paths end here, W contiguous paths at a time
/// in path order: their throughput and directions are loaded, not gathered
/// through a queue. (Out of line: it runs once per bounce, and inlined into
/// the wavefront's loop it costs the traversal's code registers.)
/// `ADD`: added to the result (`nee-mis`, whose light samples may have
/// added to it), else written.
#[inline(never)]
fn shade_misses<W: Wide, const ADD: bool>(prep: &Prepared, ws: &mut Workspace, n: usize) {
    for i in (0..n).step_by(W::LANES) {
        let hit = W::load_u_pow2(&ws.hit, i);
        let missed = W::mask_bits(!W::u_lt(hit, W::u_splat(MISS))) & low_bits(n - i);
        if missed != 0 {
            let d = Paths::v3::<W>(&ws.cur.d, i);
            let c = Paths::v3::<W>(&ws.cur.thr, i).mul_elem(background(&prep.sky, d));
            let slot = W::load_u_pow2(&ws.cur.slot, i);
            write_lanes::<W, ADD>(&mut ws.result, slot, missed, c);
        }
    }
}

/// The lambertian queue of a scene with textures: the texture passes (one
/// per texture kind the plan lists, over the lanes that share it: each
/// writes its paths' albedo), then the lambertian scatter pass, which reads
/// the written albedo where the hit's material is textured. Out of line, so
/// that a scene without textures runs the bounce it always ran.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn textured_lambertian_pass<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    prep: &Prepared,
    sampler: S,
    ws: &mut Workspace,
    queue: &Arr<u32>,
    len: usize,
    depth: u32,
    probe: &mut P,
) {
    let mut tq = ws.tex_queue.take().expect("the texture queues are put back after every pass");
    let mut tlen = [0usize; TEX_QUEUES];
    let m = &prep.materials;
    for &i in &queue[..len] {
        let tex = m.lambertian_tex[material_row::<M>(prep, ws.hit[i as usize & MASK])].kind;
        if tex != TexKind::Solid {
            let q = tex as usize - 1;
            tq[q][tlen[q] & MASK] = i;
            tlen[q] += 1;
        }
    }
    for kind in prep.plan.textures.iter() {
        let q = kind as usize - 1;
        // The texture passes are not observed by probes: their lanes are the
        // lambertian pass's, which reports them.
        for_packets::<W, ()>(&tq[q], tlen[q], &mut (), |at, _| {
            let Hits { srf, .. } = surfaces::<W, (), M>(prep, ws, at, &mut ());
            let hits = at.u(&ws.hit);
            let row = |k: usize| m.lambertian_tex[material_row::<M>(prep, W::lane_u(hits, k))].row as usize;
            let c = texture_albedo(prep, kind, srf.p, |k| W::lane_u(hits, k), row);
            for (k, &i) in at.idx.as_ref().iter().enumerate().take(at.live.count_ones() as usize) {
                let i = i as usize & MASK;
                ws.albedo[0][i] = c.x.lane(k);
                ws.albedo[1][i] = c.y.lane(k);
                ws.albedo[2][i] = c.z.lane(k);
            }
        });
    }
    ws.tex_queue = Some(tq);
    let dirs = Dirs::of(prep);
    for_packets::<W, P>(queue, len, probe, |at, probe| {
        scatter::<W, P, S, M>(prep, sampler, ws, Kind::Lambertian, depth, at, true, dirs, probe)
    });
}

/// The material row of the primitive of hit index `h` (not `MISS`).
#[inline(always)]
fn material_row<const M: bool>(prep: &Prepared, h: u32) -> usize {
    if h < QUAD_BASE {
        prep.spheres.row[h as usize] as usize
    } else if !M || h < MOVING_BASE {
        prep.quads.row[(h - QUAD_BASE) as usize] as usize
    } else {
        prep.moving.s.row[(h - MOVING_BASE) as usize] as usize
    }
}

/// Calls `f` with each packet of W indices of the first `len` entries of
/// `queue` (the last packet padded by repeating its first index, so every lane
/// holds a real path) and its real lanes. The indices are masked
/// into the arrays' range (a no-op on indices below `MAX_PATHS`), so the
/// gathers by them need no bounds checks.
#[inline(always)]
fn for_packets<W: Wide, P: Probe>(queue: &Arr<u32>, len: usize, probe: &mut P, mut f: impl FnMut(Queued<W>, &mut P)) {
    debug_assert!(len <= MAX_PATHS && queue[..len].iter().all(|&i| (i as usize) < MAX_PATHS));
    for i in (0..len).step_by(W::LANES) {
        let active = (len - i).min(W::LANES);
        let run = W::load_u_pow2(queue, i);
        let first = W::u_splat(queue[i & MASK]);
        let run = W::u_select(W::mask_from_bits(low_bits(active)), run, first);
        let idx = W::idx_of(run & W::u_splat(MASK as u32));
        probe.lanes(Stage::Scatter, active as u32, W::LANES as u32);
        f(Queued { idx, live: low_bits(active) }, probe);
    }
}

#[inline(always)]
fn write_results<W: Wide, const ADD: bool>(ws: &mut Workspace, at: impl Packet<W>, c: V3<W>) {
    let slot = at.u(&ws.cur.slot);
    write_lanes::<W, ADD>(&mut ws.result, slot, at.live(), c);
}

/// `result[slot[k]] = c[k]` (`ADD`: `+= c[k]`) for the lanes k set in `lanes`.
#[inline(always)]
fn write_lanes<W: Wide, const ADD: bool>(result: &mut Arr<[f32; 3]>, slot: W::U32, mut lanes: u32, c: V3<W>) {
    // The lanes as arrays once (a lane taken from a vector one at a time
    // was stored whole to the stack each time), indexed below `LANES`.
    debug_assert!(lanes < 1 << W::LANES as u64);
    let slot = W::idx_of(slot);
    let (cx, cy, cz) = (W::idx_of(c.x.to_bits()), W::idx_of(c.y.to_bits()), W::idx_of(c.z.to_bits()));
    let (slot, cx, cy, cz) = (slot.as_ref(), cx.as_ref(), cy.as_ref(), cz.as_ref());
    while lanes != 0 {
        let k = lanes.trailing_zeros() as usize & (W::LANES - 1);
        lanes &= lanes - 1;
        let s = slot[k] as usize;
        debug_assert!(s < MAX_PATHS);
        let c = [f32::from_bits(cx[k]), f32::from_bits(cy[k]), f32::from_bits(cz[k])];
        let r = &mut result[s & MASK];
        *r = if ADD { [r[0] + c[0], r[1] + c[1], r[2] + c[2]] } else { c };
    }
}

/// A packet's hits: the rays' directions, the surfaces, and the hit
/// spheres' material parameters (albedo, and fuzz or index of refraction).
struct Hits<W: Wide> {
    d: V3<W>,
    srf: Surface<W>,
    albedo: V3<W>,
    param: W,
}

/// The hit surfaces of a packet of queued paths. The hit primitives'
/// shading records ([`Shade`]) are loaded whole, one per lane, and
/// transposed. In a scene with quads a packet may hold both kinds: both
/// records and both surfaces are computed, and each lane keeps its own (the
/// same values the scalar kernel computes for its one kind).
#[inline(always)]
fn surfaces<W: Wide, P: Probe, const M: bool>(
    prep: &Prepared,
    ws: &Workspace,
    at: impl Packet<W>,
    probe: &mut P,
) -> Hits<W> {
    let sph = at.u(&ws.hit);
    if !M && prep.quads.is_empty() {
        // Book one's surfaces, as they were. The index is masked into the
        // records' range: a no-op on a hit index, and a lane of a run that is
        // not live (a miss's index, or a stale one) reads some record.
        let rec =
            W::gather_rows8(&prep.spheres.shade, &W::idx_of(sph & W::u_splat(prep.spheres.shade.len() as u32 - 1)));
        let c = V3::new(rec[Shade::CX], rec[Shade::CY], rec[Shade::CZ]);
        let r = rec[Shade::R];
        let d = at.v3(&ws.cur.d);
        let srf = surface(at.v3(&ws.cur.o), d, at.f(&ws.t), c, r);
        if P::PATHS {
            probe.shaded(ws.ids::<W>(&at.idx()), sph, r, srf.n, srf.front, at.live());
        }
        let a = Shade::ALBEDO;
        return Hits { d, srf, albedo: V3::new(rec[a], rec[a + 1], rec[a + 2]), param: rec[Shade::PARAM] };
    }
    let d = at.v3(&ws.cur.d);
    let o = at.v3(&ws.cur.o);
    let t = at.f(&ws.t);
    let q_mask = W::u_splat(prep.quads.shade.len() as u32 - 1);
    if !M && prep.spheres.is_empty() {
        // A scene of quads alone (the Cornell boxes): every hit is a quad's,
        // so the sphere records and surfaces the mixed case computes and
        // then selects away are not computed (the same lanes, bit for bit).
        let rec = W::gather_rows8(&prep.quads.shade, &W::idx_of(sph & q_mask));
        let srf = quad_surface(o, d, t, V3::new(rec[0], rec[1], rec[2]), rec[3]);
        if P::PATHS {
            probe.shaded(ws.ids::<W>(&at.idx()), sph, W::splat(0.0), srf.n, srf.front, at.live());
        }
        let a = Shade::ALBEDO;
        return Hits { d, srf, albedo: V3::new(rec[a], rec[a + 1], rec[a + 2]), param: rec[Shade::PARAM] };
    }
    let (srf, rec): (Surface<W>, [W; 8]) = {
        let is_sphere = W::u_lt(sph, W::u_splat(QUAD_BASE));
        let s_mask = W::u_splat(prep.spheres.shade.len() as u32 - 1);
        let srec = W::gather_rows8(&prep.spheres.shade, &W::idx_of(sph & s_mask));
        let qrec = W::gather_rows8(&prep.quads.shade, &W::idx_of(sph & q_mask));
        let (is_sphere, srec) =
            if !M { (is_sphere, srec) } else { moving_records::<W>(prep, at.f(&ws.cur.time), sph, is_sphere, srec) };
        let c = V3::new(srec[Shade::CX], srec[Shade::CY], srec[Shade::CZ]);
        let r = W::select(is_sphere, srec[Shade::R], W::splat(0.0));
        let s_srf = surface(o, d, t, c, srec[Shade::R]);
        let q_srf = quad_surface(o, d, t, V3::new(qrec[0], qrec[1], qrec[2]), qrec[3]);
        let srf = Surface {
            p: V3::select(is_sphere, s_srf.p, q_srf.p),
            n: V3::select(is_sphere, s_srf.n, q_srf.n),
            front: W::select(is_sphere, s_srf.front, q_srf.front),
            offset: W::select(is_sphere, s_srf.offset, q_srf.offset),
        };
        if P::PATHS {
            probe.shaded(ws.ids::<W>(&at.idx()), sph, r, srf.n, srf.front, at.live());
        }
        (srf, std::array::from_fn(|k| W::select(is_sphere, srec[k], qrec[k])))
    };
    let a = Shade::ALBEDO;
    Hits { d, srf, albedo: V3::new(rec[a], rec[a + 1], rec[a + 2]), param: rec[Shade::PARAM] }
}

/// A packet's sphere records where some lanes may have hit a moving sphere:
/// in those lanes the moving sphere's record with its centre at the path's
/// time ([`centre_at`], the scalar kernel's formula), and the lanes counted
/// as spheres.
#[inline(never)]
fn moving_records<W: Wide>(prep: &Prepared, time: W, hit: W::U32, is_sphere: W, srec: [W; 8]) -> (W, [W; 8]) {
    let m = &prep.moving;
    let is_moving = !W::u_lt(hit, W::u_splat(MOVING_BASE));
    let m_mask = W::u_splat(m.s.shade.len() as u32 - 1);
    let midx = W::idx_of(hit & m_mask);
    let mut mrec = W::gather_rows8(&m.s.shade, &midx);
    let vel = W::gather_rows8(&m.vel, &midx);
    let c =
        centre_at(V3::new(mrec[Shade::CX], mrec[Shade::CY], mrec[Shade::CZ]), V3::new(vel[0], vel[1], vel[2]), time);
    (mrec[Shade::CX], mrec[Shade::CY], mrec[Shade::CZ]) = (c.x, c.y, c.z);
    (is_sphere | is_moving, std::array::from_fn(|k| W::select(is_moving, mrec[k], srec[k])))
}

fn debug_shade<W: Wide, P: Probe, const M: bool>(
    prep: &Prepared,
    ws: &mut Workspace,
    mode: Mode,
    at: Queued<W>,
    probe: &mut P,
) {
    let hits = surfaces::<W, P, M>(prep, ws, at, probe);
    let c = match mode {
        Mode::Normals => normal_colour(hits.srf.n),
        // The flat colour (`MaterialTables::flat_colour`): the albedo, white for glass.
        Mode::Flat | Mode::Gradient | Mode::Path => hits.albedo,
    };
    write_results::<W, false>(ws, at, c);
}

/// Scatters a packet of paths that hit material `kind`; survivors join the next bounce.
#[cfg_attr(not(feature = "phases"), inline(always))]
#[cfg_attr(feature = "phases", inline(never))]
#[allow(clippy::too_many_arguments)]
fn scatter<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    prep: &Prepared,
    sampler: S,
    ws: &mut Workspace,
    kind: Kind,
    depth: u32,
    at: impl Packet<W>,
    textured: bool,
    dirs: Dirs,
    probe: &mut P,
) {
    // `dirs`: the plan's estimator (its sampler layout, its mixture or its
    // light sample at lambertian vertices); a literal at the call, so each
    // is compiled apart.
    debug_assert_eq!(dirs == Dirs::Book, prep.plan.sample_toward > 0);
    debug_assert_eq!(dirs == Dirs::Nee, prep.plan.nee > 0);
    let dims = if dirs == Dirs::Bsdf { Bounces::BSDF } else { prep.bounces };
    let Hits { d, srf, albedo, param } = surfaces::<W, P, M>(prep, ws, at, probe);
    // A textured lambertian's record has parameter 1: its albedo is the one
    // its texture pass wrote.
    let albedo = if textured { V3::select(param.gt(W::splat(0.0)), at.v3(&ws.albedo), albedo) } else { albedo };
    let cur = &ws.cur;
    let mut rng = cur.rng::<W, S>(sampler, at);
    rng.seek(dims.scatter(depth));
    let all = W::mask_from_bits(u32::MAX);
    let thr = at.v3(&ws.cur.thr);
    let (dir, alive, albedo) = match kind {
        Kind::Lambertian => {
            let dir = lambertian(srf.n, &mut rng);
            match dirs {
                Dirs::Bsdf => (dir, all, albedo),
                Dirs::Book => {
                    let (dir, w) =
                        book_mixture(&prep.lights, srf.p, dir, |d| cosine_pdf(srf.n, d), dims.light(depth), &mut rng);
                    (dir, all, albedo * w)
                }
                Dirs::Nee => {
                    if depth + 1 < prep.settings.max_depth {
                        let (ld, t, carry) =
                            next_event(&prep.emitters, srf.p, |d| cosine_pdf(srf.n, d), dims.light(depth), &mut rng);
                        let c = thr.mul_elem(albedo.mul_elem(carry));
                        let shadow = Shadow { o: spawn(&srf, ld), d: ld, tmax: shadow_tmax(t, srf.offset), c };
                        queue_shadow::<W, M>(ws, at, shadow);
                    }
                    (dir, all, albedo)
                }
            }
        }
        Kind::Metal => {
            let (dir, alive) = metal(d, srf.n, param, &mut rng);
            (dir, alive, albedo)
        }
        Kind::Dielectric => (dielectric(d, srf.n, srf.front, param, &mut rng), all, albedo),
        // Lights and media have their own passes (`bounce`).
        Kind::DiffuseLight | Kind::Isotropic => (d, !all, albedo),
    };
    // The albedo of a dielectric's record is white, as the scalar kernel's [1; 3].
    let thr = thr.mul_elem(albedo);
    // Under nee-mis, the density of the direction, for the weight of a light
    // it reaches: the cosine lobe's, 0 for a specular bounce.
    let pdf =
        (dirs == Dirs::Nee).then(|| if kind == Kind::Lambertian { cosine_pdf(srf.n, dir) } else { W::splat(0.0) });
    continue_paths::<W, S, M>(prep, ws, at, depth, dims, rng, thr, alive, spawn(&srf, dir), dir, pdf);
}

/// A packet's light samples (`nee-mis`): shadow rays from `o` along `d` to
/// `tmax`, each carrying `c` to its path's result if nothing blocks it.
struct Shadow<W: Wide> {
    o: V3<W>,
    d: V3<W>,
    tmax: W,
    c: V3<W>,
}

/// Appends the real lanes of a packet's light samples that carry anything
/// to the shadow queue, as the scalar kernel traces exactly those.
#[inline(always)]
fn queue_shadow<W: Wide, const M: bool>(ws: &mut Workspace, at: impl Packet<W>, sh: Shadow<W>) {
    let zero = W::splat(0.0);
    let carries = sh.c.x.gt(zero) | sh.c.y.gt(zero) | sh.c.z.gt(zero);
    let keep = W::mask_bits(carries) & at.live();
    if keep == 0 {
        return;
    }
    let slot = at.u(&ws.cur.slot);
    let time = if M { Some(at.f(&ws.cur.time)) } else { None };
    ws.shadows.append::<W>(keep, sh.o, sh.d, sh.tmax, sh.c, slot, time);
}

/// The end of every scatter pass: paths whose throughput is zero die, then
/// Russian roulette (every lane draws, as the scalar path does when it gets
/// here; lanes already dead draw too, but their streams are never used
/// again), and the survivors' rays from `o` along `dir` join the next
/// bounce with their slots and, in a scene that moves, their paths' times.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn continue_paths<W: Wide, S: PathSampler, const M: bool>(
    prep: &Prepared,
    ws: &mut Workspace,
    at: impl Packet<W>,
    depth: u32,
    dims: Bounces,
    mut rng: S::Lanes<W>,
    thr: V3<W>,
    alive: <W as crate::real::Real>::Mask,
    o: V3<W>,
    dir: V3<W>,
    pdf: Option<W>,
) {
    let zero = W::splat(0.0);
    let dark = thr.x.eq(zero) & thr.y.eq(zero) & thr.z.eq(zero);
    let mut alive = alive & !dark;
    let mut thr = thr;
    if roulette_applies(&prep.estimator, depth + 1) {
        rng.seek(dims.roulette(depth));
        let (t, survives) = roulette(thr, &mut rng);
        thr = t;
        alive = alive & survives;
    }
    let alive = W::mask_bits(alive) & at.live();
    let cur = &ws.cur;
    let slot = at.u(&cur.slot);
    let time = if M { Some(at.f(&cur.time)) } else { None };
    ws.next.append::<W, S>(alive, o, dir, thr, S::lane_words::<W>(&rng), slot, time, pdf);
}
