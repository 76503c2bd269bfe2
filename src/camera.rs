//! Camera rays for both widths: the book's positionable thin-lens camera,
//! prepared from a [`View`] (the scene's camera in f64; the job module builds it).

use crate::error::{Error, Result};
use crate::real::Real;
use crate::sampling::{in_unit_disk, layout, Stream};
use crate::vec3::V3;
use glam::DVec3;

/// The camera, prepared for an image size. The basis is computed in f64 and
/// rounded once. Pixel positions are kept relative to the eye, so a camera far
/// from the origin loses no precision in its ray directions.
#[derive(Clone, Copy, Debug)]
pub struct PreparedCamera {
    pub center: [f32; 3],
    /// Upper-left pixel centre minus the eye (on the focus plane).
    pub to_pixel00: [f32; 3],
    /// One pixel to the right / one pixel down, on the focus plane.
    pub du: [f32; 3],
    pub dv: [f32; 3],
    /// Lens disk radius vectors (zero for a pinhole).
    pub lens_u: [f32; 3],
    pub lens_v: [f32; 3],
    /// Sample the lens (the plan turns this off for pinhole cameras).
    pub lens: bool,
    /// Jitter samples uniformly inside the pixel's square (off for 1 spp: centres).
    pub jitter: bool,
}

fn f3(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

/// Where the camera is and what it sees, in f64 (built from the scene's camera).
#[derive(Clone, Copy, Debug)]
pub struct View {
    pub look_from: DVec3,
    pub look_at: DVec3,
    pub vup: DVec3,
    pub vfov_deg: f64,
    /// Distance to the plane in focus.
    pub focus_dist: f64,
    /// Lens disk radius (0: pinhole).
    pub lens_radius: f64,
}

impl PreparedCamera {
    pub fn new(view: &View, width: u32, height: u32, jitter: bool) -> Self {
        let (from, at, vup) = (view.look_from, view.look_at, view.vup);
        let focus = view.focus_dist;
        let h = view.vfov_deg.to_radians() / 2.0;
        let vh = 2.0 * h.tan() * focus;
        let vw = vh * width as f64 / height as f64;
        let w = (from - at).normalize();
        let u = vup.cross(w).normalize();
        let v = w.cross(u);
        let du = u * vw / width as f64;
        let dv = -v * vh / height as f64;
        let upper_left = -(focus * w) - (u * vw) / 2.0 + (v * vh) / 2.0;
        let to00 = upper_left + 0.5 * (du + dv);
        let lr = view.lens_radius;
        PreparedCamera {
            center: f3(from),
            to_pixel00: f3(to00),
            du: f3(du),
            dv: f3(dv),
            lens_u: f3(u * lr),
            lens_v: f3(v * lr),
            lens: lr > 0.0,
            jitter,
        }
    }

    /// Checks that the f32 camera of `view` is computable for every image
    /// size rtow accepts (1x1 up to `MAX_PIXELS` on a side): every vector
    /// finite, the pixel steps and the eye-relative pixel grid non-zero, and
    /// the squared length of a ray's unnormalized direction a normal f32 (the
    /// ray direction is normalized in f32). A backstop behind the range checks
    /// of the scene's validation.
    pub fn check(view: &View) -> Result<()> {
        let big = crate::limits::MAX_PIXELS as u32;
        for (w, h) in [(1, 1), (big, 1), (1, big)] {
            let cam = PreparedCamera::new(view, w, h, true);
            let vecs = [cam.center, cam.to_pixel00, cam.du, cam.dv, cam.lens_u, cam.lens_v];
            let len2 = |v: [f32; 3]| v.iter().map(|&x| x as f64 * x as f64).sum::<f64>();
            let ok = vecs.iter().flatten().all(|x| x.is_finite())
                && [cam.du, cam.dv].iter().all(|v| len2(*v) > 0.0)
                && len2(cam.to_pixel00) >= (f32::MIN_POSITIVE as f64) * 2f64.powi(24);
            if !ok {
                return Err(Error::invalid(
                    "camera",
                    format!(
                        "look_from, look_at, vfov_deg and the focus distance give no camera the f32 kernels can \
                         represent at {w}x{h} pixels (pixel step {:?}, grid {:?})",
                        cam.du, cam.to_pixel00
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The ray through pixel (`px`, `py`) (integer coordinates, as reals):
    /// `(origin, unit direction)`. Draws 2 values for jitter and 2 for the lens
    /// when those are on (dimensions `layout::PIXEL` and `layout::LENS`).
    #[inline(always)]
    pub fn ray<R: Real, S: Stream<R>>(&self, px: R, py: R, rng: &mut S) -> (V3<R>, V3<R>) {
        let (sx, sy) = if self.jitter {
            rng.seek(layout::PIXEL);
            let jx = rng.next() - R::splat(0.5);
            let jy = rng.next() - R::splat(0.5);
            (px + jx, py + jy)
        } else {
            (px, py)
        };
        let target = V3::splat3(self.to_pixel00) + V3::splat3(self.du) * sx + V3::splat3(self.dv) * sy;
        let center = V3::splat3(self.center);
        if self.lens {
            rng.seek(layout::LENS);
            let (lx, ly) = in_unit_disk(rng);
            let lo = V3::splat3(self.lens_u) * lx + V3::splat3(self.lens_v) * ly;
            ((center + lo), (target - lo).normalize())
        } else {
            (center, target.normalize())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::ScalarStream;

    #[test]
    fn centre_pixel_looks_at_look_at() {
        let view = View {
            look_from: DVec3::new(13.0, 2.0, 3.0),
            look_at: DVec3::ZERO,
            vup: DVec3::Y,
            vfov_deg: 20.0,
            focus_dist: DVec3::new(13.0, 2.0, 3.0).length(),
            lens_radius: 0.0,
        };
        let cam = PreparedCamera::new(&view, 401, 201, false);
        let mut rng = ScalarStream::for_path(0, 0, 0);
        let (o, d) = cam.ray(200.0f32, 100.0f32, &mut rng);
        let want = DVec3::new(-13.0, -2.0, -3.0).normalize();
        assert_eq!(o.to_array(), [13.0, 2.0, 3.0]);
        for (a, b) in d.to_array().iter().zip(want.to_array()) {
            assert!((*a as f64 - b).abs() < 1e-6);
        }
    }
}
