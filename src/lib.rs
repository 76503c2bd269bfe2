//! rtow: a data-oriented path tracer for the scenes of *Ray Tracing in One Weekend*.
//!
//! Data flow, one module each (the README's code map):
//!
//! ```text
//! scene (user-facing, validated) + settings (resolved once: scene + flags)
//!   -> prepare -> plan::Prepared (a typed Plan, SoA spheres, material tables, camera, BVH)
//!   -> render (tiles over rayon) -> kernel::scalar | kernel::wavefront<W> (8 or 16 lanes)
//!        (geometry: intersection and BVH; material: scatter; sampling: random streams;
//!         probe: what instruments see)
//!   -> film (per-tile accumulators) -> Image -> output (PNG / PFM / EXR, atomic)
//! ```
//!
//! The kernels are one estimator: every formula is written once over
//! [`real::Real`] and instantiated for `f32`, `wide::f32x8` and `wide::f32x16`,
//! so for the same seed they produce bit-identical images. The instruments in
//! [`tools`] (bench, stress, converge) drive the real kernels through probes.
pub mod camera;
pub mod error;
pub mod estimator;
pub mod film;
pub mod geometry;
pub mod kernel;
pub mod limits;
pub mod material;
pub mod output;
pub mod plan;
pub mod prepare;
pub mod probe;
pub mod real;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod settings;
pub mod shard;
pub mod tools;
pub mod vec3;

pub use error::{Error, Result};
pub use film::Image;
pub use render::{isa, render, Kernel, Rendered, Stats};
pub use scene::Scene;
pub use settings::{AccelChoice, KernelChoice, Overrides, RenderOptions, Settings};

/// The settings a scene asks for (its `render` table, else rtow's defaults).
pub fn default_settings(scene: &Scene) -> Settings {
    Settings::resolve(&scene.render, &Overrides::default())
}
