//! rtow: a data-oriented path tracer for the scenes of *Ray Tracing in One
//! Weekend*, fast and bit-exact: a scalar reference kernel and a SIMD
//! wavefront kernel (8 or 16 lanes, structure-of-arrays, a queue per material
//! kind) render the same image, bit for bit, for a seed.
//!
//! # Use
//!
//! A scene (built in code, a preset, or a JSON / TOML file), resolved once
//! with overrides and options into a [`Job`], rendered into an [`Image`]:
//!
//! ```ignore
#![doc = include_str!("../tests/suite/front_page.rs")]
//! ```
//!
//! (The test suite runs this example as it is: `tests/suite/front_page.rs`.)
//!
//! Past one machine, a job renders a shard of its samples or rows into a
//! partial film, and films merge into exactly the one-process image
//! ([`shard`]). Writing several outputs as one transaction: [`output`].
//! Triangle meshes (icospheres, Wavefront OBJ files read and written): [`mesh`].
//!
//! # Speed needs the build's instruction set
//!
//! SIMD code is chosen at compile time. rtow's own `.cargo/config.toml` sets
//! `target-cpu=native`, but a crate that depends on rtow builds with its own
//! flags: set them in *your* `.cargo/config.toml` (or `RUSTFLAGS`), e.g.
//!
//! ```toml
//! [target.x86_64-unknown-linux-gnu]
//! rustflags = ["-C", "target-cpu=native"]   # or x86-64-v3 (AVX2), x86-64-v4 (AVX-512)
//! ```
//!
//! [`isa()`] says what a build got. Every build renders the same image.
//!
//! # Layout
//!
//! The data flow is the module layout (docs/architecture.md has the picture):
//! the user side ([`scene`]) and the kernel side (camera, plan, geometry,
//! materials, sampling, kernels, film) never import each other; the job
//! module is the bridge that reads both, once per render. The [`instruments`]
//! measure the real renderer through probes; [`internals`] exposes its
//! building blocks to tests, benchmarks and experiments (no stability promise).

mod camera;
mod choice;
mod error;
mod estimator;
pub mod files;
pub mod film;
mod geometry;
mod handle;
mod input;
pub mod instruments;
mod job;
mod kernel;
pub mod limits;
mod material;
mod math;
pub mod mesh;
pub mod output;
mod plan;
mod probe;
pub mod provenance;
mod real;
mod render;
pub mod rounds;
mod sampling;
pub mod scene;
mod settings;
pub mod shard;
mod texture;
mod vec3;

pub use choice::{AccelChoice, EstimatorChoice, KernelChoice, Mode, OnInterrupt, OnRejected};
pub use error::{Error, Result};
pub use estimator::{Adaptive, Roulette, ADAPTIVE_MIN_SPP, ROULETTE_AFTER_RAYS};
pub use film::Image;
pub use job::{Job, Overrides, RenderOptions, DEFAULT_TILE, IMAGES_ENV};
pub use kernel::{build_description, isa, Kernel, HAS_SIMD16};
pub use render::{
    render, render_counted, render_crop, render_features, render_probed, AovReport, Crop, Progress, Rendered, Stats,
    WORKER_STACK,
};
pub use sampling::Sampler;
pub use scene::{Scene, SceneSource};
pub use settings::Settings;

/// The renderer's building blocks, for tests, benchmarks and experiments: the
/// geometry and its BVH, the materials' scatter functions, the samplers, the
/// kernels, the numeric interface. Not a stable API.
pub mod internals {
    pub mod camera {
        pub use crate::camera::*;
    }
    pub mod estimator {
        pub use crate::estimator::*;
    }
    pub mod geometry {
        pub use crate::geometry::*;
    }
    pub mod handle {
        pub use crate::handle::*;
    }
    pub mod kernel {
        pub use crate::kernel::*;
    }
    pub mod material {
        pub use crate::material::*;
    }
    pub mod math {
        pub use crate::math::*;
    }
    pub mod plan {
        pub use crate::plan::*;
    }
    pub mod real {
        pub use crate::real::*;
    }
    pub mod sampling {
        pub use crate::sampling::*;
    }
    pub mod texture {
        pub use crate::texture::*;
    }
    pub mod vec3 {
        pub use crate::vec3::*;
    }
}
