//! criterion benchmarks: the scalar reference against the SIMD path.
//!
//! `cargo bench` (about two minutes on 2 cores). Groups:
//! - `intersect`: closest hit over the final scene's spheres (brute force), one
//!   fixed batch of rays, scalar one ray at a time against 8-wide packets;
//! - `render`: one 32x32 tile of the final scene at 2 spp, depth 50, per kernel
//!   (brute force);
//! - `accel`: the same tile, brute force against the BVH, for both kernels.
//! Throughput is in rays (criterion's "elements").

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use rtow::film::TileFilm;
use rtow::geometry::{closest_hit_scalar, closest_hit_x8};
use rtow::kernel::{scalar, wavefront, Counters};
use rtow::plan::{AccelChoice, Prepared, Settings};
use rtow::sampling::ScalarStream;
use rtow::vec3::V3;
use std::hint::black_box;
use std::time::Duration;
use wide::f32x8;

fn prepared(spp: u32, accel: AccelChoice) -> Prepared {
    let scene = rtow::scene::final_scene();
    Prepared::new(&scene, Settings { width: 400, height: 225, spp, max_depth: 50, seed: 1 }, accel).unwrap()
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

fn intersect(c: &mut Criterion) {
    let prep = prepared(1, AccelChoice::Brute);
    let r = rays(&prep);
    let n = r[0].len();
    let mut g = c.benchmark_group("intersect");
    g.sample_size(10).measurement_time(Duration::from_secs(4)).throughput(Throughput::Elements(n as u64));
    g.bench_function("scalar", |b| {
        b.iter(|| {
            let mut acc = 0u32;
            for i in 0..n {
                let o = V3::new(r[0][i], r[1][i], r[2][i]);
                let d = V3::new(r[3][i], r[4][i], r[5][i]);
                acc = acc.wrapping_add(closest_hit_scalar(&prep.spheres, o, d).0);
            }
            black_box(acc)
        })
    });
    g.bench_function("simd8", |b| {
        let ld = |k: usize, i: usize| f32x8::new(r[k][i..i + 8].try_into().unwrap());
        b.iter(|| {
            let mut acc = wide::u32x8::splat(0);
            for i in (0..n).step_by(8) {
                let o = V3::new(ld(0, i), ld(1, i), ld(2, i));
                let d = V3::new(ld(3, i), ld(4, i), ld(5, i));
                acc += closest_hit_x8(&prep.spheres, o, d).0;
            }
            black_box(acc)
        })
    });
    g.finish();
}

fn render_tile(c: &mut Criterion) {
    let prep = prepared(2, AccelChoice::Brute);
    let tile = || TileFilm::new(160, 96, 32, 32);
    let mut counters = Counters::default();
    scalar::render_tile(&prep, &mut tile(), &mut counters);
    let mut g = c.benchmark_group("render");
    g.sample_size(10).measurement_time(Duration::from_secs(6)).throughput(Throughput::Elements(counters.rays));
    g.bench_function("scalar", |b| {
        b.iter(|| {
            let mut t = tile();
            scalar::render_tile(&prep, &mut t, &mut Counters::default());
            black_box(t.sum[0])
        })
    });
    let mut ws = wavefront::Workspace::default();
    g.bench_function("simd", |b| {
        b.iter(|| {
            let mut t = tile();
            wavefront::render_tile(&prep, &mut ws, &mut t, &mut Counters::default());
            black_box(t.sum[0])
        })
    });
    g.finish();
}

/// Brute force against the BVH, for both kernels, on a tile of the final scene.
fn accel(c: &mut Criterion) {
    let mut g = c.benchmark_group("accel");
    let tile = || TileFilm::new(160, 96, 32, 32);
    for accel in [AccelChoice::Brute, AccelChoice::Bvh, AccelChoice::BvhRay] {
        let prep = prepared(2, accel);
        let mut counters = Counters::default();
        scalar::render_tile(&prep, &mut tile(), &mut counters);
        g.sample_size(10).measurement_time(Duration::from_secs(4)).throughput(Throughput::Elements(counters.rays));
        let name = format!("{accel:?}").to_lowercase();
        if accel != AccelChoice::BvhRay {
            // The scalar kernel walks the BVH one ray at a time either way.
            g.bench_function(format!("scalar/{name}"), |b| {
                b.iter(|| {
                    let mut t = tile();
                    scalar::render_tile(&prep, &mut t, &mut Counters::default());
                    black_box(t.sum[0])
                })
            });
        }
        let mut ws = wavefront::Workspace::default();
        g.bench_function(format!("simd/{name}"), |b| {
            b.iter(|| {
                let mut t = tile();
                wavefront::render_tile(&prep, &mut ws, &mut t, &mut Counters::default());
                black_box(t.sum[0])
            })
        });
    }
    g.finish();
}

criterion_group!(benches, intersect, render_tile, accel);
criterion_main!(benches);
