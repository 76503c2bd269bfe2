//! The JSON Schema of scene files (`rtow schema`), derived from the scene
//! types (`schemars`, under the `schema` feature). The derived schemas
//! follow the types' serde attributes; the types whose reading is written
//! by hand (`de.rs`: a texture, the background, the sampler and estimator
//! names) describe here what that reading accepts.

use super::{Background, Scene, Texture};
use crate::choice::EstimatorChoice;
use crate::sampling::Sampler;
use schemars::{json_schema, JsonSchema, Schema, SchemaGenerator};
use std::borrow::Cow;

/// The schema of a scene file (JSON, and TOML read as the same data): a
/// JSON Schema (draft 2020-12) of what the scene reader accepts, less the
/// value ranges [`Scene::validate`] checks after reading.
pub fn scene_schema() -> serde_json::Value {
    let mut schema = schemars::schema_for!(Scene);
    schema.insert("title".into(), "rtow scene file".into());
    schema.insert(
        "description".into(),
        "A scene for rtow render (JSON, or TOML of the same shape). Value ranges (finite numbers, positive \
         radii, colours in range, the limits on list sizes) are checked when the scene is rendered; see \
         docs/scene-format.md."
            .into(),
    );
    schema.to_value()
}

/// A colour or a point: exactly three numbers.
fn vec3(generator: &mut SchemaGenerator) -> Schema {
    generator.subschema_for::<[f32; 3]>()
}

impl JsonSchema for Texture {
    fn schema_name() -> Cow<'static, str> {
        "Texture".into()
    }

    fn json_schema(generator: &mut SchemaGenerator) -> Schema {
        let colour = vec3(generator);
        let kind = |name: &str, fields: serde_json::Value, required: &[&str]| {
            let mut properties = serde_json::json!({ "type": { "const": name } });
            if let (Some(p), Some(f)) = (properties.as_object_mut(), fields.as_object()) {
                p.extend(f.clone());
            }
            let mut all = vec!["type"];
            all.extend_from_slice(required);
            serde_json::json!({
                "type": "object",
                "properties": properties,
                "required": all,
                "additionalProperties": false,
            })
        };
        json_schema!({
            "description": "A lambertian's albedo: a colour [r, g, b], or a checker, noise or image texture.",
            "oneOf": [
                colour,
                kind("checker", serde_json::json!({ "scale": { "type": "number" }, "even": colour, "odd": colour }),
                     &["scale", "even", "odd"]),
                kind("noise", serde_json::json!({ "scale": { "type": "number" } }), &["scale"]),
                kind("image", serde_json::json!({ "file": { "type": "string" } }), &["file"]),
            ]
        })
    }
}

impl JsonSchema for Background {
    fn schema_name() -> Cow<'static, str> {
        "Background".into()
    }

    fn json_schema(generator: &mut SchemaGenerator) -> Schema {
        let colour = vec3(generator);
        json_schema!({
            "description": "What rays that leave the scene see: \"sky\" (the sky gradient) or a colour [r, g, b].",
            "oneOf": [{ "const": "sky" }, colour]
        })
    }
}

/// A string that is one of `names`.
fn one_of(names: &[&str], description: &str) -> Schema {
    json_schema!({ "description": description, "type": "string", "enum": names })
}

impl JsonSchema for Sampler {
    fn schema_name() -> Cow<'static, str> {
        "Sampler".into()
    }

    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        one_of(Sampler::NAMES, "Where the random decisions come from.")
    }
}

impl JsonSchema for EstimatorChoice {
    fn schema_name() -> Cow<'static, str> {
        "Estimator".into()
    }

    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        one_of(EstimatorChoice::NAMES, "How paths choose their directions at diffuse vertices.")
    }
}
