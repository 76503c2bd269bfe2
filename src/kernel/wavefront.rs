//! The SIMD wavefront path tracer.
//!
//! A tile's paths for a batch of samples are generated together, then advanced
//! one bounce at a time, all in structure-of-arrays:
//!
//! ```text
//! generate camera rays (8 at a time)
//! loop until no path is alive or max_depth rays were traced:
//!     intersect: 8 contiguous rays per packet, every sphere broadcast against them
//!     classify:  each path joins the queue of its hit's material kind, or the miss queue
//!     miss pass: throughput x sky -> the path's result
//!     one scatter pass per material kind the scene uses (8 paths at a time, gathered)
//!     compaction: survivors are appended to the next bounce's arrays
//! add results to the film in sample order
//! ```
//!
//! Lane k of every packet computes exactly what the scalar kernel computes for
//! that path: the formulas are the width-generic ones, the random stream is the
//! same xoshiro128+ run lane-wise, and the closest-hit tie rule is the same.
//! Memory is bounded: a workspace holds `tile pixels x batch samples` paths.

use super::{normal_colour, sky, Counters};
use crate::estimator::{roulette, roulette_applies};
use crate::film::TileFilm;
use crate::geometry::{spawn, surface, Surface, MISS};
use crate::material::{dielectric, lambertian, metal};
use crate::plan::Prepared;
use crate::real::Real;
use crate::sampling::{path_state, Xoshiro128PlusX8};
use crate::scene::{Kind, Mode};
use crate::vec3::V3;
use wide::{f32x8, u32x8};

/// Paths in flight per workspace (per thread), at most.
pub const MAX_PATHS: usize = 2048;

const MISS_QUEUE: usize = 3;

/// Path state, structure of arrays. Arrays have 8 lanes of slack so the last
/// packet can always be loaded whole (its extra lanes are computed, never stored).
#[derive(Default)]
struct Paths {
    o: [Vec<f32>; 3],
    d: [Vec<f32>; 3],
    thr: [Vec<f32>; 3],
    rng: [Vec<u32>; 4],
    /// Index of the path's result: `sample_in_batch * tile_pixels + pixel_in_tile`.
    slot: Vec<u32>,
    len: usize,
}

impl Paths {
    fn with_capacity(cap: usize) -> Self {
        let f = || vec![0.0f32; cap + 8];
        let u = || vec![0u32; cap + 8];
        Paths {
            o: [f(), f(), f()],
            d: [f(), f(), f()],
            thr: [f(), f(), f()],
            rng: [u(), u(), u(), u()],
            slot: u(),
            len: 0,
        }
    }

    /// Appends the lanes of `alive` (a bitmask) of 8 paths: SIMD stream
    /// compaction, the live lanes permuted to the front and stored as whole
    /// vectors (the arrays' 8 lanes of slack take the rest).
    #[inline(always)]
    fn append(&mut self, alive: u32, o: V3<f32x8>, d: V3<f32x8>, thr: V3<f32x8>, rng: &Xoshiro128PlusX8, slot: u32x8) {
        let perm = u32x8::new(COMPRESS[alive as usize]);
        let at = self.len;
        let put = |v: &mut Vec<f32>, x: f32x8| {
            let packed: u32x8 = bytemuck::cast::<f32x8, u32x8>(x).shuffle(perm);
            v[at..at + 8].copy_from_slice(&bytemuck::cast::<u32x8, [f32; 8]>(packed));
        };
        for (a, (ov, dv, tv)) in [(o.x, d.x, thr.x), (o.y, d.y, thr.y), (o.z, d.z, thr.z)].into_iter().enumerate() {
            put(&mut self.o[a], ov);
            put(&mut self.d[a], dv);
            put(&mut self.thr[a], tv);
        }
        let put_u = |v: &mut Vec<u32>, x: u32x8| v[at..at + 8].copy_from_slice(&x.shuffle(perm).to_array());
        for w in 0..4 {
            put_u(&mut self.rng[w], rng.s[w]);
        }
        put_u(&mut self.slot, slot);
        self.len = at + alive.count_ones() as usize;
    }
}

/// For each 8-bit lane mask, the indices of its set lanes first (stream compaction).
static COMPRESS: [[u32; 8]; 256] = compress_table();

const fn compress_table() -> [[u32; 8]; 256] {
    let mut t = [[0u32; 8]; 256];
    let mut m = 0;
    while m < 256 {
        let (mut k, mut n) = (0, 0);
        while k < 8 {
            if m & (1 << k) != 0 {
                t[m][n] = k as u32;
                n += 1;
            }
            k += 1;
        }
        m += 1;
    }
    t
}

#[inline(always)]
fn load(v: &[f32], i: usize) -> f32x8 {
    f32x8::new(v[i..i + 8].try_into().unwrap())
}

#[inline(always)]
fn load_u(v: &[u32], i: usize) -> u32x8 {
    u32x8::new(v[i..i + 8].try_into().unwrap())
}

#[inline(always)]
fn store(v: &mut [f32], i: usize, x: f32x8) {
    v[i..i + 8].copy_from_slice(&x.to_array());
}

#[inline(always)]
fn gather(v: &[f32], idx: &[u32; 8]) -> f32x8 {
    f32x8::new(std::array::from_fn(|k| v[idx[k] as usize]))
}

#[inline(always)]
fn gather_u(v: &[u32], idx: &[u32; 8]) -> u32x8 {
    u32x8::new(std::array::from_fn(|k| v[idx[k] as usize]))
}

/// A mask with every lane on.
#[inline(always)]
fn all_lanes() -> f32x8 {
    bytemuck::cast(u32x8::splat(u32::MAX))
}

#[inline(always)]
fn v3_gather(v: &[Vec<f32>; 3], idx: &[u32; 8]) -> V3<f32x8> {
    V3::new(gather(&v[0], idx), gather(&v[1], idx), gather(&v[2], idx))
}

#[inline(always)]
fn lanes(v: V3<f32x8>) -> [[f32; 8]; 3] {
    [v.x.to_array(), v.y.to_array(), v.z.to_array()]
}

/// A thread's wavefront state, reused across tiles (no allocation per tile).
pub struct Workspace {
    cur: Paths,
    next: Paths,
    hit: Vec<u32>,
    t: Vec<f32>,
    /// Indices into `cur`, one queue per material kind (by `Kind as usize`) and one for
    /// misses, each `MAX_PATHS` long (filled from the front each bounce).
    queue: [Vec<u32>; 4],
    result: Vec<[f32; 3]>,
    /// The tile's pixels (row-major local indices) that still take samples.
    active: Vec<u32>,
}

impl Default for Workspace {
    fn default() -> Self {
        Workspace {
            cur: Paths::with_capacity(MAX_PATHS),
            next: Paths::with_capacity(MAX_PATHS),
            hit: vec![0; MAX_PATHS + 8],
            t: vec![0.0; MAX_PATHS + 8],
            queue: std::array::from_fn(|_| vec![0; MAX_PATHS]),
            result: vec![[0.0; 3]; MAX_PATHS],
            active: Vec::with_capacity(MAX_PATHS),
        }
    }
}

/// Renders every sample of every pixel of `tile` (at most `MAX_PATHS` pixels).
///
/// Samples are rendered in rounds that end at the adaptive decision points
/// (one round of `spp` samples without adaptive sampling). After each round,
/// pixels whose error estimate is low enough leave the active list; the next
/// round traces only the others, so fewer active pixels get more samples per
/// batch and the packets stay full.
pub fn render_tile(prep: &Prepared, ws: &mut Workspace, tile: &mut TileFilm, counters: &mut Counters) {
    let px = tile.sum.len();
    assert!(px <= MAX_PATHS, "tile of {px} pixels exceeds the wavefront's {MAX_PATHS} paths");
    let spp = prep.settings.spp;
    let est = &prep.estimator;
    ws.active.clear();
    ws.active.extend(0..px as u32);
    let mut done = 0;
    while done < spp && !ws.active.is_empty() {
        let end = est.round_end(done, spp);
        render_round(prep, ws, tile, done as usize, end as usize, counters);
        done = end;
        if let (true, Some(a)) = (done < spp, est.adaptive) {
            ws.active.retain(|&l| !a.converged(tile, l as usize));
        }
    }
}

/// Samples `s0..s1` of every active pixel, in batches of at most `MAX_PATHS` paths.
fn render_round(prep: &Prepared, ws: &mut Workspace, tile: &mut TileFilm, s0: usize, s1: usize, c: &mut Counters) {
    let na = ws.active.len();
    let batch = (MAX_PATHS / na).max(1);
    let mut b0 = s0;
    while b0 < s1 {
        let b1 = (b0 + batch).min(s1);
        ws.result[..(b1 - b0) * na].fill([0.0; 3]);
        generate(prep, &mut ws.cur, &ws.active, tile, b0, b1);
        for depth in 0..prep.settings.max_depth {
            if ws.cur.len == 0 {
                break;
            }
            bounce(prep, ws, depth, c);
        }
        for s in 0..b1 - b0 {
            for (j, &local) in ws.active.iter().enumerate() {
                tile.add(local as usize, ws.result[s * na + j]);
            }
        }
        b0 = b1;
    }
}

/// Camera rays for samples `s0..s1` of every active pixel of the tile, 8 at a time.
/// Path `slot` is sample `s0 + slot / na` of active pixel `slot % na`.
fn generate(prep: &Prepared, p: &mut Paths, active: &[u32], tile: &TileFilm, s0: usize, s1: usize) {
    let st = &prep.settings;
    let na = active.len();
    let n = (s1 - s0) * na;
    // Pixel coordinates ride in the throughput arrays until the rays exist.
    for slot in 0..n {
        let (x, y) = tile.pixel_of(active[slot % na] as usize);
        let sample = (s0 + slot / na) as u64;
        let state = path_state(st.seed, y as u64 * st.width as u64 + x as u64, sample);
        for w in 0..4 {
            p.rng[w][slot] = state[w];
        }
        p.thr[0][slot] = x as f32;
        p.thr[1][slot] = y as f32;
        p.slot[slot] = slot as u32;
    }
    for i in (0..n).step_by(8) {
        let mut rng = Xoshiro128PlusX8 { s: std::array::from_fn(|w| load_u(&p.rng[w], i)) };
        let (o, d) = prep.camera.ray(load(&p.thr[0], i), load(&p.thr[1], i), &mut rng);
        for a in 0..3 {
            let (oa, da) = [(o.x, d.x), (o.y, d.y), (o.z, d.z)][a];
            store(&mut p.o[a], i, oa);
            store(&mut p.d[a], i, da);
            store(&mut p.thr[a], i, f32x8::splat(1.0));
        }
        for w in 0..4 {
            p.rng[w][i..i + 8].copy_from_slice(&rng.s[w].to_array());
        }
    }
    p.len = n;
}

/// One bounce of every live path: intersect, classify, shade misses, scatter.
/// `depth` counts the rays each path has traced before this bounce (0: camera rays).
fn bounce(prep: &Prepared, ws: &mut Workspace, depth: u32, counters: &mut Counters) {
    let n = ws.cur.len;
    counters.rays += n as u64;
    let cur = &ws.cur;
    for i in (0..n).step_by(8) {
        let live = (n - i).min(8);
        let o = [&cur.o[0][..], &cur.o[1][..], &cur.o[2][..]];
        let d = [&cur.d[0][..], &cur.d[1][..], &cur.d[2][..]];
        let (hit, t) = prep.closest_hits8(o, d, i, live);
        ws.hit[i..i + 8].copy_from_slice(&hit);
        ws.t[i..i + 8].copy_from_slice(&t);
        counters.isect_active += live as u64;
        counters.isect_lanes += 8;
    }
    let mut len = [0usize; 4];
    for (i, &h) in ws.hit[..n].iter().enumerate() {
        let q = if h == MISS { MISS_QUEUE } else { prep.spheres.kind[h as usize] as usize };
        ws.queue[q][len[q]] = i as u32;
        len[q] += 1;
    }
    let queues = std::mem::take(&mut ws.queue);
    ws.next.len = 0;
    for_packets(&queues[MISS_QUEUE][..len[MISS_QUEUE]], counters, |idx, active| {
        let c = v3_gather(&ws.cur.thr, idx).mul_elem(sky(&prep.sky, v3_gather(&ws.cur.d, idx)));
        write_results(ws, idx, active, c);
    });
    match prep.plan.mode {
        Mode::Path => {
            for kind in Kind::ALL {
                if prep.plan.uses(kind) {
                    let q = &queues[kind as usize][..len[kind as usize]];
                    for_packets(q, counters, |idx, active| scatter(prep, ws, kind, depth, idx, active));
                }
            }
        }
        mode => {
            for (q, &l) in queues[..MISS_QUEUE].iter().zip(&len) {
                for_packets(&q[..l], counters, |idx, active| debug_shade(prep, ws, mode, idx, active));
            }
        }
    }
    ws.queue = queues;
    std::mem::swap(&mut ws.cur, &mut ws.next);
}

/// Calls `f` with each packet of 8 indices of `queue` (the last one padded by
/// repeating its first index) and the number of real lanes.
#[inline(always)]
fn for_packets(queue: &[u32], counters: &mut Counters, mut f: impl FnMut(&[u32; 8], usize)) {
    for chunk in queue.chunks(8) {
        let idx: [u32; 8] = std::array::from_fn(|k| *chunk.get(k).unwrap_or(&chunk[0]));
        counters.scatter_active += chunk.len() as u64;
        counters.scatter_lanes += 8;
        f(&idx, chunk.len());
    }
}

#[inline(always)]
fn write_results(ws: &mut Workspace, idx: &[u32; 8], active: usize, c: V3<f32x8>) {
    let c = lanes(c);
    for k in 0..active {
        let slot = ws.cur.slot[idx[k] as usize] as usize;
        ws.result[slot] = [c[0][k], c[1][k], c[2][k]];
    }
}

/// The hit surfaces of 8 queued paths.
#[inline(always)]
fn surfaces(prep: &Prepared, ws: &Workspace, idx: &[u32; 8]) -> (V3<f32x8>, Surface<f32x8>, [u32; 8]) {
    let sp = &prep.spheres;
    let sph: [u32; 8] = std::array::from_fn(|k| ws.hit[idx[k] as usize]);
    let c = V3::new(gather(&sp.cx, &sph), gather(&sp.cy, &sph), gather(&sp.cz, &sph));
    let d = v3_gather(&ws.cur.d, idx);
    let srf = surface(v3_gather(&ws.cur.o, idx), d, gather(&ws.t, idx), c, gather(&sp.r, &sph));
    (d, srf, sph)
}

fn debug_shade(prep: &Prepared, ws: &mut Workspace, mode: Mode, idx: &[u32; 8], active: usize) {
    let (_, srf, sph) = surfaces(prep, ws, idx);
    let c = match mode {
        Mode::Normals => normal_colour(srf.n),
        _ => {
            let sp = &prep.spheres;
            let cols: [[f32; 3]; 8] =
                std::array::from_fn(|k| prep.materials.flat_colour(sp.kind[sph[k] as usize], sp.row[sph[k] as usize]));
            V3::new(f32x8::new(cols.map(|c| c[0])), f32x8::new(cols.map(|c| c[1])), f32x8::new(cols.map(|c| c[2])))
        }
    };
    write_results(ws, idx, active, c);
}

/// Scatters 8 paths that hit material `kind`; survivors join the next bounce.
#[inline(always)]
fn scatter(prep: &Prepared, ws: &mut Workspace, kind: Kind, depth: u32, idx: &[u32; 8], active: usize) {
    let (d, srf, sph) = surfaces(prep, ws, idx);
    let cur = &ws.cur;
    let mut rng = Xoshiro128PlusX8 { s: std::array::from_fn(|w| gather_u(&cur.rng[w], idx)) };
    let rows: [usize; 8] = std::array::from_fn(|k| prep.spheres.row[sph[k] as usize] as usize);
    let m = &prep.materials;
    let thr = v3_gather(&cur.thr, idx);
    let (dir, thr, alive) = match kind {
        Kind::Lambertian => {
            let albedo = rows.map(|r| m.lambertian[r]);
            let a = V3::new(
                f32x8::new(albedo.map(|c| c[0])),
                f32x8::new(albedo.map(|c| c[1])),
                f32x8::new(albedo.map(|c| c[2])),
            );
            (lambertian(srf.n, &mut rng), thr.mul_elem(a), all_lanes())
        }
        Kind::Metal => {
            let params = rows.map(|r| m.metal[r]);
            let a = V3::new(
                f32x8::new(params.map(|p| p.0[0])),
                f32x8::new(params.map(|p| p.0[1])),
                f32x8::new(params.map(|p| p.0[2])),
            );
            let (dir, ok) = metal(d, srf.n, f32x8::new(params.map(|p| p.1)), &mut rng);
            (dir, thr.mul_elem(a), ok)
        }
        Kind::Dielectric => {
            let ior = f32x8::new(rows.map(|r| m.dielectric[r]));
            let one = V3::splat3([1.0; 3]);
            (dielectric(d, srf.n, srf.front, ior, &mut rng), thr.mul_elem(one), all_lanes())
        }
    };
    let zero = f32x8::splat(0.0);
    let dark = thr.x.eq(zero) & thr.y.eq(zero) & thr.z.eq(zero);
    let mut alive = alive & !dark;
    let mut thr = thr;
    // Every lane draws, as the scalar path does when it gets here; lanes that
    // are already dead draw too, but their streams are never used again.
    if roulette_applies(&prep.estimator, depth + 1) {
        let (t, survives) = roulette(thr, &mut rng);
        thr = t;
        alive &= survives;
    }
    let alive = alive.to_bitmask() & ((1u32 << active) - 1);
    let slot = gather_u(&cur.slot, idx);
    ws.next.append(alive, spawn(&srf, dir), dir, thr, &rng, slot);
}
