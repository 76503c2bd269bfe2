//! Where a hit is and where the rays that leave it start: the hit surface
//! ([`Surface`]) every kind's shading reads, and [`spawn`], which moves a new
//! ray's origin off the surface by the kind's offset, to the side it leaves
//! by (self-hits are prevented there, not by a `t_min`).

use crate::real::Real;
use crate::vec3::V3;

/// What the shading needs to know about a hit.
#[derive(Clone, Copy, Debug)]
pub struct Surface<R: Real> {
    /// The hit point, re-projected onto the sphere.
    pub p: V3<R>,
    /// Unit normal facing against the ray (the book's `rec.normal`).
    pub n: V3<R>,
    /// The ray hit the outside (the side the signed radius's normal points to).
    pub front: R::Mask,
    /// Distance by which rays leaving `p` start off the surface (see [`spawn`]).
    pub offset: R,
}

/// `2^-20`: sixteen units of roundoff (`u = 2^-24`).
pub const OFFSET_ULPS: f32 = 1.0 / 1_048_576.0;

/// The origin of a new ray leaving `s.p` in direction `dir`: pushed off the
/// surface by `s.offset` to the side `dir` points to.
#[inline(always)]
pub fn spawn<R: Real>(s: &Surface<R>, dir: V3<R>) -> V3<R> {
    let side = dir.dot(s.n).ge(R::splat(0.0));
    let off = R::select(side, s.offset, -s.offset);
    s.p + s.n * off
}
