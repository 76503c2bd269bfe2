//! criterion benchmarks: the scalar reference against the SIMD path at both
//! lane widths (8; and 16, which is one 512-bit register on AVX-512 builds and
//! two 256-bit halves otherwise).
//!
//! `cargo bench` (a few minutes on 2 cores). Groups:
//! - `intersect`: closest hit over the final scene's spheres (brute force), one
//!   fixed batch of rays, scalar one ray at a time against packets of 8 (and 16);
//! - `render`: one 32x32 tile of the final scene at 2 spp, depth 50, per kernel
//!   (brute force);
//! - `accel`: the same tile, brute force against the BVH (packets, and one ray
//!   at a time), for every kernel;
//! - `cornell`: one 32x32 tile of The Next Week's Cornell box (`nw-cornell-box`,
//!   18 quads: two trees' walks, the light pass) at 128x128, 2 spp, depth 50, per
//!   kernel, with the default accelerator (the BVH).
//!
//! Throughput is in rays (criterion's "elements"). Renders run with the probe off (`()`).

use criterion::{criterion_group, criterion_main, BenchmarkGroup, Criterion, Throughput};
use rtow::film::TileFilm;
use rtow::internals::geometry::closest_brute;
use rtow::internals::kernel::{scalar, wavefront};
use rtow::internals::plan::Prepared;
use rtow::internals::real::Wide;
use rtow::internals::sampling::{ScalarStream, Sobol};
use rtow::internals::vec3::V3;
use rtow::{AccelChoice, Job, Overrides, RenderOptions, Sampler, Settings};
use std::hint::black_box;
use std::time::Duration;
use wide::{f32x16, f32x8};

/// The final scene at 400x225, depth 50, seed 1, with the default (Sobol) sampler.
fn job(spp: u32, accel: AccelChoice) -> Job {
    let scene = rtow::scene::final_scene();
    let s = Settings { width: 400, height: 225, spp, max_depth: 50, seed: 1, ..Settings::default() };
    Job::new(&scene, &Overrides::from(s), &RenderOptions { accel, ..Default::default() }).unwrap()
}

/// The sampler the kernels run with (the default, Sobol points).
fn sobol(prep: &Prepared) -> Sobol {
    match prep.settings.sampler {
        Sampler::Sobol { dims } => Sobol { dims },
        Sampler::Independent => unreachable!("the benchmarks render with the default sampler"),
    }
}

/// 4096 camera rays of the final scene (jittered, through the lens), SoA.
fn rays(prep: &Prepared) -> [Vec<f32>; 6] {
    let mut v: [Vec<f32>; 6] = Default::default();
    for i in 0..4096u32 {
        let (x, y) = ((i * 7919) % 400, (i * 104_729) % 225);
        let mut rng = ScalarStream::for_path(1, i as u64, 0);
        let (o, d) = prep.camera.ray(x as f32, y as f32, &mut rng);
        for (k, c) in [o.x, o.y, o.z, d.x, d.y, d.z].into_iter().enumerate() {
            v[k].push(c);
        }
    }
    v
}

fn intersect_wide<W: Wide>(
    g: &mut BenchmarkGroup<criterion::measurement::WallTime>,
    prep: &Prepared,
    r: &[Vec<f32>; 6],
) {
    let n = r[0].len();
    g.bench_function(format!("simd{}", W::LANES), |b| {
        b.iter(|| {
            let mut acc = 0u32;
            for i in (0..n).step_by(W::LANES) {
                let o = V3::new(W::load(&r[0], i), W::load(&r[1], i), W::load(&r[2], i));
                let d = V3::new(W::load(&r[3], i), W::load(&r[4], i), W::load(&r[5], i));
                let (hit, _) = closest_brute(&prep.shapes.spheres, o, d, W::splat(0.0), &mut ());
                acc = acc.wrapping_add(W::lane_u(hit, 0));
            }
            black_box(acc)
        })
    });
}

fn intersect(c: &mut Criterion) {
    let job = job(1, AccelChoice::Brute);
    let prep = job.prepared();
    let r = rays(prep);
    let n = r[0].len();
    let mut g = c.benchmark_group("intersect");
    g.sample_size(10).measurement_time(Duration::from_secs(4)).throughput(Throughput::Elements(n as u64));
    g.bench_function("scalar", |b| {
        b.iter(|| {
            let mut acc = 0u32;
            #[allow(clippy::needless_range_loop)] // six arrays indexed alike
            for i in 0..n {
                let o = V3::new(r[0][i], r[1][i], r[2][i]);
                let d = V3::new(r[3][i], r[4][i], r[5][i]);
                acc = acc.wrapping_add(closest_brute(&prep.shapes.spheres, o, d, 0.0, &mut ()).0);
            }
            black_box(acc)
        })
    });
    intersect_wide::<f32x8>(&mut g, prep, &r);
    intersect_wide::<f32x16>(&mut g, prep, &r);
    g.finish();
}

/// The final scene's benchmark tile: 32x32 pixels at (160, 96), among the small spheres.
fn tile() -> TileFilm {
    TileFilm::new(160, 96, 32, 32)
}

/// The Cornell box at 128x128, depth 50, seed 1, with the default sampler and accelerator.
fn cornell_job(spp: u32) -> Job {
    let scene = rtow::scene::preset("nw-cornell-box").expect("nw-cornell-box is a preset");
    let s = Settings { width: 128, height: 128, spp, max_depth: 50, seed: 1, ..Settings::default() };
    Job::new(&scene, &Overrides::from(s), &RenderOptions::default()).unwrap()
}

/// The Cornell box's benchmark tile: 32x32 pixels at (48, 64) of 128x128, across the
/// edges of both boxes, their faces and the floor.
fn cornell_tile() -> TileFilm {
    TileFilm::new(48, 64, 32, 32)
}

/// Benchmarks every kernel on the tile; `prefix` names the group's row.
fn kernels(g: &mut BenchmarkGroup<criterion::measurement::WallTime>, prep: &Prepared, prefix: &str, scalar_too: bool) {
    kernels_on(g, prep, prefix, scalar_too, tile);
}

/// Benchmarks every kernel on the tiles `tile` makes.
fn kernels_on(
    g: &mut BenchmarkGroup<criterion::measurement::WallTime>,
    prep: &Prepared,
    prefix: &str,
    scalar_too: bool,
    tile: fn() -> TileFilm,
) {
    if scalar_too {
        g.bench_function(format!("scalar{prefix}"), |b| {
            b.iter(|| {
                let mut t = tile();
                scalar::render_tile(prep, sobol(prep), &mut t, 0..prep.settings.spp, &mut ());
                black_box(t.sum[0])
            })
        });
    }
    wide_kernel::<f32x8>(g, prep, prefix, tile);
    wide_kernel::<f32x16>(g, prep, prefix, tile);
}

fn wide_kernel<W: Wide>(
    g: &mut BenchmarkGroup<criterion::measurement::WallTime>,
    prep: &Prepared,
    prefix: &str,
    tile: fn() -> TileFilm,
) {
    let mut ws = wavefront::Workspace::default();
    g.bench_function(format!("simd{}{prefix}", W::LANES), |b| {
        b.iter(|| {
            let mut t = tile();
            wavefront::render_tile::<W, (), _>(prep, sobol(prep), &mut ws, &mut t, 0..prep.settings.spp, &mut ());
            black_box(t.sum[0])
        })
    });
}

/// Rays one tile traces (the same for every kernel).
fn tile_rays(prep: &Prepared, tile: fn() -> TileFilm) -> u64 {
    scalar::render_tile(prep, sobol(prep), &mut tile(), 0..prep.settings.spp, &mut ())
}

fn render_tile(c: &mut Criterion) {
    let job = job(2, AccelChoice::Brute);
    let prep = job.prepared();
    let mut g = c.benchmark_group("render");
    g.sample_size(10).measurement_time(Duration::from_secs(6)).throughput(Throughput::Elements(tile_rays(prep, tile)));
    kernels(&mut g, prep, "", true);
    g.finish();
}

/// Brute force against the BVH, for every kernel, on a tile of the final scene.
fn accel(c: &mut Criterion) {
    let mut g = c.benchmark_group("accel");
    for accel in [AccelChoice::Brute, AccelChoice::Bvh, AccelChoice::BvhRay] {
        let job = job(2, accel);
        let prep = job.prepared();
        g.sample_size(10)
            .measurement_time(Duration::from_secs(4))
            .throughput(Throughput::Elements(tile_rays(prep, tile)));
        // The scalar kernel walks the BVH one ray at a time either way.
        kernels(&mut g, prep, &format!("/{}", accel.name()), accel != AccelChoice::BvhRay);
    }
    g.finish();
}

/// The Cornell box: scalar against both lane widths, on one tile (quads, the light pass).
fn cornell(c: &mut Criterion) {
    let job = cornell_job(2);
    let prep = job.prepared();
    let mut g = c.benchmark_group("cornell");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(6))
        .throughput(Throughput::Elements(tile_rays(prep, cornell_tile)));
    kernels_on(&mut g, prep, "", true, cornell_tile);
    g.finish();
}

criterion_group!(benches, intersect, render_tile, accel, cornell);
criterion_main!(benches);
