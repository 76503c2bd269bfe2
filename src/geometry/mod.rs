//! Geometry: spheres as structure-of-arrays and the ray-sphere intersection.

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
