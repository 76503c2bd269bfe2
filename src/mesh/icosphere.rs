//! Icospheres (placeholder until the mesh-sources branch lands).
use crate::error::{Error, Result};
use std::collections::HashMap;

fn unit(v: [f64; 3]) -> [f64; 3] {
    let l = ((v[0] * v[0] + v[1] * v[1]) + v[2] * v[2]).sqrt();
    [v[0] / l, v[1] / l, v[2] / l]
}

pub type UnitMesh = (Vec<[f64; 3]>, Vec<[u32; 3]>);

pub fn unit_icosphere(level: u32) -> Result<UnitMesh> {
    if level > crate::limits::MAX_ICOSPHERE_LEVEL {
        return Err(Error::invalid("level", "too fine"));
    }
    let p = (1.0 + 5f64.sqrt()) / 2.0;
    let base = [
        [-1.0, p, 0.0],
        [1.0, p, 0.0],
        [-1.0, -p, 0.0],
        [1.0, -p, 0.0],
        [0.0, -1.0, p],
        [0.0, 1.0, p],
        [0.0, -1.0, -p],
        [0.0, 1.0, -p],
        [p, 0.0, -1.0],
        [p, 0.0, 1.0],
        [-p, 0.0, -1.0],
        [-p, 0.0, 1.0],
    ];
    let mut v: Vec<[f64; 3]> = base.iter().map(|&b| unit(b)).collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(f.len() * 4);
        for &[a, b, c] in &f {
            let mut m = |x: u32, y: u32| -> u32 {
                *mid.entry((x.min(y), x.max(y))).or_insert_with(|| {
                    let (p, q) = (v[x as usize], v[y as usize]);
                    v.push(unit([(p[0] + q[0]) * 0.5, (p[1] + q[1]) * 0.5, (p[2] + q[2]) * 0.5]));
                    v.len() as u32 - 1
                })
            };
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    Ok((v, f))
}

pub fn place(unit: &[[f64; 3]], center: [f32; 3], radius: f32) -> Vec<[f32; 3]> {
    let (c, r) = (center.map(f64::from), radius as f64);
    unit.iter().map(|u| std::array::from_fn(|i| (c[i] + r * u[i]) as f32)).collect()
}
