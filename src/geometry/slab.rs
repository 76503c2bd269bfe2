//! Rays against axis-aligned boxes (the slab test) and the boxes
//! themselves: what a tree's walk tests at every node, conservative by the
//! bounds in [`super::bvh`]'s module documentation.

use crate::real::Real;
use crate::vec3::V3;

/// Every primitive's box is padded by `2 D PAD` on every side, `D` bounding
/// the coordinates of the scene's rays and primitives (`2^-19`).
pub const PAD: f32 = 1.0 / 524_288.0;
/// 1 + 2 gamma_3 with gamma_3 = 3u / (1 - 3u), rounded up.
pub const EXIT_SCALE: f32 = 1.0 + 2.0 * (3.0 / 16_777_216.0) * 1.000_001;
/// Prune a box only when its entry is beyond `best * PRUNE_SCALE`.
pub const PRUNE_SCALE: f32 = 1.0 + 1.0 / 1_048_576.0;
/// Directions components smaller than this are replaced by it (with their
/// sign) in the slab test, so that `0 * inf` never makes a NaN.
const TINY_DIR: f32 = 1e-30;

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: [f32; 3],
    pub max: [f32; 3],
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb { min: [f32::INFINITY; 3], max: [f32::NEG_INFINITY; 3] };

    /// The box `[min - pad, max + pad]`.
    pub fn padded(min: [f32; 3], max: [f32; 3], pad: f32) -> Aabb {
        Aabb { min: min.map(|x| x - pad), max: max.map(|x| x + pad) }
    }

    /// Grows the box to hold `o`. Boxes hold no NaN (a scene's coordinates
    /// are finite), so a select does: one `minss`/`maxss` each, where
    /// `f32::min` takes three instructions and a conditional store a branch
    /// that random boxes mispredict (a tree's build grows boxes more than it
    /// does anything).
    #[inline]
    pub fn grow(&mut self, o: &Aabb) {
        for a in 0..3 {
            self.min[a] = if o.min[a] < self.min[a] { o.min[a] } else { self.min[a] };
            self.max[a] = if o.max[a] > self.max[a] { o.max[a] } else { self.max[a] };
        }
    }

    pub fn area(&self) -> f32 {
        let e: [f32; 3] = std::array::from_fn(|a| (self.max[a] - self.min[a]).max(0.0));
        2.0 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0])
    }

    pub fn centre(&self) -> [f32; 3] {
        std::array::from_fn(|k| 0.5 * self.min[k] + 0.5 * self.max[k])
    }
}

/// `1 / x` per lane; components smaller than `TINY_DIR` are replaced by it
/// (with their sign), so the slab test never computes `0 * inf` (the
/// boxes' slab tests and the cuboids', [`super::cuboids`]).
#[inline(always)]
pub fn inv_lanes<R: Real>(x: R) -> R {
    let tiny = R::splat(TINY_DIR);
    R::splat(1.0) / R::select(x.abs().lt(tiny), tiny.copysign(x), x)
}

/// What the slab test needs of the rays `o + t d`: `1/d` (see [`inv_lanes`])
/// and `-(o * (1/d))`.
#[inline(always)]
pub fn slab_ray<R: Real>(o: V3<R>, d: V3<R>) -> (V3<R>, V3<R>) {
    let inv = V3::new(inv_lanes(d.x), inv_lanes(d.y), inv_lanes(d.z));
    (inv, -o.mul_elem(inv))
}

/// Entry and exit distances of the rays through boxes, entry clamped at
/// `zero` (0, passed in so that a caller can make it opaque), given
/// [`slab_ray`]'s `1/d` and `-(o * (1/d))`: each face's distance is one
/// fused multiply-add (see the error bounds in [`super::bvh`]).
#[inline(always)]
pub fn slab<R: Real>(bmin: V3<R>, bmax: V3<R>, inv: V3<R>, noi: V3<R>, zero: R) -> (R, R) {
    let face = |b: R, inv: R, noi: R| b.mul_add_bound(inv, noi);
    let t0 = V3::new(face(bmin.x, inv.x, noi.x), face(bmin.y, inv.y, noi.y), face(bmin.z, inv.z, noi.z));
    let t1 = V3::new(face(bmax.x, inv.x, noi.x), face(bmax.y, inv.y, noi.y), face(bmax.z, inv.z, noi.z));
    // No NaN can arise (|1/d| <= 1e30, finite coordinates) and the test only
    // needs to be conservative, so the one-instruction min/max do.
    let near = t0.x.fast_min(t1.x).fast_max(t0.y.fast_min(t1.y)).fast_max(t0.z.fast_min(t1.z)).fast_max(zero);
    let far = t0.x.fast_max(t1.x).fast_min(t0.y.fast_max(t1.y)).fast_min(t0.z.fast_max(t1.z));
    (near, far)
}
