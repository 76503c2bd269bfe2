//! Reading a partial film: the preamble and header checked first, then the
//! data in bounded pieces, pixel by pixel, its checksum verified at the end.

use super::*;

/// One pixel's accumulators as a partial film stores them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pixel {
    /// Accepted samples.
    pub count: u32,
    /// The fixed-point sums ([`accum`]).
    pub sum: [i128; 3],
    /// The sums of squares (zero when the film has none).
    pub sum_sq: [f64; 3],
}

/// Where a reader refused a file: before its header could be believed (not
/// a film, truncated, a future version), in the header, or in the data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    Preamble,
    Header,
    Data,
}

/// Bytes of the data read at once (whole pixels).
const CHUNK: usize = 1 << 16;

/// A partial film being read: its preamble and header read and checked
/// (every field within the documented limits, the file's length the one the
/// header implies), its data not read yet. [`PartReader::read_pixels`] reads
/// the data in bounded pieces and hands each pixel to a caller (who may add
/// it to an accumulator: `rtow merge` holds one image, whatever the number of
/// parts).
pub struct PartReader<R: Read> {
    path: PathBuf,
    header: Header,
    src: R,
    crc: crc32fast::Hasher,
}

impl<R: Read> PartReader<R> {
    /// Reads the preamble and the header of a film of `len` bytes (`None`:
    /// unknown, e.g. a pipe) from `src`: at most `16 + MAX_HEADER_BYTES`
    /// bytes. Every error names `path` and says at which stage it was found.
    pub fn new(mut src: R, len: Option<u64>, path: &Path) -> std::result::Result<Self, (Stage, Error)> {
        let bad = |stage: Stage, m: String| (stage, Error::Input(format!("{}: {m}", path.display())));
        let early = |m: String| bad(Stage::Preamble, m);
        let io = |e: std::io::Error| early(format!("cannot read: {e}"));
        let mut pre = [0u8; PREFIX];
        let n = read_up_to(&mut src, &mut pre).map_err(io)?;
        if n < 8 || &pre[..8] != MAGIC {
            return Err(early("not an rtow partial film (no RTOWFILM signature)".into()));
        }
        if n < PREFIX {
            return Err(early(format!("truncated: {n} bytes, shorter than the 16-byte preamble")));
        }
        let version = u32::from_le_bytes(pre[8..12].try_into().expect("4 bytes"));
        if version > VERSION {
            return Err(early(format!(
                "format version {version} is newer than this rtow reads ({VERSION}); use a newer rtow"
            )));
        }
        if version == 0 {
            return Err(early("corrupted: format version 0 does not exist".into()));
        }
        if version < VERSION {
            let why = if version == 1 {
                "it carries no scene, so its data cannot be verified"
            } else {
                "it records no film scale and does not count its rejected samples by cause"
            };
            return Err(early(format!(
                "format version {version} is older than this rtow reads ({VERSION}): {why}; merge or resume it \
                 with the rtow that wrote it, or render it again"
            )));
        }
        let hlen = u32::from_le_bytes(pre[12..16].try_into().expect("4 bytes"));
        let header_end = PREFIX as u64 + hlen as u64;
        if let Some(len) = len {
            if len <= header_end + TRAILER as u64 {
                return Err(early(format!(
                    "truncated: {len} bytes, but the header alone is {header_end} bytes long (with the checksum {})",
                    header_end + TRAILER as u64
                )));
            }
        }
        if hlen > MAX_HEADER_BYTES {
            return Err(bad(
                Stage::Header,
                format!("corrupted: a header of {hlen} bytes, more than the {MAX_HEADER_BYTES} any film has"),
            ));
        }
        let mut text = vec![0u8; hlen as usize];
        let got = read_up_to(&mut src, &mut text).map_err(io)?;
        if got < text.len() {
            return Err(early(format!("truncated: {} bytes, inside the header", PREFIX + got)));
        }
        let mut crc = crc32fast::Hasher::new();
        crc.update(&pre);
        crc.update(&text);
        let h: Header = serde_json::from_slice(&text)
            .map_err(|_| bad(Stage::Header, "corrupted: the header is not valid JSON".into()))?;
        Part::check_header(&h).map_err(|m| bad(Stage::Header, format!("inconsistent header: {m}")))?;
        let expected = header_end + h.scene_bytes + Part::pixel_count(&h) * Part::pixel_bytes(&h) + TRAILER as u64;
        if let Some(len) = len {
            if len < expected {
                return Err(early(format!("truncated: {len} bytes, the header says {expected}")));
            }
            if len > expected {
                return Err(bad(Stage::Header, format!("corrupted: {len} bytes, the header says {expected}")));
            }
        }
        Ok(PartReader { path: path.to_path_buf(), header: h, src, crc })
    }

    /// The header, checked.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// Reads the data in bounded pieces, giving every pixel (with its index
    /// in the film's rows, row-major) to `sink`, then the checksum; then
    /// checks that the data holds what the header claims. On a refusal,
    /// `sink` may have seen some of the pixels. Returns the header and the
    /// embedded scene (checked against the header's `scene_hash`).
    pub fn read_pixels(mut self, mut sink: impl FnMut(usize, &Pixel)) -> Result<(Header, Vec<u8>)> {
        let path = self.path.display().to_string();
        let bad = |m: String| Error::Input(format!("{path}: {m}"));
        let h = &self.header;
        let px = Part::pixel_count(h) as usize;
        let pb = Part::pixel_bytes(h) as usize;
        let per_chunk = (CHUNK / pb).max(1);
        let mut buf = vec![0u8; per_chunk.min(px.max(1)) * pb];
        let max_count = h.samples[1] - h.samples[0];
        let mut problem: Option<String> = None;
        let mut accepted = 0u64;
        let mut i = 0;
        let short = |e: std::io::Error| match e.kind() {
            std::io::ErrorKind::UnexpectedEof => bad("truncated while it was read (did the file change?)".into()),
            _ => bad(format!("cannot read: {e}")),
        };
        // The scene (its length checked against the limit with the header).
        let mut scene = vec![0u8; h.scene_bytes as usize];
        self.src.read_exact(&mut scene).map_err(short)?;
        self.crc.update(&scene);
        if hex(fnv1a(&scene)) != h.scene_hash {
            problem =
                Some(format!("corrupted: the embedded scene does not have the scene hash {}", quoted(&h.scene_hash)));
        }
        while i < px {
            let k = per_chunk.min(px - i);
            let b = &mut buf[..k * pb];
            self.src.read_exact(b).map_err(short)?;
            self.crc.update(b);
            // After a problem the rest is only checksummed, so that a
            // corrupted file is reported as such.
            if problem.is_none() {
                for (j, raw) in b.chunks_exact(pb).enumerate() {
                    match decode(h, raw, max_count) {
                        Ok(p) => {
                            accepted += p.count as u64;
                            sink(i + j, &p);
                        }
                        Err(m) => {
                            problem = Some(m);
                            break;
                        }
                    }
                }
            }
            i += k;
        }
        let mut tail = [0u8; TRAILER];
        self.src.read_exact(&mut tail).map_err(short)?;
        let stored = u32::from_le_bytes(tail);
        let actual = self.crc.clone().finalize();
        if read_up_to(&mut self.src, &mut [0u8; 1]).map_err(short)? != 0 {
            return Err(bad("corrupted: bytes after the checksum (did the file change while it was read?)".into()));
        }
        if stored != actual {
            return Err(bad(format!("corrupted: checksum {actual:08x} does not match the stored {stored:08x}")));
        }
        if let Some(m) = problem {
            return Err(bad(m));
        }
        let c = &h.counters;
        if accepted + c.rejected_samples != c.samples {
            return Err(bad(format!(
                "inconsistent header: {} samples counted, but the pixels hold {accepted} and {} were rejected",
                c.samples, c.rejected_samples
            )));
        }
        Ok((self.header, scene))
    }
}

/// Reads until `buf` is full or the input ends; the bytes read.
fn read_up_to(src: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match src.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

/// One pixel of the data of a film with header `h`: the sample count (at
/// most `max_count`), the three sums (in range for the count) and, with
/// moments, the three sums of squares (finite, not negative).
fn decode(h: &Header, raw: &[u8], max_count: u32) -> std::result::Result<Pixel, String> {
    let nb = h.sum_bytes as usize;
    let mut p = Pixel { count: u32::from_le_bytes(raw[..4].try_into().expect("4 bytes")), ..Pixel::default() };
    if p.count > max_count {
        return Err(format!("corrupted: a pixel has {} samples, more than the part's {max_count}", p.count));
    }
    let mut at = 4;
    for s in &mut p.sum {
        let mut b = if raw[at + nb - 1] & 0x80 != 0 { [0xff; 16] } else { [0; 16] };
        b[..nb].copy_from_slice(&raw[at..at + nb]);
        at += nb;
        *s = i128::from_le_bytes(b);
        // Each accepted sample is below 2^95 in fixed point.
        if s.unsigned_abs() > (p.count as u128) << 95 {
            return Err("corrupted: a pixel's sum is out of range for its samples".into());
        }
    }
    if h.moments {
        for v in &mut p.sum_sq {
            *v = f64::from_le_bytes(raw[at..at + 8].try_into().expect("8 bytes"));
            at += 8;
            if !(v.is_finite() && *v >= 0.0) {
                return Err("corrupted: a sum of squares is negative or not finite".into());
            }
        }
    }
    Ok(p)
}

impl Part {
    /// Pixels of the film's rows (checked headers only: at most `MAX_PIXELS`).
    fn pixel_count(h: &Header) -> u64 {
        h.width as u64 * (h.rows[1] as u64).saturating_sub(h.rows[0] as u64)
    }

    /// The fixed-point scale of a checked header's sums.
    pub fn scale(h: &Header) -> accum::Scale {
        accum::Scale::new(h.film_exponent).expect("a checked header's exponent")
    }

    fn check_header(h: &Header) -> std::result::Result<(), String> {
        if h.fraction_bits != accum::FRACTION_BITS {
            return Err(format!(
                "sums with {} fractional bits; this rtow uses {}",
                h.fraction_bits,
                accum::FRACTION_BITS
            ));
        }
        if h.film_exponent > accum::MAX_EXPONENT {
            return Err(format!(
                "film_exponent {} is more than the largest, {} (which holds every finite f32)",
                h.film_exponent,
                accum::MAX_EXPONENT
            ));
        }
        if h.counters.rejected_out_of_range > h.counters.rejected_samples {
            return Err(format!(
                "{} samples rejected as out of range, more than the {} rejected",
                h.counters.rejected_out_of_range, h.counters.rejected_samples
            ));
        }
        if h.scene_bytes > MAX_SCENE_BYTES {
            return Err(format!("a scene of {} bytes, more than the {MAX_SCENE_BYTES} any scene takes", h.scene_bytes));
        }
        if !(1..=16).contains(&h.sum_bytes) {
            return Err(format!("sum_bytes {} is not between 1 and 16", h.sum_bytes));
        }
        if h.width == 0 || h.height == 0 || h.spp == 0 {
            return Err("width, height and spp must be at least 1".into());
        }
        // The limits every render is held to (`Settings::validate`), before
        // anything is allocated for the pixels.
        let pixels = h.width as u64 * h.height as u64;
        if pixels > MAX_PIXELS {
            return Err(format!(
                "{}x{} is {pixels} pixels, more than the {MAX_PIXELS} any render has",
                h.width, h.height
            ));
        }
        if pixels * h.spp as u64 > u32::MAX as u64 * 1024 {
            return Err(format!("{} samples per pixel at {pixels} pixels is more than any render takes", h.spp));
        }
        let s = h.split;
        let whole = s.kind == SplitKind::None;
        if s.of == 0 || s.shard == 0 || s.shard > s.of || (whole && s.of != 1) {
            return Err(format!("shard {}/{} does not exist", s.shard, s.of));
        }
        s.check(h.spp, h.height).map_err(|e| e.to_string())?;
        let samples = s.samples(h.spp);
        let rows = s.rows(h.height);
        if h.samples != [samples.start, samples.end] || h.rows != [rows.start, rows.end] {
            return Err(format!(
                "{} of {} spp and {} rows covers samples {samples:?} and rows {rows:?}, not {:?} and {:?}",
                s.describe(),
                h.spp,
                h.height,
                h.samples,
                h.rows
            ));
        }
        // What the data must hold: every pixel of the rows traced every
        // sample of the range (fewer with adaptive sampling, the films with
        // moments). Rejected samples are counted apart (see `read_pixels`).
        let c = &h.counters;
        let traced = Self::pixel_count(h) * samples.len() as u64;
        if c.samples > traced || (!h.moments && c.samples != traced) {
            return Err(format!(
                "{} samples counted, but {} pixels over samples {samples:?} trace {traced}",
                c.samples,
                Self::pixel_count(h)
            ));
        }
        Ok(())
    }
}
