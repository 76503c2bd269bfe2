//! The instruments that measure the renderer: `bench` (rays/s and work per
//! kernel, baselines), `stress` (numerical stress against an f64 oracle) and
//! `converge` (run time against error). They drive the real kernels, observing
//! them through probes ([`crate::kernel::probe`]); none keeps a copy of a kernel.

pub mod bench;
pub mod converge;
pub mod stress;
