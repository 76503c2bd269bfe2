//! Smooth shading: the vertex normals of meshes that give them (OBJ files
//! with `vn` lines), interpolated across each triangle, over [`Real`] (one
//! formula for the scalar kernel and every lane width).
//!
//! A triangle's plane (its hit index `TRIANGLE_BASE + i`:
//! [`super::triangles`]) still decides everything geometric:
//! the hit point, which face was hit, and the offset and side of every ray
//! that leaves it ([`super::spawn`]). The interpolated normal only shades:
//! the materials' directions, densities and the debug and feature normals.
//!
//! Where shading and geometry disagree (a direction on the shading side of
//! the shading normal but under the geometric surface, near silhouettes of
//! a coarse mesh) the kernels end the path or drop the light sample rather
//! than let it through the surface ([`below`]): a reflection never leaves
//! through the triangle it reflected from, so light does not leak through
//! an open mesh.
//!
//! The interpolation: for corners `v0, v1, v2` with normals `n0, n1, n2` and
//! a hit point `p` in the triangle's plane, the barycentric coordinates of
//! `p` are `b1 = (p - v0) . a1`, `b2 = (p - v0) . a2`, with `a1`, `a2` the
//! dual basis of the edges `e1 = v1 - v0`, `e2 = v2 - v0` (computed once, in
//! f64), and the shading normal is `n0 + b1 (n1 - n0) + b2 (n2 - n0)`,
//! normalized and turned to the side of the geometric normal the ray sees.
//! A record of zeros (a flat mesh's triangle, in a scene with smooth
//! meshes), a hit of another kind, or an interpolated normal of (nearly) zero length shades with
//! the geometric normal.

use super::hit::{MOVING_BASE, TRIANGLE_BASE};
use super::surface::Surface;
use crate::real::{Real, MAX_LANES};
use crate::vec3::V3;
use glam::DVec3;

/// The vertex normals of a scene's triangles (by triangle, in hit-index
/// order), or none when no mesh gives normals (then no kernel reads it).
#[derive(Clone, Debug, Default)]
pub struct Smooth {
    /// Per record: `v0`, `a1`, `a2`, `n0`, `n1 - n0`, `n2 - n0` (see the
    /// module); all zeros for a record shaded flat.
    pub rec: Vec<[f32; 18]>,
}

impl Smooth {
    /// Whether no record is smooth: the kernels then shade with the
    /// geometric normal and test nothing more.
    pub fn is_empty(&self) -> bool {
        self.rec.is_empty()
    }

    /// Room for `n` more records, exactly.
    pub fn reserve(&mut self, n: usize) {
        self.rec.reserve_exact(n);
    }

    /// A record shaded with its geometric normal.
    pub fn push_flat(&mut self) {
        self.rec.push([0.0; 18]);
    }

    /// The record of the triangle `v` with unit vertex normals `n` (world
    /// space); flat if the triangle has no area.
    pub fn push(&mut self, v: [[f32; 3]; 3], n: [[f32; 3]; 3]) {
        let d = |a: [f32; 3]| DVec3::from_array(a.map(f64::from));
        let v0 = d(v[0]);
        let (e1, e2) = (d(v[1]) - v0, d(v[2]) - v0);
        let (d11, d22, d12) = (e1.dot(e1), e2.dot(e2), e1.dot(e2));
        let det = d11 * d22 - d12 * d12;
        if !(det > 0.0 && det.is_finite()) {
            return self.push_flat();
        }
        let a1 = (e1 * d22 - e2 * d12) / det;
        let a2 = (e2 * d11 - e1 * d12) / det;
        let n0 = d(n[0]);
        let parts = [v0, a1, a2, n0, d(n[1]) - n0, d(n[2]) - n0];
        self.rec.push(std::array::from_fn(|j| parts[j / 3][j % 3] as f32));
    }
}

/// The shading normal at the surfaces `srf` of hits `hit(k)` (lane k): the
/// interpolated vertex normal where the hit is a smooth triangle's, turned
/// to the side of `srf.n` (the geometric normal facing the ray); `srf.n`
/// elsewhere.
#[inline(always)]
pub fn shading_normal<R: Real>(smooth: &Smooth, hit: impl Fn(usize) -> u32, srf: &Surface<R>) -> V3<R> {
    let rec = |k: usize| {
        let h = hit(k);
        (TRIANGLE_BASE..MOVING_BASE).contains(&h).then(|| smooth.rec.get((h - TRIANGLE_BASE) as usize)).flatten()
    };
    let recs: [[f32; 18]; MAX_LANES] = std::array::from_fn(|k| match k < R::LANES {
        true => rec(k).copied().unwrap_or([0.0; 18]),
        false => [0.0; 18],
    });
    let comp = |j: usize| R::from_fn(|k| recs[k][j]);
    let at = |j: usize| V3::new(comp(j), comp(j + 1), comp(j + 2));
    let q = srf.p - at(0);
    let (b1, b2) = (q.dot(at(3)), q.dot(at(6)));
    let ns = at(9) + at(12) * b1 + at(15) * b2;
    let len2 = ns.dot(ns);
    let ok = len2.gt(R::splat(1e-24));
    let ns = ns * (R::splat(1.0) / R::select(ok, len2, R::splat(1.0)).sqrt());
    let ns = V3::select(ns.dot(srf.n).lt(R::splat(0.0)), -ns, ns);
    V3::select(ok, ns, srf.n)
}

/// Lanes whose direction `dir` leaves under the geometric surface `ng` (the
/// normal facing the ray that arrived): with smooth shading, a reflection
/// or light sample there would pass through the surface.
#[inline(always)]
pub fn below<R: Real>(ng: V3<R>, dir: V3<R>) -> R::Mask {
    dir.dot(ng).le(R::splat(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn srf(p: [f32; 3], n: [f32; 3]) -> Surface<f32> {
        Surface { p: V3::from_array(p), n: V3::from_array(n), front: true, offset: 0.0 }
    }

    #[test]
    fn the_corners_get_their_normals_and_the_middle_their_mean() {
        let v = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
        let s2 = 0.5f32.sqrt();
        let n = [[0.0, 0.0, 1.0], [s2, 0.0, s2], [0.0, s2, s2]];
        let mut sm = Smooth::default();
        sm.push_flat(); // a flat triangle before it
        sm.push(v, n);
        let hit = |_| TRIANGLE_BASE + 1;
        for (p, want) in [(v[0], n[0]), (v[1], n[1]), (v[2], n[2])] {
            let got = shading_normal(&sm, hit, &srf(p, [0.0, 0.0, 1.0])).to_array();
            (0..3).for_each(|c| assert!((got[c] - want[c]).abs() < 1e-6, "{got:?} {want:?}"));
        }
        // The midpoint of the long edge: the mean of two normals, normalized.
        let got = shading_normal(&sm, hit, &srf([1.0, 1.0, 0.0], [0.0, 0.0, 1.0])).to_array();
        let m = [s2 / 2.0, s2 / 2.0, s2];
        let len = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
        (0..3).for_each(|c| assert!((got[c] - m[c] / len).abs() < 1e-6, "{got:?}"));
        // Seen from the back (the geometric normal facing -z): turned.
        let back = shading_normal(&sm, hit, &srf([1.0, 1.0, 0.0], [0.0, 0.0, -1.0])).to_array();
        (0..3).for_each(|c| assert_eq!(back[c], -got[c]));
    }

    #[test]
    fn flat_records_other_kinds_and_degenerate_triangles_shade_with_the_geometric_normal() {
        let mut sm = Smooth::default();
        sm.push_flat();
        sm.push([[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], [[0.0, 0.0, 1.0]; 3]);
        let n = [0.6, 0.0, 0.8];
        for hit in [TRIANGLE_BASE, TRIANGLE_BASE + 1, TRIANGLE_BASE + 7, TRIANGLE_BASE - 1, 3, MOVING_BASE + 1] {
            assert_eq!(shading_normal(&sm, |_| hit, &srf([0.5, 0.0, 0.0], n)).to_array(), n, "hit {hit}");
        }
        // Opposite normals cancel at the middle: the geometric normal.
        let mut sm = Smooth::default();
        sm.push([[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.0, 0.0, 1.0]]);
        assert_eq!(shading_normal(&sm, |_| TRIANGLE_BASE, &srf([0.5, 0.0, 0.0], n)).to_array(), n);
    }
}
