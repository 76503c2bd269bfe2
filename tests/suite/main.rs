//! rtow's integration tests, one test binary (`cargo test --release` links
//! one binary instead of one per file: each file once took 40-60 s to link
//! with the release profile's LTO). A file per subject; `tests/kernels` holds
//! the kernels' bit-identity, BVH and numerics tests, which CI also runs on the
//! baseline instruction set with debug assertions; `tests/fuzz.rs` stays its
//! own binary for long fuzzing runs.
//!
//! One subject: `cargo test --release --test suite estimator::`.

#[path = "../bad_input/mod.rs"]
mod bad_input;
#[path = "../common/mod.rs"]
mod common;

mod aov;
mod architecture;
mod bench_cli;
mod cli;
mod converge_cli;
mod crop;
mod diff_cli;
mod estimator;
mod film_range;
mod hostile;
mod images;
mod lambertian;
mod lights;
mod materials;
mod media;
mod meshes;
mod motion;
mod nextweek;
mod physics;
mod rounds;
mod sampler;
mod sampler_cli;
mod scene_files;
mod scene_format;
mod schema_cli;
mod set_cli;
mod shards;
mod smooth;
mod split;
mod stability;
mod textures;
mod trust;
