//! The kernels' tests: lanes against one lane (`lanes`), bit-identical
//! images across kernels, widths and accelerators (`equivalence`), the BVH
//! against brute force (`bvh`), the width-generic numerics against f64
//! (`math`), triangles against an f64 oracle, watertight, and their tree
//! (`triangles`), instanced meshes' tree, hits and self-hits
//! (`instances`). CI also runs them on the baseline instruction set (SSE2),
//! unoptimized, with debug assertions on: the suite built with `--cfg
//! rtow_kernel_tests` holds these alone (`main.rs`).

mod bvh;
mod equivalence;
mod instances;
mod lanes;
mod math;
mod triangles;

use rtow::internals::real::Wide;
use rtow::internals::vec3::V3;

/// The rays of `chunk` (at most `W::LANES`) as one packet, the last ray
/// repeated in the lanes past them.
fn packet<W: Wide>(chunk: &[(V3<f32>, V3<f32>)]) -> (V3<W>, V3<W>) {
    let at = |k: usize| chunk[k.min(chunk.len() - 1)];
    let o = V3::new(W::from_fn(|k| at(k).0.x), W::from_fn(|k| at(k).0.y), W::from_fn(|k| at(k).0.z));
    let d = V3::new(W::from_fn(|k| at(k).1.x), W::from_fn(|k| at(k).1.y), W::from_fn(|k| at(k).1.z));
    (o, d)
}
