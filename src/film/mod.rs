//! The film: exact fixed-point accumulators ([`accum`]), per tile while
//! rendering ([`TileFilm`]) and per band of rows for a whole render or a shard
//! ([`Film`]); the partial film files that shards write and `rtow merge` reads
//! ([`part`]); and the image with its outputs ([`Image`]).
//!
//! The film knows nothing of the estimator: it exposes each pixel's moments
//! ([`TileFilm::moments`]) and `estimator.rs` turns them into an error estimate.

pub mod accum;
pub mod aov;
pub mod part;

use crate::error::{Error, Result};
use std::io::Cursor;

/// The image file types rtow writes: PNG (8-bit, gamma encoded), PFM and EXR (linear).
pub const IMAGE_TYPES: [&str; 3] = ["png", "pfm", "exr"];
use std::ops::Range;
use std::path::Path;

/// A pixel's accepted samples: their number, sum and sum of squares per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moments {
    pub n: u32,
    /// The exact fixed-point sum, as f64 (rounded once).
    pub sum: [f64; 3],
    /// The sum of the squared samples, in f64, added in sample order.
    pub sum_sq: [f64; 3],
}

/// The accumulators of one tile. Each sample is converted to fixed point by
/// the film's [`accum::Scale`] and added to its pixel's `i128` sums
/// ([`accum`]), so the sums do not depend on threads, tiles, kernels or how
/// samples are grouped. Samples with a NaN, infinite or out-of-range component
/// are rejected (and counted, by cause), never added.
///
/// Besides the sums that make the image, each pixel can keep the f64 sum of
/// the squares of its samples (added in sample order, which every kernel and
/// every resume keeps): adaptive sampling's error estimate needs it.
#[derive(Clone, Debug)]
pub struct TileFilm {
    pub x0: u32,
    pub y0: u32,
    pub w: u32,
    pub h: u32,
    /// Per pixel, the fixed-point sums of the accepted samples ([`accum`]).
    pub sum: Vec<[i128; 3]>,
    /// Per pixel, the accepted samples.
    pub count: Vec<u32>,
    /// Per pixel, the sums of squares. Empty unless asked for ([`TileFilm::with_moments`]).
    pub sum_sq: Vec<[f64; 3]>,
    /// Samples rejected, whatever the cause.
    pub rejected: u64,
    /// Of those, the finite samples outside the film's range ([`accum::Rejection::OutOfRange`]).
    pub rejected_out_of_range: u64,
    /// The fixed-point scale of the sums (the render's; exponent 0 unless [`TileFilm::scaled`]).
    pub scale: accum::Scale,
    /// Shadow rays the kernel traced for this tile (`nee-mis`), counted
    /// apart from the rays; not part of the film's data.
    pub shadow_rays: u64,
}

impl TileFilm {
    pub fn new(x0: u32, y0: u32, w: u32, h: u32) -> Self {
        let n = (w * h) as usize;
        TileFilm {
            x0,
            y0,
            w,
            h,
            sum: vec![[0; 3]; n],
            count: vec![0; n],
            sum_sq: Vec::new(),
            rejected: 0,
            rejected_out_of_range: 0,
            scale: accum::Scale::UNIT,
            shadow_rays: 0,
        }
    }

    /// Converts samples by `scale` (the render's: [`crate::plan::Plan::film_scale`]).
    pub fn scaled(mut self, scale: accum::Scale) -> Self {
        self.scale = scale;
        self
    }

    #[inline(always)]
    fn reject(&mut self, why: accum::Rejection) {
        self.rejected += 1;
        self.rejected_out_of_range += (why == accum::Rejection::OutOfRange) as u64;
    }

    /// Also keeps the sums of squares that adaptive sampling's error estimate needs.
    pub fn with_moments(mut self) -> Self {
        self.sum_sq = vec![[0.0; 3]; self.sum.len()];
        self
    }

    /// Pixels in the tile.
    pub fn len(&self) -> usize {
        self.sum.len()
    }

    pub fn is_empty(&self) -> bool {
        self.sum.is_empty()
    }

    /// Adds one sample to pixel `local` (row-major inside the tile).
    #[cfg_attr(not(feature = "phases"), inline)]
    #[cfg_attr(feature = "phases", inline(never))]
    pub fn add(&mut self, local: usize, c: [f32; 3]) {
        match self.scale.to_fixed(c) {
            Ok(q) => {
                let s = &mut self.sum[local];
                s[0] += q[0];
                s[1] += q[1];
                s[2] += q[2];
                self.count[local] += 1;
                if let Some(m) = self.sum_sq.get_mut(local) {
                    for k in 0..3 {
                        let v = c[k] as f64;
                        m[k] += v * v;
                    }
                }
            }
            Err(why) => self.reject(why),
        }
    }

    /// Adds a batch of samples of the pixels `locals` (row-major inside the
    /// tile): `samples` holds rounds of one sample per pixel, sample `r` of
    /// pixel `locals[j]` at `r * locals.len() + j` (the wavefront's layout).
    /// The sums, counts, sums of squares and rejections are those of
    /// [`TileFilm::add`] called sample by sample in that order (each pixel's
    /// samples are added in sample order either way); a pixel's sums are
    /// loaded and stored once per batch instead of once per sample.
    /// (Never inlined: it runs once per batch, and inlined into the
    /// wavefront's loop it costs the traversal's code registers.)
    #[inline(never)]
    pub fn add_rounds(&mut self, locals: &[u32], samples: &[[f32; 3]]) {
        if self.sum_sq.is_empty() {
            self.add_rounds_with::<false>(locals, samples)
        } else {
            self.add_rounds_with::<true>(locals, samples)
        }
    }

    #[inline(always)]
    fn add_rounds_with<const MOMENTS: bool>(&mut self, locals: &[u32], samples: &[[f32; 3]]) {
        let na = locals.len();
        let scale = self.scale;
        debug_assert!(na == 0 || samples.len().is_multiple_of(na));
        for (j, &local) in locals.iter().enumerate() {
            let local = local as usize;
            // Samples below 2^19 per channel (all but the rarest) sum in a
            // run; the others, and a full run, take the general path.
            let mut run = accum::Run::default();
            let (mut sum, mut n, mut rejected, mut out_of_range) = ([0i128; 3], 0u32, 0u64, 0u64);
            let mut sq = if MOMENTS { self.sum_sq[local] } else { [0.0; 3] };
            let mut i = j;
            while let Some(&c) = samples.get(i) {
                i += na;
                let accepted = run.try_add(c, scale)
                    || match scale.to_fixed(c) {
                        Ok(q) => {
                            for k in 0..3 {
                                sum[k] += q[k];
                            }
                            n += 1;
                            true
                        }
                        Err(why) => {
                            rejected += 1;
                            out_of_range += (why == accum::Rejection::OutOfRange) as u64;
                            false
                        }
                    };
                // Every accepted sample's squares, in sample order.
                if MOMENTS && accepted {
                    for k in 0..3 {
                        let v = c[k] as f64;
                        sq[k] += v * v;
                    }
                }
            }
            let r = run.sums();
            let s = &mut self.sum[local];
            for k in 0..3 {
                s[k] += sum[k] + r[k] as i128;
            }
            self.count[local] += n + run.len();
            if MOMENTS {
                self.sum_sq[local] = sq;
            }
            self.rejected += rejected;
            self.rejected_out_of_range += out_of_range;
        }
    }

    /// Pixel `local`'s moments (the sums of squares are 0 without [`TileFilm::with_moments`]).
    #[inline]
    pub fn moments(&self, local: usize) -> Moments {
        Moments {
            n: self.count[local],
            sum: self.sum[local].map(|s| self.scale.to_f64(s)),
            sum_sq: self.sum_sq.get(local).copied().unwrap_or([0.0; 3]),
        }
    }

    /// Pixel (x, y) of the tile's top-left corner plus `local`.
    pub fn pixel_of(&self, local: usize) -> (u32, u32) {
        (self.x0 + local as u32 % self.w, self.y0 + local as u32 / self.w)
    }
}

/// The accumulators of a band of whole rows of an image (all of it for a
/// one-process render; a shard's rows for a row split): what a render
/// produces, what a partial film file stores and what `rtow merge` adds up.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    /// Height of the whole image.
    pub height: u32,
    /// The rows held: `rows.start..rows.end`.
    pub rows: Range<u32>,
    pub sum: Vec<[i128; 3]>,
    pub count: Vec<u32>,
    /// Empty, or one entry per pixel (see [`TileFilm::sum_sq`]).
    pub sum_sq: Vec<[f64; 3]>,
    /// The fixed-point scale of the sums (exponent 0 unless [`Film::scaled`]).
    pub scale: accum::Scale,
}

impl Film {
    /// An empty film of rows `rows` of a `width` x `height` image.
    pub fn new(width: u32, height: u32, rows: Range<u32>, moments: bool) -> Film {
        assert!(rows.start <= rows.end && rows.end <= height, "rows {rows:?} outside an image of height {height}");
        let n = width as usize * rows.len();
        Film {
            width,
            height,
            rows,
            sum: vec![[0; 3]; n],
            count: vec![0; n],
            sum_sq: if moments { vec![[0.0; 3]; n] } else { Vec::new() },
            scale: accum::Scale::UNIT,
        }
    }

    /// Sums in the fixed point of `scale` (the render's, or a partial film's).
    pub fn scaled(mut self, scale: accum::Scale) -> Film {
        self.scale = scale;
        self
    }

    pub fn has_moments(&self) -> bool {
        !self.sum_sq.is_empty() || self.sum.is_empty()
    }

    fn index(&self, x: u32, y: u32) -> usize {
        (y - self.rows.start) as usize * self.width as usize + x as usize
    }

    /// Copies a finished tile (inside the band, of the same scale) into the film.
    pub fn put_tile(&mut self, t: &TileFilm) {
        assert_eq!(t.scale, self.scale, "a tile of another fixed-point scale");
        for local in 0..t.len() {
            let (x, y) = t.pixel_of(local);
            let i = self.index(x, y);
            self.sum[i] = t.sum[local];
            self.count[i] = t.count[local];
            if let (Some(d), Some(s)) = (self.sum_sq.get_mut(i), t.sum_sq.get(local)) {
                *d = *s;
            }
        }
    }

    /// A tile that starts from this film's accumulators (to resume a render),
    /// of its scale. It keeps sums of squares if the film has them.
    pub fn tile(&self, x0: u32, y0: u32, w: u32, h: u32) -> TileFilm {
        let mut t = TileFilm::new(x0, y0, w, h).scaled(self.scale);
        if !self.sum_sq.is_empty() {
            t = t.with_moments();
        }
        for local in 0..t.len() {
            let (x, y) = t.pixel_of(local);
            let i = self.index(x, y);
            t.sum[local] = self.sum[i];
            t.count[local] = self.count[i];
            if let Some(m) = t.sum_sq.get_mut(local) {
                *m = self.sum_sq[i];
            }
        }
        t
    }

    /// Adds `other`'s accumulators (rows inside this film's, of the same
    /// scale: partial films of different scales are refused before) into this
    /// one: exact for the sums and counts whatever the order of the parts. The
    /// sums of squares are kept only if both have them. `None` if a count would
    /// exceed `u32::MAX` (parts that overlap; checked before, this is a guard).
    pub fn absorb(&mut self, other: &Film) -> Option<()> {
        assert!(other.width == self.width && other.rows.start >= self.rows.start && other.rows.end <= self.rows.end);
        assert_eq!(other.scale, self.scale, "films of different fixed-point scales");
        if !other.has_moments() {
            self.sum_sq = Vec::new();
        }
        let off = self.index(0, other.rows.start);
        for (j, (s, &n)) in other.sum.iter().zip(&other.count).enumerate() {
            let i = off + j;
            self.count[i] = self.count[i].checked_add(n)?;
            for (d, s) in self.sum[i].iter_mut().zip(s) {
                *d += s;
            }
            if let Some(d) = self.sum_sq.get_mut(i) {
                for (d, s) in d.iter_mut().zip(&other.sum_sq[j]) {
                    *d += s;
                }
            }
        }
        Some(())
    }

    /// Sets pixel `i` of the band (row-major from its first row) to `p`
    /// (the sums of squares only if the film keeps them).
    pub fn set_pixel(&mut self, i: usize, p: &part::Pixel) {
        self.count[i] = p.count;
        self.sum[i] = p.sum;
        if let Some(d) = self.sum_sq.get_mut(i) {
            *d = p.sum_sq;
        }
    }

    /// Adds `p` to pixel `i` of the band: exact for the sums and counts
    /// whatever the order. `None` if the count would exceed `u32::MAX`.
    pub fn add_pixel(&mut self, i: usize, p: &part::Pixel) -> Option<()> {
        self.count[i] = self.count[i].checked_add(p.count)?;
        for (d, s) in self.sum[i].iter_mut().zip(&p.sum) {
            *d += s;
        }
        if let Some(d) = self.sum_sq.get_mut(i) {
            for (d, s) in d.iter_mut().zip(&p.sum_sq) {
                *d += s;
            }
        }
        Some(())
    }

    /// The mean of every pixel of the band into `image` (same width and height).
    pub fn write_into(&self, image: &mut Image) {
        assert!(image.width == self.width && image.height == self.height);
        let off = self.rows.start as usize * self.width as usize;
        for (i, (s, &n)) in self.sum.iter().zip(&self.count).enumerate() {
            image.data[off + i] = self.scale.mean(*s, n);
        }
    }

    /// The whole image (rows outside the band are black).
    pub fn image(&self) -> Image {
        let mut img = Image::new(self.width, self.height);
        self.write_into(&mut img);
        img
    }
}

/// A linear RGB image, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub data: Vec<[f32; 3]>,
}

/// Why an image that is not PFM or EXR is refused as linear light.
const NOT_LINEAR: &str = "not a linear float image: give a .pfm or .exr (rtow render --float writes one)";

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Image { width, height, data: vec![[0.0; 3]; (width * height) as usize] }
    }

    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.data[(y * self.width + x) as usize]
    }

    /// Writes a tile's mean values into the image.
    pub fn put_tile(&mut self, t: &TileFilm) {
        for local in 0..t.len() {
            let (x, y) = t.pixel_of(local);
            self.data[(y * self.width + x) as usize] = t.scale.mean(t.sum[local], t.count[local]);
        }
    }

    /// The pixels of columns `x` and rows `y` (within the image), as an image of their own.
    pub fn crop(&self, x: Range<u32>, y: Range<u32>) -> Image {
        let mut out = Image::new(x.len() as u32, y.len() as u32);
        for (row, yy) in y.enumerate() {
            let from = (yy * self.width + x.start) as usize;
            let to = row * x.len();
            out.data[to..to + x.len()].copy_from_slice(&self.data[from..from + x.len()]);
        }
        out
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

    /// The bytes of the image as the file type `path`'s extension names: PNG
    /// (8-bit, `gamma`), PFM or EXR (linear); another is a usage error naming
    /// `IMAGE_TYPES`, as `field`.
    pub fn file_bytes(&self, path: &Path, gamma: f32, field: &str) -> Result<Vec<u8>> {
        let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(self.png_bytes(gamma)),
            Some("pfm") => Ok(self.pfm_bytes()),
            Some("exr") => Ok(self.exr_bytes()),
            _ => crate::output::check_extension(path, &IMAGE_TYPES, field).map(|_| Vec::new()),
        }
    }

    /// Writes the image atomically: PNG (8-bit, `gamma`), PFM or EXR (linear), by extension.
    pub fn save(&self, path: &Path, gamma: f32) -> Result<()> {
        crate::output::write_atomic(path, &self.file_bytes(path, gamma, "image")?)
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
            // Only a linear float image: an 8-bit, gamma-encoded PNG or JPEG
            // read as linear light would give meaningless errors.
            match reader.format() {
                Some(image::ImageFormat::OpenExr) => {}
                Some(f) => return Err(bad(format!("is a {f:?} image, {NOT_LINEAR}"))),
                None => return Err(bad("is neither a PFM nor an EXR image".into())),
            }
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

    /// A batch added at once gives exactly the film of its samples added
    /// one by one in the wavefront's order: sums, counts, sums of squares
    /// and rejections, with and without moments, for pixels in any order.
    #[test]
    fn a_batch_is_its_samples_added_one_by_one() {
        let locals = [5u32, 0, 7, 2, 3];
        let mut x = 0x9e37_79b9u32;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        };
        let samples: Vec<[f32; 3]> = (0..locals.len() * 6)
            .map(|i| match i % 11 {
                3 => [f32::NAN, 1.0, 0.0],
                7 => [0.0, 0.0, 3e19],
                _ => std::array::from_fn(|_| f32::from_bits(next() % 0x4100_0000) - 1e-3),
            })
            .collect();
        for moments in [false, true] {
            let new = || if moments { TileFilm::new(0, 0, 4, 2).with_moments() } else { TileFilm::new(0, 0, 4, 2) };
            let (mut one, mut batch) = (new(), new());
            // Two batches, so sums carry over.
            for half in samples.chunks(locals.len() * 3) {
                for round in half.chunks(locals.len()) {
                    for (&l, &c) in locals.iter().zip(round) {
                        one.add(l as usize, c);
                    }
                }
                batch.add_rounds(&locals, half);
            }
            assert!(one.rejected > one.rejected_out_of_range && one.rejected_out_of_range > 0);
            assert!(one.count.iter().any(|&n| n > 0));
            assert_eq!((&one.sum, &one.count, one.rejected), (&batch.sum, &batch.count, batch.rejected));
            assert_eq!(one.rejected_out_of_range, batch.rejected_out_of_range);
            let bits = |t: &TileFilm| t.sum_sq.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&one), bits(&batch));
        }
    }

    #[test]
    fn nan_and_inf_never_reach_the_image() {
        let mut t = TileFilm::new(0, 0, 1, 1);
        t.add(0, [1.0, 1.0, 1.0]);
        t.add(0, [f32::NAN, 0.0, 0.0]);
        t.add(0, [0.0, f32::INFINITY, 0.0]);
        t.add(0, [3.0, 3.0, 3.0]);
        assert_eq!(t.rejected, 2);
        assert_eq!(t.count[0], 2);
        let mut img = Image::new(1, 1);
        img.put_tile(&t);
        assert_eq!(img.get(0, 0), [2.0, 2.0, 2.0]);
    }

    #[test]
    fn a_sample_out_of_range_is_rejected() {
        // Colours are unbounded; a sample beyond the fixed-point range is
        // rejected whole, like NaN and Inf, counted as out of range, and the
        // pixel keeps its other samples.
        let mut t = TileFilm::new(0, 0, 1, 1);
        t.add(0, [f32::MAX, 1.0, 1.0]);
        t.add(0, [1.0, 1.0, -(accum::SAMPLE_LIMIT as f32)]);
        t.add(0, [3.0e19, 1.0, 1.0]);
        t.add(0, [1.0e9, 1.0, 1.0]);
        t.add(0, [3.0e9, 1.0, 1.0]);
        t.add(0, [f32::NAN, 1.0, 1.0]);
        assert_eq!((t.rejected, t.rejected_out_of_range), (4, 3));
        assert_eq!(t.count[0], 2);
        let mut img = Image::new(1, 1);
        img.put_tile(&t);
        assert_eq!(img.get(0, 0), [2.0e9, 1.0, 1.0]);
    }

    /// A film scaled for a bright emitter holds its samples (the unit film
    /// rejects them) and reads back their exact mean; dark samples round to
    /// its coarser step.
    #[test]
    fn a_scaled_film_holds_what_the_unit_film_rejects() {
        let scale = accum::Scale::for_brightness(1e30);
        assert_eq!(scale.exponent(), 53);
        let mut unit = TileFilm::new(0, 0, 2, 1);
        let mut t = TileFilm::new(0, 0, 2, 1).scaled(scale);
        for film in [&mut unit, &mut t] {
            film.add(0, [1e30, 1e30, 5e29]);
            film.add(0, [1e30, 0.0, 5e29]);
            film.add_rounds(&[1], &[[f32::MAX, 0.5, 0.0], [3e34, 0.5, 1.0]]);
        }
        assert_eq!((unit.rejected, unit.rejected_out_of_range, unit.count[0]), (4, 4, 0));
        assert_eq!((t.rejected, t.rejected_out_of_range, t.count.as_slice()), (1, 1, &[2, 1][..]));
        let mut img = Image::new(2, 1);
        img.put_tile(&t);
        assert_eq!(img.get(0, 0), [1e30, 5e29, 5e29]);
        // 0.5 and 1.0 are far below the step (2^21): they round to 0.
        assert_eq!(img.get(1, 0), [3e34, 0.0, 0.0]);
        assert_eq!(t.moments(0).sum, [2e30f32 as f64, 1e30f32 as f64, 2.0 * 5e29f32 as f64]);
    }

    #[test]
    fn moments_of_known_samples() {
        let mut t = TileFilm::new(0, 0, 1, 1).with_moments();
        t.add(0, [1.0, 2.0, 0.5]);
        t.add(0, [3.0, 2.0, 0.25]);
        assert_eq!(t.moments(0), Moments { n: 2, sum: [4.0, 4.0, 0.75], sum_sq: [10.0, 8.0, 0.3125] });
    }

    /// Random samples split among tiles, resumed and merged in any grouping
    /// give the film a one-pass render gives.
    /// Random samples split among tiles, resumed and merged in any grouping
    /// give the film a one-pass render gives, at exponent 0 and at a scaled
    /// film's (samples 2^70 times brighter, exponent 40).
    #[test]
    fn films_merge_exactly_in_any_grouping() {
        for (scale, up) in [(accum::Scale::UNIT, 1.0f32), (accum::Scale::new(40).unwrap(), 2.0f32.powi(70))] {
            let (w, h) = (5u32, 4u32);
            let sample = |x: u32, y: u32, s: u32| {
                let v = crate::sampling::ScalarStream::for_path(7, (y * w + x) as u64, s as u64);
                let mut v = v;
                use crate::sampling::Stream;
                let f = |u: f32| (u * u * 3.0 + 1e-7 / (u + 1e-3)) * up;
                [f(v.next()), f(v.next()), f(v.next())]
            };
            let spp = 37;
            let empty = |rows: Range<u32>| Film::new(w, h, rows, false).scaled(scale);
            let render = |rows: Range<u32>, samples: Range<u32>, from: Option<&Film>| {
                let mut f = from.cloned().unwrap_or_else(|| empty(rows.clone()));
                for y in rows.clone() {
                    let mut t = f.tile(0, y, w, 1);
                    for x in 0..w {
                        for s in samples.clone() {
                            t.add(x as usize, sample(x, y, s));
                        }
                    }
                    assert_eq!(t.rejected, 0);
                    f.put_tile(&t);
                }
                f
            };
            let whole = render(0..h, 0..spp, None);
            // By samples, merged in reverse order.
            let mut by_samples = empty(0..h);
            for r in [30..37, 11..30, 0..11].iter() {
                by_samples.absorb(&render(0..h, r.clone(), None)).unwrap();
            }
            assert_eq!(by_samples, whole);
            // By rows.
            let mut by_rows = empty(0..h);
            for r in [2..4, 0..1, 1..2] {
                by_rows.absorb(&render(r, 0..spp, None)).unwrap();
            }
            assert_eq!(by_rows, whole);
            // Resumed.
            let first = render(0..h, 0..9, None);
            assert_eq!(render(0..h, 9..spp, Some(&first)), whole);
            assert_eq!(by_rows.image().hash(), whole.image().hash());
            // The image is the samples' mean at either scale (u^2 * 3 has mean 1).
            let img = whole.image();
            assert!(img.data.iter().flatten().all(|&v| v > 0.0 && v < 3.1 * up), "{:?}", img.data[0]);
            let mean = img.data.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * w * h) as f64;
            assert!(mean > 0.5 * up as f64 && mean < 1.5 * up as f64, "{mean:e}");
        }
    }

    #[test]
    #[should_panic(expected = "different fixed-point scales")]
    fn films_of_different_scales_are_never_added() {
        let mut a = Film::new(2, 2, 0..2, false);
        a.absorb(&Film::new(2, 2, 0..2, false).scaled(accum::Scale::new(1).unwrap()));
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
