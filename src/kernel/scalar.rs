//! The reference path tracer: one path at a time, iterative, straightforward.
//! Every formula comes from the width-generic modules, instantiated at `f32`.

use super::{background, normal_colour, texture_albedo};
use crate::choice::Mode;
use crate::estimator::{
    cosine_pdf, mis_bsdf, roulette, roulette_applies, shadow_tmax, Directions, Toward, ISOTROPIC_PDF,
};
use crate::film::TileFilm;
use crate::geometry::{
    below, emission, quad_surface, sample_media, shading_normal, spawn, surface, transmittance, Hit, HitKind, Surface,
    MEDIUM_BASE, MISS,
};
use crate::handle::Kind;
use crate::material::{dielectric, lambertian, metal};
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
/// Instantiated for a scene on the general path (moving spheres or
/// instanced meshes: `Shapes::general`) and for one without (see
/// `trace_in`), chosen once per tile.
pub fn render_tile<S: PathSampler, P: Probe>(
    prep: &Prepared,
    sampler: S,
    tile: &mut TileFilm,
    samples: Range<u32>,
    probe: &mut P,
) -> u64 {
    if !prep.shapes.general() {
        render_tile_in::<S, P, false>(prep, sampler, tile, samples, probe)
    } else {
        render_tile_in::<S, P, true>(prep, sampler, tile, samples, probe)
    }
}

/// [`render_tile`] for a scene on the general path (`M`) or not.
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

/// What every step at one vertex reads: the prepared scene, the bounce's
/// depth (the rays the path traced before it) and whether the vertex sends
/// a light sample (`nee-mis`, while a ray is left for it).
#[derive(Clone, Copy)]
struct Vertex<'a> {
    prep: &'a Prepared,
    depth: u32,
    nee: bool,
    /// The estimator's directions at diffuse vertices (the plan's).
    how: Directions,
}

impl Vertex<'_> {
    /// What the vertex's directions are drawn toward.
    #[inline(always)]
    fn toward(&self) -> Toward<'_> {
        let p = self.prep;
        Toward { lights: &p.lights, emitters: &p.emitters, dim: p.bounces.light(self.depth) }
    }
}

/// A material as the kernels read it: its kind and its row in the kind's table.
#[derive(Clone, Copy)]
struct Material {
    kind: Kind,
    row: usize,
}

/// The shadow ray of a light sample drawn at `x` (`Some` from
/// [`Directions::at`]): from `x` moved off its surface along the ray by the
/// surface's offset (none inside a medium), carrying `albedo` times the
/// light's weighted radiance.
#[inline(always)]
fn shadow_ray(
    light: Option<(V3<f32>, f32, V3<f32>)>,
    x: V3<f32>,
    srf: Option<&Surface<f32>>,
    albedo: [f32; 3],
) -> Option<Shadow> {
    let (d, t, carry) = light?;
    let (o, offset) = match srf {
        Some(srf) => (spawn(srf, d), srf.offset),
        None => (x, 0.0),
    };
    Some(Shadow { o, d, tmax: shadow_tmax(t, offset), c: V3::from_array(albedo).mul_elem(carry) })
}

/// The scattered direction and attenuation of a path along `d` that hit
/// (`hit`, of material `mat`) at `srf`, the direction's density (0 for a
/// specular one) and, under `nee-mis`, the light sample; or `None` when the
/// path is absorbed (out of line in `phases` builds).
#[cfg_attr(not(feature = "phases"), inline(always))]
#[cfg_attr(feature = "phases", inline(never))]
fn scatter(
    v: Vertex,
    hit: u32,
    mat: Material,
    d: V3<f32>,
    (srf, n): (&Surface<f32>, V3<f32>),
    rng: &mut impl Stream<f32>,
) -> Option<Scatter> {
    let (prep, row) = (v.prep, mat.row);
    let m = &prep.materials;
    // With smooth shading (`n`, the shading normal), what leaves under the
    // geometric surface (`srf.n`) ends there (`geometry::smooth`).
    let smooth = !prep.shapes.smooth.is_empty();
    rng.seek(prep.bounces.scatter(v.depth));
    Some(match mat.kind {
        Kind::Lambertian => {
            let albedo = lambertian_albedo(prep, row, hit, srf.p);
            let dir = lambertian(n, rng);
            let vx = v.how.at(v.toward(), srf.p, dir, |d| cosine_pdf(n, d), v.nee, rng);
            let light = if smooth { vx.light.filter(|l| !below(srf.n, l.0)) } else { vx.light };
            let shadow = shadow_ray(light, srf.p, Some(srf), albedo);
            let pdf = if v.how == Directions::Book { 0.0 } else { cosine_pdf(n, vx.dir) };
            let atten = if smooth && below(srf.n, vx.dir) { [0.0; 3] } else { albedo.map(|a| a * vx.weight) };
            (vx.dir, atten, pdf, shadow)
        }
        Kind::Metal => {
            let (albedo, fuzz) = m.metal[row];
            let (dir, alive) = metal(d, n, fuzz, rng);
            if !alive || (smooth && below(srf.n, dir)) {
                return None;
            }
            (dir, albedo, 0.0, None)
        }
        Kind::Dielectric => (dielectric(d, n, srf.front, m.dielectric[row], rng), [1.0; 3], 0.0, None),
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
    let (c, rays, _) = if !prep.shapes.general() {
        trace_in::<P, false>(prep, x, y, id, rng, probe)
    } else {
        trace_in::<P, true>(prep, x, y, id, rng, probe)
    };
    (c, rays)
}

/// A path's radiance, the rays it traced and the shadow rays it traced.
type Traced = ([f32; 3], u32, u32);

/// One path in flight: its current ray, its time (scenes with moving
/// spheres; inherited by every ray it scatters), its throughput, the
/// radiance it has gathered, and what weighs the light it may hit next.
struct Path {
    id: PathId<f32>,
    o: V3<f32>,
    d: V3<f32>,
    time: f32,
    thr: V3<f32>,
    sum: V3<f32>,
    /// The density of the direction the path last scattered in (0: the
    /// camera's, or a specular bounce's), for the weight of a light it hits.
    pdf: f32,
    shadow_rays: u32,
    /// Whether the path's last direction was sampled at a diffuse or
    /// isotropic vertex (for the probe's [`Strategy`] only).
    scattered: bool,
}

impl Path {
    /// The path's camera ray through pixel (x, y), and its time when `M`.
    #[inline(always)]
    fn start<P: Probe, const M: bool>(
        prep: &Prepared,
        (x, y): (u32, u32),
        id: PathId<f32>,
        rng: &mut impl Stream<f32>,
        probe: &mut P,
    ) -> Path {
        let (o, d) = camera_ray(prep, x, y, rng);
        let o = if P::PATHS && probe.paths() { probe.camera(id, o, d, 1) } else { o };
        let time = if M && !prep.shapes.moving.is_empty() {
            rng.seek(layout::TIME);
            rng.next()
        } else {
            0.0
        };
        let (thr, sum) = (V3::new(1.0, 1.0, 1.0), V3::new(0.0, 0.0, 0.0));
        Path { id, o, d, time, thr, sum, pdf: 0.0, shadow_rays: 0, scattered: false }
    }

    /// The path's end after `rays` rays: its radiance plus `last`.
    #[inline(always)]
    fn end(&self, rays: u32, last: V3<f32>) -> Traced {
        ((self.sum + last).to_array(), rays, self.shadow_rays)
    }
}

/// [`trace`] for a scene on the general path (`M`: moving spheres, and the
/// path draws a time, or instanced meshes) or not (`false` compiles to the
/// path of a scene without either). Also
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
) -> Traced {
    let mut path = Path::start::<P, M>(prep, (x, y), id, rng, probe);
    let how = prep.plan.directions();
    for depth in 0..prep.settings.max_depth {
        // A light sample at this bounce's vertex stands for one more ray.
        let nee = prep.plan.nee > 0 && depth + 1 < prep.settings.max_depth;
        if let Some(end) = step::<P, M>(Vertex { prep, depth, nee, how }, &mut path, rng, probe) {
            return end;
        }
    }
    (path.sum.to_array(), prep.settings.max_depth, path.shadow_rays)
}

/// One bounce of `path`: its closest hit (or a medium's free flight), the
/// vertex there, its light sample, and the path's next ray; `Some` with the
/// path's result when it ends here.
#[inline(always)]
fn step<P: Probe, const M: bool>(
    v: Vertex,
    path: &mut Path,
    rng: &mut impl Stream<f32>,
    probe: &mut P,
) -> Option<Traced> {
    let (prep, depth, rays) = (v.prep, v.depth, v.depth + 1);
    probe.rays(depth, 1);
    let (hit, t) = closest_hit::<P, M>(prep, path.o, path.d, path.time, probe);
    if P::PATHS && probe.paths() {
        probe.traced(path.id, path.o, path.d, hit, t, 1);
    }
    // Scenes with media: the nearest of the surface and a free-flight sample per medium.
    let (hit, t) =
        if prep.media.is_empty() { (hit, t) } else { sample_media(&prep.media, path.o, path.d, hit, t, depth, rng) };
    if hit == MISS {
        // A black background adds nothing, whatever the throughput
        // (`SkyColours::is_black`): the wavefront shades no miss then.
        let black = prep.sky.is_black();
        let c = if black { V3::splat3([0.0; 3]) } else { path.thr.mul_elem(background(&prep.sky, path.d)) };
        if P::PATHS && probe.paths() {
            probe.contributed(path.id, rays, Strategy::Background, c);
        }
        return Some(if black { (path.sum.to_array(), rays, path.shadow_rays) } else { path.end(rays, c) });
    }
    let (next_o, dir, atten, shadow, kind) = if hit >= MEDIUM_BASE {
        let (o, dir, atten, shadow) = medium_vertex(v, path, hit, t, rng);
        (o, dir, atten, shadow, Kind::Isotropic)
    } else {
        match shade::<P, M>(v, path, hit, t, rng, probe) {
            Ok((dir, atten, srf, dir_pdf, shadow, kind)) => {
                path.pdf = dir_pdf;
                path.scattered = kind == Kind::Lambertian;
                (spawn(&srf, dir), dir, atten, shadow, kind)
            }
            Err(c) => {
                if P::PATHS && probe.paths() {
                    let how = if path.scattered { Strategy::Scattered } else { Strategy::Specular };
                    probe.contributed(path.id, rays, how, c);
                }
                return Some(path.end(rays, c));
            }
        }
    };
    if P::PATHS && probe.paths() {
        probe.scattered(path.id, kind, dir, atten, path.pdf);
    }
    if let Some(sh) = shadow {
        trace_shadow::<P, M>(prep, path, sh, rays, probe);
    }
    path.thr = path.thr.mul_elem(V3::from_array(atten));
    if path.thr.x == 0.0 && path.thr.y == 0.0 && path.thr.z == 0.0 {
        return Some((path.sum.to_array(), rays, path.shadow_rays));
    }
    if roulette_applies(&prep.estimator, rays) {
        rng.seek(prep.bounces.roulette(depth));
        let (t, survives) = roulette(path.thr, rng);
        if !survives {
            return Some((path.sum.to_array(), rays, path.shadow_rays));
        }
        path.thr = t;
    }
    path.o = next_o;
    path.d = dir;
    None
}

/// Isotropic scattering inside medium `hit - MEDIUM_BASE`, where the path
/// stopped at `t`: a uniform direction (or the book's mixture), the
/// medium's albedo, and the light sample from the stopping point.
#[inline(always)]
fn medium_vertex(
    v: Vertex,
    path: &mut Path,
    hit: u32,
    t: f32,
    rng: &mut impl Stream<f32>,
) -> (V3<f32>, V3<f32>, [f32; 3], Option<Shadow>) {
    let prep = v.prep;
    rng.seek(prep.bounces.scatter(v.depth));
    let dir = unit_vector(rng);
    let p = path.o + path.d * t;
    let albedo = prep.media.albedo[(hit - MEDIUM_BASE) as usize];
    path.scattered = true;
    if v.how != Directions::Book {
        path.pdf = ISOTROPIC_PDF;
    }
    let vx = v.how.at(v.toward(), p, dir, |_| ISOTROPIC_PDF, v.nee, rng);
    let shadow = shadow_ray(vx.light, p, None, albedo);
    (p, vx.dir, albedo.map(|a| a * vx.weight), shadow)
}

/// The shadow ray of a light sample at the vertex after `rays` rays: what
/// it carries is added to the path's radiance unless something blocks it
/// (through media, times their transmittance).
#[inline(always)]
fn trace_shadow<P: Probe, const M: bool>(prep: &Prepared, path: &mut Path, sh: Shadow, rays: u32, probe: &mut P) {
    let c = path.thr.mul_elem(sh.c);
    if !(c.x > 0.0 || c.y > 0.0 || c.z > 0.0) {
        return;
    }
    path.shadow_rays += 1;
    let time = path.time;
    if !prep.shapes.occluded::<f32, P, M>(sh.o, sh.d, sh.tmax, true, || time, probe) {
        let c = if prep.media.is_empty() { c } else { c * transmittance(&prep.media, sh.o, sh.d, sh.tmax) };
        if P::PATHS && probe.paths() {
            probe.contributed(path.id, rays + 1, Strategy::LightSample, c);
        }
        path.sum = path.sum + c;
    }
}

/// A scattered path: its new direction, the attenuation, the surface it
/// leaves, the direction's density (0: specular), its light sample, and
/// the vertex's material kind.
type Scattered = (V3<f32>, [f32; 3], Surface<f32>, f32, Option<Shadow>, Kind);

/// The surface `path` hit (`hit`, at `t` along its ray): the scattered
/// direction, the attenuation and the surface, or the path's last term (a
/// light, weighted under `nee-mis` against the light sample of the vertex
/// that scattered toward it with the path's density; a debug shading; 0
/// for an absorbed path).
#[inline(always)]
fn shade<P: Probe, const M: bool>(
    v: Vertex,
    path: &Path,
    hit: u32,
    t: f32,
    rng: &mut impl Stream<f32>,
    probe: &mut P,
) -> Result<Scattered, V3<f32>> {
    let (prep, o, d, id) = (v.prep, path.o, path.d, path.id);
    let (srf, kind, row, radius) = hit_surface::<M>(prep, o, d, t, hit, path.time);
    if P::PATHS && probe.paths() {
        probe.shaded(id, hit, radius, srf.n, srf.front, 1);
    }
    let m = &prep.materials;
    let n = shading(prep, hit, &srf);
    let dir_atten = match prep.plan.mode {
        Mode::Normals => return Err(normal_colour(n)),
        Mode::Flat | Mode::Gradient => return Err(V3::from_array(m.flat_colour(kind, row as u32))),
        Mode::Path if kind == Kind::DiffuseLight => {
            let (emit, one_sided) = m.light[row];
            let e = path.thr.mul_elem(emission(V3::from_array(emit), one_sided, srf.front));
            if prep.plan.nee == 0 {
                return Err(e);
            }
            return Err(e * mis_bsdf(path.pdf, prep.emitters.pdf_of(o, d, prep.emitters.of_row[row], hit)));
        }
        Mode::Path => match scatter(v, hit, Material { kind, row }, d, (&srf, n), rng) {
            Some(s) => s,
            None => return Err(V3::new(0.0, 0.0, 0.0)),
        },
    };
    let (dir, atten, dir_pdf, shadow) = dir_atten;
    Ok((dir, atten, srf, dir_pdf, shadow, kind))
}

/// The surface of hit `hit` at `t` along the ray (`o`, `d`) at `time`
/// (scenes with moving spheres, `M`): the surface, its material's kind and
/// row, and the sphere's signed radius (0 for a flat surface).
#[inline(always)]
pub(super) fn hit_surface<const M: bool>(
    prep: &Prepared,
    o: V3<f32>,
    d: V3<f32>,
    t: f32,
    hit: u32,
    time: f32,
) -> (Surface<f32>, Kind, usize, f32) {
    let sp = &prep.shapes.spheres;
    let Hit { kind: hit_kind, index: i } = Hit::of(hit);
    match hit_kind {
        HitKind::Sphere => {
            let srf = surface(o, d, t, V3::new(sp.cx[i], sp.cy[i], sp.cz[i]), sp.r[i]);
            (srf, sp.kind[i], sp.row[i] as usize, sp.r[i])
        }
        HitKind::Moving if M => {
            let m = &prep.shapes.moving;
            let r = m.s.r[i];
            (surface(o, d, t, m.centre(i, time), r), m.s.kind[i], m.s.row[i] as usize, r)
        }
        HitKind::Triangle if M => {
            let tr = &prep.shapes.triangles;
            let (kind, row) = tr.material_of(i);
            (tr.surface(o, d, t, i), kind, row as usize, 0.0)
        }
        HitKind::Instance if M => {
            let is = &prep.shapes.instances;
            let (srf, k) = is.surface(o, d, t, hit);
            (srf, is.kind[k], is.row[k] as usize, 0.0)
        }
        _ => {
            let qs = &prep.shapes.quads;
            let [nx, ny, nz, dn, ..] = qs.shade[i].0;
            (quad_surface(o, d, t, V3::new(nx, ny, nz), dn), qs.kind[i], qs.row[i] as usize, 0.0)
        }
    }
}

/// The shading normal of hit `hit` at `srf`: the geometric normal, or a
/// smooth mesh's interpolated one ([`shading_normal`]).
#[inline(always)]
pub(super) fn shading(prep: &Prepared, hit: u32, srf: &Surface<f32>) -> V3<f32> {
    match prep.shapes.smooth.is_empty() {
        true => srf.n,
        false => shading_normal(&prep.shapes.smooth, |_| hit, srf),
    }
}

/// The albedo of Lambertian material row `row` at `p` on hit `hit`: its
/// colour, or its texture's there.
#[inline(always)]
pub(super) fn lambertian_albedo(prep: &Prepared, row: usize, hit: u32, p: V3<f32>) -> [f32; 3] {
    let m = &prep.materials;
    let tex = m.lambertian_tex[row];
    match tex.kind {
        TexKind::Solid => m.lambertian[row],
        kind => texture_albedo(prep, kind, p, |_| hit, |_| tex.row as usize).to_array(),
    }
}
