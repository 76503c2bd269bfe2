//! What a scene needs, decided once before rendering, and the scene prepared
//! for the kernels (SoA spheres, per-kind material tables, the camera).

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::estimator::Estimator;
use crate::geometry::Spheres;
use crate::material::MaterialTables;
use crate::scene::{Kind, Mode, Scene, Sky};
use serde::Serialize;

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
        let kinds = if self.kinds.is_empty() {
            "none".to_string()
        } else {
            self.kinds.join(", ")
        };
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
        for (name, v) in [
            ("width", self.width),
            ("height", self.height),
            ("spp", self.spp),
            ("max_depth", self.max_depth),
        ] {
            if v == 0 {
                return Err(Error::invalid(name, "must be at least 1"));
            }
        }
        let px = self.width as u64 * self.height as u64;
        if px > MAX_PIXELS {
            return Err(Error::invalid(
                "width x height",
                format!(
                    "{}x{} = {px} pixels; at most {MAX_PIXELS} fit in memory",
                    self.width, self.height
                ),
            ));
        }
        if px * self.spp as u64 > u32::MAX as u64 * 1024 {
            return Err(Error::invalid(
                "spp",
                format!("{} samples per pixel at {px} pixels is too many", self.spp),
            ));
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
        SkyColours {
            horizon: s.horizon,
            zenith: s.zenith,
        }
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
    /// Russian roulette and adaptive sampling (off unless the render options say so).
    pub estimator: Estimator,
}

impl Prepared {
    pub fn new(scene: &Scene, settings: Settings) -> Result<Self> {
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
        let plan = Plan {
            mode: scene.mode,
            kinds: if scene.mode == Mode::Path {
                kinds.iter().map(|k| k.name()).collect()
            } else {
                vec![]
            },
            lens: camera.lens && scene.mode != Mode::Gradient,
            jitter,
            accel: "brute force",
            stop_at_zero_throughput: true,
        };
        let camera = Camera {
            lens: plan.lens,
            ..camera
        };
        Ok(Prepared {
            plan,
            settings,
            spheres,
            materials,
            camera,
            sky: scene.sky.into(),
            estimator: Estimator::default(),
        })
    }
}
