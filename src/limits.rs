//! Documented bounds on what one run may ask for. Each protects memory or time
//! and is checked before any work, with the bound named in the error message.

/// Most pixels an image may have (memory for the film and the 8-bit output:
/// about 30 bytes a pixel, 4 GB at the limit).
pub const MAX_PIXELS: u64 = 1 << 27;

/// Most spheres a scene may have (the SoA index is a u32 and memory is finite).
pub const MAX_SPHERES: usize = 1 << 24;

/// Largest tile edge in pixels: a tile's paths must fit one wavefront workspace.
pub const MAX_TILE: u32 = 45;
