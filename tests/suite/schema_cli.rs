//! `rtow schema`, through the binary: a JSON Schema every preset's export
//! satisfies, and that refuses documents the scene reader refuses.

use crate::common;

use common::rtow;
use rtow::scene::{presets, scene_from_str, scene_to_string, Format};
use serde_json::{json, Value};
use std::path::Path;

/// The schema `rtow schema` prints, compiled.
fn validator() -> jsonschema::Validator {
    let dir = tempfile::tempdir().unwrap();
    let r = rtow(dir.path(), &["schema"]);
    r.ok();
    let schema: Value = serde_json::from_str(&r.stdout).expect("rtow schema prints JSON");
    assert_eq!(schema["$schema"], "https://json-schema.org/draft/2020-12/schema");
    jsonschema::validator_for(&schema).expect("a valid JSON Schema")
}

/// The validator's first error about `doc`, if any.
fn refusal(v: &jsonschema::Validator, doc: &Value) -> Option<String> {
    v.iter_errors(doc).next().map(|e| format!("{e} at {}", e.instance_path()))
}

#[test]
fn every_presets_export_satisfies_the_schema() {
    let v = validator();
    for p in presets() {
        let scene = (p.build)();
        let doc: Value = serde_json::from_str(&scene_to_string(&scene, Format::Json)).unwrap();
        if let Some(e) = refusal(&v, &doc) {
            panic!("{}: {e}", p.name);
        }
        // TOML files are the same data: the TOML export, read as data, too.
        let toml: toml::Value = toml::from_str(&scene_to_string(&scene, Format::Toml)).unwrap();
        let doc = serde_json::to_value(toml).unwrap();
        if let Some(e) = refusal(&v, &doc) {
            panic!("{} (TOML): {e}", p.name);
        }
    }
}

#[test]
fn the_schema_refuses_what_the_reader_refuses() {
    let v = validator();
    let base = serde_json::from_str::<Value>(&scene_to_string(&rtow::scene::final_scene(), Format::Json)).unwrap();
    let sphere = |s: Value| {
        let mut doc = base.clone();
        doc["spheres"][0] = s;
        doc
    };
    let lambertian = json!({"type": "lambertian", "albedo": [0.5, 0.5, 0.5]});
    let mut no_camera = base.clone();
    no_camera.as_object_mut().unwrap().remove("camera");
    let mut typo = base.clone();
    typo["camera"]["vfovv"] = json!(30);
    let wrong: Vec<(&str, Value)> = vec![
        ("no camera", no_camera),
        ("an unknown camera field", typo),
        ("a radius as a string", sphere(json!({"center": [0, 0, 0], "radius": "1", "material": lambertian}))),
        ("a centre of 4 numbers", sphere(json!({"center": [0, 0, 0, 0], "radius": 1, "material": lambertian}))),
        ("an unknown material", sphere(json!({"center": [0, 0, 0], "radius": 1, "material": {"type": "glass"}}))),
        (
            "another type's field",
            sphere(
                json!({"center": [0, 0, 0], "radius": 1, "material": {"type": "dielectric", "ior": 1.5, "fuzz": 0}}),
            ),
        ),
        (
            "a texture on a metal",
            sphere(json!({"center": [0, 0, 0], "radius": 1,
                "material": {"type": "metal", "fuzz": 0, "albedo": {"type": "noise", "scale": 4}}})),
        ),
        ("a background word", {
            let mut d = base.clone();
            d["background"] = json!("night");
            d
        }),
        ("an unknown sampler", {
            let mut d = base.clone();
            d["render"] = json!({"sampler": "halton"});
            d
        }),
        ("a negative width", {
            let mut d = base.clone();
            d["render"] = json!({"width": -1});
            d
        }),
        ("a boundary of two shapes", {
            let mut d = base.clone();
            d["media"] = json!([{"boundary": {"sphere": {"center": [0, 0, 0], "radius": 1},
                "box": {"a": [0, 0, 0], "b": [1, 1, 1]}}, "density": 1, "albedo": [1, 1, 1]}]);
            d
        }),
    ];
    for (what, doc) in wrong {
        // The reader refuses it (so the schema must).
        let text = serde_json::to_string(&doc).unwrap();
        assert!(scene_from_str(&text, Format::Json, Path::new("x.json")).is_err(), "{what}: the reader accepts it");
        assert!(refusal(&v, &doc).is_some(), "{what}: the schema accepts it");
    }
    // And what it accepts beyond the exports: a texture, a constant background, a sampler.
    let mut doc = sphere(json!({"center": [0, 0, 0], "radius": 1,
        "material": {"type": "lambertian", "albedo": {"type": "checker", "scale": 0.3, "even": [0, 0, 0], "odd": [1, 1, 1]}}}));
    doc["background"] = json!([0, 0, 0]);
    doc["render"] = json!({"sampler": "sobol", "estimator": "nee-mis", "samples_per_pixel": 4});
    scene_from_str(&serde_json::to_string(&doc).unwrap(), Format::Json, Path::new("x.json")).unwrap();
    assert_eq!(refusal(&v, &doc), None);
}
