//! What a scene needs, decided once before rendering, and the scene prepared
//! for the kernels (SoA spheres, per-kind material tables, the camera).

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::estimator::Estimator;
use crate::geometry::{closest_hit_scalar, closest_hit_x8, Bvh, Spheres};
use crate::material::MaterialTables;
use crate::scene::{Kind, Mode, Scene, Sky};
use crate::vec3::V3;
use serde::Serialize;
use wide::{f32x8, u32x8};

/// The decisions that make each render do only the work its scene needs.
#[derive(Clone, Debug, Serialize, PartialEq, Eq)]
pub struct Plan {
    pub mode: Mode,
    /// Material kinds some sphere uses: only these get a queue and a scatter pass.
    pub kinds: Vec<&'static str>,
    /// Thin-lens sampling (false: pinhole rays, no lens samples drawn).
    pub lens: bool,
    /// Jitter inside the pixel (false at 1 sample per pixel: pixel centres).
    pub jitter: bool,
    /// Closest-hit search.
    pub accel: &'static str,
    /// Paths stop as soon as their throughput is exactly zero.
    pub stop_at_zero_throughput: bool,
}

impl Plan {
    pub fn uses(&self, kind: Kind) -> bool {
        self.kinds.contains(&kind.name())
    }

    /// A human-readable account of the plan (`rtow render --explain`).
    pub fn explain(&self) -> String {
        let kinds = if self.kinds.is_empty() { "none".to_string() } else { self.kinds.join(", ") };
        format!(
            "plan: mode {:?}; material passes: {kinds}; camera: {} rays, {}; closest hit: {}; paths stop at zero throughput: {}",
            self.mode,
            if self.lens { "thin-lens" } else { "pinhole" },
            if self.jitter { "jittered in the pixel" } else { "through pixel centres" },
            self.accel,
            if self.stop_at_zero_throughput { "yes" } else { "no" },
        )
    }
}

/// How closest hits are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum AccelChoice {
    /// Brute force below the measured crossover, BVH above it.
    #[default]
    Auto,
    /// Every ray tests every sphere (8 rays per packet in the SIMD kernel).
    Brute,
    /// The 8-wide BVH; the SIMD kernel walks it with packets of 8 rays
    /// (measured fastest: see README).
    Bvh,
    /// The same BVH; the SIMD kernel walks it one ray at a time with 8-wide
    /// node and leaf tests (kept for comparison).
    BvhRay,
}

/// With at least this many spheres `auto` builds a BVH. Measured with
/// `rtow bench` on random scenes (see README, "Skip what a scene doesn't need").
pub const BVH_CROSSOVER: usize = 16;

/// The settings a render runs with, after scene defaults and flags are merged.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub seed: u64,
}

/// Most pixels an image may have (memory for the film and the 8-bit output).
pub const MAX_PIXELS: u64 = 1 << 27;

impl Settings {
    pub fn validate(&self) -> Result<()> {
        for (name, v) in
            [("width", self.width), ("height", self.height), ("spp", self.spp), ("max_depth", self.max_depth)]
        {
            if v == 0 {
                return Err(Error::invalid(name, "must be at least 1"));
            }
        }
        let px = self.width as u64 * self.height as u64;
        if px > MAX_PIXELS {
            return Err(Error::invalid(
                "width x height",
                format!("{}x{} = {px} pixels; at most {MAX_PIXELS} fit in memory", self.width, self.height),
            ));
        }
        if px * self.spp as u64 > u32::MAX as u64 * 1024 {
            return Err(Error::invalid("spp", format!("{} samples per pixel at {px} pixels is too many", self.spp)));
        }
        Ok(())
    }
}

/// The sky as two colours, ready for both kernels.
#[derive(Clone, Copy, Debug)]
pub struct SkyColours {
    pub horizon: [f32; 3],
    pub zenith: [f32; 3],
}

impl From<Sky> for SkyColours {
    fn from(s: Sky) -> Self {
        SkyColours { horizon: s.horizon, zenith: s.zenith }
    }
}

/// Everything the kernels read, laid out for them.
#[derive(Clone, Debug)]
pub struct Prepared {
    pub plan: Plan,
    pub settings: Settings,
    pub spheres: Spheres,
    pub materials: MaterialTables,
    pub camera: Camera,
    pub sky: SkyColours,
    /// Present when the plan chose the BVH.
    pub bvh: Option<Bvh>,
    /// The SIMD kernel walks the BVH with 8-ray packets.
    pub packets: bool,
    /// Russian roulette and adaptive sampling (off unless the render options say so).
    pub estimator: Estimator,
}

impl Prepared {
    pub fn new(scene: &Scene, settings: Settings, accel: AccelChoice) -> Result<Self> {
        scene.validate()?;
        settings.validate()?;
        let mut materials = MaterialTables::default();
        let ids: Vec<(Kind, u32)> = scene.spheres.iter().map(|s| materials.push(&s.material)).collect();
        let spheres = Spheres::new(&scene.spheres, |i| ids[i]);
        let mut kinds: Vec<Kind> = ids.iter().map(|&(k, _)| k).collect();
        kinds.sort();
        kinds.dedup();
        let jitter = settings.spp > 1;
        let camera = Camera::new(&scene.camera, settings.width, settings.height, jitter);
        let use_bvh = match accel {
            AccelChoice::Brute => false,
            AccelChoice::Bvh | AccelChoice::BvhRay => true,
            AccelChoice::Auto => spheres.len >= BVH_CROSSOVER,
        } && scene.mode != Mode::Gradient
            && !spheres.is_empty();
        let bvh = use_bvh.then(|| {
            let c = &scene.camera;
            let extent = c.look_from.iter().fold(0.0f32, |m, x| m.max(x.abs())) + c.lens_radius() as f32;
            Bvh::build(&spheres, extent)
        });
        let packets = accel != AccelChoice::BvhRay;
        let plan = Plan {
            mode: scene.mode,
            kinds: if scene.mode == Mode::Path { kinds.iter().map(|k| k.name()).collect() } else { vec![] },
            lens: camera.lens && scene.mode != Mode::Gradient,
            jitter,
            accel: match (&bvh, packets) {
                (None, _) => "brute force",
                (Some(_), false) => "bvh8, one ray at a time (8-wide nodes)",
                (Some(_), true) => "bvh8, 8-ray packets (scalar kernel: one ray at a time)",
            },
            stop_at_zero_throughput: true,
        };
        let camera = Camera { lens: plan.lens, ..camera };
        Ok(Prepared {
            plan,
            settings,
            spheres,
            materials,
            camera,
            sky: scene.sky.into(),
            bvh,
            packets,
            estimator: Estimator::default(),
        })
    }

    /// The closest hit of one ray (scalar kernel).
    #[inline(always)]
    pub fn closest_hit(&self, o: V3<f32>, d: V3<f32>) -> (u32, f32) {
        match &self.bvh {
            Some(b) => b.closest_hit_scalar(o, d),
            None => closest_hit_scalar(&self.spheres, o, d),
        }
    }

    /// The closest hits of the `n <= 8` rays at `i..i + n` of SoA arrays `o`, `d`
    /// (SIMD kernel): 8 rays per packet against every sphere by brute force, or
    /// one ray at a time through the BVH with 8-wide node and leaf tests.
    #[inline(always)]
    pub fn closest_hits8(&self, o: [&[f32]; 3], d: [&[f32]; 3], i: usize, n: usize) -> ([u32; 8], [f32; 8]) {
        let ld = |v: &[f32]| f32x8::new(v[i..i + 8].try_into().unwrap());
        match &self.bvh {
            Some(b) if self.packets => {
                let o8 = V3::new(ld(o[0]), ld(o[1]), ld(o[2]));
                let d8 = V3::new(ld(d[0]), ld(d[1]), ld(d[2]));
                let (h, t) = b.closest_hit_packet(o8, d8, (1u32 << n) - 1);
                (h.to_array(), t.to_array())
            }
            Some(b) => {
                let mut hit = [crate::geometry::MISS; 8];
                let mut t = [f32::INFINITY; 8];
                for k in 0..n {
                    let j = i + k;
                    (hit[k], t[k]) =
                        b.closest_hit_wide(V3::new(o[0][j], o[1][j], o[2][j]), V3::new(d[0][j], d[1][j], d[2][j]));
                }
                (hit, t)
            }
            None => {
                let o8 = V3::new(ld(o[0]), ld(o[1]), ld(o[2]));
                let d8 = V3::new(ld(d[0]), ld(d[1]), ld(d[2]));
                let (h, t): (u32x8, f32x8) = closest_hit_x8(&self.spheres, o8, d8);
                (h.to_array(), t.to_array())
            }
        }
    }
}
