//! rtow's integration tests, one test binary (`cargo test --release` links
//! one binary instead of one per file: under the release profile's LTO each
//! test binary optimizes the whole library again at its link, 40-90 s
//! each). A file per subject; `kernels` holds the kernels' bit-identity, BVH
//! and numerics tests, which CI also runs on the baseline instruction set
//! with debug assertions: built with `RUSTFLAGS="--cfg rtow_kernel_tests"`,
//! the suite holds them alone (and leaves out the dev-dependencies only the
//! other subjects use: Cargo.toml). `tests/memory.rs` runs the binary alone.
//! `fuzz` is the fuzzer: `cargo test` runs it 3 seconds a target, a long run
//! `RTOW_FUZZ_SECS=3600 cargo test --release --test suite fuzz::`.
//!
//! One subject: `cargo test --release --test suite estimator::`.

#[path = "../common/mod.rs"]
mod common;
mod kernels;

#[cfg(not(rtow_kernel_tests))]
#[path = "../bad_input/mod.rs"]
mod bad_input;

/// The library's front-page example, which `src/lib.rs` shows as it is (a
/// doctest would link the whole library once more under the release
/// profile's LTO: 20 s of the test command).
#[cfg(not(rtow_kernel_tests))]
mod front_page {
    include!("front_page.rs");

    #[test]
    fn the_front_page_example_runs() {
        main().unwrap();
    }
}

/// The subjects beyond the kernels, left out of the baseline build.
macro_rules! subjects {
    ($($subject:ident),* $(,)?) => {
        $(
            #[cfg(not(rtow_kernel_tests))]
            mod $subject;
        )*
    };
}

subjects!(
    aov,
    architecture,
    bench_cli,
    cli,
    converge_cli,
    crop,
    diff_cli,
    estimator,
    film_range,
    fuzz,
    hostile,
    images,
    instances,
    lambertian,
    lights,
    materials,
    media,
    meshes,
    motion,
    nextweek,
    physics,
    rounds,
    sampler,
    sampler_cli,
    scene_files,
    scene_format,
    schema_cli,
    set_cli,
    shards,
    smooth,
    split,
    stability,
    textures,
    trust,
);
