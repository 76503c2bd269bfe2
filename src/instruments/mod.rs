//! The instruments that measure the renderer: [`bench`](mod@bench) (rays/s and
//! work per kernel, baselines), [`stress`] (numerical stress against an f64
//! oracle) and [`converge`] (run time against error). They drive the real
//! kernels, observing them through [`probe`]s; none keeps a copy of a kernel.
//! [`diff`] measures images instead: how far one is from another (MSE,
//! relMSE, FLIP, region z-tests). [`trace`] prints one pixel's paths, event by event.

pub mod bench;
pub mod callgrind;
pub mod converge;
pub mod diff;
pub mod instructions;
pub mod noise;
pub mod stress;
pub mod trace;

/// Probes: what the kernels let an instrument see (a type parameter with
/// empty inlined methods, `()` for a plain render).
pub mod probe {
    pub use crate::probe::*;
}
