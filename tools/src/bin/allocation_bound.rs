//! How much could any per-pixel sample allocation save, at equal RMSE?
//!
//! Traces `spp` paths per pixel with the scalar kernel and keeps, per pixel,
//! the variance of one sample (channel average of the per-channel variances,
//! the quantity RMSE averages), its mean, and its cost in rays. Then compares,
//! for the same MSE, the rays that these allocations need (exact variances, no
//! rounding, no minimum or maximum sample count, so they are ideals):
//!
//! - uniform: every pixel `n` samples;
//! - MSE-optimal: `n_i` proportional to `sigma_i / sqrt(c_i)` (minimizes the
//!   sum of `sigma_i^2 / n_i` for a given sum of `n_i c_i`);
//! - equal absolute error: `n_i` proportional to `sigma_i^2` (what stopping at a
//!   threshold on the standard error tends to);
//! - equal relative error: `n_i` proportional to `sigma_i^2 / max(m_i, floor)^2`
//!   (what `--adaptive` tends to).
//!
//! Usage: `cargo run --release -p rtow-tools --bin allocation_bound -- [SCENE] [WIDTH] [HEIGHT] [SPP] [SEED]`
//! (defaults: final 200 113 128 77).

use rtow::instruments::probe::PathId;
use rtow::internals::estimator::RELATIVE_ERROR_FLOOR;
use rtow::internals::kernel::scalar;
use rtow::internals::sampling::ScalarStream;
use rtow::scene::preset;
use rtow::{Job, Overrides, RenderOptions, Settings};

struct Pixel {
    var: f64,
    mean: f64,
    cost: f64,
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, d: &str| args.get(i).cloned().unwrap_or_else(|| d.to_string());
    let name = arg(0, "final");
    let num = |i: usize, d: &str| -> u64 {
        arg(i, d).parse().unwrap_or_else(|_| {
            eprintln!("error: argument {} must be a whole number, not '{}'", i + 1, arg(i, d));
            std::process::exit(2)
        })
    };
    let (w, h, spp, seed) = (num(1, "200") as u32, num(2, "113") as u32, num(3, "128") as u32, num(4, "77"));
    let Some(scene) = preset(&name) else {
        eprintln!("error: unknown preset '{name}'");
        std::process::exit(2)
    };
    if spp < 2 {
        eprintln!("error: SPP must be at least 2 (a variance needs two samples)");
        std::process::exit(2)
    }
    let settings = Settings { width: w, height: h, spp, max_depth: 50, seed, ..Settings::default() };
    let job = match Job::new(&scene, &Overrides::from(settings), &RenderOptions::default()) {
        Ok(j) => j,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2)
        }
    };
    let prep = job.prepared();
    let mut pixels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let pixel = (y * w + x) as u64;
            let mut rays = 0u64;
            let mut m = [[0.0f64; 2]; 3];
            for sample in 0..spp {
                let mut rng = ScalarStream::for_path(seed, pixel, sample as u64);
                let id = PathId { pixel: pixel as u32, sample };
                let (v, n) = scalar::trace(prep, x, y, id, &mut rng, &mut ());
                rays += n as u64;
                for k in 0..3 {
                    m[k][0] += v[k] as f64;
                    m[k][1] += v[k] as f64 * v[k] as f64;
                }
            }
            let n = spp as f64;
            let var = m.iter().map(|[s1, s2]| ((s2 - s1 * s1 / n) / (n - 1.0)).max(0.0)).sum::<f64>() / 3.0;
            let mean = m.iter().map(|[s1, _]| s1 / n).sum::<f64>() / 3.0;
            pixels.push(Pixel { var, mean, cost: rays as f64 / n });
        }
    }
    let p = pixels.len() as f64;
    let e = |f: &dyn Fn(&Pixel) -> f64| pixels.iter().map(f).sum::<f64>() / p;
    // With n_i = k w_i samples: MSE = E[var / (k w)] and rays per pixel = k E[w c],
    // so MSE x rays = E[var / w] E[w c] whatever k (pixels with w = 0 have var = 0).
    let product =
        |w: &dyn Fn(&Pixel) -> f64| e(&|q| if w(q) > 0.0 { q.var / w(q) } else { 0.0 }) * e(&|q| w(q) * q.cost);
    let rel = |q: &Pixel| q.mean.max(RELATIVE_ERROR_FLOOR);
    let uniform = product(&|_| 1.0);
    let optimal = product(&|q| (q.var / q.cost).sqrt());
    let equal_abs = product(&|q| q.var);
    let equal_rel = product(&|q| q.var / rel(q).powi(2));
    let mut vars: Vec<f64> = pixels.iter().map(|q| q.var).collect();
    vars.sort_by(f64::total_cmp);
    let total: f64 = vars.iter().sum();
    let top = |f: f64| vars[vars.len() - (f * p) as usize..].iter().sum::<f64>() / total;
    println!("{name} {w}x{h}, {spp} paths per pixel, seed {seed}: mean rays per path {:.3}", e(&|q| q.cost));
    println!(
        "share of the summed per-pixel variance in the noisiest 1% / 10% / 50% of pixels: {:.1}% / {:.1}% / {:.1}%",
        100.0 * top(0.01),
        100.0 * top(0.10),
        100.0 * top(0.50)
    );
    println!("rays for the same MSE, relative to uniform sampling (ideal allocations, exact variances):");
    println!("  MSE-optimal (n ~ sigma / sqrt(cost)):      {:.3}", optimal / uniform);
    println!("  equal absolute error (n ~ sigma^2):        {:.3}", equal_abs / uniform);
    println!("  equal relative error (n ~ sigma^2 / m^2):  {:.3}", equal_rel / uniform);
}
