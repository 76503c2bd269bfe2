//! The kernel side of the bridge: what a scene needs, decided once before
//! rendering ([`Plan`]), and the scene laid out for the kernels
//! ([`Prepared`]). The job module builds both from a scene; the kernels read
//! them and do only what the plan says. Nothing here knows the scene's schema.

use crate::camera::PreparedCamera;
use crate::choice::Mode;
use crate::estimator::{Directions, Estimator};
use crate::film::accum::Scale;
use crate::geometry::{Emitters, Lights, Media, Shapes};
use crate::handle::Kind;
use crate::material::MaterialTables;
use crate::sampling::layout::Bounces;
use crate::settings::Settings;
use crate::texture::{TexSet, TextureTables};
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
    /// The closest-hit search over the meshes' triangles, when the scene
    /// has any (a hit's surface is a quad's, on the triangle's plane).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub triangles: Option<Accel>,
    /// The placements of shared meshes (`geometry::instances`), when rays
    /// are traced: searched after the moving spheres, through the
    /// instances' own tree and each mesh's tree in its frame.
    #[serde(skip_serializing_if = "is_zero")]
    pub instances: usize,
    /// The shared meshes those instances place, each held once.
    #[serde(skip_serializing_if = "is_zero")]
    pub shared_meshes: usize,
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
    /// How diffuse vertices choose their directions: the estimator the plan runs.
    pub fn directions(&self) -> Directions {
        if self.sample_toward > 0 {
            Directions::Book
        } else if self.nee > 0 {
            Directions::Nee
        } else {
            Directions::Bsdf
        }
    }

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
        let triangles = match self.triangles {
            Some(Accel::Brute) => "; triangles: brute force, watertight test",
            Some(_) => "; triangles: their own bvh8, watertight test",
            None => "",
        };
        let instances = match self.instances {
            0 => String::new(),
            n => format!(
                "; instances: {n} placements of {} shared mesh(es), each mesh's bvh8 walked in its own frame under the \
                 instances' bvh8",
                self.shared_meshes
            ),
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
            "plan: mode {:?}; material passes: {kinds}{textures}; camera: {} rays, {}; closest hit: {}{quads}{cuboids}{moving}{triangles}{instances}{media}{toward}; paths stop at zero throughput{film}",
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
    /// Every primitive kind and its tree where the plan chose one, searched
    /// as one aggregate.
    pub shapes: Shapes,
    /// The constant media (empty for a scene without, and in the debug modes).
    pub media: Media,
    pub materials: MaterialTables,
    /// The texture tables (empty for a scene without textures).
    pub textures: TextureTables,
    pub camera: PreparedCamera,
    pub sky: SkyColours,
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
