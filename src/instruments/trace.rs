//! `rtow render --trace-pixel x,y`: one pixel's paths, event by event, for
//! a few samples: the camera ray, each ray's hit (primitive, material,
//! distance, point), the normal and face there, the direction each vertex
//! scattered to with its density and attenuation, and every term added to
//! the radiance with its strategy; then each sample's radiance and the
//! pixel's value. The events come from the scalar kernel through the
//! [`Observed`] probe (every kernel renders the same bits, so the trace is
//! the render's), and the pixel's value is what the film gives.

use crate::choice::Mode;
use crate::error::{Error, Result};
use crate::film::TileFilm;
use crate::geometry::{Hit, HitKind};
use crate::handle::Kind;
use crate::job::Job;
use crate::kernel::scalar;
use crate::plan::Prepared;
use crate::probe::{Lanes, Observed, PathEvents, PathId, Strategy};
use crate::real::MAX_LANES;
use crate::sampling::with_path_sampler;
use crate::vec3::V3;
use std::any::Any;
use std::fmt::Write;
use std::ops::Range;

/// Most samples a trace follows (each prints a few lines a bounce).
pub const MAX_TRACE_SAMPLES: u32 = 64;

/// `x,y`: the pixel at column `x`, row `y`.
pub fn parse_pixel(text: &str) -> Result<(u32, u32)> {
    let bad =
        || Error::invalid("trace_pixel", format!("'{}' is not x,y (a column and a row)", crate::output::clip(text)));
    match text.split(',').map(|p| p.trim().parse::<u32>()).collect::<std::result::Result<Vec<_>, _>>() {
        Ok(v) if v.len() == 2 => Ok((v[0], v[1])),
        _ => Err(bad()),
    }
}

/// The trace of pixel (`x`, `y`) over samples `samples` of `job`, as text.
pub fn trace_pixel(job: &Job, x: u32, y: u32, samples: Range<u32>) -> Result<String> {
    let prep = job.prepared();
    let s = prep.settings;
    if x >= s.width || y >= s.height {
        return Err(Error::invalid(
            "trace_pixel",
            format!("({x}, {y}) is not a pixel of the {}x{} image", s.width, s.height),
        ));
    }
    if prep.plan.mode == Mode::Gradient {
        return Err(Error::invalid("trace_pixel", "this scene traces no paths (a gradient)"));
    }
    if samples.is_empty() || samples.len() > MAX_TRACE_SAMPLES as usize || samples.end > s.spp {
        return Err(Error::invalid(
            "trace_samples",
            format!(
                "{} samples: give 1 to {MAX_TRACE_SAMPLES}, at most the render's {} per pixel",
                samples.len(),
                s.spp
            ),
        ));
    }
    let mut tile = TileFilm::new(x, y, 1, 1).scaled(prep.plan.film_scale());
    if prep.estimator.adaptive.is_some() {
        tile = tile.with_moments();
    }
    let mut probe = Observed::with(Recorder { prep, text: String::new(), sum: [0.0; 3], ray: 0 });
    with_path_sampler!(s.sampler, sampler => {
        scalar::render_tile(prep, sampler, &mut tile, samples.clone(), &mut probe);
    });
    let trace: String = probe.finish();
    let mut text = format!(
        "pixel ({x}, {y}), samples {}..{} of {} (seed {}, sampler {}, estimator {}, depth {}); every kernel traces \
         these bits\n",
        samples.start, samples.end, s.spp, s.seed, s.sampler, s.estimator, s.max_depth
    );
    text.push_str(&trace);
    let value = tile.scale.mean(tile.sum[0], tile.count[0]);
    let _ = writeln!(
        text,
        "pixel value over these {} samples (the film's mean): {}{}",
        tile.count[0],
        v3(value),
        if tile.rejected > 0 {
            format!("; {} samples rejected (not finite or out of range)", tile.rejected)
        } else {
            String::new()
        }
    );
    Ok(text)
}

/// Three numbers as Rust prints f32 (exactly, round-tripping).
fn v3(v: [f32; 3]) -> String {
    format!("({:?}, {:?}, {:?})", v[0], v[1], v[2])
}

fn p3(v: V3<f32>) -> String {
    v3(v.to_array())
}

/// The path events of one pixel, written down as they come.
struct Recorder<'a> {
    prep: &'a Prepared,
    text: String,
    /// The radiance of the path under way, term by term.
    sum: [f32; 3],
    /// Rays of the path under way so far.
    ray: u32,
}

impl Recorder<'_> {
    /// What primitive hit index `hit` names, and its material.
    fn describe(&self, hit: u32) -> String {
        let sh = &self.prep.shapes;
        let Hit { kind, index } = Hit::of(hit);
        let (what, material) = match kind {
            HitKind::Sphere => (format!("sphere {index}"), Some(sh.spheres.kind[index])),
            HitKind::Moving => (format!("moving sphere {index}"), Some(sh.moving.s.kind[index])),
            HitKind::Quad => (format!("quad {index}"), sh.quads.kind.get(index).copied()),
            HitKind::Triangle => {
                let material = (index < sh.triangles.len()).then(|| sh.triangles.material_of(index).0);
                (format!("triangle {index}"), material)
            }
            HitKind::Instance => {
                let (i, k) = sh.instances.of(hit);
                (format!("triangle {k} of instance {i}"), Some(sh.instances.kind[i]))
            }
            HitKind::Medium => (format!("medium {index} (stops inside it)"), Some(Kind::Isotropic)),
            HitKind::Miss => ("nothing".into(), None),
        };
        match material {
            Some(m) => format!("{what} ({})", m.name()),
            None => what,
        }
    }

    /// The radiance of the path that ended, if one is open.
    fn end_path(&mut self) {
        if self.ray > 0 {
            let _ = writeln!(self.text, "  radiance {}", v3(self.sum));
        }
    }

    fn close(mut self) -> String {
        self.end_path();
        self.text
    }
}

impl PathEvents for Recorder<'_> {
    fn camera(&mut self, ids: &Lanes, o: &mut [V3<f32>; MAX_LANES], d: &[V3<f32>; MAX_LANES]) {
        self.end_path();
        let (sample, o, d) = (ids.sample[0], o[0], d[0]);
        let _ = writeln!(self.text, "sample {sample}:\n  camera ray from {} toward {}", p3(o), p3(d));
        self.sum = [0.0; 3];
        self.ray = 0;
    }

    fn traced(
        &mut self,
        _ids: &Lanes,
        o: &[V3<f32>; MAX_LANES],
        d: &[V3<f32>; MAX_LANES],
        hit: &[u32; MAX_LANES],
        t: &[f32; MAX_LANES],
    ) {
        self.ray += 1;
        let what = self.describe(hit[0]);
        if hit[0] == crate::geometry::MISS {
            let _ = writeln!(self.text, "  ray {}: hits nothing (leaves the scene)", self.ray);
        } else {
            let p = o[0] + d[0] * t[0];
            let _ = writeln!(self.text, "  ray {}: hits {what} at t = {:?}, point {}", self.ray, t[0], p3(p));
        }
    }

    fn shaded(&mut self, _ids: &Lanes, _radius: &[f32; MAX_LANES], n: &[V3<f32>; MAX_LANES], front: u32) {
        let face = if front & 1 != 0 { "front" } else { "back" };
        let _ = writeln!(self.text, "    normal {} ({face} face)", p3(n[0]));
    }

    fn scattered(&mut self, _id: PathId<f32>, kind: Kind, dir: V3<f32>, atten: [f32; 3], pdf: f32) {
        let _ = writeln!(
            self.text,
            "    {} scatters toward {}, attenuation {}, density {:?}",
            kind.name(),
            p3(dir),
            v3(atten),
            pdf
        );
    }

    fn contributed(&mut self, _id: PathId<f32>, length: u32, strategy: Strategy, c: V3<f32>) {
        let c = c.to_array();
        self.sum = [self.sum[0] + c[0], self.sum[1] + c[1], self.sum[2] + c[2]];
        let _ = writeln!(self.text, "    + {} {} (a path of {length} rays)", strategy.name(), v3(c));
    }

    fn finish(self: Box<Self>) -> Box<dyn Any + Send> {
        Box::new(self.close())
    }
}
