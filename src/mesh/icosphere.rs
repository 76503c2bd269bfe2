//! Icospheres: a sphere tessellated by subdividing a regular icosahedron,
//! bit-exact to the definition below, so that any implementation of it (in
//! another language, or another renderer) builds the same f32 vertices and
//! the same triangles, in the same order.
//!
//! All arithmetic is IEEE-754 binary64, evaluated left to right, without
//! fused multiply-add.
//!
//! 1. `phi = (1 + sqrt(5)) / 2`; `unit(x, y, z) = (x / l, y / l, z / l)` with
//!    `l = sqrt((x x + y y) + z z)`.
//! 2. The 12 icosahedron vertices, in this index order, are `unit()` of:
//!    0 `(-1, phi, 0)`, 1 `(1, phi, 0)`, 2 `(-1, -phi, 0)`, 3 `(1, -phi, 0)`,
//!    4 `(0, -1, phi)`, 5 `(0, 1, phi)`, 6 `(0, -1, -phi)`, 7 `(0, 1, -phi)`,
//!    8 `(phi, 0, -1)`, 9 `(phi, 0, 1)`, 10 `(-phi, 0, -1)`, 11 `(-phi, 0, 1)`.
//! 3. The 20 faces, in this order, each counter-clockwise seen from outside
//!    (`cross(v1 - v0, v2 - v0)` points outward): [`ICOSAHEDRON`].
//! 4. Each subdivision level walks the faces in order and replaces each face
//!    `(a, b, c)`, in its place, by the four faces `(a, ab, ca)`,
//!    `(b, bc, ab)`, `(c, ca, bc)`, `(ab, bc, ca)`. Midpoints are looked up in
//!    the order `ab`, `bc`, `ca`; an edge's midpoint is made once, when the
//!    first face with that edge (either way round) asks for it, appended to
//!    the vertex list, and shared by both faces. Its value is
//!    `unit((a + b) * 0.5)`, per component on the unit vectors.
//! 5. Level `N` has `10 4^N + 2` vertices, `30 4^N` edges and `20 4^N`
//!    triangles ([`vertices`], [`triangles`]); levels 0 to
//!    [`MAX_ICOSPHERE_LEVEL`] (7: 327,680 triangles) are made.
//! 6. The vertices of the sphere of centre `c` and radius `r` (f32, `r` with
//!    its sign) are `float(double(c) + double(r) * u)` per component: the
//!    product and the sum each rounded in double, then one rounding to f32
//!    ([`place`]).
//!
//! A negative radius gives the point-mirrored vertices in the same index
//! order, so every face winds inward and its normal points to the centre:
//! the books' hollow sphere, with no special case.
//!
//! [`unit_icosphere`] builds the unit mesh of a level once; [`place`] puts
//! it at each sphere (many spheres of one level share one unit mesh).

use super::{unit, TriMesh};
use crate::error::{Error, Result};
use crate::limits::MAX_ICOSPHERE_LEVEL;
use std::collections::HashMap;

/// The icosahedron's 20 faces, counter-clockwise seen from outside, in order.
pub const ICOSAHEDRON: [[u32; 3]; 20] = [
    [0, 11, 5],
    [0, 5, 1],
    [0, 1, 7],
    [0, 7, 10],
    [0, 10, 11],
    [1, 5, 9],
    [5, 11, 4],
    [11, 10, 2],
    [10, 7, 6],
    [7, 1, 8],
    [3, 9, 4],
    [3, 4, 2],
    [3, 2, 6],
    [3, 6, 8],
    [3, 8, 9],
    [4, 9, 5],
    [2, 4, 11],
    [6, 2, 10],
    [8, 6, 7],
    [9, 8, 1],
];

/// Vertices of the icosphere of `level`: `10 4^level + 2`.
pub const fn vertices(level: u32) -> usize {
    10 * (1 << (2 * level)) + 2
}

/// Triangles of the icosphere of `level`: `20 4^level`.
pub const fn triangles(level: u32) -> usize {
    20 * (1 << (2 * level))
}

/// A unit icosphere: its vertices on the unit sphere, in double, and its triangles.
pub type UnitMesh = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// The unit icosphere of `level` (see the module's definition): its vertices
/// on the unit sphere, in double, and its triangles. Refuses (exit status 2)
/// a level above [`MAX_ICOSPHERE_LEVEL`].
pub fn unit_icosphere(level: u32) -> Result<UnitMesh> {
    if level > MAX_ICOSPHERE_LEVEL {
        return Err(Error::invalid(
            "icosphere level",
            format!(
                "{level} is too fine: at most {MAX_ICOSPHERE_LEVEL} ({} triangles a sphere; \
                 limits::MAX_ICOSPHERE_LEVEL)",
                triangles(MAX_ICOSPHERE_LEVEL)
            ),
        ));
    }
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let base = [
        [-1.0, phi, 0.0],
        [1.0, phi, 0.0],
        [-1.0, -phi, 0.0],
        [1.0, -phi, 0.0],
        [0.0, -1.0, phi],
        [0.0, 1.0, phi],
        [0.0, -1.0, -phi],
        [0.0, 1.0, -phi],
        [phi, 0.0, -1.0],
        [phi, 0.0, 1.0],
        [-phi, 0.0, -1.0],
        [-phi, 0.0, 1.0],
    ];
    let mut verts = Vec::with_capacity(vertices(level));
    verts.extend(base.map(unit));
    let mut faces = ICOSAHEDRON.to_vec();
    for _ in 0..level {
        // Each edge is in two faces: as many midpoints as half the corners.
        let mut made: HashMap<(u32, u32), u32> = HashMap::with_capacity(faces.len() * 3 / 2);
        let mut mid = |a: u32, b: u32| {
            *made.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (verts[a as usize], verts[b as usize]);
                verts.push(unit([(p[0] + q[0]) * 0.5, (p[1] + q[1]) * 0.5, (p[2] + q[2]) * 0.5]));
                (verts.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for &[a, b, c] in &faces {
            let ab = mid(a, b);
            let bc = mid(b, c);
            let ca = mid(c, a);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    debug_assert_eq!((verts.len(), faces.len()), (vertices(level), triangles(level)));
    Ok((verts, faces))
}

/// The vertices of the sphere of `center` and `radius` (its sign kept) from
/// the unit vertices `unit`: `float(double(c) + double(r) * u)` per component.
pub fn place(unit: &[[f64; 3]], center: [f32; 3], radius: f32) -> Vec<[f32; 3]> {
    let c = center.map(f64::from);
    let r = f64::from(radius);
    unit.iter().map(|u| [(c[0] + r * u[0]) as f32, (c[1] + r * u[1]) as f32, (c[2] + r * u[2]) as f32]).collect()
}

/// The icosphere of `level` at `center` and `radius` as a mesh (no normals):
/// [`unit_icosphere`] then [`place`]. For many spheres of one level, build
/// the unit mesh once and place it for each.
pub fn sphere_mesh(center: [f32; 3], radius: f32, level: u32) -> Result<TriMesh> {
    let (unit, triangles) = unit_icosphere(level)?;
    Ok(TriMesh { positions: place(&unit, center, radius), triangles, normals: None })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::flat_normal;
    use std::collections::HashSet;

    /// The mesh of `level` at the origin with radius `r`.
    fn at_origin(level: u32, r: f32) -> TriMesh {
        sphere_mesh([0.0; 3], r, level).unwrap()
    }

    #[test]
    fn counts_edges_and_euler_characteristic_at_every_level() {
        for level in 0..=MAX_ICOSPHERE_LEVEL {
            let (v, t) = unit_icosphere(level).unwrap();
            let k = 4usize.pow(level);
            assert_eq!((v.len(), t.len()), (10 * k + 2, 20 * k), "level {level}");
            let mut directed = HashSet::new();
            let mut undirected: HashMap<(u32, u32), u32> = HashMap::new();
            for &[a, b, c] in &t {
                for (p, q) in [(a, b), (b, c), (c, a)] {
                    assert!(directed.insert((p, q)), "level {level}: directed edge {p}->{q} twice");
                    *undirected.entry((p.min(q), p.max(q))).or_default() += 1;
                }
            }
            assert_eq!(undirected.len(), 30 * k, "level {level}: edges");
            assert!(undirected.values().all(|&n| n == 2), "level {level}: an edge not in exactly two faces");
            // Every vertex is used, and V - E + F = 2.
            let used: HashSet<u32> = t.iter().flatten().copied().collect();
            assert_eq!(used.len(), v.len());
            assert_eq!(v.len() as i64 - undirected.len() as i64 + t.len() as i64, 2);
            // On the unit sphere, to rounding.
            assert!(v.iter().all(|p| ((p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - 1.0).abs() < 1e-15));
        }
        let e = unit_icosphere(MAX_ICOSPHERE_LEVEL + 1).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert_eq!(
            e.to_string(),
            "icosphere level: 8 is too fine: at most 7 (327680 triangles a sphere; limits::MAX_ICOSPHERE_LEVEL)"
        );
    }

    #[test]
    fn faces_wind_outwards_and_the_volume_converges_to_the_sphere() {
        // Signed volume over 4/3 pi r^3, levels 0 to 4, to 4 digits.
        let ratios = [0.6055, 0.8735, 0.9662, 0.9914, 0.9978];
        for (level, want) in ratios.into_iter().enumerate() {
            let m = at_origin(level as u32, 1.0);
            let ratio = m.signed_volume() / (4.0 / 3.0 * std::f64::consts::PI);
            assert!((ratio - want).abs() < 5e-5, "level {level}: {ratio}");
            // Every flat normal points away from the centre.
            for t in 0..m.triangles.len() {
                let [a, b, c] = m.corners(t);
                let n = flat_normal([a, b, c]);
                let outward: f32 = (0..3).map(|k| n[k] * (a[k] + b[k] + c[k])).sum();
                assert!(outward > 0.0, "level {level} triangle {t} faces inwards");
            }
        }
    }

    #[test]
    fn a_negative_radius_mirrors_the_vertices_and_winds_inwards() {
        for level in 0..=3 {
            let (unit, tris) = unit_icosphere(level).unwrap();
            for (c, r) in [([0.0f32; 3], 1.0f32), ([0.0; 3], 0.37), ([1.5, -2.25, 7.0], 0.3), ([-1e3, 3.0, 0.1], 1e-2)]
            {
                let out = place(&unit, c, r);
                let inner = place(&unit, c, -r);
                let mirrored: Vec<[f64; 3]> = unit.iter().map(|u| u.map(|x| -x)).collect();
                let want = place(&mirrored, c, r);
                assert!(inner.iter().flatten().map(|x| x.to_bits()).eq(want.iter().flatten().map(|x| x.to_bits())));
                if c == [0.0; 3] {
                    // About the origin, the negated vertices (a zero stays
                    // +0: 0 + -0 is +0), bit for bit.
                    let neg = |x: &f32| if *x == 0.0 { 0f32.to_bits() } else { (-x).to_bits() };
                    assert!(inner.iter().flatten().map(|x| x.to_bits()).eq(out.iter().flatten().map(neg)));
                }
                let vol = |positions| TriMesh { positions, triangles: tris.clone(), normals: None }.signed_volume();
                let (v_out, v_in) = (vol(out), vol(inner));
                assert!(v_out > 0.0 && v_in < 0.0, "level {level} c {c:?} r {r}: {v_out} {v_in}");
            }
        }
    }

    #[test]
    fn vertices_are_bit_exact() {
        // Bits computed by an independent implementation of the module's
        // definition (Python floats, struct.pack('<f') for the rounding to f32).
        let (unit, _) = unit_icosphere(2).unwrap();
        let bits = |v: [f64; 3]| v.map(f64::to_bits);
        assert_eq!(bits(unit[0]), UNIT_0);
        assert_eq!(bits(unit[12]), UNIT_12);
        assert_eq!(bits(unit[161]), UNIT_161);
        let placed = place(&unit, [1.25, -3.5, 0.1], 0.7);
        assert_eq!(placed[12].map(f32::to_bits), PLACED_12);
        assert_eq!(placed[161].map(f32::to_bits), PLACED_161);
        let hollow = place(&unit, [1.25, -3.5, 0.1], -0.7);
        assert_eq!(hollow[161].map(f32::to_bits), HOLLOW_161);
        let far = place(&unit, [-123456.7, 0.001, 9876.5], 3.3e-3);
        assert_eq!(far[57].map(f32::to_bits), FAR_57);
    }

    const UNIT_0: [u64; 3] = [0xbfe0d2ca0da1530d, 0x3feb38880b4603e5, 0x0];
    const UNIT_12: [u64; 3] = [0xbfe9e3779b97f4a8, 0x3fe0000000000001, 0x3fd3c6ef372fe950];
    const UNIT_161: [u64; 3] = [0x3feb38880b4603e4, 0x3fe0d2ca0da1530e, 0x0];
    const PLACED_12: [u32; 3] = [0x3f2f062f, 0xc049999a, 0x3ea1f3a2];
    const PLACED_161: [u32; 3] = [0x3fec37e3, 0xc048727f, 0x3dcccccd];
    const HOLLOW_161: [u32; 3] = [0x3f27903a, 0xc0778d81, 0x3dcccccd];
    const FAR_57: [u32; 3] = [0xc7f1205a, 0x3b7c1ab2, 0x461a5201];
}
