//! Directions toward the shapes a scene samples (The Rest of Your Life's
//! `lights` list, rtow's `sample_toward`), over `Real`, so that the scalar
//! kernel and every lane width compute the same bits.
//!
//! Two operations per shape, as the book's `hittable::random` and
//! `hittable::pdf_value`, each in solid angle at a point `x`:
//! - a quad: a uniform point on the parallelogram; the density of a
//!   direction that meets it at distance `t` with cosine `c` to its normal
//!   is `t^2 / (|c| area)`, 0 where the ray misses it;
//! - a sphere seen from outside: a uniform direction in the cone it
//!   subtends; the density is `1 / (2 pi (1 - cos theta_max))` inside the
//!   cone, 0 outside. The book evaluates `sqrt(1 - r^2 / d^2)` from inside
//!   the sphere too (a NaN); here a point inside or on the sphere samples
//!   the uniform sphere of directions (density `1 / 4 pi`: each of them
//!   meets it). `1 - cos theta_max` is computed as `s / (1 + sqrt(1 - s))`
//!   with `s = r^2 / d^2`, without the cancellation of `1 - sqrt(1 - s)`
//!   for a small or far sphere.
//!
//! # Which directions have a density
//!
//! A density must be positive for every direction its sampler draws, as the
//! computer rounds it: a drawn direction judged outside its shape is weighted
//! as if the shape could not have drawn it (`book`: by the material's density
//! alone, so it brings the light's full radiance, `L`, where its share is
//! `L` times the light's tiny solid angle; `nee-mis`: the sample is lost).
//! A test of the exact shape misjudges a fraction of the drawn directions
//! near its outline of the order of the rounding error over the shape's
//! size, and that error grows as the shape shrinks or moves away. The old
//! sphere test (`d . oc >= (1 - (1 - cos theta_max)) |oc|`) compared two
//! cosines that differ by less than their rounding near the outline of a
//! small cone (and rounds `cos theta_max` to 1 below `r / d = 2.4e-4`):
//! `rtow stress`'s family `small-lights` measures what that did to the
//! image (docs/stability.md).
//!
//! So each shape's test is widened by a bound on that rounding, computed
//! from the query's own distances (never the scene's extent), with a margin:
//! - a sphere: the ray passes within `r + 64u |oc|` of the centre, measured
//!   as the sphere's hit test measures it (`|oc - (oc . d) d|`, which rounds
//!   to about `6u |oc|`, plus the sampled direction's own error of a few
//!   `u`);
//! - a quad: its plane coordinates `a`, `b` within `[-tol, 1 + tol]`, with
//!   `tol = 64u (|x|_inf + t + |Q|_inf + |u|_inf + |v|_inf) |v| / |u x v|`
//!   (for `a`; `|u|` for `b`): the error of the hit point relative to `Q`,
//!   over the parallelogram's height.
//!
//! A direction in the band that misses the shape itself is given the
//! shape's density too; what that costs is the radiance behind the band,
//! weighted down: at most the band's solid angle times the background, a
//! relative `~1e-4` of the light's own contribution at `r / d = 1e-4`.
//!
//! - a mesh of `diffuse_light`: a point uniform over its surface, with
//!   the densities of [`super::light_mesh`] (of a point for `nee-mis`, of
//!   a direction, summed over the triangles along it, for `book`).
//!
//! A list samples one of its shapes, uniformly (its density is the average
//! of the shapes'). The shapes' densities are evaluated for every lane and
//! each lane keeps its own: the list is short (at most
//! [`crate::limits::MAX_SAMPLED_SHAPES`]) and the same for every lane.

use super::light_mesh::LightMesh;
use super::spheres::{sphere_disc, sphere_t};
use crate::real::Real;
use crate::sampling::cos_sin_turn;
use crate::vec3::V3;

const PI: f32 = std::f32::consts::PI;

/// A quad of the list, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightQuad {
    pub q: [f32; 3],
    pub u: [f32; 3],
    pub v: [f32; 3],
    /// The unit normal `u x v / |u x v|` and the plane's offset `n . q`.
    pub n: [f32; 3],
    pub d: f32,
    /// `(u x v) / |u x v|^2`: the plane coordinates of a point `p` are
    /// `a = w . ((p - q) x v)`, `b = w . (u x (p - q))`.
    pub w: [f32; 3],
    /// `|u x v|`.
    pub area: f32,
    /// The edge tolerances' scales: `tol_a = ta (|x|_inf + t + ext)` (and
    /// `tol_b` with `tb`), in units of `a` and `b` (see the module).
    pub ta: f32,
    pub tb: f32,
    /// `|Q|_inf + |u|_inf + |v|_inf`.
    pub ext: f32,
}

/// The light tests' rounding bands: `64u` per unit of distance (see the module).
const BAND: f32 = 64.0 / 16_777_216.0;

/// A sphere of the list: centre and (positive) radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSphere {
    pub c: [f32; 3],
    pub r: f32,
}

/// The shapes a scene samples toward: quads first, then spheres, then
/// meshes (the order a uniform pick counts them in).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lights {
    pub quads: Vec<LightQuad>,
    pub spheres: Vec<LightSphere>,
    pub meshes: Vec<LightMesh>,
}

impl LightQuad {
    /// The quad `q + a u + b v`, its derived values computed in f64.
    pub fn new(q: [f32; 3], u: [f32; 3], v: [f32; 3]) -> LightQuad {
        let d = |a: [f32; 3]| glam::DVec3::from_array(a.map(f64::from));
        let f = |a: glam::DVec3| a.to_array().map(|x| x as f32);
        let nraw = d(u).cross(d(v));
        let n = nraw.normalize();
        let inf = |a: [f32; 3]| a.iter().fold(0.0f32, |m, x| m.max(x.abs()));
        let height = |e: [f32; 3]| d(e).length() / nraw.length();
        LightQuad {
            q,
            u,
            v,
            n: f(n),
            d: n.dot(d(q)) as f32,
            w: f(nraw / nraw.length_squared()),
            area: nraw.length() as f32,
            ta: (BAND as f64 * height(v)) as f32,
            tb: (BAND as f64 * height(u)) as f32,
            ext: inf(q) + inf(u) + inf(v),
        }
    }
}

impl Lights {
    pub fn len(&self) -> usize {
        self.quads.len() + self.spheres.len() + self.meshes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// A direction from `x` toward a shape of the list: shape
    /// `floor(pick n)` (clamped to the list), at the point or in the cone
    /// that `u1`, `u2` (uniform in [0, 1)) choose. Unit length.
    #[inline(always)]
    pub fn sample<R: Real>(&self, x: V3<R>, pick: R, u1: R, u2: R) -> V3<R> {
        let n = self.len();
        debug_assert!(n > 0, "a light sample needs a shape");
        let which = (pick * R::splat(n as f32)).floor().min(R::splat((n - 1) as f32));
        let mut dir = V3::new(R::splat(0.0), R::splat(1.0), R::splat(0.0));
        for (k, l) in self.quads.iter().enumerate() {
            let p = V3::splat3(l.q) + V3::splat3(l.u) * u1 + V3::splat3(l.v) * u2;
            let toward = unit_toward(x, p, V3::splat3(l.n));
            dir = V3::select(which.eq(R::splat(k as f32)), toward, dir);
        }
        let base = self.quads.len();
        for (k, s) in self.spheres.iter().enumerate() {
            let toward = sphere_sample(s, x, u1, u2);
            dir = V3::select(which.eq(R::splat((base + k) as f32)), toward, dir);
        }
        if !self.meshes.is_empty() {
            dir = self.toward_meshes(x, (pick, which), u1, u2, dir);
        }
        dir
    }

    /// [`Lights::sample`]'s meshes: the lanes whose pick `which` is a mesh
    /// get a direction toward a point on it (out of line: the scenes
    /// without mesh lights keep the code they had).
    #[inline(never)]
    #[cold]
    fn toward_meshes<R: Real>(&self, x: V3<R>, (pick, which): (R, R), u1: R, u2: R, mut dir: V3<R>) -> V3<R> {
        // What is left of `pick` past the choice of shape picks the triangle.
        let base = self.quads.len() + self.spheres.len();
        let sub = pick * R::splat(self.len() as f32) - which;
        for (k, m) in self.meshes.iter().enumerate() {
            let (p, nm) = m.points(sub, u1, u2);
            let toward = unit_toward(x, p, nm);
            dir = V3::select(which.eq(R::splat((base + k) as f32)), toward, dir);
        }
        dir
    }

    /// The sum of the meshes' densities of `dir` from `x` (out of line).
    #[inline(never)]
    #[cold]
    fn meshes_pdf<R: Real>(&self, x: V3<R>, dir: V3<R>) -> R {
        self.meshes.iter().fold(R::splat(0.0), |sum, m| sum + m.pdf_lines(x, dir))
    }

    /// The density (solid angle, at `x`) of the unit direction `dir` under
    /// [`Lights::sample`]: the average of the shapes' densities.
    #[inline(always)]
    pub fn pdf<R: Real>(&self, x: V3<R>, dir: V3<R>) -> R {
        let mut sum = R::splat(0.0);
        for l in &self.quads {
            sum = sum + quad_pdf(l, x, dir);
        }
        for s in &self.spheres {
            sum = sum + sphere_pdf(s, x, dir);
        }
        if !self.meshes.is_empty() {
            sum = sum + self.meshes_pdf(x, dir);
        }
        sum * R::splat(1.0 / self.len() as f32)
    }
}

/// The emitters the `nee-mis` estimator samples (next-event estimation):
/// the scene's static light spheres, quads and meshes as shapes (in
/// [`Lights`]' order: quads, spheres, meshes), each one's radiance and
/// sidedness, and the way back from a light primitive that a path hits to
/// its shape.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Emitters {
    pub shapes: Lights,
    /// Per shape: its emitted radiance and whether it emits from its front face only.
    pub emit: Vec<[f32; 3]>,
    pub one_sided: Vec<bool>,
    /// Per row of the light material table (one row per light primitive):
    /// the index of its shape, or [`Emitters::UNSAMPLED`] (a moving light,
    /// which only the scattered directions reach).
    pub of_row: Vec<u32>,
}

/// A light sample seen from a point: the unit direction toward it, the
/// distance to the light along it, its density (solid angle, over the
/// whole list) and the radiance the light sends back along it. Where the
/// sample is unusable (the point on the light itself, a cone direction that
/// rounding made miss the sphere) the density is 0.
#[derive(Clone, Copy, Debug)]
pub struct LightSample<R: Real> {
    pub dir: V3<R>,
    pub t: R,
    pub pdf: R,
    pub emit: V3<R>,
}

impl Emitters {
    /// The shape index of a light that is not sampled.
    pub const UNSAMPLED: u32 = u32::MAX;

    pub fn len(&self) -> usize {
        self.shapes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// A light sample from `x`: shape `floor(pick n)`, then a uniform point
    /// on a quad or a uniform direction in the cone of a sphere (`u1`, `u2`),
    /// as [`Lights::sample`] draws them. Every lane evaluates every shape and
    /// keeps its own.
    #[inline(always)]
    pub fn sample<R: Real>(&self, x: V3<R>, pick: R, u1: R, u2: R) -> LightSample<R> {
        let n = self.len();
        debug_assert!(n > 0, "a light sample needs a light");
        let zero = R::splat(0.0);
        let one = R::splat(1.0);
        let which = (pick * R::splat(n as f32)).floor().min(R::splat((n - 1) as f32));
        let up = V3::new(zero, one, zero);
        let mut out = LightSample { dir: up, t: zero, pdf: zero, emit: V3::new(zero, zero, zero) };
        let lights = &self.shapes;
        for (k, l) in lights.quads.iter().enumerate() {
            let p = V3::splat3(l.q) + V3::splat3(l.u) * u1 + V3::splat3(l.v) * u2;
            let take = which.eq(R::splat(k as f32));
            out = self.toward_point(x, Drawn { shape: k, p, n: V3::splat3(l.n), area: l.area }, take, out);
        }
        let base = lights.quads.len();
        for (k, s) in lights.spheres.iter().enumerate() {
            let dir = sphere_sample(s, x, u1, u2);
            let r2 = R::splat(s.r * s.r);
            // A drawn direction that rounding put just outside the sphere
            // (in the band) meets it at its closest point.
            // From inside, every direction meets it (the far root).
            let (in_band, disc, g, b) = sphere_band(s, x, dir);
            let (_, t) = sphere_t(disc.max(zero), g, b, r2);
            let outside = g.length_squared().gt(r2);
            let inside = g.length_squared().le(r2);
            let pdf = R::select((in_band | inside) & t.gt(zero), sphere_pdf(s, x, dir), zero);
            let j = base + k;
            let emit = emission(V3::splat3(self.emit[j]), mask::<R>(self.one_sided[j]), outside);
            let take = which.eq(R::splat(j as f32));
            out = LightSample {
                dir: V3::select(take, dir, out.dir),
                t: R::select(take, t, out.t),
                pdf: R::select(take, pdf, out.pdf),
                emit: V3::select(take, emit, out.emit),
            };
        }
        if !lights.meshes.is_empty() {
            out = self.sample_meshes(x, (pick, which), u1, u2, out);
        }
        out.pdf = out.pdf * R::splat(1.0 / n as f32);
        out
    }

    /// [`Emitters::sample`]'s meshes: the lanes whose pick `which` is a
    /// mesh get a point on it (out of line: the scenes without mesh lights
    /// keep the code they had).
    #[inline(never)]
    #[cold]
    fn sample_meshes<R: Real>(
        &self,
        x: V3<R>,
        (pick, which): (R, R),
        u1: R,
        u2: R,
        mut out: LightSample<R>,
    ) -> LightSample<R> {
        // What is left of `pick` past the choice of shape picks the triangle.
        let lights = &self.shapes;
        let base = lights.quads.len() + lights.spheres.len();
        let sub = pick * R::splat(self.len() as f32) - which;
        for (k, m) in lights.meshes.iter().enumerate() {
            let (p, nm) = m.points(sub, u1, u2);
            let take = which.eq(R::splat((base + k) as f32));
            out = self.toward_point(x, Drawn { shape: base + k, p, n: nm, area: m.area }, take, out);
        }
        out
    }

    /// [`Emitters::pdf_of`]'s meshes: the density of the point hit, in the
    /// lanes whose shape is a mesh (out of line).
    #[inline(never)]
    #[cold]
    fn meshes_pdf_of<R: Real>(&self, x: V3<R>, dir: V3<R>, (shape, hit): (R::U32, R::U32), mut pdf: R) -> R {
        let lights = &self.shapes;
        let base = lights.quads.len() + lights.spheres.len();
        for (k, m) in lights.meshes.iter().enumerate() {
            let mine = R::u_eq(shape, R::u_splat((base + k) as u32));
            pdf = R::select(mine, m.pdf_hits(x, dir, hit, mine), pdf);
        }
        pdf
    }

    /// A light sample from `x` toward the point drawn on a quad or a mesh,
    /// in the lanes of `take` (`out` in the others): density `t^2 / (|cos|
    /// area)`, 0 where that is not finite (`x` on the light, an edge-on
    /// direction, no area).
    #[inline(always)]
    fn toward_point<R: Real>(&self, x: V3<R>, drawn: Drawn<R>, take: R::Mask, out: LightSample<R>) -> LightSample<R> {
        let Drawn { shape: k, p, n, area } = drawn;
        let (zero, one) = (R::splat(0.0), R::splat(1.0));
        let to = p - x;
        let len2 = to.length_squared();
        let t = len2.sqrt();
        let dir = to * (one / t);
        let cos = n.dot(dir);
        let pdf = len2 / (cos.abs() * R::splat(area));
        let ok = len2.gt(zero) & pdf.is_finite();
        let emit = emission(V3::splat3(self.emit[k]), mask::<R>(self.one_sided[k]), cos.lt(zero));
        LightSample {
            dir: V3::select(take & ok, dir, out.dir),
            t: R::select(take, t, out.t),
            pdf: R::select(take, R::select(ok, pdf, zero), out.pdf),
            emit: V3::select(take, emit, out.emit),
        }
    }

    /// The density (solid angle, at `x`, over the whole list) with which
    /// [`Emitters::sample`] draws the unit direction `dir` toward shape
    /// `shape` (per lane; [`Emitters::UNSAMPLED`]: 0): the density of the
    /// light a path hit (hit index `hit`: a mesh's density is that of the
    /// point on the triangle hit), for the weight of its emission. Only that
    /// shape's: a light sample toward another shape along the same line
    /// would be blocked by this one.
    #[inline(always)]
    pub fn pdf_of<R: Real>(&self, x: V3<R>, dir: V3<R>, shape: R::U32, hit: R::U32) -> R {
        let zero = R::splat(0.0);
        let mut pdf = zero;
        let lights = &self.shapes;
        for (k, l) in lights.quads.iter().enumerate() {
            pdf = R::select(R::u_eq(shape, R::u_splat(k as u32)), quad_pdf(l, x, dir), pdf);
        }
        let base = lights.quads.len();
        for (k, s) in lights.spheres.iter().enumerate() {
            pdf = R::select(R::u_eq(shape, R::u_splat((base + k) as u32)), sphere_pdf(s, x, dir), pdf);
        }
        if !lights.meshes.is_empty() {
            pdf = self.meshes_pdf_of(x, dir, (shape, hit), pdf);
        }
        pdf * R::splat(1.0 / self.len().max(1) as f32)
    }
}

/// A point drawn on shape `shape` of the list (a quad or a mesh), the unit
/// normal there, and the shape's whole area.
struct Drawn<R: Real> {
    shape: usize,
    p: V3<R>,
    n: V3<R>,
    area: f32,
}

/// The radiance a light emits towards a ray that hit it: `emit`, or 0 on the
/// back face (`front` false) of a one-sided light (`one_sided` true). The
/// kernels' light passes weigh a hit light by it, and [`Emitters::sample`]
/// a sampled one.
#[inline(always)]
pub fn emission<R: Real>(emit: V3<R>, one_sided: R::Mask, front: R::Mask) -> V3<R> {
    V3::select(one_sided & !front, V3::splat3([0.0; 3]), emit)
}

/// The unit direction from `x` toward the drawn point `p`, or `fallback`
/// (the shape's normal) where `x` is `p` itself: any direction does there,
/// its density being 0.
#[inline(always)]
fn unit_toward<R: Real>(x: V3<R>, p: V3<R>, fallback: V3<R>) -> V3<R> {
    let to = p - x;
    let len2 = to.length_squared();
    V3::select(len2.gt(R::splat(0.0)), to * (R::splat(1.0) / len2.sqrt()), fallback)
}

/// A mask of every lane set to `b`.
#[inline(always)]
fn mask<R: Real>(b: bool) -> R::Mask {
    R::splat(if b { 1.0 } else { 0.0 }).gt(R::splat(0.5))
}

/// The density of `dir` from `x` toward quad `l`: `t^2 / (|n . dir| area)`
/// where the ray `x + t dir` (t > 0) meets the parallelogram, else 0.
#[inline(always)]
pub fn quad_pdf<R: Real>(l: &LightQuad, x: V3<R>, dir: V3<R>) -> R {
    let zero = R::splat(0.0);
    let one = R::splat(1.0);
    let n = V3::splat3(l.n);
    let denom = n.dot(dir);
    let cos = denom.abs();
    let t = (R::splat(l.d) - n.dot(x)) / denom;
    let p = x + dir * t - V3::splat3(l.q);
    let w = V3::splat3(l.w);
    let a = w.dot(p.cross(V3::splat3(l.v)));
    let b = w.dot(V3::splat3(l.u).cross(p));
    // The rounding band (see the module): from this query's distances.
    let reach = x.max_abs() + t.abs() + R::splat(l.ext);
    let (ta, tb) = (reach * R::splat(l.ta), reach * R::splat(l.tb));
    let inside = a.ge(-ta) & a.le(one + ta) & b.ge(-tb) & b.le(one + tb);
    let hit = cos.gt(R::splat(1e-8)) & t.gt(zero) & inside;
    // Where `hit` is false the quotient may be infinite or NaN; it is not kept.
    R::select(hit, t * t / (cos * R::splat(l.area)), zero)
}

/// `(s, 1 - cos theta_max)` of sphere `s` seen from `x`: `s = r^2 / d^2`
/// (at least 1: `x` inside or on the sphere) and the cone's `1 - cos`.
#[inline(always)]
fn cone<R: Real>(s: &LightSphere, x: V3<R>) -> (V3<R>, R, R) {
    let oc = V3::splat3(s.c) - x;
    let d2 = oc.length_squared();
    let ratio = R::splat(s.r * s.r) / d2;
    let one = R::splat(1.0);
    let one_minus_cos = ratio / (one + (one - ratio).max(R::splat(0.0)).sqrt());
    (oc, ratio, one_minus_cos)
}

/// Whether the line `x + t dir` (`t > 0`, unit `dir`) passes within the
/// rounding band of sphere `s` (see the module), with the sphere test's
/// `(disc, g, b')` ([`sphere_disc`]): `b' > 0` and `|l| <= r + 64u |g|`,
/// `l = g - b' dir` the offset of the closest point from the centre.
#[inline(always)]
fn sphere_band<R: Real>(s: &LightSphere, x: V3<R>, dir: V3<R>) -> (R::Mask, R, V3<R>, R) {
    let r = R::splat(s.r);
    let (disc, g, b) = sphere_disc(x, dir, V3::splat3(s.c), r * r);
    let delta = g.length_squared().sqrt() * R::splat(BAND);
    // |l|^2 <= (r + delta)^2, i.e. disc = r^2 - |l|^2 >= -(2r + delta) delta.
    let in_band = b.gt(R::splat(0.0)) & disc.ge(-((r + r + delta) * delta));
    (in_band, disc, g, b)
}

/// The density of `dir` from `x` toward sphere `s` (see the module): the
/// cone's uniform density for a direction in the sphere's rounding band.
#[inline(always)]
pub fn sphere_pdf<R: Real>(s: &LightSphere, x: V3<R>, dir: V3<R>) -> R {
    let (_, ratio, one_minus_cos) = cone(s, x);
    let one = R::splat(1.0);
    let inside = ratio.ge(one);
    let (in_cone, ..) = sphere_band(s, x, dir);
    let cone_pdf = R::select(in_cone, one / (R::splat(2.0 * PI) * one_minus_cos), R::splat(0.0));
    R::select(inside, R::splat(1.0 / (4.0 * PI)), cone_pdf)
}

/// A direction from `x` toward sphere `s`: uniform in the cone it subtends
/// (cos theta uniform in [cos theta_max, 1], the angle `2 pi (u1 - 1/2)`
/// around the axis), or uniform over the sphere of directions from inside.
#[inline(always)]
pub fn sphere_sample<R: Real>(s: &LightSphere, x: V3<R>, u1: R, u2: R) -> V3<R> {
    let (oc, ratio, one_minus_cos) = cone(s, x);
    let one = R::splat(1.0);
    let inside = ratio.ge(one);
    // 1 - cos theta: in [0, 1 - cos theta_max] in the cone, [0, 2] inside.
    let omc = u2 * R::select(inside, R::splat(2.0), one_minus_cos);
    let z = one - omc;
    let sin = (omc * (R::splat(2.0) - omc)).max(R::splat(0.0)).sqrt();
    let (c, sn) = cos_sin_turn(u1);
    let (lx, ly) = (sin * c, sin * sn);
    // The axis: toward the centre (any axis from inside; the centre itself
    // may be `x`).
    let len2 = oc.length_squared();
    let axis = V3::select(
        inside | len2.eq(R::splat(0.0)),
        V3::new(R::splat(0.0), R::splat(0.0), one),
        oc * (one / len2.sqrt()),
    );
    let (t1, t2) = basis(axis);
    (t1 * lx + t2 * ly + axis * z).normalize()
}

/// Two unit vectors that make an orthonormal basis with the unit vector `w`
/// (Duff et al., "Building an Orthonormal Basis, Revisited", 2017): no
/// division by a small number, branch-free.
#[inline(always)]
pub fn basis<R: Real>(w: V3<R>) -> (V3<R>, V3<R>) {
    let one = R::splat(1.0);
    let sign = R::select(w.z.ge(R::splat(0.0)), one, R::splat(-1.0));
    let a = R::splat(-1.0) / (sign + w.z);
    let b = w.x * w.y * a;
    let t1 = V3::new(one + sign * w.x * w.x * a, sign * b, -(sign * w.x));
    let t2 = V3::new(b, sign + w.y * w.y * a, -w.y);
    (t1, t2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_basis_is_orthonormal() {
        for w in [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.6, 0.0, 0.8], [0.0, -0.6, -0.8], [1.0, 0.0, 0.0]] {
            let w = V3::<f32>::from_array(w);
            let (t1, t2) = basis(w);
            for (a, b) in [(t1, t2), (t1, w), (t2, w)] {
                assert!(a.dot(b).abs() < 1e-6);
            }
            for v in [t1, t2] {
                assert!((v.length_squared() - 1.0).abs() < 1e-6);
            }
        }
    }
}
