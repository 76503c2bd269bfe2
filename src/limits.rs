//! Documented bounds on every input rtow accepts: file sizes, scene contents,
//! world lengths and resource flags. Each one is checked before any work that
//! depends on it, so hostile input is refused (exit status 2) instead of
//! exhausting memory, hanging, or rendering garbage. docs/reliability.md
//! lists them.

use crate::choice::OnRejected;
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
/// The most meshes a scene file may list (its own and each group's, each
/// list bounded while it is read); their triangles are bounded by
/// [`MAX_SCENE_TRIANGLES`].
pub const MAX_MESHES: usize = 1 << 16;
/// The most triangles a scene may hold once flattened (every mesh, each
/// group's copy included; a mesh shared by instances once), checked before
/// any is made: 2^23. Preparing a
/// scene peaks at about 150 bytes a triangle (the tree's build included:
/// 376 MiB measured for 2,488,320 triangles), about 1.3 GB at the limit.
/// Also bounds the triangles' hit indices (`TRIANGLE_BASE + i`, `i <
/// 2^28`).
pub const MAX_SCENE_TRIANGLES: u64 = 1 << 23;
/// The most triangles the instances of shared meshes may place, every
/// placement counted (`geometry::instances`): 2^30, the range of their hit
/// indices. A shared mesh's triangles are held once, whatever its
/// placements, and counted once toward [`MAX_SCENE_TRIANGLES`].
pub const MAX_INSTANCED_TRIANGLES: u64 = 1 << 30;
/// Shapes the `book` estimator samples toward, at most (its `sample_toward`
/// list, or the lights it takes by default), and lights the `nee-mis`
/// estimator samples: every diffuse vertex evaluates the density of each.
pub const MAX_SAMPLED_SHAPES: usize = 64;

/// Largest triangle mesh file read (bytes, a Wavefront OBJ: `mesh::obj`),
/// refused by its size before it is read. The file is held whole while it is
/// scanned and parsed.
pub const MAX_MESH_FILE_BYTES: u64 = 256 << 20;
/// Most triangles a triangle mesh may have (`mesh::TriMesh::check`), after
/// its polygons are split into triangles. A mesh file's are counted while it
/// is scanned, before it is parsed. A triangle takes 12 bytes in a mesh; the
/// OBJ parser (tobj) holds about 110 bytes a face line while it reads: a
/// file of this many triangles peaked at 2.0 GB (measured).
pub const MAX_TRIANGLES: usize = 1 << 24;
/// Most vertices a triangle mesh may have (12 bytes each, 24 with normals),
/// and most positions (`v`), normals (`vn`) and texture coordinates (`vt`)
/// a mesh file may list, each counted while it is scanned.
pub const MAX_MESH_VERTICES: usize = 1 << 24;
/// The most distinct OBJ files a scene may name (each read once, however
/// many meshes name it).
pub const MAX_MESH_FILES: usize = 1024;
/// Finest icosphere (`mesh::icosphere`): level 7, 327,680 triangles and
/// 163,842 vertices a sphere; each level has four times the triangles of the
/// one before.
pub const MAX_ICOSPHERE_LEVEL: u32 = 7;

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

/// A render in which more than this fraction of the samples were rejected
/// (NaN, infinite, or out of the film's range) fails with exit status 2 rather
/// than writing an image that is mostly black: the scene is numerically
/// degenerate (e.g. an albedo near f32::MAX). Fewer are reported (a warning
/// line, the statistics), and `--on-rejected error` fails on any.
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

/// The samples a render (or the parts of a merge) rejected, by cause.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rejected {
    /// Samples traced (accepted and rejected).
    pub samples: u64,
    /// Samples rejected, whatever the cause.
    pub total: u64,
    /// Of those, the finite samples outside the film's range.
    pub out_of_range: u64,
    /// The film's range: a sample is accepted when every channel's magnitude is below it.
    pub range: f64,
}

impl Rejected {
    /// Samples with a NaN or infinite channel.
    pub fn non_finite(&self) -> u64 {
        self.total - self.out_of_range
    }

    /// E.g. "12 of 1,234,567 samples (0.00097%) rejected (3 NaN or infinite;
    /// 9 finite but out of the film's range: |x| >= 9.223e18)": a finite
    /// sample is never called NaN or infinite.
    pub fn describe(&self) -> String {
        let mut causes = Vec::new();
        if self.non_finite() > 0 {
            causes.push(format!("{} NaN or infinite", grouped(self.non_finite())));
        }
        if self.out_of_range > 0 {
            causes.push(format!(
                "{} finite but out of the film's range: |x| >= {:.3e}",
                grouped(self.out_of_range),
                self.range
            ));
        }
        let pct = if self.samples > 0 { 100.0 * self.total as f64 / self.samples as f64 } else { 0.0 };
        format!(
            "{} of {} samples ({}%) rejected ({})",
            grouped(self.total),
            grouped(self.samples),
            significant(pct),
            causes.join("; ")
        )
    }

    /// The line a run prints on stderr when it rejected samples, whatever
    /// its verbosity (`None`: none rejected).
    pub fn warning(&self) -> Option<String> {
        (self.total > 0).then(|| format!("{} and left out of the image", self.describe()))
    }

    /// Fails (exit status 2) when more than [`MAX_REJECTED_FRACTION`] of the samples were rejected.
    pub fn check_fraction(&self) -> Result<()> {
        if self.samples > 0 && self.total as f64 > MAX_REJECTED_FRACTION * self.samples as f64 {
            return Err(Error::Degenerate(format!(
                "{} (at most {}% may be): the scene is numerically degenerate; no image written",
                self.describe(),
                100.0 * MAX_REJECTED_FRACTION
            )));
        }
        Ok(())
    }

    /// [`Rejected::check_fraction`], then, under [`OnRejected::Error`], fails
    /// (exit status 2) when any sample was rejected.
    pub fn check(&self, policy: OnRejected) -> Result<()> {
        self.check_fraction()?;
        if policy == OnRejected::Error && self.total > 0 {
            return Err(Error::Degenerate(format!("{} and --on-rejected error: nothing written", self.describe())));
        }
        Ok(())
    }
}

/// `n` with its thousands separated by commas (1,234,567).
pub fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, ch) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(ch);
    }
    out
}

/// A percentage with two significant digits at least (0.00097, 12, 100).
fn significant(pct: f64) -> String {
    if pct == 0.0 || pct >= 1.0 {
        format!("{pct:.2}").trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        let decimals = (1.0 - pct.log10().floor()) as usize;
        format!("{pct:.decimals$}")
    }
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
        let r = |total, out_of_range, samples| Rejected { samples, total, out_of_range, range: 2f64.powi(63) };
        assert!(r(0, 0, 0).check_fraction().is_ok());
        assert!(r(1, 0, 1000).check_fraction().is_ok());
        assert!(r(1, 1, 1000).check(OnRejected::Warn).is_ok());
        let e = r(2, 0, 1000).check_fraction().unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("2 NaN or infinite") && !e.to_string().contains("range"), "{e}");
        // A finite sample is never called NaN or infinite.
        let e = r(2, 2, 1000).check_fraction().unwrap_err().to_string();
        assert!(!e.contains("NaN") && e.contains("2 finite but out of the film's range: |x| >= 9.223e18"), "{e}");
        let e = r(5, 2, 1000).check_fraction().unwrap_err().to_string();
        assert!(e.contains("3 NaN or infinite; 2 finite but out"), "{e}");
        // The policy: any rejected sample fails under `error`, none under `warn`.
        assert!(r(0, 0, 1000).check(OnRejected::Error).is_ok());
        let e = r(1, 1, 1000).check(OnRejected::Error).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("--on-rejected error: nothing written"), "{e}");
    }

    #[test]
    fn the_warning_names_the_count() {
        let r = Rejected { samples: 1_234_567, total: 12, out_of_range: 12, range: 2f64.powi(63) };
        assert_eq!(
            r.warning().unwrap(),
            "12 of 1,234,567 samples (0.00097%) rejected (12 finite but out of the film's range: |x| >= 9.223e18) \
             and left out of the image"
        );
        assert_eq!(Rejected { total: 0, out_of_range: 0, ..r }.warning(), None);
        assert_eq!(grouped(0), "0");
        assert_eq!(grouped(999), "999");
        assert_eq!(grouped(1000), "1,000");
        assert_eq!(grouped(u64::MAX), "18,446,744,073,709,551,615");
        assert_eq!(significant(100.0), "100");
        assert_eq!(significant(12.5), "12.5");
        assert_eq!(significant(0.1), "0.10");
    }
}
