//! Looking closer: `render --crop` (a window of the image, its pixels bit for
//! bit those of the whole render, in every kernel and for windows that cut
//! tiles anywhere), `--trace-pixel` (one pixel's paths, event by event), and
//! a linear image as the output.

use crate::common::{failure, listing, rtow};
use std::path::Path;

/// The linear image of an EXR file: width, height and RGB values.
fn exr(path: &Path) -> (u32, u32, Vec<f32>) {
    let img = image::open(path).unwrap().into_rgb32f();
    (img.width(), img.height(), img.into_raw())
}

const SIZE: [&str; 8] = ["--width", "50", "--height", "30", "--spp", "3", "--depth", "6"];

#[test]
fn a_crop_is_bit_for_bit_the_window_of_the_whole_render() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for scene in ["final", "nw-cornell-box"] {
        let mut whole = vec!["render", scene, "-o", "w.png", "--float", "w.exr", "-q"];
        whole.extend_from_slice(&SIZE);
        rtow(d, &whole).ok();
        let (w, _, full) = exr(&d.join("w.exr"));
        // Windows that start and end inside tiles (16 pixels), a single pixel, the whole image.
        for (x0, x1, y0, y1) in [(3, 37, 5, 22), (49, 50, 0, 1), (0, 50, 0, 30), (17, 18, 29, 30)] {
            for kernel in ["scalar", "simd8", "simd16"] {
                let window = format!("{x0},{x1},{y0},{y1}");
                let mut a = vec!["render", scene, "--crop", &window, "--kernel", kernel, "-o", "c.png"];
                a.extend_from_slice(&["--float", "c.exr", "--stats-json", "c.json", "-q"]);
                a.extend_from_slice(&SIZE);
                rtow(d, &a).ok();
                let (cw, ch, crop) = exr(&d.join("c.exr"));
                assert_eq!((cw, ch), (x1 - x0, y1 - y0), "{scene} {window}");
                for y in y0..y1 {
                    for x in x0..x1 {
                        let at = |v: &[f32], i: u32| [v[3 * i as usize], v[3 * i as usize + 1], v[3 * i as usize + 2]];
                        let (a, b) = (at(&crop, (y - y0) * cw + (x - x0)), at(&full, y * w + x));
                        assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "{scene} {kernel} {window} ({x}, {y})");
                    }
                }
                let stats: serde_json::Value =
                    serde_json::from_str(&std::fs::read_to_string(d.join("c.json")).unwrap()).unwrap();
                assert_eq!(stats["crop"]["x"]["start"], x0, "{}", stats["crop"]);
                assert_eq!(stats["samples"], (x1 - x0) * (y1 - y0) * 3, "{scene} {window}: samples of the window only");
            }
        }
    }
}

#[test]
fn a_bad_window_or_a_crop_with_what_it_cannot_do_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&[&str], &str); 9] = [
        (&["--crop", "0,10,0"], "x0,x1,y0,y1"),
        (&["--crop", "a,b,c,d"], "x0,x1,y0,y1"),
        (&["--crop", "-1,10,0,10"], "x0,x1,y0,y1"),
        (&["--crop", "10,10,0,10"], "not a window"),
        (&["--crop", "0,51,0,10"], "not a window"),
        (&["--crop", "0,10,0,31"], "not a window"),
        (&["--crop", "0,10,0,10", "--shard", "1/2", "-o", "p.rtfilm"], "--shard"),
        (&["--crop", "0,10,0,10", "-o", "p.rtfilm"], ".rtfilm"),
        (&["--crop", "0,10,0,10", "--time-limit", "1s"], "--time-limit"),
    ];
    for (extra, says) in cases {
        let mut a = vec!["render", "final"];
        a.extend_from_slice(&SIZE);
        a.extend_from_slice(extra);
        let line = failure(&rtow(d, &a), 2, says);
        assert!(line.contains("--crop") && line.contains(says), "{extra:?}: {line}");
    }
    assert!(listing(d).is_empty(), "{:?}", listing(d));
}

#[test]
fn the_output_may_be_a_linear_image_by_its_extension() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut a = vec!["render", "final", "-o", "a.png", "--float", "a.exr", "-q"];
    a.extend_from_slice(&SIZE);
    rtow(d, &a).ok();
    for out in ["b.exr", "b.pfm"] {
        let mut b = vec!["render", "final", "-o", out, "-q"];
        b.extend_from_slice(&SIZE);
        rtow(d, &b).ok();
    }
    assert_eq!(std::fs::read(d.join("a.exr")).unwrap(), std::fs::read(d.join("b.exr")).unwrap());
    let (w, h, pfm) = (50usize, 30usize, std::fs::read(d.join("b.pfm")).unwrap());
    assert!(pfm.starts_with(b"PF\n50 30\n"), "a PFM header");
    assert_eq!(pfm.len() - pfm.iter().enumerate().filter(|&(_, &c)| c == b'\n').nth(2).unwrap().0 - 1, w * h * 12);
    let r = rtow(d, &["render", "final", "-o", "b.jpg"]);
    assert!(failure(&r, 2, "jpg").contains(".png or .exr or .pfm or .rtfilm"), "{}", r.stderr);
}

/// The pixel value a trace ends with, as its text prints it.
fn traced_value(stdout: &str) -> String {
    let line = stdout.lines().find(|l| l.starts_with("pixel value over")).expect("the trace ends with the pixel value");
    line.rsplit_once(": ").unwrap().1.to_string()
}

#[test]
fn a_pixel_trace_follows_its_paths_and_ends_with_the_renders_value() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut a = vec!["render", "final", "--trace-pixel", "20,12", "--trace-samples", "3"];
    a.extend_from_slice(&SIZE);
    let r = rtow(d, &a);
    r.ok();
    for want in ["sample 0:", "sample 2:", "camera ray from", "ray 1: hits sphere", "scatters toward", "radiance ("] {
        assert!(r.stdout.contains(want), "no {want:?} in the trace:\n{}", r.stdout);
    }
    assert!(!r.stdout.contains("sample 3:"), "three samples only");
    assert!(listing(d).is_empty(), "a trace writes no file: {:?}", listing(d));
    // The value it ends with is the render's pixel, bit for bit.
    let mut c = vec!["render", "final", "--crop", "20,21,12,13", "-o", "p.exr", "-q"];
    c.extend_from_slice(&SIZE);
    rtow(d, &c).ok();
    let (_, _, v) = exr(&d.join("p.exr"));
    assert_eq!(traced_value(&r.stdout), format!("({:?}, {:?}, {:?})", v[0], v[1], v[2]));
    // Light samples are traced as their own terms.
    let mut n = vec!["render", "nw-cornell-box", "--estimator", "nee-mis", "--trace-pixel", "25,15"];
    n.extend_from_slice(&["--trace-samples", "16", "--width", "50", "--height", "30", "--spp", "16", "--depth", "6"]);
    let r = rtow(d, &n);
    r.ok();
    assert!(r.stdout.contains("+ light sample ("), "{}", r.stdout);
    assert!(r.stdout.contains("(lambertian)"), "{}", r.stdout);
}

#[test]
fn a_pixel_trace_refuses_what_it_cannot_follow() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&[&str], &str); 6] = [
        (&["--trace-pixel", "50,3"], "not a pixel"),
        (&["--trace-pixel", "3"], "x,y"),
        (&["--trace-pixel", "-3,4"], "x,y"),
        (&["--trace-pixel", "3,4", "--trace-samples", "0"], "--trace-samples"),
        (&["--trace-pixel", "3,4", "--trace-samples", "65"], "--trace-samples"),
        (&["--trace-pixel", "3,4", "-o", "x.png"], "--output"),
    ];
    for (extra, says) in cases {
        let mut a = vec!["render", "final"];
        a.extend_from_slice(&SIZE);
        a.extend_from_slice(extra);
        let line = failure(&rtow(d, &a), 2, says);
        assert!(line.contains(says), "{extra:?}: {line}");
    }
    let r = rtow(d, &["render", "ch01-gradient", "--trace-pixel", "1,1"]);
    assert!(failure(&r, 2, "gradient").contains("--trace-pixel"));
}
