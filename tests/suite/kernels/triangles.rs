//! Triangles: the watertight test against an f64 oracle (clear hits and
//! clear misses exact, `t` close), closed meshes that never leak (rays at
//! vertices and edges, from outside and from inside, tiny to huge, near and
//! far from the origin), and the triangles' tree against brute force, bit for
//! bit, one ray (one box or 8 boxes a test) and packets of 8 and 16,
//! closest hit and any hit.

use proptest::prelude::*;
use rtow::internals::geometry::{
    quad_surface, spawn, triangle_hit, triangles::plane, Bvh, Closest, LeafTriangle, Primitive, Projection, Surface,
    Triangles, Walk, Walker, MISS, QUAD_BASE,
};
use rtow::internals::real::Wide;
use rtow::internals::vec3::V3;
use rtow::mesh::icosphere::{place, unit_icosphere};
use wide::{f32x16, f32x8};

/// A mesh's triangles, hit indices `QUAD_BASE + k`.
fn triangles(pos: &[[f32; 3]], tris: &[[u32; 3]]) -> Triangles {
    let mut t = Triangles::default();
    for (k, tri) in tris.iter().enumerate() {
        t.push(tri.map(|i| pos[i as usize]), QUAD_BASE + k as u32);
    }
    t
}

fn f64s(v: [f32; 3]) -> [f64; 3] {
    v.map(f64::from)
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

/// The f64 oracle (Möller-Trumbore on the f32 vertices): the line's `t` and
/// barycentric weights of its crossing with the triangle's plane.
fn oracle(o: [f64; 3], d: [f64; 3], v: [[f32; 3]; 3]) -> (f64, [f64; 3]) {
    let (v0, v1, v2) = (f64s(v[0]), f64s(v[1]), f64s(v[2]));
    let (e1, e2) = (sub(v1, v0), sub(v2, v0));
    let p = cross(d, e2);
    let det = dot(e1, p);
    let s = sub(o, v0);
    let b1 = dot(s, p) / det;
    let q = cross(s, e1);
    let b2 = dot(d, q) / det;
    (dot(e2, q) / det, [1.0 - b1 - b2, b1, b2])
}

/// The test for one ray, and for it in every lane of packets of 8 and 16:
/// `(hit, t bits)`, the same in every width.
fn test_all(o: [f32; 3], d: [f32; 3], tri: &LeafTriangle) -> Result<(bool, u32), TestCaseError> {
    let (o1, d1) = (V3::from_array(o), V3::from_array(d));
    let (hit, t) = triangle_hit(o1, d1, &Projection::new(d1), tri);
    let one = (hit, if hit { t.to_bits() } else { 0 });
    fn lanes<W: Wide>(o: [f32; 3], d: [f32; 3], tri: &LeafTriangle) -> Vec<(bool, u32)> {
        let (o, d) = (V3::<W>::splat3(o), V3::<W>::splat3(d));
        let (hit, t) = triangle_hit(o, d, &Projection::new(d), tri);
        let bits = W::mask_bits(hit);
        (0..W::LANES).map(|k| (bits >> k & 1 == 1, if bits >> k & 1 == 1 { t.lane(k).to_bits() } else { 0 })).collect()
    }
    for l in lanes::<f32x8>(o, d, tri).into_iter().chain(lanes::<f32x16>(o, d, tri)) {
        prop_assert_eq!(l, one, "a lane differs from the scalar test");
    }
    Ok(one)
}

fn leaf(v: [[f32; 3]; 3]) -> LeafTriangle {
    triangles(&v, &[[0, 1, 2]]).leaf(0)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Clear hits are hits with `t` within `2^-16` of the oracle's, clear
    /// misses are misses, at scales from 1e-3 to 1e4 and up to 1e5 from the
    /// origin, in the scalar test and every lane of both widths alike. A
    /// clear hit is well inside the triangle, and its ray starts off the
    /// plane by more than the self-hit test's rounding band.
    #[test]
    fn the_triangle_test_agrees_with_the_f64_oracle(
        v in prop::array::uniform3(prop::array::uniform3(-1.0f64..1.0)),
        origin in prop::array::uniform3(-3.0f64..3.0),
        w in prop::array::uniform3(0.0f64..1.0),
        outside in 0usize..4,
        scale in -3i32..5,
        far in prop::array::uniform3(-1.0f64..1.0),
        far_exp in 0i32..6,
    ) {
        let s = 10f64.powi(scale);
        let at = far.map(|x| x * 10f64.powi(far_exp));
        let vf: [[f32; 3]; 3] = v.map(|p| std::array::from_fn(|i| (at[i] + s * p[i]) as f32));
        let (v0, v1, v2) = (f64s(vf[0]), f64s(vf[1]), f64s(vf[2]));
        let n = cross(sub(v1, v0), sub(v2, v0));
        let area = dot(n, n).sqrt();
        let edge = [sub(v1, v0), sub(v2, v1), sub(v0, v2)].map(|e| dot(e, e).sqrt());
        let longest = edge.iter().fold(0.0f64, |m, &e| m.max(e));
        // Not a sliver: its smallest height at least a tenth of its longest edge.
        prop_assume!(area / longest > 0.1 * longest);
        // Barycentric weights: inside by at least 0.05, or (`outside` < 3) one
        // of them below -0.05.
        let mut b = w.map(|x| 0.05 + x);
        if outside < 3 {
            b[outside] = -0.05 - w[outside];
        }
        let sum: f64 = b.iter().sum();
        let b = b.map(|x| x / sum);
        let target: [f64; 3] = std::array::from_fn(|i| b[0] * v0[i] + b[1] * v1[i] + b[2] * v2[i]);
        let o: [f64; 3] = std::array::from_fn(|i| at[i] + s * origin[i]);
        let of = o.map(|x| x as f32);
        let d = sub(target, f64s(of));
        let df = d.map(|x| x as f32);
        let (o64, d64) = (f64s(of), f64s(df));
        // Not grazing: the ray meets the plane at 30 degrees or more.
        let cos = dot(d64, n).abs() / (dot(d64, d64).sqrt() * area);
        prop_assume!(cos > 0.5);
        let (t64, bary) = oracle(o64, d64, vf);
        let margin = bary.iter().fold(f64::INFINITY, |m, &x| m.min(x));
        let (hit, t) = test_all(of, df, &leaf(vf))?;
        // The self-hit test decides the origin's side of the plane in f32
        // (`n.o` against `dn`, both within a few units of roundoff of
        // `|o| + |dn|`): a hit from an origin closer to the plane than that
        // band may go either way (rays the kernels spawn start well outside it).
        let unit = n.map(|x| x / area);
        let dn = dot(unit, v0);
        let band = 16.0 * 2f64.powi(-24) * (dot(o64, o64).sqrt() + dn.abs());
        let off_plane = (dot(unit, o64) - dn).abs() > band;
        if margin > 0.01 && t64 > 1e-3 && off_plane {
            prop_assert!(hit, "a clear hit missed: t {t64}, barycentric {bary:?}");
            let t = f32::from_bits(t) as f64;
            prop_assert!((t - t64).abs() <= t64 * 2f64.powi(-16), "t {t} against {t64}");
        } else if margin < -0.01 || t64 < -1e-3 {
            prop_assert!(!hit, "a clear miss hit: t {t64}, barycentric {bary:?}");
        }
    }
}

/// The closest hit over `tris` by brute force.
fn brute(tris: &Triangles, o: V3<f32>, d: V3<f32>) -> Closest<f32> {
    let mut best = Closest::none();
    tris.brute::<f32, (), false>(o, d, 0.0, &mut best, &mut ());
    best
}

/// An icosphere of `level` at `(c, r)`, as the scenes place it.
fn icosphere(level: u32, c: [f32; 3], r: f32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let (unit, tris) = unit_icosphere(level).unwrap();
    (place(&unit, c, r), tris)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// A closed mesh does not leak: rays aimed exactly at its vertices and at
    /// the (rounded) midpoints of its edges, from outside (above the point)
    /// and from its centre, always hit it, for icospheres of radius 1e-3 to
    /// 1e4 (hollow ones too) up to 1e4 radii from the origin (farther, a
    /// sphere spans few f32 spacings of its coordinates and its icosphere
    /// flattens: no closed mesh is left to leak).
    #[test]
    fn rays_at_edges_and_vertices_never_leak_through_a_closed_mesh(
        level in 0u32..3,
        c in prop::array::uniform3(-1.0f32..1.0),
        c_exp in 0i32..5,
        r_exp in -3i32..5,
        hollow in any::<bool>(),
        lift in 0.01f32..100.0,
        tilt in prop::array::uniform3(-0.3f32..0.3),
    ) {
        let r = 10f32.powi(r_exp) * if hollow { -1.0 } else { 1.0 };
        let c = c.map(|x| x * r.abs() * 10f32.powi(c_exp));
        let (pos, tris) = icosphere(level, c, r);
        let mesh = triangles(&pos, &tris);
        let mut targets: Vec<[f32; 3]> = pos.clone();
        for t in &tris {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let (p, q) = (pos[a as usize], pos[b as usize]);
                targets.push(std::array::from_fn(|i| ((p[i] as f64 + q[i] as f64) * 0.5) as f32));
            }
        }
        for p in targets {
            // From outside: above the point, along its (tilted) outward direction.
            let out: [f32; 3] = std::array::from_fn(|i| (p[i] - c[i]) / r.abs() + tilt[i]);
            let o: [f32; 3] = std::array::from_fn(|i| p[i] + lift * r.abs() * out[i]);
            let d = V3::from_array(std::array::from_fn(|i| p[i] - o[i]));
            if d.length_squared() > 0.0 {
                let hit = brute(&mesh, V3::from_array(o), d);
                prop_assert!(hit.index != MISS, "a ray from {o:?} at {p:?} leaked (r {r}, centre {c:?})");
            }
            // From the centre.
            let d = V3::from_array(std::array::from_fn(|i| p[i] - c[i]));
            let hit = brute(&mesh, V3::from_array(c), d);
            prop_assert!(hit.index != MISS, "a ray from the centre at {p:?} leaked (r {r}, centre {c:?})");
        }
    }

    /// The triangles' tree finds brute force's closest hit (the same triangle,
    /// the same `t` bits) and any hit alike, one ray and packets of 8 and 16,
    /// on a closed mesh and a soup of random triangles around it.
    #[test]
    fn the_triangle_tree_finds_brute_forces_hit(
        soup in prop::collection::vec(prop::array::uniform3(prop::array::uniform3(-4.0f32..4.0)), 0..40),
        origins in prop::collection::vec(prop::array::uniform3(-6.0f32..6.0), 1..40),
        dirs in prop::collection::vec(prop::array::uniform3(-1.0f32..1.0), 1..40),
        level in 0u32..3,
    ) {
        let (mut pos, mut tris) = icosphere(level, [0.5, -0.25, 0.0], 2.0);
        for t in &soup {
            let n = pos.len() as u32;
            pos.extend_from_slice(t);
            tris.push([n, n + 1, n + 2]);
        }
        let mesh = triangles(&pos, &tris);
        let extent = 6.0;
        let bvh = Bvh::build(&mesh, extent, Walk::OneByOne);
        let rays: Vec<(V3<f32>, V3<f32>)> = origins
            .iter()
            .zip(dirs.iter().cycle())
            .map(|(o, d)| (V3::from_array(*o), V3::from_array(*d)))
            .collect();
        for &(o, d) in &rays {
            let b = brute(&mesh, o, d);
            let tree = bvh.walk::<f32, (), false>(o, d, 0.0, Closest::none(), &mut ());
            prop_assert_eq!((b.index, b.t.to_bits()), (tree.index, tree.t.to_bits()), "scalar walk");
            let wide = bvh.walk_one_wide::<(), false>(o, d, 0.0, Closest::none(), &mut ());
            prop_assert_eq!((b.index, b.t.to_bits()), (wide.index, wide.t.to_bits()), "one ray, 8 boxes a test");
            let any_wide = bvh.walk_one_wide::<(), true>(o, d, 0.0, Closest::below(f32::INFINITY, true), &mut ());
            prop_assert_eq!(b.index != MISS, any_wide.index != MISS, "one ray, 8 boxes a test, any hit");
            let any = bvh.walk::<f32, (), true>(o, d, 0.0, Closest::below(f32::INFINITY, true), &mut ());
            prop_assert_eq!(b.index != MISS, any.index != MISS, "scalar any hit");
        }
        packets::<f32x8>(&mesh, &bvh, &rays)?;
        packets::<f32x16>(&mesh, &bvh, &rays)?;
    }
}

fn packets<W: Wide + Walker>(
    mesh: &Triangles,
    bvh: &Bvh<LeafTriangle>,
    rays: &[(V3<f32>, V3<f32>)],
) -> Result<(), TestCaseError> {
    for chunk in rays.chunks(W::LANES) {
        let (o, d) = super::packet::<W>(chunk);
        let tree = bvh.walk::<W, (), false>(o, d, W::splat(0.0), Closest::none(), &mut ());
        let any = bvh.walk::<W, (), true>(
            o,
            d,
            W::splat(0.0),
            Closest::below(W::splat(f32::INFINITY), W::splat(0.0).eq(W::splat(0.0))),
            &mut (),
        );
        for (k, &(o, d)) in chunk.iter().enumerate() {
            let b = brute(mesh, o, d);
            prop_assert_eq!(
                (b.index, b.t.to_bits()),
                (W::lane_u(tree.index, k), tree.t.lane(k).to_bits()),
                "packet of {}",
                W::LANES
            );
            prop_assert_eq!(b.index != MISS, W::lane_u(any.index, k) != MISS, "any hit, packet of {}", W::LANES);
        }
    }
    Ok(())
}

/// The surface the kernels shade at a triangle hit (its planar record's:
/// the plane's normal and offset, the point re-projected), for a ray that
/// hit triangle `index - QUAD_BASE` of `tris` at `t`.
fn hit_surface(pos: &[[f32; 3]], tris: &[[u32; 3]], o: V3<f32>, d: V3<f32>, hit: &Closest<f32>) -> Surface<f32> {
    let corners = tris[(hit.index - QUAD_BASE) as usize].map(|i| pos[i as usize]);
    let (n, dn) = plane(corners);
    quad_surface(o, d, hit.t, V3::from_array(n), dn)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Self-hits, at scales the books never use: a ray spawned from a
    /// triangle hit (the shading record's surface and the quads' offset, as
    /// the kernels spawn it) never hits that triangle again, in any
    /// direction, for lone triangles of size 1e-4 to 1e4 up to 1e6 from the
    /// origin; on a closed mesh (an icosphere of radius 1e-4 to 1e4, hollow
    /// ones too, its centre up to 1e4 radii and 1e6 from the origin), every
    /// ray spawned into it hits it again elsewhere: none leaks out.
    #[test]
    fn spawned_rays_never_rehit_their_triangle_and_never_leak_out_of_a_closed_mesh(
        size_exp in -4.0f64..4.0,
        far_exp in -4.0f64..6.0,
        corners in prop::array::uniform3(prop::array::uniform3(-1.0f64..1.0)),
        toward in prop::array::uniform3(-1.0f64..1.0),
        level in 0u32..3,
        r_exp in -4i32..5,
        c_exp in 0i32..5,
        hollow in any::<bool>(),
        aim in any::<u32>(),
        bary in (0.05f64..0.9, 0.05f64..0.45),
        dirs in prop::collection::vec(prop::array::uniform3(-1.0f32..1.0), 24),
    ) {
        let dirs: Vec<V3<f32>> = dirs.iter().map(|d| V3::from_array(*d)).filter(|d| d.length_squared() > 1e-6).collect();
        // A lone triangle.
        let size = 10f64.powf(size_exp);
        let len = toward.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-9);
        let centre: [f64; 3] = std::array::from_fn(|i| toward[i] / len * 10f64.powf(far_exp));
        let v: [[f32; 3]; 3] = corners.map(|c| std::array::from_fn(|i| (centre[i] + size * c[i]) as f32));
        let tris = [[0, 1, 2]];
        let (n, _) = plane(v);
        if n != [0.0; 3] {
            let mesh = triangles(&v, &tris);
            let p: [f32; 3] = std::array::from_fn(|i| ((v[0][i] as f64 + v[1][i] as f64 + v[2][i] as f64) / 3.0) as f32);
            let o: [f32; 3] = std::array::from_fn(|i| p[i] + (size * (n[i] as f64 + 0.3)) as f32);
            let d = V3::from_array(p) - V3::from_array(o);
            let hit = brute(&mesh, V3::from_array(o), d);
            if hit.index != MISS {
                let s = hit_surface(&v, &tris, V3::from_array(o), d, &hit);
                for &dir in &dirs {
                    let again = brute(&mesh, spawn(&s, dir), dir);
                    prop_assert_eq!(again.index, MISS, "a ray leaving {:?} along {:?} hit its triangle {:?} again", s.p, dir, v);
                }
            }
        }
        // A closed mesh.
        let r = 10f32.powi(r_exp) * if hollow { -1.0 } else { 1.0 };
        let c: [f32; 3] = std::array::from_fn(|i| (toward[i] / len) as f32 * r.abs() * 10f32.powi(c_exp));
        prop_assume!(c.iter().all(|x| x.abs() <= 1e6));
        let (pos, tris) = icosphere(level, c, r);
        let mesh = triangles(&pos, &tris);
        let k = aim as usize % tris.len();
        let [a, b, e] = tris[k].map(|i| pos[i as usize].map(f64::from));
        let p: [f32; 3] =
            std::array::from_fn(|i| (a[i] + bary.0 * (b[i] - a[i]) + bary.1 * (1.0 - bary.0) * (e[i] - a[i])) as f32);
        for from_inside in [false, true] {
            let o = if from_inside { c } else { std::array::from_fn(|i| c[i] + 3.0 * (p[i] - c[i])) };
            let (o, d) = (V3::from_array(o), V3::from_array(p) - V3::from_array(o));
            let hit = brute(&mesh, o, d);
            prop_assert!(hit.index != MISS, "a ray at {:?} leaked (r {}, centre {:?})", p, r, c);
            let s = hit_surface(&pos, &tris, o, d, &hit);
            // The side away from the centre: the plane's normal for a
            // solid sphere, its opposite for a hollow one.
            let corners = tris[(hit.index - QUAD_BASE) as usize].map(|i| pos[i as usize]);
            let outward = V3::from_array(plane(corners).0) * r.signum();
            for &dir in &dirs {
                let again = brute(&mesh, spawn(&s, dir), dir);
                prop_assert!(again.index != hit.index, "a ray leaving {:?} along {:?} hit its triangle again", s.p, dir);
                if dir.dot(outward) < 0.0 {
                    prop_assert!(again.index != MISS, "a ray spawned into the mesh at {:?} along {:?} leaked (r {}, centre {:?})", s.p, dir, r, c);
                }
            }
        }
    }
}
