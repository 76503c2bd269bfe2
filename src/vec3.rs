//! `V3<R>`: a 3-vector of `Real`s (one ray, or the same component of 8 rays).
//!
//! Deliberately minimal and explicit about evaluation order: `dot` is
//! `(x*x' + y*y') + z*z'`, everywhere, for both widths.

use crate::real::Real;
use std::ops::{Add, Mul, Neg, Sub};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<R> {
    pub x: R,
    pub y: R,
    pub z: R,
}

impl<R: Real> V3<R> {
    #[inline(always)]
    pub fn new(x: R, y: R, z: R) -> Self {
        V3 { x, y, z }
    }
    #[inline(always)]
    pub fn splat3(v: [f32; 3]) -> Self {
        V3::new(R::splat(v[0]), R::splat(v[1]), R::splat(v[2]))
    }
    #[inline(always)]
    pub fn dot(self, o: Self) -> R {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    #[inline(always)]
    pub fn length_squared(self) -> R {
        self.dot(self)
    }
    /// `self / |self|` (one sqrt, one divide, three multiplies).
    #[inline(always)]
    pub fn normalize(self) -> Self {
        let inv = R::splat(1.0) / self.length_squared().sqrt();
        self * inv
    }
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        V3::new(self.y * o.z - self.z * o.y, self.z * o.x - self.x * o.z, self.x * o.y - self.y * o.x)
    }
    #[inline(always)]
    pub fn mul_elem(self, o: Self) -> Self {
        V3::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
    #[inline(always)]
    pub fn select(m: R::Mask, a: Self, b: Self) -> Self {
        V3::new(R::select(m, a.x, b.x), R::select(m, a.y, b.y), R::select(m, a.z, b.z))
    }
    /// Largest absolute component.
    #[inline(always)]
    pub fn max_abs(self) -> R {
        self.x.abs().max(self.y.abs()).max(self.z.abs())
    }
    /// Lane `k`: the vector of one ray.
    #[inline(always)]
    pub fn lane(self, k: usize) -> V3<f32> {
        V3::new(self.x.lane(k), self.y.lane(k), self.z.lane(k))
    }
}

impl<R: Real> Add for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        V3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl<R: Real> Sub for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        V3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl<R: Real> Neg for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        V3::new(-self.x, -self.y, -self.z)
    }
}

/// Vector times a real (per lane).
impl<R: Real> Mul<R> for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: R) -> Self {
        V3::new(self.x * s, self.y * s, self.z * s)
    }
}

impl V3<f32> {
    pub fn to_array(self) -> [f32; 3] {
        [self.x, self.y, self.z]
    }
    pub fn from_array(a: [f32; 3]) -> Self {
        V3::new(a[0], a[1], a[2])
    }
}
