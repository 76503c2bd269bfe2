//! Path storage: the per-path arrays (structure of arrays) of the paths in
//! flight and of the bounce's shadow rays, and their compaction.

use super::*;

/// The length of every per-path array: a power of two with room past
/// `MAX_PATHS` for a packet of any width, so that
/// - the last packet can be loaded and stored whole (its extra lanes are
///   computed, never used), and compaction may write a packet past the kept
///   lanes;
/// - an index masked with `CAP - 1` is in bounds by construction: the gathers
///   by queued index, the loads and stores at a packet's start and the queue
///   and result writes need no bounds check ([`Wide::gather_pow2`]). Every
///   index is below `MAX_PATHS` where it is used, so the mask never changes one
///   (debug builds assert it where the index comes from memory).
pub(super) const CAP: usize = 4096;
pub(super) const MASK: usize = CAP - 1;
const _: () = assert!(CAP.is_power_of_two() && CAP >= MAX_PATHS + MAX_LANES);

/// A per-path array.
pub(super) type Arr<T> = Box<[T; CAP]>;

pub(super) fn arr<T: Copy + std::fmt::Debug>(x: T) -> Arr<T> {
    vec![x; CAP].into_boxed_slice().try_into().unwrap()
}

/// The miss queue's index (after one queue per material kind). Misses are
/// shaded by their own pass over contiguous paths (`shade_misses`): the
/// one-path-at-a-time classification of scenes with quads fills this queue
/// (branch-free) and nothing reads it.
pub(super) const MISS_QUEUE: usize = Kind::ALL.len();

/// The texture queues' count: one per texture kind with a pass (`TexKind as usize - 1`).
pub(super) const TEX_QUEUES: usize = TexKind::PASSES.len();

/// A packet's paths as they join the next bounce: their rays, throughput,
/// sampler words and slots, and (a scene with moving spheres) their times
/// and (under `nee-mis`) their directions' densities.
pub(super) struct NewPaths<W: Wide> {
    pub(super) o: V3<W>,
    pub(super) d: V3<W>,
    pub(super) thr: V3<W>,
    pub(super) rng: [W::U; 4],
    pub(super) slot: W::U,
    pub(super) time: Option<W>,
    pub(super) pdf: Option<W>,
}

/// Path state, structure of arrays.
pub(super) struct Paths {
    pub(super) o: [Arr<f32>; 3],
    pub(super) d: [Arr<f32>; 3],
    pub(super) thr: [Arr<f32>; 3],
    pub(super) rng: [Arr<u32>; 4],
    /// Index of the path's result: `sample_in_batch * active_pixels + active_index`.
    pub(super) slot: Arr<u32>,
    /// The path's time (motion blur): written and read only for a scene
    /// with moving spheres.
    pub(super) time: Arr<f32>,
    /// The density its last direction was drawn with (0: the camera's or a
    /// specular one): written and read only under `nee-mis`.
    pub(super) pdf: Arr<f32>,
    pub(super) len: usize,
}

impl Paths {
    pub(super) fn new() -> Self {
        let f = || arr(0.0f32);
        let u = || arr(0u32);
        Paths {
            o: [f(), f(), f()],
            d: [f(), f(), f()],
            thr: [f(), f(), f()],
            rng: [u(), u(), u(), u()],
            slot: u(),
            time: f(),
            pdf: f(),
            len: 0,
        }
    }

    /// Appends the lanes of `alive` (a bitmask) of a packet: SIMD stream
    /// compaction. `time`: the paths' times, for a scene with moving
    /// spheres; `pdf`: their directions' densities, under `nee-mis`.
    #[cfg_attr(not(feature = "phases"), inline(always))]
    #[cfg_attr(feature = "phases", inline(never))]
    pub(super) fn append<W: Wide, S: PathSampler>(&mut self, alive: u32, paths: NewPaths<W>) {
        let NewPaths { o, d, thr, rng, slot, time, pdf } = paths;
        let at = self.len;
        debug_assert!(at <= MAX_PATHS);
        let put = |v: &mut Arr<f32>, x: W| compress_f32(v, x, alive, at);
        for (a, (ov, dv, tv)) in [(o.x, d.x, thr.x), (o.y, d.y, thr.y), (o.z, d.z, thr.z)].into_iter().enumerate() {
            put(&mut self.o[a], ov);
            put(&mut self.d[a], dv);
            put(&mut self.thr[a], tv);
        }
        for (w, words) in rng.into_iter().enumerate().take(S::WORDS) {
            W::compress_store_u_pow2(words, alive, &mut self.rng[w], at);
        }
        if let Some(t) = time {
            put(&mut self.time, t);
        }
        if let Some(p) = pdf {
            put(&mut self.pdf, p);
        }
        self.len = at + W::compress_store_u_pow2(slot, alive, &mut self.slot, at);
    }

    #[inline(always)]
    pub(super) fn v3<W: Wide>(v: &[Arr<f32>; 3], i: usize) -> V3<W> {
        V3::new(W::load_pow2(&v[0], i), W::load_pow2(&v[1], i), W::load_pow2(&v[2], i))
    }

    /// The sampler streams of a packet's paths (their `S::WORDS` words each).
    #[inline(always)]
    pub(super) fn rng<W: Wide, S: PathSampler>(&self, sampler: S, at: impl Packet<W>) -> S::Lanes<W> {
        sampler.lanes::<W>(std::array::from_fn(|w| if w < S::WORDS { at.u(&self.rng[w]) } else { W::u_splat(0) }))
    }

    /// Stores the streams of the run of paths at `i` back.
    #[inline(always)]
    pub(super) fn store_rng<W: Wide, S: PathSampler>(&mut self, rng: &S::Lanes<W>, i: usize) {
        for (w, words) in S::lane_words::<W>(rng).into_iter().enumerate().take(S::WORDS) {
            W::store_u_pow2(words, &mut self.rng[w], i);
        }
    }
}

/// Stores the lanes of `keep` (a bitmask) of `x` at `v[at..]`, in lane
/// order (SIMD stream compaction of a per-path f32 array).
#[inline(always)]
pub(super) fn compress_f32<W: Wide>(v: &mut Arr<f32>, x: W, keep: u32, at: usize) -> usize {
    let v: &mut [u32; CAP] = bytemuck::cast_slice_mut(&mut v[..]).try_into().unwrap();
    W::compress_store_u_pow2(x.to_bits(), keep, v, at)
}

/// The shadow rays of a bounce (`nee-mis`), structure of arrays: at most
/// one per path, appended by the diffuse scatter passes, traced by the
/// shadow pass.
pub(super) struct Shadows {
    pub(super) o: [Arr<f32>; 3],
    pub(super) d: [Arr<f32>; 3],
    pub(super) tmax: Arr<f32>,
    /// What each carries to its path's result if nothing blocks it.
    pub(super) c: [Arr<f32>; 3],
    pub(super) slot: Arr<u32>,
    /// Scenes with moving spheres: the path's time.
    pub(super) time: Arr<f32>,
    pub(super) len: usize,
}

impl Shadows {
    pub(super) fn new() -> Self {
        let f = || arr(0.0f32);
        Shadows {
            o: [f(), f(), f()],
            d: [f(), f(), f()],
            tmax: f(),
            c: [f(), f(), f()],
            slot: arr(0),
            time: f(),
            len: 0,
        }
    }

    /// Appends the lanes of `keep` (a bitmask): SIMD stream compaction.
    #[inline(always)]
    pub(super) fn append<W: Wide>(&mut self, keep: u32, sh: &Shadow<W>, slot: W::U32, time: Option<W>) {
        let Shadow { o, d, tmax, c } = *sh;
        let at = self.len;
        debug_assert!(at + keep.count_ones() as usize <= MAX_PATHS);
        let put = |v: &mut Arr<f32>, x: W| compress_f32(v, x, keep, at);
        for (a, (ov, dv, cv)) in [(o.x, d.x, c.x), (o.y, d.y, c.y), (o.z, d.z, c.z)].into_iter().enumerate() {
            put(&mut self.o[a], ov);
            put(&mut self.d[a], dv);
            put(&mut self.c[a], cv);
        }
        put(&mut self.tmax, tmax);
        if let Some(t) = time {
            put(&mut self.time, t);
        }
        self.len = at + W::compress_store_u_pow2(slot, keep, &mut self.slot, at);
    }
}
