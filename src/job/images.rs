//! Image textures' files: found, read (bounded), decoded and linearized
//! once per job, before anything renders.
//!
//! A scene names an image by the file name it gives (`{"type": "image",
//! "file": "earthmap.jpg"}`). An absolute name is read as it is; a relative
//! one is looked for first beside the scene file (for a partial film being
//! merged or resumed, beside the film), then in the folder the environment
//! variable `RTOW_IMAGES` names (the book's `RTW_IMAGES`; set to nothing, it
//! is unset), and nowhere else: never in the working directory as such.
//! Presets have no scene file: their images come from `RTOW_IMAGES` only.
//!
//! Every refusal is exit status 2, naming the scene field that names the
//! file, the name, the path read and what is wrong, never a solid colour
//! (the book's cyan): a name found nowhere (and where it was looked for), a
//! path that is a folder, a FIFO, a socket, a device or a link to nothing
//! rather than a file, a file too large, not a PNG or JPEG, with too many
//! texels, or truncated or corrupt: a PNG with a CRC error in any chunk, or
//! cut before the end of its IEND chunk ([`png_chunks`]); a JPEG without its
//! EOI marker, one zune-jpeg refuses in strict mode, or one whose scans end
//! before their last block ([`decode_jpeg`]). A JPEG carries no checksum: a
//! flipped bit that leaves a valid stream decodes to other texels and
//! cannot be told from a real image.
//!
//! Each distinct file (on Unix: device and inode, whatever names, links or
//! folders lead to it) is read and decoded once. Every file is found, read
//! and its header checked first, the image textures of a scene together
//! held to [`MAX_TOTAL_TEXELS`]; only then is each decoded.
//!
//! The bytes of every image are hashed into the job's identity (the
//! setting `images`), so two renders of one scene file with different images
//! never share an image key (their shards do not merge), and a merge that
//! finds other bytes under the name refuses to verify the parts with them.

use crate::error::{Error, Result};
use crate::film::part::fnv1a;
use crate::input::{self, at, shown, FileId, ReadError, Regular};
use crate::limits::{MAX_IMAGE_TEXTURES, MAX_TEXELS, MAX_TEXTURE_FILE_BYTES, MAX_TOTAL_TEXELS};
use crate::output::{clip_to, printable};
use crate::scene::Scene;
use crate::texture::ImageTex;
use std::fs::{File, Metadata};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The environment variable naming the folder of image textures.
pub const IMAGES_ENV: &str = "RTOW_IMAGES";

/// The folder `RTOW_IMAGES` names: `None` when it is unset or empty (an
/// empty value would otherwise name the working directory).
pub fn images_folder() -> Option<PathBuf> {
    std::env::var_os(IMAGES_ENV).filter(|v| !v.is_empty()).map(PathBuf::from)
}

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
        Images::load_within(scene, origin, images_folder().as_deref(), MAX_TOTAL_TEXELS)
    }

    /// [`Images::load`] with the folder of `RTOW_IMAGES` and the budget of
    /// texels given.
    fn load_within(scene: &Scene, origin: Option<&Path>, folder: Option<&Path>, budget: u64) -> Result<Images> {
        let names = scene.image_file_fields();
        if names.len() > MAX_IMAGE_TEXTURES {
            return Err(Error::invalid(
                &names[MAX_IMAGE_TEXTURES].1,
                format!(
                    "the scene names {} image files; at most {MAX_IMAGE_TEXTURES} are read (limits::MAX_IMAGE_TEXTURES)",
                    names.len()
                ),
            ));
        }
        // First every file found, read and its header checked, against the
        // budget too; then each decoded (read again: a file that changed in
        // between is refused), so nothing is decoded for a scene that is refused.
        let mut files: Vec<Pending> = Vec::new();
        let mut texels = 0u64;
        let mut which = Vec::with_capacity(names.len());
        for (name, field) in &names {
            let refuse = |what: String| Error::invalid(field, format!("image texture '{}' {what}", shown_name(name)));
            let found = find(name, origin, folder).map_err(refuse)?;
            if let Some(k) = files.iter().position(|f| f.id == found.id) {
                which.push(k);
                continue;
            }
            let bad = |what: String| refuse(format!("{}{what}", at(&found.path, name)));
            let bytes = read_bounded(&found.file, &found.meta).map_err(bad)?;
            let (format, w, h) = probe(&bytes).map_err(bad)?;
            let n = w as u64 * h as u64;
            if texels + n > budget {
                return Err(bad(format!(
                    "has {w} x {h} texels: with the {texels} of the {} image files before it, more than the {budget} \
                     the image textures of a scene may have together (limits::MAX_TOTAL_TEXELS)",
                    files.len()
                )));
            }
            texels += n;
            which.push(files.len());
            files.push(Pending {
                id: found.id,
                hash: fnv1a(&bytes),
                format,
                size: (w, h),
                name,
                field,
                path: found.path,
                file: found.file,
                meta: found.meta,
            });
        }
        let textures = files
            .iter()
            .map(|f| {
                let bad = |what: String| {
                    Error::invalid(
                        f.field,
                        format!("image texture '{}' {}{what}", shown_name(f.name), at(&f.path, f.name)),
                    )
                };
                let mut file = &f.file;
                std::io::Seek::rewind(&mut file).map_err(|e| bad(format!("cannot be read: {e}")))?;
                let bytes = read_bounded(file, &f.meta).map_err(bad)?;
                if fnv1a(&bytes) != f.hash {
                    return Err(bad("changed while rtow read it; run again once it is written".into()));
                }
                Ok(Arc::new(decode(&bytes, f.format, f.size).map_err(bad)?))
            })
            .collect::<Result<Vec<_>>>()?;
        let list = names
            .iter()
            .zip(which)
            .map(|(&(name, _), k)| Image { name: name.to_string(), hash: files[k].hash, texture: textures[k].clone() })
            .collect();
        Ok(Images { list })
    }
}

/// A distinct file found, read once and its header checked: decoded next.
struct Pending<'a> {
    id: FileId,
    hash: u64,
    format: image::ImageFormat,
    size: (u32, u32),
    /// The first name and field that lead to it.
    name: &'a str,
    field: &'a str,
    path: PathBuf,
    file: File,
    meta: Metadata,
}

/// A scene's name of an image for a message, as [`shown`].
fn shown_name(name: &str) -> String {
    shown(Path::new(name))
}

/// The file a scene's image `name` is: itself if absolute, else the first of
/// `origin`'s folder and `folder` (`RTOW_IMAGES`) that holds it. Refused (a
/// message that follows the name) when nothing is found, or when the first
/// path that exists is not a regular file.
fn find(name: &str, origin: Option<&Path>, folder: Option<&Path>) -> std::result::Result<Regular, String> {
    let given = Path::new(name);
    if given.is_absolute() {
        return open_regular(given, name)?.ok_or_else(|| "not found: no such file".to_string());
    }
    let beside = origin.map(|o| o.parent().unwrap_or(Path::new("")));
    let mut looked = Vec::new();
    for dir in beside.into_iter().chain(folder) {
        if let Some(found) = open_regular(&dir.join(given), name)? {
            return Ok(found);
        }
        let mut place = if dir.as_os_str().is_empty() { ".".to_string() } else { shown(dir) };
        if Some(dir) == folder && !dir.is_dir() {
            place.push_str(&format!(" ({IMAGES_ENV}, not a folder)"));
        }
        looked.push(place);
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
        return Err(format!(
            "not found: {IMAGES_ENV} is not set (a scene without a file, such as a preset, reads its images from the \
             folder it names){hint}"
        ));
    }
    Err(format!("not found: looked in {}{hint}", looked.join(", ")))
}

/// The regular file at `path`, open; `None` when nothing is there. Anything
/// else that is there (a folder, a FIFO, a dangling link), or a path that
/// cannot be looked at, is refused.
fn open_regular(path: &Path, name: &str) -> std::result::Result<Option<Regular>, String> {
    input::open_regular(path).map_err(|u| {
        format!("{}{}", at(path, name), u.describe("not an image file: an image texture is a PNG or JPEG file"))
    })
}

/// The file's bytes, refused beyond [`MAX_TEXTURE_FILE_BYTES`] (by its size
/// before reading, and while reading a file that grows).
fn read_bounded(file: &File, meta: &Metadata) -> std::result::Result<Vec<u8>, String> {
    input::read_bounded(file, meta, MAX_TEXTURE_FILE_BYTES).map_err(|e| match e {
        ReadError::TooLarge(_) => {
            format!("is larger than {} MiB, the most an image texture file may take", MAX_TEXTURE_FILE_BYTES >> 20)
        }
        ReadError::Io(e) => format!("cannot be read: {e}"),
    })
}

/// The decoder's limits: [`MAX_TEXELS`] and 16 bytes a texel.
fn limits() -> image::Limits {
    let mut limits = image::Limits::default();
    let side = MAX_TEXELS as u32;
    limits.max_image_width = Some(side);
    limits.max_image_height = Some(side);
    // The decoded image and its RGB copy, with room for the decoder's own buffers.
    limits.max_alloc = Some(MAX_TEXELS * 16);
    limits
}

/// What the decoder said about a bad file, escaped and bounded.
fn corrupt(format: image::ImageFormat, why: &dyn std::fmt::Display) -> String {
    let kind = if format == image::ImageFormat::Png { "PNG" } else { "JPEG" };
    format!("is a truncated or corrupt {kind} file ({})", clip_to(&printable(&why.to_string()), 200))
}

/// A PNG or JPEG file's format and size from its header, refused when it is
/// neither or has more than [`MAX_TEXELS`] texels (nothing is decoded).
fn probe(bytes: &[u8]) -> std::result::Result<(image::ImageFormat, u32, u32), String> {
    let format = image::guess_format(bytes).map_err(|_| "is not a PNG or JPEG image".to_string())?;
    if !matches!(format, image::ImageFormat::Png | image::ImageFormat::Jpeg) {
        return Err(format!("is a {format:?} image; image textures are PNG or JPEG"));
    }
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    reader.limits(limits());
    let (w, h) = reader.into_dimensions().map_err(|e| corrupt(format, &e))?;
    if w as u64 * h as u64 > MAX_TEXELS || w == 0 || h == 0 {
        return Err(format!("has {w} x {h} texels; an image texture has 1 to {MAX_TEXELS}"));
    }
    Ok((format, w, h))
}

/// A PNG or JPEG file's texels (`size` as [`probe`] read it), as 8-bit RGB
/// (grey replicated, alpha dropped: stb_image's three channels), linearized.
fn decode(bytes: &[u8], format: image::ImageFormat, size: (u32, u32)) -> std::result::Result<ImageTex, String> {
    let (width, height, rgb) = match format {
        image::ImageFormat::Jpeg => decode_jpeg(bytes)?,
        _ => {
            png_chunks(bytes).map_err(|why| corrupt(format, &why))?;
            let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
            reader.limits(limits());
            let img = reader.decode().map_err(|e| corrupt(format, &e))?.into_rgb8();
            (img.width(), img.height(), img.into_raw())
        }
    };
    if (width, height) != size {
        return Err(corrupt(
            format,
            &format_args!("its header says {} x {}, its data {width} x {height}", size.0, size.1),
        ));
    }
    ImageTex::from_rgb8(width, height, &rgb).ok_or_else(|| "is an empty image".to_string())
}

/// Checks a PNG's chunks, from the signature to IEND (bytes after it are
/// allowed): each whole, with its CRC. The png crate checks the CRCs of the
/// chunks it reads, but stops after the image data: a file cut in or before
/// its IEND chunk, or with a flipped bit in a chunk after the image data,
/// decodes.
pub(crate) fn png_chunks(bytes: &[u8]) -> std::result::Result<(), String> {
    let mut i = 8; // after the signature
    while let Some(head) = bytes.get(i..i + 8) {
        let len = u32::from_be_bytes([head[0], head[1], head[2], head[3]]) as usize;
        let kind = &head[4..8];
        let Some(body) = bytes.get(i + 4..i + 8 + len) else { break };
        let Some(crc) = bytes.get(i + 8 + len..i + 12 + len) else { break };
        if crc32fast::hash(body).to_be_bytes() != crc {
            return Err(format!("CRC error in the {} chunk at byte {i}", printable(&String::from_utf8_lossy(kind))));
        }
        if kind == b"IEND" {
            return Ok(());
        }
        i += 12 + len;
    }
    Err("no IEND chunk: the file is cut short".into())
}

/// A JPEG's texels as 8-bit RGB, decoded by zune-jpeg (the decoder of
/// `image`, with `image`'s choice of colours: RGB, RGBA, grey and grey with
/// alpha as they are, anything else as RGB) in strict mode, which refuses a
/// code that is in no Huffman table, a marker where none belongs and a file
/// that ends inside a scan (`image` runs it leniently and fills in grey).
/// Two more checks (neither changes a whole file's texels):
///
/// * the segments, walked from SOI, reach an EOI marker (bytes after it are
///   allowed, as every decoder allows them): a file cut short has none;
/// * every run of entropy-coded data holds all the blocks it should: even in
///   strict mode the decoder fills with zero bits the blocks of a scan (or
///   restart interval) that ends early at a marker (a header whose size was
///   changed, a scan cut and closed with an EOI). So the file is decoded a
///   second time with [`FILLER`] bytes inserted before every marker that
///   ends such a run: a run that held all its blocks never reaches them, and
///   the texels are the same; one that ended early decodes them instead of
///   zeros, and they differ.
fn decode_jpeg(bytes: &[u8]) -> std::result::Result<(u32, u32, Vec<u8>), String> {
    use zune_jpeg::zune_core::{bytestream::ZCursor, colorspace::ColorSpace, options::DecoderOptions};
    let bad = |why: &dyn std::fmt::Display| corrupt(image::ImageFormat::Jpeg, why);
    let ends = data_ends(bytes).ok_or_else(|| bad(&"no end-of-image marker: the file is cut short"))?;
    let run = |bytes: &[u8]| {
        let side = MAX_TEXELS as usize;
        let options = DecoderOptions::default().set_strict_mode(true).set_max_width(side).set_max_height(side);
        let mut decoder = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), options);
        decoder.decode_headers().map_err(|e| bad(&e))?;
        let out = match decoder.input_colorspace() {
            Some(c @ (ColorSpace::RGB | ColorSpace::RGBA | ColorSpace::Luma | ColorSpace::LumaA)) => c,
            _ => ColorSpace::RGB,
        };
        decoder.set_options(decoder.options().jpeg_set_out_colorspace(out));
        let pixels = decoder.decode().map_err(|e| bad(&e))?;
        let (w, h) = decoder.dimensions().ok_or_else(|| bad(&"no size"))?;
        Ok::<_, String>((w, h, out, pixels))
    };
    let (w, h, out, pixels) = run(bytes)?;
    if ends.len() > MAX_DATA_RUNS {
        return Err(bad(&format_args!("{} runs of entropy-coded data, more than {MAX_DATA_RUNS}", ends.len())));
    }
    let mut filled = Vec::with_capacity(bytes.len() + ends.len() * FILLER.len());
    let mut from = 0;
    for &end in &ends {
        filled.extend_from_slice(&bytes[from..end]);
        filled.extend_from_slice(&FILLER);
        from = end;
    }
    filled.extend_from_slice(&bytes[from..]);
    if !run(&filled).is_ok_and(|again| again.3 == pixels) {
        return Err(bad(&"a scan ends before its last block: the texels after it would be made up"));
    }
    drop(filled);
    let channels = out.num_components();
    if pixels.len() != w * h * channels {
        return Err(bad(&format_args!("{} bytes decoded for {w} x {h} texels", pixels.len())));
    }
    let rgb = match out {
        ColorSpace::RGB => pixels,
        ColorSpace::RGBA => pixels.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect(),
        _ => pixels.chunks_exact(channels).flat_map(|p| [p[0]; 3]).collect(),
    };
    Ok((w as u32, h as u32, rgb))
}

/// Bytes a short run reads instead of the zero bits the decoder makes up:
/// 32 pseudo-random bytes (no 0xFF, which would start a marker, and a first
/// bit of 1, so the first Huffman code read from them is not the one zero
/// bits give, nor is a refinement bit). A short run is found when what it
/// decodes from them differs from what it decodes from zeros; a fixed
/// pattern such as 0xFE repeated was seen to decode to the same texels as zeros.
const FILLER: [u8; 32] = [
    0xAF, 0x9C, 0x18, 0xF0, 0x9F, 0xAB, 0xD8, 0xC0, 0xD6, 0xA3, 0x84, 0x0A, 0xA2, 0xFC, 0x5F, 0x71, 0x88, 0xCB, 0x1C,
    0xFC, 0xAF, 0x75, 0x9A, 0xCC, 0x49, 0xED, 0x61, 0xFA, 0xBD, 0x6D, 0x72, 0x25,
];

/// Most runs of entropy-coded data (scans and restart intervals) a JPEG may
/// have: 2^20, a restart after every block of a 2^24-texel grey image in 4
/// scans; the second decoding is at most 32 MiB larger than the file.
const MAX_DATA_RUNS: usize = 1 << 20;

/// Where a JPEG's runs of entropy-coded data end: the offset of each marker
/// that follows one (a restart, or the marker after a scan), from walking
/// its segments from SOI; `None` when the walk does not reach an EOI marker.
/// Not the end of a progressive JPEG's first scan when another scan follows:
/// zune-jpeg requires the marker after that scan to follow its last block
/// within the bytes it reads ahead, and refuses the file if anything is
/// inserted there. (When EOI follows it, the file is refused either way: a
/// progressive image of one scan is a file cut and closed with an EOI.)
fn data_ends(bytes: &[u8]) -> Option<Vec<usize>> {
    let mut ends = Vec::new();
    let (mut progressive, mut scans) = (false, 0);
    let mut i = 2; // after SOI
    while i + 1 < bytes.len() {
        if bytes[i] != 0xFF {
            return None;
        }
        let marker = bytes[i + 1];
        match marker {
            0xD9 => return Some(ends),
            // Fill bytes before a marker.
            0xFF => i += 1,
            0x01 | 0xD0..=0xD7 => i += 2,
            _ => {
                let len = u16::from_be_bytes([*bytes.get(i + 2)?, *bytes.get(i + 3)?]) as usize;
                if len < 2 {
                    return None;
                }
                i += 2 + len;
                // SOF2, SOF6, SOF10, SOF14: a progressive frame.
                progressive |= matches!(marker, 0xC2 | 0xC6 | 0xCA | 0xCE);
                if marker == 0xDA {
                    scans += 1;
                    // The scan's data, to the next marker that is neither
                    // stuffing (FF 00) nor a restart (FF D0..D7).
                    loop {
                        while i + 1 < bytes.len() && !(bytes[i] == 0xFF && bytes[i + 1] != 0x00) {
                            i += 1;
                        }
                        if i + 1 >= bytes.len() {
                            return None;
                        }
                        ends.push(i);
                        let mut m = i + 1;
                        while bytes.get(m) == Some(&0xFF) {
                            m += 1;
                        }
                        match bytes.get(m) {
                            Some(0xD0..=0xD7) => i = m + 1,
                            Some(0xD9) => break,
                            _ => {
                                if progressive && scans == 1 {
                                    ends.pop();
                                }
                                break;
                            }
                        }
                    }
                }
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, Sphere, Texture};

    /// A `w` x `h` image of varied texels, encoded as `format` (`image`'s
    /// encoders: a baseline JPEG, 4:2:0, no restarts).
    fn encoded(w: u32, h: u32, format: image::ImageFormat) -> Vec<u8> {
        let img =
            image::RgbImage::from_fn(w, h, |x, y| image::Rgb([(x * 13) as u8, (y * 29) as u8, ((x * y) ^ 0x5a) as u8]));
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, format).unwrap();
        out.into_inner()
    }

    /// A 24 x 16 progressive JPEG (4:2:0, 10 scans) with a restart marker
    /// after every MCU (26 of them): `cjpeg -progressive -restart 1B` (libjpeg-turbo
    /// 2.1.5) of a gradient, `(10 x, 16 y, 3 x y mod 256)`. `image`'s encoder
    /// writes neither progressive scans nor restarts.
    fn progressive() -> Vec<u8> {
        let hex = "\
        ffd8ffe000104a46494600010100000100010000ffdb004300080606070605080707070909080a0c140d0c0b0b0c1912130f\
        141d1a1f1e1d1a1c1c20242e2720222c231c1c2837292c30313434341f27393d38323c2e333432ffdb0043010909090c0b0c\
        180d0d1832211c21323232323232323232323232323232323232323232323232323232323232323232323232323232323232\
        3232323232323232ffc20011080010001803012200021101031101ffc4001700000301000000000000000000000000000004\
        0506ffc40017010003010000000000000000000000000002030405ffdd00040001ffda000c03010002100310000001cb50b4\
        e84dffd04cd308d4ffc4001810000301010000000000000000000000000002030401ffda00080101000105024ce7ffd05cc7\
        ffd15cfc3fffd29c0fffd3581fffd4581fffc40017110003010000000000000000000000000000030422ffda000801030101\
        3f019ae3ffd05dd93fffc4001b1100020203010000000000000000000000010200031112d1f0ffda0008010201013f014b13\
        404cffd06bd33ee19fffc40017100100030000000000000000000000000000011131ffda0008010100063f027fffd07fffd1\
        c7ffd27fffd3b97fffd47fffc4001a100002030101000000000000000000000000011121415181ffda0008010100013f2193\
        0fffd0544b47ffd1c8ecffd2aa5a3fffd3c8be1fffd4e8bc3fffda000c03010002000300000010dbffd037ffc40018110003\
        01010000000000000000000000000001112131ffda0008010301013f106de9ffd07469ffc4001d1101000104030100000000\
        0000000000000111002151813141c1f0ffda0008010201013f100072b7bf0197c3baffd015d068f8dce6bfffc4001b100100\
        020301010000000000000000000001001121317161c1ffda0008010100013f10c4f99fffd010107b3fffd15ec3944fffd213\
        5a173fffd3b6acad47ffd45babf19180ecffd9";
        (0..hex.len()).step_by(2).map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap()).collect()
    }

    /// What `image` (zune-jpeg run leniently, the png crate) decodes.
    fn lenient(bytes: &[u8]) -> Option<Vec<u8>> {
        Some(image::load_from_memory(bytes).ok()?.into_rgb8().into_raw())
    }

    fn strict(bytes: &[u8]) -> std::result::Result<ImageTex, String> {
        let (format, w, h) = probe(bytes)?;
        decode(bytes, format, (w, h))
    }

    #[test]
    fn whole_files_decode_to_what_image_decodes() {
        let files = [
            (encoded(37, 19, image::ImageFormat::Png), (37, 19)),
            (encoded(37, 19, image::ImageFormat::Jpeg), (37, 19)),
            (progressive(), (24, 16)),
        ];
        for (bytes, (w, h)) in files {
            let t = strict(&bytes).unwrap();
            assert_eq!((t.width, t.height), (w, h));
            assert!(t.texels == ImageTex::from_rgb8(w, h, &lenient(&bytes).unwrap()).unwrap().texels);
        }
        // Grey: replicated (image's into_rgb8). Bytes after the end are allowed.
        let grey = image::GrayImage::from_fn(9, 5, |x, y| image::Luma([(x * 20 + y) as u8]));
        let mut jpg = std::io::Cursor::new(Vec::new());
        grey.write_to(&mut jpg, image::ImageFormat::Jpeg).unwrap();
        let mut jpg = jpg.into_inner();
        let t = strict(&jpg).unwrap();
        assert!(t.texels == ImageTex::from_rgb8(9, 5, &lenient(&jpg).unwrap()).unwrap().texels, "grey JPEG");
        jpg.extend_from_slice(b"trailing bytes");
        assert!(strict(&jpg).unwrap().texels == t.texels);
        let mut png = encoded(5, 3, image::ImageFormat::Png);
        png.extend_from_slice(b"trailing bytes");
        assert!(strict(&png).is_ok());
    }

    /// Whether `bytes[n..]` starts a marker segment other than a restart (a
    /// JPEG cut there, or after its 0xFF, which may be a fill byte, ends
    /// between two segments).
    fn at_segment(bytes: &[u8], n: usize) -> bool {
        bytes[n] == 0xFF && !matches!(bytes[n + 1], 0x00 | 0xD0..=0xD7)
    }

    #[test]
    fn cut_jpegs_and_pngs_are_refused_wherever_they_are_cut() {
        let files =
            [encoded(40, 24, image::ImageFormat::Png), encoded(40, 24, image::ImageFormat::Jpeg), progressive()];
        for bytes in &files {
            // Every length short of the whole file, the last bytes (a JPEG's
            // EOI, a PNG's IEND) included.
            for n in 0..bytes.len() {
                assert!(strict(&bytes[..n]).is_err(), "cut to {n} of {} bytes: accepted", bytes.len());
            }
        }
        // What `image` accepts: a JPEG cut in its scan, grey filled in.
        let jpg = &files[1];
        let cut = &jpg[..jpg.len() * 3 / 4];
        assert!(lenient(cut).is_some(), "image decodes a cut JPEG");
        let e = strict(cut).unwrap_err();
        assert!(e.contains("truncated or corrupt JPEG") && e.contains("no end-of-image marker"), "{e}");
        // Cut and closed with an EOI marker: the decoder, even strict, would
        // fill in the blocks after the cut. Refused wherever the cut is in
        // the entropy-coded data (restart markers included); a progressive
        // JPEG cut between two of its segments is a valid JPEG of fewer scans.
        for bytes in &files[1..] {
            let mut refused = 0;
            for n in 2..bytes.len() - 2 {
                let mut b = bytes[..n].to_vec();
                b.extend_from_slice(&[0xFF, 0xD9]);
                match strict(&b) {
                    Err(_) => refused += 1,
                    Ok(_) => assert!(
                        at_segment(bytes, n) || at_segment(bytes, n - 1),
                        "cut at {n} of {} and closed: accepted",
                        bytes.len()
                    ),
                }
            }
            assert!(refused > bytes.len() / 2);
        }
    }

    /// Every single flipped bit of a PNG is refused (the chunks' CRCs and
    /// lengths). A JPEG has no checksum: a flipped bit is refused, or
    /// decodes to texels the file holds (an image of a size within its
    /// blocks: 4:2:0, one 16 x 16 MCU for 12 x 7), never made up; a flip
    /// that makes the header claim more blocks than the scans hold is refused.
    #[test]
    fn flipped_bits_of_a_png_are_refused_and_of_a_jpeg_never_make_up_texels() {
        let png = encoded(12, 7, image::ImageFormat::Png);
        for bit in 0..png.len() * 8 {
            let mut b = png.clone();
            b[bit / 8] ^= 1 << (bit % 8);
            assert!(strict(&b).is_err(), "PNG with bit {bit} flipped: accepted");
        }
        for (jpg, mcus) in [(encoded(12, 7, image::ImageFormat::Jpeg), (16, 16)), (progressive(), (32, 16))] {
            let (mut refused, mut short) = (0, 0);
            for bit in 0..jpg.len() * 8 {
                let mut b = jpg.clone();
                b[bit / 8] ^= 1 << (bit % 8);
                match strict(&b) {
                    Ok(t) => assert!(t.width <= mcus.0 && t.height <= mcus.1, "bit {bit}: {} x {}", t.width, t.height),
                    Err(e) => {
                        assert!(e.starts_with("is ") || e.starts_with("has "), "{e}");
                        refused += 1;
                        short += e.contains("a scan ends before its last block") as usize;
                    }
                }
            }
            println!("{refused} of {} flipped bits refused, {short} of them for a short scan", jpg.len() * 8);
            assert!(refused > 0 && short > 0);
        }
    }

    /// A sphere under each image file name of `files`.
    fn scene_of(files: &[String]) -> Scene {
        let mut s = crate::scene::preset("ch07-diffuse").unwrap();
        s.spheres = files
            .iter()
            .map(|f| Sphere {
                center: [0.0; 3],
                center1: None,
                radius: 1.0,
                material: Material::Lambertian { albedo: Texture::Image { file: f.clone() } },
            })
            .collect();
        s
    }

    #[test]
    fn one_file_under_many_names_is_decoded_once_and_the_budget_counts_files() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("sub")).unwrap();
        std::fs::write(d.join("a.png"), encoded(8, 4, image::ImageFormat::Png)).unwrap();
        std::fs::write(d.join("b.png"), encoded(8, 4, image::ImageFormat::Png)).unwrap();
        std::fs::hard_link(d.join("a.png"), d.join("hard.png")).unwrap();
        #[cfg(unix)]
        std::os::unix::fs::symlink(d.join("a.png"), d.join("sub/link.png")).unwrap();
        #[cfg(not(unix))]
        std::fs::copy(d.join("a.png"), d.join("sub/link.png")).unwrap();
        let origin = d.join("scene.json");
        let names: Vec<String> = ["a.png", "./a.png", "sub/../a.png", "hard.png"]
            .iter()
            .map(|s| s.to_string())
            .chain(cfg!(unix).then(|| "sub/link.png".to_string()))
            .chain([d.join("a.png").to_string_lossy().into_owned()])
            .collect();
        let images = Images::load_within(&scene_of(&names), Some(&origin), None, 32).unwrap();
        assert_eq!(images.list.len(), names.len());
        assert!(images.list.iter().all(|i| Arc::ptr_eq(&i.texture, &images.list[0].texture)), "one texture");
        // Another file of the same size is another 32 texels: over a budget of 32.
        let mut more = names.clone();
        more.push("b.png".into());
        let e = Images::load_within(&scene_of(&more), Some(&origin), None, 32).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!("spheres[{}].material.albedo.file: image texture 'b.png' at ", names.len())),
            "{e}"
        );
        assert!(e.contains("has 8 x 4 texels: with the 32 of the 1 image files before it, more than the 32"), "{e}");
        assert!(Images::load_within(&scene_of(&more), Some(&origin), None, 64).is_ok());
    }
}
