//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod stats;

use rtow::AccelChoice;
use rtow::{render, Image, KernelChoice, RenderOptions, Scene, Settings};

pub fn settings(width: u32, height: u32, spp: u32, max_depth: u32, seed: u64) -> Settings {
    Settings { width, height, spp, max_depth, seed }
}

pub fn render_with(scene: &Scene, s: Settings, kernel: KernelChoice, threads: usize, tile: u32) -> rtow::Rendered {
    render_accel(scene, s, kernel, threads, tile, AccelChoice::Auto)
}

pub fn render_accel(
    scene: &Scene,
    s: Settings,
    kernel: KernelChoice,
    threads: usize,
    tile: u32,
    accel: AccelChoice,
) -> rtow::Rendered {
    render(scene, s, RenderOptions { kernel, threads: Some(threads), tile, accel, ..Default::default() }, None)
        .expect("render")
}

pub fn image(scene: &Scene, s: Settings, kernel: KernelChoice) -> Image {
    render_with(scene, s, kernel, 2, 16).image
}

/// Asserts bit-identical images, naming the first differing pixel.
pub fn assert_identical(a: &Image, b: &Image, what: &str) {
    assert_eq!((a.width, a.height), (b.width, b.height), "{what}: sizes differ");
    for (i, (p, q)) in a.data.iter().zip(&b.data).enumerate() {
        let (pb, qb) = (p.map(f32::to_bits), q.map(f32::to_bits));
        assert!(pb == qb, "{what}: pixel ({}, {}) differs: {p:?} vs {q:?}", i as u32 % a.width, i as u32 / a.width);
    }
}
