//! Geometry: spheres as structure-of-arrays and the ray-sphere intersection.

pub mod bvh;
pub mod intersect;
pub mod spheres;

pub use bvh::{Bvh, SahCost, Walk};
pub use intersect::{closest_hit, spawn, sphere_disc, sphere_t, surface, Closest, Surface, OFFSET_ULPS};
pub use spheres::{Shade, Spheres, MISS};
