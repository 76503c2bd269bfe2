//! The first hit of every camera ray, for the feature buffers a denoiser
//! reads ([`crate::film::aov`]): per pixel, the mean over its samples of
//! what the camera ray meets first.
//!
//! A pixel's sample `k` draws its camera ray (and its time, with moving
//! spheres) exactly as every kernel's path `k` of that pixel does, from the
//! same sampler stream. The rays go in packets of 8 ([`features`]: the
//! wavefront's camera rays and closest hit), their surfaces one at a time
//! with the scalar kernel's code; [`first_hit`] is the same for one ray with
//! the scalar kernel alone, and the two agree bit for bit (as the kernels
//! do; `tests/suite/kernels`). So the buffers are those of the render's own
//! camera rays, whatever kernel renders the colour, and the same bits for
//! every kernel.
//!
//! What a sample gives:
//! * **albedo**: a diffuse surface's colour after its texture; a metal's
//!   albedo; 1 for a dielectric (clear glass reflects and transmits all);
//!   a light's colour scaled to a largest channel of 1 (0 seen from the
//!   back of a one-sided light); the background seen, clamped to [0, 1].
//! * **normal**: the unit shading normal (a smooth mesh's interpolated
//!   one), facing against the camera ray (world space); 0 where the ray
//!   leaves the scene.
//! * **depth**: the distance along the (unit) camera ray; 0 where it leaves
//!   the scene.
//!
//! Media are not surfaces: the buffers show the first surface behind a
//! fog (a denoiser's albedo and normal are a surface's).

use super::background;
use super::scalar::{hit_surface, lambertian_albedo, shading};
use crate::film::aov::{Aovs, Features};
use crate::film::Image;
use crate::geometry::{emission, MISS};
use crate::handle::Kind;
use crate::plan::Prepared;
use crate::real::{U32Lanes, Wide};
use crate::sampling::{layout, PathSampler, Stream};
use crate::vec3::V3;
use rayon::prelude::*;
use std::ops::Range;
use wide::f32x8;

/// What one camera ray meets first (or, for a pixel, the mean over its samples).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstHit {
    pub albedo: [f32; 3],
    pub normal: [f32; 3],
    pub depth: f32,
}

/// The first hit of sample `sample` of pixel (x, y).
pub fn first_hit<S: PathSampler>(prep: &Prepared, sampler: S, x: u32, y: u32, sample: u32) -> FirstHit {
    let pixel = y as u64 * prep.settings.width as u64 + x as u64;
    let mut rng = sampler.scalar(prep.settings.seed, pixel, sample);
    if !prep.shapes.general() {
        first_hit_in::<false>(prep, x, y, &mut rng)
    } else {
        first_hit_in::<true>(prep, x, y, &mut rng)
    }
}

/// [`first_hit`] for a scene on the general path (`M`: moving spheres or
/// instanced meshes) or not.
fn first_hit_in<const M: bool>(prep: &Prepared, x: u32, y: u32, rng: &mut impl Stream<f32>) -> FirstHit {
    let (o, d) = prep.camera.ray(x as f32, y as f32, rng);
    let time = if M && !prep.shapes.moving.is_empty() {
        rng.seek(layout::TIME);
        rng.next()
    } else {
        0.0
    };
    let best = prep.shapes.closest::<f32, (), M>(o, d, true, || time, &mut ());
    surface_of::<M>(prep, o, d, best.index, best.t, time)
}

/// The mean of the first hits of samples `samples` of pixel (x, y), their
/// rays traced in packets of `W::LANES` (a short last packet repeats its
/// last ray); summed in f64 in sample order.
fn pixel_mean<W: Wide, S: PathSampler, const M: bool>(
    prep: &Prepared,
    sampler: S,
    (x, y): (u32, u32),
    samples: Range<u32>,
) -> FirstHit {
    debug_assert!(W::LANES <= 16, "a packet's words fit 16 lanes");
    let st = &prep.settings;
    let pixel_words = sampler.pixel_words(st.seed, y as u64 * st.width as u64 + x as u64);
    let mut sum = Sum::default();
    let mut s0 = samples.start;
    while s0 < samples.end {
        let live = (samples.end - s0).min(W::LANES as u32) as usize;
        let words: [[u32; 4]; 16] = std::array::from_fn(|k| sampler.words_at(pixel_words, s0 + k.min(live - 1) as u32));
        let mut rng = sampler.lanes::<W>(std::array::from_fn(|w| W::U::from_fn(|k| words[k][w])));
        let (o, d) = prep.camera.ray(W::splat(x as f32), W::splat(y as f32), &mut rng);
        let time = if M && !prep.shapes.moving.is_empty() {
            rng.seek(layout::TIME);
            rng.next()
        } else {
            W::splat(0.0)
        };
        let all = W::splat(1.0).gt(W::splat(0.5));
        let best = prep.shapes.closest::<W, (), M>(o, d, all, || time, &mut ());
        for k in 0..live {
            let (index, t) = (W::lane_u(best.index, k), best.t.lane(k));
            sum.add(surface_of::<M>(prep, o.lane(k), d.lane(k), index, t, time.lane(k)));
        }
        s0 += live as u32;
    }
    sum.mean(samples.len())
}

/// What the ray (`o`, `d`) at `time` meets: hit `index` at `t`, or nothing.
fn surface_of<const M: bool>(prep: &Prepared, o: V3<f32>, d: V3<f32>, index: u32, t: f32, time: f32) -> FirstHit {
    if index == MISS {
        let sky = background(&prep.sky, d).to_array().map(|c| c.clamp(0.0, 1.0));
        return FirstHit { albedo: sky, normal: [0.0; 3], depth: 0.0 };
    }
    let (srf, kind, row, _) = hit_surface::<M>(prep, o, d, t, index, time);
    let m = &prep.materials;
    let albedo = match kind {
        Kind::Lambertian => lambertian_albedo(prep, row, index, srf.p),
        Kind::Metal => m.metal[row].0,
        Kind::Dielectric | Kind::Isotropic => [1.0; 3],
        Kind::DiffuseLight => {
            let (emit, one_sided) = m.light[row];
            let e = emission(V3::from_array(emit), one_sided, srf.front).to_array();
            let top = e[0].max(e[1]).max(e[2]);
            if top > 0.0 {
                e.map(|c| c / top)
            } else {
                [0.0; 3]
            }
        }
    };
    FirstHit { albedo, normal: shading(prep, index, &srf).to_array(), depth: t }
}

/// The buffers `aovs` of the window of columns `cols` and rows `rows`, each
/// pixel the mean over samples `samples` (summed in f64 in sample order, so
/// the result does not depend on threads). Rows run in parallel on the
/// current rayon pool.
pub fn features<S: PathSampler>(
    prep: &Prepared,
    sampler: S,
    cols: Range<u32>,
    rows: Range<u32>,
    samples: Range<u32>,
    aovs: Aovs,
) -> Features {
    let (w, h) = (cols.len() as u32, rows.len() as u32);
    let general = prep.shapes.general();
    let per_row: Vec<Vec<FirstHit>> = rows
        .into_par_iter()
        .map(|y| {
            let at = |x| match general {
                false => pixel_mean::<f32x8, S, false>(prep, sampler, (x, y), samples.clone()),
                true => pixel_mean::<f32x8, S, true>(prep, sampler, (x, y), samples.clone()),
            };
            cols.clone().map(at).collect()
        })
        .collect();
    let pixels = || per_row.iter().flatten();
    let image = |f: fn(&FirstHit) -> [f32; 3]| Image { width: w, height: h, data: pixels().map(f).collect() };
    Features {
        width: w,
        height: h,
        albedo: aovs.albedo.then(|| image(|p| p.albedo)),
        normal: aovs.normal.then(|| image(|p| p.normal)),
        depth: aovs.depth.then(|| pixels().map(|p| p.depth).collect()),
    }
}

/// First hits added up in f64, in the order given.
#[derive(Default)]
struct Sum {
    albedo: [f64; 3],
    normal: [f64; 3],
    depth: f64,
}

impl Sum {
    fn add(&mut self, f: FirstHit) {
        for c in 0..3 {
            self.albedo[c] += f.albedo[c] as f64;
            self.normal[c] += f.normal[c] as f64;
        }
        self.depth += f.depth as f64;
    }

    /// The mean over `n` hits (0 for none).
    fn mean(&self, n: usize) -> FirstHit {
        let n = n.max(1) as f64;
        let f = |v: f64| (v / n) as f32;
        FirstHit { albedo: self.albedo.map(f), normal: self.normal.map(f), depth: f(self.depth) }
    }
}
