//! Hits: which primitive a ray hit, as one `u32` whose range names the kind
//! ([`HitKind`]) and whose offset in it the primitive, and the closest-hit
//! rule every search uses ([`Closest`]).
//!
//! One tie order across kinds: hit indices are spheres `i`, then
//! `QUAD_BASE + i` (quads, a cuboid's hit being its face's), then
//! `TRIANGLE_BASE + i` (the meshes' triangles), then `MOVING_BASE + i`,
//! then `INSTANCE_BASE + i` (instanced meshes' triangles), then
//! `MEDIUM_BASE + k`, below `MISS`; the smallest `t` wins, ties to the
//! lowest index, so brute force and every walk find the same hit bit for
//! bit whatever the order the kinds are searched in. The
//! wavefront tells kinds apart lane by lane with one compare against a base;
//! scalar code decodes a hit with [`Hit::of`].

use crate::real::{Mask, Real};

/// The hit index of "no hit".
pub const MISS: u32 = u32::MAX;

/// The hit index of quad `i` is `QUAD_BASE + i`: every quad comes after every
/// sphere in the tie order (spheres are fewer than `2^20`), and below
/// [`MOVING_BASE`].
pub const QUAD_BASE: u32 = 1 << 30;

/// The hit index of triangle `i` of the scene's meshes (world space) is
/// `TRIANGLE_BASE + i`: above every quad's (`QUAD_BASE + i`, `i < 2^28`:
/// `crate::limits::MAX_QUADS`), below [`MOVING_BASE`] (`i < 2^28`:
/// `crate::limits::MAX_SCENE_TRIANGLES`).
pub const TRIANGLE_BASE: u32 = QUAD_BASE + (1 << 28);

/// The hit index of moving sphere `i` is `MOVING_BASE + i`: above every
/// triangle's (`TRIANGLE_BASE + i`, `i < 2^28`), below [`INSTANCE_BASE`].
pub const MOVING_BASE: u32 = 3 << 29;

/// The hit index of an instanced mesh's triangle is `INSTANCE_BASE + i`,
/// `i` its place among every instance's triangles (`super::Instances`):
/// above every moving sphere's (fewer than `2^20`), below [`MEDIUM_BASE`]
/// (`i < 2^30`: `crate::limits::MAX_INSTANCED_TRIANGLES`).
pub const INSTANCE_BASE: u32 = 1 << 31;

/// The hit index of medium `k` is `MEDIUM_BASE + k`: above every instanced
/// triangle's, below [`MISS`].
pub const MEDIUM_BASE: u32 = 3 << 30;

/// The kinds a hit can name, in the tie order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HitKind {
    Sphere,
    /// A quad, loose or a cuboid's face.
    Quad,
    /// A triangle of the scene's meshes (world space).
    Triangle,
    Moving,
    /// A triangle of an instanced mesh.
    Instance,
    /// A scattering event inside a constant medium.
    Medium,
    Miss,
}

impl HitKind {
    /// The first hit index of the kind.
    pub const fn base(self) -> u32 {
        match self {
            HitKind::Sphere => 0,
            HitKind::Quad => QUAD_BASE,
            HitKind::Triangle => TRIANGLE_BASE,
            HitKind::Moving => MOVING_BASE,
            HitKind::Instance => INSTANCE_BASE,
            HitKind::Medium => MEDIUM_BASE,
            HitKind::Miss => MISS,
        }
    }
}

/// A hit index decoded: its kind and the primitive's index within the kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Hit {
    pub kind: HitKind,
    pub index: usize,
}

impl Hit {
    /// The hit that index `h` names.
    #[inline(always)]
    pub fn of(h: u32) -> Hit {
        let kind = if h < QUAD_BASE {
            HitKind::Sphere
        } else if h < TRIANGLE_BASE {
            HitKind::Quad
        } else if h < MOVING_BASE {
            HitKind::Triangle
        } else if h < INSTANCE_BASE {
            HitKind::Moving
        } else if h < MEDIUM_BASE {
            HitKind::Instance
        } else if h < MISS {
            HitKind::Medium
        } else {
            HitKind::Miss
        };
        Hit { kind, index: (h - kind.base()) as usize }
    }
}

/// The closest hit found so far by a group of rays (one, or a packet), and
/// the rule every search uses to replace it: a hit is taken when it is
/// closer, or equally close with a lower hit index. With this rule the
/// answer does not depend on the order in which primitives are tested, so
/// brute force and every BVH walk find the same hit, bit for bit.
#[derive(Clone, Copy, Debug)]
pub struct Closest<R: Real> {
    pub t: R,
    pub index: R::U32,
}

impl<R: Real> Closest<R> {
    #[inline(always)]
    pub fn none() -> Self {
        Closest { t: R::splat(f32::INFINITY), index: R::u_splat(MISS) }
    }

    /// No hit yet in the lanes of `live`; `t = -inf` in the others, which no
    /// hit can improve and no box entry (never below 0) can reach.
    #[inline(always)]
    pub fn live(live: R::Mask) -> Self {
        Closest { t: R::select(live, R::splat(f32::INFINITY), R::splat(f32::NEG_INFINITY)), index: R::u_splat(MISS) }
    }

    /// Any-hit queries: no hit yet below `tmax` in the lanes of `live`
    /// (`-inf` in the others).
    #[inline(always)]
    pub fn below(tmax: R, live: R::Mask) -> Self {
        Closest { t: R::select(live, tmax, R::splat(f32::NEG_INFINITY)), index: R::u_splat(MISS) }
    }

    /// Whether some lane found a hit.
    #[inline(always)]
    pub fn found(&self) -> R::Mask {
        !R::u_eq(self.index, R::u_splat(MISS))
    }

    /// Any-hit queries: the lanes that found a hit leave the search (their
    /// `t` becomes `-inf`, which no box entry reaches); true once no lane
    /// searches.
    #[inline(always)]
    pub fn leave_found(&mut self) -> bool {
        self.t = R::select(self.found(), R::splat(f32::NEG_INFINITY), self.t);
        !self.t.gt(R::splat(f32::NEG_INFINITY)).any()
    }

    /// Takes the lanes of `hit` whose `t` beats the current one (ties: lower index).
    #[inline(always)]
    pub fn offer(&mut self, hit: R::Mask, t: R, index: R::U32) {
        let closer = hit & (t.lt(self.t) | (t.eq(self.t) & R::u_lt(index, self.index)));
        self.t = R::select(closer, t, self.t);
        self.index = R::u_select(closer, index, self.index);
    }
}
