//! A scene, rtow against the book's own C++, region by region (the Cornell box, the Cornell smoke,
//! the final scene: docs/books.md).
//!
//! Reads two renders of each side with different seeds, the book's as the 8-bit P3 PPM its
//! code writes and rtow's as a linear PFM (`rtow render ... --float x.pfm`), of the same size.
//! rtow's linear values are first encoded exactly as the book's `write_color` encodes its own
//! (gamma 2: `int(256 clamp(sqrt(x), 0, 0.999))`, in f64), so both sides carry the same clamp
//! (the light's 15 becomes 255) and the same quantization; every byte is then decoded to
//! linear light at the middle of its step, `((b + 0.5) / 256)^2`, and compared there.
//!
//! The image is split into K x K regions. For each region and channel: the mean of each
//! side (the average of its two seeds), and `z = (book - rtow) / sqrt(s_book^2 + s_rtow^2)`,
//! where `s^2 = sum_p (x1_p - x2_p)^2 / (4 n^2)` is the variance of the region's two-seed
//! mean estimated from the seeds' per-pixel differences (`n` pixels; pixels' errors are
//! independent: every pixel draws its own samples). A region that is identical on both
//! sides in every pixel (the clamped light) has `z = 0`.
//!
//! Any of the four may be either kind (a `.ppm` is read as the book's, anything else as
//! rtow's), to compare two rtow renders, or two of the book's, the same way.
//!
//! Usage: `cargo run --release --example compare_regions -- [--regions K] [--noise] BOOK1.ppm
//! BOOK2.ppm RTOW1.pfm RTOW2.pfm` (K defaults to 6; `--noise` adds each side's `s`, the standard
//! error of its two-seed mean, per channel). Prints a Markdown table, then a summary: the
//! number of |z| > 3, the root mean square of z (about 1 when the two agree within noise).
//! A last line checks the noise estimate on each side: seed 1 against seed 2, per region
//! and channel, `(mean1 - mean2) / (2 s)`, whose root mean square is about 1 when pixels'
//! errors are independent and the estimate is right.

use std::path::Path;
use std::process::ExitCode;

/// A linear image, row-major from the top-left, as f64.
struct Linear {
    width: usize,
    height: usize,
    data: Vec<[f64; 3]>,
}

/// The book's 8-bit encoding of one linear value (color.h's `write_color`).
fn book_byte(x: f64) -> u8 {
    let g = if x > 0.0 { x.sqrt() } else { 0.0 };
    (256.0 * g.clamp(0.0, 0.999)) as u8
}

/// A byte decoded to linear light at the middle of its quantization step.
fn decode(b: u8) -> f64 {
    let g = (b as f64 + 0.5) / 256.0;
    g * g
}

/// Reads the book's ASCII PPM (P3, maxval 255).
fn read_ppm(path: &Path) -> Result<Linear, String> {
    let name = path.display();
    let text = std::fs::read_to_string(path).map_err(|e| format!("{name}: {e}"))?;
    let mut words = text.split_ascii_whitespace();
    let mut next = |what: &str| words.next().ok_or_else(|| format!("{name}: truncated PPM: {what} missing"));
    if next("magic")? != "P3" {
        return Err(format!("{name}: not a P3 PPM (the book writes P3)"));
    }
    let mut number = |what: &str| -> Result<usize, String> {
        let w = next(what)?;
        w.parse::<usize>().map_err(|_| format!("{name}: PPM {what} '{w}' is not a non-negative integer"))
    };
    let (width, height, maxval) = (number("width")?, number("height")?, number("maxval")?);
    if maxval != 255 || width == 0 || height == 0 || width * height > rtow::limits::MAX_PIXELS as usize {
        return Err(format!("{name}: a {width}x{height} PPM with maxval {maxval}: expected the book's 8-bit image"));
    }
    let mut data = Vec::with_capacity(width * height);
    for _ in 0..width * height {
        let mut px = [0.0; 3];
        for c in &mut px {
            let v = number("pixel value")?;
            let b = u8::try_from(v).map_err(|_| format!("{name}: pixel value {v} above 255"))?;
            *c = decode(b);
        }
        data.push(px);
    }
    Ok(Linear { width, height, data })
}

/// Reads rtow's linear PFM and passes it through the book's encoding.
fn read_rtow(path: &Path) -> Result<Linear, String> {
    let img = rtow::Image::load_float(path).map_err(|e| e.to_string())?;
    let data = img.data.iter().map(|p| p.map(|v| decode(book_byte(v as f64)))).collect();
    Ok(Linear { width: img.width as usize, height: img.height as usize, data })
}

/// Reads a PPM as the book's, anything else as rtow's linear image.
fn read_any(path: &str) -> Result<Linear, String> {
    let path = Path::new(path);
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("ppm")) {
        read_ppm(path)
    } else {
        read_rtow(path)
    }
}

/// Per region and channel: the two-seed mean, the variance of that mean, and seed 1's mean
/// minus seed 2's.
type Region = ([f64; 3], [f64; 3], [f64; 3]);

fn regions(a: &Linear, b: &Linear, k: usize) -> Vec<Region> {
    let mut out = Vec::with_capacity(k * k);
    for ry in 0..k {
        for rx in 0..k {
            let (y0, y1) = (ry * a.height / k, (ry + 1) * a.height / k);
            let (x0, x1) = (rx * a.width / k, (rx + 1) * a.width / k);
            let n = ((y1 - y0) * (x1 - x0)) as f64;
            let (mut sum, mut sq, mut diff) = ([0.0; 3], [0.0; 3], [0.0; 3]);
            for y in y0..y1 {
                for x in x0..x1 {
                    let (p, q) = (a.data[y * a.width + x], b.data[y * a.width + x]);
                    for c in 0..3 {
                        sum[c] += 0.5 * (p[c] + q[c]);
                        sq[c] += (p[c] - q[c]) * (p[c] - q[c]);
                        diff[c] += p[c] - q[c];
                    }
                }
            }
            out.push((sum.map(|s| s / n), sq.map(|s| s / (4.0 * n * n)), diff.map(|d| d / n)));
        }
    }
    out
}

fn run() -> Result<(), String> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut k = 6;
    if let Some(i) = args.iter().position(|a| a == "--regions") {
        let v = args.get(i + 1).ok_or("--regions needs a number")?;
        k = v.parse().ok().filter(|&k| (1..=64).contains(&k)).ok_or(format!("--regions {v}: give 1 to 64"))?;
        args.drain(i..i + 2);
    }
    let noise = args.iter().position(|a| a == "--noise").map(|i| args.remove(i)).is_some();
    let [b1, b2, r1, r2] = <[String; 4]>::try_from(args)
        .map_err(|_| "usage: compare_regions [--regions K] [--noise] BOOK1.ppm BOOK2.ppm RTOW1.pfm RTOW2.pfm")?;
    let book = [read_any(&b1)?, read_any(&b2)?];
    let rtow = [read_any(&r1)?, read_any(&r2)?];
    for img in book.iter().chain(&rtow) {
        if (img.width, img.height) != (book[0].width, book[0].height) {
            return Err(format!(
                "sizes differ: {}x{} against {}x{}",
                img.width, img.height, book[0].width, book[0].height
            ));
        }
    }
    if k > book[0].width.min(book[0].height) {
        return Err(format!("--regions {k}: more regions than pixels across"));
    }
    let bk = regions(&book[0], &book[1], k);
    let rt = regions(&rtow[0], &rtow[1], k);
    let fmt3 = |v: [f64; 3]| format!("{:.4} {:.4} {:.4}", v[0], v[1], v[2]);
    let sd3 = |v: [f64; 3]| format!("{:.5} {:.5} {:.5}", v[0].sqrt(), v[1].sqrt(), v[2].sqrt());
    if noise {
        println!("| region (row, col) | book mean (r g b) | book s | rtow mean (r g b) | rtow s | z (r g b) |");
        println!("|---|---|---|---|---|---|");
    } else {
        println!("| region (row, col) | book mean (r g b) | rtow mean (r g b) | z (r g b) |");
        println!("|---|---|---|---|");
    }
    let (mut over, mut sum_z2, mut count, mut max_z) = (0, 0.0, 0, 0.0f64);
    for (i, ((mb, vb, _), (mr, vr, _))) in bk.iter().zip(&rt).enumerate() {
        let z: [f64; 3] = std::array::from_fn(|c| {
            let d = mb[c] - mr[c];
            let s = (vb[c] + vr[c]).sqrt();
            if s > 0.0 {
                d / s
            } else if d == 0.0 {
                0.0
            } else {
                d.signum() * f64::INFINITY
            }
        });
        for &v in &z {
            over += (v.abs() > 3.0) as usize;
            sum_z2 += v * v;
            count += 1;
            max_z = max_z.max(v.abs());
        }
        let flag = if z.iter().any(|v| v.abs() > 3.0) { " **" } else { "" };
        let (book, rtow) = if noise {
            (format!("{} | {}", fmt3(*mb), sd3(*vb)), format!("{} | {}", fmt3(*mr), sd3(*vr)))
        } else {
            (fmt3(*mb), fmt3(*mr))
        };
        println!("| ({}, {}){flag} | {book} | {rtow} | {:+.2} {:+.2} {:+.2} |", i / k, i % k, z[0], z[1], z[2]);
    }
    println!();
    println!(
        "{k}x{k} regions of {}x{} pixels, {count} region-channels: {over} with |z| > 3, rms z {:.3}, max |z| {:.2}",
        book[0].width,
        book[0].height,
        (sum_z2 / count as f64).sqrt(),
        max_z
    );
    // Seed against seed on each side: the difference of two means has variance 4 s^2.
    let self_rms = |side: &[Region]| {
        let z2: Vec<f64> = side
            .iter()
            .flat_map(|(_, v, d)| (0..3).filter(|&c| v[c] > 0.0).map(move |c| d[c] * d[c] / (4.0 * v[c])))
            .collect();
        ((z2.iter().sum::<f64>() / z2.len().max(1) as f64).sqrt(), z2.len())
    };
    let ((zb, nb), (zr, nr)) = (self_rms(&bk), self_rms(&rt));
    println!("noise check, seed 1 against seed 2: rms z {zb:.3} for the book ({nb} region-channels), {zr:.3} for rtow ({nr})");
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("compare_regions: {e}");
            ExitCode::from(2)
        }
    }
}
