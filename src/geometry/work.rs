//! What a search counts: the traversal work a closest-hit or any-hit search
//! does ([`Work`]), handed to a [`Counter`]. The kernels' probes are counters
//! (`crate::probe`); a render without one passes `()`, which counts nothing
//! and compiles to the search without counting.

/// Traversal work, in the units a search issues it: one node visit, one box
/// or primitive test of a group of rays (one ray, or a packet), one square
/// root of a group.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Work {
    /// A BVH node whose children are tested.
    Node,
    /// A child box tested (the slab test).
    Box,
    /// A sphere tested (the discriminant).
    Sphere,
    /// A sphere test that reached the square root (some lane's discriminant >= 0).
    Root,
    /// A quad tested (The Next Week's primitives).
    Quad,
    /// A cuboid tested (a box's six faces, by one slab test).
    Cuboid,
    /// A triangle tested (a mesh's).
    Triangle,
}

impl Work {
    pub const ALL: [Work; 7] =
        [Work::Node, Work::Box, Work::Sphere, Work::Root, Work::Quad, Work::Cuboid, Work::Triangle];
}

/// Receives traversal work. Every method has an empty inlined default, so a
/// search for `()` carries no counting code.
pub trait Counter {
    /// Whether this counter counts [`Work`] (searches then keep counts in
    /// registers, [`WorkTally`], and hand them over once per search).
    const WORK: bool = false;

    /// `n` units of traversal work.
    #[inline(always)]
    fn work(&mut self, _w: Work, _n: u32) {}
}

impl Counter for () {}

/// The work of one search, counted in registers and handed to the counter
/// once at its end: counting each test through `&mut C` in the inner loops
/// cost about 9% of the render (measured; docs/performance.md). Nothing is
/// counted, and nothing is left in the code, unless `C::WORK`.
pub struct WorkTally<C> {
    n: [u32; 7],
    _counter: std::marker::PhantomData<fn(&mut C)>,
}

impl<C: Counter> WorkTally<C> {
    #[inline(always)]
    pub fn new() -> Self {
        WorkTally { n: [0; 7], _counter: std::marker::PhantomData }
    }

    #[inline(always)]
    pub fn flush(self, counter: &mut C) {
        if C::WORK {
            for (w, n) in Work::ALL.into_iter().zip(self.n) {
                counter.work(w, n);
            }
        }
    }
}

impl<C: Counter> Default for WorkTally<C> {
    fn default() -> Self {
        WorkTally::new()
    }
}

impl<C: Counter> Counter for WorkTally<C> {
    const WORK: bool = C::WORK;

    #[inline(always)]
    fn work(&mut self, w: Work, n: u32) {
        if C::WORK {
            self.n[w as usize] += n;
        }
    }
}
