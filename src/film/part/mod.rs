//! Partial films (`.rtfilm`): the exact accumulators of a shard or of a whole
//! render, in a file that `rtow merge` and `rtow render --resume` read back, and
//! that refuses to be combined with anything it does not fit.
//!
//! # Format, version 3
//!
//! All integers little-endian.
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `RTOWFILM` |
//! | 4 | format version (`u32`, 3) |
//! | 4 | header length `H` in bytes (`u32`, at most [`MAX_HEADER_BYTES`]) |
//! | `H` | header: one JSON object ([`Header`]) |
//! | `S` | the scene: its canonical JSON (the bytes its `scene_hash` hashes), `scene_bytes` long |
//! | `D` | data: for every pixel of the film's rows, row-major: the accepted samples (`u32`), the three fixed-point channel sums ([`super::accum`], in the scale of the header's `film_exponent`) as two's complement integers of `sum_bytes` bytes each, then, if `moments`, the three f64 sums of squares |
//! | 4 | CRC-32 (IEEE) of everything before it |
//!
//! The header names the image (`key`: a hash of the scene, the rtow version
//! and every setting that changes the image, listed in `scene_hash` and
//! `settings` too, so a refusal can name the difference), the image size and
//! samples per pixel, the split (`samples` or `rows`, shard K of N, or `none`
//! for a whole render), the sample range and the rows it covers, the
//! fixed-point layout (fractional bits and the film's scale exponent: parts
//! of different exponents are never merged), and the kernel-independent
//! counters (rays, samples, rejected samples and how many of those were out
//! of the film's range).
//!
//! A part is self-contained: with its scene and settings, `rtow merge` can
//! render any of its pixels again and compare them with its data (the
//! verified merge, `shard::merge_files`).
//!
//! Readers refuse a file whose version is newer than theirs before looking
//! further, so a later version may change anything after the first 16 bytes.
//! Version 1 (no embedded scene) is refused: it cannot be verified. Version 2
//! (no scale exponent, rejected samples not counted by cause) is refused:
//! its rejections cannot be reported by cause.
//!
//! Every header field is checked against the limits every render is held to
//! before anything is allocated, and the file's length against the length
//! the header implies before the scene and the data are read
//! ([`PartReader`]), in bounded pieces.

use super::{accum, Film};
use crate::error::{Error, Result};
use crate::limits::MAX_PIXELS;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

mod reader;
mod split;

pub use reader::{PartReader, Pixel, Stage};
pub use split::{Split, SplitKind};

/// The first 8 bytes of every partial film.
pub const MAGIC: &[u8; 8] = b"RTOWFILM";
/// The format version this rtow writes and reads.
pub const VERSION: u32 = 3;
/// Largest partial film read (bytes): `MAX_PIXELS` pixels with the widest
/// sums and the sums of squares, and a header.
pub const MAX_FILM_BYTES: u64 =
    crate::limits::MAX_PIXELS * (4 + 3 * 16 + 3 * 8) + MAX_SCENE_BYTES + (MAX_HEADER_BYTES as u64) + 20;
/// Largest header read (bytes of JSON): the header names a few settings, far
/// less than this; a longer one is refused before it is read.
pub const MAX_HEADER_BYTES: u32 = 1 << 16;
/// Largest embedded scene (bytes of canonical JSON): a sphere of any
/// scene takes well under 256 bytes, and a scene has at most
/// [`crate::limits::MAX_SPHERES`].
pub const MAX_SCENE_BYTES: u64 = crate::limits::MAX_SPHERES as u64 * 256 + (1 << 20);
/// The file extension of partial films.
pub const EXTENSION: &str = "rtfilm";

/// Whether `path` names a partial film (ends in `.rtfilm`).
pub fn is_part_path(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case(EXTENSION))
}

/// FNV-1a, 64 bits.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h = Fnv1a::default();
    h.add(bytes);
    h.0
}

/// FNV-1a, 64 bits, over bytes written to it (a value serialized into it is
/// hashed without being held in memory).
#[derive(Clone, Copy, Debug)]
pub struct Fnv1a(pub u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Fnv1a(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a {
    pub fn add(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

impl std::io::Write for Fnv1a {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        self.add(bytes);
        Ok(bytes.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// What makes two renders the same image: the scene and every setting that
/// changes the image (not the kernel, threads, tile size or accelerator,
/// which never change it). The samples per pixel are kept apart, because a
/// film of the first 256 samples is the start of a 1024-sample render.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Identity {
    /// A hash of the scene (its canonical JSON).
    pub scene_hash: u64,
    pub width: u32,
    pub height: u32,
    /// Every other setting that changes the image, by name (e.g. `seed`, `max_depth`).
    pub settings: BTreeMap<String, String>,
}

impl Identity {
    /// The hash of all of it, with the rtow version (a later version may render differently).
    pub fn key(&self) -> u64 {
        let mut text = format!(
            "rtow {}\nscene {:016x}\nwidth {}\nheight {}\n",
            env!("CARGO_PKG_VERSION"),
            self.scene_hash,
            self.width,
            self.height
        );
        for (k, v) in &self.settings {
            text.push_str(&format!("{k} {v}\n"));
        }
        fnv1a(text.as_bytes())
    }
}

/// Counters that every kernel keeps the same way.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartCounters {
    /// Closest-hit queries.
    pub rays: u64,
    /// Samples traced (accepted and rejected).
    pub samples: u64,
    /// Samples rejected (NaN, Inf or out of the fixed-point range).
    pub rejected_samples: u64,
    /// Of those, the finite ones out of the film's range.
    pub rejected_out_of_range: u64,
}

impl PartCounters {
    pub fn add(&mut self, o: &PartCounters) {
        self.rays += o.rays;
        self.samples += o.samples;
        self.rejected_samples += o.rejected_samples;
        self.rejected_out_of_range += o.rejected_out_of_range;
    }
}

/// The header of a partial film (JSON in the file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Header {
    /// The rtow version that wrote it.
    pub rtow: String,
    /// [`Identity::key`], hex.
    pub key: String,
    /// [`Identity::scene_hash`], hex.
    pub scene_hash: String,
    pub settings: BTreeMap<String, String>,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel of the finished image.
    pub spp: u32,
    pub split: Split,
    /// Sample indices covered: `[start, end)`.
    pub samples: [u32; 2],
    /// Rows covered: `[start, end)`.
    pub rows: [u32; 2],
    /// Fractional bits of the fixed-point sums at exponent 0.
    pub fraction_bits: i32,
    /// The film's scale exponent ([`accum::Scale`]): the sums have
    /// `fraction_bits - film_exponent` fractional bits.
    pub film_exponent: u32,
    /// Bytes per stored channel sum.
    pub sum_bytes: u32,
    /// Whether the per-pixel sums of squares follow the sums.
    pub moments: bool,
    /// Length of the embedded scene (its canonical JSON).
    pub scene_bytes: u64,
    pub counters: PartCounters,
}

/// A partial film: its header and its accumulators.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    pub header: Header,
    pub film: Film,
    /// The scene's canonical JSON, whose hash is the header's `scene_hash`.
    pub scene: Vec<u8>,
}

fn hex(v: u64) -> String {
    format!("{v:016x}")
}

/// The fewest bytes that hold every sum as a two's complement integer.
fn sum_bytes(film: &Film) -> u32 {
    let mut bits_needed = 1;
    for s in film.sum.iter().flatten() {
        // Significant bits plus the sign bit.
        let b = 129 - if *s < 0 { s.leading_ones() } else { s.leading_zeros() };
        bits_needed = bits_needed.max(b);
    }
    bits_needed.div_ceil(8).clamp(1, 16)
}

const PREFIX: usize = 16;
const TRAILER: usize = 4;

impl Part {
    /// A part of the image `id` with `spp` samples per pixel: `film` holds the
    /// rows and `split` says which samples; `scene` is the scene's canonical
    /// JSON (the bytes hashed into `id.scene_hash`).
    pub fn new(id: &Identity, scene: Vec<u8>, spp: u32, split: Split, film: Film, counters: PartCounters) -> Part {
        let samples = split.samples(spp);
        let header = Header {
            rtow: env!("CARGO_PKG_VERSION").into(),
            key: hex(id.key()),
            scene_hash: hex(id.scene_hash),
            settings: id.settings.clone(),
            width: id.width,
            height: id.height,
            spp,
            split,
            samples: [samples.start, samples.end],
            rows: [film.rows.start, film.rows.end],
            fraction_bits: accum::FRACTION_BITS,
            film_exponent: film.scale.exponent(),
            sum_bytes: sum_bytes(&film),
            moments: film.has_moments(),
            scene_bytes: scene.len() as u64,
            counters,
        };
        Part { header, film, scene }
    }

    fn pixel_bytes(h: &Header) -> u64 {
        4 + 3 * h.sum_bytes as u64 + if h.moments { 24 } else { 0 }
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut h = self.header.clone();
        h.sum_bytes = sum_bytes(&self.film);
        h.moments = self.film.has_moments();
        h.scene_bytes = self.scene.len() as u64;
        let json = serde_json::to_vec(&h).expect("a header serializes");
        let px = self.film.count.len();
        let mut out =
            Vec::with_capacity(PREFIX + json.len() + self.scene.len() + px * Self::pixel_bytes(&h) as usize + TRAILER);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(&json);
        out.extend_from_slice(&self.scene);
        let nb = h.sum_bytes as usize;
        for i in 0..px {
            out.extend_from_slice(&self.film.count[i].to_le_bytes());
            for s in self.film.sum[i] {
                out.extend_from_slice(&s.to_le_bytes()[..nb]);
            }
            if h.moments {
                for v in self.film.sum_sq[i] {
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
        let crc = crc32fast::hash(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        out
    }

    /// Writes the part atomically (a temporary file renamed into place).
    pub fn write(&self, path: &Path) -> Result<()> {
        crate::output::write_atomic(path, &self.to_bytes())
    }

    /// Reads and checks a partial film; every error names `path` (exit
    /// status 2). The header is read and checked first (every field within
    /// the documented limits, the file's length the one it implies), then the
    /// accumulators are allocated and the data read in bounded pieces.
    pub fn read(path: &Path) -> Result<Part> {
        Part::read_from(Part::open(path)?)
    }

    /// Opens a partial film and reads its preamble and header (at most
    /// `16 + MAX_HEADER_BYTES` bytes), checked; the data is not read yet.
    pub fn open(path: &Path) -> Result<PartReader<std::io::BufReader<std::fs::File>>> {
        let cannot = |e: &dyn std::fmt::Display| Error::Input(format!("cannot read {}: {e}", path.display()));
        let file = std::fs::File::open(path).map_err(|e| cannot(&e))?;
        let meta = file.metadata().map_err(|e| cannot(&e))?;
        if meta.is_dir() {
            return Err(cannot(&"is a directory"));
        }
        if meta.is_file() && meta.len() > MAX_FILM_BYTES {
            return Err(Error::Input(format!(
                "partial film {} is too large: {} bytes, at most {MAX_FILM_BYTES}",
                path.display(),
                meta.len()
            )));
        }
        let len = meta.is_file().then_some(meta.len());
        PartReader::new(std::io::BufReader::with_capacity(1 << 16, file), len, path).map_err(|(_, e)| e)
    }

    /// The part an opened reader holds, read whole.
    fn read_from<R: Read>(r: PartReader<R>) -> Result<Part> {
        let h = r.header().clone();
        let mut film = Film::new(h.width, h.height, h.rows[0]..h.rows[1], h.moments).scaled(Part::scale(&h));
        let (header, scene) = r.read_pixels(|i, p| film.set_pixel(i, p))?;
        Ok(Part { header, film, scene })
    }

    /// Parses and checks the bytes of a partial film read from `path`.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Part> {
        match PartReader::new(bytes, Some(bytes.len() as u64), path) {
            Ok(r) => Part::read_from(r),
            // The bytes are at hand: a header that is wrong because the file
            // is corrupted is reported as corrupted.
            Err((Stage::Header, e)) => Err(match checksum_mismatch(bytes) {
                Some(m) => Error::Input(format!("{}: {m}", path.display())),
                None => e,
            }),
            Err((_, e)) => Err(e),
        }
    }
}

/// `Some(message)` when `bytes` (a whole film) do not end with the checksum
/// of what precedes it.
fn checksum_mismatch(bytes: &[u8]) -> Option<String> {
    let body_end = bytes.len().checked_sub(TRAILER)?;
    let stored = u32::from_le_bytes(bytes[body_end..].try_into().expect("4 bytes"));
    let actual = crc32fast::hash(&bytes[..body_end]);
    (stored != actual).then(|| format!("corrupted: checksum {actual:08x} does not match the stored {stored:08x}"))
}

/// Whether the file at `path` ends with the checksum of what precedes it,
/// read in bounded pieces (`None`: it cannot be read, or is too short).
pub fn checksum_ok(path: &Path) -> Option<bool> {
    let mut file = std::io::BufReader::with_capacity(1 << 16, std::fs::File::open(path).ok()?);
    let mut crc = crc32fast::Hasher::new();
    let mut last = Vec::with_capacity(TRAILER);
    let mut buf = vec![0u8; 1 << 16];
    let mut total = 0u64;
    loop {
        let n = file.read(&mut buf).ok()?;
        if n == 0 {
            break;
        }
        total += n as u64;
        if total > MAX_FILM_BYTES {
            return None;
        }
        // Everything but the last 4 bytes seen so far goes into the checksum.
        last.extend_from_slice(&buf[..n]);
        if last.len() > TRAILER {
            let k = last.len() - TRAILER;
            crc.update(&last[..k]);
            last.drain(..k);
        }
    }
    let stored = u32::from_le_bytes(last.as_slice().try_into().ok()?);
    Some(stored == crc.finalize())
}

/// A header's text value for a message: at most 40 characters, control
/// characters shown as `?` (a message is one bounded line).
pub fn quoted(v: &str) -> String {
    quoted_to(v, 40)
}

/// [`quoted`], at most `n` characters.
pub fn quoted_to(v: &str, n: usize) -> String {
    crate::output::clip_to(v, n).chars().map(|ch| if ch.is_control() { '?' } else { ch }).collect()
}

/// Refuses (naming `p`, ending the message with `consequence`) a part whose
/// image is not `h0`'s (from `p0`): another scene, size, rtow version or
/// setting. The sample count is not compared.
pub fn same_image(p: &Path, h: &Header, p0: &Path, h0: &Header, consequence: &str) -> Result<()> {
    let a = p0.display();
    let c = quoted;
    let refuse = |what: String| Error::Input(format!("{}: {what}; {consequence}", p.display()));
    if h.rtow != h0.rtow {
        return Err(refuse(format!("written by rtow {}, {a} by rtow {}", c(&h.rtow), c(&h0.rtow))));
    }
    if h.scene_hash != h0.scene_hash {
        return Err(refuse(format!(
            "renders a different scene than {a} (scene hash {} against {})",
            c(&h.scene_hash),
            c(&h0.scene_hash)
        )));
    }
    if (h.width, h.height) != (h0.width, h0.height) {
        return Err(refuse(format!("is {}x{}, {a} is {}x{}", h.width, h.height, h0.width, h0.height)));
    }
    if h.film_exponent != h0.film_exponent {
        let range = |e: u32| accum::Scale::new(e).map_or(f64::INFINITY, |s| s.limit());
        return Err(refuse(format!(
            "its film has scale exponent {} (samples below {:.3e}), {a}'s has {} (below {:.3e}): their sums are \
             in different fixed points",
            h.film_exponent,
            range(h.film_exponent),
            h0.film_exponent,
            range(h0.film_exponent)
        )));
    }
    for name in h.settings.keys().chain(h0.settings.keys()) {
        let (v, v0) = (h.settings.get(name), h0.settings.get(name));
        if v != v0 && INPUT_FILES.iter().any(|&(setting, _)| setting == name) {
            return Err(refuse(files_changed(name, v0, v, &format!("of {a}"), "it was rendered with")));
        }
        if v != v0 {
            let show = |v: Option<&String>| v.map_or_else(|| "(unset)".into(), |v| c(v));
            return Err(refuse(format!(
                "rendered with {} = {}, {a} with {} = {}",
                c(name),
                show(v),
                c(name),
                show(v0)
            )));
        }
    }
    if h.key != h0.key {
        return Err(refuse(format!("its image key {} differs from {a}'s {}", c(&h.key), c(&h0.key))));
    }
    Ok(())
}

/// The identity's settings that hash input files' bytes (`job::Job::identity`),
/// with what their files are called.
pub const INPUT_FILES: [(&str, &str); 2] = [("images", "image texture"), ("meshes", "OBJ file")];

/// The entries of an identity's `images` or `meshes` setting (`"<hash>
/// <name>, <hash> <name>"`, `job::Job::identity`), as (hash, name): split
/// where `, ` is followed by a hash and a space, so a name may hold `, `.
fn file_entries(v: &str) -> Vec<(&str, &str)> {
    let starts_entry = |i: usize| {
        v.as_bytes().get(i..i + 17).is_some_and(|b| b[..16].iter().all(u8::is_ascii_hexdigit) && b[16] == b' ')
    };
    let mut cuts = vec![0];
    cuts.extend((1..v.len()).filter(|&i| v.as_bytes()[i..].starts_with(b", ") && starts_entry(i + 2)).map(|i| i + 2));
    cuts.push(v.len() + 2);
    cuts.windows(2)
        .map(|w| {
            let e = &v[w[0]..w[1] - 2];
            match e.split_once(' ') {
                Some((hash, name)) => (hash, name),
                None => ("", e),
            }
        })
        .collect()
}

/// Which input files differ between two values of the identity setting
/// `setting` (`images` or `meshes`, [`INPUT_FILES`]), named with the hashes
/// of their bytes, for a refusal: `now` is the setting of what `now_is`
/// ("read now"), `then` of what `then_is` ("it was rendered with").
pub fn files_changed(
    setting: &str,
    now: Option<&String>,
    then: Option<&String>,
    now_is: &str,
    then_is: &str,
) -> String {
    let noun = INPUT_FILES.iter().find(|&&(s, _)| s == setting).map_or("input file", |&(_, noun)| noun);
    let (now, then) = (now.map_or(vec![], |v| file_entries(v)), then.map_or(vec![], |v| file_entries(v)));
    let mut changed = Vec::new();
    for &(hash, name) in &now {
        if let Some(&(h0, _)) = then.iter().find(|&&(h0, n)| n == name && h0 != hash) {
            changed.push(format!(
                "the {noun} '{}' {now_is} is not the one {then_is} (its bytes hash to {}, not {})",
                quoted(name),
                quoted(hash),
                quoted(h0)
            ));
        }
    }
    if changed.is_empty() {
        let names =
            |v: &[(&str, &str)]| v.iter().map(|(_, n)| format!("'{}'", quoted(n))).collect::<Vec<_>>().join(", ");
        changed.push(format!("the {noun}s {now_is} ({}) are not the ones {then_is} ({})", names(&now), names(&then)));
    }
    changed.join("; ")
}

/// Checks that parts (their headers, with the paths they were read from)
/// are every shard of one render, once: refuses, naming the files, parts of
/// different scenes or settings, parts of different splits, duplicate shards
/// and missing shards (naming which). A refusal that one part causes comes
/// with that part's index (the first in the order given).
pub fn check_set(parts: &[(&Path, &Header)]) -> std::result::Result<(), (Option<usize>, Error)> {
    let Some(&(p0, h0)) = parts.first() else {
        return Err((None, Error::Input("merge needs at least one partial film".into())));
    };
    for (i, &(p, h)) in parts.iter().enumerate().skip(1) {
        let blame = |e: Error| (Some(i), e);
        same_image(p, h, p0, h0, "parts of different renders cannot be merged").map_err(blame)?;
        if h.spp != h0.spp {
            return Err(blame(Error::Input(format!(
                "{}: has {} samples per pixel, {} has {}; parts of different renders cannot be merged",
                p.display(),
                h.spp,
                p0.display(),
                h0.spp
            ))));
        }
        let (a, b) = (p0.display(), p.display());
        if (h.split.kind, h.split.of) != (h0.split.kind, h0.split.of) {
            return Err(blame(Error::Input(format!(
                "{b} is {} but {a} is {}: parts of different splits overlap or leave gaps",
                h.split.describe(),
                h0.split.describe()
            ))));
        }
    }
    let n = h0.split.of;
    let mut seen: std::collections::BTreeMap<u32, &Path> = std::collections::BTreeMap::new();
    for (i, &(p, h)) in parts.iter().enumerate() {
        let k = h.split.shard;
        if let Some(prev) = seen.insert(k, p) {
            return Err((
                Some(i),
                Error::Input(format!(
                    "{}: duplicate: {} and {} are both {}",
                    p.display(),
                    prev.display(),
                    p.display(),
                    h.split.describe()
                )),
            ));
        }
    }
    if seen.len() as u64 != n as u64 {
        // Name the missing shards (the first 20 of them).
        let missing: Vec<String> = (1..=n).filter(|k| !seen.contains_key(k)).take(20).map(|k| k.to_string()).collect();
        let count = n as usize - seen.len();
        let more = if count > missing.len() { format!(" and {} more", count - missing.len()) } else { String::new() };
        let kind = if h0.split.kind == SplitKind::Rows { "rows" } else { "samples" };
        // The list of parts is bounded too (a merge may be given thousands).
        let mut names: Vec<String> = parts.iter().take(20).map(|(p, _)| p.display().to_string()).collect();
        if parts.len() > names.len() {
            names.push(format!("and {} more", parts.len() - names.len()));
        }
        return Err((
            None,
            Error::Input(format!(
                "missing {} {}{more} of {n} (split by {kind}); merged parts: {}",
                if count == 1 { "shard" } else { "shards" },
                missing.join(", "),
                names.join(", ")
            )),
        ));
    }
    Ok(())
}

/// The header of the whole render that parts with headers `headers` (checked
/// by [`check_set`]) merge into, with the accumulators `film`.
pub fn merged_header(headers: &[&Header], film: &Film) -> Header {
    let mut counters = PartCounters::default();
    for h in headers {
        counters.add(&h.counters);
    }
    let h0 = headers[0];
    let mut header = h0.clone();
    header.split = Split::WHOLE;
    header.samples = [0, h0.spp];
    header.rows = [0, h0.height];
    header.counters = counters;
    header.moments = film.has_moments();
    header.sum_bytes = sum_bytes(film);
    header
}

/// Merges parts held in memory (with the paths they were read from, for
/// messages) into the whole render's film, after [`check_set`]. The result
/// has a header that describes it as a whole render (counters summed over
/// the parts). `rtow merge` streams instead (`shard::merge_files`): it holds
/// one part at a time.
pub fn merge(parts: &[(PathBuf, Part)]) -> Result<Part> {
    let headers: Vec<(&Path, &Header)> = parts.iter().map(|(p, part)| (p.as_path(), &part.header)).collect();
    check_set(&headers).map_err(|(_, e)| e)?;
    let h0 = &parts[0].1.header;
    let mut film = Film::new(h0.width, h0.height, 0..h0.height, parts.iter().all(|(_, p)| p.film.has_moments()))
        .scaled(parts[0].1.film.scale);
    for (p, part) in parts {
        film.absorb(&part.film).ok_or_else(|| {
            Error::Input(format!("{}: overlaps the other parts (a pixel's count overflows)", p.display()))
        })?;
    }
    let header = merged_header(&headers.iter().map(|(_, h)| *h).collect::<Vec<_>>(), &film);
    Ok(Part { header, film, scene: parts[0].1.scene.clone() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{ScalarStream, Stream};
    use std::ops::Range;

    const W: u32 = 6;
    const H: u32 = 5;
    const SPP: u32 = 11;
    /// A stand-in for a scene's canonical JSON.
    const SCENE: &[u8] = br#"{"spheres":[]}"#;

    fn identity(seed: u64) -> Identity {
        let settings = [("seed", seed.to_string()), ("max_depth", "50".to_string())];
        Identity {
            scene_hash: fnv1a(SCENE),
            width: W,
            height: H,
            settings: settings.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
        }
    }

    /// A stand-in for a render: pseudo-random samples, some negative, some
    /// rejected, some dark enough to round.
    fn sample(x: u32, y: u32, s: u32) -> [f32; 3] {
        let mut r = ScalarStream::for_path(5, (y * W + x) as u64, s as u64);
        let u = [r.next(), r.next(), r.next()];
        if u[0] < 0.03 {
            return [f32::NAN, 0.0, 0.0];
        }
        if u[0] > 0.98 {
            return [0.0, 1e20, 0.0];
        }
        [u[0] * 4.0 - 3.0, u[1] * u[1] * 1e-6, u[2] * 1e3]
    }

    fn render(split: Split, moments: bool) -> Part {
        let (rows, samples) = (split.rows(H), split.samples(SPP));
        let mut film = Film::new(W, H, rows.clone(), moments);
        let mut counters = PartCounters::default();
        for y in rows {
            let mut t = film.tile(0, y, W, 1);
            for x in 0..W {
                for s in samples.clone() {
                    t.add(x as usize, sample(x, y, s));
                    counters.samples += 1;
                    counters.rays += 3;
                }
            }
            counters.rejected_samples += t.rejected;
            counters.rejected_out_of_range += t.rejected_out_of_range;
            film.put_tile(&t);
        }
        Part::new(&identity(0), SCENE.to_vec(), SPP, split, film, counters)
    }

    fn shards(kind: SplitKind, n: u32) -> Vec<(PathBuf, Part)> {
        (1..=n)
            .map(|k| (PathBuf::from(format!("part-{k}.rtfilm")), render(Split { kind, shard: k, of: n }, false)))
            .collect()
    }

    /// The message of a refusal; checks it is bad input (exit 2) naming `file`.
    fn refusal(r: Result<Part>, file: &str) -> String {
        let e = r.expect_err("must be refused");
        assert_eq!(e.exit_code(), 2, "{e}");
        let m = e.to_string();
        assert!(m.contains(file), "{m:?} does not name {file}");
        m
    }

    fn reread(p: &Part, name: &str) -> Result<Part> {
        Part::from_bytes(&p.to_bytes(), Path::new(name))
    }

    #[test]
    fn parts_round_trip_with_the_fewest_bytes() {
        for moments in [false, true] {
            let p = render(Split::WHOLE, moments);
            assert!(p.film.sum.iter().flatten().any(|&s| s < 0), "negative sums are exercised");
            assert_eq!(reread(&p, "a.rtfilm").unwrap(), p);
            let c = p.header.counters;
            assert!(c.rejected_samples > c.rejected_out_of_range && c.rejected_out_of_range > 0, "{c:?}");
        }
        let p = render(Split::WHOLE, false);
        // Sums of 11 samples below 1e3 need 32 + 4 + 10 + 1 bits: 6 bytes.
        assert_eq!(p.header.sum_bytes, 6);
        let mut zero = p.clone();
        zero.film = Film::new(W, H, 0..H, false);
        // (Every sample rejected.)
        zero.header.counters = PartCounters { rays: 0, samples: 330, rejected_samples: 330, rejected_out_of_range: 0 };
        assert_eq!(reread(&zero, "z.rtfilm").unwrap().header.sum_bytes, 1);
    }

    #[test]
    fn any_split_merges_into_the_whole_render() {
        let whole = render(Split::WHOLE, false);
        for kind in [SplitKind::Samples, SplitKind::Rows] {
            let n_max = if kind == SplitKind::Rows { H } else { SPP };
            for n in [1, 2, 3, n_max] {
                let mut parts = shards(kind, n);
                parts.reverse();
                let merged = merge(&parts).unwrap();
                assert_eq!(merged.film, whole.film, "{kind:?} {n}");
                assert_eq!(merged.header.counters, whole.header.counters);
                assert_eq!(merged.film.image().hash(), whole.film.image().hash());
                // Through files as well.
                let read: Vec<_> = parts.iter().map(|(p, part)| (p.clone(), reread(part, "x").unwrap())).collect();
                assert_eq!(merge(&read).unwrap().film, whole.film);
            }
        }
    }

    /// Samples `samples` of every pixel added to `film`, tile by tile (one row each).
    fn continue_film(film: &mut Film, samples: Range<u32>) -> PartCounters {
        let mut c = PartCounters::default();
        for y in film.rows.clone() {
            let mut t = film.tile(0, y, W, 1);
            for x in 0..W {
                for s in samples.clone() {
                    t.add(x as usize, sample(x, y, s));
                    c.samples += 1;
                }
            }
            c.rejected_samples += t.rejected;
            c.rejected_out_of_range += t.rejected_out_of_range;
            film.put_tile(&t);
        }
        c
    }

    /// A film scaled for a bright scene (exponent 53: samples up to 8.3e34)
    /// keeps its exponent through the file, merges exactly with parts of its
    /// exponent, and reads back its samples' mean.
    #[test]
    fn scaled_parts_round_trip_and_merge() {
        let scale = accum::Scale::new(53).unwrap();
        // (The stand-in's out-of-range samples, 1e20, stay out of range: 1e35.)
        let bright = |x: u32, y: u32, s: u32| sample(x, y, s).map(|v| if v == 1e20 { 1e35 } else { v * 1e30 });
        let part = |split: Split| {
            let (rows, samples) = (split.rows(H), split.samples(SPP));
            let mut film = Film::new(W, H, rows.clone(), false).scaled(scale);
            let mut counters = PartCounters::default();
            for y in rows {
                let mut t = film.tile(0, y, W, 1);
                for x in 0..W {
                    for s in samples.clone() {
                        t.add(x as usize, bright(x, y, s));
                        counters.samples += 1;
                    }
                }
                counters.rejected_samples += t.rejected;
                counters.rejected_out_of_range += t.rejected_out_of_range;
                film.put_tile(&t);
            }
            Part::new(&identity(0), SCENE.to_vec(), SPP, split, film, counters)
        };
        let whole = part(Split::WHOLE);
        assert_eq!(whole.header.film_exponent, 53);
        // 1e35 is out of even this range; NaN is not finite.
        let c = whole.header.counters;
        assert!(c.rejected_samples > c.rejected_out_of_range && c.rejected_out_of_range > 0, "{c:?}");
        let back = reread(&whole, "bright.rtfilm").unwrap();
        assert_eq!(back, whole);
        assert_eq!(back.film.scale, scale);
        let parts: Vec<_> = (1..=3)
            .map(|k| (PathBuf::from(format!("b{k}.rtfilm")), part(Split { kind: SplitKind::Rows, shard: k, of: 3 })))
            .collect();
        let merged = merge(&parts).unwrap();
        assert_eq!(merged.film, whole.film);
        assert_eq!(merged.header.film_exponent, 53);
        // The mean of a pixel is its accepted samples' mean (to the step, 2^21).
        let img = whole.film.image();
        let i = (0..(W * H) as usize).find(|&i| whole.film.count[i] > 0).unwrap();
        let (x, y) = (i as u32 % W, i as u32 / W);
        let accepted: Vec<[f32; 3]> =
            (0..SPP).map(|s| bright(x, y, s)).filter(|c| scale.to_fixed(*c).is_ok()).collect();
        let want = (accepted.iter().map(|c| c[2] as f64).sum::<f64>() / accepted.len() as f64) as f32;
        assert!((img.get(x, y)[2] / want - 1.0).abs() < 1e-6, "{:?} against {want}", img.get(x, y));
        // Parts of exponent 0 do not merge with them.
        let mut mixed = parts.clone();
        mixed[1].1 = render(Split { kind: SplitKind::Rows, shard: 2, of: 3 }, false);
        let m = refusal(merge(&mixed), "b2.rtfilm");
        assert!(m.contains("scale exponent 0") && m.contains("b1.rtfilm's has 53"), "{m}");
    }

    #[test]
    fn resume_continues_exactly() {
        let whole = render(Split::WHOLE, true);
        let mut film = Film::new(W, H, 0..H, true);
        let counters = continue_film(&mut film, 0..4);
        let done = Part::new(&identity(0), SCENE.to_vec(), 4, Split::WHOLE, film, counters);
        let mut resumed = reread(&done, "done-4.rtfilm").unwrap();
        continue_film(&mut resumed.film, 4..SPP);
        // Sums, counts, and the sums of squares (added in sample order) too.
        assert_eq!(resumed.film, whole.film);
    }

    #[test]
    fn parts_of_different_renders_are_refused() {
        let base = shards(SplitKind::Samples, 2);
        let with = |f: &dyn Fn(&mut Header)| {
            let mut v = base.clone();
            f(&mut v[1].1.header);
            v
        };
        let m = refusal(merge(&with(&|h| h.scene_hash = "00000000000000ff".into())), "part-2.rtfilm");
        assert!(m.contains("different scene"), "{m}");
        let m = refusal(
            merge(&with(&|h| {
                h.settings.insert("seed".into(), "7".into());
            })),
            "part-2.rtfilm",
        );
        assert!(m.contains("seed = 7") && m.contains("seed = 0"), "{m}");
        let m = refusal(
            merge(&with(&|h| {
                h.settings.insert("roulette".into(), "6".into());
            })),
            "part-2.rtfilm",
        );
        assert!(m.contains("roulette = 6") && m.contains("(unset)"), "{m}");
        let m = refusal(merge(&with(&|h| h.width = 7)), "part-2.rtfilm");
        assert!(m.contains("7x5"), "{m}");
        let m = refusal(merge(&with(&|h| h.spp = 12)), "part-2.rtfilm");
        assert!(m.contains("12 samples per pixel"), "{m}");
        let m = refusal(merge(&with(&|h| h.rtow = "9.9.9".into())), "part-2.rtfilm");
        assert!(m.contains("9.9.9"), "{m}");
        let m = refusal(merge(&with(&|h| h.key = "0".into())), "part-2.rtfilm");
        assert!(m.contains("image key"), "{m}");
        // Another fixed-point scale: sums that cannot be added.
        let m = refusal(merge(&with(&|h| h.film_exponent = 53)), "part-2.rtfilm");
        assert!(m.contains("scale exponent 53") && m.contains("part-1.rtfilm's has 0"), "{m}");
        // Settings really change the key.
        assert_ne!(identity(0).key(), identity(1).key());
    }

    #[test]
    fn overlapping_duplicate_and_missing_parts_are_refused() {
        let four = shards(SplitKind::Samples, 4);
        let rows = shards(SplitKind::Rows, 4);
        // A part of another split overlaps.
        let mut mixed = four.clone();
        mixed[2] = (PathBuf::from("rows-3.rtfilm"), rows[2].1.clone());
        let m = refusal(merge(&mixed), "rows-3.rtfilm");
        assert!(m.contains("by rows") && m.contains("by samples"), "{m}");
        let mut other_n = four.clone();
        other_n.push((PathBuf::from("of3.rtfilm"), shards(SplitKind::Samples, 3).remove(0).1));
        refusal(merge(&other_n), "of3.rtfilm");
        // Duplicates: the same file twice, or a copy.
        let mut dup = four.clone();
        dup.push((PathBuf::from("copy-of-2.rtfilm"), four[1].1.clone()));
        let m = refusal(merge(&dup), "copy-of-2.rtfilm");
        assert!(m.contains("part-2.rtfilm") && m.contains("duplicate"), "{m}");
        // Missing shards are named.
        let some = vec![four[0].clone(), four[2].clone()];
        let m = merge(&some).unwrap_err().to_string();
        assert!(m.contains("missing shards 2, 4 of 4"), "{m}");
        let m = merge(&four[..3]).unwrap_err().to_string();
        assert!(m.contains("missing shard 4 of 4"), "{m}");
        assert!(merge(&[]).is_err());
        // A part that claims a split into 4 billion shards is refused as
        // inconsistent (empty shards), never allocated for.
        let mut huge = four[0].1.clone();
        huge.header.split.of = u32::MAX;
        let m = refusal(reread(&huge, "huge.rtfilm"), "huge.rtfilm");
        assert!(m.contains("inconsistent header"), "{m}");
    }

    #[test]
    fn damaged_files_are_refused() {
        let p = render(Split { kind: SplitKind::Rows, shard: 2, of: 3 }, true);
        let bytes = p.to_bytes();
        let name = "damaged.rtfilm";
        let read = |b: &[u8]| Part::from_bytes(b, Path::new(name));
        assert_eq!(read(&bytes).unwrap(), p);
        // Truncated anywhere: in the preamble, the header, the data, the checksum.
        let hlen = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        for cut in [0, 5, 12, 16, 16 + hlen / 2, 16 + hlen, 16 + hlen + 7, bytes.len() / 2, bytes.len() - 1] {
            let m = refusal(read(&bytes[..cut]), name);
            assert!(m.contains("truncated") || (cut < 8 && m.contains("not an rtow")), "cut {cut}: {m}");
        }
        // Any flipped bit after the preamble.
        for at in [16, 16 + hlen / 2, 16 + hlen, 16 + hlen + 9, bytes.len() - 30, bytes.len() - 2] {
            let mut b = bytes.clone();
            b[at] ^= 0x10;
            let m = refusal(read(&b), name);
            assert!(m.contains("corrupted"), "byte {at}: {m}");
        }
        // Trailing bytes.
        let mut longer = bytes.clone();
        longer.extend_from_slice(b"xx");
        refusal(read(&longer), name);
        // Not a film at all.
        let m = refusal(read(b"\x89PNG\r\n\x1a\n........"), name);
        assert!(m.contains("not an rtow partial film"), "{m}");
        // A future version is refused as such, whatever follows.
        let mut future = bytes.clone();
        future[8..12].copy_from_slice(&(VERSION + 1).to_le_bytes());
        let m = refusal(read(&future[..20]), name);
        assert!(m.contains(&format!("format version {} is newer", VERSION + 1)), "{m}");
        // Older versions (no embedded scene; no scale, rejections not by cause) are refused as such.
        let mut old = bytes.clone();
        old[8..12].copy_from_slice(&1u32.to_le_bytes());
        assert!(refusal(read(&old), name).contains("format version 1 is older"));
        old[8..12].copy_from_slice(&2u32.to_le_bytes());
        let m = refusal(read(&old), name);
        assert!(m.contains("format version 2 is older than this rtow reads (3)") && m.contains("film scale"), "{m}");
        let mut zero = bytes.clone();
        zero[8..12].copy_from_slice(&0u32.to_le_bytes());
        refusal(read(&zero), name);
    }

    /// The image textures whose bytes changed are named; names may hold `, `.
    #[test]
    fn changed_images_are_named() {
        let then = "0123456789abcdef maps/earth, map.jpg, 00000000000000aa é.png".to_string();
        let now = "0123456789abcdef maps/earth, map.jpg, 00000000000000bb é.png".to_string();
        assert_eq!(
            file_entries(&then),
            vec![("0123456789abcdef", "maps/earth, map.jpg"), ("00000000000000aa", "é.png")]
        );
        let m = files_changed("images", Some(&now), Some(&then), "read now", "it was rendered with");
        assert_eq!(
            m,
            "the image texture 'é.png' read now is not the one it was rendered with (its bytes hash to \
             00000000000000bb, not 00000000000000aa)"
        );
        // Nothing to match by name: both lists, by name.
        let m = files_changed("images", Some(&now), None, "read now", "it was rendered with");
        assert!(m.contains("('maps/earth, map.jpg', 'é.png') are not the ones it was rendered with ()"), "{m}");
        for hostile in ["", ", ", "x, 0123456789abcdef", ", 0123456789abcdef é", "é, 0123456789abcdef "] {
            file_entries(hostile);
        }
    }

    /// Files whose checksum is right but whose content is not: written by a
    /// bug or by hand. They are refused, not trusted.
    #[test]
    fn inconsistent_files_are_refused() {
        let p = render(Split { kind: SplitKind::Samples, shard: 2, of: 3 }, false);
        let name = "odd.rtfilm";
        let edit = |f: &dyn Fn(&mut Part)| {
            let mut q = p.clone();
            f(&mut q);
            refusal(reread(&q, name), name)
        };
        assert!(edit(&|q| q.header.samples = [0, 4]).contains("inconsistent header"));
        assert!(edit(&|q| q.header.split.shard = 4).contains("does not exist"));
        assert!(edit(&|q| q.header.split.kind = SplitKind::None).contains("does not exist"));
        assert!(edit(&|q| q.header.fraction_bits = 24).contains("fractional bits"));
        let m = edit(&|q| q.header.film_exponent = accum::MAX_EXPONENT + 1);
        assert!(m.contains("film_exponent 82 is more than the largest, 81"), "{m}");
        let m = edit(&|q| q.header.counters.rejected_out_of_range = q.header.counters.rejected_samples + 1);
        assert!(m.contains("rejected as out of range, more than"), "{m}");
        assert!(edit(&|q| q.header.counters.samples += 1).contains("samples counted"));
        // Header values are quoted on one line (found by the fuzzer).
        let m = edit(&|q| q.header.scene_hash = "x\ny".into());
        assert!(m.contains("scene hash x?y") && m.lines().count() == 1, "{m}");
        // More pixels than any render has: refused before anything is allocated.
        let m = edit(&|q| (q.header.width, q.header.height) = (1 << 14, 1 << 13));
        assert!(m.contains("134217728 pixels, more than the 67108864"), "{m}");
        // A header longer than any film's.
        let mut b = p.to_bytes();
        b[12..16].copy_from_slice(&(MAX_HEADER_BYTES + 1).to_le_bytes());
        b.resize(b.len() + MAX_HEADER_BYTES as usize + 1, b' ');
        assert!(refusal(Part::from_bytes(&b, Path::new(name)), name).contains("corrupted"));
        // A pixel with more samples than the part renders.
        assert!(edit(&|q| q.film.count[3] = 5).contains("more than the part's"));
        // A sum too large for its samples (it could make an infinite mean).
        assert!(edit(&|q| q.film.sum[0][1] = i128::MAX >> 1).contains("out of range"));
        // Not JSON.
        let mut b = p.to_bytes();
        b[16] = b'#';
        let body = b.len() - 4;
        let crc = crc32fast::hash(&b[..body]);
        b[body..].copy_from_slice(&crc.to_le_bytes());
        assert!(refusal(Part::from_bytes(&b, Path::new(name)), name).contains("not valid JSON"));
    }

    #[test]
    fn shards_cover_everything_once() {
        for total in [1u32, 7, 64, 675] {
            for n in 1..=total.min(20) {
                let mut next = 0;
                for k in 1..=n {
                    let s = Split { kind: SplitKind::Samples, shard: k, of: n };
                    let r = s.samples(total);
                    assert_eq!(r.start, next);
                    assert!(!r.is_empty());
                    next = r.end;
                    assert_eq!(s.rows(total), 0..total);
                    assert_eq!(Split { kind: SplitKind::Rows, ..s }.rows(total), r);
                }
                assert_eq!(next, total);
            }
        }
        assert_eq!(Split::parse("3/8", SplitKind::Rows).unwrap(), Split { kind: SplitKind::Rows, shard: 3, of: 8 });
        for bad in ["0/4", "5/4", "1/0", "x/2", "3", "-1/2", ""] {
            let e = Split::parse(bad, SplitKind::Samples).unwrap_err().to_string();
            assert!(e.starts_with("shard:"), "{e}");
        }
        assert!(Split::parse("3/8", SplitKind::Samples).unwrap().check(7, 100).is_err());
        assert!(Split::parse("3/8", SplitKind::Rows).unwrap().check(7, 100).is_ok());
        assert!(Split::parse("3/8", SplitKind::Rows).unwrap().check(700, 5).is_err());
    }
}
