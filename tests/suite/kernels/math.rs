//! The transcendental functions over `Real` (`rtow::internals::math`): every
//! lane width computes the scalar function's bits, and the error against
//! f64 stays within the bound each function documents (measured here:
//! exhaustively where the kernels' inputs are a finite set, densely and by
//! property elsewhere).

use proptest::prelude::*;
use rtow::internals::math::{acos, atan2, exp_neg, ln, sin, SIN_MAX_ARG};
use rtow::internals::real::Real;
use wide::{f32x16, f32x8};

/// One function at the three widths.
type Widths = (fn(f32) -> f32, fn(f32x8) -> f32x8, fn(f32x16) -> f32x16);

/// `f` at 1, 8 and 16 lanes on `xs` (padded): the same bits in every lane.
fn same_bits_1(xs: &[f32], f: Widths, what: &str) {
    for chunk in xs.chunks(16) {
        let lane = |k: usize| chunk[k % chunk.len()];
        let w16 = f.2(f32x16::from_fn(lane));
        let (w8a, w8b) = (f.1(f32x8::from_fn(lane)), f.1(f32x8::from_fn(|k| lane(k + 8))));
        for k in 0..16 {
            let want = f.0(lane(k)).to_bits();
            let got8 = if k < 8 { w8a.lane(k) } else { w8b.lane(k - 8) };
            assert_eq!(got8.to_bits(), want, "{what}({}) at 8 lanes", lane(k));
            assert_eq!(w16.lane(k).to_bits(), want, "{what}({}) at 16 lanes", lane(k));
        }
    }
}

/// Awkward inputs: zeros, subnormals, integers, halves, near multiples of pi/2, huge values.
fn specials() -> Vec<f32> {
    let mut v = vec![
        0.0,
        -0.0,
        f32::MIN_POSITIVE,
        f32::MIN_POSITIVE / 3.0,
        1e-45,
        1.0,
        -1.0,
        0.5,
        -0.5,
        1.5,
        -1.5,
        f32::MAX,
        f32::EPSILON,
        1.0 - f32::EPSILON / 2.0,
        1.0 + f32::EPSILON,
    ];
    for k in -40..40 {
        let x = k as f32 * std::f32::consts::FRAC_PI_2;
        v.extend([x, f32::from_bits(x.to_bits() + 1), f32::from_bits(x.to_bits().wrapping_sub(1))]);
    }
    for e in -30..30 {
        v.push(10f32.powi(e));
        v.push(-(10f32.powi(e)));
    }
    v.retain(|x| x.is_finite());
    v
}

/// Pseudo-random f32 bit patterns (every sign, exponent and mantissa), finite only.
fn random_floats(n: usize, seed: u64) -> Vec<f32> {
    let mut s = seed;
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let x = f32::from_bits((s >> 32) as u32);
        if x.is_finite() {
            out.push(x);
        }
    }
    out
}

#[test]
fn every_width_computes_the_scalar_bits() {
    let mut xs = specials();
    xs.extend(random_floats(200_000, 1));
    same_bits_1(&xs, (sin::<f32>, sin::<f32x8>, sin::<f32x16>), "sin");
    same_bits_1(&xs, (|x| x.floor(), |x| x.floor(), |x| x.floor()), "floor");
    let pos: Vec<f32> = xs.iter().map(|x| x.abs()).filter(|&x| x > 0.0).collect();
    same_bits_1(&pos, (ln::<f32>, ln::<f32x8>, ln::<f32x16>), "ln");
    let nonneg: Vec<f32> = xs.iter().map(|x| x.abs()).chain([f32::INFINITY, 87.3, 87.4, 126.0]).collect();
    same_bits_1(&nonneg, (exp_neg::<f32>, exp_neg::<f32x8>, exp_neg::<f32x16>), "exp_neg");
    let unit: Vec<f32> = xs.iter().map(|&x| (x % 2.0).clamp(-1.0, 1.0)).collect();
    same_bits_1(&unit, (acos::<f32>, acos::<f32x8>, acos::<f32x16>), "acos");
    // atan2 of pairs: y from the list, x from the list rotated.
    let pairs: Vec<(f32, f32)> = xs.iter().zip(xs.iter().cycle().skip(7)).map(|(&a, &b)| (a, b)).collect();
    for chunk in pairs.chunks(16) {
        let lane = |k: usize| chunk[k % chunk.len()];
        let w16 = atan2(f32x16::from_fn(|k| lane(k).0), f32x16::from_fn(|k| lane(k).1));
        let w8 = atan2(f32x8::from_fn(|k| lane(k).0), f32x8::from_fn(|k| lane(k).1));
        for k in 0..16 {
            let (y, x) = lane(k);
            let want = atan2(y, x).to_bits();
            assert_eq!(w16.lane(k).to_bits(), want, "atan2({y}, {x}) at 16 lanes");
            if k < 8 {
                assert_eq!(w8.lane(k).to_bits(), want, "atan2({y}, {x}) at 8 lanes");
            }
        }
    }
}

#[test]
fn floor_is_exact() {
    for x in specials().into_iter().chain(random_floats(100_000, 2)) {
        assert_eq!(Real::floor(x).to_bits(), x.floor().to_bits(), "floor({x})");
    }
}

/// `1 - u` for every `u` the samplers draw (the 2^24-point grid of [0, 1)):
/// the inputs of a medium's free-flight distance, all of them.
#[test]
fn ln_of_every_sampler_value_is_within_its_bound() {
    let (mut worst_abs, mut worst_ulp) = (0.0f64, 0.0f64);
    for k in 0..(1u32 << 24) {
        let x = 1.0 - k as f32 * (1.0 / 16_777_216.0);
        let want = (x as f64).ln();
        let e = (ln(x) as f64 - want).abs();
        worst_abs = worst_abs.max(e);
        worst_ulp = worst_ulp.max(e / ulp_of(want));
    }
    eprintln!("ln on the sampler grid: max error {worst_abs:.3e} absolute, {worst_ulp:.3} ulp of the result");
    assert!(worst_ulp <= 2.0, "{worst_ulp}");
}

/// The spacing of f32 numbers at `v` (the unit in the last place of `v` rounded to f32).
fn ulp_of(v: f64) -> f64 {
    let a = (v.abs() as f32).max(f32::MIN_POSITIVE);
    (f32::from_bits(a.to_bits() + 1) - a) as f64
}

#[test]
fn ln_is_within_its_bound_everywhere() {
    let mut worst_ulp = 0.0f64;
    let mut xs = random_floats(2_000_000, 3);
    xs.extend(specials());
    for x in xs.into_iter().map(f32::abs).filter(|&x| x > 0.0) {
        let want = (x as f64).ln();
        worst_ulp = worst_ulp.max((ln(x) as f64 - want).abs() / ulp_of(want));
    }
    eprintln!("ln everywhere: max error {worst_ulp:.3} ulp of the result");
    assert!(worst_ulp <= 2.0, "{worst_ulp}");
}

#[test]
fn sin_is_within_its_bound() {
    // Dense over the range the bound covers (every f32 near 0, a fine grid
    // further out), and the awkward inputs.
    let mut worst = 0.0f64;
    let n = 8_000_000u64;
    let top = SIN_MAX_ARG as f64;
    for i in 0..=n {
        let x = (-top + 2.0 * top * i as f64 / n as f64) as f32;
        worst = worst.max((sin(x) as f64 - (x as f64).sin()).abs());
    }
    for k in 0..2_000_000u32 {
        let x = f32::from_bits(0x3c00_0000 + k * 8); // 2^-7 .. about 14
        worst = worst.max((sin(x) as f64 - (x as f64).sin()).abs());
    }
    for x in specials().into_iter().filter(|x| x.abs() <= SIN_MAX_ARG) {
        worst = worst.max((sin(x) as f64 - (x as f64).sin()).abs());
    }
    eprintln!("sin for |x| <= {top}: max absolute error {worst:.3e}");
    assert!(worst <= 2.5e-7, "{worst:e}");
}

#[test]
fn atan2_and_acos_are_within_their_bounds() {
    let mut worst = 0.0f64;
    let n = 2_000_000u64;
    for i in 0..n {
        // Points on circles of many radii, every angle.
        let a = std::f64::consts::TAU * i as f64 / n as f64 - std::f64::consts::PI;
        let r = 10f64.powf(-20.0 + 40.0 * ((i * 7919) % n) as f64 / n as f64);
        let (y, x) = ((r * a.sin()) as f32, (r * a.cos()) as f32);
        worst = worst.max((atan2(y, x) as f64 - (y as f64).atan2(x as f64)).abs());
    }
    for &y in &specials() {
        for &x in &specials() {
            let want = (y as f64).atan2(x as f64);
            let got = atan2(y, x) as f64;
            assert!((got - want).abs() <= 2.5e-7, "atan2({y}, {x}) = {got}, f64 {want}");
        }
    }
    eprintln!("atan2: max absolute error {worst:.3e}");
    assert!(worst <= 2.5e-7, "{worst:e}");
    let mut worst = 0.0f64;
    for i in 0..=4_000_000 {
        let x = (-1.0 + 2.0 * i as f64 / 4_000_000.0) as f32;
        worst = worst.max((acos(x) as f64 - (x as f64).acos()).abs());
    }
    for x in [1.0f32, -1.0, 0.0, -0.0, 1.0 - f32::EPSILON / 2.0, -1.0 + f32::EPSILON / 2.0] {
        worst = worst.max((acos(x) as f64 - (x as f64).acos()).abs());
    }
    eprintln!("acos: max absolute error {worst:.3e}");
    assert!(worst <= 2.5e-7, "{worst:e}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 20_000, ..ProptestConfig::default() })]

    #[test]
    fn atan2_of_any_finite_pair(y in prop::num::f32::NORMAL | prop::num::f32::SUBNORMAL | prop::num::f32::ZERO,
                                x in prop::num::f32::NORMAL | prop::num::f32::SUBNORMAL | prop::num::f32::ZERO) {
        let want = (y as f64).atan2(x as f64);
        prop_assert!((atan2(y, x) as f64 - want).abs() <= 2.5e-7, "atan2({}, {}) = {} vs {}", y, x, atan2(y, x), want);
    }

    #[test]
    fn ln_of_any_positive_number(x in prop::num::f32::POSITIVE | prop::num::f32::SUBNORMAL) {
        prop_assume!(x > 0.0 && x.is_finite());
        let want = (x as f64).ln();
        prop_assert!((ln(x) as f64 - want).abs() <= 2.0 * ulp_of(want), "ln({}) = {} vs {}", x, ln(x), want);
    }

    #[test]
    fn sin_of_any_argument_in_range(x in -SIN_MAX_ARG..SIN_MAX_ARG) {
        prop_assert!((sin(x) as f64 - (x as f64).sin()).abs() <= 2.5e-7);
    }
}

/// `exp_neg` (shadow rays' transmittance) against f64: relative error below
/// `5e-6` on `[0, 87]`, at most 8 ulp on `[0, 1]`; 0 beyond the normals and
/// at infinity; never above 1, never negative.
#[test]
fn exp_neg_is_within_its_bound() {
    let (mut worst_rel, mut worst_ulp) = (0.0f64, 0.0f64);
    let n = 1_000_000;
    for i in 0..=n {
        let x = 87.0 * i as f32 / n as f32;
        let got = exp_neg(x) as f64;
        let want = (-(x as f64)).exp();
        assert!((0.0..=1.0).contains(&got), "exp_neg({x}) = {got}");
        worst_rel = worst_rel.max((got - want).abs() / want);
        if x <= 1.0 {
            worst_ulp = worst_ulp.max((got - want).abs() / ulp_of(want));
        }
    }
    eprintln!("exp_neg: max relative error {worst_rel:.3e} on [0, 87], {worst_ulp:.2} ulp on [0, 1]");
    assert!(worst_rel < 5e-6, "{worst_rel}");
    assert!(worst_ulp <= 8.0, "{worst_ulp}");
    assert_eq!(exp_neg(0.0f32), 1.0);
    assert_eq!(exp_neg(88.0f32), 0.0);
    assert_eq!(exp_neg(f32::INFINITY), 0.0);
}
