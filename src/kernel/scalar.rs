//! The reference path tracer: one path at a time, iterative, straightforward.
//! Every formula comes from the width-generic modules, instantiated at `f32`.

use super::{normal_colour, sky, Counters};
use crate::estimator::{roulette, roulette_applies};
use crate::film::TileFilm;
use crate::geometry::{spawn, surface, MISS};
use crate::material::{dielectric, lambertian, metal};
use crate::plan::Prepared;
use crate::sampling::ScalarStream;
use crate::scene::{Kind, Mode};
use crate::vec3::V3;

/// Renders every sample of every pixel of `tile`, in sample order. With
/// adaptive sampling a pixel stops at the first decision point where its
/// error estimate is low enough.
pub fn render_tile(prep: &Prepared, tile: &mut TileFilm, counters: &mut Counters) {
    let s = &prep.settings;
    let est = &prep.estimator;
    for local in 0..tile.sum.len() {
        let (x, y) = tile.pixel_of(local);
        let pixel = y as u64 * s.width as u64 + x as u64;
        let mut done = 0;
        while done < s.spp {
            let end = est.round_end(done, s.spp);
            for sample in done..end {
                let mut rng = ScalarStream::for_path(s.seed, pixel, sample as u64);
                let c = trace(prep, x, y, &mut rng, counters);
                tile.add(local, c);
            }
            done = end;
            if done < s.spp && est.adaptive.is_some_and(|a| a.converged(tile, local)) {
                break;
            }
        }
    }
}

/// The radiance of one path through pixel (x, y).
pub fn trace(prep: &Prepared, x: u32, y: u32, rng: &mut ScalarStream, counters: &mut Counters) -> [f32; 3] {
    let sp = &prep.spheres;
    let (mut o, mut d) = prep.camera.ray(x as f32, y as f32, rng);
    let mut thr = V3::new(1.0f32, 1.0, 1.0);
    for depth in 0..prep.settings.max_depth {
        counters.rays += 1;
        let (hit, t) = prep.closest_hit(o, d);
        if hit == MISS {
            return thr.mul_elem(sky(&prep.sky, d)).to_array();
        }
        let i = hit as usize;
        let srf = surface(o, d, t, V3::new(sp.cx[i], sp.cy[i], sp.cz[i]), sp.r[i]);
        let row = sp.row[i] as usize;
        match prep.plan.mode {
            Mode::Normals => return normal_colour(srf.n).to_array(),
            Mode::Flat => return prep.materials.flat_colour(sp.kind[i], sp.row[i]),
            _ => {}
        }
        let m = &prep.materials;
        let (dir, atten) = match sp.kind[i] {
            k if k == Kind::Lambertian as u8 => (lambertian(srf.n, rng), m.lambertian[row]),
            k if k == Kind::Metal as u8 => {
                let (albedo, fuzz) = m.metal[row];
                let (dir, alive) = metal(d, srf.n, fuzz, rng);
                if !alive {
                    return [0.0; 3];
                }
                (dir, albedo)
            }
            _ => (dielectric(d, srf.n, srf.front, m.dielectric[row], rng), [1.0; 3]),
        };
        thr = thr.mul_elem(V3::from_array(atten));
        if thr.x == 0.0 && thr.y == 0.0 && thr.z == 0.0 {
            return [0.0; 3];
        }
        if roulette_applies(&prep.estimator, depth + 1) {
            let (t, survives) = roulette(thr, rng);
            if !survives {
                return [0.0; 3];
            }
            thr = t;
        }
        o = spawn(&srf, dir);
        d = dir;
    }
    [0.0; 3]
}
