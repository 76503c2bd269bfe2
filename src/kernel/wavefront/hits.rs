//! Surfaces: what a packet's hits are (position, normal, material record),
//! and the debug shadings.

use super::*;

/// A packet's hits: the rays' directions, the surfaces, and the hit
/// spheres' material parameters (albedo, and fuzz or index of refraction).
pub(super) struct Hits<W: Wide> {
    pub(super) d: V3<W>,
    pub(super) srf: Surface<W>,
    pub(super) albedo: V3<W>,
    pub(super) param: W,
}

/// The hit surfaces of a packet of queued paths. The hit primitives'
/// shading records ([`Shade`]) are loaded whole, one per lane, and
/// transposed. In a scene of several kinds a packet may hold them all: each
/// kind's records and surfaces are computed, and each lane keeps its own
/// (the same values the scalar kernel computes for its one kind).
#[inline(always)]
pub(super) fn surfaces<W: Wide, P: Probe, const M: bool>(
    prep: &Prepared,
    ws: &Workspace,
    at: impl Packet<W>,
    probe: &mut P,
) -> Hits<W> {
    let sph = at.u(&ws.hit);
    let sh = &prep.shapes;
    if !M && sh.quads.is_empty() {
        // Book one's surfaces, as they were. The index is masked into the
        // records' range: a no-op on a hit index, and a lane of a run that is
        // not live (a miss's index, or a stale one) reads some record.
        let rec = W::gather_rows8(
            &prep.shapes.spheres.shade,
            &W::idx_of(sph & W::u_splat(prep.shapes.spheres.shade.len() as u32 - 1)),
        );
        let c = V3::new(rec[Shade::CX], rec[Shade::CY], rec[Shade::CZ]);
        let r = rec[Shade::R];
        let d = at.v3(&ws.cur.d);
        let srf = surface(at.v3(&ws.cur.o), d, at.f(&ws.t), c, r);
        if P::PATHS && probe.paths() {
            probe.shaded(ws.ids::<W>(&at.idx()), sph, r, srf.n, srf.front, at.live());
        }
        let a = Shade::ALBEDO;
        return Hits { d, srf, albedo: V3::new(rec[a], rec[a + 1], rec[a + 2]), param: rec[Shade::PARAM] };
    }
    let d = at.v3(&ws.cur.d);
    let o = at.v3(&ws.cur.o);
    let t = at.f(&ws.t);
    let q_mask = W::u_splat(prep.shapes.quads.shade.len() as u32 - 1);
    if !M && sh.spheres.is_empty() {
        // A scene of quads alone (the Cornell boxes): every hit is a quad's,
        // so the sphere records and surfaces the mixed case computes and
        // then selects away are not computed (the same lanes, bit for bit).
        let rec = W::gather_rows8(&prep.shapes.quads.shade, &W::idx_of(sph & q_mask));
        let srf = quad_surface(o, d, t, V3::new(rec[0], rec[1], rec[2]), rec[3]);
        if P::PATHS && probe.paths() {
            probe.shaded(ws.ids::<W>(&at.idx()), sph, W::splat(0.0), srf.n, srf.front, at.live());
        }
        let a = Shade::ALBEDO;
        return Hits { d, srf, albedo: V3::new(rec[a], rec[a + 1], rec[a + 2]), param: rec[Shade::PARAM] };
    }
    if M && sh.only_triangles() {
        // A scene of triangles alone (`final-mesh`): every hit is one's.
        let rec = triangle_records::<W>(&sh.triangles, sph);
        let srf = quad_surface(o, d, t, V3::new(rec[0], rec[1], rec[2]), rec[3]);
        if P::PATHS && probe.paths() {
            probe.shaded(ws.ids::<W>(&at.idx()), sph, W::splat(0.0), srf.n, srf.front, at.live());
        }
        let a = Shade::ALBEDO;
        return Hits { d, srf, albedo: V3::new(rec[a], rec[a + 1], rec[a + 2]), param: rec[Shade::PARAM] };
    }
    let (srf, rec): (Surface<W>, [W; 8]) = {
        let is_sphere = W::u_lt(sph, W::u_splat(QUAD_BASE));
        let s_mask = W::u_splat(prep.shapes.spheres.shade.len() as u32 - 1);
        let srec = W::gather_rows8(&prep.shapes.spheres.shade, &W::idx_of(sph & s_mask));
        let qrec = W::gather_rows8(&prep.shapes.quads.shade, &W::idx_of(sph & q_mask));
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
        let rec = std::array::from_fn(|k| W::select(is_sphere, srec[k], qrec[k]));
        let (srf, rec) =
            if M && sh.has_meshes() { mesh_surfaces::<W>(prep, o, d, t, sph, srf, rec) } else { (srf, rec) };
        if P::PATHS && probe.paths() {
            probe.shaded(ws.ids::<W>(&at.idx()), sph, r, srf.n, srf.front, at.live());
        }
        (srf, rec)
    };
    let a = Shade::ALBEDO;
    Hits { d, srf, albedo: V3::new(rec[a], rec[a + 1], rec[a + 2]), param: rec[Shade::PARAM] }
}

/// A packet's sphere records where some lanes may have hit a moving sphere:
/// in those lanes the moving sphere's record with its centre at the path's
/// time ([`centre_at`], the scalar kernel's formula), and the lanes counted
/// as spheres.
#[inline(never)]
pub(super) fn moving_records<W: Wide>(
    prep: &Prepared,
    time: W,
    hit: W::U32,
    is_sphere: W,
    srec: [W; 8],
) -> (W, [W; 8]) {
    let m = &prep.shapes.moving;
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

/// A packet's surfaces and records where some lanes may have hit a mesh's
/// triangle, in world space or instanced.
#[inline(never)]
fn mesh_surfaces<W: Wide>(
    prep: &Prepared,
    o: V3<W>,
    d: V3<W>,
    t: W,
    hit: W::U32,
    srf: Surface<W>,
    rec: [W; 8],
) -> (Surface<W>, [W; 8]) {
    let (srf, rec) = if prep.shapes.triangles.is_empty() {
        (srf, rec)
    } else {
        triangle_surfaces::<W>(prep, o, d, t, hit, srf, rec)
    };
    match prep.shapes.instances.is_empty() {
        true => (srf, rec),
        false => instance_surfaces::<W>(prep, o, d, t, hit, srf, rec),
    }
}

/// A packet's surfaces and records where some lanes may have hit a
/// triangle of the scene's meshes: in those lanes the quads' surface on the
/// triangle's plane and the shading record of its plane and its mesh's
/// material ([`triangle_records`]).
#[inline(always)]
fn triangle_surfaces<W: Wide>(
    prep: &Prepared,
    o: V3<W>,
    d: V3<W>,
    t: W,
    hit: W::U32,
    srf: Surface<W>,
    rec: [W; 8],
) -> (Surface<W>, [W; 8]) {
    let trec = triangle_records::<W>(&prep.shapes.triangles, hit);
    let on = !W::u_lt(hit, W::u_splat(TRIANGLE_BASE)) & W::u_lt(hit, W::u_splat(MOVING_BASE));
    let t_srf = quad_surface(o, d, t, V3::new(trec[0], trec[1], trec[2]), trec[3]);
    let surface = Surface {
        p: V3::select(on, t_srf.p, srf.p),
        n: V3::select(on, t_srf.n, srf.n),
        front: W::select(on, t_srf.front, srf.front),
        offset: W::select(on, t_srf.offset, srf.offset),
    };
    (surface, std::array::from_fn(|k| W::select(on, trec[k], rec[k])))
}

/// The shading records of the triangles of hit indices `hit`, one row a
/// lane ([`crate::geometry::Triangles::shade_of`]), transposed.
#[inline(always)]
fn triangle_records<W: Wide>(tr: &crate::geometry::Triangles, hit: W::U32) -> [W; 8] {
    let mut rows = [Shade::default(); MAX_LANES];
    for (k, row) in rows.iter_mut().enumerate().take(W::LANES) {
        row.0 = tr.shade_of(W::lane_u(hit, k));
    }
    W::gather_rows8(&rows[..W::LANES], &index_run::<W>(0))
}

/// A packet's surfaces and records where some lanes may have hit an
/// instanced mesh: in those lanes the instanced triangle's surface and its
/// instance's material (`Instances::surface`, the scalar kernel's
/// function, lane by lane: the same bits).
#[inline(always)]
fn instance_surfaces<W: Wide>(
    prep: &Prepared,
    o: V3<W>,
    d: V3<W>,
    t: W,
    hit: W::U32,
    srf: Surface<W>,
    rec: [W; 8],
) -> (Surface<W>, [W; 8]) {
    let is = &prep.shapes.instances;
    let mut lanes = 0u32;
    let mut s = [[0.0f32; 8]; MAX_LANES];
    let mut m = [[0.0f32; 4]; MAX_LANES];
    for k in 0..W::LANES {
        let h = W::lane_u(hit, k);
        if (INSTANCE_BASE..MEDIUM_BASE).contains(&h) {
            let (f, i) = is.surface(o.lane(k), d.lane(k), t.lane(k), h);
            let front = if f.front { 1.0 } else { 0.0 };
            s[k] = [f.p.x, f.p.y, f.p.z, f.n.x, f.n.y, f.n.z, front, f.offset];
            m[k] = is.material[i];
            lanes |= 1 << k;
        }
    }
    if lanes == 0 {
        return (srf, rec);
    }
    let on = W::mask_from_bits(lanes);
    let c = |j: usize| W::from_fn(|k| s[k][j]);
    let surface = Surface {
        p: V3::select(on, V3::new(c(0), c(1), c(2)), srf.p),
        n: V3::select(on, V3::new(c(3), c(4), c(5)), srf.n),
        front: W::select(on, c(6).gt(W::splat(0.5)), srf.front),
        offset: W::select(on, c(7), srf.offset),
    };
    let rec = std::array::from_fn(|j| if j < 4 { rec[j] } else { W::select(on, W::from_fn(|k| m[k][j - 4]), rec[j]) });
    (surface, rec)
}

pub(super) fn debug_shade<W: Wide, P: Probe, const M: bool>(
    prep: &Prepared,
    ws: &mut Workspace,
    mode: Mode,
    at: Queued<W>,
    probe: &mut P,
) {
    let hits = surfaces::<W, P, M>(prep, ws, at, probe);
    let c = match mode {
        Mode::Normals if !prep.shapes.smooth.is_empty() => {
            normal_colour(super::scatter::smooth_normals::<W>(prep, ws, at, &hits.srf))
        }
        Mode::Normals => normal_colour(hits.srf.n),
        // The flat colour (`MaterialTables::flat_colour`): the albedo, white for glass.
        Mode::Flat | Mode::Gradient | Mode::Path => hits.albedo,
    };
    write_results::<W, false>(ws, at, c);
}
