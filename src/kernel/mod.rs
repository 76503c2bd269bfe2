//! The kernels: the scalar reference (one path at a time) and the wavefront
//! (queues of paths, packets of `W::LANES` rays, generic over the lane width),
//! and what they share: the sky, the debug shadings, path ids for probes.

pub mod scalar;
pub mod wavefront;

use crate::plan::SkyColours;
use crate::real::Real;
use crate::vec3::V3;

/// The sky seen in unit direction `d`: horizon to zenith by `0.5 (d.y + 1)`.
#[inline(always)]
pub fn sky<R: Real>(s: &SkyColours, d: V3<R>) -> V3<R> {
    let a = R::splat(0.5) * (d.y + R::splat(1.0));
    V3::splat3(s.horizon) * (R::splat(1.0) - a) + V3::splat3(s.zenith) * a
}

/// Chapter 5's normal shading, `0.5 (n + 1)`.
#[inline(always)]
pub fn normal_colour<R: Real>(n: V3<R>) -> V3<R> {
    (n + V3::splat3([1.0, 1.0, 1.0])) * R::splat(0.5)
}

/// Chapter 1's gradient at pixel (x, y) (y = 0 is the top row).
pub fn gradient(x: u32, y: u32, width: u32, height: u32) -> [f32; 3] {
    let j = height - 1 - y;
    [x as f32 / width as f32, j as f32 / height as f32, 0.2]
}
