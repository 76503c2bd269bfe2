//! Probes: observers that the kernels and the traversals take as a type
//! parameter. Every method has an empty inlined default, so a render with the
//! probe `()` compiles to the uninstrumented code (`rtow bench` shows it costs
//! nothing). Tools that need to see inside a kernel (lane occupancy, work
//! counters, `rtow stress`'s oracle, `rtow converge --split`) all run the one
//! other probe, [`Observed`]: it counts work inline and hands path events, lane
//! by lane, to a [`PathEvents`] object. Each probe type is one more copy of
//! every kernel in the build (about as much compile time as the renderer's
//! own), so the tools share one; none copies a kernel.
//!
//! The kernels call the path events with the lanes they hold: one lane for the
//! scalar kernel (`R = f32`), 8 or 16 for the wavefront (`live` says which
//! lanes are real paths). A path is named by its pixel (`y * width + x`) and
//! sample index, which do not depend on kernel, tile or thread.

pub use crate::geometry::work::{Counter, Work};
use crate::handle::Kind;
use crate::real::{Real, MAX_LANES};
use crate::vec3::V3;
use std::any::Any;

/// Which (pixel, sample) each lane holds.
#[derive(Clone, Copy, Debug)]
pub struct PathId<R: Real> {
    pub pixel: R::U32,
    pub sample: R::U32,
}

/// Where a term of a path's radiance came from: the strategies whose
/// variances `rtow converge --split` tells apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Strategy {
    /// The background, seen by a ray that left the scene.
    Background,
    /// A light seen by a camera ray or through specular bounces (weight 1 under every estimator).
    Specular,
    /// A light reached by a direction that a diffuse or isotropic vertex
    /// sampled: `bsdf`'s cosine lobe, `book`'s mixture, or under `nee-mis`
    /// the material's density, weighted against the light sample.
    Scattered,
    /// An unblocked light sample (a shadow ray of `nee-mis`), weighted.
    LightSample,
}

impl Strategy {
    pub const ALL: [Strategy; 4] =
        [Strategy::Background, Strategy::Specular, Strategy::Scattered, Strategy::LightSample];

    pub fn name(self) -> &'static str {
        match self {
            Strategy::Background => "background",
            Strategy::Specular => "specular",
            Strategy::Scattered => "scattered",
            Strategy::LightSample => "light sample",
        }
    }
}

/// The kernel stages whose SIMD lane occupancy is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    Intersect,
    Scatter,
}

/// An observer of the kernels; its traversal work counting is its
/// [`Counter`] side.
pub trait Probe: Counter {
    /// Whether the kernels must compute path ids for [`Probe::camera`],
    /// [`Probe::traced`] and [`Probe::shaded`] (false: the events are not called).
    const PATHS: bool = false;

    /// Whether this probe, as it is now, wants the path events (only asked
    /// when [`Probe::PATHS`]): a tool's probe that counts work only says no,
    /// and the kernels skip the path ids and the events.
    #[inline(always)]
    fn paths(&self) -> bool {
        Self::PATHS
    }

    /// A camera ray was generated; returns its origin (a probe may move it
    /// along the ray, as `rtow stress`'s far-camera check does).
    #[inline(always)]
    fn camera<R: Real>(&mut self, _id: PathId<R>, o: V3<R>, _d: V3<R>, _live: u32) -> V3<R> {
        o
    }

    /// A ray's closest hit was found (`hit` is the sphere index or `MISS`).
    #[inline(always)]
    fn traced<R: Real>(&mut self, _id: PathId<R>, _o: V3<R>, _d: V3<R>, _hit: R::U32, _t: R, _live: u32) {}

    /// A hit was shaded: the sphere's signed radius, the normal facing the ray
    /// and whether the ray hit the front face.
    #[inline(always)]
    fn shaded<R: Real>(&mut self, _id: PathId<R>, _sphere: R::U32, _radius: R, _n: V3<R>, _front: R::Mask, _live: u32) {
    }

    /// A term `c` was added to the radiance of path `id`: exactly the value
    /// the kernel adds (throughput, attenuation and MIS weight included), from
    /// a path of `length` segments (1: a camera ray that saw a light or the
    /// background; a light sample at the vertex after `k` rays: `k + 1`), by
    /// `strategy`. The terms of a path add up to its radiance, in this order.
    /// Called by the scalar kernel, the reference that every kernel matches
    /// bit for bit, and only when [`Probe::PATHS`].
    #[inline(always)]
    fn contributed(&mut self, _id: PathId<f32>, _length: u32, _strategy: Strategy, _c: V3<f32>) {}

    /// Path `id` scattered at a vertex whose material is of kind `kind`
    /// (`Isotropic`: inside a medium): its next direction `dir`, the
    /// attenuation `atten` it multiplies the throughput by (the albedo times
    /// the estimator's weight) and `pdf`, the density of `dir` that weighs a
    /// light the next ray hits under `nee-mis` (0 for a specular bounce and
    /// under `book`, whose weight holds the mixture's density). Called by the
    /// scalar kernel, only when [`Probe::PATHS`].
    #[inline(always)]
    fn scattered(&mut self, _id: PathId<f32>, _kind: Kind, _dir: V3<f32>, _atten: [f32; 3], _pdf: f32) {}

    /// `n` rays are traced next, each the `depth`-th of its path (0: camera rays).
    #[inline(always)]
    fn rays(&mut self, _depth: u32, _n: u32) {}

    /// A SIMD pass over `issued` lanes of which `active` were real paths.
    #[inline(always)]
    fn lanes(&mut self, _stage: Stage, _active: u32, _issued: u32) {}
}

/// No instrumentation: what normal renders use.
impl Probe for () {}

/// Exact work counters and lane occupancy: deterministic for a seed and the
/// settings, whatever the threads, tiles or timing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct WorkCounters {
    pub nodes: u64,
    pub box_tests: u64,
    pub sphere_tests: u64,
    pub roots: u64,
    pub quad_tests: u64,
    /// Cuboid tests (absent from parts written before cuboids: 0).
    #[serde(default)]
    pub cuboid_tests: u64,
    /// Triangle tests (absent from parts written before meshes: 0).
    #[serde(default)]
    pub triangle_tests: u64,
    pub isect_active: u64,
    pub isect_lanes: u64,
    pub scatter_active: u64,
    pub scatter_lanes: u64,
}

impl WorkCounters {
    pub fn merge(&mut self, o: &WorkCounters) {
        self.nodes += o.nodes;
        self.box_tests += o.box_tests;
        self.sphere_tests += o.sphere_tests;
        self.roots += o.roots;
        self.quad_tests += o.quad_tests;
        self.cuboid_tests += o.cuboid_tests;
        self.triangle_tests += o.triangle_tests;
        self.isect_active += o.isect_active;
        self.isect_lanes += o.isect_lanes;
        self.scatter_active += o.scatter_active;
        self.scatter_lanes += o.scatter_lanes;
    }

    /// Active / issued lanes in intersection and scatter (`None` when no SIMD lanes ran).
    pub fn occupancy(&self) -> (Option<f64>, Option<f64>) {
        let occ = |a: u64, l: u64| (l > 0).then(|| a as f64 / l as f64);
        (occ(self.isect_active, self.isect_lanes), occ(self.scatter_active, self.scatter_lanes))
    }
}

impl Counter for WorkCounters {
    const WORK: bool = true;

    #[inline(always)]
    fn work(&mut self, w: Work, n: u32) {
        let c = match w {
            Work::Node => &mut self.nodes,
            Work::Box => &mut self.box_tests,
            Work::Sphere => &mut self.sphere_tests,
            Work::Root => &mut self.roots,
            Work::Quad => &mut self.quad_tests,
            Work::Cuboid => &mut self.cuboid_tests,
            Work::Triangle => &mut self.triangle_tests,
        };
        *c += n as u64;
    }
}

impl Probe for WorkCounters {
    #[inline(always)]
    fn lanes(&mut self, stage: Stage, active: u32, issued: u32) {
        let (a, l) = match stage {
            Stage::Intersect => (&mut self.isect_active, &mut self.isect_lanes),
            Stage::Scatter => (&mut self.scatter_active, &mut self.scatter_lanes),
        };
        *a += active as u64;
        *l += issued as u64;
    }
}

/// The work counters split by the depth of the rays (0: camera rays): how
/// traversal work per ray grows as paths lose coherence.
#[derive(Clone, Debug, Default)]
pub struct WorkByDepth {
    depth: usize,
    pub by_depth: Vec<WorkCounters>,
    /// Rays traced at each depth.
    pub rays: Vec<u64>,
}

impl WorkByDepth {
    pub fn merge(&mut self, o: &WorkByDepth) {
        if self.by_depth.len() < o.by_depth.len() {
            self.by_depth.resize(o.by_depth.len(), WorkCounters::default());
            self.rays.resize(o.rays.len(), 0);
        }
        for (d, w) in o.by_depth.iter().enumerate() {
            self.by_depth[d].merge(w);
            self.rays[d] += o.rays[d];
        }
    }

    /// The counters over every depth.
    pub fn total(&self) -> WorkCounters {
        let mut w = WorkCounters::default();
        self.by_depth.iter().for_each(|d| w.merge(d));
        w
    }

    fn at(&mut self) -> &mut WorkCounters {
        if self.by_depth.len() <= self.depth {
            self.by_depth.resize(self.depth + 1, WorkCounters::default());
            self.rays.resize(self.depth + 1, 0);
        }
        &mut self.by_depth[self.depth]
    }
}

impl Counter for WorkByDepth {
    const WORK: bool = true;

    #[inline(always)]
    fn work(&mut self, w: Work, n: u32) {
        self.at().work(w, n);
    }
}

impl Probe for WorkByDepth {
    #[inline(always)]
    fn rays(&mut self, depth: u32, n: u32) {
        self.depth = depth as usize;
        self.at();
        self.rays[self.depth] += n as u64;
    }

    #[inline(always)]
    fn lanes(&mut self, stage: Stage, active: u32, issued: u32) {
        self.at().lanes(stage, active, issued);
    }
}

/// One packet's path ids as plain values (lane `k` of each), for observers
/// that are not generic over the lane type.
#[derive(Clone, Copy, Debug)]
pub struct Lanes {
    /// Lanes in the packet (1 for the scalar kernel).
    pub n: usize,
    /// Which of them are real paths (bit `k`: lane `k`).
    pub live: u32,
    pub pixel: [u32; MAX_LANES],
    pub sample: [u32; MAX_LANES],
}

impl Lanes {
    fn of<R: Real>(id: PathId<R>, live: u32) -> Lanes {
        Lanes {
            n: R::LANES,
            live,
            pixel: std::array::from_fn(|k| if k < R::LANES { R::lane_u(id.pixel, k) } else { 0 }),
            sample: std::array::from_fn(|k| if k < R::LANES { R::lane_u(id.sample, k) } else { 0 }),
        }
    }

    /// The live lanes, in order.
    pub fn live(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.n).filter(|&k| self.live & (1 << k) != 0)
    }
}

/// Lanes of `x`, then zeros.
fn unpack<R: Real>(x: R) -> [f32; MAX_LANES] {
    std::array::from_fn(|k| if k < R::LANES { x.lane(k) } else { 0.0 })
}

fn unpack_u<R: Real>(x: R::U32) -> [u32; MAX_LANES] {
    std::array::from_fn(|k| if k < R::LANES { R::lane_u(x, k) } else { 0 })
}

fn unpack3<R: Real>(v: V3<R>) -> [V3<f32>; MAX_LANES] {
    std::array::from_fn(|k| if k < R::LANES { v.lane(k) } else { V3::new(0.0, 0.0, 0.0) })
}

/// A tool's view of the path events of [`Probe`], lane by lane and not
/// generic over the lane type, so that every tool runs the same copy of the
/// kernels ([`Observed`]). Arrays hold [`Lanes::n`] lanes.
pub trait PathEvents: Send {
    /// [`Probe::camera`]: may move the origins `o` (every lane, live or not).
    fn camera(&mut self, _ids: &Lanes, _o: &mut [V3<f32>; MAX_LANES], _d: &[V3<f32>; MAX_LANES]) {}

    /// [`Probe::traced`].
    fn traced(
        &mut self,
        _ids: &Lanes,
        _o: &[V3<f32>; MAX_LANES],
        _d: &[V3<f32>; MAX_LANES],
        _hit: &[u32; MAX_LANES],
        _t: &[f32; MAX_LANES],
    ) {
    }

    /// [`Probe::shaded`]; `front` bit `k`: lane `k` hit a front face.
    fn shaded(&mut self, _ids: &Lanes, _radius: &[f32; MAX_LANES], _n: &[V3<f32>; MAX_LANES], _front: u32) {}

    /// [`Probe::contributed`].
    fn contributed(&mut self, _id: PathId<f32>, _length: u32, _strategy: Strategy, _c: V3<f32>) {}

    /// [`Probe::scattered`].
    fn scattered(&mut self, _id: PathId<f32>, _kind: Kind, _dir: V3<f32>, _atten: [f32; 3], _pdf: f32) {}

    /// What the tool keeps of this observer once its tile is rendered.
    fn finish(self: Box<Self>) -> Box<dyn Any + Send>;
}

/// The tools' probe: exact work counters by ray depth, kept inline, and the
/// path events of an optional [`PathEvents`] object.
pub struct Observed<'a> {
    pub work: WorkByDepth,
    events: Option<Box<dyn PathEvents + 'a>>,
}

impl<'a> Observed<'a> {
    /// Work counters only.
    pub fn counting() -> Self {
        Observed { work: WorkByDepth::default(), events: None }
    }

    /// Work counters and `events`.
    pub fn with(events: impl PathEvents + 'a) -> Self {
        Observed { work: WorkByDepth::default(), events: Some(Box::new(events)) }
    }

    /// What the events object kept ([`PathEvents::finish`]), as the type it
    /// gives.
    ///
    /// # Panics
    ///
    /// For a counting probe, or a `T` that is not the type its events object
    /// gives: a tool asks for what its own object keeps, so either is a bug,
    /// and an empty result would pass for a clean one.
    pub fn finish<T: 'static>(self) -> T {
        let kept = self.events.expect("Observed::finish on a probe that counts work only").finish();
        *kept.downcast().expect("Observed::finish: the events object keeps another type")
    }
}

impl Counter for Observed<'_> {
    const WORK: bool = true;

    #[inline(always)]
    fn work(&mut self, w: Work, n: u32) {
        self.work.work(w, n);
    }
}

impl Probe for Observed<'_> {
    const PATHS: bool = true;

    #[inline(always)]
    fn paths(&self) -> bool {
        self.events.is_some()
    }

    #[inline]
    fn camera<R: Real>(&mut self, id: PathId<R>, o: V3<R>, d: V3<R>, live: u32) -> V3<R> {
        match &mut self.events {
            None => o,
            Some(e) => {
                let mut moved = unpack3(o);
                e.camera(&Lanes::of(id, live), &mut moved, &unpack3(d));
                V3::new(R::from_fn(|k| moved[k].x), R::from_fn(|k| moved[k].y), R::from_fn(|k| moved[k].z))
            }
        }
    }

    #[inline]
    fn traced<R: Real>(&mut self, id: PathId<R>, o: V3<R>, d: V3<R>, hit: R::U32, t: R, live: u32) {
        if let Some(e) = &mut self.events {
            e.traced(&Lanes::of(id, live), &unpack3(o), &unpack3(d), &unpack_u::<R>(hit), &unpack(t));
        }
    }

    #[inline]
    fn shaded<R: Real>(&mut self, id: PathId<R>, _sphere: R::U32, radius: R, n: V3<R>, front: R::Mask, live: u32) {
        if let Some(e) = &mut self.events {
            e.shaded(&Lanes::of(id, live), &unpack(radius), &unpack3(n), R::mask_bits(front));
        }
    }

    #[inline]
    fn contributed(&mut self, id: PathId<f32>, length: u32, strategy: Strategy, c: V3<f32>) {
        if let Some(e) = &mut self.events {
            e.contributed(id, length, strategy, c);
        }
    }

    #[inline]
    fn scattered(&mut self, id: PathId<f32>, kind: Kind, dir: V3<f32>, atten: [f32; 3], pdf: f32) {
        if let Some(e) = &mut self.events {
            e.scattered(id, kind, dir, atten, pdf);
        }
    }

    #[inline(always)]
    fn rays(&mut self, depth: u32, n: u32) {
        self.work.rays(depth, n);
    }

    #[inline(always)]
    fn lanes(&mut self, stage: Stage, active: u32, issued: u32) {
        self.work.lanes(stage, active, issued);
    }
}
