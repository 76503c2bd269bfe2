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

mod classify;
mod hits;
mod packet;
mod passes;
mod scatter;
mod store;
mod workspace;

use crate::choice::Mode;
use crate::estimator::{
    cosine_pdf, mis_bsdf, roulette, roulette_applies, shadow_tmax, Directions, Toward, ISOTROPIC_PDF,
};
use crate::film::TileFilm;
use crate::geometry::{
    below, centre_at, emission, quad_surface, sample_media, shading_normal, spawn, surface, transmittance, Shade,
    Surface, Triangles, INSTANCE_BASE, MEDIUM_BASE, MISS, MOVING_BASE, QUAD_BASE, TRIANGLE_BASE,
};
use crate::handle::Kind;
use crate::kernel::{background, normal_colour, texture_albedo};
use crate::material::{dielectric, lambertian, metal};
use crate::plan::{KindSet, Prepared};
use crate::probe::{PathId, Probe, Stage};
use crate::real::{U32Lanes, Wide, MAX_LANES};
use crate::sampling::layout::{self, Bounces};
use crate::sampling::{unit_vector, PathSampler, Stream};
use crate::texture::TexKind;
use crate::vec3::V3;
use std::ops::Range;

use classify::*;
use hits::*;
use packet::*;
use passes::*;
use scatter::*;
use store::*;
pub use workspace::Workspace;

/// Paths in flight per workspace (per thread), at most.
pub const MAX_PATHS: usize = 2048;

/// What every pass of one bounce reads besides the workspace: the prepared
/// scene, the sampler and the bounce's depth (the rays each path traced
/// before it; 0: camera rays).
#[derive(Clone, Copy)]
pub(super) struct Bounce<'a, S> {
    pub(super) prep: &'a Prepared,
    pub(super) sampler: S,
    pub(super) depth: u32,
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
/// The kernel is instantiated twice: for a scene on the general path
/// (`Shapes::general`: moving spheres, each path carrying a time, or
/// instanced meshes, whose hits are decoded lane by lane) and for one
/// without (`M = false`), which compiles to the bounce it ran before motion
/// blur existed; the choice is made here, once per tile.
pub fn render_tile<W: Wide, P: Probe, S: PathSampler>(
    prep: &Prepared,
    sampler: S,
    ws: &mut Workspace,
    tile: &mut TileFilm,
    samples: Range<u32>,
    probe: &mut P,
) -> u64 {
    if !prep.shapes.general() {
        render_tile_in::<W, P, S, false>(prep, sampler, ws, tile, samples, probe)
    } else {
        render_tile_in::<W, P, S, true>(prep, sampler, ws, tile, samples, probe)
    }
}

/// [`render_tile`] for a scene on the general path (`M`) or not.
pub(super) fn render_tile_in<W: Wide, P: Probe, S: PathSampler, const M: bool>(
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
pub(super) fn render_round<W: Wide, P: Probe, S: PathSampler, const M: bool>(
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
        if P::PATHS && probe.paths() {
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
pub(super) fn generate<W: Wide, P: Probe, S: PathSampler, const M: bool>(
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
        if M && !prep.shapes.moving.is_empty() {
            // The path's time, after its camera ray, as the scalar kernel draws it.
            rng.seek(layout::TIME);
            let time: W = rng.next();
            time.store_pow2(&mut ws.cur.time, i);
        }
        let o = if P::PATHS && probe.paths() {
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

/// One bounce of every live path: intersect and shade misses, classify, scatter.
/// `depth` counts the rays each path has traced before this bounce (0: camera
/// rays). Returns the rays traced. (Inlined, as the compiler chose to before
/// the light pass made it larger.)
#[cfg_attr(not(feature = "phases"), inline(always))]
pub(super) fn bounce<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    prep: &Prepared,
    sampler: S,
    ws: &mut Workspace,
    depth: u32,
    probe: &mut P,
) -> u64 {
    let b = Bounce { prep, sampler, depth };
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
    let mut q =
        Queues { q: ws.queue.take().expect("the queues are put back after every bounce"), len: [0; MISS_QUEUE + 1] };
    ws.next.len = 0;
    // A scene without moving spheres, instances or media (on the general
    // path, one of triangles alone) classifies W paths at a time
    // (`classify_packets`); the others one path at a time.
    if (!M || prep.shapes.only_triangles()) && prep.media.is_empty() {
        classify_bounce::<W, P, S, M>(b, ws, n, &mut q, probe);
    } else {
        classify_paths::<M>(prep, ws, n, &mut q);
    }
    material_passes::<W, P, S, M>(b, ws, &q, probe);
    ws.queue = Some(q.q);
    if nee && ws.shadows.len > 0 {
        shadow_pass::<W, P, M>(prep, ws, probe);
    }
    std::mem::swap(&mut ws.cur, &mut ws.next);
    n as u64
}

/// The bounce's queues: one per material kind, and the misses'; the paths
/// (their indices in the bounce's arrays) each holds, and how many.
pub(super) struct Queues {
    pub(super) q: [Arr<u32>; MISS_QUEUE + 1],
    pub(super) len: [usize; MISS_QUEUE + 1],
}

/// Classification W paths at a time (a scene without moving spheres or
/// media): the packet's material kinds (one lookup per lane, in the
/// spheres' or the quads' table); a packet whose hits share a kind that has
/// a plain scatter pass is scattered where it is; the others' lanes are
/// compressed onto their kinds' queues, in path order as one path at a time
/// would append them. Misses (shaded before) join no queue.
#[inline(always)]
fn classify_bounce<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    b: Bounce<S>,
    ws: &mut Workspace,
    n: usize,
    q: &mut Queues,
    probe: &mut P,
) {
    let prep = b.prep;
    debug_assert!(prep.shapes.spheres.kind.len().is_power_of_two() && prep.shapes.quads.kind.len().is_power_of_two());
    // The path tracer queues only the kinds it has passes for (the plan's);
    // the debug modes shade every kind.
    let path = prep.plan.mode == Mode::Path;
    let kinds = if path { prep.plan.kinds } else { KindSet::all() };
    // The kinds whose pass is `scatter` alone: not lights, not a
    // lambertian whose texture passes must run first.
    let in_place = Kind::SURFACES.map(|k| {
        path && prep.plan.directions() == Directions::Bsdf
            && prep.plan.kinds.contains(k)
            && match k {
                Kind::Lambertian => prep.plan.textures.is_empty(),
                Kind::Metal | Kind::Dielectric => true,
                Kind::DiffuseLight | Kind::Isotropic => false,
            }
    });
    let classes = Classes { kinds, in_place };
    // Compiled apart for a scene with quads: a sphere-only scene's
    // packets read one kind table, with no test per lane.
    let placed = if prep.shapes.quads.is_empty() {
        classify_packets::<W, P, S, M, false>(b, ws, n, classes, q, probe)
    } else {
        classify_packets::<W, P, S, M, true>(b, ws, n, classes, q, probe)
    };
    debug_assert!(
        ws.hit[..n].iter().filter(|&&h| h != MISS).count() == q.len.iter().sum::<usize>() + placed,
        "the plan left out a kind that was hit"
    );
}

/// Classification one path at a time (scenes with moving spheres or
/// media): each hit onto its material kind's queue (a medium's onto the
/// isotropic one), in path order; misses onto theirs.
#[inline(always)]
fn classify_paths<const M: bool>(prep: &Prepared, ws: &Workspace, n: usize, q: &mut Queues) {
    // The sphere and quad arrays have a power-of-two length above every hit
    // index (`Spheres::pad`, `Quads::pad`).
    let kind_mask = prep.shapes.spheres.kind.len().wrapping_sub(1);
    let quad_mask = prep.shapes.quads.kind.len().wrapping_sub(1);
    let moving_mask = prep.shapes.moving.s.kind.len().wrapping_sub(1);
    for (i, &h) in ws.hit[..n].iter().enumerate() {
        // Hit indices in order: spheres, quads, moving spheres, instanced
        // triangles, media, MISS (two tests for a sphere or a quad, as
        // before media existed; moving spheres only in a scene that has
        // them).
        let k = if h < QUAD_BASE {
            prep.shapes.spheres.kind[h as usize & kind_mask] as usize
        } else if h < MEDIUM_BASE {
            if !M || h < TRIANGLE_BASE {
                prep.shapes.quads.kind[(h - QUAD_BASE) as usize & quad_mask] as usize
            } else if h < MOVING_BASE {
                prep.shapes.triangles.material_of((h - TRIANGLE_BASE) as usize).0 as usize
            } else if h < INSTANCE_BASE {
                prep.shapes.moving.s.kind[(h - MOVING_BASE) as usize & moving_mask] as usize
            } else {
                let is = &prep.shapes.instances;
                is.kind[is.of(h).0] as usize
            }
        } else if h == MISS {
            MISS_QUEUE
        } else {
            Kind::Isotropic as usize
        };
        q.q[k][q.len[k] & MASK] = i as u32;
        q.len[k] += 1;
    }
}

/// Each material kind's pass over its queue, as the plan and the mode say.
#[inline(always)]
fn material_passes<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    b: Bounce<S>,
    ws: &mut Workspace,
    queues: &Queues,
    probe: &mut P,
) {
    let prep = b.prep;
    let nee = prep.plan.nee > 0;
    for kind in Kind::ALL {
        let (q, qlen) = (&queues.q[kind as usize], queues.len[kind as usize]);
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
                isotropic_pass::<W, P, S, M>(b, ws, q, qlen, probe);
            }
            Mode::Path if kind == Kind::Lambertian && !prep.plan.textures.is_empty() => {
                textured_lambertian_pass::<W, P, S, M>(b, ws, q, qlen, probe);
            }
            // The book and nee-mis estimators' passes apart: the bsdf
            // estimator's are the ones it always ran (the same instructions
            // per ray).
            Mode::Path if prep.plan.kinds.contains(kind) && prep.plan.sample_toward > 0 => {
                for_packets::<W, P>(q, qlen, probe, |at, probe| {
                    scatter::<W, P, S, M>(b, ws, kind, at, false, Directions::Book, probe)
                });
            }
            Mode::Path if prep.plan.kinds.contains(kind) && nee => {
                for_packets::<W, P>(q, qlen, probe, |at, probe| {
                    scatter::<W, P, S, M>(b, ws, kind, at, false, Directions::Nee, probe)
                });
            }
            Mode::Path if prep.plan.kinds.contains(kind) => {
                for_packets::<W, P>(q, qlen, probe, |at, probe| {
                    scatter::<W, P, S, M>(b, ws, kind, at, false, Directions::Bsdf, probe)
                });
            }
            Mode::Path => debug_assert!(qlen == 0, "the plan left out a kind that was hit"),
            mode @ (Mode::Flat | Mode::Normals | Mode::Gradient) => {
                for_packets::<W, P>(q, qlen, probe, |at, probe| debug_shade::<W, P, M>(prep, ws, mode, at, probe));
            }
        }
    }
}
