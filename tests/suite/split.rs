//! `rtow converge --split`: the error of each estimator split by path length
//! and strategy. Every term a kernel adds reaches the probe (the buckets add
//! up to the image), each strategy appears only under the estimators that
//! have it, and terms the estimators share have the same variance.

use crate::common;

use common::{job, rtow, settings, Run};
use rtow::instruments::converge::{self, ConvergeConfig, ConvergeSpec, Reference, Split, Variant, LENGTHS};
use rtow::instruments::probe::Strategy;
use rtow::scene::preset;
use rtow::{KernelChoice, RenderOptions};
use std::path::Path;

fn splits() -> Vec<Split> {
    let scene = preset("rol-cornell-box").unwrap();
    let j = job(
        &scene,
        settings(24, 24, 16, 12, 5),
        RenderOptions { kernel: KernelChoice::Simd, threads: Some(2), ..Default::default() },
    );
    let cfg = ConvergeConfig::new(ConvergeSpec {
        kernels: vec![KernelChoice::Simd],
        variants: ["bsdf+sobol", "book+sobol", "nee-mis+sobol"].map(|v| Variant::parse(v).unwrap()).to_vec(),
        spp_list: vec![4, 16],
        reference: Reference::Spp(32),
        repeat: 1,
        adaptive_min: 16,
        at_spp: None,
        split: Some(16),
        split_seeds: 3,
    })
    .unwrap();
    let report = converge::run(&j, "rol-cornell-box", &cfg, |_| {}).unwrap();
    assert!(report.markdown().contains("## Where the error lives: 16 spp, 3 seeds"));
    assert_eq!(report.split_csv().lines().next().unwrap().split(',').count(), 10);
    report.splits
}

fn total(sp: &Split, s: Strategy) -> f64 {
    (0..LENGTHS).map(|l| sp.var_of(l, s)).sum()
}

#[test]
fn the_split_accounts_for_every_term_and_tells_the_strategies_apart() {
    let sp = splits();
    let [bsdf, book, nee] = [&sp[0], &sp[1], &sp[2]];
    for s in &sp {
        let name = s.variant.name();
        // The buckets add up to the image, pixel by pixel (f64 sums of the f32 terms).
        assert!(s.unaccounted < 1e-5, "{name}: {}", s.unaccounted);
        assert!(s.total_var > 0.0 && s.total_var.is_finite(), "{name}");
        assert_eq!((s.spp, s.seeds), (16, 3));
        // The box has no sky: nothing reaches the background.
        assert_eq!(total(s, Strategy::Background), 0.0, "{name}");
        // Camera rays that see the light directly are the same paths under every estimator.
        assert_eq!(s.var_of(0, Strategy::Specular), bsdf.var_of(0, Strategy::Specular), "{name}");
        assert!(s.var_of(0, Strategy::Specular) > 0.0);
        // Nothing scatters before the camera ray's hit.
        assert_eq!(s.var_of(0, Strategy::Scattered), 0.0, "{name}");
        assert!(total(s, Strategy::Scattered) > 0.0, "{name}");
    }
    // Light samples only under nee-mis, and from the second segment on.
    assert_eq!(total(bsdf, Strategy::LightSample), 0.0);
    assert_eq!(total(book, Strategy::LightSample), 0.0);
    assert!(total(nee, Strategy::LightSample) > 0.0);
    assert_eq!(nee.var_of(0, Strategy::LightSample), 0.0);
    // Direct light (length 2): the light sample, weighted against the
    // scattered direction, beats the cosine lobe by far.
    let direct = |s: &Split| s.by_length(1).1;
    assert!(direct(nee) * 10.0 < direct(bsdf), "{} vs {}", direct(nee), direct(bsdf));
    // The same expected image: each length's mean agrees across estimators
    // within its noise (three seeds at 16 spp: a loose bound).
    for l in 0..4 {
        let (mb, vb) = bsdf.by_length(l);
        let (mn, vn) = nee.by_length(l);
        assert!((mb - mn).abs() < 4.0 * ((vb + vn) / 3.0).sqrt() + 1e-6, "length {}: {mb} vs {mn}", l + 1);
    }
}

fn run(dir: &Path, args: &[&str]) -> Run {
    rtow(dir, args)
}

#[test]
fn converge_split_writes_its_table_and_refuses_bad_settings() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let base = [
        "converge",
        "nw-cornell-smoke",
        "--width",
        "12",
        "--height",
        "12",
        "--depth",
        "8",
        "--variants",
        "bsdf,nee-mis",
        "--spp-list",
        "2,4",
        "--reference-spp",
        "8",
        "--sampler",
        "independent",
        "--threads",
        "1",
        "--out",
        "out",
    ];
    let mut args = base.to_vec();
    args.extend(["--split", "4", "--split-seeds", "2"]);
    let o = run(d, &args);
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(o.stdout.contains("split: nee-mis: MSE"), "{}", o.stdout);
    let csv = std::fs::read_to_string(d.join("out/nw-cornell-smoke-split.csv")).unwrap();
    assert!(csv.lines().any(|l| l.contains(",nee-mis,4,2,") && l.contains(",light sample,")), "{csv}");
    assert!(!csv.lines().any(|l| l.contains(",bsdf,") && l.contains(",light sample,")), "{csv}");
    let md = std::fs::read_to_string(d.join("out/nw-cornell-smoke.md")).unwrap();
    assert!(md.contains("MSE x seconds by path length"), "{md}");

    // Refused before anything renders, naming the setting; nothing written.
    for (extra, needle) in [
        (&["--split", "3"][..], "split: 3 is not one of the sample counts"),
        (&["--split", "4", "--split-seeds", "1"], "split_seeds:"),
        (&["--split", "4", "--variants", "adaptive"], "is adaptive"),
        (&["--split", "4", "--size", "400"], "at most 40000"),
    ] {
        let mut args = base.to_vec();
        args[base.len() - 1] = "out2";
        match extra {
            [split, n, "--size", px] => {
                (args[3], args[5]) = (px, px);
                args.extend([*split, *n]);
            }
            _ => args.extend(extra),
        }
        let o = run(d, &args);
        assert_eq!(o.code, 2, "{extra:?}: {}", o.stderr);
        assert!(o.stderr.contains(needle), "{extra:?}: {}", o.stderr);
        assert!(!o.stdout.contains("reference: done"), "{extra:?}: rendered before refusing");
        assert!(!d.join("out2").exists(), "{extra:?}");
    }
}
