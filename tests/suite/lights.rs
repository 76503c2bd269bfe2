//! Directions toward the shapes of the `book` estimator
//! (`rtow::internals::geometry::lights`) against f64: sampled directions
//! have the density the estimator divides by, the density integrates to 1
//! over the sphere of directions, and the sampler covers exactly the solid
//! angle the density claims (E[1 / pdf] over samples = the solid angle),
//! for a quad and for a sphere seen from far, near, on its surface and
//! from inside; a mesh's density against an f64 sum over its triangles,
//! and a hit's density against its light sample's. Every estimate is
//! checked against its own standard error.

use glam::DVec3;
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use rtow::internals::geometry::{LightQuad, LightSphere, Lights};
use rtow::internals::vec3::V3;
use std::f64::consts::PI;

fn dv(v: V3<f32>) -> DVec3 {
    DVec3::new(v.x as f64, v.y as f64, v.z as f64)
}

fn v3(a: [f64; 3]) -> V3<f32> {
    V3::new(a[0] as f32, a[1] as f32, a[2] as f32)
}

struct Uniform(Xoshiro256PlusPlus);

impl Uniform {
    fn new(seed: u64) -> Self {
        Uniform(Xoshiro256PlusPlus::seed_from_u64(seed))
    }
    /// Uniform in [0, 1) on the 2^-24 grid the streams draw from.
    fn next(&mut self) -> f32 {
        (self.0.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }
    /// A uniform unit vector (f64).
    fn direction(&mut self) -> DVec3 {
        let z = 1.0 - 2.0 * (self.0.next_u64() as f64 / 2f64.powi(64));
        let phi = 2.0 * PI * (self.0.next_u64() as f64 / 2f64.powi(64));
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// The f64 density of `d` from `x` toward quad (q, u, v) under uniform area sampling.
fn quad_pdf64(q: DVec3, u: DVec3, v: DVec3, x: DVec3, d: DVec3) -> f64 {
    let n = u.cross(v);
    let area = n.length();
    let nu = n / area;
    let denom = nu.dot(d);
    if denom.abs() < 1e-12 {
        return 0.0;
    }
    let t = (nu.dot(q) - nu.dot(x)) / denom;
    let p = x + d * t - q;
    let w = n / n.length_squared();
    let (a, b) = (w.dot(p.cross(v)), w.dot(u.cross(p)));
    if t <= 0.0 || !(0.0..=1.0).contains(&a) || !(0.0..=1.0).contains(&b) {
        return 0.0;
    }
    t * t / (denom.abs() * area)
}

/// The solid angle of triangle (a, b, c) seen from the origin (Van Oosterom and Strackee).
fn triangle_solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let num = a.dot(b.cross(c)).abs();
    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * num.atan2(den)
}

/// The shapes and viewpoints: (name, list, x, the solid angle it subtends from x).
fn cases() -> Vec<(&'static str, Lights, DVec3, f64)> {
    let (q, u, v) = ([343.0, 554.0, 332.0], [-130.0, 0.0, 0.0], [0.0, 0.0, -105.0]);
    let quad = Lights { quads: vec![LightQuad::new(q, u, v)], ..Lights::default() };
    let quad_angle = |x: DVec3| {
        let (q, u, v) = (DVec3::from(q.map(f64::from)), DVec3::from(u.map(f64::from)), DVec3::from(v.map(f64::from)));
        triangle_solid_angle(q - x, q + u - x, q + u + v - x) + triangle_solid_angle(q - x, q + u + v - x, q + v - x)
    };
    let sphere = |c: [f32; 3], r: f32| Lights { spheres: vec![LightSphere { c, r }], ..Lights::default() };
    let cone = |c: [f32; 3], r: f32, x: DVec3| {
        let d = (DVec3::from(c.map(f64::from)) - x).length();
        let r = r as f64;
        if d <= r {
            4.0 * PI
        } else {
            2.0 * PI * (1.0 - (1.0 - r * r / (d * d)).sqrt())
        }
    };
    let floor = DVec3::new(278.0, 0.0, 278.0);
    let wall = DVec3::new(555.0, 100.0, 300.0);
    let (c, r) = ([190.0, 90.0, 190.0], 90.0);
    let near = DVec3::new(190.0, 90.0, 290.0);
    let on = DVec3::new(190.0, 0.0, 190.0);
    let far = DVec3::new(1e4, 5e3, -3e4);
    vec![
        ("quad from the floor", quad.clone(), floor, quad_angle(floor)),
        ("quad from a wall (grazing)", quad.clone(), wall, quad_angle(wall)),
        ("sphere from the floor", sphere(c, r), floor, cone(c, r, floor)),
        ("sphere from 10 above it", sphere(c, r), near, cone(c, r, near)),
        ("sphere from its surface", sphere(c, r), on, cone(c, r, on)),
        ("sphere from far", sphere(c, r), far, cone(c, r, far)),
        ("sphere from inside", sphere(c, r), DVec3::new(200.0, 80.0, 170.0), 4.0 * PI),
    ]
}

#[test]
fn sampled_directions_have_the_density_of_an_f64_oracle() {
    for (name, lights, x, _) in cases() {
        let xf = v3(x.to_array());
        let mut rng = Uniform::new(1);
        let (mut zero, n) = (0, 100_000);
        for _ in 0..n {
            let d = lights.sample(xf, 0.0, rng.next(), rng.next());
            let len = dv(d).length();
            assert!((len - 1.0).abs() < 1e-6, "{name}: |d| = {len}");
            let p = lights.pdf(xf, d) as f64;
            assert!(p.is_finite() && p >= 0.0, "{name}: pdf {p}");
            let oracle = if let Some(l) = lights.quads.first() {
                let f = |a: [f32; 3]| DVec3::from(a.map(f64::from));
                quad_pdf64(f(l.q), f(l.u), f(l.v), dv(xf), dv(d))
            } else {
                let s = lights.spheres[0];
                let oc = DVec3::from(s.c.map(f64::from)) - dv(xf);
                let r = s.r as f64;
                if oc.length() <= r {
                    1.0 / (4.0 * PI)
                } else {
                    1.0 / (2.0 * PI * (1.0 - (1.0 - r * r / oc.length_squared()).sqrt()))
                }
            };
            if p == 0.0 || oracle == 0.0 {
                // A direction at the very edge of the shape (the f32 and f64
                // tests disagree there): counted, at most 1e-4 of them.
                zero += 1;
                continue;
            }
            // f32 density against f64: within 1e-3 relative (far from the
            // grazing and tiny-cone cases the bound is ~1e-5; the far sphere's
            // cone of 4e-6 sr and the grazing quad lose up to ~2^10 ulps).
            assert!((p / oracle - 1.0).abs() < 1e-3, "{name}: pdf {p} against {oracle}");
        }
        assert!(zero <= n / 10_000, "{name}: {zero} sampled directions have density 0");
    }
}

#[test]
fn the_density_integrates_to_one_and_the_samples_cover_the_solid_angle() {
    for (name, lights, x, omega) in cases() {
        let xf = v3(x.to_array());
        let mut rng = Uniform::new(2);
        let n = 400_000;
        // Uniform directions: E[4 pi pdf] = 1.
        let (mut s1, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let d = rng.direction();
            let f = 4.0 * PI * lights.pdf(xf, v3(d.to_array())) as f64;
            s1 += f;
            s2 += f * f;
        }
        let (mean, err) = (s1 / n as f64, ((s2 / n as f64 - (s1 / n as f64).powi(2)).max(0.0) / n as f64).sqrt());
        assert!((mean - 1.0).abs() < 5.0 * err + 1e-4, "{name}: integral {mean} +- {err}");
        // Sampled directions: E[1 / pdf] = the solid angle.
        let (mut s1, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let d = lights.sample(xf, 0.0, rng.next(), rng.next());
            let p = lights.pdf(xf, d) as f64;
            let f = if p > 0.0 { 1.0 / p } else { 0.0 };
            s1 += f;
            s2 += f * f;
        }
        let (mean, err) = (s1 / n as f64, ((s2 / n as f64 - (s1 / n as f64).powi(2)).max(0.0) / n as f64).sqrt());
        assert!(
            (mean / omega - 1.0).abs() < 1e-3 + 5.0 * err / omega,
            "{name}: E[1/pdf] {mean} +- {err}, solid angle {omega}"
        );
    }
}

#[test]
fn a_list_picks_its_shapes_uniformly_and_averages_their_densities() {
    let l = Lights {
        quads: vec![LightQuad::new([343.0, 554.0, 332.0], [-130.0, 0.0, 0.0], [0.0, 0.0, -105.0])],
        spheres: vec![LightSphere { c: [190.0, 90.0, 190.0], r: 90.0 }],
        ..Lights::default()
    };
    let x = V3::new(400.0f32, 0.0, 100.0);
    let mut rng = Uniform::new(3);
    let (mut up, n) = (0, 100_000);
    for _ in 0..n {
        let d = l.sample(x, rng.next(), rng.next(), rng.next());
        // Toward the quad y > 0.88; toward the sphere y < 0.69.
        if d.y > 0.8 {
            up += 1;
        }
        let both = l.pdf(x, d);
        let (q, s) =
            (Lights { spheres: vec![], ..l.clone() }.pdf(x, d), Lights { quads: vec![], ..l.clone() }.pdf(x, d));
        assert_eq!(both, (q + s) * 0.5, "the list's density is the average");
    }
    let frac = up as f64 / n as f64;
    assert!((frac - 0.5).abs() < 5.0 * (0.25 / n as f64).sqrt(), "{frac} of the samples toward the quad");
    // The last shape takes a pick just below 1.
    let d = l.sample(x, 0.99999994, 0.5, 0.5);
    assert!(d.y < 0.8);
}

/// Shapes from 1e-1 to 1e-6 of their distance (a small lamp, a panel light
/// far away), sphere, quad and the quad as a mesh of two triangles, seen
/// from a point away from the origin:
/// every direction the sampler draws has a positive density (a drawn
/// direction judged outside its shape weighs the whole radiance of the
/// light by the material's density alone: the floor under a small light
/// was tens of times too bright under `book`), the light sample of
/// `nee-mis` is never dropped, and E[1 / pdf] is the solid angle.
#[test]
fn tiny_and_far_shapes_give_every_sampled_direction_its_density() {
    use rtow::internals::geometry::{Emitters, LightMesh, QUAD_BASE};
    let x = DVec3::new(3.25, 0.5, -1.75);
    let dir = DVec3::new(0.3, 0.9, 0.2).normalize();
    for e in 1..=6 {
        for dist in [1.0, 40.0] {
            let size = dist * 10f64.powi(-e);
            let c = x + dir * dist;
            let (sphere, quad) = (
                LightSphere { c: [c.x as f32, c.y as f32, c.z as f32], r: size as f32 },
                LightQuad::new(
                    [(c.x - size / 2.0) as f32, c.y as f32, (c.z - size / 2.0) as f32],
                    [0.0, 0.0, size as f32],
                    [size as f32, 0.0, 0.0],
                ),
            );
            let tris = two_triangles(quad.q, quad.u, quad.v);
            let mesh = LightMesh::new(&tris, QUAD_BASE, 1e3);
            // A mesh whose corners are fewer than 16 f32 steps apart is left
            // out (at 1e-6 of the distance 1 they are 2 apart: every drawn
            // point rounds onto a corner or the diagonal, and which triangle
            // a line meets is decided by exact zeros).
            let steps = size / (c.abs().max_element() * f64::EPSILON * 2f64.powi(29));
            let mesh = (steps >= 16.0).then_some(("two triangles", Lights { meshes: vec![mesh], ..Lights::default() }));
            for (name, lights) in [
                ("sphere", Lights { spheres: vec![sphere], ..Lights::default() }),
                ("quad", Lights { quads: vec![quad], ..Lights::default() }),
            ]
            .into_iter()
            .chain(mesh)
            {
                let emitters =
                    Emitters { shapes: lights.clone(), emit: vec![[1.0; 3]], one_sided: vec![false], of_row: vec![0] };
                let xf = v3(x.to_array());
                let mut rng = Uniform::new(7);
                let n = 20_000;
                let (mut zero, mut dropped, mut inv) = (0, 0, 0.0f64);
                for _ in 0..n {
                    let (pick, u1, u2) = (rng.next(), rng.next(), rng.next());
                    let d = lights.sample(xf, pick, u1, u2);
                    let p = lights.pdf(xf, d) as f64;
                    if p > 0.0 {
                        inv += 1.0 / p;
                    } else {
                        zero += 1;
                    }
                    if emitters.sample(xf, pick, u1, u2).pdf <= 0.0 {
                        dropped += 1;
                    }
                }
                let what = format!("{name} of size {size:e} at {dist}");
                assert_eq!(zero, 0, "{what}: {zero} of {n} sampled directions have density 0");
                assert_eq!(dropped, 0, "{what}: {dropped} of {n} light samples dropped");
                // The solid angle, in f64: a sphere's cone; a small square's
                // area times its cosine over the distance squared (to 1e-2
                // at size 1e-1, far better below); the same of each triangle
                // as rounded to f32 (at 1e-5 of their coordinates' size the
                // rounding moves their corners by percents).
                let f = |a: [f32; 3]| DVec3::from(a.map(f64::from));
                let small = |t: &[[f32; 3]; 3]| {
                    let c = (f(t[0]) + f(t[1]) + f(t[2])) / 3.0 - x;
                    let n = (f(t[1]) - f(t[0])).cross(f(t[2]) - f(t[0])) / 2.0;
                    n.dot(c).abs() / c.length().powi(3)
                };
                let omega = match name {
                    "sphere" => {
                        let s = (size / dist).powi(2);
                        2.0 * PI * s / (1.0 + (1.0 - s).sqrt())
                    }
                    "quad" => size * size * dir.y / (dist * dist),
                    _ => tris.iter().map(small).sum(),
                };
                let tol = if e == 1 && name != "sphere" { 2e-2 } else { 2e-3 };
                let ratio = inv / n as f64 / omega;
                assert!((ratio - 1.0).abs() < tol, "{what}: E[1/pdf] / solid angle = {ratio}");
            }
        }
    }
}

/// A point inside a light sphere (fog inside a lamp, a path that entered
/// it): every direction meets the sphere, and `nee-mis`'s light sample
/// toward it is never dropped, at density `1 / 4 pi`.
#[test]
fn a_light_sample_from_inside_its_sphere_is_kept() {
    use rtow::internals::geometry::Emitters;
    let s = LightSphere { c: [1.0, 2.0, 3.0], r: 0.5 };
    let emitters = Emitters {
        shapes: Lights { spheres: vec![s], ..Lights::default() },
        emit: vec![[1.0; 3]],
        one_sided: vec![false],
        of_row: vec![0],
    };
    let mut rng = Uniform::new(9);
    for x in [[1.0f32, 2.0, 3.0], [1.2, 2.1, 2.9], [1.0, 2.0, 3.45]] {
        for _ in 0..10_000 {
            let ls = emitters.sample(V3::from_array(x), 0.0, rng.next(), rng.next());
            assert!((ls.pdf as f64 * 4.0 * PI - 1.0).abs() < 1e-6, "from {x:?} toward {:?}: pdf {}", ls.dir, ls.pdf);
            assert!(ls.t > 0.0 && ls.t <= 1.0, "t {}", ls.t);
        }
    }
}

/// The triangles of an icosphere of level `level` around `c`, radius `r`.
fn icosphere(c: [f32; 3], r: f32, level: u32) -> Vec<[[f32; 3]; 3]> {
    let m = rtow::mesh::icosphere::sphere_mesh(c, r, level).unwrap();
    (0..m.triangles.len()).map(|t| m.corners(t)).collect()
}

/// The parallelogram `q + a u + b v` as two triangles.
fn two_triangles(q: [f32; 3], u: [f32; 3], v: [f32; 3]) -> Vec<[[f32; 3]; 3]> {
    let add = |a: [f32; 3], b: [f32; 3]| [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
    vec![[q, add(q, u), add(add(q, u), v)], [q, add(add(q, u), v), add(q, v)]]
}

/// The f64 density of `d` from `x` toward triangles sampled uniformly by
/// area: the sum over the triangles the ray meets of `t^2 / (|cos| area)`.
fn mesh_pdf64(tris: &[[[f32; 3]; 3]], x: DVec3, d: DVec3) -> f64 {
    let f = |a: [f32; 3]| DVec3::from(a.map(f64::from));
    let area: f64 = tris.iter().map(|t| 0.5 * (f(t[1]) - f(t[0])).cross(f(t[2]) - f(t[0])).length()).sum();
    let mut sum = 0.0;
    for t in tris {
        let (v0, e1, e2) = (f(t[0]), f(t[1]) - f(t[0]), f(t[2]) - f(t[0]));
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-300 {
            continue;
        }
        let s = x - v0;
        let (a, q) = (s.dot(p) / det, s.cross(e1));
        let b = d.dot(q) / det;
        let dist = e2.dot(q) / det;
        if a >= 0.0 && b >= 0.0 && a + b <= 1.0 && dist > 0.0 {
            let n = e1.cross(e2).normalize();
            sum += dist * dist / n.dot(d).abs();
        }
    }
    sum / area
}

/// A mesh's triangles.
type Tris = Vec<[[f32; 3]; 3]>;

/// A mesh light's cases: name, triangles, the point it is seen from.
fn mesh_cases() -> Vec<(&'static str, Tris, DVec3)> {
    let floor = DVec3::new(400.0, 0.0, 100.0);
    let (q, u, v) = ([343.0, 554.0, 332.0], [-130.0, 0.0, 0.0], [0.0, 0.0, -105.0]);
    let mut tent = two_triangles([200.0, 300.0, 100.0], [100.0, 80.0, 0.0], [0.0, 0.0, 150.0]);
    tent.extend(two_triangles([300.0, 380.0, 100.0], [100.0, -80.0, 0.0], [0.0, 0.0, 150.0]));
    vec![
        ("icosphere (level 2) from the floor", icosphere([190.0, 90.0, 190.0], 90.0, 2), floor),
        ("icosphere (level 0) from near", icosphere([190.0, 90.0, 190.0], 90.0, 0), DVec3::new(190.0, 200.0, 190.0)),
        ("a quad as two triangles from the floor", two_triangles(q, u, v), floor),
        ("a tent (two bent quads) from beside it", tent, DVec3::new(600.0, 350.0, 175.0)),
    ]
}

/// A mesh light sampled by area (`book`): every drawn direction's density
/// is the f64 oracle's sum over the triangles along it, the density
/// integrates to 1 over the sphere of directions (a closed mesh's far side
/// counted: every point of the surface once), and a quad given as two
/// triangles has the quad's density.
#[test]
fn a_mesh_light_has_the_density_of_an_f64_oracle_and_it_integrates_to_one() {
    use rtow::internals::geometry::{LightMesh, QUAD_BASE};
    for (name, tris, x) in mesh_cases() {
        let lights = Lights { meshes: vec![LightMesh::new(&tris, QUAD_BASE, 1e3)], ..Lights::default() };
        let xf = v3(x.to_array());
        let mut rng = Uniform::new(11);
        let (mut zero, n) = (0, 50_000);
        for _ in 0..n {
            let d = lights.sample(xf, rng.next(), rng.next(), rng.next());
            assert!((dv(d).length() - 1.0).abs() < 1e-6, "{name}");
            let (p, oracle) = (lights.pdf(xf, d) as f64, mesh_pdf64(&tris, dv(xf), dv(d)));
            if p == 0.0 || oracle == 0.0 {
                zero += 1;
                continue;
            }
            // Along a shared edge the two tests may count one triangle or two: rare.
            if (p / oracle - 1.0).abs() >= 1e-3 {
                zero += 1;
            }
        }
        assert!(zero <= n / 10_000, "{name}: {zero} of {n} sampled directions off the oracle's density");
        let (mut s1, mut s2, m) = (0.0, 0.0, 400_000);
        for _ in 0..m {
            let f = 4.0 * PI * lights.pdf(xf, v3(rng.direction().to_array())) as f64;
            s1 += f;
            s2 += f * f;
        }
        let (mean, err) = (s1 / m as f64, ((s2 / m as f64 - (s1 / m as f64).powi(2)).max(0.0) / m as f64).sqrt());
        assert!((mean - 1.0).abs() < 5.0 * err + 1e-4, "{name}: integral {mean} +- {err}");
    }
    let (q, u, v) = ([343.0, 554.0, 332.0], [-130.0, 0.0, 0.0], [0.0, 0.0, -105.0]);
    let mesh = Lights { meshes: vec![LightMesh::new(&two_triangles(q, u, v), QUAD_BASE, 1e3)], ..Lights::default() };
    let quad = Lights { quads: vec![LightQuad::new(q, u, v)], ..Lights::default() };
    let (x, mut rng) = (V3::new(400.0f32, 0.0, 100.0), Uniform::new(12));
    for _ in 0..10_000 {
        let d = quad.sample(x, 0.0, rng.next(), rng.next());
        let (a, b) = (mesh.pdf(x, d), quad.pdf(x, d));
        assert!((a / b - 1.0).abs() < 1e-4, "two triangles {a} against the quad's {b} toward {d:?}");
    }
}

/// `nee-mis` samples a mesh light by area: a light sample's density is its
/// point's, and the density a path that hits the same point is weighted
/// with ([`Emitters::pdf_of`], from the triangle it hit) is the same.
#[test]
fn a_mesh_emitter_weighs_a_hit_with_the_density_of_its_light_sample() {
    use rtow::internals::geometry::triangles::plane;
    use rtow::internals::geometry::{triangle_hit, Emitters, LeafTriangle, LightMesh, Projection, QUAD_BASE};
    for (name, tris, x) in mesh_cases() {
        let e = Emitters {
            shapes: Lights { meshes: vec![LightMesh::new(&tris, QUAD_BASE, 1e3)], ..Lights::default() },
            emit: vec![[1.0; 3]],
            one_sided: vec![false],
            of_row: vec![0],
        };
        let leaves: Vec<LeafTriangle> = tris
            .iter()
            .enumerate()
            .map(|(k, &v)| {
                let (n, dn) = plane(v);
                LeafTriangle { v, n, dn, index: QUAD_BASE + k as u32 }
            })
            .collect();
        let xf = v3(x.to_array());
        let mut rng = Uniform::new(13);
        let (mut seen, mut other, n) = (0, 0, 20_000);
        for _ in 0..n {
            let ls = e.sample(xf, rng.next(), rng.next(), rng.next());
            assert!(ls.pdf > 0.0 && ls.pdf.is_finite(), "{name}: a light sample dropped: {}", ls.pdf);
            // The triangle the shadow ray would reach first.
            let pr = Projection::new(ls.dir);
            let (mut best, mut index) = (f32::INFINITY, 0);
            for l in &leaves {
                let (hit, t) = triangle_hit(xf, ls.dir, &pr, l);
                if hit && t < best {
                    (best, index) = (t, l.index);
                }
            }
            if (best / ls.t - 1.0).abs() > 1e-4 {
                continue; // the sampled point is hidden behind the mesh itself
            }
            seen += 1;
            let hit = e.pdf_of(xf, ls.dir, 0, index);
            // A point drawn at a fold (the tent's ridge) may be found on the
            // triangle beside its own, which leans otherwise: rare.
            if (hit / ls.pdf - 1.0).abs() >= 1e-3 {
                other += 1;
            }
        }
        assert!(seen > n / 20, "{name}: {seen} of {n} samples visible");
        assert!(other <= n / 2_000, "{name}: {other} of {seen} hits weighted with another density than their sample's");
    }
}
