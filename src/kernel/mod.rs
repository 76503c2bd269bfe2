//! The two kernels, and what they share: shading of misses and debug modes,
//! and the counters every kernel keeps the same way.

pub mod scalar;
pub mod wavefront;

use crate::plan::SkyColours;
use crate::real::Real;
use crate::vec3::V3;
use serde::Serialize;

/// Which kernel renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum KernelKind {
    /// One path at a time: the reference.
    Scalar,
    /// The wavefront kernel: 8-wide packets and a queue per material kind.
    Simd,
}

impl KernelKind {
    pub fn name(self) -> &'static str {
        match self {
            KernelKind::Scalar => "scalar",
            KernelKind::Simd => "simd",
        }
    }
}

/// Work counters; one ray = one closest-hit query against the scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub rays: u64,
    /// SIMD lanes doing real work / lanes issued, in intersection.
    pub isect_active: u64,
    pub isect_lanes: u64,
    /// The same in the scatter passes.
    pub scatter_active: u64,
    pub scatter_lanes: u64,
}

impl Counters {
    pub fn merge(&mut self, o: &Counters) {
        self.rays += o.rays;
        self.isect_active += o.isect_active;
        self.isect_lanes += o.isect_lanes;
        self.scatter_active += o.scatter_active;
        self.scatter_lanes += o.scatter_lanes;
    }
}

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
