//! Geometry: every primitive kind as structure of arrays, its intersection
//! test written once over `Real` (the scalar kernel and every lane width
//! compute the same bits), the trees over them and the one aggregate that
//! searches them all.
//!
//! - [`hit`]: hit indices (a kind's range and the primitive's index in it)
//!   and the closest-hit rule every search uses; [`work`]: what a search
//!   counts; [`slab`]: rays against boxes; [`surface`]: the hit surface and
//!   where a new ray starts.
//! - [`primitive`]: what a kind gives the searches ([`Primitive`], [`Leaf`]).
//! - The kinds, a file each: [`spheres`] (static spheres, a negative radius
//!   the book's hollow sphere, and the robust ray-sphere test), [`quads`]
//!   (The Next Week's parallelograms, with forms of the test for quads whose
//!   normal lies along an axis or that stand upright about one), [`cuboids`]
//!   (a box, six quads after the search, tested whole by one slab test in
//!   its own frame), [`moving`] (spheres whose centre moves over the
//!   shutter interval, tested at each path's time), [`triangles`] (meshes'
//!   triangles in world space, a watertight test; a hit's surface is a
//!   quad's on the triangle's plane), [`instances`] (a mesh several
//!   groups place, held once in its own frame with its tree, each
//!   placement a turn and a move). A primitive carries its
//!   material's handle (`handle::Kind` and a row) and nothing else of
//!   materials: the tables it indexes, and the shading, live above.
//! - [`bvh`]: an 8-wide SAH tree over any kind, its one walk written once for
//!   one ray and for packets; [`shapes`]: every kind and its tree, searched
//!   in one closest-hit and one any-hit search.
//! - [`media`]: constant media (a sphere or box boundary), sampled after the
//!   closest hit; not in a tree. [`lights`]: the shapes the `book` and
//!   `nee-mis` estimators sample (static spheres and quads, and meshes:
//!   [`light_mesh`]), their points and densities, and what a light emits
//!   toward a ray (front face or both).

pub mod bvh;
pub mod cuboids;
pub mod hit;
pub mod instances;
pub mod light_mesh;
pub mod lights;
pub mod media;
pub mod moving;
pub mod primitive;
pub mod quads;
pub mod shapes;
pub mod slab;
pub mod smooth;
pub mod spheres;
pub mod surface;
pub mod triangles;
pub mod work;

pub use bvh::{Bvh, SahCost, Walk, Walker};
pub use cuboids::{cuboid_hit, CuboidRec, Cuboids, LeafCuboid};
pub use hit::{Closest, Hit, HitKind, INSTANCE_BASE, MEDIUM_BASE, MISS, MOVING_BASE, QUAD_BASE, TRIANGLE_BASE};
pub use instances::{Instances, LeafInstance, SharedMesh};
pub use light_mesh::LightMesh;
pub use lights::{emission, Emitters, LightQuad, LightSample, LightSphere, Lights};
pub use media::{sample_media, transmittance, Boundary, Media};
pub use moving::{centre_at, LeafMoving, MovingSpheres};
pub use primitive::{closest_brute, Leaf, Primitive};
pub use quads::{quad_hit, quad_hit_axis, quad_hit_general, quad_hit_upright, quad_surface, LeafQuad, QuadRec, Quads};
pub use shapes::{Shapes, TreeChoice, Trees};
pub use smooth::{below, shading_normal, Smooth};
pub use spheres::{sphere_disc, sphere_t, surface, LeafSphere, Shade, Spheres};
pub use surface::{spawn, Surface, OFFSET_ULPS};
pub use triangles::{triangle_hit, LeafTriangle, Projection, Triangles};
pub use work::{Counter, Work, WorkTally};
