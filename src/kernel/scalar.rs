//! The reference path tracer: one path at a time, iterative, straightforward.
//! Every formula comes from the width-generic modules, instantiated at `f32`.

use super::{background, normal_colour, texture_albedo};
use crate::choice::Mode;
use crate::estimator::{book_mixture, cosine_pdf, roulette, roulette_applies, ISOTROPIC_PDF};
use crate::film::TileFilm;
use crate::geometry::{quad_surface, sample_media, spawn, surface, Surface, MEDIUM_BASE, MISS, MOVING_BASE, QUAD_BASE};
use crate::material::{dielectric, emission, lambertian, metal, Kind};
use crate::plan::Prepared;
use crate::probe::{PathId, Probe};
use crate::sampling::{layout, unit_vector, PathSampler, Stream};
use crate::texture::TexKind;
use crate::vec3::V3;
use std::ops::Range;

/// Renders samples `samples` of every pixel of `tile`, in sample order, with
/// the paths' values drawn by `sampler`; returns the rays traced. With
/// adaptive sampling a pixel stops at the first decision point where its
/// error estimate is low enough.
/// Instantiated for a scene with moving spheres and for one without (see
/// `trace_in`), chosen once per tile.
pub fn render_tile<S: PathSampler, P: Probe>(
    prep: &Prepared,
    sampler: S,
    tile: &mut TileFilm,
    samples: Range<u32>,
    probe: &mut P,
) -> u64 {
    if prep.moving.is_empty() {
        render_tile_in::<S, P, false>(prep, sampler, tile, samples, probe)
    } else {
        render_tile_in::<S, P, true>(prep, sampler, tile, samples, probe)
    }
}

/// [`render_tile`] for a scene with moving spheres (`M`) or without.
#[cfg_attr(feature = "phases", inline(never))]
fn render_tile_in<S: PathSampler, P: Probe, const M: bool>(
    prep: &Prepared,
    sampler: S,
    tile: &mut TileFilm,
    samples: Range<u32>,
    probe: &mut P,
) -> u64 {
    let s = &prep.settings;
    let est = &prep.estimator;
    let mut rays = 0;
    for local in 0..tile.sum.len() {
        let (x, y) = tile.pixel_of(local);
        let pixel = y * s.width + x;
        let mut done = samples.start;
        while done < samples.end {
            let end = est.round_end(done, samples.end);
            for sample in done..end {
                let mut rng = sampler.scalar(s.seed, pixel as u64, sample);
                let (c, n) = trace_in::<P, M>(prep, x, y, PathId { pixel, sample }, &mut rng, probe);
                rays += n as u64;
                tile.add(local, c);
            }
            done = end;
            if done < samples.end && est.adaptive.is_some_and(|a| a.converged(tile, local)) {
                break;
            }
        }
    }
    rays
}

/// The camera ray through pixel (x, y) (out of line in `phases` builds, for profiles).
#[cfg_attr(not(feature = "phases"), inline(always))]
#[cfg_attr(feature = "phases", inline(never))]
fn camera_ray(prep: &Prepared, x: u32, y: u32, rng: &mut impl Stream<f32>) -> (V3<f32>, V3<f32>) {
    prep.camera.ray(x as f32, y as f32, rng)
}

/// The closest hit of one ray (out of line in `phases` builds).
#[cfg_attr(not(feature = "phases"), inline(always))]
#[cfg_attr(feature = "phases", inline(never))]
fn closest_hit<P: Probe, const M: bool>(
    prep: &Prepared,
    o: V3<f32>,
    d: V3<f32>,
    time: f32,
    probe: &mut P,
) -> (u32, f32) {
    prep.closest_hit::<P, M>(o, d, time, probe)
}

/// The scattered direction and attenuation of a path that hit material
/// (`kind`, `row`) at `srf`, or `None` when it is absorbed (out of line in
/// `phases` builds).
#[cfg_attr(not(feature = "phases"), inline(always))]
#[cfg_attr(feature = "phases", inline(never))]
#[allow(clippy::too_many_arguments)]
fn scatter(
    prep: &Prepared,
    hit: u32,
    kind: Kind,
    row: usize,
    d: V3<f32>,
    srf: &Surface<f32>,
    depth: u32,
    rng: &mut impl Stream<f32>,
) -> Option<(V3<f32>, [f32; 3])> {
    let m = &prep.materials;
    rng.seek(prep.bounces.scatter(depth));
    Some(match kind {
        Kind::Lambertian => {
            let tex = m.lambertian_tex[row];
            let albedo = match tex.kind {
                TexKind::Solid => m.lambertian[row],
                kind => texture_albedo(prep, kind, srf.p, |_| hit, |_| tex.row as usize).to_array(),
            };
            let dir = lambertian(srf.n, rng);
            if prep.plan.sample_toward == 0 {
                (dir, albedo)
            } else {
                let (dir, w) =
                    book_mixture(&prep.lights, srf.p, dir, |d| cosine_pdf(srf.n, d), prep.bounces.light(depth), rng);
                (dir, albedo.map(|a| a * w))
            }
        }
        Kind::Metal => {
            let (albedo, fuzz) = m.metal[row];
            let (dir, alive) = metal(d, srf.n, fuzz, rng);
            if !alive {
                return None;
            }
            (dir, albedo)
        }
        Kind::Dielectric => (dielectric(d, srf.n, srf.front, m.dielectric[row], rng), [1.0; 3]),
        // Lights end the path before scattering (`trace`); media scatter in `trace`.
        Kind::DiffuseLight | Kind::Isotropic => return None,
    })
}

/// The radiance of one path through pixel (x, y), and the rays it traced.
pub fn trace<P: Probe>(
    prep: &Prepared,
    x: u32,
    y: u32,
    id: PathId<f32>,
    rng: &mut impl Stream<f32>,
    probe: &mut P,
) -> ([f32; 3], u32) {
    if prep.moving.is_empty() {
        trace_in::<P, false>(prep, x, y, id, rng, probe)
    } else {
        trace_in::<P, true>(prep, x, y, id, rng, probe)
    }
}

/// [`trace`] for a scene with moving spheres (`M`: the path draws a time)
/// or without (`false` compiles to the path of a scene without).
fn trace_in<P: Probe, const M: bool>(
    prep: &Prepared,
    x: u32,
    y: u32,
    id: PathId<f32>,
    rng: &mut impl Stream<f32>,
    probe: &mut P,
) -> ([f32; 3], u32) {
    let (o, mut d) = camera_ray(prep, x, y, rng);
    let mut o = if P::PATHS { probe.camera(id, o, d, 1) } else { o };
    // The path's time (scenes with moving spheres only), inherited by every
    // ray it scatters.
    let time = if M {
        rng.seek(layout::TIME);
        rng.next()
    } else {
        0.0
    };
    let mut thr = V3::new(1.0f32, 1.0, 1.0);
    for depth in 0..prep.settings.max_depth {
        let rays = depth + 1;
        probe.rays(depth, 1);
        let (hit, t) = closest_hit::<P, M>(prep, o, d, time, probe);
        if P::PATHS {
            probe.traced(id, o, d, hit, t, 1);
        }
        // Scenes with media: the nearest of the surface and a free-flight sample per medium.
        let (hit, t) =
            if prep.media.is_empty() { (hit, t) } else { sample_media(&prep.media, o, d, hit, t, depth, rng) };
        if hit == MISS {
            return (thr.mul_elem(background(&prep.sky, d)).to_array(), rays);
        }
        let (next_o, dir, atten) = if hit >= MEDIUM_BASE {
            // Isotropic scattering inside medium k: a uniform direction.
            rng.seek(prep.bounces.scatter(depth));
            let dir = unit_vector(rng);
            let p = o + d * t;
            let albedo = prep.media.albedo[(hit - MEDIUM_BASE) as usize];
            if prep.plan.sample_toward == 0 {
                (p, dir, albedo)
            } else {
                let (dir, w) = book_mixture(&prep.lights, p, dir, |_| ISOTROPIC_PDF, prep.bounces.light(depth), rng);
                (p, dir, albedo.map(|a| a * w))
            }
        } else {
            let (dir, atten, srf) = match shade::<P, M>(prep, o, d, t, time, hit, id, depth, thr, rng, probe) {
                Ok(s) => s,
                Err(c) => return (c, rays),
            };
            (spawn(&srf, dir), dir, atten)
        };
        thr = thr.mul_elem(V3::from_array(atten));
        if thr.x == 0.0 && thr.y == 0.0 && thr.z == 0.0 {
            return ([0.0; 3], rays);
        }
        if roulette_applies(&prep.estimator, rays) {
            rng.seek(prep.bounces.roulette(depth));
            let (t, survives) = roulette(thr, rng);
            if !survives {
                return ([0.0; 3], rays);
            }
            thr = t;
        }
        o = next_o;
        d = dir;
    }
    ([0.0; 3], prep.settings.max_depth)
}

/// A scattered path: its new direction, the attenuation, the surface it leaves.
type Scattered = (V3<f32>, [f32; 3], Surface<f32>);

/// The surface hit `hit` at `t` along `o + t d`: the scattered direction, the
/// attenuation and the surface, or the path's final colour (a light, a debug
/// shading, an absorbed path).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn shade<P: Probe, const M: bool>(
    prep: &Prepared,
    o: V3<f32>,
    d: V3<f32>,
    t: f32,
    time: f32,
    hit: u32,
    id: PathId<f32>,
    depth: u32,
    thr: V3<f32>,
    rng: &mut impl Stream<f32>,
    probe: &mut P,
) -> Result<Scattered, [f32; 3]> {
    let sp = &prep.spheres;
    let (srf, kind, row) = if hit < QUAD_BASE {
        let i = hit as usize;
        let srf = surface(o, d, t, V3::new(sp.cx[i], sp.cy[i], sp.cz[i]), sp.r[i]);
        if P::PATHS {
            probe.shaded(id, hit, sp.r[i], srf.n, srf.front, 1);
        }
        (srf, sp.kind[i], sp.row[i] as usize)
    } else if M && hit >= MOVING_BASE {
        let (m, i) = (&prep.moving, (hit - MOVING_BASE) as usize);
        let r = m.s.r[i];
        let srf = surface(o, d, t, m.centre(i, time), r);
        if P::PATHS {
            probe.shaded(id, hit, r, srf.n, srf.front, 1);
        }
        (srf, m.s.kind[i], m.s.row[i] as usize)
    } else {
        let qs = &prep.quads;
        let i = (hit - QUAD_BASE) as usize;
        let [nx, ny, nz, dn, ..] = qs.shade[i].0;
        let srf = quad_surface(o, d, t, V3::new(nx, ny, nz), dn);
        if P::PATHS {
            probe.shaded(id, hit, 0.0, srf.n, srf.front, 1);
        }
        (srf, qs.kind[i], qs.row[i] as usize)
    };
    let m = &prep.materials;
    let (dir, atten) = match prep.plan.mode {
        Mode::Normals => return Err(normal_colour(srf.n).to_array()),
        Mode::Flat | Mode::Gradient => return Err(m.flat_colour(kind, row as u32)),
        Mode::Path if kind == Kind::DiffuseLight => {
            let (emit, one_sided) = m.light[row];
            let e = emission(V3::from_array(emit), one_sided, srf.front);
            return Err(thr.mul_elem(e).to_array());
        }
        Mode::Path => match scatter(prep, hit, kind, row, d, &srf, depth, rng) {
            Some(s) => s,
            None => return Err([0.0; 3]),
        },
    };
    Ok((dir, atten, srf))
}
