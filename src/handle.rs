//! Handles: how the kernel side names a material without holding it. A
//! primitive's material is the handle `(Kind, row)`: the kind picks the
//! material's table and its wavefront queue and pass (one each per kind),
//! the row its place in that kind's table (`material::MaterialTables`).
//! Geometry stores the handle per primitive, as structure of arrays beside
//! the shapes (the wavefront's classification reads a packet's kinds by hit
//! index, one byte each), and needs nothing else of materials; the material
//! module holds the tables a handle indexes and the scatter functions, the
//! kernels dispatch on the kind. This module imports nothing.

/// The kind of a primitive's material: which kind's table its row indexes,
/// and its wavefront queue (one per kind).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum Kind {
    Lambertian = 0,
    Metal = 1,
    Dielectric = 2,
    /// The Next Week's `diffuse_light`: emission, and the path ends (no scatter).
    DiffuseLight = 3,
    /// The Next Week's `isotropic`: a path that stopped inside a constant
    /// medium scatters to a uniform direction, attenuated by the medium's
    /// albedo. Media are not primitives: no sphere or quad has this kind.
    Isotropic = 4,
}

impl Kind {
    pub const ALL: [Kind; 5] = [Kind::Lambertian, Kind::Metal, Kind::Dielectric, Kind::DiffuseLight, Kind::Isotropic];
    /// The kinds a sphere or a quad can have (all but `Isotropic`).
    pub const SURFACES: [Kind; 4] = [Kind::Lambertian, Kind::Metal, Kind::Dielectric, Kind::DiffuseLight];
    pub fn name(self) -> &'static str {
        match self {
            Kind::Lambertian => "lambertian",
            Kind::Metal => "metal",
            Kind::Dielectric => "dielectric",
            Kind::DiffuseLight => "diffuse_light",
            Kind::Isotropic => "isotropic",
        }
    }
}
