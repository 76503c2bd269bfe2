//! Moving spheres (The Next Week's `sphere(center1, center2, r, mat)`): a
//! primitive kind of their own, structure of arrays, so a scene without them
//! pays nothing.
//!
//! A moving sphere's centre at time `t` in [0, 1) is
//! `c(t) = c0 + t v` with `v = center1 - c0` ([`centre_at`]), computed per lane
//! in f32 with one formula over [`Real`] (a product and a sum: no fused
//! multiply-add anywhere, so the scalar kernel and every lane width compute
//! the same bits). The hit test is then the static sphere test
//! ([`super::sphere_disc`], [`super::sphere_t`]) with that centre, and the
//! surface is [`super::surface()`] with that centre: the hit of a moving sphere
//! at time `t` *is* the hit of the static sphere at `c(t)`, bit for bit
//! (`tests/suite/motion.rs`). At `t = 0`, `c0 + 0 v` is exactly `c0`.
//!
//! The hit index of moving sphere `i` is `MOVING_BASE + i`: after every
//! sphere and every quad in the one order of the closest-hit tie rule, below
//! [`super::MISS`]. Its bounds in the BVH cover the shutter interval (the
//! union of its boxes at `t = 0` and `t = 1`), so traversal ignores time.

use super::hit::{Closest, MOVING_BASE};
use super::primitive::{Leaf, Primitive};
use super::quads::{next_down, next_up};
use super::slab::Aabb;
use super::spheres::{test_sphere, Shade, Spheres};
use super::work::Counter;
use crate::handle::Kind;
use crate::real::Real;
use crate::vec3::V3;

/// `c0 + t v`: the centre at time `t` of the sphere moving from `c0` by `v`.
#[inline(always)]
pub fn centre_at<R: Real>(c0: V3<R>, v: V3<R>, t: R) -> V3<R> {
    c0 + v * t
}

/// Moving spheres: their centre at time 0, radius and material handle in a
/// [`Spheres`] (with its padding and shading records: the centre there is
/// `c0`), and their motion `v` per sphere (padding included: zero), as
/// 32-byte records (`[vx, vy, vz, 0, ...]`) that a packet gathers as it
/// gathers the shading records.
#[derive(Clone, Debug, Default)]
pub struct MovingSpheres {
    pub s: Spheres,
    pub vel: Vec<Shade>,
}

impl MovingSpheres {
    /// Appends a sphere moving from `c0` (time 0) to `c1` (time 1): `v = c1 - c0`
    /// computed in f64 and rounded once.
    pub fn push(&mut self, c0: [f32; 3], c1: [f32; 3], radius: f32, kind: Kind, row: u32) {
        self.s.push(c0, radius, kind, row);
        let v: [f32; 3] = std::array::from_fn(|k| (c1[k] as f64 - c0[k] as f64) as f32);
        self.vel.push(Shade([v[0], v[1], v[2], 0.0, 0.0, 0.0, 0.0, 0.0]));
    }

    /// Pads to a power of two, at least 8, with spheres no ray can hit (see [`Spheres::pad`]).
    pub fn pad(&mut self) {
        self.s.pad();
        self.vel.resize(self.s.cx.len(), Shade::default());
    }

    pub fn len(&self) -> usize {
        self.s.len
    }

    pub fn is_empty(&self) -> bool {
        self.s.len == 0
    }

    /// The motion of sphere `i`.
    #[inline(always)]
    pub fn v(&self, i: usize) -> [f32; 3] {
        let [x, y, z, ..] = self.vel[i].0;
        [x, y, z]
    }

    /// The centre of sphere `i` at time 0.
    #[inline(always)]
    pub fn c0(&self, i: usize) -> [f32; 3] {
        [self.s.cx[i], self.s.cy[i], self.s.cz[i]]
    }

    /// The centre of sphere `i` at time `t` ([`centre_at`], one lane).
    #[inline(always)]
    pub fn centre(&self, i: usize, t: f32) -> V3<f32> {
        centre_at(V3::from_array(self.c0(i)), V3::from_array(self.v(i)), t)
    }

    /// The box of sphere `i` over the shutter interval: the union of its
    /// boxes at `t = 0` and `t = 1`, computed in f64 (every centre the
    /// kernels compute lies within a few units of roundoff of the segment
    /// between; the BVH's padding covers that many times over).
    pub fn swept(&self, i: usize) -> ([f64; 3], [f64; 3]) {
        let (c0, v, r) = (self.c0(i), self.v(i), self.s.r[i].abs() as f64);
        let lo = std::array::from_fn(|k| (c0[k] as f64).min(c0[k] as f64 + v[k] as f64) - r);
        let hi = std::array::from_fn(|k| (c0[k] as f64).max(c0[k] as f64 + v[k] as f64) + r);
        (lo, hi)
    }
}

/// A leaf's moving sphere: its centre at time 0, motion, squared radius and
/// hit index (`MOVING_BASE + i`).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct LeafMoving {
    c0: [f32; 3],
    v: [f32; 3],
    r2: f32,
    index: u32,
}

impl Leaf for LeafMoving {
    type Setup<R: Real> = ();
    type Lanes = ();
    #[inline(always)]
    fn setup<R: Real>(_o: V3<R>, _d: V3<R>) {}

    /// The centre at each lane's time ([`centre_at`]), then the static sphere test.
    #[inline(always)]
    fn test<R: Real, C: Counter>(
        &self,
        o: V3<R>,
        d: V3<R>,
        time: R,
        _setup: &(),
        best: &mut Closest<R>,
        counter: &mut C,
    ) {
        let c = centre_at(V3::splat3(self.c0), V3::splat3(self.v), time);
        test_sphere(best, o, d, c, R::splat(self.r2), self.index, counter);
    }
}

impl Primitive for MovingSpheres {
    type Leaf = LeafMoving;
    const GENERAL: bool = true;

    fn count(&self) -> usize {
        self.s.len
    }

    #[inline(always)]
    fn leaf(&self, i: usize) -> LeafMoving {
        LeafMoving { c0: self.c0(i), v: self.v(i), r2: self.s.r2[i], index: MOVING_BASE + i as u32 }
    }

    /// The union of its boxes at `t = 0` and `t = 1` ([`MovingSpheres::swept`]),
    /// rounded outwards and padded as the static spheres' are: the centre a
    /// kernel computes, `c0 + t v` in f32, lies within `2u (|c0| + |v|)` of
    /// the exact segment, far inside the padding.
    fn bounds(&self, i: usize, pad: f32) -> Aabb {
        let (lo, hi) = self.swept(i);
        Aabb { min: lo.map(|x| next_down(x) - pad), max: hi.map(|x| next_up(x) + pad) }
    }
}
