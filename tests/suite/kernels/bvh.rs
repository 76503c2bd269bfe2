//! The BVH finds exactly brute force's closest hit (same sphere, same `t` bits)
//! for every traversal (scalar, one ray with 8-wide nodes, packets of 8 and 16),
//! on scenes that stress the build: large extents, coincident centroids, and
//! deep trees.

use proptest::prelude::*;
use rtow::internals::geometry::{
    closest_brute, Bvh, Closest, Cuboids, LeafCuboid, LeafQuad, LeafSphere, Primitive, Quads, Spheres, Walk, Walker,
};
use rtow::internals::handle::Kind;
use rtow::internals::real::Wide;
use rtow::internals::vec3::V3;
use rtow::scene::{box_quads, Camera, Group, Material, QuadBox};
use wide::{f32x16, f32x8};

fn spheres(list: &[([f32; 3], f32)]) -> Spheres {
    let mut s = Spheres::default();
    for &(c, r) in list {
        s.push(c, r, Kind::Lambertian, 0);
    }
    s.pad();
    s
}

fn unit(v: [f32; 3]) -> V3<f32> {
    let v = V3::new(v[0], v[1], v[2]);
    if v.length_squared() < 1e-6 {
        V3::new(0.0, 0.0, 1.0)
    } else {
        v.normalize()
    }
}

/// Every traversal against brute force, for `rays` (origin, direction), on
/// the trees built for each walk.
fn check(s: &Spheres, extent: f32, rays: &[(V3<f32>, V3<f32>)]) -> Result<(), TestCaseError> {
    for walk in [Walk::OneByOne, Walk::Wide8] {
        check_tree(s, &Bvh::build_spheres(s, extent, walk), rays)?;
    }
    Ok(())
}

fn check_tree(s: &Spheres, bvh: &Bvh<LeafSphere>, rays: &[(V3<f32>, V3<f32>)]) -> Result<(), TestCaseError> {
    for &(o, d) in rays {
        let (bi, bt) = closest_brute(s, o, d, 0.0, &mut ());
        let tree = walk(bvh, o, d, Closest::none());
        let (si, st) = (tree.index, tree.t);
        let (wi, wt) = bvh.closest_hit_wide(o, d, &mut ());
        prop_assert_eq!((bi, bt.to_bits()), (si, st.to_bits()), "scalar BVH");
        prop_assert_eq!((bi, bt.to_bits()), (wi, wt.to_bits()), "one ray, 8-wide nodes");
    }
    packets::<f32x8>(s, bvh, rays)?;
    packets::<f32x16>(s, bvh, rays)
}

/// The tree's one walk (closest hit) for the rays `o + t d` from `best`.
fn walk<L: rtow::internals::geometry::Leaf, R: Walker>(
    bvh: &Bvh<L>,
    o: V3<R>,
    d: V3<R>,
    best: Closest<R>,
) -> Closest<R> {
    bvh.walk::<R, (), false>(o, d, R::splat(0.0), best, &mut ())
}

/// Up to `W::LANES` rays as a packet (the last one repeated in the lanes beyond).
fn packet<W: Wide>(chunk: &[(V3<f32>, V3<f32>)]) -> (V3<W>, V3<W>) {
    let n = chunk.len();
    let at = |k: usize| chunk[k.min(n - 1)];
    let o = V3::new(W::from_fn(|k| at(k).0.x), W::from_fn(|k| at(k).0.y), W::from_fn(|k| at(k).0.z));
    let d = V3::new(W::from_fn(|k| at(k).1.x), W::from_fn(|k| at(k).1.y), W::from_fn(|k| at(k).1.z));
    (o, d)
}

fn packets<W: Wide>(s: &Spheres, bvh: &Bvh<LeafSphere>, rays: &[(V3<f32>, V3<f32>)]) -> Result<(), TestCaseError> {
    for chunk in rays.chunks(W::LANES) {
        let n = chunk.len();
        let (o, d) = packet::<W>(chunk);
        let live = if n == 32 { u32::MAX } else { (1u32 << n) - 1 };
        let tree = walk(bvh, o, d, Closest::<W>::live(W::mask_from_bits(live)));
        let (pi, pt) = (tree.index, tree.t);
        let (ri, rt) = bvh.closest_hits_one_by_one(o, d, live, &mut ());
        for (k, &(o, d)) in chunk.iter().enumerate() {
            let (bi, bt) = closest_brute(s, o, d, 0.0, &mut ());
            prop_assert_eq!((bi, bt.to_bits()), (W::lane_u(pi, k), pt.lane(k).to_bits()), "packet of {}", W::LANES);
            prop_assert_eq!((bi, bt.to_bits()), (W::lane_u(ri, k), rt.lane(k).to_bits()), "one by one");
        }
    }
    Ok(())
}

fn rays_toward(targets: &[[f32; 3]], origins: &[[f32; 3]]) -> Vec<(V3<f32>, V3<f32>)> {
    let mut v = Vec::new();
    for (i, o) in origins.iter().enumerate() {
        let t = targets[i % targets.len()];
        let o3 = V3::new(o[0], o[1], o[2]);
        v.push((o3, unit([t[0] - o[0], t[1] - o[1], t[2] - o[2]])));
    }
    v
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Spheres from 1e-3 to 1e4 in size, spread over 1e5: boxes of very different scales.
    #[test]
    fn large_extents(
        list in prop::collection::vec((prop::array::uniform3(-1e5f32..1e5), prop_oneof![1e-3f32..1.0, 1.0f32..1e4]), 1..200),
        origins in prop::collection::vec(prop::array::uniform3(-2e5f32..2e5), 1..40),
    ) {
        let s = spheres(&list);
        let targets: Vec<[f32; 3]> = list.iter().map(|l| l.0).collect();
        check(&s, 2e5, &rays_toward(&targets, &origins))?;
    }

    /// Many spheres on the same centre (and some on the same spot with equal
    /// radii): the binned build cannot split them; ties go to the lowest index.
    #[test]
    fn coincident_centroids(
        centre in prop::array::uniform3(-10.0f32..10.0),
        radii in prop::collection::vec(prop_oneof![0.1f32..3.0, Just(1.0f32)], 1..100),
        origins in prop::collection::vec(prop::array::uniform3(-30.0f32..30.0), 1..40),
    ) {
        let list: Vec<([f32; 3], f32)> = radii.iter().map(|&r| (centre, r)).collect();
        check(&spheres(&list), 40.0, &rays_toward(&[centre], &origins))?;
    }

    /// A long chain of spheres, nested by size along a line: a deep tree.
    #[test]
    fn deep_trees(
        n in 200usize..1500,
        ratio in 1.001f32..1.005,
        origins in prop::collection::vec(prop::array::uniform3(-5.0f32..5.0), 1..24),
    ) {
        let list: Vec<([f32; 3], f32)> = (0..n).map(|i| ([ratio.powi(i as i32) - 1.0, 0.0, 0.0], 0.01 * ratio.powi(i as i32))).collect();
        let targets: Vec<[f32; 3]> = list.iter().step_by(37).map(|l| l.0).collect();
        let far = list.last().unwrap().0[0] + 10.0;
        check(&spheres(&list), far, &rays_toward(&targets, &origins))?;
    }
}

/// Quads from a list of (corner, edge u, edge v).
fn quads(list: &[([f32; 3], [f32; 3], [f32; 3])], extent: f32) -> Quads {
    let mut q = Quads::default();
    for &(c, u, v) in list {
        q.push(c, u, v, extent, Kind::Lambertian, 0);
    }
    q.pad();
    q
}

/// The six faces of the box `min..max`, built by the library's `box()`.
fn box_faces(min: [f32; 3], max: [f32; 3]) -> Vec<([f32; 3], [f32; 3], [f32; 3])> {
    let b = QuadBox { a: min, b: max, material: Material::Lambertian { albedo: [0.5; 3].into() } };
    let f32s = |v: [f64; 3]| v.map(|x| x as f32);
    box_quads(&b).iter().map(|&(q, u, v)| (f32s(q), f32s(u), f32s(v))).collect()
}

/// The quads' tree (scalar walk, packets of 8 and 16), starting from a
/// sphere hit or none, against brute force: the same quad (or sphere), the
/// same `t` bits.
fn check_quads(q: &Quads, extent: f32, start: (u32, f32), rays: &[(V3<f32>, V3<f32>)]) -> Result<(), TestCaseError> {
    let bvh = Bvh::build(q, extent, Walk::OneByOne);
    for &(o, d) in rays {
        let mut brute = Closest::<f32> { index: start.0, t: start.1 };
        q.brute::<_, _, false>(o, d, 0.0, &mut brute, &mut ());
        let tree = walk(&bvh, o, d, Closest::<f32> { index: start.0, t: start.1 });
        prop_assert_eq!((brute.index, brute.t.to_bits()), (tree.index, tree.t.to_bits()), "scalar quad walk");
    }
    quad_packets::<f32x8>(q, &bvh, start, rays)?;
    quad_packets::<f32x16>(q, &bvh, start, rays)
}

fn quad_packets<W: Wide>(
    q: &Quads,
    bvh: &Bvh<LeafQuad>,
    start: (u32, f32),
    rays: &[(V3<f32>, V3<f32>)],
) -> Result<(), TestCaseError> {
    for chunk in rays.chunks(W::LANES) {
        let (o, d) = packet::<W>(chunk);
        let best = walk(bvh, o, d, Closest::<W> { index: W::u_splat(start.0), t: W::splat(start.1) });
        for (k, &(o, d)) in chunk.iter().enumerate() {
            let mut brute = Closest::<f32> { index: start.0, t: start.1 };
            q.brute::<_, _, false>(o, d, 0.0, &mut brute, &mut ());
            prop_assert_eq!(
                (brute.index, brute.t.to_bits()),
                (W::lane_u(best.index, k), best.t.lane(k).to_bits()),
                "quad packet of {}",
                W::LANES
            );
        }
    }
    Ok(())
}

/// The cuboids' tree (scalar walk, packets of 8 and 16), starting from a
/// sphere hit or none, against brute force over the cuboids: the same face,
/// the same `t` bits.
fn check_cuboids(
    c: &Cuboids,
    q: &Quads,
    extent: f32,
    start: (u32, f32),
    rays: &[(V3<f32>, V3<f32>)],
) -> Result<(), TestCaseError> {
    let mut c = c.clone();
    c.bound_faces(q);
    let bvh = Bvh::build(&c, extent, Walk::OneByOne);
    let brute = |o, d| {
        let mut b = Closest::<f32> { index: start.0, t: start.1 };
        c.brute::<_, _, false>(o, d, 0.0, &mut b, &mut ());
        (b.index, b.t.to_bits())
    };
    for &(o, d) in rays {
        let tree = walk(&bvh, o, d, Closest::<f32> { index: start.0, t: start.1 });
        prop_assert_eq!(brute(o, d), (tree.index, tree.t.to_bits()), "scalar cuboid walk");
    }
    fn packets<W: Wide>(
        bvh: &Bvh<LeafCuboid>,
        start: (u32, f32),
        rays: &[(V3<f32>, V3<f32>)],
        brute: &dyn Fn(V3<f32>, V3<f32>) -> (u32, u32),
    ) -> Result<(), TestCaseError> {
        for chunk in rays.chunks(W::LANES) {
            let (o, d) = packet::<W>(chunk);
            let best = walk(bvh, o, d, Closest::<W> { index: W::u_splat(start.0), t: W::splat(start.1) });
            for (k, &(o, d)) in chunk.iter().enumerate() {
                prop_assert_eq!(
                    brute(o, d),
                    (W::lane_u(best.index, k), best.t.lane(k).to_bits()),
                    "cuboid packet of {}",
                    W::LANES
                );
            }
        }
        Ok(())
    }
    packets::<f32x8>(&bvh, start, rays, &brute)?;
    packets::<f32x16>(&bvh, start, rays, &brute)
}

/// Rays from `origins` to the corners, edge midpoints and centres of the quads.
fn rays_to_quads(list: &[([f32; 3], [f32; 3], [f32; 3])], origins: &[[f32; 3]]) -> Vec<(V3<f32>, V3<f32>)> {
    let mut targets = Vec::new();
    for &(c, u, v) in list {
        for (a, b) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5), (1.0, 0.5)] {
            targets.push(std::array::from_fn(|k| c[k] + a * u[k] + b * v[k]));
        }
    }
    rays_toward(&targets, origins)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Axis-aligned boxes (flat quads: their bounding boxes have no
    /// thickness before padding), with shared edges and coplanar faces of
    /// touching boxes, and rays at their corners and edges.
    #[test]
    fn quad_boxes_match_brute_force(
        boxes in prop::collection::vec((prop::array::uniform3(-50.0f32..50.0), prop::array::uniform3(0.5f32..30.0)), 1..40),
        origins in prop::collection::vec(prop::array::uniform3(-120.0f32..120.0), 1..30),
        sphere_t in prop_oneof![Just(f32::INFINITY), 1.0f32..200.0],
    ) {
        let mut list = Vec::new();
        for &(min, size) in &boxes {
            let max = std::array::from_fn(|k| min[k] + size[k]);
            list.extend(box_faces(min, max));
            // A touching neighbour along x: coplanar faces, a shared face.
            list.extend(box_faces([max[0], min[1], min[2]], [max[0] + size[0], max[1], max[2]]));
        }
        let q = quads(&list, 200.0);
        let start = if sphere_t.is_finite() { (7, sphere_t) } else { (u32::MAX, f32::INFINITY) };
        check_quads(&q, 200.0, start, &rays_to_quads(&list, &origins))?;
    }

    /// Boxes turned about y (as the scene's groups turn them), tested whole
    /// as cuboids, touching and overlapping, and rays at their faces'
    /// corners and edges.
    #[test]
    fn cuboids_match_brute_force(
        boxes in prop::collection::vec((prop::array::uniform3(-50.0f32..50.0), prop::array::uniform3(0.5f32..30.0), -180.0f32..180.0), 1..40),
        origins in prop::collection::vec(prop::array::uniform3(-120.0f32..120.0), 1..30),
        sphere_t in prop_oneof![Just(f32::INFINITY), 1.0f32..200.0],
    ) {
        let mut scene = rtow::scene::preset("nw-cornell-box-empty").unwrap();
        scene.quads.clear();
        scene.camera = Camera::looking([0.0, 0.0, 1.0], [0.0; 3], 40.0);
        scene.groups = boxes.iter().map(|&(min, size, angle)| Group {
            rotate_y: angle,
            boxes: vec![QuadBox { a: min, b: std::array::from_fn(|k| min[k] + size[k]), material: Material::Lambertian { albedo: [0.5; 3].into() } }],
            ..Group::default()
        }).collect();
        let flat = scene.flatten();
        let list: Vec<_> = flat.quads.iter().map(|f| (f.q, f.u, f.v)).collect();
        let mut q = quads(&list, 200.0);
        let mut c = Cuboids::default();
        for b in &flat.cuboids {
            c.push(b.center, b.axes, b.half, b.first as u32);
        }
        q.set_cuboid_faces(flat.cuboids.iter().map(|b| b.first as u32));
        let start = if sphere_t.is_finite() { (7, sphere_t) } else { (u32::MAX, f32::INFINITY) };
        check_cuboids(&c, &q, 200.0, start, &rays_to_quads(&list, &origins))?;
    }

    /// Quads of any orientation and shape (sines down to 0.01), at large
    /// and small scales.
    #[test]
    fn oriented_quads_match_brute_force(
        list in prop::collection::vec((prop::array::uniform3(-1e4f32..1e4), prop::array::uniform3(-100.0f32..100.0), prop::array::uniform3(-100.0f32..100.0)), 1..120),
        origins in prop::collection::vec(prop::array::uniform3(-2e4f32..2e4), 1..30),
    ) {
        let list: Vec<_> = list.into_iter().filter(|(_, u, v)| {
            let (u, v) = (V3::new(u[0], u[1], u[2]), V3::new(v[0], v[1], v[2]));
            u.cross(v).length_squared() > 1e-4 * u.length_squared() * v.length_squared()
        }).collect();
        prop_assume!(!list.is_empty());
        let q = quads(&list, 2.1e4);
        check_quads(&q, 2.1e4, (u32::MAX, f32::INFINITY), &rays_to_quads(&list, &origins))?;
    }
}
