//! Scattering: a material pass's new directions, shadow rays and the
//! compaction of the surviving paths into the next bounce.

use super::*;

/// Scatters a packet of paths that hit material `kind`; survivors join the next bounce.
#[cfg_attr(not(feature = "phases"), inline(always))]
#[cfg_attr(feature = "phases", inline(never))]
pub(super) fn scatter<W: Wide, P: Probe, S: PathSampler, const M: bool>(
    b: Bounce<S>,
    ws: &mut Workspace,
    kind: Kind,
    at: impl Packet<W>,
    textured: bool,
    dirs: Directions,
    probe: &mut P,
) {
    let Bounce { prep, sampler, depth } = b;
    // `dirs`: the plan's estimator (its sampler layout, its mixture or its
    // light sample at lambertian vertices); a literal at the call, so each
    // is compiled apart.
    debug_assert_eq!(dirs == Directions::Book, prep.plan.sample_toward > 0);
    debug_assert_eq!(dirs == Directions::Nee, prep.plan.nee > 0);
    let dims = if dirs == Directions::Bsdf { Bounces::BSDF } else { prep.bounces };
    let Hits { d, srf, albedo, param } = surfaces::<W, P, M>(prep, ws, at, probe);
    // A textured lambertian's record has parameter 1: its albedo is the one
    // its texture pass wrote.
    let albedo = if textured { V3::select(param.gt(W::splat(0.0)), at.v3(&ws.albedo), albedo) } else { albedo };
    let cur = &ws.cur;
    let mut rng = cur.rng::<W, S>(sampler, at);
    rng.seek(dims.scatter(depth));
    let all = W::mask_from_bits(u32::MAX);
    let thr = at.v3(&ws.cur.thr);
    // With smooth shading (`n`, the shading normal), what leaves under the
    // geometric surface (`srf.n`) ends there (`geometry::smooth`), as in the
    // scalar kernel.
    let smooth = !prep.shapes.smooth.is_empty();
    let n = if smooth { smooth_normals::<W>(prep, ws, at, &srf) } else { srf.n };
    let (dir, alive, albedo) = match kind {
        Kind::Lambertian => {
            let dir = lambertian(n, &mut rng);
            let toward = Toward { lights: &prep.lights, emitters: &prep.emitters, dim: dims.light(depth) };
            let send = depth + 1 < prep.settings.max_depth;
            let vx = dirs.at(toward, srf.p, dir, |d| cosine_pdf(n, d), send, &mut rng);
            if let Some((ld, t, carry)) = vx.light {
                let carry = if smooth { V3::select(below(srf.n, ld), V3::splat3([0.0; 3]), carry) } else { carry };
                let c = thr.mul_elem(albedo.mul_elem(carry));
                let shadow = Shadow { o: spawn(&srf, ld), d: ld, tmax: shadow_tmax(t, srf.offset), c };
                queue_shadow::<W, M>(ws, at, shadow);
            }
            let atten = albedo * vx.weight;
            let atten = if smooth { V3::select(below(srf.n, vx.dir), V3::splat3([0.0; 3]), atten) } else { atten };
            (vx.dir, all, atten)
        }
        Kind::Metal => {
            let (dir, alive) = metal(d, n, param, &mut rng);
            let alive = if smooth { alive & !below(srf.n, dir) } else { alive };
            (dir, alive, albedo)
        }
        Kind::Dielectric => (dielectric(d, n, srf.front, param, &mut rng), all, albedo),
        // Lights and media have their own passes (`bounce`).
        Kind::DiffuseLight | Kind::Isotropic => (d, !all, albedo),
    };
    // The albedo of a dielectric's record is white, as the scalar kernel's [1; 3].
    let thr = thr.mul_elem(albedo);
    // Under nee-mis, the density of the direction, for the weight of a light
    // it reaches: the cosine lobe's, 0 for a specular bounce.
    let pdf =
        (dirs == Directions::Nee).then(|| if kind == Kind::Lambertian { cosine_pdf(n, dir) } else { W::splat(0.0) });
    let next = Scattered { thr, alive, o: spawn(&srf, dir), dir, pdf };
    continue_paths::<W, S, M>(prep, ws, at, depth, dims, rng, next);
}

/// The shading normals of a packet's surfaces `srf` in a scene with smooth
/// meshes ([`shading_normal`]; out of line: only such scenes call it).
#[inline(never)]
pub(super) fn smooth_normals<W: Wide>(prep: &Prepared, ws: &Workspace, at: impl Packet<W>, srf: &Surface<W>) -> V3<W> {
    let hit = at.u(&ws.hit);
    shading_normal(&prep.shapes.smooth, |k| W::lane_u(hit, k), srf)
}

/// A packet's scattered paths: their throughput after the vertex, which
/// lanes live on, their new rays from `o` along `dir`, and (under `nee-mis`)
/// the directions' densities.
pub(super) struct Scattered<W: Wide> {
    pub(super) thr: V3<W>,
    pub(super) alive: <W as crate::real::Real>::Mask,
    pub(super) o: V3<W>,
    pub(super) dir: V3<W>,
    pub(super) pdf: Option<W>,
}

/// A packet's light samples (`nee-mis`): shadow rays from `o` along `d` to
/// `tmax`, each carrying `c` to its path's result if nothing blocks it.
#[derive(Clone, Copy)]
pub(super) struct Shadow<W: Wide> {
    pub(super) o: V3<W>,
    pub(super) d: V3<W>,
    pub(super) tmax: W,
    pub(super) c: V3<W>,
}

/// Appends the real lanes of a packet's light samples that carry anything
/// to the shadow queue, as the scalar kernel traces exactly those.
#[inline(always)]
pub(super) fn queue_shadow<W: Wide, const M: bool>(ws: &mut Workspace, at: impl Packet<W>, sh: Shadow<W>) {
    let zero = W::splat(0.0);
    let carries = sh.c.x.gt(zero) | sh.c.y.gt(zero) | sh.c.z.gt(zero);
    let keep = W::mask_bits(carries) & at.live();
    if keep == 0 {
        return;
    }
    let slot = at.u(&ws.cur.slot);
    let time = if M { Some(at.f(&ws.cur.time)) } else { None };
    ws.shadows.append::<W>(keep, &sh, slot, time);
}

/// The end of every scatter pass: paths whose throughput is zero die, then
/// Russian roulette (every lane draws, as the scalar path does when it gets
/// here; lanes already dead draw too, but their streams are never used
/// again), and the survivors' rays from `o` along `dir` join the next
/// bounce with their slots and, in a scene that moves, their paths' times.
#[inline(always)]
pub(super) fn continue_paths<W: Wide, S: PathSampler, const M: bool>(
    prep: &Prepared,
    ws: &mut Workspace,
    at: impl Packet<W>,
    depth: u32,
    dims: Bounces,
    mut rng: S::Lanes<W>,
    next: Scattered<W>,
) {
    let Scattered { thr, alive, o, dir, pdf } = next;
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
    let rng = S::lane_words::<W>(&rng);
    ws.next.append::<W, S>(alive, NewPaths { o, d: dir, thr, rng, slot, time, pdf });
}
