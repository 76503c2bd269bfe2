//! Geometry: spheres as structure-of-arrays and the ray-sphere intersection.

pub mod bvh;
pub mod intersect;
pub mod spheres;

pub use bvh::Bvh;
pub use intersect::{closest_hit_scalar, closest_hit_x8, spawn, sphere_disc, sphere_t, surface, Surface};
pub use spheres::{Spheres, MISS};
