//! Lanes against one lane: every width-generic building block the kernels
//! share (float and integer lane operations, the samplers' streams, Russian
//! roulette) computes in lane k exactly what the scalar kernel computes.
//! Here rather than beside the code so that CI runs them on the baseline
//! instruction set (SSE2) with the other kernel tests, without building the
//! library's unit tests a second time.

use rtow::internals::estimator::roulette;
use rtow::internals::real::{Real, U32Lanes};
use rtow::internals::sampling::lanes::hash32;
use rtow::internals::sampling::sobol::{pixel_key, sample_bits};
use rtow::internals::sampling::{layout, unit_vector, Independent, PathSampler, Sobol, Stream};
use rtow::internals::vec3::V3;
use wide::{f32x16, f32x8, u32x16, u32x8};

#[test]
fn unit_from_bits_agrees_across_widths() {
    let words = [0u32, 1, 255, 256, 0x8000_0000, u32::MAX, 0xdead_beef, 12345];
    let wide = f32x8::unit_from_bits(u32x8::new(words)).to_array();
    for (k, w) in words.iter().enumerate() {
        let s = f32::unit_from_bits(*w);
        assert_eq!(s.to_bits(), wide[k].to_bits());
        assert!((0.0..1.0).contains(&s));
    }
    assert!(f32x16::unit_from_bits(u32x16::splat(u32::MAX)).to_array().iter().all(|&u| u < 1.0));
}

#[test]
fn min_max_copysign_agree_across_widths() {
    let a = [1.0f32, -2.0, 0.0, -0.0, 3.5, f32::INFINITY, -1e-30, 7.0];
    let b = [2.0f32, -3.0, -0.0, 0.0, 3.5, 1.0, 1e-30, -7.0];
    let (wa, wb) = (f32x8::new(a), f32x8::new(b));
    let mn = Real::min(wa, wb).to_array();
    let mx = Real::max(wa, wb).to_array();
    let cs = Real::copysign(wa, wb).to_array();
    for k in 0..8 {
        assert_eq!(Real::min(a[k], b[k]).to_bits(), mn[k].to_bits());
        assert_eq!(Real::max(a[k], b[k]).to_bits(), mx[k].to_bits());
        assert_eq!(Real::copysign(a[k], b[k]).to_bits(), cs[k].to_bits());
    }
}

fn words(n: usize, seed: u32) -> Vec<u32> {
    let mut s = seed;
    let mut v = vec![0, 1, u32::MAX, 0x8000_0000, 0x7fff_ffff];
    while v.len() < n {
        s = hash32(s.wrapping_add(0x9e37_79b9));
        v.push(s);
    }
    v
}

fn agree<U: U32Lanes>(f: impl Fn(U, U) -> U, g: impl Fn(u32, u32) -> u32) {
    let a = words(64 * U::LANES, 1);
    let b = words(64 * U::LANES, 2);
    for (ca, cb) in a.chunks(U::LANES).zip(b.chunks(U::LANES)) {
        let r = f(U::from_fn(|k| ca[k]), U::from_fn(|k| cb[k]));
        for k in 0..U::LANES {
            assert_eq!(r.lane(k), g(ca[k], cb[k]));
        }
    }
}

fn all_ops<U: U32Lanes>() {
    agree::<U>(|a, b| a.wrapping_add(b), u32::wrapping_add);
    agree::<U>(|a, b| a.wrapping_sub(b), u32::wrapping_sub);
    agree::<U>(|a, b| a.wrapping_mul(b), u32::wrapping_mul);
    agree::<U>(|a, b| (a ^ b) | (a & b), |a, b| (a ^ b) | (a & b));
    agree::<U>(|a, _| (a << 7) ^ (a >> 13), |a, _| (a << 7) ^ (a >> 13));
    agree::<U>(|a, _| a.reverse_bits(), |a, _| a.reverse_bits());
    let table: [u32; 16] = std::array::from_fn(|j| hash32(j as u32 % 8));
    agree::<U>(|a, _| U::lookup8(&table, a), |a, _| table[a as usize % 8]);
    agree::<U>(|a, _| hash32(a), |a, _| hash32(a));
}

#[test]
fn integer_lanes_agree_with_scalar_u32() {
    all_ops::<u32>();
    all_ops::<u32x8>();
    all_ops::<u32x16>();
}

#[test]
fn all_zero_sees_every_lane() {
    assert!(u32x8::splat(0).all_zero());
    assert!(!u32x8::new([0, 0, 0, 0, 0, 0, 0, 1]).all_zero());
    assert!(!u32x16::from_fn(|k| (k == 15) as u32).all_zero());
    assert!(0u32.all_zero() && !1u32.all_zero());
}

fn sobol_lanes_agree<U: U32Lanes>() {
    for dim in (0..130).chain([1000, u32::MAX]) {
        for limit in [4, 124] {
            for chunk in 0..4u32 {
                let keys: Vec<u32> = (0..U::LANES as u32).map(|k| pixel_key(chunk as u64, k as u64 * 7)).collect();
                let idx: Vec<u32> = (0..U::LANES as u32).map(|k| hash32(k + chunk) >> (chunk * 8)).collect();
                let bits = sample_bits(U::from_fn(|k| keys[k]), U::from_fn(|k| idx[k]), dim, limit);
                for k in 0..U::LANES {
                    assert_eq!(bits.lane(k), sample_bits(keys[k], idx[k], dim, limit), "dim {dim} lane {k}");
                }
            }
        }
    }
}

#[test]
fn sobol_points_in_lanes_are_the_scalar_points() {
    sobol_lanes_agree::<u32x8>();
    sobol_lanes_agree::<u32x16>();
}

/// The lanes' streams of 8 paths (`key(k)`: seed, pixel, sample of lane k)
/// as the wavefront makes them, and the scalar kernel's stream of each.
fn streams<S: PathSampler>(s: S, key: impl Fn(usize) -> (u64, u64, u32)) -> (S::Lanes<f32x8>, Vec<S::Scalar>) {
    let w: Vec<[u32; 4]> = (0..8).map(|k| s.words(key(k).0, key(k).1, key(k).2)).collect();
    let lanes = s.lanes::<f32x8>(std::array::from_fn(|i| u32x8::new(std::array::from_fn(|k| w[k][i]))));
    (lanes, (0..8).map(|k| s.scalar(key(k).0, key(k).1, key(k).2)).collect())
}

/// Lane k of `v` and the scalar `s`: the same bits.
fn same(v: V3<f32x8>, k: usize, s: V3<f32>, what: &str) {
    let l = [v.x.to_array()[k], v.y.to_array()[k], v.z.to_array()[k]];
    assert_eq!(l.map(f32::to_bits), s.to_array().map(f32::to_bits), "{what} lane {k}");
}

#[test]
fn independent_streams_draw_in_lanes_what_the_scalar_streams_draw() {
    let (mut x8, mut sc) = streams(Independent, |k| (42, k as u64 * 1013, 5 + k as u32 % 3));
    for _ in 0..200 {
        let w: f32x8 = x8.next();
        let v3: V3<f32x8> = unit_vector(&mut x8);
        for (k, sk) in sc.iter_mut().enumerate() {
            assert_eq!(w.to_array()[k].to_bits(), Stream::<f32>::next(sk).to_bits());
            same(v3, k, unit_vector(sk), "unit vector");
        }
    }
}

#[test]
fn sobol_streams_draw_in_lanes_what_the_scalar_streams_draw() {
    for sample0 in [0u32, 100, 1 << 20] {
        for dims in [4, 124] {
            let (mut w, mut sc) = streams(Sobol { dims }, |k| (42, k as u64, sample0 + k as u32));
            for depth in [0u32, 1, 7, 39, 40, 41, 1000] {
                Stream::<f32x8>::seek(&mut w, layout::scatter(depth));
                let v3: V3<f32x8> = unit_vector(&mut w);
                let r: f32x8 = w.next();
                for (k, s) in sc.iter_mut().enumerate() {
                    Stream::<f32>::seek(s, layout::scatter(depth));
                    same(v3, k, unit_vector(s), "unit vector");
                    let rs: f32 = s.next();
                    assert_eq!(rs.to_bits(), r.to_array()[k].to_bits(), "depth {depth} lane {k}");
                }
            }
        }
    }
}

#[test]
fn roulette_agrees_across_widths_and_keeps_the_mean() {
    let thr: [[f32; 3]; 8] = [
        [0.5, 0.25, 0.1],
        [1.0, 0.0, 0.0],
        [2.0, 3.0, 0.5],
        [0.0, 0.0, 0.0],
        [1e-6, 2e-6, 0.0],
        [0.9, 0.9, 0.9],
        [0.3, 0.7, 0.2],
        [0.99999, 0.5, 0.5],
    ];
    let (mut x8, mut sc) = streams(Independent, |k| (3, k as u64, 0));
    let t8 = V3::new(f32x8::new(thr.map(|t| t[0])), f32x8::new(thr.map(|t| t[1])), f32x8::new(thr.map(|t| t[2])));
    let mut mean = [[0.0f64; 3]; 8];
    let n = 20_000;
    for _ in 0..n {
        let (w, live8) = roulette(t8, &mut x8);
        let live8 = live8.to_bitmask();
        for k in 0..8 {
            let (s, live) = roulette(V3::from_array(thr[k]), &mut sc[k]);
            assert_eq!(live, live8 & (1 << k) != 0, "lane {k}");
            if live {
                same(w, k, s, "survivor");
                for (m, v) in mean[k].iter_mut().zip(s.to_array()) {
                    *m += v as f64 / n as f64;
                }
            }
        }
    }
    for k in 0..8 {
        for c in 0..3 {
            // Survival is Bernoulli(p) and a survivor carries thr / p: the
            // mean is thr, with standard error thr sqrt((1 - p) / (p n)).
            let t = thr[k][c] as f64;
            let p = thr[k].iter().fold(0.0f32, |a, &b| a.max(b)).min(1.0) as f64;
            let se = if p > 0.0 { t * ((1.0 - p) / (p * n as f64)).sqrt() } else { 0.0 };
            assert!((mean[k][c] - t).abs() <= 5.0 * se + 1e-9 * t, "lane {k} channel {c}: {} vs {t}", mean[k][c]);
        }
    }
}
