//! Triangle meshes and where they come from: the mesh type ([`TriMesh`]),
//! icospheres that tessellate a sphere bit-exactly ([`icosphere`]), and
//! Wavefront OBJ files read and written ([`obj`]).
//!
//! A triangle lists three vertex indices counter-clockwise seen from its
//! front: `cross(p1 - p0, p2 - p0)` is the front normal ([`flat_normal`]).
//! A closed mesh whose triangles all face outwards has a positive
//! [`TriMesh::signed_volume`].
//!
//! Nothing here renders or knows the kernels: a mesh is plain data, checked
//! ([`TriMesh::check`]) against the bounds of [`crate::limits`].

pub mod icosphere;
pub mod obj;

pub use icosphere::{place, sphere_mesh, unit_icosphere, UnitMesh};
pub use obj::{parse_obj, read_obj, write_obj, ObjObject};

use crate::error::{Error, Result};
use crate::limits::{MAX_MESH_VERTICES, MAX_TRIANGLES};

/// A triangle mesh: positions, triangles as vertex indices (counter-clockwise
/// seen from the front: `cross(p1 - p0, p2 - p0)` is the front normal),
/// optional per-vertex normals (one per position when present, as given:
/// not normalized).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
}

impl TriMesh {
    /// Refuses (exit status 2, field `mesh`) a mesh that is not one rtow can
    /// use: no triangles; more than [`MAX_TRIANGLES`] triangles or
    /// [`MAX_MESH_VERTICES`] vertices; an index past the positions; a
    /// coordinate or normal component that is NaN or infinite; normals that
    /// are not one per position. Degenerate triangles (two equal indices, or
    /// collinear corners) are allowed: they have no area and are never hit.
    pub fn check(&self) -> Result<()> {
        match self.fault() {
            None => Ok(()),
            Some(message) => Err(Error::invalid("mesh", message)),
        }
    }

    /// What [`TriMesh::check`] refuses, as a message; `None` for a usable mesh.
    pub(crate) fn fault(&self) -> Option<String> {
        self.fault_within(MAX_MESH_VERTICES, MAX_TRIANGLES)
    }

    /// [`TriMesh::fault`] with the bounds on vertices and triangles given.
    pub(crate) fn fault_within(&self, max_vertices: usize, max_triangles: usize) -> Option<String> {
        let (nv, nt) = (self.positions.len(), self.triangles.len());
        if nt == 0 {
            return Some("has no triangles".into());
        }
        if nt > max_triangles {
            return Some(format!("has {nt} triangles; at most {max_triangles} (limits::MAX_TRIANGLES)"));
        }
        if nv > max_vertices {
            return Some(format!("has {nv} vertices; at most {max_vertices} (limits::MAX_MESH_VERTICES)"));
        }
        if let Some(i) = self.positions.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
            return Some(format!("vertex {i} is not finite: {:?}", self.positions[i]));
        }
        if let Some((t, tri)) = self.triangles.iter().enumerate().find(|(_, t)| t.iter().any(|&i| i as usize >= nv)) {
            return Some(format!("triangle {t} {tri:?} has an index past the {nv} vertices"));
        }
        if let Some(normals) = &self.normals {
            if normals.len() != nv {
                return Some(format!("has {} normals for {nv} vertices; one per vertex, or none", normals.len()));
            }
            if let Some(i) = normals.iter().position(|n| !n.iter().all(|x| x.is_finite())) {
                return Some(format!("normal {i} is not finite: {:?}", normals[i]));
            }
        }
        None
    }

    /// The corners of triangle `t`.
    ///
    /// # Panics
    /// When `t` or one of its indices is out of range ([`TriMesh::check`] rules that out).
    pub fn corners(&self, t: usize) -> [[f32; 3]; 3] {
        self.triangles[t].map(|i| self.positions[i as usize])
    }

    /// The smallest box holding every position, `(min, max)`; `None` when
    /// there are none. (Positions no triangle uses count too.)
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let first = *self.positions.first()?;
        Some(self.positions.iter().fold((first, first), |(lo, hi), p| {
            (std::array::from_fn(|k| lo[k].min(p[k])), std::array::from_fn(|k| hi[k].max(p[k])))
        }))
    }

    /// The volume the triangles enclose, in double, signed: positive when a
    /// closed mesh's triangles face outwards, negative when they all face
    /// inwards. The sum over triangles of `(p0 - o) . ((p1 - o) x (p2 - o)) / 6`
    /// about the first position `o` (for a closed mesh any point gives the
    /// same volume, up to rounding: a near one the least). 0 for a mesh
    /// without positions. [`TriMesh::check`] the mesh first: an index out of
    /// range panics.
    pub fn signed_volume(&self) -> f64 {
        let Some(o) = self.positions.first().map(|p| p.map(f64::from)) else {
            return 0.0;
        };
        let sum: f64 = self
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| sub(self.positions[i as usize].map(f64::from), o));
                dot(a, cross(b, c))
            })
            .sum();
        sum / 6.0
    }
}

/// The unit front normal of the triangle `p` (corners counter-clockwise seen
/// from the front): `unit(cross(p1 - p0, p2 - p0))`, every step in IEEE-754
/// double from the f32 corners (no fused multiply-add), then rounded to f32.
/// `cross(a, b)` is `(ay bz - az by, az bx - ax bz, ax by - ay bx)`;
/// `unit(v)` is `v / sqrt((vx vx + vy vy) + vz vz)`. A degenerate triangle
/// (corners equal or collinear, so the cross product is exactly zero: in
/// double it cannot underflow for f32 corners) gives `[0.0, 0.0, 0.0]`.
pub fn flat_normal(p: [[f32; 3]; 3]) -> [f32; 3] {
    let [p0, p1, p2] = p.map(|v| v.map(f64::from));
    let n = cross(sub(p1, p0), sub(p2, p0));
    if n == [0.0; 3] {
        return [0.0; 3];
    }
    unit(n).map(|x| x as f32)
}

/// `v / |v|`, the length `sqrt((x x + y y) + z z)`: the order icospheres and
/// [`flat_normal`] are defined with.
pub(crate) fn unit(v: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = v;
    let len = (x * x + y * y + z * z).sqrt();
    [x / len, y / len, z / len]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> TriMesh {
        // Outward-facing: cross(p1 - p0, p2 - p0) points away from the inside.
        TriMesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            normals: None,
        }
    }

    #[test]
    fn a_tetrahedron_checks_and_has_its_volume_and_bounds() {
        let t = tetrahedron();
        t.check().unwrap();
        assert_eq!(t.signed_volume(), 1.0 / 6.0);
        assert_eq!(t.bounds(), Some(([0.0; 3], [1.0; 3])));
        let inward = TriMesh { triangles: t.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect(), ..t.clone() };
        assert_eq!(inward.signed_volume(), -1.0 / 6.0);
        assert_eq!(flat_normal(t.corners(0)), [0.0, 0.0, -1.0]);
        assert_eq!(flat_normal(t.corners(1)), [0.0, -1.0, 0.0]);
        let s = 1.0 / 3f64.sqrt();
        assert_eq!(flat_normal(t.corners(3)), [s as f32; 3]);
        assert_eq!(TriMesh::default().bounds(), None);
    }

    #[test]
    fn degenerate_triangles_have_a_zero_normal() {
        assert_eq!(flat_normal([[1.0, 2.0, 3.0]; 3]), [0.0; 3]);
        assert_eq!(flat_normal([[0.0; 3], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]), [0.0; 3]);
        // The smallest f32 steps still give a direction (double does not underflow).
        let d = f32::from_bits(1);
        assert_eq!(flat_normal([[0.0; 3], [d, 0.0, 0.0], [0.0, d, 0.0]]), [0.0, 0.0, 1.0]);
        // The largest coordinates do not overflow.
        let m = f32::MAX;
        assert_eq!(flat_normal([[-m, -m, 0.0], [m, -m, 0.0], [-m, m, 0.0]]), [0.0, 0.0, 1.0]);
    }

    #[test]
    fn check_refuses_what_cannot_be_used() {
        let t = tetrahedron();
        let fault = |m: TriMesh| m.check().unwrap_err().to_string();
        assert_eq!(fault(TriMesh::default()), "mesh: has no triangles");
        let mut m = t.clone();
        m.triangles[2][1] = 4;
        assert_eq!(fault(m), "mesh: triangle 2 [0, 4, 2] has an index past the 4 vertices");
        let mut m = t.clone();
        m.positions[1][2] = f32::NAN;
        assert_eq!(fault(m), "mesh: vertex 1 is not finite: [1.0, 0.0, NaN]");
        let mut m = t.clone();
        m.normals = Some(vec![[0.0, 0.0, 1.0]; 3]);
        assert_eq!(fault(m.clone()), "mesh: has 3 normals for 4 vertices; one per vertex, or none");
        m.normals.as_mut().unwrap().push([f32::INFINITY, 0.0, 0.0]);
        assert_eq!(fault(m.clone()), "mesh: normal 3 is not finite: [inf, 0.0, 0.0]");
        m.normals.as_mut().unwrap()[3] = [1.0, 0.0, 0.0];
        m.check().unwrap();
        let mut m = t;
        m.triangles = vec![[0, 0, 0]; MAX_TRIANGLES + 1];
        assert!(fault(m).contains("limits::MAX_TRIANGLES"));
    }
}
