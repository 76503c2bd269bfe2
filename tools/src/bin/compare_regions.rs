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
//! sides in every pixel (the clamped light) has `z = 0`. The statistics are `rtow diff`'s
//! (`rtow::instruments::diff::regions`); this example adds the book's PPM and encoding,
//! and prints a table per region. Two files rtow reads (PNG, EXR, PFM, `.rtfilm`) compare
//! the same way with `rtow diff A1 B1 --a2 A2 --b2 B2`.
//!
//! Any of the four may be either kind (a `.ppm` is read as the book's, anything else as
//! rtow's), to compare two rtow renders, or two of the book's, the same way.
//!
//! Usage: `cargo run --release -p rtow-tools --bin compare_regions -- [--regions K] [--noise] BOOK1.ppm
//! BOOK2.ppm RTOW1.pfm RTOW2.pfm` (K defaults to 6; `--noise` adds each side's `s`, the standard
//! error of its two-seed mean, per channel). Prints a Markdown table, then a summary: the
//! number of |z| > 3, the root mean square of z (about 1 when the two agree within noise).
//! A last line checks the noise estimate on each side: seed 1 against seed 2, per region
//! and channel, `(mean1 - mean2) / (2 s)`, whose root mean square is about 1 when pixels'
//! errors are independent and the estimate is right.

use rtow::instruments::diff::{decode_byte, Regions, ZTest};
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

/// A byte decoded to linear light at the middle of its quantization step (gamma 2).
fn decode(b: u8) -> f64 {
    decode_byte(b, 2.0)
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

/// A side's two seeds, region by region (`rtow diff`'s statistics).
fn regions(a: &Linear, b: &Linear, k: usize) -> Regions {
    Regions::two_renders(k, a.width, a.height, |i| a.data[i], |i| b.data[i])
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
    let t = ZTest::new(&bk, &rt, 3.0);
    for ((b, r), z) in bk.cells.iter().zip(&rt.cells).zip(&t.cells) {
        let z = z.z;
        let flag = if z.iter().any(|v| v.abs() > 3.0) { " **" } else { "" };
        let (book, rtow) = if noise {
            (format!("{} | {}", fmt3(b.mean), sd3(b.var)), format!("{} | {}", fmt3(r.mean), sd3(r.var)))
        } else {
            (fmt3(b.mean), fmt3(r.mean))
        };
        println!("| ({}, {}){flag} | {book} | {rtow} | {:+.2} {:+.2} {:+.2} |", b.row, b.col, z[0], z[1], z[2]);
    }
    println!();
    println!(
        "{k}x{k} regions of {}x{} pixels, {} region-channels: {} with |z| > 3, rms z {:.3}, max |z| {:.2}",
        book[0].width,
        book[0].height,
        t.count,
        t.over,
        t.rms,
        t.worst.z.abs()
    );
    // Seed against seed on each side: the difference of two means has variance 4 s^2.
    let ((zb, nb), (zr, nr)) = (bk.self_check().unwrap_or_default(), rt.self_check().unwrap_or_default());
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
