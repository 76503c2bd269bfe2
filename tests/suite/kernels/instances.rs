//! Instanced meshes: the instances' tree against their brute force, bit for
//! bit (one ray, packets of 8 and 16, closest hit and any hit), hits
//! against an f64 oracle of the placed triangle, and self-hits where the
//! move into the mesh's frame rounds the most: a mesh far from its frame's
//! origin, placed near the world's (and far from both), whose spawned rays
//! never find their triangle again and never leak out of it.

use proptest::prelude::*;
use rtow::internals::geometry::{
    spawn, Bvh, Closest, Instances, LeafInstance, Primitive, SharedMesh, Walker, INSTANCE_BASE, MISS,
};
use rtow::internals::handle::Kind;
use rtow::internals::real::Wide;
use rtow::internals::vec3::V3;
use rtow::mesh::icosphere::{place, unit_icosphere};
use wide::{f32x16, f32x8};

/// An icosphere of `level` at `(c, r)` in its own frame.
fn icosphere(level: u32, c: [f32; 3], r: f32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let (unit, tris) = unit_icosphere(level).unwrap();
    (place(&unit, c, r), tris)
}

/// The shared mesh of `(pos, tris)`, its tree padded for coordinates up to `extent`.
fn shared(pos: &[[f32; 3]], tris: &[[u32; 3]], extent: f32) -> SharedMesh {
    SharedMesh::new(tris.iter().map(|t| t.map(|i| pos[i as usize])), extent)
}

/// The placement `(angle in degrees, move)` as the groups make it.
fn turn(deg: f64) -> (f64, f64) {
    let (s, c) = deg.to_radians().sin_cos();
    (c, s)
}

/// Brute force over the instances, one ray.
fn brute<const ANY: bool>(inst: &Instances, o: V3<f32>, d: V3<f32>) -> Closest<f32> {
    let mut best = if ANY { Closest::below(f32::INFINITY, true) } else { Closest::none() };
    inst.brute::<f32, (), ANY>(o, d, 0.0, &mut best, &mut ());
    best
}

/// The instances' tree, one ray.
fn walk<const ANY: bool>(tree: &Bvh<LeafInstance>, o: V3<f32>, d: V3<f32>) -> Closest<f32> {
    let mut best = if ANY { Closest::below(f32::INFINITY, true) } else { Closest::none() };
    f32::walk_one_ray::<LeafInstance, (), ANY>(tree, o, d, 0.0, &mut best, &mut ());
    best
}

fn packets<W: Wide + Walker>(
    inst: &Instances,
    tree: &Bvh<LeafInstance>,
    rays: &[(V3<f32>, V3<f32>)],
) -> Result<(), TestCaseError> {
    for chunk in rays.chunks(W::LANES) {
        let (o, d) = super::packet::<W>(chunk);
        let live = W::splat(0.0).eq(W::splat(0.0));
        let mut closest = Closest::live(live);
        W::walk_one_ray::<LeafInstance, (), false>(tree, o, d, W::splat(0.0), &mut closest, &mut ());
        let mut any = Closest::below(W::splat(f32::INFINITY), live);
        W::walk_one_ray::<LeafInstance, (), true>(tree, o, d, W::splat(0.0), &mut any, &mut ());
        let mut brute_packet = Closest::live(live);
        inst.brute::<W, (), false>(o, d, W::splat(0.0), &mut brute_packet, &mut ());
        for (k, &(o, d)) in chunk.iter().enumerate() {
            let b = brute::<false>(inst, o, d);
            let lane = |c: &Closest<W>| (W::lane_u(c.index, k), c.t.lane(k).to_bits());
            prop_assert_eq!((b.index, b.t.to_bits()), lane(&closest), "tree, packet of {}", W::LANES);
            prop_assert_eq!((b.index, b.t.to_bits()), lane(&brute_packet), "brute force, packet of {}", W::LANES);
            prop_assert_eq!(b.index != MISS, W::lane_u(any.index, k) != MISS, "any hit, packet of {}", W::LANES);
        }
    }
    Ok(())
}

/// The ray `o + t d` against the triangle `v` in f64: `t` where it meets
/// the triangle's plane, and whether that point is clearly inside (its
/// barycentric coordinates all above `margin`).
fn oracle(o: [f64; 3], d: [f64; 3], v: [[f64; 3]; 3], margin: f64) -> Option<f64> {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross =
        |a: [f64; 3], b: [f64; 3]| [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (e1, e2) = (sub(v[1], v[0]), sub(v[2], v[0]));
    let n = cross(e1, e2);
    let t = dot(n, sub(v[0], o)) / dot(n, d);
    let p = std::array::from_fn(|i| o[i] + t * d[i]);
    let area = dot(n, n);
    let b1 = dot(cross(sub(p, v[0]), e2), n) / area;
    let b2 = dot(cross(e1, sub(p, v[0])), n) / area;
    (t > 0.0 && b1 > margin && b2 > margin && 1.0 - b1 - b2 > margin).then_some(t)
}

/// The instance's world placement of a mesh-frame point, in f64.
fn placed(p: [f32; 3], (c, s): (f64, f64), t: [f64; 3]) -> [f64; 3] {
    let p = p.map(f64::from);
    [c * p[0] + s * p[2] + t[0], p[1] + t[1], -s * p[0] + c * p[2] + t[2]]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// The instances' tree finds brute force's hit, bit for bit: three
    /// placements of one icosphere and two of another, turned and moved,
    /// overlapping, against rays from anywhere around them.
    #[test]
    fn the_instance_tree_finds_brute_forces_hit(
        angles in prop::array::uniform5(-180.0f64..180.0),
        moves in prop::array::uniform5(prop::array::uniform3(-3.0f64..3.0)),
        rays in prop::collection::vec((prop::array::uniform3(-8.0f32..8.0), prop::array::uniform3(-1.0f32..1.0)), 40),
    ) {
        let (a, at) = icosphere(1, [0.5, 0.0, 0.0], 1.0);
        let (b, bt) = icosphere(2, [0.0, 0.0, 0.0], 0.7);
        let mut inst = Instances::new(vec![shared(&a, &at, 20.0), shared(&b, &bt, 20.0)]);
        for (k, (angle, t)) in angles.iter().zip(moves).enumerate() {
            inst.push(k % 2, turn(*angle), t, Kind::Lambertian, 0);
        }
        let tree = inst.tree(20.0);
        let rays: Vec<(V3<f32>, V3<f32>)> = rays
            .iter()
            .map(|(o, d)| (V3::from_array(*o), V3::from_array(*d)))
            .filter(|(_, d)| d.length_squared() > 1e-6)
            .collect();
        for &(o, d) in &rays {
            let (b, w) = (brute::<false>(&inst, o, d), walk::<false>(&tree, o, d));
            prop_assert_eq!((b.index, b.t.to_bits()), (w.index, w.t.to_bits()), "one ray from {:?} along {:?}", o, d);
            prop_assert!(b.index == MISS || b.index >= INSTANCE_BASE);
            prop_assert_eq!(b.index != MISS, walk::<true>(&tree, o, d).index != MISS, "any hit");
            prop_assert_eq!(b.index != MISS, brute::<true>(&inst, o, d).index != MISS, "any hit, brute force");
        }
        packets::<f32x8>(&inst, &tree, &rays)?;
        packets::<f32x16>(&inst, &tree, &rays)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Self-hits where the move into the mesh's frame rounds the most: an
    /// icosphere of radius 1e-3 to 1e3 whose centre lies 1e2 to 1e5 radii
    /// from its frame's origin, placed (turned, moved) at up to 1e4 radii
    /// from the world's origin, near it or far. A ray at a point of a
    /// triangle hits that triangle at the f64 oracle's distance (within
    /// 2^-14 relative); every ray spawned from the hit as the kernels
    /// spawn it (`Instances::surface`'s offset) never finds that triangle
    /// again, and one spawned into the mesh never leaks out of it.
    #[test]
    fn instanced_triangles_are_hit_where_placed_and_never_hit_again_by_their_own_rays(
        r_exp in -3i32..4,
        away_exp in 2i32..6,
        world_exp in -2i32..5,
        axis in prop::array::uniform3(-1.0f64..1.0),
        toward in prop::array::uniform3(-1.0f64..1.0),
        angle in -180.0f64..180.0,
        aim in any::<u32>(),
        bary in (0.1f64..0.8, 0.1f64..0.4),
        dirs in prop::collection::vec(prop::array::uniform3(-1.0f32..1.0), 24),
    ) {
        let dirs: Vec<V3<f32>> = dirs.iter().map(|d| V3::from_array(*d)).filter(|d| d.length_squared() > 1e-6).collect();
        let unit = |v: [f64; 3]| {
            let l = v.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-9);
            v.map(|x| x / l)
        };
        let r = 10f32.powi(r_exp);
        // The mesh in its frame, far from the frame's origin.
        let c: [f32; 3] = unit(axis).map(|x| (x * r as f64 * 10f64.powi(away_exp)) as f32);
        let (pos, tris) = icosphere(1, c, r);
        // Placed so that its centre lands near `world` (turned, then moved).
        let rot = turn(angle);
        let world = unit(toward).map(|x| x * r as f64 * 10f64.powi(world_exp));
        let turned = placed(c, rot, [0.0; 3]);
        let t: [f64; 3] = std::array::from_fn(|i| world[i] - turned[i]);
        let reach = t.iter().chain(&c.map(f64::from)).fold(0.0f64, |m, x| m.max(x.abs())) as f32 + 2.0 * r;
        let mut inst = Instances::new(vec![shared(&pos, &tris, 4.0 * reach)]);
        inst.push(0, rot, t, Kind::Lambertian, 0);
        let tree = inst.tree(4.0 * reach);
        let k = aim as usize % tris.len();
        let v = tris[k].map(|i| placed(pos[i as usize], rot, t));
        let p: [f64; 3] = std::array::from_fn(|i| v[0][i] + bary.0 * (v[1][i] - v[0][i]) + bary.1 * (1.0 - bary.0) * (v[2][i] - v[0][i]));
        let centre = placed(c, rot, t);
        let o32: [f32; 3] = std::array::from_fn(|i| (centre[i] + 3.0 * (p[i] - centre[i])) as f32);
        let (o, d) = (V3::from_array(o32), V3::from_array(p.map(|x| x as f32)) - V3::from_array(o32));
        let hit = walk::<false>(&tree, o, d);
        prop_assert!(hit.index != MISS, "a ray at {:?} missed the mesh (r {}, centre {:?})", p, r, centre);
        let (o64, d64) = (o32.map(f64::from), [d.x, d.y, d.z].map(f64::from));
        if hit.index == INSTANCE_BASE + k as u32 {
            if let Some(t64) = oracle(o64, d64, v, 0.02) {
                // The ray moved into the frame carries about `u` of the
                // coordinates there (the mesh's distance from its frame's
                // origin, the move) into the hit's distance.
                let frame = (reach as f64 + o64.iter().fold(0.0f64, |m, x| m.max(x.abs()))) * 2f64.powi(-24);
                let len = d64.iter().map(|x| x * x).sum::<f64>().sqrt();
                let tol = t64 * 2f64.powi(-14) + 16.0 * frame / len;
                prop_assert!(((hit.t as f64) - t64).abs() <= tol, "t {} against the oracle's {} (tolerance {})", hit.t, t64, tol);
            }
        }
        let (s, i) = inst.surface(o, d, hit.t, hit.index);
        prop_assert_eq!(i, 0);
        // The ray came from outside: the surface's normal points out.
        for &dir in &dirs {
            let start = spawn(&s, dir);
            let again = walk::<false>(&tree, start, dir);
            prop_assert!(again.index != hit.index, "a ray leaving {:?} along {:?} hit its triangle again (offset {})", s.p, dir, s.offset);
            prop_assert_eq!(walk::<true>(&tree, start, dir).index != MISS, again.index != MISS);
            if dir.dot(s.n) < 0.0 {
                prop_assert!(again.index != MISS, "a ray spawned into the mesh at {:?} along {:?} leaked", s.p, dir);
            }
        }
    }
}
