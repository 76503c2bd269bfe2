//! Packets: `W` paths read at once, either gathered from a queue ([`Queued`])
//! or contiguous ([`Run`]), and the loop over a queue's packets.

use super::*;

/// Where a packet's W paths are in `cur`, and which of its lanes are real
/// (`live`, a bitmask): W queued indices, read by gathers ([`Queued`]), or W
/// contiguous indices, read by whole-vector loads ([`Run`]). The scatter
/// passes are written once over both.
pub(super) trait Packet<W: Wide>: Copy {
    /// The packet's lanes of a per-path array.
    fn f(self, v: &Arr<f32>) -> W;
    fn u(self, v: &Arr<u32>) -> W::U32;
    fn v3(self, v: &[Arr<f32>; 3]) -> V3<W> {
        V3::new(self.f(&v[0]), self.f(&v[1]), self.f(&v[2]))
    }
    /// The paths' indices (probes, and the passes that write lane by lane).
    fn idx(self) -> W::Idx;
    /// The real lanes.
    fn live(self) -> u32;
}

/// W queued indices, masked below `CAP` (the last packet of a queue padded
/// with a real path's index), and the real lanes.
pub(super) struct Queued<W: Wide> {
    pub(super) idx: W::Idx,
    pub(super) live: u32,
}

impl<W: Wide> Clone for Queued<W> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<W: Wide> Copy for Queued<W> {}

impl<W: Wide> Packet<W> for Queued<W> {
    #[inline(always)]
    fn f(self, v: &Arr<f32>) -> W {
        W::gather_pow2(v, &self.idx)
    }
    #[inline(always)]
    fn u(self, v: &Arr<u32>) -> W::U32 {
        W::gather_u_pow2(v, &self.idx)
    }
    #[inline(always)]
    fn idx(self) -> W::Idx {
        self.idx
    }
    #[inline(always)]
    fn live(self) -> u32 {
        self.live
    }
}

/// The W contiguous paths `i..i + W` (`i` a multiple of W below
/// `MAX_PATHS`), of which the lanes `live` are real: a packet scattered
/// where the classification found it, without a queue. Lanes outside `live`
/// (misses, or past the bounce's last path) hold stale values: they compute
/// what they compute and nothing of theirs is written.
#[derive(Clone, Copy)]
pub(super) struct Run {
    pub(super) i: usize,
    pub(super) live: u32,
}

impl<W: Wide> Packet<W> for Run {
    #[inline(always)]
    fn f(self, v: &Arr<f32>) -> W {
        W::load_pow2(v, self.i)
    }
    #[inline(always)]
    fn u(self, v: &Arr<u32>) -> W::U32 {
        W::load_u_pow2(v, self.i)
    }
    #[inline(always)]
    fn idx(self) -> W::Idx {
        index_run::<W>(self.i)
    }
    #[inline(always)]
    fn live(self) -> u32 {
        self.live
    }
}

/// Bits `0..n` set.
#[inline(always)]
pub(super) fn low_bits(n: usize) -> u32 {
    if n >= 32 {
        u32::MAX
    } else {
        (1u32 << n) - 1
    }
}

/// The indices `i..i + LANES`.
#[inline(always)]
pub(super) fn index_run<W: Wide>(i: usize) -> W::Idx {
    let mut idx = W::Idx::default();
    for (k, v) in idx.as_mut().iter_mut().enumerate() {
        *v = (i + k) as u32;
    }
    idx
}

/// Calls `f` with each packet of W indices of the first `len` entries of
/// `queue` (the last packet padded by repeating its first index, so every lane
/// holds a real path) and its real lanes. The indices are masked
/// into the arrays' range (a no-op on indices below `MAX_PATHS`), so the
/// gathers by them need no bounds checks.
#[inline(always)]
pub(super) fn for_packets<W: Wide, P: Probe>(
    queue: &Arr<u32>,
    len: usize,
    probe: &mut P,
    mut f: impl FnMut(Queued<W>, &mut P),
) {
    debug_assert!(len <= MAX_PATHS && queue[..len].iter().all(|&i| (i as usize) < MAX_PATHS));
    for i in (0..len).step_by(W::LANES) {
        let active = (len - i).min(W::LANES);
        let run = W::load_u_pow2(queue, i);
        let first = W::u_splat(queue[i & MASK]);
        let run = W::u_select(W::mask_from_bits(low_bits(active)), run, first);
        let idx = W::idx_of(run & W::u_splat(MASK as u32));
        probe.lanes(Stage::Scatter, active as u32, W::LANES as u32);
        f(Queued { idx, live: low_bits(active) }, probe);
    }
}
