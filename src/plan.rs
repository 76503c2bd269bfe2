//! The kernel side of the bridge: what a scene needs, decided once before
//! rendering ([`Plan`]), and the scene laid out for the kernels
//! ([`Prepared`]). The job module builds both from a scene; the kernels read
//! them and do only what the plan says. Nothing here knows the scene's schema.

use crate::camera::PreparedCamera;
use crate::choice::Mode;
use crate::estimator::Estimator;
use crate::film::accum::Scale;
use crate::geometry::{
    self, Bvh, Closest, CuboidBvh, Cuboids, Emitters, Lights, Media, MovingBvh, MovingSpheres, QuadBvh, Quads, Spheres,
    MISS, QUAD_BASE,
};
use crate::material::{Kind, MaterialTables};
use crate::probe::Probe;
use crate::real::{Real, Wide};
use crate::sampling::layout::Bounces;
use crate::settings::Settings;
use crate::texture::{TexSet, TextureTables};
use crate::vec3::V3;
use serde::{Serialize, Serializer};

/// A set of material kinds (serialized as the list of their names).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KindSet(u8);

impl KindSet {
    /// Every kind.
    pub fn all() -> KindSet {
        let mut s = KindSet::default();
        for k in Kind::ALL {
            s.insert(k);
        }
        s
    }
    pub fn insert(&mut self, k: Kind) {
        self.0 |= 1 << k as u8;
    }
    pub fn contains(self, k: Kind) -> bool {
        self.0 & (1 << k as u8) != 0
    }
    pub fn iter(self) -> impl Iterator<Item = Kind> {
        Kind::ALL.into_iter().filter(move |&k| self.contains(k))
    }
    /// The surface kinds of the set ([`Kind::SURFACES`]).
    pub fn surfaces(self) -> impl Iterator<Item = Kind> {
        Kind::SURFACES.into_iter().filter(move |&k| self.contains(k))
    }
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }
}

impl FromIterator<Kind> for KindSet {
    fn from_iter<I: IntoIterator<Item = Kind>>(it: I) -> Self {
        let mut s = KindSet::default();
        it.into_iter().for_each(|k| s.insert(k));
        s
    }
}

impl Serialize for KindSet {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.iter().map(Kind::name))
    }
}

/// How closest hits are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Accel {
    /// Every ray tests every sphere.
    Brute,
    /// The BVH; the wavefront walks it with packets of rays (the scalar kernel one ray at a time).
    BvhPackets,
    /// The BVH, one ray at a time with 8-wide node and leaf tests.
    BvhRays,
}

impl Accel {
    pub fn describe(self) -> &'static str {
        match self {
            Accel::Brute => "brute force",
            Accel::BvhPackets => "bvh8, packets of rays (scalar kernel: one ray at a time)",
            Accel::BvhRays => "bvh8, one ray at a time (8-wide nodes)",
        }
    }
}

/// The decisions that make each render do only the work its scene needs.
#[derive(Clone, Debug, Serialize, PartialEq, Eq)]
pub struct Plan {
    pub mode: Mode,
    /// Material kinds some sphere uses: only these get a queue and a scatter pass.
    pub kinds: KindSet,
    /// Texture kinds some lambertian uses (path tracing only): each gets a
    /// pass that writes the albedo before the material passes. Empty for a
    /// scene without textures, which runs no texture code at all.
    #[serde(skip_serializing_if = "TexSet::is_empty")]
    pub textures: TexSet,
    /// Thin-lens sampling (false: pinhole rays, no lens samples drawn).
    pub lens: bool,
    /// Jitter inside the pixel (false at 1 sample per pixel: pixel centres).
    pub jitter: bool,
    /// Closest-hit search.
    pub accel: Accel,
    /// The closest-hit search over quads, when the scene has any (searched
    /// after the spheres', improving their closest hit; a scene without quads
    /// pays nothing).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quads: Option<Accel>,
    /// The closest-hit search over cuboids (the scene's boxes, each tested
    /// whole by one slab test: `geometry::cuboids`), when the scene has any
    /// (searched after the loose quads'). Their faces are quads for
    /// everything else.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cuboids: Option<Accel>,
    /// The closest-hit search over moving spheres, when the scene has any
    /// (searched after the quads'; each path then carries a time, drawn by
    /// the camera from `layout::TIME` and inherited by its scattered rays).
    /// A scene without moving spheres draws no time and pays nothing.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moving: Option<Accel>,
    /// The `book` estimator's shapes (its `sample_toward` list, else the
    /// scene's lights), when it runs and has any: each diffuse vertex then
    /// mixes the material's density with directions toward them. 0: the
    /// materials' own densities only (the `bsdf` estimator, whose bounce
    /// draws and computes nothing for this).
    #[serde(skip_serializing_if = "is_zero")]
    pub sample_toward: usize,
    /// The `nee-mis` estimator's lights (the scene's static emitters), when
    /// it runs and has any: each diffuse vertex then sends a shadow ray
    /// toward one of them, weighted against the scattered direction by the
    /// power heuristic. 0: no light samples.
    #[serde(skip_serializing_if = "is_zero")]
    pub nee: usize,
    /// The film's fixed-point scale exponent ([`Scale`]), chosen from the
    /// brightest emission the scene can produce (`job::prepare::brightest`)
    /// before any work: 0, the unit scale, for every scene whose brightest
    /// emission is below 2^47 (every preset); above, the smallest that leaves
    /// 2^16 of headroom over it in the film's range.
    #[serde(skip_serializing_if = "is_zero_u32")]
    pub film_exponent: u32,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

fn is_zero_u32(n: &u32) -> bool {
    *n == 0
}

impl Plan {
    /// The film's fixed-point scale (of [`Plan::film_exponent`]).
    pub fn film_scale(&self) -> Scale {
        Scale::new(self.film_exponent).expect("the plan's exponent is at most MAX_EXPONENT")
    }

    /// A human-readable account of the plan (`rtow render --explain`).
    pub fn explain(&self) -> String {
        let kinds: Vec<&str> = self.kinds.iter().map(Kind::name).collect();
        let kinds = if kinds.is_empty() { "none".to_string() } else { kinds.join(", ") };
        let quads = match self.quads {
            Some(Accel::Brute) => "; quads: brute force",
            Some(_) => "; quads: their own bvh8, one box at a time",
            None => "",
        };
        let cuboids = match self.cuboids {
            Some(Accel::Brute) => "; boxes: brute force, one slab test per box",
            Some(_) => "; boxes: their own bvh8, one slab test per box",
            None => "",
        };
        let moving = match self.moving {
            Some(Accel::Brute) => "; moving spheres: brute force at each path's time",
            Some(_) => "; moving spheres: their own bvh8 over the shutter interval, tested at each path's time",
            None => "",
        };
        let textures: Vec<&str> = self.textures.iter().map(|t| t.name()).collect();
        let textures =
            if textures.is_empty() { String::new() } else { format!("; texture passes: {}", textures.join(", ")) };
        let media = if self.kinds.contains(Kind::Isotropic) {
            "; media: a free-flight pass after the closest hit (analytic chords)"
        } else {
            ""
        };
        let toward = match self.sample_toward {
            0 => String::new(),
            n => format!("; diffuse vertices: the book's mixture, half toward {n} shape(s)"),
        };
        let toward = match self.nee {
            0 => toward,
            n => format!(
                "{toward}; diffuse vertices: a shadow ray toward one of {n} light(s) (any-hit packets, their own queue), \
                 weighted against the scattered direction by the power heuristic"
            ),
        };
        let film = match self.film_scale() {
            s if s.exponent() == 0 => String::new(),
            s => format!(
                "; film: fixed point scaled by 2^-{} for the brightest emission (samples below {:.3e}, steps of {:.3e})",
                s.exponent(),
                s.limit(),
                s.resolution()
            ),
        };
        format!(
            "plan: mode {:?}; material passes: {kinds}{textures}; camera: {} rays, {}; closest hit: {}{quads}{cuboids}{moving}{media}{toward}; paths stop at zero throughput{film}",
            self.mode,
            if self.lens { "thin-lens" } else { "pinhole" },
            if self.jitter { "jittered in the pixel" } else { "through pixel centres" },
            self.accel.describe(),
        )
    }
}

/// What rays that leave the scene see, ready for both kernels: the sky
/// gradient's two colours, or one constant colour (The Next Week's background).
#[derive(Clone, Copy, Debug)]
pub struct SkyColours {
    pub horizon: [f32; 3],
    pub zenith: [f32; 3],
    /// A constant background in place of the gradient.
    pub constant: Option<[f32; 3]>,
}

impl SkyColours {
    /// A black background: a path that leaves the scene adds nothing, so
    /// neither kernel shades its miss (the scalar kernel's sum and the
    /// wavefront's result stay as they are, bit for bit, whatever the
    /// path's throughput).
    pub fn is_black(&self) -> bool {
        self.constant.is_some_and(|c| c.iter().all(|&x| x == 0.0))
    }
}

/// Everything the kernels read, laid out for them.
#[derive(Clone, Debug)]
pub struct Prepared {
    pub plan: Plan,
    pub settings: Settings,
    pub spheres: Spheres,
    /// The quads (empty for a scene without: padding only).
    pub quads: Quads,
    /// The constant media (empty for a scene without, and in the debug modes).
    pub media: Media,
    pub materials: MaterialTables,
    /// The texture tables (empty for a scene without textures).
    pub textures: TextureTables,
    pub camera: PreparedCamera,
    pub sky: SkyColours,
    /// Present when the plan chose a BVH.
    pub bvh: Option<Bvh>,
    /// The quads' tree, when the plan chose one for them.
    pub quad_bvh: Option<QuadBvh>,
    /// The boxes, each tested whole (empty for a scene without).
    pub cuboids: Cuboids,
    /// Their tree, when the plan chose one for them.
    pub cuboid_bvh: Option<CuboidBvh>,
    /// The moving spheres (empty for a scene without: padding only).
    pub moving: MovingSpheres,
    /// Their tree, when the plan chose one for them.
    pub moving_bvh: Option<MovingBvh>,
    /// Russian roulette and adaptive sampling (off unless the render options say so).
    pub estimator: Estimator,
    /// The shapes the `book` estimator samples toward (empty unless
    /// `plan.sample_toward`).
    pub lights: Lights,
    /// The lights the `nee-mis` estimator samples (empty unless `plan.nee`).
    pub emitters: Emitters,
    /// The sampler dimensions of each bounce (the `book` estimator's when
    /// it samples toward shapes, else the `bsdf` estimator's).
    pub bounces: Bounces,
}

impl Prepared {
    /// The closest hit of one ray at time `time` (scalar kernel): the BVH one
    /// box at a time, or brute force. `M`: the scene has moving spheres
    /// (`false` compiles to the search of a scene without).
    #[inline(always)]
    pub fn closest_hit<P: Probe, const M: bool>(&self, o: V3<f32>, d: V3<f32>, time: f32, probe: &mut P) -> (u32, f32) {
        let (index, t) = match &self.bvh {
            Some(b) => b.closest_hit_scalar(o, d, probe),
            None => geometry::closest_hit(&self.spheres, o, d, probe),
        };
        if !M && self.quads.is_empty() {
            return (index, t);
        }
        let mut best = Closest { t, index };
        if !M || !self.quads.is_empty() {
            match &self.quad_bvh {
                Some(b) => best = b.walk_scalar(o, d, best, probe),
                None => geometry::closest_quad_hit(&self.quads, o, d, &mut best, probe),
            }
            if !self.cuboids.is_empty() {
                match &self.cuboid_bvh {
                    Some(b) => best = b.walk_scalar(o, d, best, probe),
                    None => geometry::closest_cuboid_hit(&self.cuboids, o, d, &mut best, probe),
                }
            }
        }
        if M {
            match &self.moving_bvh {
                Some(b) => best = b.walk_scalar_at(o, d, time, best, probe),
                None => geometry::closest_moving_hit(&self.moving, o, d, time, &mut best, probe),
            }
        }
        (best.index, best.t)
    }

    /// The closest hits of a packet of rays (wavefront kernel; bit k of `live`
    /// marks a real ray), as the plan says: brute force, BVH packets, or the BVH
    /// one ray at a time. `M`: the scene has moving spheres (`false` compiles
    /// to the search of a scene without); `time` gives the rays' times, called
    /// only when `M`.
    #[cfg_attr(not(feature = "phases"), inline(always))]
    #[cfg_attr(feature = "phases", inline(never))]
    pub fn closest_hits<W: Wide, P: Probe, const M: bool>(
        &self,
        o: V3<W>,
        d: V3<W>,
        live: u32,
        time: impl FnOnce() -> W,
        probe: &mut P,
    ) -> (W::U32, W) {
        let (index, t) = match (&self.bvh, self.plan.accel) {
            (Some(b), Accel::BvhRays) => b.closest_hits_one_by_one(o, d, live, probe),
            (Some(b), _) => b.closest_hit_packet(o, d, live, probe),
            (None, _) => geometry::closest_hit(&self.spheres, o, d, probe),
        };
        if !M && self.quads.is_empty() {
            return (index, t);
        }
        // Lanes not in `live` take no part (t = -inf), as in the packet walk.
        let t = W::select(W::mask_from_bits(live), t, W::splat(f32::NEG_INFINITY));
        let mut best = Closest { t, index };
        if !M || !self.quads.is_empty() {
            match &self.quad_bvh {
                Some(b) => best = b.walk_packet(o, d, best, probe),
                None => geometry::closest_quad_hit(&self.quads, o, d, &mut best, probe),
            }
            if !self.cuboids.is_empty() {
                match &self.cuboid_bvh {
                    Some(b) => best = b.walk_packet(o, d, best, probe),
                    None => geometry::closest_cuboid_hit(&self.cuboids, o, d, &mut best, probe),
                }
            }
        }
        if M {
            let time = time();
            match &self.moving_bvh {
                Some(b) => best = b.walk_packet_at(o, d, time, best, probe),
                None => geometry::closest_moving_hit(&self.moving, o, d, time, &mut best, probe),
            }
        }
        (best.index, best.t)
    }

    /// Whether something lies on the segment `o + t d`, `0 < t < tmax`, of
    /// one ray at time `time` (a shadow ray, scalar kernel): any hit, the
    /// search stopping at the first. Media do not block (their
    /// transmittance is [`geometry::transmittance`]).
    #[inline(always)]
    pub fn occluded_one<P: Probe, const M: bool>(
        &self,
        o: V3<f32>,
        d: V3<f32>,
        tmax: f32,
        time: f32,
        probe: &mut P,
    ) -> bool {
        let mut best = Closest { t: tmax, index: MISS };
        match &self.bvh {
            Some(b) => best = b.any_hit_scalar_at(o, d, 0.0, best, probe),
            None => geometry::any_sphere_hit(&self.spheres, o, d, &mut best, probe),
        }
        if best.index == MISS && !self.quads.is_empty() {
            match &self.quad_bvh {
                Some(b) => best = b.any_hit_scalar_at(o, d, 0.0, best, probe),
                None => geometry::any_quad_hit(&self.quads, o, d, &mut best, probe),
            }
        }
        if best.index == MISS && !self.cuboids.is_empty() {
            match &self.cuboid_bvh {
                Some(b) => best = b.any_hit_scalar_at(o, d, 0.0, best, probe),
                None => geometry::any_cuboid_hit(&self.cuboids, o, d, &mut best, probe),
            }
        }
        if M && best.index == MISS {
            match &self.moving_bvh {
                Some(b) => best = b.any_hit_scalar_at(o, d, time, best, probe),
                None => geometry::any_moving_hit(&self.moving, o, d, time, &mut best, probe),
            }
        }
        best.index != MISS
    }

    /// [`Prepared::occluded_one`] for a packet of shadow rays (bit k of
    /// `live` marks a real one; the others are not occluded): the packet
    /// walks in their any-hit form, each lane leaving at its first hit and
    /// each search stopping once no lane is left. The same answer as one ray
    /// at a time, whatever the order: a hit below `tmax` is one whatever
    /// else was found.
    #[inline(always)]
    pub fn occluded<W: Wide, P: Probe, const M: bool>(
        &self,
        o: V3<W>,
        d: V3<W>,
        tmax: W,
        live: u32,
        time: impl FnOnce() -> W,
        probe: &mut P,
    ) -> <W as Real>::Mask {
        let mut best = Closest {
            t: W::select(W::mask_from_bits(live), tmax, W::splat(f32::NEG_INFINITY)),
            index: W::u_splat(MISS),
        };
        match &self.bvh {
            Some(b) => best = b.any_hit_packet_at(o, d, W::splat(0.0), best, probe),
            None => geometry::any_sphere_hit(&self.spheres, o, d, &mut best, probe),
        }
        if !best.leave_found() && !self.quads.is_empty() {
            match &self.quad_bvh {
                Some(b) => best = b.any_hit_packet_at(o, d, W::splat(0.0), best, probe),
                None => geometry::any_quad_hit(&self.quads, o, d, &mut best, probe),
            }
        }
        if !best.leave_found() && !self.cuboids.is_empty() {
            match &self.cuboid_bvh {
                Some(b) => best = b.any_hit_packet_at(o, d, W::splat(0.0), best, probe),
                None => geometry::any_cuboid_hit(&self.cuboids, o, d, &mut best, probe),
            }
        }
        if M && !best.leave_found() {
            let time = time();
            match &self.moving_bvh {
                Some(b) => best = b.any_hit_packet_at(o, d, time, best, probe),
                None => geometry::any_moving_hit(&self.moving, o, d, time, &mut best, probe),
            }
        }
        !W::u_eq(best.index, W::u_splat(MISS))
    }

    /// Whether hit index `hit` (not `MISS`) is a quad's.
    #[inline(always)]
    pub fn is_quad(hit: u32) -> bool {
        hit >= QUAD_BASE
    }
}
