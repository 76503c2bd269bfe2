//! Spheres as structure-of-arrays, padded to a multiple of 8.

use crate::material::Kind;

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

    /// Pads the arrays to a multiple of 8 with spheres no ray can hit.
    pub fn pad(&mut self) {
        while !self.cx.len().is_multiple_of(8) {
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
}
