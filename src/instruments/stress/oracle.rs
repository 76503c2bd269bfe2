//! The f64 oracle: the sphere test of `geometry::intersect` in f64 on the same
//! f32 inputs, with the f32 kernel's error bounds, so every answer of the
//! kernel can be judged right, wrong, or inside the rounding band. Also the
//! textbook test (`b*b - 4ac`, `t_min = 0.001`), as a reference that never gates.

use super::v64;
use crate::vec3::V3;
use glam::DVec3;

pub const U: f64 = 1.0 / 16_777_216.0;

/// Every first-order bound below is multiplied by this, for the higher-order
/// terms the first-order analysis drops (each is O(u) relative to its term).
pub const SLACK: f64 = 1.01;

/// A direction within this of tangent (|cos| to the normal) leaves the surface
/// on a side decided by rounding: the spawn side test `dir . n >= 0` is computed
/// with an error below `3u + (|n| - 1) + (|dir| - 1) <= 12u`.
pub const SIDE_EPS: f64 = 16.0 * U;

/// The textbook's `t_min`.
pub const TEXTBOOK_T_MIN: f32 = 0.001;

/// Largest |z| (difference of means over its standard error) an image
/// comparison may show. Under the null hypothesis (same expected image) a
/// |z| above 5 has a probability below 1e-5 per statistic.
pub const Z_LIMIT: f64 = 5.0;

/// A ray as f64, exactly the f32 values the kernel was given.
#[derive(Clone, Copy, Debug)]
pub struct RayF64 {
    pub o: DVec3,
    /// The direction as given (|d| = 1 + eta, not exactly 1).
    pub d: DVec3,
    pub d_len: f64,
    /// Unit direction.
    pub dh: DVec3,
    /// `| |d| - 1 |`.
    pub eta: f64,
}

impl RayF64 {
    pub fn new(o: V3<f32>, d: V3<f32>) -> Self {
        let (o, d) = (v64(o), v64(d));
        let d_len = d.length();
        RayF64 { o, d, d_len, dh: d / d_len, eta: (d_len - 1.0).abs() }
    }

    /// The point at parameter `t` (in units of the f32 direction, as the kernel's `t`).
    pub fn at(&self, t: f64) -> DVec3 {
        self.o + self.d * t
    }
}

/// How a kernel's answer compares with the oracle's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HitVerdict {
    Right,
    /// Inside the rounding band of a bound: any answer is acceptable.
    InBand,
    Wrong,
}

/// What exact (f64) arithmetic says about one ray (given as f32) and one sphere,
/// with the error bounds of the f32 kernel on that ray.
///
/// Notation (as in `geometry/spheres.rs`): `f = o - c`, `b = f . d^`,
/// `h = |f - b d^|` (distance of the centre from the ray's line),
/// `disc = r^2 - h^2`, `cc = |f|^2 - r^2`, `eta = | |d| - 1 |`.
#[derive(Clone, Copy, Debug)]
pub struct Truth {
    /// |radius| and the signed radius.
    pub r: f64,
    pub r_signed: f64,
    pub f_len: f64,
    pub eta: f64,
    pub b: f64,
    pub h: f64,
    pub disc: f64,
    /// Bound on |disc computed by the kernel - disc|.
    pub e_disc: f64,
    pub cc: f64,
    /// Bound on |cc computed by the kernel - cc| (the sign of cc says inside/outside).
    pub e_c: f64,
    /// Both roots in the kernel's units of `t` (ascending), when `disc >= 0`.
    pub roots: Option<[f64; 2]>,
    /// The root at the origin when the origin is within `e_c` of the surface:
    /// the kernel may return it or skip it.
    pub optional: Option<usize>,
    /// The first positive root that is not optional: the answer the kernel owes.
    pub required: Option<f64>,
}

impl Truth {
    pub fn new(ray: &RayF64, c: DVec3, r_signed: f64) -> Truth {
        let r = r_signed.abs();
        let f = ray.o - c;
        let fl = f.length();
        let b = f.dot(ray.dh);
        let l = f - ray.dh * b;
        let h = l.length();
        let disc = (r - h) * (r + h);
        let eta = ray.eta;
        // |l computed - l|: f rounded (u|f|), b's dot (3u|f|, along d), the product
        // b d and the subtraction (u|f| + u|l|), and |d| != 1 (2 eta |f|, along d).
        let delta = (5.0 * U + 2.0 * eta + eta * eta) * fl + U * h;
        let e_disc = SLACK
            * (U * r * r
                + 3.0 * U * (h + delta) * (h + delta)
                + 4.0 * U * h * fl
                + 2.0 * U * h * h
                + delta * delta
                + U * disc.abs());
        let cc = (fl - r) * (fl + r);
        let e_c = SLACK * (5.0 * U * fl * fl + U * r * r + U * cc.abs());
        let mut tr = Truth {
            r,
            r_signed,
            f_len: fl,
            eta,
            b,
            h,
            disc,
            e_disc,
            cc,
            e_c,
            roots: None,
            optional: None,
            required: None,
        };
        if disc >= 0.0 {
            let s = disc.sqrt();
            let q = -(b + s.copysign(b));
            let (t1, t2) = if q != 0.0 { (cc / q, q) } else { (0.0, 0.0) };
            let roots = [t1.min(t2) / ray.d_len, t1.max(t2) / ray.d_len];
            tr.roots = Some(roots);
            if cc.abs() <= e_c {
                tr.optional = Some(if roots[0].abs() <= roots[1].abs() { 0 } else { 1 });
            }
            tr.required = (0..2).filter(|&i| Some(i) != tr.optional && roots[i] > 0.0).map(|i| roots[i]).next();
        }
        tr
    }

    /// The ray passes within the rounding band of tangency: the kernel's
    /// hit/miss decision may go either way.
    pub fn grazing(&self) -> bool {
        self.disc.abs() <= self.e_disc
    }

    /// The index of the root nearest to `t`.
    pub fn nearest(&self, t: f64) -> Option<usize> {
        self.roots.map(|r| if (r[0] - t).abs() <= (r[1] - t).abs() { 0 } else { 1 })
    }

    /// Judges a kernel's answer (hit at `t`, or miss) against this sphere alone.
    pub fn judge(&self, hit: bool, t: f64) -> HitVerdict {
        if self.grazing() {
            return HitVerdict::InBand;
        }
        if !hit {
            return if self.required.is_some() { HitVerdict::Wrong } else { HitVerdict::Right };
        }
        match (self.roots, self.nearest(t)) {
            (Some(roots), Some(i)) if Some(i) == self.optional || Some(roots[i]) == self.required => HitVerdict::Right,
            _ => HitVerdict::Wrong,
        }
    }

    /// Bound on the distance from the sphere of the point `o + t d` where the
    /// kernel reports a hit at `t` (see `geometry/spheres.rs`, "Error bounds").
    pub fn dist_bound(&self, t: f64) -> f64 {
        let (fl, r, h, eta) = (self.f_len, self.r, self.h, self.eta);
        let s = self.disc.max(0.0).sqrt();
        // The exact root of the computed quadratic, then the origin's rounding.
        let on_perturbed = (8.0 * U + 4.0 * eta) * fl + (7.0 * U + 2.0 * eta) * r + U * fl;
        // Rounding of the root returned as q (sqrt, add).
        let far_dt = U * r + U * (fl + r);
        // Returned as c / q: the constant term's inconsistency over |q|, and the division.
        let c_incons = (9.0 * U + 6.0 * eta) * fl * fl
            + 2.0 * U * r * r
            + U * self.cc.abs()
            + 2.0 * U * h * fl
            + 5.0 * U * h * h
            + U * self.disc.abs();
        let q_low = (self.b.abs() - (5.0 * U + 2.0 * eta) * fl).max(0.0)
            + (s - self.e_disc / (s + self.e_disc.sqrt())).max(0.0);
        let near_dt = if q_low > 0.0 { c_incons / q_low + 3.0 * U * t.abs() } else { f64::INFINITY };
        SLACK * (on_perturbed + far_dt.max(near_dt))
    }

    /// How far along the ray a root found at `t` may lie from the true one.
    pub fn t_tol(&self, t: f64) -> f64 {
        let s = self.disc.max(0.0).sqrt();
        let se = self.e_disc.sqrt();
        (self.dist_bound(t) * self.r + self.e_disc) / s.max(se).max(f64::MIN_POSITIVE)
    }

    /// The front/back face at root `i`, or `None` when the ray is too close to
    /// tangent there for the kernel's normal (from its rounded hit point) to decide.
    pub fn front_at(&self, ray: &RayF64, c: DVec3, i: usize) -> Option<bool> {
        let t = self.roots?[i];
        let p = ray.at(t);
        let cos = ray.dh.dot(p - c) / self.r;
        let band = (self.t_tol(t) + 2.0 * U * (t.abs() + p.length())) / self.r + SIDE_EPS;
        if cos.abs() <= band {
            None
        } else {
            Some(cos * self.r_signed.signum() < 0.0)
        }
    }
}

/// The textbook test (the book's first `hit_sphere`): `b*b - 4ac` in f32, the
/// first root above `t_min`. For comparison only; never used by the kernels.
pub fn textbook_hit(o: V3<f32>, d: V3<f32>, c: V3<f32>, r: f32, t_min: f32) -> Option<f32> {
    let oc = o - c;
    let a = d.dot(d);
    let b = 2.0 * oc.dot(d);
    let cc = oc.dot(oc) - r * r;
    let disc = b * b - 4.0 * a * cc;
    if !(disc >= 0.0) {
        return None;
    }
    let sq = disc.sqrt();
    [(-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a)].into_iter().find(|t| *t > t_min && t.is_finite())
}
