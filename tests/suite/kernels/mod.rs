//! The kernels' tests: lanes against one lane (`lanes`), bit-identical
//! images across kernels, widths and accelerators (`equivalence`), the BVH
//! against brute force (`bvh`), the width-generic numerics against f64
//! (`math`), triangles against an f64 oracle, watertight, and their tree
//! (`triangles`). CI also runs them on the baseline instruction set (SSE2)
//! with debug assertions on: the suite built with `--cfg rtow_kernel_tests`
//! holds these alone (`main.rs`).

mod bvh;
mod equivalence;
mod lanes;
mod math;
mod triangles;
