//! The kernels' tests, one binary: lanes against one lane (`lanes`), bit-identical images across kernels,
//! widths and accelerators (`equivalence`), the BVH against brute force
//! (`bvh`), the width-generic numerics against f64 (`math`), triangles
//! against an f64 oracle, watertight, and their tree (`triangles`). CI runs them
//! also on the baseline instruction set (SSE2) with debug assertions on.

#[path = "../common/mod.rs"]
mod common;

mod bvh;
mod equivalence;
mod lanes;
mod math;
mod triangles;
