//! The passes over queues and runs: shadow rays, intersection, media,
//! isotropic scattering, misses, textures, and the result writes.

use super::*;

/// The shadow rays of the bounce (`nee-mis`), W contiguous rays per packet:
/// any-hit queries ([`Prepared::occluded`]); what an unblocked one carries
/// (times the media's transmittance, in a scene with media) is added to its
/// path's result. Out of line: it runs once per bounce.
#[inline(never)]
pub(super) fn shadow_pass<W: Wide, P: Probe, const M: bool>(prep: &Prepared, ws: &mut Workspace, probe: &mut P) {
    let n = ws.shadows.len;
    for i in (0..n).step_by(W::LANES) {
        let sh = &ws.shadows;
        let live = low_bits((n - i).min(W::LANES));
        let (o, d) = (Paths::v3::<W>(&sh.o, i), Paths::v3::<W>(&sh.d, i));
        let tmax = W::load_pow2(&sh.tmax, i);
        let blocked =
            prep.shapes.occluded::<W, P, M>(o, d, tmax, W::mask_from_bits(live), || W::load_pow2(&sh.time, i), probe);
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
pub(super) fn intersect<W: Wide, P: Probe, const M: bool>(
    prep: &Prepared,
    ws: &mut Workspace,
    n: usize,
    probe: &mut P,
) {
    for i in (0..n).step_by(W::LANES) {
        let live = (n - i).min(W::LANES);
        let (o, d) = (Paths::v3::<W>(&ws.cur.o, i), Paths::v3::<W>(&ws.cur.d, i));
        let time = &ws.cur.time;
        let live_mask = W::mask_from_bits(low_bits(live));
        let best = prep.shapes.closest::<W, P, M>(o, d, live_mask, || W::load_pow2(time, i), probe);
        let (hit, t) = (best.index, best.t);
        W::store_u_pow2(hit, &mut ws.hit, i);
        t.store_pow2(&mut ws.t, i);
        probe.lanes(Stage::Intersect, live as u32, W::LANES as u32);
        if P::PATHS && probe.paths() {
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
pub(super) fn medium_pass<W: Wide, S: PathSampler>(
    prep: &Prepared,
    sampler: S,
    ws: &mut Workspace,
    n: usize,
    depth: u32,
) {
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
pub(super) fn isotropic_pass<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    b: Bounce<S>,
    ws: &mut Workspace,
    queue: &Arr<u32>,
    len: usize,
    probe: &mut P,
) {
    let Bounce { prep, sampler, depth } = b;
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
        let toward = Toward { lights: &prep.lights, emitters: &prep.emitters, dim: prep.bounces.light(depth) };
        let send = depth + 1 < prep.settings.max_depth;
        let vx = prep.plan.directions().at(toward, p, dir, |_| W::splat(ISOTROPIC_PDF), send, &mut rng);
        if let Some((ld, t, carry)) = vx.light {
            let c = thr.mul_elem(albedo.mul_elem(carry));
            queue_shadow::<W, M>(ws, at, Shadow { o: p, d: ld, tmax: shadow_tmax(t, W::splat(0.0)), c });
        }
        let (dir, albedo) = (vx.dir, albedo * vx.weight);
        let thr = thr.mul_elem(albedo);
        let all = W::mask_from_bits(u32::MAX);
        let pdf = nee.then(|| W::splat(ISOTROPIC_PDF));
        let next = Scattered { thr, alive: all, o: p, dir, pdf };
        continue_paths::<W, S, M>(prep, ws, at, depth, prep.bounces, rng, next);
    });
}

/// The misses of the first `n` paths end here, W contiguous paths at a time
/// in path order: their throughput and directions are loaded, not gathered
/// through a queue. (Out of line: it runs once per bounce, and inlined into
/// the wavefront's loop it costs the traversal's code registers.)
/// `ADD`: added to the result (`nee-mis`, whose light samples may have
/// added to it), else written.
#[inline(never)]
pub(super) fn shade_misses<W: Wide, const ADD: bool>(prep: &Prepared, ws: &mut Workspace, n: usize) {
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
pub(super) fn textured_lambertian_pass<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    b: Bounce<S>,
    ws: &mut Workspace,
    queue: &Arr<u32>,
    len: usize,
    probe: &mut P,
) {
    let prep = b.prep;
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
    let dirs = prep.plan.directions();
    for_packets::<W, P>(queue, len, probe, |at, probe| {
        scatter::<W, P, S, M>(b, ws, Kind::Lambertian, at, true, dirs, probe)
    });
}

/// The material row of the primitive of hit index `h` (not `MISS`, not
/// a medium's).
#[inline(always)]
pub(super) fn material_row<const M: bool>(prep: &Prepared, h: u32) -> usize {
    if h < QUAD_BASE {
        prep.shapes.spheres.row[h as usize] as usize
    } else if !M || h < TRIANGLE_BASE {
        prep.shapes.quads.row[(h - QUAD_BASE) as usize] as usize
    } else if h < MOVING_BASE {
        prep.shapes.triangles.material_of((h - TRIANGLE_BASE) as usize).1 as usize
    } else if h < INSTANCE_BASE {
        prep.shapes.moving.s.row[(h - MOVING_BASE) as usize] as usize
    } else {
        let is = &prep.shapes.instances;
        is.row[is.of(h).0] as usize
    }
}

#[inline(always)]
pub(super) fn write_results<W: Wide, const ADD: bool>(ws: &mut Workspace, at: impl Packet<W>, c: V3<W>) {
    let slot = at.u(&ws.cur.slot);
    write_lanes::<W, ADD>(&mut ws.result, slot, at.live(), c);
}

/// `result[slot[k]] = c[k]` (`ADD`: `+= c[k]`) for the lanes k set in `lanes`.
#[inline(always)]
pub(super) fn write_lanes<W: Wide, const ADD: bool>(
    result: &mut Arr<[f32; 3]>,
    slot: W::U32,
    mut lanes: u32,
    c: V3<W>,
) {
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
