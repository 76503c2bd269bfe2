//! `rtow diff`'s inputs: PNG, EXR, PFM and partial films (`.rtfilm`), told
//! apart by their first bytes, each read with rtow's limits and checks (a
//! damaged file is refused naming it, exit status 2, never a panic).

use crate::error::{Error, Result};
use crate::film::part::{self, Part, SplitKind};
use crate::film::{Film, Image};
use crate::limits::{MAX_IMAGE_BYTES, MAX_PIXELS};
use serde::Serialize;
use std::io::Read;
use std::path::{Path, PathBuf};

/// What an input is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// 8-bit, gamma encoded: linearized with the gamma given.
    Png,
    /// Linear light.
    Exr,
    /// Linear light.
    Pfm,
    /// A partial film: its mean is the image, linear light; it may carry per-pixel moments.
    Film,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::Png => "PNG",
            Kind::Exr => "EXR",
            Kind::Pfm => "PFM",
            Kind::Film => "partial film",
        }
    }
}

/// An input image.
#[derive(Clone, Debug)]
pub struct Input {
    pub path: PathBuf,
    pub kind: Kind,
    /// Linear light.
    pub image: Image,
    /// The image as 8-bit bytes a display shows: a PNG's own, else the
    /// linear image encoded as rtow writes its PNGs ([`Image::to_rgb8`]).
    pub display: Vec<u8>,
    /// A partial film's accumulators.
    pub film: Option<Film>,
}

/// A byte of an 8-bit image encoded with `gamma`, as linear light: the middle
/// of its quantization step, `((b + 0.5) / 256)^gamma` (rtow and the book
/// write `int(256 x^(1/gamma))`, clamped to 255).
pub fn decode_byte(b: u8, gamma: f64) -> f64 {
    ((b as f64 + 0.5) / 256.0).powf(gamma)
}

const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
const EXR_MAGIC: &[u8] = b"\x76\x2f\x31\x01";

impl Input {
    /// Reads `path`: a PNG (linearized with `gamma`), an EXR or PFM, or a
    /// partial film (a whole render or a shard by samples: a shard by rows
    /// holds only some rows and is refused).
    pub fn read(path: &Path, gamma: f32) -> Result<Input> {
        let bad = |m: &str| Error::Input(format!("{}: {m}", path.display()));
        let head = first_bytes(path)?;
        let (kind, image, display, film) = if head.starts_with(part::MAGIC) {
            let film = read_film(path)?;
            let image = film.image();
            let display = image.to_rgb8(gamma);
            (Kind::Film, image, display, Some(film))
        } else if head.starts_with(PNG_SIGNATURE) {
            let (image, display) = read_png(path, gamma)?;
            (Kind::Png, image, display, None)
        } else if head.starts_with(b"PF\n") || head.starts_with(EXR_MAGIC) {
            let image = Image::load_float(path)?;
            finite(&image).map_err(|m| bad(&m))?;
            let display = image.to_rgb8(gamma);
            (if head.starts_with(EXR_MAGIC) { Kind::Exr } else { Kind::Pfm }, image, display, None)
        } else {
            return Err(bad("is not a PNG, EXR, PFM (colour) or rtow partial film (.rtfilm) file"));
        };
        Ok(Input { path: path.to_path_buf(), kind, image, display, film })
    }

    /// Whether the input carries per-pixel moments (a film rendered with `--adaptive`).
    pub fn has_moments(&self) -> bool {
        self.film.as_ref().is_some_and(|f| !f.sum_sq.is_empty())
    }

    /// Pixel `i`'s mean (linear, f64) and the variance of that mean per
    /// channel, from a film's moments: the samples' variance
    /// `(sum_sq - sum^2 / n) / (n - 1)` over `n` (0 below 2 samples: no
    /// estimate). Only for an input that [`Input::has_moments`].
    pub fn moments(&self, i: usize) -> ([f64; 3], [f64; 3]) {
        let f = self.film.as_ref().expect("a film");
        let n = f.count[i] as f64;
        let sum = f.sum[i].map(|s| f.scale.to_f64(s));
        let mean = sum.map(|s| if n > 0.0 { s / n } else { 0.0 });
        let var: [f64; 3] = std::array::from_fn(|c| {
            if n < 2.0 {
                0.0
            } else {
                ((f.sum_sq[i][c] - sum[c] * sum[c] / n) / (n - 1.0)).max(0.0) / n
            }
        });
        (mean, var)
    }

    /// `width x height`.
    pub fn size(&self) -> (u32, u32) {
        (self.image.width, self.image.height)
    }
}

/// The first bytes of the file at `path` (at most 16).
fn first_bytes(path: &Path) -> Result<Vec<u8>> {
    let cannot = |e: &dyn std::fmt::Display| Error::Input(format!("cannot read {}: {e}", path.display()));
    let file = std::fs::File::open(path).map_err(|e| cannot(&e))?;
    if file.metadata().map_err(|e| cannot(&e))?.is_dir() {
        return Err(cannot(&"is a directory"));
    }
    let mut head = Vec::with_capacity(16);
    file.take(16).read_to_end(&mut head).map_err(|e| cannot(&e))?;
    Ok(head)
}

/// A partial film, read with every check `rtow merge` makes.
fn read_film(path: &Path) -> Result<Film> {
    let p = Part::read(path)?;
    let h = &p.header;
    if h.split.kind == SplitKind::Rows {
        return Err(Error::Input(format!(
            "{}: is {} of {} rows: it holds rows {}..{} only; merge the shards first (rtow merge)",
            path.display(),
            h.split.describe(),
            h.height,
            h.rows[0],
            h.rows[1]
        )));
    }
    Ok(p.film)
}

/// A PNG, checked chunk by chunk (a file cut short or with a flipped bit is
/// refused), decoded within rtow's pixel limit to 8-bit RGB (grey
/// replicated, alpha dropped, 16-bit rounded), and linearized with `gamma`.
fn read_png(path: &Path, gamma: f32) -> Result<(Image, Vec<u8>)> {
    let bad = |m: String| Error::Input(format!("{}: {m}", path.display()));
    let bytes = crate::limits::read_bounded(path, MAX_IMAGE_BYTES, "image")?;
    crate::job::png_chunks(&bytes).map_err(|m| bad(format!("is a truncated or corrupt PNG file ({m})")))?;
    let reader = || {
        let mut r = image::ImageReader::with_format(std::io::Cursor::new(&bytes[..]), image::ImageFormat::Png);
        let mut limits = image::Limits::default();
        limits.max_alloc = Some(MAX_PIXELS * 16 + (64 << 20));
        r.limits(limits);
        r
    };
    let corrupt = |e: image::ImageError| {
        bad(format!("is a truncated or corrupt PNG file ({})", crate::output::clip_to(&e.to_string(), 200)))
    };
    let (w, h) = reader().into_dimensions().map_err(corrupt)?;
    if w == 0 || h == 0 || w as u64 * h as u64 > MAX_PIXELS {
        return Err(bad(format!("a {w}x{h} PNG: an image has 1 to {MAX_PIXELS} pixels")));
    }
    let display = reader().decode().map_err(corrupt)?.into_rgb8().into_raw();
    let lut: Vec<f32> = (0..=255u8).map(|b| decode_byte(b, gamma as f64) as f32).collect();
    let data = display.chunks_exact(3).map(|p| [lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]]).collect();
    Ok((Image { width: w, height: h, data }, display))
}

/// Refuses an image with a NaN or infinite value, naming its first such pixel.
fn finite(image: &Image) -> std::result::Result<(), String> {
    match image.data.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        Some(i) => Err(format!(
            "pixel ({}, {}) is not finite ({:?}): rtow diff compares finite images",
            i as u32 % image.width,
            i as u32 / image.width,
            image.data[i]
        )),
        None => Ok(()),
    }
}
