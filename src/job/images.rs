//! Image textures' files: found, read (bounded), decoded and linearized
//! once per job, before anything renders.
//!
//! A scene names an image by the file name it gives (`{"type": "image",
//! "file": "earthmap.jpg"}`). An absolute name is read as it is; a relative
//! one is looked for first beside the scene file (for a partial film being
//! merged or resumed, beside the film), then in the folder the environment
//! variable `RTOW_IMAGES` names (the book's `RTW_IMAGES`). Presets have no
//! scene file: their images come from `RTOW_IMAGES` only. A file that is not
//! found, too large, or not a PNG or JPEG is an error naming it (exit status
//! 2), never a solid colour (the book's cyan).
//!
//! The bytes of every image are hashed into the job's identity (the
//! setting `images`), so two renders of one scene file with different images
//! never share an image key (their shards do not merge), and a merge that
//! finds other bytes under the name refuses to verify the parts with them.

use crate::error::{Error, Result};
use crate::film::part::fnv1a;
use crate::limits::{MAX_IMAGE_TEXTURES, MAX_TEXELS, MAX_TEXTURE_FILE_BYTES};
use crate::scene::Scene;
use crate::texture::ImageTex;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The environment variable naming the folder of image textures.
pub const IMAGES_ENV: &str = "RTOW_IMAGES";

/// One image file a scene names: its name as the scene gives it, the hash of
/// its bytes and its texels.
#[derive(Debug)]
pub struct Image {
    pub name: String,
    pub hash: u64,
    pub texture: Arc<ImageTex>,
}

/// Every image a job's scene names, in the order the scene first names them.
#[derive(Debug, Default)]
pub struct Images {
    pub list: Vec<Image>,
}

impl Images {
    /// The texture a scene names `name` (loaded by [`Images::load`]).
    pub fn get(&self, name: &str) -> Option<&Arc<ImageTex>> {
        self.list.iter().find(|i| i.name == name).map(|i| &i.texture)
    }

    /// Reads every image `scene` names; `origin` is the scene file (or the
    /// partial film) whose folder relative names are looked for in first.
    pub fn load(scene: &Scene, origin: Option<&Path>) -> Result<Images> {
        let names = scene.image_files();
        if names.len() > MAX_IMAGE_TEXTURES {
            return Err(Error::Input(format!(
                "the scene names {} image files; at most {MAX_IMAGE_TEXTURES} are read",
                names.len()
            )));
        }
        let folder = std::env::var_os(IMAGES_ENV).map(PathBuf::from);
        let list = names
            .into_iter()
            .map(|name| {
                let path = find(name, origin, folder.as_deref())?;
                let bytes = read_bounded(&path)?;
                let texture = Arc::new(decode(&path, &bytes)?);
                Ok(Image { name: name.to_string(), hash: fnv1a(&bytes), texture })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Images { list })
    }
}

/// The file a scene's image `name` is: itself if absolute, else the first of
/// `origin`'s folder and `folder` (`RTOW_IMAGES`) that holds it.
fn find(name: &str, origin: Option<&Path>, folder: Option<&Path>) -> Result<PathBuf> {
    let given = Path::new(name);
    if given.is_absolute() {
        return if given.is_file() {
            Ok(given.to_path_buf())
        } else {
            Err(Error::Input(format!("image texture {}: no such file", given.display())))
        };
    }
    let beside = origin.map(|o| o.parent().unwrap_or(Path::new("")).to_path_buf());
    let mut looked = Vec::new();
    for dir in beside.iter().map(PathBuf::as_path).chain(folder) {
        let path = dir.join(given);
        if path.is_file() {
            return Ok(path);
        }
        looked.push(if dir.as_os_str().is_empty() { ".".to_string() } else { dir.display().to_string() });
    }
    let hint = match folder {
        Some(_) => String::new(),
        None => format!(
            "; set {IMAGES_ENV} to the folder that holds it{}",
            if name == "earthmap.jpg" {
                " (the book's map: https://raytracing.github.io/images/earthmap.jpg, in its repository's images/ folder)"
            } else {
                ""
            }
        ),
    };
    if looked.is_empty() {
        return Err(Error::Input(format!(
            "image texture '{name}' not found: {IMAGES_ENV} is not set (a scene without a file, such as a preset, \
             reads its images from the folder it names){hint}"
        )));
    }
    Err(Error::Input(format!("image texture '{name}' not found: looked in {}{hint}", looked.join(", "))))
}

/// The file's bytes, refused beyond [`MAX_TEXTURE_FILE_BYTES`].
fn read_bounded(path: &Path) -> Result<Vec<u8>> {
    let io = |e: std::io::Error| Error::Input(format!("image texture {}: {e}", path.display()));
    let file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    file.take(MAX_TEXTURE_FILE_BYTES + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > MAX_TEXTURE_FILE_BYTES {
        return Err(Error::Input(format!(
            "image texture {}: larger than {} MiB, the most an image texture may take",
            path.display(),
            MAX_TEXTURE_FILE_BYTES >> 20
        )));
    }
    Ok(bytes)
}

/// A PNG or JPEG file's texels, at most [`MAX_TEXELS`] of them, as 8-bit
/// RGB (grey replicated, alpha dropped: stb_image's three channels), linearized.
fn decode(path: &Path, bytes: &[u8]) -> Result<ImageTex> {
    let bad = |why: String| Error::Input(format!("image texture {}: {why}", path.display()));
    let format = image::guess_format(bytes).map_err(|_| bad("not a PNG or JPEG image".into()))?;
    if !matches!(format, image::ImageFormat::Png | image::ImageFormat::Jpeg) {
        return Err(bad(format!("a {format:?} image; image textures are PNG or JPEG")));
    }
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    let mut limits = image::Limits::default();
    let side = MAX_TEXELS as u32;
    limits.max_image_width = Some(side);
    limits.max_image_height = Some(side);
    // The decoded image and its RGB copy, with room for the decoder's own buffers.
    limits.max_alloc = Some(MAX_TEXELS * 16);
    reader.limits(limits.clone());
    let (w, h) = reader.into_dimensions().map_err(|e| bad(e.to_string()))?;
    if w as u64 * h as u64 > MAX_TEXELS || w == 0 || h == 0 {
        return Err(bad(format!("{w} x {h} texels; an image texture has 1 to {MAX_TEXELS}")));
    }
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    reader.limits(limits);
    let img = reader.decode().map_err(|e| bad(e.to_string()))?.into_rgb8();
    ImageTex::from_rgb8(img.width(), img.height(), img.as_raw()).ok_or_else(|| bad("an empty image".into()))
}
