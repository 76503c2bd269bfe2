//! The reference path tracer: one path at a time, iterative, straightforward.
//! Every formula comes from the width-generic modules, instantiated at `f32`.

use super::{background, normal_colour, texture_albedo};
use crate::choice::Mode;
use crate::estimator::{
    book_mixture, cosine_pdf, mis_bsdf, next_event, roulette, roulette_applies, shadow_tmax, ISOTROPIC_PDF,
};
use crate::film::TileFilm;
use crate::geometry::{
    quad_surface, sample_media, spawn, surface, transmittance, Hit, HitKind, Surface, MEDIUM_BASE, MISS,
};
use crate::material::{dielectric, emission, lambertian, metal, Kind};
use crate::plan::Prepared;
use crate::probe::{PathId, Probe, Strategy};
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
    if prep.shapes.moving.is_empty() {
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
                let (c, n, shadow) = trace_in::<P, M>(prep, x, y, PathId { pixel, sample }, &mut rng, probe);
                rays += n as u64;
                tile.shadow_rays += shadow as u64;
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
    let best = prep.shapes.closest::<f32, P, M>(o, d, true, || time, probe);
    (best.index, best.t)
}

/// A scattered direction, its attenuation, its density (0: specular) and
/// its vertex's light sample.
type Scatter = (V3<f32>, [f32; 3], f32, Option<Shadow>);

/// A light sample's shadow ray (the `nee-mis` estimator): its origin,
/// direction and length, and what it carries per unit throughput if nothing
/// blocks it.
struct Shadow {
    o: V3<f32>,
    d: V3<f32>,
    tmax: f32,
    c: V3<f32>,
}

/// What a diffuse vertex sends toward a light under `nee-mis` (`None`
/// when the estimator does not run at this bounce): the shadow ray from
/// `o` (`x` moved off its surface along the ray by `offset`), carrying
/// `albedo` times the light's weighted radiance.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn light_sample(
    prep: &Prepared,
    nee: bool,
    x: V3<f32>,
    srf: Option<&Surface<f32>>,
    own_pdf: impl Fn(V3<f32>) -> f32,
    albedo: [f32; 3],
    depth: u32,
    rng: &mut impl Stream<f32>,
) -> Option<Shadow> {
    if !nee {
        return None;
    }
    let (d, t, carry) = next_event(&prep.emitters, x, own_pdf, prep.bounces.light(depth), rng);
    let (o, offset) = match srf {
        Some(srf) => (spawn(srf, d), srf.offset),
        None => (x, 0.0),
    };
    Some(Shadow { o, d, tmax: shadow_tmax(t, offset), c: V3::from_array(albedo).mul_elem(carry) })
}

/// The scattered direction and attenuation of a path that hit material
/// (`kind`, `row`) at `srf`, the direction's density (0 for a specular
/// one) and, under `nee-mis`, the light sample; or `None` when the path is
/// absorbed (out of line in `phases` builds).
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
    nee: bool,
    rng: &mut impl Stream<f32>,
) -> Option<Scatter> {
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
                let shadow = light_sample(prep, nee, srf.p, Some(srf), |d| cosine_pdf(srf.n, d), albedo, depth, rng);
                (dir, albedo, cosine_pdf(srf.n, dir), shadow)
            } else {
                let (dir, w) =
                    book_mixture(&prep.lights, srf.p, dir, |d| cosine_pdf(srf.n, d), prep.bounces.light(depth), rng);
                (dir, albedo.map(|a| a * w), 0.0, None)
            }
        }
        Kind::Metal => {
            let (albedo, fuzz) = m.metal[row];
            let (dir, alive) = metal(d, srf.n, fuzz, rng);
            if !alive {
                return None;
            }
            (dir, albedo, 0.0, None)
        }
        Kind::Dielectric => (dielectric(d, srf.n, srf.front, m.dielectric[row], rng), [1.0; 3], 0.0, None),
        // Lights end the path before scattering (`trace`); media scatter in `trace`.
        Kind::DiffuseLight | Kind::Isotropic => return None,
    })
}

/// The radiance of one path through pixel (x, y), and the rays it traced
/// (not counting its shadow rays).
pub fn trace<P: Probe>(
    prep: &Prepared,
    x: u32,
    y: u32,
    id: PathId<f32>,
    rng: &mut impl Stream<f32>,
    probe: &mut P,
) -> ([f32; 3], u32) {
    let (c, rays, _) = if prep.shapes.moving.is_empty() {
        trace_in::<P, false>(prep, x, y, id, rng, probe)
    } else {
        trace_in::<P, true>(prep, x, y, id, rng, probe)
    };
    (c, rays)
}

/// [`trace`] for a scene with moving spheres (`M`: the path draws a time)
/// or without (`false` compiles to the path of a scene without). Also
/// returns the shadow rays it traced.
///
/// The radiance is a sum: under `nee-mis` each unblocked light sample adds
/// its share at its bounce, in bounce order, then the path's last term (the
/// background, or a light it hit, weighted against the light samples); the
/// other estimators add only the last (to 0, which changes no bit the film
/// keeps).
fn trace_in<P: Probe, const M: bool>(
    prep: &Prepared,
    x: u32,
    y: u32,
    id: PathId<f32>,
    rng: &mut impl Stream<f32>,
    probe: &mut P,
) -> ([f32; 3], u32, u32) {
    let (o, mut d) = camera_ray(prep, x, y, rng);
    let mut o = if P::PATHS && probe.paths() { probe.camera(id, o, d, 1) } else { o };
    // The path's time (scenes with moving spheres only), inherited by every
    // ray it scatters.
    let time = if M {
        rng.seek(layout::TIME);
        rng.next()
    } else {
        0.0
    };
    let mut thr = V3::new(1.0f32, 1.0, 1.0);
    let mut sum = V3::new(0.0f32, 0.0, 0.0);
    // The density of the direction the path last scattered in (0: the
    // camera's, or a specular bounce's), for the weight of a light it hits.
    let mut pdf = 0.0f32;
    let mut shadow_rays = 0;
    // Whether the path's last direction was sampled at a diffuse or
    // isotropic vertex (for the probe's [`Strategy`] only).
    let mut scattered = false;
    for depth in 0..prep.settings.max_depth {
        let rays = depth + 1;
        // A light sample at this bounce's vertex stands for one more ray.
        let nee = prep.plan.nee > 0 && rays < prep.settings.max_depth;
        probe.rays(depth, 1);
        let (hit, t) = closest_hit::<P, M>(prep, o, d, time, probe);
        if P::PATHS && probe.paths() {
            probe.traced(id, o, d, hit, t, 1);
        }
        // Scenes with media: the nearest of the surface and a free-flight sample per medium.
        let (hit, t) =
            if prep.media.is_empty() { (hit, t) } else { sample_media(&prep.media, o, d, hit, t, depth, rng) };
        if hit == MISS {
            // A black background adds nothing, whatever the throughput
            // (`SkyColours::is_black`): the wavefront shades no miss then.
            let black = prep.sky.is_black();
            let c = if black { V3::splat3([0.0; 3]) } else { thr.mul_elem(background(&prep.sky, d)) };
            if P::PATHS && probe.paths() {
                probe.contributed(id, rays, Strategy::Background, c);
            }
            return ((if black { sum } else { sum + c }).to_array(), rays, shadow_rays);
        }
        let (next_o, dir, atten, shadow) = if hit >= MEDIUM_BASE {
            // Isotropic scattering inside medium k: a uniform direction.
            rng.seek(prep.bounces.scatter(depth));
            let dir = unit_vector(rng);
            let p = o + d * t;
            let albedo = prep.media.albedo[(hit - MEDIUM_BASE) as usize];
            scattered = true;
            if prep.plan.sample_toward == 0 {
                pdf = ISOTROPIC_PDF;
                let shadow = light_sample(prep, nee, p, None, |_| ISOTROPIC_PDF, albedo, depth, rng);
                (p, dir, albedo, shadow)
            } else {
                let (dir, w) = book_mixture(&prep.lights, p, dir, |_| ISOTROPIC_PDF, prep.bounces.light(depth), rng);
                (p, dir, albedo.map(|a| a * w), None)
            }
        } else {
            let (dir, atten, srf, dir_pdf, shadow, diffuse) =
                match shade::<P, M>(prep, o, d, t, time, hit, id, depth, thr, pdf, nee, rng, probe) {
                    Ok(s) => s,
                    Err(c) => {
                        if P::PATHS && probe.paths() {
                            let how = if scattered { Strategy::Scattered } else { Strategy::Specular };
                            probe.contributed(id, rays, how, c);
                        }
                        return ((sum + c).to_array(), rays, shadow_rays);
                    }
                };
            pdf = dir_pdf;
            scattered = diffuse;
            (spawn(&srf, dir), dir, atten, shadow)
        };
        if let Some(sh) = shadow {
            let c = thr.mul_elem(sh.c);
            if c.x > 0.0 || c.y > 0.0 || c.z > 0.0 {
                shadow_rays += 1;
                if !prep.shapes.occluded::<f32, P, M>(sh.o, sh.d, sh.tmax, true, || time, probe) {
                    let c = if prep.media.is_empty() { c } else { c * transmittance(&prep.media, sh.o, sh.d, sh.tmax) };
                    if P::PATHS && probe.paths() {
                        probe.contributed(id, rays + 1, Strategy::LightSample, c);
                    }
                    sum = sum + c;
                }
            }
        }
        thr = thr.mul_elem(V3::from_array(atten));
        if thr.x == 0.0 && thr.y == 0.0 && thr.z == 0.0 {
            return (sum.to_array(), rays, shadow_rays);
        }
        if roulette_applies(&prep.estimator, rays) {
            rng.seek(prep.bounces.roulette(depth));
            let (t, survives) = roulette(thr, rng);
            if !survives {
                return (sum.to_array(), rays, shadow_rays);
            }
            thr = t;
        }
        o = next_o;
        d = dir;
    }
    (sum.to_array(), prep.settings.max_depth, shadow_rays)
}

/// A scattered path: its new direction, the attenuation, the surface it
/// leaves, the direction's density (0: specular), its light sample, and
/// whether the vertex is diffuse.
type Scattered = (V3<f32>, [f32; 3], Surface<f32>, f32, Option<Shadow>, bool);

/// The surface hit `hit` at `t` along `o + t d`: the scattered direction, the
/// attenuation and the surface, or the path's last term (a light, weighted
/// under `nee-mis` against the light sample of the vertex that scattered
/// toward it with density `pdf`; a debug shading; 0 for an absorbed path).
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
    pdf: f32,
    nee: bool,
    rng: &mut impl Stream<f32>,
    probe: &mut P,
) -> Result<Scattered, V3<f32>> {
    let sp = &prep.shapes.spheres;
    let Hit { kind: hit_kind, index: i } = Hit::of(hit);
    let (srf, kind, row) = match hit_kind {
        HitKind::Sphere => {
            let srf = surface(o, d, t, V3::new(sp.cx[i], sp.cy[i], sp.cz[i]), sp.r[i]);
            if P::PATHS && probe.paths() {
                probe.shaded(id, hit, sp.r[i], srf.n, srf.front, 1);
            }
            (srf, sp.kind[i], sp.row[i] as usize)
        }
        HitKind::Moving if M => {
            let m = &prep.shapes.moving;
            let r = m.s.r[i];
            let srf = surface(o, d, t, m.centre(i, time), r);
            if P::PATHS && probe.paths() {
                probe.shaded(id, hit, r, srf.n, srf.front, 1);
            }
            (srf, m.s.kind[i], m.s.row[i] as usize)
        }
        _ => {
            let qs = &prep.shapes.quads;
            let [nx, ny, nz, dn, ..] = qs.shade[i].0;
            let srf = quad_surface(o, d, t, V3::new(nx, ny, nz), dn);
            if P::PATHS && probe.paths() {
                probe.shaded(id, hit, 0.0, srf.n, srf.front, 1);
            }
            (srf, qs.kind[i], qs.row[i] as usize)
        }
    };
    let m = &prep.materials;
    let dir_atten = match prep.plan.mode {
        Mode::Normals => return Err(normal_colour(srf.n)),
        Mode::Flat | Mode::Gradient => return Err(V3::from_array(m.flat_colour(kind, row as u32))),
        Mode::Path if kind == Kind::DiffuseLight => {
            let (emit, one_sided) = m.light[row];
            let e = thr.mul_elem(emission(V3::from_array(emit), one_sided, srf.front));
            if prep.plan.nee == 0 {
                return Err(e);
            }
            return Err(e * mis_bsdf(pdf, prep.emitters.pdf_of(o, d, prep.emitters.of_row[row])));
        }
        Mode::Path => match scatter(prep, hit, kind, row, d, &srf, depth, nee, rng) {
            Some(s) => s,
            None => return Err(V3::new(0.0, 0.0, 0.0)),
        },
    };
    let (dir, atten, dir_pdf, shadow) = dir_atten;
    Ok((dir, atten, srf, dir_pdf, shadow, kind == Kind::Lambertian))
}
