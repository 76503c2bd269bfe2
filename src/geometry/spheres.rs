//! Spheres as structure-of-arrays, padded to a multiple of 8.

use crate::scene::{Kind, Sphere};

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
    /// Material kind of each sphere (`Kind as u8`).
    pub kind: Vec<u8>,
    /// Row of the sphere's material in its kind's table.
    pub row: Vec<u32>,
    /// Number of real spheres; the arrays are longer (padding).
    pub len: usize,
}

impl Spheres {
    /// Lays out `spheres`, given each one's (kind, row) in the material tables.
    pub fn new(spheres: &[Sphere], material_of: impl Fn(usize) -> (Kind, u32)) -> Self {
        let n = spheres.len();
        let padded = n.div_ceil(8) * 8;
        let mut s = Spheres {
            cx: Vec::with_capacity(padded),
            cy: Vec::with_capacity(padded),
            cz: Vec::with_capacity(padded),
            r: Vec::with_capacity(padded),
            r2: Vec::with_capacity(padded),
            kind: Vec::with_capacity(padded),
            row: Vec::with_capacity(padded),
            len: n,
        };
        for (i, sp) in spheres.iter().enumerate() {
            let (kind, row) = material_of(i);
            s.cx.push(sp.center[0]);
            s.cy.push(sp.center[1]);
            s.cz.push(sp.center[2]);
            s.r.push(sp.radius);
            s.r2.push(sp.radius * sp.radius);
            s.kind.push(kind as u8);
            s.row.push(row);
        }
        for _ in n..padded {
            s.cx.push(0.0);
            s.cy.push(0.0);
            s.cz.push(0.0);
            s.r.push(0.0);
            s.r2.push(-1.0);
            s.kind.push(Kind::Lambertian as u8);
            s.row.push(0);
        }
        s
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}
