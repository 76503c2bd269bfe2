//! The estimator's parts that both kernels share, so they take the same
//! decisions:
//!
//! - How a path chooses its direction at a diffuse vertex (a lambertian hit
//!   or a medium's isotropic scattering), three estimators
//!   (`crate::choice::EstimatorChoice`): `bsdf`, the material's own density
//!   (books one and two); `book`, The Rest of Your Life's one-sample
//!   mixture, half the directions toward the `sample_toward` shapes or the
//!   lights ([`book_mixture`]); `nee-mis`, a shadow ray toward a point on a
//!   light at every diffuse vertex ([`next_event`]), weighted against the
//!   scattered direction by the power heuristic ([`mis_light`],
//!   [`mis_bsdf`]). All three are unbiased: they change the noise, not the
//!   expected image.
//! - Optional changes that trade noise for work, off by default (with both
//!   off the kernels draw and add exactly what they drew and added before):
//!   Russian roulette and adaptive sampling:
//!
//! - Russian roulette is width-generic ([`roulette`]) and draws one value from
//!   the path's own stream, at the same bounce in both kernels.
//! - Adaptive sampling decides at fixed sample counts ([`Adaptive::round_end`]),
//!   from the film's per-pixel moments ([`TileFilm::moments`], turned into an
//!   error by [`relative_error`]), which both kernels fill with the same values
//!   in the same order.

use crate::error::{Error, Result};
use crate::film::{Moments, TileFilm};
use crate::geometry::{Emitters, Lights};
use crate::real::Real;
use crate::sampling::Stream;
use crate::vec3::V3;
use serde::Serialize;

/// How a diffuse or isotropic vertex chooses its direction: the render's
/// estimator, decided once from the plan (`Plan::directions`), the one type
/// both kernels read ([`Directions::at`]). The wavefront passes it as a
/// literal at each scatter pass's call, so each is compiled apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Directions {
    /// The material's density (`bsdf`).
    Bsdf,
    /// The book's mixture toward the `sample_toward` shapes or the lights (`book`).
    Book,
    /// The material's density, and a light sample (`nee-mis`).
    Nee,
}

/// What a vertex's directions are drawn toward: the `book` mixture's
/// shapes, the `nee-mis` lights, and the sampler dimension of the bounce's
/// light draws ([`crate::sampling::layout::Bounces::light`]).
#[derive(Clone, Copy)]
pub struct Toward<'a> {
    pub lights: &'a Lights,
    pub emitters: &'a Emitters,
    pub dim: u32,
}

/// A diffuse vertex's decision: the path's next direction, the factor on
/// its albedo (the `book` mixture's weight; 1 otherwise) and, under
/// `nee-mis`, the light sample to send ([`next_event`]'s direction,
/// distance and carry).
pub struct Diffuse<R: Real> {
    pub dir: V3<R>,
    pub weight: R,
    pub light: Option<(V3<R>, R, V3<R>)>,
}

impl Directions {
    /// The decision at a diffuse vertex `x` whose material sampled `dir`
    /// with density `own_pdf`, written once for both kernels and every
    /// width: `bsdf` keeps `dir`; `book` draws the mixture
    /// ([`book_mixture`]); `nee-mis` keeps `dir` and, when `send` (a ray is
    /// left for it), draws a light sample ([`next_event`]).
    #[inline(always)]
    pub fn at<R: Real, S: Stream<R>>(
        self,
        toward: Toward,
        x: V3<R>,
        dir: V3<R>,
        own_pdf: impl Fn(V3<R>) -> R,
        send: bool,
        rng: &mut S,
    ) -> Diffuse<R> {
        let one = R::splat(1.0);
        match self {
            Directions::Bsdf => Diffuse { dir, weight: one, light: None },
            Directions::Book => {
                let (dir, weight) = book_mixture(toward.lights, x, dir, own_pdf, toward.dim, rng);
                Diffuse { dir, weight, light: None }
            }
            Directions::Nee => {
                let light = send.then(|| next_event(toward.emitters, x, own_pdf, toward.dim, rng));
                Diffuse { dir, weight: one, light }
            }
        }
    }
}

/// The `book` estimator at a diffuse vertex `x` (The Rest of Your Life's
/// `mixture_pdf` of the material's density and the `lights` list, 50/50):
/// `own` is the direction the material sampled (from the bounce's
/// scattering dimensions) and `own_pdf` its density, which is also the
/// material's scattering density (a cosine lobe `max(0, n . d) / pi`, or
/// the isotropic `1 / 4 pi`). Draws 3 values from dimension `dim` on
/// (`layout::Bounces::light`): the
/// choice (below 1/2: toward the list, and which of its shapes), then the
/// point on the shape. Returns the direction and the weight
/// `own_pdf(dir) / (own_pdf(dir) / 2 + lights.pdf(dir) / 2)` that
/// multiplies the albedo, 0 where the mixture's density is 0 (the material
/// does not scatter there: `own_pdf` is 0 too). Every lane draws and
/// evaluates both halves; each keeps its own choice.
#[inline(always)]
pub fn book_mixture<R: Real, S: Stream<R>>(
    lights: &Lights,
    x: V3<R>,
    own: V3<R>,
    own_pdf: impl Fn(V3<R>) -> R,
    dim: u32,
    rng: &mut S,
) -> (V3<R>, R) {
    rng.seek(dim);
    let choice = rng.next();
    let u1 = rng.next();
    let u2 = rng.next();
    let half = R::splat(0.5);
    let toward = choice.lt(half);
    let dir = V3::select(toward, lights.sample(x, choice * R::splat(2.0), u1, u2), own);
    let p_own = own_pdf(dir);
    let pdf = half * p_own + half * lights.pdf(x, dir);
    let zero = R::splat(0.0);
    (dir, R::select(pdf.gt(zero), p_own / pdf, zero))
}

/// The `nee-mis` estimator's light sample at a diffuse vertex `x` whose
/// scattering density is `own_pdf` (which is also its BSDF over its
/// albedo: the cosine lobe `max(0, n . d) / pi`, or the isotropic `1 / 4
/// pi`). Draws 3 values from dimension `dim` on
/// ([`crate::sampling::layout::Bounces::light`]): which light, then the
/// point on it. Returns the shadow ray's direction, the distance to the
/// light along it, and what it carries if nothing blocks it, per unit
/// albedo and throughput: the light's radiance times the power heuristic's
/// weight over the density, `own_pdf / (p_light (1 + (own_pdf / p_light)^2))`
/// ([`mis_light`]); 0 where the sample is unusable or the material does not
/// scatter toward it.
#[inline(always)]
pub fn next_event<R: Real, S: Stream<R>>(
    emitters: &Emitters,
    x: V3<R>,
    own_pdf: impl Fn(V3<R>) -> R,
    dim: u32,
    rng: &mut S,
) -> (V3<R>, R, V3<R>) {
    rng.seek(dim);
    let pick = rng.next();
    let u1 = rng.next();
    let u2 = rng.next();
    let ls = emitters.sample(x, pick, u1, u2);
    let w = mis_light(own_pdf(ls.dir), ls.pdf);
    (ls.dir, ls.t, ls.emit * w)
}

/// A light sample's weight over its density under the power heuristic,
/// `w_light / p_light = p_light / (p_light^2 + p_bsdf^2)`, times the BSDF's
/// `p_bsdf`: `r / (1 + r^2)` with `r = p_bsdf / p_light`, written
/// `1 / (1 / r + r)` so that neither a tiny nor a huge ratio overflows (each
/// gives 0). 0 where `p_light` is 0 (no sample).
#[inline(always)]
pub fn mis_light<R: Real>(p_bsdf: R, p_light: R) -> R {
    let (zero, one) = (R::splat(0.0), R::splat(1.0));
    let r = p_bsdf / p_light;
    R::select(p_light.gt(zero), one / (one / r + r), zero)
}

/// The power heuristic's weight of emission reached by a scattered
/// direction of density `p_bsdf`, which a light sample would have drawn
/// with density `p_light`: `1 / (1 + (p_light / p_bsdf)^2)`; 1 where
/// `p_bsdf` is 0 (the camera ray, a specular bounce: no light sample
/// competed).
#[inline(always)]
pub fn mis_bsdf<R: Real>(p_bsdf: R, p_light: R) -> R {
    let (zero, one) = (R::splat(0.0), R::splat(1.0));
    let q = p_light / p_bsdf;
    R::select(p_bsdf.gt(zero), one / (one + q * q), one)
}

/// The end of a shadow ray toward a light at distance `t` from the vertex,
/// from an origin moved `offset` off the surface: short of the light by a
/// relative `2^-10` (its own surface never blocks it) and by the offset.
#[inline(always)]
pub fn shadow_tmax<R: Real>(t: R, offset: R) -> R {
    t * R::splat(1.0 - 1.0 / 1024.0) - offset
}

/// A lambertian's scattering density at normal `n`: `max(0, n . d) / pi`.
#[inline(always)]
pub fn cosine_pdf<R: Real>(n: V3<R>, d: V3<R>) -> R {
    n.dot(d).max(R::splat(0.0)) * R::splat(std::f32::consts::FRAC_1_PI)
}

/// The isotropic phase function's density, `1 / 4 pi`.
pub const ISOTROPIC_PDF: f32 = 0.25 * std::f32::consts::FRAC_1_PI;

/// By default roulette starts once a path has traced this many rays. Measured
/// on the final scene and ch11-defocus (docs/convergence.md): starting after
/// 3 rays costs 28% of the efficiency 1/(MSE x rays) on both (the sky is the
/// only light, so a live path's next rays are likely to reach it and matter);
/// after 6 rays it gains 3% on the final scene and costs 7% on ch11-defocus.
pub const ROULETTE_AFTER_RAYS: u32 = 6;

/// Russian roulette on the path throughput: from `after_rays` rays on, a
/// path survives with probability `min(1, max throughput component)` and is
/// reweighted (unbiased; it changes the noise, not the expected image).
/// Valid by construction ([`Roulette::new`] is the one check). Serialized as
/// the number `after_rays`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(transparent)]
pub struct Roulette {
    /// Roulette starts once a path has traced this many rays (1: right after the camera ray).
    after_rays: u32,
}

impl Default for Roulette {
    fn default() -> Self {
        Roulette { after_rays: ROULETTE_AFTER_RAYS }
    }
}

impl Roulette {
    /// Roulette after `after_rays` rays: at least 1 (the camera ray).
    pub fn new(after_rays: u32) -> Result<Roulette> {
        if after_rays == 0 {
            return Err(Error::invalid(
                "roulette.after_rays",
                "roulette can start after 1 ray (the camera ray) at the earliest, not 0",
            ));
        }
        Ok(Roulette { after_rays })
    }

    /// Roulette starts once a path has traced this many rays (1: right after the camera ray).
    pub fn after_rays(&self) -> u32 {
        self.after_rays
    }

    /// How the film identity and `--explain` describe it.
    pub fn describe(roulette: Option<Roulette>) -> String {
        match roulette {
            Some(r) => format!("after {} rays", r.after_rays),
            None => "off".into(),
        }
    }

    /// What [`Roulette::describe`] wrote (`None`: text it never writes).
    pub fn from_description(text: &str) -> Option<Option<Roulette>> {
        if text == "off" {
            return Some(None);
        }
        let n = text.strip_prefix("after ")?.strip_suffix(" rays")?.parse().ok()?;
        Roulette::new(n).ok().map(Some)
    }
}

/// Russian roulette on a path's throughput `thr` (after the bounce's albedo):
/// the path survives with probability `p = min(1, max component of thr)` and
/// its throughput is divided by `p`, so its expected contribution is unchanged.
/// Draws exactly one value, in every lane. Returns (new throughput, survives).
/// Where `p` is 1 the throughput is returned unchanged (not divided).
#[inline(always)]
pub fn roulette<R: Real, S: Stream<R>>(thr: V3<R>, rng: &mut S) -> (V3<R>, R::Mask) {
    let one = R::splat(1.0);
    let p = thr.x.max(thr.y).max(thr.z).min(one);
    let u = rng.next();
    let survives = u.lt(p);
    let keep = p.ge(one);
    let scaled = V3::new(thr.x / p, thr.y / p, thr.z / p);
    (V3::select(keep, thr, scaled), survives)
}

/// Whether a path that has traced `rays` rays (1 = just the camera ray) and
/// just scattered faces the roulette before its next ray.
#[inline(always)]
pub fn roulette_applies(est: &Estimator, rays: u32) -> bool {
    match est.roulette {
        Some(r) => rays >= r.after_rays,
        None => false,
    }
}

/// Adaptive sampling: a pixel stops once its relative standard error is at
/// most `threshold`. Decisions are taken only after `min_spp`, `2 min_spp`,
/// `4 min_spp`, ... samples. Valid by construction ([`Adaptive::new`] is the
/// one check).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Adaptive {
    threshold: f32,
    min_spp: u32,
}

/// Default first decision point (samples per pixel). An error estimate from
/// fewer samples is too often wrong the lucky way: on the final scene, first
/// decisions at 32 samples cost 23% more MSE x rays than at 64
/// (docs/convergence.md).
pub const ADAPTIVE_MIN_SPP: u32 = 64;

/// Below this mean value a pixel's error is taken relative to this floor, so
/// that (nearly) black pixels are not sampled forever for a relative error
/// that nobody can see.
pub const RELATIVE_ERROR_FLOOR: f64 = 0.05;

impl Adaptive {
    /// A pixel stops once its relative error is at most `threshold`; the
    /// first decision is taken after `min_spp` samples.
    pub fn new(threshold: f32, min_spp: u32) -> Result<Adaptive> {
        Adaptive::check_threshold(threshold)?;
        if min_spp < 2 {
            return Err(Error::invalid(
                "adaptive.min_spp",
                format!("the first decision needs at least 2 samples to estimate an error, not {min_spp}"),
            ));
        }
        Ok(Adaptive { threshold, min_spp })
    }

    /// The threshold's own rule (a positive number), for a caller that
    /// takes the threshold before the first decision point (`rtow
    /// converge`'s variants).
    pub fn check_threshold(threshold: f32) -> Result<()> {
        if !(threshold.is_finite() && threshold > 0.0) {
            return Err(Error::invalid(
                "adaptive.threshold",
                format!("the relative error threshold must be a positive number, not {threshold}"),
            ));
        }
        Ok(())
    }

    /// A pixel stops once its relative error is at most this.
    pub fn threshold(&self) -> f32 {
        self.threshold
    }

    /// The first decision is taken after this many samples per pixel.
    pub fn min_spp(&self) -> u32 {
        self.min_spp
    }

    /// How the film identity describes it.
    pub fn describe(adaptive: Option<Adaptive>) -> String {
        match adaptive {
            Some(a) => format!("threshold {} from {} spp", a.threshold, a.min_spp),
            None => "off".into(),
        }
    }

    /// What [`Adaptive::describe`] wrote (`None`: text it never writes).
    pub fn from_description(text: &str) -> Option<Option<Adaptive>> {
        if text == "off" {
            return Some(None);
        }
        let (t, m) = text.strip_prefix("threshold ")?.strip_suffix(" spp")?.split_once(" from ")?;
        Adaptive::new(t.parse().ok()?, m.parse().ok()?).ok().map(Some)
    }

    /// The next decision point after `done` samples, or `spp` if there is none
    /// before it: the kernels render samples `done..round_end(done)` and then
    /// (if more remain) ask [`Adaptive::converged`].
    pub fn round_end(&self, done: u32, spp: u32) -> u32 {
        let mut c = self.min_spp.max(1) as u64;
        while c <= done as u64 {
            c *= 2;
        }
        c.min(spp as u64) as u32
    }

    /// Whether pixel `local` of `tile` has reached the threshold.
    #[inline]
    pub fn converged(&self, tile: &TileFilm, local: usize) -> bool {
        relative_error(&tile.moments(local)) <= self.threshold as f64
    }
}

/// The relative standard error of a pixel's mean: the standard error (root of
/// the channels' mean sample variance over the sample count) over the pixel's
/// mean value (the channels' average, at least [`RELATIVE_ERROR_FLOOR`]).
/// Infinite below 2 samples. It is computed from the very samples being
/// averaged, so stopping on it is slightly biased (docs/convergence.md).
pub fn relative_error(m: &Moments) -> f64 {
    let n = m.n as f64;
    if m.n < 2 {
        return f64::INFINITY;
    }
    let mut var = 0.0;
    let mut mean = 0.0;
    for k in 0..3 {
        var += ((m.sum_sq[k] - m.sum[k] * m.sum[k] / n) / (n - 1.0)).max(0.0);
        mean += m.sum[k] / n;
    }
    let se = (var / 3.0 / n).sqrt();
    se / (mean / 3.0).max(RELATIVE_ERROR_FLOOR)
}

/// The estimator's options, as the kernels see them (both off by default).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Estimator {
    pub roulette: Option<Roulette>,
    pub adaptive: Option<Adaptive>,
}

impl Estimator {
    /// The end of the round of samples that starts at `done` (see [`Adaptive::round_end`]).
    #[inline]
    pub fn round_end(&self, done: u32, spp: u32) -> u32 {
        match &self.adaptive {
            Some(a) => a.round_end(done, spp),
            None => spp,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptions_read_back() {
        for r in [None, Some(Roulette::new(1).unwrap()), Some(Roulette::default())] {
            assert_eq!(Roulette::from_description(&Roulette::describe(r)), Some(r));
        }
        for a in [None, Some(Adaptive::new(0.02, 64).unwrap()), Some(Adaptive::new(1e-7, 2).unwrap())] {
            assert_eq!(Adaptive::from_description(&Adaptive::describe(a)), Some(a));
        }
        for bad in ["", "after 0 rays", "after x rays", "threshold -1 from 64 spp", "threshold 0.1 from 1 spp", "on"] {
            assert_eq!(Roulette::from_description(bad).flatten(), None, "{bad}");
            assert!(Adaptive::from_description(bad).flatten().is_none(), "{bad}");
        }
    }

    #[test]
    fn decision_points_double_from_min() {
        let a = Adaptive::new(0.1, 16).unwrap();
        let ends: Vec<u32> = std::iter::successors(Some(0u32), |&d| (d < 100).then(|| a.round_end(d, 100))).collect();
        assert_eq!(ends, vec![0, 16, 32, 64, 100]);
        assert_eq!(a.round_end(0, 8), 8);
        assert_eq!(a.round_end(0, u32::MAX), 16);
        assert_eq!(a.round_end(1 << 31, u32::MAX), u32::MAX);
        assert_eq!(Estimator::default().round_end(0, 77), 77);
    }

    #[test]
    fn relative_error_of_known_samples() {
        let mut t = TileFilm::new(0, 0, 2, 1).with_moments();
        let err = |t: &TileFilm, l| relative_error(&t.moments(l));
        assert_eq!(err(&t, 0), f64::INFINITY);
        // Pixel 0: samples 1 and 3 in every channel: mean 2, variance 2, se 1.
        t.add(0, [1.0; 3]);
        assert_eq!(err(&t, 0), f64::INFINITY);
        t.add(0, [3.0; 3]);
        assert!((err(&t, 0) - 0.5).abs() < 1e-12);
        // Pixel 1: identical samples have no error; a dark noisy pixel is
        // measured against the floor.
        t.add(1, [0.5; 3]);
        t.add(1, [0.5; 3]);
        assert_eq!(err(&t, 1), 0.0);
        let mut d = TileFilm::new(0, 0, 1, 1).with_moments();
        d.add(0, [0.0; 3]);
        d.add(0, [0.02; 3]);
        let se = (0.0002f64 / 2.0).sqrt();
        assert!((err(&d, 0) - se / RELATIVE_ERROR_FLOOR).abs() < 1e-6);
        let a = Adaptive::new(0.6, 2).unwrap();
        assert!(a.converged(&t, 0) && !Adaptive::new(0.4, 2).unwrap().converged(&t, 0));
    }

    #[test]
    fn bad_adaptive_values_name_the_flag() {
        for t in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let e = Adaptive::new(t, 16).unwrap_err().to_string();
            assert!(e.starts_with("adaptive.threshold:"), "{e}");
        }
        let e = Adaptive::new(0.1, 1).unwrap_err().to_string();
        assert!(e.starts_with("adaptive.min_spp:"), "{e}");
    }
}
