//! Feature buffers for denoisers (`render --aov albedo,normal,depth`): each
//! pixel the mean of its camera rays' first surfaces, held to an f64 oracle
//! of the camera and the spheres; the same bits in every kernel and in a
//! crop's window; as EXR layers or PFM files beside the image, written with
//! the image or not at all.

use crate::common::{failure, listing, rtow, Run};
use std::path::Path;

/// Three spheres 3 units in front of a camera at the origin (vfov 40°,
/// square image): a diffuse one in the middle, glass on the left, a light
/// on the right, before a background brighter than 1 in blue.
const SCENE: &str = r#"{"camera": {"look_from": [0, 0, 0], "look_at": [0, 0, -1], "vup": [0, 1, 0], "vfov_deg": 40},
  "spheres": [
    {"center": [0, 0, -3], "radius": 0.4, "material": {"type": "lambertian", "albedo": [0.8, 0.3, 0.2]}},
    {"center": [-0.75, 0, -3], "radius": 0.3, "material": {"type": "dielectric", "ior": 1.5}},
    {"center": [0.75, 0, -3], "radius": 0.3, "material": {"type": "diffuse_light", "emit": [4, 2, 0]}}
  ],
  "background": [0.2, 0.4, 2.0]}"#;

const N: u32 = 32;
const SIZE: [&str; 8] = ["--width", "32", "--height", "32", "--spp", "8", "--depth", "4"];

fn ok(r: &Run, what: &str) {
    assert!(!r.stderr.contains("panicked"), "{what}: {}", r.stderr);
    assert_eq!(r.code, 0, "{what}: {}", r.stderr);
}

/// A PFM file: width, height, channels and values, top row first.
fn pfm(path: &Path) -> (u32, u32, usize, Vec<f32>) {
    let bytes = std::fs::read(path).unwrap();
    let mut lines = bytes.splitn(4, |&b| b == b'\n');
    let channels = match lines.next().unwrap() {
        b"PF" => 3,
        b"Pf" => 1,
        m => panic!("{}: magic {m:?}", path.display()),
    };
    let size = std::str::from_utf8(lines.next().unwrap()).unwrap();
    let (w, h) = size.split_once(' ').unwrap();
    let (w, h): (u32, u32) = (w.parse().unwrap(), h.parse().unwrap());
    assert_eq!(lines.next().unwrap(), b"-1.0", "little-endian");
    let body: Vec<f32> = lines.next().unwrap().chunks(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
    let row = w as usize * channels;
    assert_eq!(body.len(), row * h as usize);
    let top_first = body.chunks(row).rev().flatten().copied().collect();
    (w, h, channels, top_first)
}

/// The camera ray through the point (sx, sy) of the image plane (pixels, y
/// down), in f64.
fn ray(sx: f64, sy: f64) -> [f64; 3] {
    let h = 20f64.to_radians().tan();
    let d = [-h + 2.0 * h * sx / N as f64, h - 2.0 * h * sy / N as f64, -1.0];
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    d.map(|c| c / len)
}

/// The first of the scene's spheres that unit ray `d` from the origin hits:
/// its index, the distance and the unit normal there.
fn oracle(d: [f64; 3]) -> Option<(usize, f64, [f64; 3])> {
    let spheres = [([0.0, 0.0, -3.0], 0.4), ([-0.75, 0.0, -3.0], 0.3), ([0.75, 0.0, -3.0], 0.3)];
    let mut best: Option<(usize, f64, [f64; 3])> = None;
    for (i, (c, r)) in spheres.iter().enumerate() {
        let b: f64 = (0..3).map(|k| d[k] * c[k]).sum();
        let cc: f64 = (0..3).map(|k| c[k] * c[k]).sum::<f64>() - r * r;
        let disc = b * b - cc;
        if disc < 0.0 {
            continue;
        }
        let t = b - disc.sqrt();
        if best.is_none_or(|(_, bt, _)| t < bt) {
            best = Some((i, t, [0, 1, 2].map(|k| (t * d[k] - c[k]) / r)));
        }
    }
    best
}

/// Each pixel whose whole square (its corners and centre, by the oracle)
/// sees one sphere gets that sphere's albedo exactly, and a mean normal and
/// depth within the range the oracle finds over its square; a pixel whose
/// square sees none gets the background clamped to 1, and zeros.
#[test]
fn the_buffers_are_the_first_surface_averaged_over_the_samples() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("s.json"), SCENE).unwrap();
    let mut a = vec!["render", "s.json", "--aov", "albedo,normal,depth", "-o", "x.png", "-q"];
    a.extend_from_slice(&SIZE);
    ok(&rtow(d, &a), "render");
    let (albedo, normal, depth) =
        (pfm(&d.join("x.albedo.pfm")), pfm(&d.join("x.normal.pfm")), pfm(&d.join("x.depth.pfm")));
    assert_eq!((albedo.0, albedo.1, albedo.2, normal.2, depth.2), (N, N, 3, 3, 1));
    let want_albedo = [[0.8f32, 0.3, 0.2], [1.0, 1.0, 1.0], [1.0, 0.5, 0.0]];
    let mut seen = [0; 4];
    for y in 0..N {
        for x in 0..N {
            let i = (y * N + x) as usize;
            let at = |v: &[f32]| [v[3 * i], v[3 * i + 1], v[3 * i + 2]];
            let points = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)];
            let hits: Vec<_> = points.iter().map(|(u, v)| oracle(ray(x as f64 + u, y as f64 + v))).collect();
            if hits.iter().all(|h| h.is_none()) {
                assert_eq!(at(&albedo.3), [0.2, 0.4, 1.0], "({x}, {y}): the background, clamped");
                assert_eq!((at(&normal.3), depth.3[i]), ([0.0; 3], 0.0), "({x}, {y})");
                seen[3] += 1;
                continue;
            }
            let Some(Some((k, ..))) = hits.first().copied() else { continue };
            if !hits.iter().all(|h| h.is_some_and(|h| h.0 == k)) {
                continue;
            }
            seen[k] += 1;
            assert_eq!(at(&albedo.3), want_albedo[k], "({x}, {y}) on sphere {k}");
            let within = |got: f32, vals: Vec<f64>, what: &str| {
                let (lo, hi) = vals.iter().fold((f64::MAX, f64::MIN), |(l, h), &v| (l.min(v), h.max(v)));
                assert!(
                    got as f64 >= lo - 1e-3 && got as f64 <= hi + 1e-3,
                    "({x}, {y}) {what}: {got} not in [{lo}, {hi}]"
                );
            };
            within(depth.3[i], hits.iter().map(|h| h.unwrap().1).collect(), "depth");
            for c in 0..3 {
                within(at(&normal.3)[c], hits.iter().map(|h| h.unwrap().2[c]).collect(), "normal");
            }
        }
    }
    assert!(seen.iter().all(|&n| n >= 20), "pixels checked per sphere and background: {seen:?}");
}

/// Every kernel writes the same bits; an EXR output holds the colour and
/// the buffers as layers, the same values as the PFM files and the image;
/// a crop's buffers are the window of the whole render's.
#[test]
fn the_buffers_are_the_same_bits_in_every_kernel_in_an_exr_and_in_a_crop() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for scene in ["final", "nw-cornell-box"] {
        let mut first: Option<Vec<Vec<u8>>> = None;
        for kernel in ["scalar", "simd8", "simd16"] {
            let mut a = vec!["render", scene, "--aov", "albedo,normal,depth", "--kernel", kernel, "-o", "x.pfm", "-q"];
            a.extend_from_slice(&SIZE);
            ok(&rtow(d, &a), kernel);
            let files: Vec<Vec<u8>> = ["x.albedo.pfm", "x.normal.pfm", "x.depth.pfm"]
                .iter()
                .map(|f| std::fs::read(d.join(f)).unwrap())
                .collect();
            match &first {
                None => first = Some(files),
                Some(f) => assert!(f == &files, "{scene}: {kernel} differs from scalar"),
            }
        }
        let mut a =
            vec!["render", scene, "--aov", "albedo,normal,depth", "-o", "x.exr", "--stats-json", "s.json", "-q"];
        a.extend_from_slice(&SIZE);
        ok(&rtow(d, &a), "exr");
        let layers = exr_channels(&d.join("x.exr"));
        let names: Vec<&str> = layers.iter().map(|(n, _)| n.as_str()).collect();
        let want = ["B", "G", "R", "albedo.B", "albedo.G", "albedo.R", "depth.Z", "normal.X", "normal.Y", "normal.Z"];
        assert_eq!(names, want, "{scene}: channels, sorted");
        let channel = |name: &str| layers.iter().find(|(n, _)| n == name).unwrap().1.clone();
        let (_, _, _, colour) = pfm(&d.join("x.pfm"));
        for (file, names) in [("x.albedo.pfm", ["albedo.R", "albedo.G", "albedo.B"]), ("x.pfm", ["R", "G", "B"])] {
            let (_, _, _, v) = if file == "x.pfm" { (0, 0, 3, colour.clone()) } else { pfm(&d.join(file)) };
            for (c, n) in names.iter().enumerate() {
                let got: Vec<u32> = channel(n).iter().map(|v| v.to_bits()).collect();
                let want: Vec<u32> = v.iter().skip(c).step_by(3).map(|v| v.to_bits()).collect();
                assert!(got == want, "{scene}: {n} differs from {file}");
            }
        }
        let (_, _, _, dep) = pfm(&d.join("x.depth.pfm"));
        assert!(channel("depth.Z").iter().zip(&dep).all(|(a, b)| a.to_bits() == b.to_bits()), "{scene}: depth");
        // Readers that know only RGB still read the colour.
        let rgb = image::open(d.join("x.exr")).unwrap().into_rgb32f().into_raw();
        assert!(rgb.iter().zip(&colour).all(|(a, b)| a.to_bits() == b.to_bits()), "{scene}: RGB of the layered EXR");
        let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("s.json")).unwrap()).unwrap();
        assert_eq!(stats["aov"]["buffers"], serde_json::json!(["albedo", "normal", "depth"]), "{}", stats["aov"]);
        assert_eq!(stats["aov"]["files"], serde_json::json!(["x.exr"]), "{}", stats["aov"]);
        // A crop: the window of the whole render's buffers.
        let mut a = vec!["render", scene, "--aov", "normal", "--crop", "5,21,3,30", "-o", "c.png", "-q"];
        a.extend_from_slice(&SIZE);
        ok(&rtow(d, &a), "crop");
        let (cw, ch, _, crop) = pfm(&d.join("c.normal.pfm"));
        assert_eq!((cw, ch), (16, 27));
        let (_, _, _, whole) = pfm(&d.join("x.normal.pfm"));
        for y in 3..30 {
            for x in 5..21 {
                let (i, j) = (((y - 3) * cw + x - 5) as usize * 3, (y * N + x) as usize * 3);
                assert_eq!(crop[i..i + 3], whole[j..j + 3], "{scene} ({x}, {y})");
            }
        }
        assert!(!d.join("c.albedo.pfm").exists(), "only the buffers asked for");
    }
}

/// The channels of an EXR file by name (sorted), as f32.
fn exr_channels(path: &Path) -> Vec<(String, Vec<f32>)> {
    use exr::prelude::*;
    let img = read().no_deep_data().largest_resolution_level().all_channels().first_valid_layer().all_attributes();
    let img = img.from_file(path).unwrap();
    img.layer_data
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect()
}

/// Buffers where no image is written, or named wrong, are refused before
/// any work; an output of theirs that cannot be written leaves nothing.
#[test]
fn the_buffers_are_refused_where_they_cannot_go_and_written_with_the_image_or_not_at_all() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&[&str], &str); 4] = [
        (&["--aov", "albedo,normals"], "did you mean 'normal'"),
        (&["--aov", "albedo", "-o", "p.rtfilm"], "a partial film carries none"),
        (&["--aov", "albedo", "--shard", "1/2", "-o", "p.rtfilm"], "a partial film carries none"),
        (&["--aov", "depth,depth"], "twice"),
    ];
    for (extra, says) in cases {
        let mut a = vec!["render", "final"];
        a.extend_from_slice(&SIZE);
        a.extend_from_slice(extra);
        let line = failure(&rtow(d, &a), 2, says);
        assert!(line.contains("--aov") && line.contains(says), "{extra:?}: {line}");
    }
    let r = rtow(d, &["render", "ch01-gradient", "--aov", "albedo", "-q"]);
    assert!(failure(&r, 2, "gradient").contains("no surfaces"), "{}", r.stderr);
    assert!(listing(d).is_empty(), "{:?}", listing(d));
    // A buffer's file that cannot be written: nothing is.
    std::fs::create_dir(d.join("x.normal.pfm")).unwrap();
    let mut a = vec!["render", "final", "--aov", "albedo,normal", "-o", "x.png"];
    a.extend_from_slice(&SIZE);
    let r = rtow(d, &a);
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert!(r.stderr.contains("x.normal.pfm"), "{}", r.stderr);
    assert_eq!(listing(d), ["x.normal.pfm"], "nothing written");
}
