//! Classification: each path that hit joins the queue of its hit's material
//! kind, or a packet of one kind is scattered where it is.

use super::*;

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
pub(super) fn classify_packets<W: Wide, P: Probe, S: PathSampler, const M: bool, const Q: bool>(
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
    let kind_of = &prep.shapes.spheres.kind[..];
    let kind_mask = kind_of.len().wrapping_sub(1);
    // `Q`: the scene has quads (a sphere-only scene reads one table; the
    // quads' may be empty).
    debug_assert_eq!(Q, !prep.shapes.quads.is_empty());
    let quad_kind = &prep.shapes.quads.kind[..];
    let quad_mask = quad_kind.len().wrapping_sub(1);
    let only_quads = prep.shapes.spheres.is_empty();
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
pub(super) enum Dirs {
    /// The material's density (`bsdf`).
    Bsdf,
    /// The book's mixture.
    Book,
    /// The material's density, and a light sample on the shadow queue (`nee-mis`).
    Nee,
}

impl Dirs {
    /// The plan's.
    pub(super) fn of(prep: &Prepared) -> Self {
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
pub(super) fn light_weight<W: Wide, const M: bool>(prep: &Prepared, ws: &Workspace, at: Queued<W>) -> W {
    let hit = at.u(&ws.hit);
    let e = &prep.emitters;
    let shape = W::u_from_fn(|k| e.of_row[material_row::<M>(prep, W::lane_u(hit, k))]);
    let o = at.v3(&ws.cur.o);
    let d = at.v3(&ws.cur.d);
    mis_bsdf(at.f(&ws.cur.pdf), e.pdf_of(o, d, shape))
}
