//! Smooth shading: an OBJ file's vertex normals interpolated across its
//! triangles (held to an f64 oracle through the normal feature buffer), the
//! same bits in every kernel under every estimator, and no light through a
//! surface whose shading normal leans past its geometry.

use crate::common::rtow;
use std::path::Path;

/// Writes an OBJ file of triangles `faces` over positions `v` with normals `n` (one per position).
fn write_obj(path: &Path, v: &[[f64; 3]], n: &[[f64; 3]], faces: &[[usize; 3]]) {
    let mut text = String::new();
    v.iter().for_each(|p| text += &format!("v {} {} {}\n", p[0], p[1], p[2]));
    n.iter().for_each(|p| text += &format!("vn {} {} {}\n", p[0], p[1], p[2]));
    for f in faces {
        let [a, b, c] = f.map(|i| i + 1);
        text += &format!("f {a}//{a} {b}//{b} {c}//{c}\n");
    }
    std::fs::write(path, text).unwrap();
}

/// A UV sphere of unit radius, its normals the exact radial directions.
fn write_sphere(path: &Path) {
    let (rings, segs) = (12, 24);
    let mut v = vec![[0.0, 1.0, 0.0]];
    for i in 1..rings {
        let th = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segs {
            let ph = 2.0 * std::f64::consts::PI * j as f64 / segs as f64;
            v.push([th.sin() * ph.cos(), th.cos(), -th.sin() * ph.sin()]);
        }
    }
    v.push([0.0, -1.0, 0.0]);
    let at = |i: usize, j: usize| 1 + (i - 1) * segs + j % segs;
    let mut f = Vec::new();
    for j in 0..segs {
        f.push([0, at(1, j), at(1, j + 1)]);
        f.push([v.len() - 1, at(rings - 1, j + 1), at(rings - 1, j)]);
        for i in 1..rings - 1 {
            f.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            f.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    write_obj(path, &v, &v, &f);
}

fn ok(r: &crate::common::Run, what: &str) {
    assert!(!r.stderr.contains("panicked"), "{what}: {}", r.stderr);
    assert_eq!(r.code, 0, "{what}: {}", r.stderr);
}

/// A linear PFM file's values, top row first.
fn pfm(path: &Path) -> Vec<f32> {
    let bytes = std::fs::read(path).unwrap();
    let mut parts = bytes.splitn(4, |&b| b == b'\n');
    let channels = if parts.next().unwrap() == b"PF" { 3 } else { 1 };
    let size = std::str::from_utf8(parts.next().unwrap()).unwrap().to_string();
    let w: usize = size.split(' ').next().unwrap().parse().unwrap();
    parts.next();
    let body: Vec<f32> = parts.next().unwrap().chunks(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
    body.chunks(w * channels).rev().flatten().copied().collect()
}

/// A square of two triangles at z = -2 filling the view of a camera at the
/// origin, its corners' normals leaning outwards: at each pixel centre (1
/// spp: no jitter) the normal buffer holds the normals interpolated at the
/// hit point, normalized (an f64 oracle), within a few units of f32 rounding.
#[test]
fn the_shading_normal_interpolates_the_files_normals() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let v = [[-1.0, -1.0, -2.0], [1.0, -1.0, -2.0], [1.0, 1.0, -2.0], [-1.0, 1.0, -2.0]];
    let n = [[-0.6, -0.3, 1.0], [0.5, -0.6, 1.0], [0.6, 0.5, 1.0], [-0.4, 0.6, 1.0]];
    let faces = [[0, 1, 2], [0, 2, 3]];
    write_obj(&d.join("sq.obj"), &v, &n, &faces);
    std::fs::write(
        d.join("s.json"),
        r#"{"camera": {"look_from": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 40},
            "meshes": [{"shape": {"obj": {"file": "sq.obj"}}, "material": {"type": "lambertian", "albedo": [0.5, 0.5, 0.5]}}]}"#,
    )
    .unwrap();
    const N: usize = 16;
    let size = ["--width", "16", "--height", "16", "--spp", "1", "--depth", "3"];
    let mut a = vec!["render", "s.json", "--aov", "normal", "-o", "x.pfm", "-q"];
    a.extend_from_slice(&size);
    ok(&rtow(d, &a), "render");
    let got = pfm(&d.join("x.normal.pfm"));
    let h = 20f64.to_radians().tan();
    let unit = |a: [f64; 3]| {
        let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        a.map(|x| x / l)
    };
    for y in 0..N {
        for x in 0..N {
            let dir =
                unit([-h + 2.0 * h * (x as f64 + 0.5) / N as f64, h - 2.0 * h * (y as f64 + 0.5) / N as f64, -1.0]);
            let t = -2.0 / dir[2];
            let p = dir.map(|c| c * t);
            // The diagonal from corner 0 to corner 2 splits the square.
            let f = if p[1] - p[0] <= 0.0 { faces[0] } else { faces[1] };
            let (a, b, c) = (v[f[0]], v[f[1]], v[f[2]]);
            // Barycentric coordinates in the plane z = -2 (2D).
            let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
            let b1 = ((p[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (p[1] - a[1])) / det;
            let b2 = ((b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1])) / det;
            let (na, nb, nc) = (unit(n[f[0]]), unit(n[f[1]]), unit(n[f[2]]));
            let want = unit(std::array::from_fn(|k| (1.0 - b1 - b2) * na[k] + b1 * nb[k] + b2 * nc[k]));
            for k in 0..3 {
                let e = (got[3 * (y * N + x) + k] as f64 - want[k]).abs();
                assert!(e < 2e-6, "({x}, {y}) component {k}: {} against {}", got[3 * (y * N + x) + k], want[k]);
            }
        }
    }
}

/// Smooth spheres of the three materials with a flat triangle and a quad
/// light: the scalar kernel, simd8 and simd16 render the same image under
/// each estimator, no sample rejected.
#[test]
fn smooth_meshes_render_the_same_bits_in_every_kernel_under_every_estimator() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_sphere(&d.join("ball.obj"));
    // A file without normals: its triangle keeps flat shading beside the smooth ones.
    std::fs::write(d.join("tri.obj"), "v -3 0 -3\nv 3 0 -3\nv 0 3 -3.5\nf 1 2 3\n").unwrap();
    let text = r#"{"camera": {"look_from": [0, 1, 3], "look_at": [0, 0.4, -1], "vfov_deg": 50},
      "sample_toward": [{"type": "quad", "q": [-0.5, 2.5, -1.5], "u": [1, 0, 0], "v": [0, 0, 1]}],
      "quads": [{"q": [-0.5, 2.5, -1.5], "u": [1, 0, 0], "v": [0, 0, 1], "material": {"type": "diffuse_light", "emit": [6, 6, 6]}},
                {"q": [-4, -0.45, 2], "u": [8, 0, 0], "v": [0, 0, -8], "material": {"type": "lambertian", "albedo": [0.6, 0.6, 0.6]}}],
      "meshes": [{"shape": {"obj": {"file": "tri.obj"}}, "material": {"type": "lambertian", "albedo": [0.2, 0.5, 0.3]}}],
      "groups": [
        {"translate": [-1.0, 0, -1.2], "meshes": [{"shape": {"obj": {"file": "ball.obj", "scale": 0.45}}, "material": {"type": "lambertian", "albedo": [0.8, 0.3, 0.2]}}]},
        {"translate": [0, 0, -1.2], "rotate_y": 30, "meshes": [{"shape": {"obj": {"file": "ball.obj", "scale": 0.45}}, "material": {"type": "metal", "albedo": [0.8, 0.8, 0.9], "fuzz": 0.2}}]},
        {"translate": [1.0, 0, -1.2], "meshes": [{"shape": {"obj": {"file": "ball.obj", "scale": 0.45}}, "material": {"type": "dielectric", "ior": 1.5}}]}
      ],
      "background": [0.1, 0.1, 0.15]}"#;
    std::fs::write(d.join("s.json"), text).unwrap();
    let size = ["--width", "40", "--height", "30", "--spp", "4", "--depth", "8"];
    for estimator in ["bsdf", "nee-mis", "book"] {
        let mut hashes = Vec::new();
        for kernel in ["scalar", "simd8", "simd16"] {
            let mut a = vec!["render", "s.json", "--kernel", kernel, "--estimator", estimator, "-o", "x.png"];
            a.extend_from_slice(&["--stats-json", "x.json", "-q"]);
            a.extend_from_slice(&size);
            ok(&rtow(d, &a), &format!("{estimator} {kernel}"));
            let st: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("x.json")).unwrap()).unwrap();
            assert_eq!(st["rejected_samples"], 0, "{estimator} {kernel}");
            hashes.push(st["image_hash"].as_str().unwrap().to_string());
        }
        assert!(hashes.iter().all(|h| h == &hashes[0]), "{estimator}: {hashes:?}");
    }
}

/// A sheet filling the view whose normals all lean 80 degrees off its
/// plane's, lit only from behind: no path and no light sample passes
/// through it, under any estimator and kernel: the image is black. (Lit
/// from the front, the same sheet is not.)
#[test]
fn light_does_not_pass_through_a_surface_whose_shading_normal_leans_past_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let v = [[-4.0, -4.0, 0.0], [4.0, -4.0, 0.0], [4.0, 4.0, 0.0], [-4.0, 4.0, 0.0]];
    let lean = [0.985, 0.0, 0.174];
    write_obj(&d.join("sheet.obj"), &v, &[lean; 4], &[[0, 1, 2], [0, 2, 3]]);
    let scene = |light_z: f32, facing: f32| {
        format!(
            r#"{{"camera": {{"look_from": [0, 0, 3], "look_at": [0, 0, 0], "vfov_deg": 60}},
              "meshes": [{{"shape": {{"obj": {{"file": "sheet.obj"}}}}, "material": {{"type": "lambertian", "albedo": [0.9, 0.9, 0.9]}}}}],
              "quads": [{{"q": [1, -3, {light_z}], "u": [{facing}, 0, 0], "v": [0, 6, 0], "material": {{"type": "diffuse_light", "emit": [10, 10, 10]}}}}],
              "sample_toward": [{{"type": "quad", "q": [1, -3, {light_z}], "u": [{facing}, 0, 0], "v": [0, 6, 0]}}],
              "background": [0, 0, 0]}}"#
        )
    };
    let size = ["--width", "24", "--height", "24", "--spp", "16", "--depth", "6"];
    // Behind the sheet (z = -0.5), on the side its normals lean to (x > 1).
    std::fs::write(d.join("behind.json"), scene(-0.5, 2.0)).unwrap();
    // In front of it, beside the camera's view, facing the sheet.
    std::fs::write(d.join("front.json"), scene(2.9, 2.0)).unwrap();
    for estimator in ["bsdf", "nee-mis", "book"] {
        for kernel in ["scalar", "simd"] {
            for (file, dark) in [("behind.json", true), ("front.json", false)] {
                let mut a = vec!["render", file, "--kernel", kernel, "--estimator", estimator, "-o", "x.pfm", "-q"];
                a.extend_from_slice(&size);
                ok(&rtow(d, &a), &format!("{file} {estimator} {kernel}"));
                let img = pfm(&d.join("x.pfm"));
                let lit = img.iter().filter(|&&c| c != 0.0).count();
                match dark {
                    true => assert_eq!(lit, 0, "{file} {estimator} {kernel}: light came through the sheet"),
                    false => assert!(lit > img.len() / 4, "{file} {estimator} {kernel}: {lit} values lit"),
                }
            }
        }
    }
}
