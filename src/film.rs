//! The film: linear f32 accumulators, filled in sample order, and the outputs.

use crate::error::{Error, Result};
use std::io::Cursor;
use std::path::Path;

/// The accumulators of one tile. Each pixel's samples are added in sample
/// order, so the sum does not depend on threads, tiles or kernels. Samples with
/// a NaN or infinite component are rejected (and counted), never added; so is a
/// finite sample that would overflow its pixel's sum (colours are unbounded).
///
/// Besides the f32 sums that make the image, each pixel can keep f64 first and
/// second moments of its samples: the per-pixel error estimate of adaptive
/// sampling is computed from them (see [`TileFilm::relative_error`]).
#[derive(Clone, Debug)]
pub struct TileFilm {
    pub x0: u32,
    pub y0: u32,
    pub w: u32,
    pub h: u32,
    pub sum: Vec<[f32; 3]>,
    pub count: Vec<u32>,
    /// Per pixel: the sum of the samples and of their squares, per channel, in f64.
    /// Empty unless adaptive sampling asked for them ([`TileFilm::with_moments`]).
    pub moments: Vec<[[f64; 3]; 2]>,
    pub rejected: u64,
}

impl TileFilm {
    pub fn new(x0: u32, y0: u32, w: u32, h: u32) -> Self {
        let n = (w * h) as usize;
        TileFilm { x0, y0, w, h, sum: vec![[0.0; 3]; n], count: vec![0; n], moments: Vec::new(), rejected: 0 }
    }

    /// Also keeps the per-pixel moments that adaptive sampling's error estimate needs.
    pub fn with_moments(mut self) -> Self {
        self.moments = vec![[[0.0; 3]; 2]; self.sum.len()];
        self
    }

    /// Adds one sample to pixel `local` (row-major inside the tile).
    #[inline]
    pub fn add(&mut self, local: usize, c: [f32; 3]) {
        let s = self.sum[local];
        let next = [s[0] + c[0], s[1] + c[1], s[2] + c[2]];
        if c.iter().chain(next.iter()).all(|v| v.is_finite()) {
            self.sum[local] = next;
            self.count[local] += 1;
            if let Some(m) = self.moments.get_mut(local) {
                for k in 0..3 {
                    let v = c[k] as f64;
                    m[0][k] += v;
                    m[1][k] += v * v;
                }
            }
        } else {
            self.rejected += 1;
        }
    }

    /// The relative standard error of pixel `local`'s mean: the standard error
    /// (root of the channels' mean sample variance over the sample count)
    /// over the pixel's mean value (the channels' average, at least
    /// [`RELATIVE_ERROR_FLOOR`](crate::estimator::RELATIVE_ERROR_FLOOR)).
    /// Infinite below 2 samples. It is computed from the very samples being
    /// averaged, so stopping on it is slightly biased (see the README).
    pub fn relative_error(&self, local: usize) -> f64 {
        let n = self.count[local] as f64;
        let Some(&[s1, s2]) = self.moments.get(local) else { return f64::INFINITY };
        if n < 2.0 {
            return f64::INFINITY;
        }
        let mut var = 0.0;
        let mut mean = 0.0;
        for k in 0..3 {
            var += ((s2[k] - s1[k] * s1[k] / n) / (n - 1.0)).max(0.0);
            mean += s1[k] / n;
        }
        let se = (var / 3.0 / n).sqrt();
        se / (mean / 3.0).max(crate::estimator::RELATIVE_ERROR_FLOOR)
    }

    /// Pixel (x, y) of the tile's top-left corner plus `local`.
    pub fn pixel_of(&self, local: usize) -> (u32, u32) {
        (self.x0 + local as u32 % self.w, self.y0 + local as u32 / self.w)
    }
}

/// A linear RGB image, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub data: Vec<[f32; 3]>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Image { width, height, data: vec![[0.0; 3]; (width * height) as usize] }
    }

    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.data[(y * self.width + x) as usize]
    }

    /// Writes a tile's mean values into the image.
    pub fn put_tile(&mut self, t: &TileFilm) {
        for local in 0..t.sum.len() {
            let (x, y) = t.pixel_of(local);
            let n = t.count[local];
            let v = if n == 0 { [0.0; 3] } else { t.sum[local].map(|s| s / n as f32) };
            self.data[(y * self.width + x) as usize] = v;
        }
    }

    /// FNV-1a over the bits of every value: equal hashes, identical images.
    pub fn hash(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for v in self.data.iter().flatten() {
            for b in v.to_bits().to_le_bytes() {
                h ^= b as u64;
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
        h
    }

    /// 8-bit sRGB-ish bytes with the book's encoding: `x^(1/gamma)`, clamped
    /// to [0, 0.999], times 256.
    pub fn to_rgb8(&self, gamma: f32) -> Vec<u8> {
        let inv = 1.0 / gamma;
        self.data
            .iter()
            .flatten()
            .map(|&v| {
                let g = if gamma == 1.0 { v } else { v.max(0.0).powf(inv) };
                (256.0 * g.clamp(0.0, 0.999)) as u8
            })
            .collect()
    }

    pub fn png_bytes(&self, gamma: f32) -> Vec<u8> {
        let mut out = Vec::new();
        let img = image::RgbImage::from_raw(self.width, self.height, self.to_rgb8(gamma)).expect("size matches");
        img.write_to(&mut Cursor::new(&mut out), image::ImageFormat::Png).expect("PNG encodes in memory");
        out
    }

    /// Portable float map: linear RGB, little-endian, rows bottom to top.
    pub fn pfm_bytes(&self) -> Vec<u8> {
        let mut out = format!("PF\n{} {}\n-1.0\n", self.width, self.height).into_bytes();
        for y in (0..self.height).rev() {
            for x in 0..self.width {
                for v in self.get(x, y) {
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
        out
    }

    pub fn exr_bytes(&self) -> Vec<u8> {
        let raw: Vec<f32> = self.data.iter().flatten().copied().collect();
        let img = image::Rgb32FImage::from_raw(self.width, self.height, raw).expect("size matches");
        let mut out = Vec::new();
        image::DynamicImage::ImageRgb32F(img)
            .write_to(&mut Cursor::new(&mut out), image::ImageFormat::OpenExr)
            .expect("EXR encodes in memory");
        out
    }

    /// Writes the image atomically: PNG (8-bit, `gamma`), PFM or EXR (linear), by extension.
    pub fn save(&self, path: &Path, gamma: f32) -> Result<()> {
        let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
        let bytes = match ext.as_deref() {
            Some("png") => self.png_bytes(gamma),
            Some("pfm") => self.pfm_bytes(),
            Some("exr") => self.exr_bytes(),
            _ => {
                return Err(Error::Output {
                    path: path.to_path_buf(),
                    message: "unknown image type (use .png, .pfm or .exr)".into(),
                })
            }
        };
        crate::output::write_atomic(path, &bytes)
    }

    /// Reads a linear image back (PFM or EXR), e.g. a converge reference.
    pub fn load_float(path: &Path) -> Result<Image> {
        let bad = |m: String| Error::Input(format!("{}: {m}", path.display()));
        let bytes = crate::limits::read_bounded(path, crate::limits::MAX_IMAGE_BYTES, "image")?;
        if bytes.starts_with(b"PF\n") {
            let text_end = nth_newline(&bytes, 3).ok_or_else(|| bad("truncated PFM header".into()))?;
            let header = std::str::from_utf8(&bytes[..text_end]).map_err(|e| bad(e.to_string()))?;
            let mut it = header.split_whitespace().skip(1);
            let mut word = |what: &str| it.next().ok_or_else(|| bad(format!("PFM header: {what} missing")));
            let (ws, hs, ss) = (word("width")?, word("height")?, word("scale")?);
            // Sizes are positive integers that fit the film, each named when it is not.
            let size = |what: &str, s: &str| -> Result<u32> {
                match s.parse::<i64>() {
                    Ok(v) if v >= 1 && v as u64 <= crate::limits::MAX_PIXELS => Ok(v as u32),
                    Ok(v) => {
                        Err(bad(format!("PFM header: {what} {v} must be from 1 to {}", crate::limits::MAX_PIXELS)))
                    }
                    Err(_) => Err(bad(format!("PFM header: {what} '{s}' is not an integer"))),
                }
            };
            let (w, h) = (size("width", ws)?, size("height", hs)?);
            if w as u64 * h as u64 > crate::limits::MAX_PIXELS {
                return Err(bad(format!("PFM header: {w}x{h} pixels, at most {}", crate::limits::MAX_PIXELS)));
            }
            let scale = match ss.parse::<f64>() {
                Ok(v) if v.is_finite() && v != 0.0 => v,
                _ => return Err(bad(format!("PFM header: scale '{ss}' must be a non-zero number"))),
            };
            let body = &bytes[text_end + 1..];
            if body.len() as u64 != w as u64 * h as u64 * 12 {
                return Err(bad("PFM size does not match its header".into()));
            }
            let rd = |i: usize| {
                let b: [u8; 4] = body[4 * i..4 * i + 4].try_into().unwrap();
                if scale < 0.0 {
                    f32::from_le_bytes(b)
                } else {
                    f32::from_be_bytes(b)
                }
            };
            let mut img = Image::new(w, h);
            for row in 0..h {
                for x in 0..w {
                    let i = ((row * w + x) * 3) as usize;
                    img.data[((h - 1 - row) * w + x) as usize] = [rd(i), rd(i + 1), rd(i + 2)];
                }
            }
            Ok(img)
        } else {
            let mut reader = image::ImageReader::new(Cursor::new(&bytes[..]))
                .with_guessed_format()
                .map_err(|e| bad(e.to_string()))?;
            // The decoder's memory is bounded like the file: at most MAX_PIXELS RGBA f32 pixels.
            let mut limits = image::Limits::default();
            limits.max_alloc = Some(crate::limits::MAX_PIXELS * 16 + (64 << 20));
            reader.limits(limits);
            let img = reader.decode().map_err(|e| bad(e.to_string()))?;
            if img.width() as u64 * img.height() as u64 > crate::limits::MAX_PIXELS {
                return Err(bad(format!(
                    "{}x{} pixels, at most {}",
                    img.width(),
                    img.height(),
                    crate::limits::MAX_PIXELS
                )));
            }
            let img = img.into_rgb32f();
            let (w, h) = img.dimensions();
            let data = img.into_raw().chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            Ok(Image { width: w, height: h, data })
        }
    }
}

fn nth_newline(b: &[u8], n: usize) -> Option<usize> {
    b.iter().enumerate().filter(|(_, &c)| c == b'\n').nth(n - 1).map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_and_inf_never_reach_the_image() {
        let mut t = TileFilm::new(0, 0, 1, 1);
        t.add(0, [1.0, 1.0, 1.0]);
        t.add(0, [f32::NAN, 0.0, 0.0]);
        t.add(0, [0.0, f32::INFINITY, 0.0]);
        t.add(0, [3.0, 3.0, 3.0]);
        assert_eq!(t.rejected, 2);
        let mut img = Image::new(1, 1);
        img.put_tile(&t);
        assert_eq!(img.get(0, 0), [2.0, 2.0, 2.0]);
    }

    #[test]
    fn relative_error_of_known_samples() {
        let mut t = TileFilm::new(0, 0, 2, 1).with_moments();
        assert_eq!(t.relative_error(0), f64::INFINITY);
        // Pixel 0: samples 1 and 3 in every channel: mean 2, variance 2, se 1.
        t.add(0, [1.0; 3]);
        t.add(0, [3.0; 3]);
        assert!((t.relative_error(0) - 0.5).abs() < 1e-12);
        // Pixel 1: identical samples have no error; a dark noisy pixel is
        // measured against the floor.
        t.add(1, [0.5; 3]);
        t.add(1, [0.5; 3]);
        assert_eq!(t.relative_error(1), 0.0);
        let mut d = TileFilm::new(0, 0, 1, 1).with_moments();
        d.add(0, [0.0; 3]);
        d.add(0, [0.02; 3]);
        let se = (0.0002f64 / 2.0).sqrt();
        assert!((d.relative_error(0) - se / crate::estimator::RELATIVE_ERROR_FLOOR).abs() < 1e-6);
    }

    #[test]
    fn a_sum_that_would_overflow_is_rejected() {
        let mut t = TileFilm::new(0, 0, 1, 1);
        t.add(0, [f32::MAX, 1.0, 1.0]);
        t.add(0, [f32::MAX, 1.0, 1.0]);
        assert_eq!(t.rejected, 1);
        let mut img = Image::new(1, 1);
        img.put_tile(&t);
        assert_eq!(img.get(0, 0), [f32::MAX, 1.0, 1.0]);
    }

    #[test]
    fn pfm_round_trips() {
        let mut img = Image::new(3, 2);
        for (i, p) in img.data.iter_mut().enumerate() {
            *p = [i as f32, 0.5, -1.0];
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.pfm");
        img.save(&path, 1.0).unwrap();
        assert_eq!(Image::load_float(&path).unwrap(), img);
        let path = dir.path().join("a.exr");
        img.save(&path, 1.0).unwrap();
        assert_eq!(Image::load_float(&path).unwrap(), img);
    }

    #[test]
    fn book_encoding() {
        let img = Image { width: 2, height: 1, data: vec![[0.25, 1.0, 2.0], [0.0, -1.0, 0.5]] };
        assert_eq!(img.to_rgb8(2.0), vec![128, 255, 255, 0, 0, 181]);
    }
}
