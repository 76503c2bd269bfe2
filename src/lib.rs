//! rtow: a data-oriented path tracer for the scenes of *Ray Tracing in One Weekend*.
//!
//! Data flow (see the README): [`scene::Scene`] (validated, from a preset or a
//! file) -> [`plan::Prepared`] (SoA spheres, per-kind material tables, a
//! [`plan::Plan`] of what the scene needs) -> [`render::render`] (tiles over
//! rayon, the scalar reference kernel or the SIMD wavefront kernel) ->
//! [`film::Image`] (linear f32, PNG / PFM / EXR) and [`render::Stats`].
//!
//! The two kernels are one estimator: every formula is written once over
//! [`real::Real`] and instantiated for `f32` and `wide::f32x8`, so for the same
//! seed they produce bit-identical images.

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
pub mod real;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod tools;
pub mod vec3;

pub use error::{Error, Result};
pub use film::Image;
pub use kernel::KernelKind;
pub use plan::Settings;
pub use render::{isa, render, RenderOptions, Rendered, Stats};
pub use scene::Scene;

/// The settings a scene asks for (its `render` table, else the book's defaults),
/// with `spp` etc. still overridable by the caller.
pub fn default_settings(scene: &Scene) -> Settings {
    let r = scene.render;
    Settings {
        width: r.width.unwrap_or(400),
        height: r.height.unwrap_or(225),
        spp: r.samples_per_pixel.unwrap_or(32),
        max_depth: r.max_depth.unwrap_or(50),
        seed: r.seed.unwrap_or(0),
    }
}
