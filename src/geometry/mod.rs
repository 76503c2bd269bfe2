//! Geometry: every primitive kind as structure of arrays, its intersection
//! test written once over `Real` (the scalar kernel and every lane width
//! compute the same bits), and the trees over them.
//!
//! - [`spheres`]: static spheres (a negative radius is the book's hollow
//!   sphere) and their 32-byte shading records; [`intersect`]: the robust
//!   ray-sphere test, the brute-force closest-hit and any-hit loops of every
//!   kind, the surface and where a new ray starts.
//! - [`quads`]: The Next Week's parallelograms, with forms of the test for
//!   quads whose normal lies along an axis or that stand upright about one.
//! - [`cuboids`]: a box (six quads after the search) tested whole, by one
//!   slab test in its own frame.
//! - [`moving`]: spheres whose centre moves over the shutter interval,
//!   tested at each path's time.
//! - [`media`]: constant media (a sphere or box boundary), sampled after the
//!   closest hit; not in a tree.
//! - [`lights`]: the shapes the `book` and `nee-mis` estimators sample
//!   (static spheres and quads), their points and densities.
//! - [`bvh`]: one 8-wide SAH tree per kind (spheres, loose quads, cuboids,
//!   moving spheres), generic over the leaf.
//!
//! One tie order across kinds: hit indices are spheres `i`, then
//! `QUAD_BASE + i` (quads, a cuboid's hit being its face's), then
//! `MOVING_BASE + i`, then `MEDIUM_BASE + k`, below `MISS`; the smallest `t`
//! wins, ties to the lowest index, so brute force and every walk find the
//! same hit bit for bit whatever the order the kinds are searched in.

pub mod bvh;
pub mod cuboids;
pub mod intersect;
pub mod lights;
pub mod media;
pub mod moving;
pub mod quads;
pub mod spheres;

pub use bvh::{Bvh, CuboidBvh, LeafCuboid, LeafMoving, LeafQuad, MovingBvh, QuadBvh, SahCost, Walk};
pub use cuboids::{cuboid_hit, CuboidRec, Cuboids};
pub use intersect::{
    any_cuboid_hit, any_moving_hit, any_quad_hit, any_sphere_hit, closest_cuboid_hit, closest_hit, closest_moving_hit,
    closest_quad_hit, spawn, sphere_disc, sphere_t, surface, Closest, Surface, OFFSET_ULPS,
};
pub use lights::{Emitters, LightQuad, LightSample, LightSphere, Lights};
pub use media::{sample_media, transmittance, Boundary, Media, MEDIUM_BASE};
pub use moving::{centre_at, MovingSpheres, MOVING_BASE};
pub use quads::{quad_hit, quad_hit_axis, quad_hit_general, quad_hit_upright, quad_surface, QuadRec, Quads, QUAD_BASE};
pub use spheres::{Shade, Spheres, MISS};
