//! A thread's wavefront state, reused across tiles.

use super::*;

/// A thread's wavefront state, reused across tiles (no allocation per tile).
pub struct Workspace {
    pub(super) cur: Paths,
    pub(super) next: Paths,
    pub(super) hit: Arr<u32>,
    pub(super) t: Arr<f32>,
    /// Indices into `cur`, one queue per material kind (by `Kind as usize`) and one for
    /// misses (filled from the front each bounce).
    pub(super) queue: Option<[Arr<u32>; MISS_QUEUE + 1]>,
    /// Each path's colour, by its slot.
    pub(super) result: Arr<[f32; 3]>,
    /// The bounce's shadow rays (`nee-mis`), and how many the tile traced.
    pub(super) shadows: Shadows,
    pub(super) shadow_rays: u64,
    /// Scenes with textures: the albedo of each textured lambertian hit, by
    /// its index in `cur`, written by the texture passes, read by the
    /// lambertian pass; and the texture queues.
    pub(super) albedo: [Arr<f32>; 3],
    pub(super) tex_queue: Option<[Arr<u32>; TEX_QUEUES]>,
    /// The tile's pixels (row-major local indices) that still take samples.
    pub(super) active: Vec<u32>,
    /// Per active pixel, for the camera rays of a round: its coordinates and
    /// what its paths' sampler state words share ([`PathSampler::pixel_words`]).
    pub(super) pixel_xy: Vec<[f32; 2]>,
    pub(super) pixel_words: Vec<[u32; 4]>,
    /// Probes only: the image index of each active pixel, and the batch's first sample.
    pub(super) pixel: Vec<u32>,
    pub(super) batch_start: u32,
}

impl Default for Workspace {
    fn default() -> Self {
        Workspace {
            cur: Paths::new(),
            next: Paths::new(),
            hit: arr(0),
            t: arr(0.0),
            queue: Some(std::array::from_fn(|_| arr(0))),
            result: arr([0.0; 3]),
            shadows: Shadows::new(),
            shadow_rays: 0,
            albedo: [arr(0.0), arr(0.0), arr(0.0)],
            tex_queue: Some(std::array::from_fn(|_| arr(0))),
            active: Vec::with_capacity(MAX_PATHS),
            pixel_xy: Vec::with_capacity(MAX_PATHS),
            pixel_words: Vec::with_capacity(MAX_PATHS),
            pixel: Vec::with_capacity(MAX_PATHS),
            batch_start: 0,
        }
    }
}

impl Workspace {
    /// The path ids of the paths whose `cur` indices are `idx` (probes only).
    pub(super) fn ids<W: Wide>(&self, idx: &W::Idx) -> PathId<W> {
        let na = self.active.len() as u32;
        let slot = |k: usize| self.cur.slot[idx.as_ref()[k] as usize & MASK];
        PathId {
            pixel: W::u_from_fn(|k| self.pixel[(slot(k) % na) as usize]),
            sample: W::u_from_fn(|k| self.batch_start + slot(k) / na),
        }
    }
}
