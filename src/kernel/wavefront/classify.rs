//! Classification: each path that hit joins the queue of its hit's material
//! kind, or a packet of one kind is scattered where it is.

use super::*;

/// What the classification sorts by: the kinds that get a queue (the
/// plan's; every kind in the debug modes) and, by `Kind as usize`, the
/// surface kinds a packet of one kind is scattered in place for.
#[derive(Clone, Copy)]
pub(super) struct Classes {
    pub(super) kinds: KindSet,
    pub(super) in_place: [bool; Kind::SURFACES.len()],
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
pub(super) fn classify_packets<W: Wide, P: Probe, S: PathSampler, const M: bool, const Q: bool>(
    b: Bounce<S>,
    ws: &mut Workspace,
    n: usize,
    classes: Classes,
    q: &mut Queues,
    probe: &mut P,
) -> usize {
    let (prep, Classes { kinds, in_place }) = (b.prep, classes);
    let (queues, len) = (&mut q.q, &mut q.len);
    const SURF: usize = Kind::SURFACES.len();
    // The fewest hits a packet scattered in place has: its lanes' arithmetic
    // is a whole packet's whatever their number, so an emptier one costs
    // more than the queue it saves (measured: docs/history.md, the fifth round).
    let full_enough = W::LANES * 3 / 4;
    // `Q`: the scene has quads (a sphere-only scene reads one table; the
    // quads' may be empty).
    debug_assert_eq!(Q, !prep.shapes.quads.is_empty());
    let tables = KindTables::of(prep);
    let want: [bool; SURF] = Kind::SURFACES.map(|k| kinds.contains(k));
    let mut lens: [usize; SURF] = Kind::SURFACES.map(|k| len[k as usize]);
    let iota = W::u_from_fn(|k| k as u32);
    // In place: the bsdf estimator's passes only (book one's scenes, and
    // any other scene this classification serves, rendered with it); under
    // the book and nee-mis estimators every packet is queued, as before.
    debug_assert!(prep.plan.directions() == Directions::Bsdf || !in_place.contains(&true));
    let mut placed = 0;
    for i in (0..n).step_by(W::LANES) {
        let hit = W::load_u_pow2(&ws.hit, i);
        let hits = W::mask_bits(W::u_lt(hit, W::u_splat(MISS))) & low_bits(n - i);
        let kind = tables.kinds::<W, Q, M>(hit);
        if hits != 0 {
            let first = W::lane_u(kind, hits.trailing_zeros() as usize & (W::LANES - 1));
            let same = W::mask_bits(W::u_eq(kind, W::u_splat(first))) & hits;
            if same == hits && hits.count_ones() as usize >= full_enough && in_place[first as usize & (SURF - 1)] {
                probe.lanes(Stage::Scatter, hits.count_ones(), W::LANES as u32);
                if cfg!(debug_assertions) {
                    placed += hits.count_ones() as usize;
                }
                scatter_in_place::<W, P, S, M>(b, ws, first, Run { i, live: hits }, probe);
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

/// The material kind tables of the spheres and the quads, each a power of
/// two long above every index it is read at (`Spheres::pad`, `Quads::pad`),
/// and the triangles' (by mesh).
struct KindTables<'a> {
    spheres: &'a [Kind],
    quads: &'a [Kind],
    triangles: &'a Triangles,
    /// The scene has quads and no static sphere.
    only_quads: bool,
}

impl<'a> KindTables<'a> {
    fn of(prep: &'a Prepared) -> Self {
        let (spheres, quads) = (&prep.shapes.spheres.kind[..], &prep.shapes.quads.kind[..]);
        debug_assert!(quads.len() as u32 <= QUAD_BASE);
        KindTables { spheres, quads, triangles: &prep.shapes.triangles, only_quads: prep.shapes.spheres.is_empty() }
    }

    /// The material kind of each lane's hit (misses read some kind; their
    /// lanes are not hits). `Q`: the scene has quads; `M`: the scene is on
    /// the general path, which classifies packets only when its primitives
    /// are all triangles (`Shapes::only_triangles`).
    #[inline(always)]
    fn kinds<W: Wide, const Q: bool, const M: bool>(&self, hit: W::U32) -> W::U32 {
        let (kind_mask, quad_mask) = (self.spheres.len().wrapping_sub(1), self.quads.len().wrapping_sub(1));
        if Q && self.only_quads {
            // Every hit is a quad's: its index masked into the quads' table
            // (`QUAD_BASE` is above the mask), without the test per lane.
            W::u_from_fn(|k| self.quads[W::lane_u(hit, k) as usize & quad_mask] as u32)
        } else if Q {
            // Misses (MISS is above every quad's index) read some quad's kind.
            W::u_from_fn(|k| {
                let h = W::lane_u(hit, k);
                if h < QUAD_BASE {
                    self.spheres[h as usize & kind_mask] as u32
                } else {
                    self.quads[(h - QUAD_BASE) as usize & quad_mask] as u32
                }
            })
        } else if M {
            // Every hit is a triangle's (misses read some triangle's kind).
            W::u_from_fn(|k| self.triangles.kind_of_hit(W::lane_u(hit, k)) as u32)
        } else {
            W::u_from_fn(|k| self.spheres[W::lane_u(hit, k) as usize & kind_mask] as u32)
        }
    }
}

/// A packet whose hits all share surface kind `kind` (as `Kind as u32`),
/// scattered where it is by the bsdf estimator's pass. The kind a literal
/// in each arm: each scatter is compiled for its kind.
#[inline(always)]
fn scatter_in_place<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    b: Bounce<S>,
    ws: &mut Workspace,
    kind: u32,
    run: Run,
    probe: &mut P,
) {
    const LAMBERTIAN: u32 = Kind::Lambertian as u32;
    const METAL: u32 = Kind::Metal as u32;
    let bsdf = Directions::Bsdf;
    match kind {
        LAMBERTIAN => scatter::<W, P, S, M>(b, ws, Kind::Lambertian, run, false, bsdf, probe),
        METAL => scatter::<W, P, S, M>(b, ws, Kind::Metal, run, false, bsdf, probe),
        _ => {
            debug_assert_eq!(kind, Kind::Dielectric as u32);
            scatter::<W, P, S, M>(b, ws, Kind::Dielectric, run, false, bsdf, probe)
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
    mis_bsdf(at.f(&ws.cur.pdf), e.pdf_of(o, d, shape, hit))
}
