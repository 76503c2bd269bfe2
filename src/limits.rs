//! Documented bounds on every input rtow accepts: file sizes, scene contents,
//! world lengths and resource flags. Each one is checked before any work that
//! depends on it, so hostile input is refused (exit status 2) instead of
//! exhausting memory, hanging, or rendering garbage. docs/reliability.md
//! lists them.

use crate::error::{Error, Result};

/// Most pixels an image may have: 2^26, an 8192 x 8192 image. Memory: the
/// exact per-pixel sums (52 bytes a pixel, `film::accum`) plus the linear
/// image (12) and the 8-bit output, about 4.5 GB at the limit.
pub const MAX_PIXELS: u64 = 1 << 26;

/// Refuses a `width` x `height` image of more than [`MAX_PIXELS`] pixels,
/// naming `field` (e.g. `width x height`).
pub fn check_pixels(field: &str, width: u32, height: u32) -> Result<()> {
    let px = width as u64 * height as u64;
    if px > MAX_PIXELS {
        return Err(Error::invalid(
            field,
            format!("{width}x{height} = {px} pixels; at most {MAX_PIXELS} fit in memory"),
        ));
    }
    Ok(())
}

/// Largest tile edge in pixels: a tile's 45 x 45 = 2025 pixels must fit one
/// wavefront workspace of `MAX_PATHS` = 2048 paths (one sample each at a time).
pub const MAX_TILE: u32 = 45;

/// Largest JSON scene file read (bytes). serde_json parses it as a stream into
/// the scene, so the memory a JSON scene needs is about its spheres (40 bytes
/// each) plus the file itself.
pub const MAX_JSON_BYTES: u64 = 64 << 20;

/// Largest TOML scene file read (bytes). The TOML parser holds the whole
/// document as a tree (up to about 75 bytes of memory per byte of a file of
/// short values: 635 MB peak measured for an 8 MiB array of `1,`), so TOML
/// files are held to a smaller size. A TOML scene of this size holds about
/// 47,000 spheres as `rtow export` writes them; larger scenes are JSON.
pub const MAX_TOML_BYTES: u64 = 8 << 20;

/// Largest `rtow bench` baseline read (bytes).
pub const MAX_BASELINE_BYTES: u64 = 16 << 20;

/// Largest float image read (`rtow converge --reference`, bytes): a PFM of
/// `MAX_PIXELS` pixels fits with its header.
pub const MAX_IMAGE_BYTES: u64 = MAX_PIXELS * 12 + 4096;

/// Most spheres a scene may have, checked while the file is parsed (a JSON
/// file stops being read at the first sphere over the limit): 1,048,576
/// spheres take 40 MB as a scene and about 160 MB prepared (SoA, BVH).
pub const MAX_SPHERES: usize = 1 << 20;
/// The most quads a scene may hold once its boxes (six quads each) and groups
/// are flattened; a scene file's quad and box lists are bounded while they are read.
pub const MAX_QUADS: usize = 1 << 20;
/// The most groups (instances) a scene file may hold.
pub const MAX_GROUPS: usize = 1 << 16;
/// The most constant media a scene may hold (its own and its groups'): each
/// costs every ray of the scene a chord test and a draw per bounce (media
/// are not in a BVH), and takes its own sampler dimensions.
pub const MAX_MEDIA: usize = 64;
/// Shapes the `book` estimator samples toward, at most (its `sample_toward`
/// list, or the lights it takes by default), and lights the `nee-mis`
/// estimator samples: every diffuse vertex evaluates the density of each.
pub const MAX_SAMPLED_SHAPES: usize = 64;

/// The longest image file name a scene may give (bytes).
pub const MAX_PATH_BYTES: usize = 4096;
/// The most distinct image files a scene may name.
pub const MAX_IMAGE_TEXTURES: usize = 64;
/// Largest image texture file read (bytes).
pub const MAX_TEXTURE_FILE_BYTES: u64 = 64 << 20;
/// Most texels an image texture may have: 2^24 (a 4096 x 4096 map; the
/// book's earth is 1024 x 512). Each texel takes 12 bytes prepared (linear
/// f32 RGB), 192 MiB at the limit; the decoder is held to the same bound.
pub const MAX_TEXELS: u64 = 1 << 24;
/// Most texels the image textures of one scene may have together: 2^25
/// (two maps at [`MAX_TEXELS`], or [`MAX_IMAGE_TEXTURES`] maps the size of
/// the book's earth), 384 MiB prepared. Each distinct file counts once,
/// however many names lead to it; the sum is checked from each file's
/// header, before it is decoded.
pub const MAX_TOTAL_TEXELS: u64 = 1 << 25;

/// The world-length range where the kernels' intersection error bounds hold,
/// the range `rtow stress` measures (radius and distance 1e-4 .. 1e6; its
/// `stress-tiny` preset has a hollow sphere of radius 9e-5): every
/// coordinate (sphere centres, `look_from`, `look_at`) within
/// `[-MAX_COORD, MAX_COORD]`, every radius `|r|` in `[MIN_RADIUS, MAX_RADIUS]`.
/// Outside it `r^2` or `|o - c|^2` overflow or underflow f32 (a sphere of
/// radius 1e20 would silently vanish).
pub const MAX_COORD: f32 = 1e6;
pub const MIN_RADIUS: f32 = 1e-5;
pub const MAX_RADIUS: f32 = 1e6;

/// A checker's cell size and a noise texture's frequency: a checker's scale
/// in `[MIN_TEXTURE_SCALE, MAX_TEXTURE_SCALE]` (a cell smaller than the f32
/// spacing of the coordinates it tiles is noise, not a checker), a noise
/// scale in `[0, MAX_TEXTURE_SCALE]`.
pub const MIN_TEXTURE_SCALE: f32 = 1e-5;
pub const MAX_TEXTURE_SCALE: f32 = 1e6;

/// The focus distance (given, or |look_from - look_at|): the camera's f32
/// pixel grid is computed relative to the eye at this distance, and its ray
/// directions are normalized in f32, so it must neither underflow nor overflow.
pub const MIN_FOCUS: f32 = 1e-6;
pub const MAX_FOCUS: f32 = 1e7;

/// Narrowest field of view (degrees): below about 1e-4 degrees the whole
/// image spans fewer f32 steps than it has pixels and every pixel sees the
/// same ray. (`stress-far-camera` uses 0.0027 degrees.)
pub const MIN_VFOV_DEG: f32 = 1e-4;

/// Largest thin-lens radius (world units).
pub const MAX_LENS_RADIUS: f32 = MAX_COORD;

/// Most worker threads: more than any machine rtow runs on has cores; each
/// thread costs a stack and a workspace.
pub const MAX_THREADS: usize = 1024;

/// A render in which more than this fraction of the samples were NaN or
/// infinite (and so rejected from the image) fails with exit status 2 rather
/// than writing an image that is mostly black: the scene is numerically
/// degenerate (e.g. a colour near f32::MAX).
pub const MAX_REJECTED_FRACTION: f64 = 1e-3;

/// Reads the file at `path` whole, refusing it (exit status 2) when it is
/// larger than `limit` bytes: by its size before reading anything, and by
/// counting while reading (a pipe or a growing file has no size up front), so
/// at most `limit + 1` bytes are ever held. `what` names the input in errors.
pub fn read_bounded(path: &std::path::Path, limit: u64, what: &str) -> Result<Vec<u8>> {
    use std::io::Read;
    let cannot = |e: &dyn std::fmt::Display| Error::Input(format!("cannot read {}: {e}", path.display()));
    let too_big = |size: &dyn std::fmt::Display| {
        Error::Input(format!("{what} {} is too large: {size} bytes, at most {limit}", path.display()))
    };
    let file = std::fs::File::open(path).map_err(|e| cannot(&e))?;
    let meta = file.metadata().map_err(|e| cannot(&e))?;
    if meta.is_dir() {
        return Err(cannot(&"is a directory"));
    }
    if meta.is_file() && meta.len() > limit {
        return Err(too_big(&meta.len()));
    }
    let mut bytes = Vec::with_capacity(if meta.is_file() { meta.len() as usize } else { 0 });
    file.take(limit + 1).read_to_end(&mut bytes).map_err(|e| cannot(&e))?;
    if bytes.len() as u64 > limit {
        return Err(too_big(&format_args!("more than {limit}")));
    }
    Ok(bytes)
}

/// Worker threads: at least 1, at most [`MAX_THREADS`] (`None`: one per core).
pub fn check_threads(threads: Option<usize>) -> Result<()> {
    match threads {
        Some(0) => Err(Error::invalid("threads", "must be at least 1")),
        Some(n) if n > MAX_THREADS => Err(Error::invalid("threads", format!("{n} is too many; at most {MAX_THREADS}"))),
        _ => Ok(()),
    }
}

/// Fails when more than [`MAX_REJECTED_FRACTION`] of `samples` were rejected.
pub fn check_rejected(rejected: u64, samples: u64) -> Result<()> {
    if samples > 0 && rejected as f64 > MAX_REJECTED_FRACTION * samples as f64 {
        return Err(Error::Degenerate(format!(
            "{rejected} of {samples} samples ({:.2}%) were NaN or infinite (at most {}% may be): \
             the scene is numerically degenerate; no image written",
            100.0 * rejected as f64 / samples as f64,
            100.0 * MAX_REJECTED_FRACTION
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threads_are_bounded() {
        assert!(check_threads(None).is_ok());
        assert!(check_threads(Some(MAX_THREADS)).is_ok());
        let e = check_threads(Some(100_000_000)).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("1024"), "{e}");
        assert!(check_threads(Some(0)).is_err());
    }

    #[test]
    fn rejected_fraction_is_bounded() {
        assert!(check_rejected(0, 0).is_ok());
        assert!(check_rejected(1, 1000).is_ok());
        let e = check_rejected(2, 1000).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("NaN or infinite"), "{e}");
    }
}
