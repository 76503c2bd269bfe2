//! A triangle mesh as a light the `book` and `nee-mis` estimators sample:
//! a point uniform over its whole surface (a triangle with probability its
//! share of the area, then a uniform point in it), and the densities of
//! that choice.
//!
//! - **Of a point** (`nee-mis`: a light sample's, and the point a scattered
//!   ray hit): `t^2 / (|cos| A)`, at distance `t`, with cosine `cos` between
//!   the ray and the triangle's normal, `A` the mesh's whole area.
//! - **Of a direction** (`book`'s mixture, which keeps the direction and
//!   not the point): the sum of that over every triangle the line `x + t d`,
//!   `t > 0`, passes through, since each of those points would have drawn
//!   it. A closed mesh seen from outside is met twice; a light sample
//!   toward its far side is blocked by its near side. The sum walks a tree
//!   of the mesh's own ([`Bvh::visit`]).
//!
//! # Which directions have a density
//!
//! As for the other shapes ([`super::lights`]), every direction the
//! sampler draws must get a positive density as the computer rounds it. A
//! drawn point is rounded (to about `3u (|v0| + |e1| + |e2|)`), and so is
//! its direction (about `3u` relative): a line toward a point near an
//! outer edge of an open mesh, or near the outline of a closed one, can
//! pass just outside every triangle. So the sum is taken in f64, twice:
//! over the triangles the line passes through (Woop, Benthin and Wald's
//! test, watertight: a line through a shared edge is counted by one side
//! or, on an exact zero, both); where it passes through none, the term of
//! the one triangle it passes nearest, if within `16u (|o|_inf + t +
//! |v|_inf)` of it (each edge function against the edge's length, in the
//! test's sheared projection): a direction in that band outside the mesh
//! gets the density of the triangle it was most likely drawn on (near a
//! closed mesh's outline, half the sum just inside it, which meets the
//! front and the back). The mesh's tree is padded well beyond the band.
//!
//! Everything a lane computes here is computed one lane at a time in
//! `f32` (the triangle pick is a search of a table), by the functions the
//! scalar kernel calls too: every lane width gets the scalar kernel's bits.

use super::bvh::{Bvh, Walk};
use super::triangles::{plane, LeafTriangle, Triangles};
use crate::real::{Real, MAX_LANES};
use crate::vec3::V3;
use glam::DVec3;

/// A triangle as a light samples it: a corner, the two edges from it, and
/// its plane (unit normal, `n . v0`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Corner {
    v0: [f32; 3],
    e1: [f32; 3],
    e2: [f32; 3],
    n: [f32; 3],
    dn: f32,
}

/// A mesh of `diffuse_light`, in world space, sampled by area.
#[derive(Clone, Debug)]
pub struct LightMesh {
    tris: Vec<Corner>,
    /// Triangle `k`'s share of the area and every one's before it
    /// (computed in f64, rounded once; the last is 1).
    cdf: Vec<f32>,
    /// The whole area (degenerate triangles count 0: they are never drawn,
    /// never hit).
    pub area: f32,
    /// The hit index of its first triangle (its triangles' are consecutive).
    first: u32,
    /// Its triangles again, in a tree, for the density of a direction.
    tree: Bvh<LeafTriangle>,
}

/// Two meshes are the same light when their triangles and hit indices are
/// (the tree is built from them).
impl PartialEq for LightMesh {
    fn eq(&self, o: &Self) -> bool {
        (&self.tris, &self.cdf, self.area, self.first) == (&o.tris, &o.cdf, o.area, o.first)
    }
}

impl LightMesh {
    /// The light of the triangles `v` (world space), whose hit indices are
    /// `first..`; `extent` bounds every ray origin (the tree's padding,
    /// [`Bvh::build`]).
    pub fn new(v: &[[[f32; 3]; 3]], first: u32, extent: f32) -> LightMesh {
        let d = |a: [f32; 3]| DVec3::from_array(a.map(f64::from));
        let mut searched = Triangles::default();
        let mut tris = Vec::with_capacity(v.len());
        let mut sums = Vec::with_capacity(v.len());
        let mut sum = 0.0f64;
        for (k, &t) in v.iter().enumerate() {
            let (n, dn) = plane(t);
            let twice = (d(t[1]) - d(t[0])).cross(d(t[2]) - d(t[0])).length();
            // A degenerate triangle has no normal ([`plane`]): no area.
            sum += if n == [0.0; 3] { 0.0 } else { 0.5 * twice };
            sums.push(sum);
            let edge = |a: [f32; 3]| std::array::from_fn(|i| a[i] - t[0][i]);
            tris.push(Corner { v0: t[0], e1: edge(t[1]), e2: edge(t[2]), n, dn });
            searched.push(t, first + k as u32);
        }
        let mut cdf: Vec<f32> = sums.iter().map(|s| if sum > 0.0 { (s / sum) as f32 } else { 0.0 }).collect();
        if let (Some(last), true) = (cdf.last_mut(), sum > 0.0) {
            *last = 1.0;
        }
        // Boxes padded 4 times as much as the scene's trees: far beyond the
        // band (`Primitive::extent`, [`Bvh::build`]).
        let tree = Bvh::build(&searched, 4.0 * extent, Walk::OneByOne);
        LightMesh { tris, cdf, area: sum as f32, first, tree }
    }

    /// Its triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// The point that `sub`, `u1`, `u2` (each in [0, 1]) choose, and the
    /// unit normal there: the first triangle whose share of the area with
    /// those before it exceeds `sub`, then the point `v0 + s (1 - u2) e1 +
    /// s u2 e2` with `s = sqrt(u1)` (uniform in the triangle).
    pub fn point(&self, sub: f32, u1: f32, u2: f32) -> ([f32; 3], [f32; 3]) {
        let j = self.cdf.partition_point(|&c| c <= sub).min(self.tris.len().saturating_sub(1));
        let Some(t) = self.tris.get(j) else { return ([0.0; 3], [0.0; 3]) };
        let s = u1.sqrt();
        let (b1, b2) = (s * (1.0 - u2), s * u2);
        (std::array::from_fn(|i| t.v0[i] + t.e1[i] * b1 + t.e2[i] * b2), t.n)
    }

    /// The density (solid angle, at `o`) of the point that the ray `o + t
    /// d` hit on the triangle of hit index `index`: `t^2 / (|cos| A)`, `t`
    /// where the ray meets the triangle's plane; 0 for a triangle not of
    /// this mesh.
    pub fn pdf_hit(&self, o: [f32; 3], d: [f32; 3], index: u32) -> f32 {
        let Some(tri) = self.tris.get(index.wrapping_sub(self.first) as usize) else { return 0.0 };
        let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let cos = dot(tri.n, d);
        let t = (tri.dn - dot(tri.n, o)) / cos;
        positive(t * t / (cos.abs() * self.area))
    }

    /// The density (solid angle, at `o`) of the unit direction `d` (see
    /// the module): the sum over the triangles the ray `o + t d` meets.
    pub fn pdf_line(&self, o: [f32; 3], d: [f32; 3]) -> f32 {
        let line = Line::new(o, d);
        let (mut through, mut near) = (0.0f64, (f64::INFINITY, 0.0f64));
        self.tree.visit(V3::from_array(o), V3::from_array(d), |tri| match line.meets(tri) {
            Meets::Through(w) => through += w,
            Meets::Near(off, w) if off < near.0 => near = (off, w),
            Meets::Near(..) | Meets::No => {}
        });
        let sum = if through > 0.0 { through } else { near.1 };
        positive((sum / self.area as f64) as f32)
    }

    /// [`LightMesh::point`] for every lane.
    #[inline(always)]
    pub fn points<R: Real>(&self, sub: R, u1: R, u2: R) -> (V3<R>, V3<R>) {
        let (mut p, mut n) = ([[0.0f32; 3]; MAX_LANES], [[0.0f32; 3]; MAX_LANES]);
        for k in 0..R::LANES {
            (p[k], n[k]) = self.point(sub.lane(k), u1.lane(k), u2.lane(k));
        }
        let v = |a: &[[f32; 3]; MAX_LANES]| {
            V3::new(R::from_fn(|k| a[k][0]), R::from_fn(|k| a[k][1]), R::from_fn(|k| a[k][2]))
        };
        (v(&p), v(&n))
    }

    /// [`LightMesh::pdf_line`] for every lane.
    #[inline(always)]
    pub fn pdf_lines<R: Real>(&self, o: V3<R>, d: V3<R>) -> R {
        R::from_fn(|k| self.pdf_line(o.lane(k).to_array(), d.lane(k).to_array()))
    }

    /// [`LightMesh::pdf_hit`] for the lanes of `mine`, else 0.
    #[inline(always)]
    pub fn pdf_hits<R: Real>(&self, o: V3<R>, d: V3<R>, hit: R::U32, mine: R::Mask) -> R {
        let bits = R::mask_bits(mine);
        R::from_fn(|k| {
            if bits >> k & 1 == 1 {
                self.pdf_hit(o.lane(k).to_array(), d.lane(k).to_array(), R::lane_u(hit, k))
            } else {
                0.0
            }
        })
    }
}

/// A line `o + t d` as the light's densities test it, in f64: its origin,
/// direction, Woop's axes and shear ([`super::triangles`]), and `|o|_inf`.
struct Line {
    o: DVec3,
    d: DVec3,
    /// The axes `kx`, `ky`, `kz` (`kz` where `|d|` is largest).
    k: [usize; 3],
    sx: f64,
    sy: f64,
    o_inf: f64,
}

/// How a line passes a triangle (near it: how far outside, in the
/// band's units), and the triangle's term `t^2 / |cos|`.
enum Meets {
    Through(f64),
    Near(f64, f64),
    No,
}

/// The light tests' rounding band for meshes: `16u` per unit of distance
/// (see the module).
const BAND: f64 = 16.0 / 16_777_216.0;

impl Line {
    fn new(o: [f32; 3], d: [f32; 3]) -> Line {
        let (o, d) = (DVec3::from_array(o.map(f64::from)), DVec3::from_array(d.map(f64::from)));
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let k = [(kz + 1) % 3, (kz + 2) % 3, kz];
        Line { o, d, k, sx: d[k[0]] / d[kz], sy: d[k[1]] / d[kz], o_inf: o.abs().max_element() }
    }

    /// Whether the line passes through the triangle (`t > 0`), or within
    /// the band of it (see the module), and its term.
    fn meets(&self, tri: &LeafTriangle) -> Meets {
        let n = DVec3::from_array(tri.n.map(f64::from));
        let cos = n.dot(self.d);
        let t = (tri.dn as f64 - n.dot(self.o)) / cos;
        if !(t > 0.0 && t.is_finite()) {
            return Meets::No;
        }
        let [kx, ky, kz] = self.k;
        let p = tri.v.map(|v| {
            let a = DVec3::from_array(v.map(f64::from)) - self.o;
            (a[kx] - self.sx * a[kz], a[ky] - self.sy * a[kz])
        });
        let edge = |p: (f64, f64), q: (f64, f64)| (q.0 * p.1 - q.1 * p.0, (q.0 - p.0).hypot(q.1 - p.1));
        let e = [edge(p[1], p[2]), edge(p[2], p[0]), edge(p[0], p[1])];
        let term = t * t / cos.abs();
        if e.iter().all(|e| e.0 >= 0.0) || e.iter().all(|e| e.0 <= 0.0) {
            return Meets::Through(term);
        }
        let v_inf = tri.v.iter().flatten().fold(0.0f32, |m, x| m.max(x.abs())) as f64;
        let band = BAND * (self.o_inf + t + v_inf);
        // How far outside its farthest edge, for either winding.
        let outside = |sign: f64| e.iter().fold(0.0f64, |m, e| m.max(-sign * e.0 / e.1));
        let off = outside(1.0).min(outside(-1.0));
        if off <= band {
            Meets::Near(off / band, term)
        } else {
            Meets::No
        }
    }
}

/// `x` where it is a density (positive and finite), else 0.
fn positive(x: f32) -> f32 {
    if x > 0.0 && x.is_finite() {
        x
    } else {
        0.0
    }
}
