//! Spheres as structure-of-arrays, padded to a power of two (at least 8),
//! and their shading records.

use crate::material::{Kind, MaterialTables};

/// The sphere index of "no hit".
pub const MISS: u32 = u32::MAX;

#[derive(Clone, Debug, Default)]
pub struct Spheres {
    pub cx: Vec<f32>,
    pub cy: Vec<f32>,
    pub cz: Vec<f32>,
    /// Signed radius (negative: normal flipped inwards).
    pub r: Vec<f32>,
    /// `r * r`; padding has -1, which no ray can hit (disc = -1 - |l|^2 < 0).
    pub r2: Vec<f32>,
    /// Material kind of each sphere.
    pub kind: Vec<Kind>,
    /// Row of the sphere's material in its kind's table.
    pub row: Vec<u32>,
    /// Number of real spheres; the arrays are longer (padding).
    pub len: usize,
    /// Per sphere (padding included), what shading reads: [`Shade`]. Filled
    /// by [`Spheres::shade_with`] once the materials are known; empty before.
    pub shade: Vec<Shade>,
}

/// What shading reads of a hit sphere, in one aligned 32-byte record, so
/// that a packet's records load as one vector each and transpose into lanes
/// ([`crate::real::Wide::gather_rows8`]): the centre, the signed radius and
/// the material's parameters: the albedo (white for a dielectric) and the
/// fuzz of a metal or the index of refraction of a dielectric (0 for a
/// lambertian). The values are copies of the scene's f32s, so shading from
/// them computes what shading from the SoA arrays and the material tables does.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub struct Shade(pub [f32; 8]);

impl Shade {
    pub const CX: usize = 0;
    pub const CY: usize = 1;
    pub const CZ: usize = 2;
    pub const R: usize = 3;
    pub const ALBEDO: usize = 4;
    /// The metal's fuzz, the dielectric's index of refraction.
    pub const PARAM: usize = 7;
}

impl AsRef<[f32; 8]> for Shade {
    #[inline(always)]
    fn as_ref(&self) -> &[f32; 8] {
        &self.0
    }
}

impl Spheres {
    /// Appends a sphere: centre, signed radius, and its material's (kind, row).
    pub fn push(&mut self, center: [f32; 3], radius: f32, kind: Kind, row: u32) {
        self.cx.push(center[0]);
        self.cy.push(center[1]);
        self.cz.push(center[2]);
        self.r.push(radius);
        self.r2.push(radius * radius);
        self.kind.push(kind);
        self.row.push(row);
        self.len += 1;
    }

    /// Pads the arrays to a power of two, at least 8, with spheres no ray can
    /// hit: a sphere index masked with `len - 1` is then in bounds by
    /// construction, and for the real spheres' indices the mask changes
    /// nothing (the wavefront's lookups by hit index need no bounds checks).
    pub fn pad(&mut self) {
        let target = self.cx.len().max(8).next_power_of_two();
        while self.cx.len() < target {
            let n = self.len;
            self.push([0.0; 3], 0.0, Kind::Lambertian, 0);
            self.r2[n] = -1.0;
            self.len = n;
        }
    }

    /// One sphere (tests and the stress sweeps).
    pub fn one(center: [f32; 3], radius: f32) -> Spheres {
        let mut s = Spheres::default();
        s.push(center, radius, Kind::Lambertian, 0);
        s.pad();
        s
    }

    /// Moves sphere `i` (tests and the stress sweeps).
    pub fn set(&mut self, i: usize, center: [f32; 3], radius: f32) {
        (self.cx[i], self.cy[i], self.cz[i]) = (center[0], center[1], center[2]);
        self.r[i] = radius;
        self.r2[i] = radius * radius;
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Fills [`Spheres::shade`] from the material tables (after [`Spheres::pad`]).
    pub fn shade_with(&mut self, m: &MaterialTables) {
        self.shade = (0..self.cx.len())
            .map(|i| {
                let (albedo, param) = if i < self.len { m.record(self.kind[i], self.row[i]) } else { ([0.0; 3], 0.0) };
                let [a0, a1, a2] = albedo;
                Shade([self.cx[i], self.cy[i], self.cz[i], self.r[i], a0, a1, a2, param])
            })
            .collect();
    }
}
