//! Bad scene files, shared by `tests/suite/cli.rs` (through the binary) and
//! `tests/suite/scene_files.rs` (through the library).
#![allow(dead_code)]

/// One bad scene file and what its error must say.
pub struct Case {
    /// File name; its extension picks the format.
    pub file: &'static str,
    pub text: String,
    /// Must appear in the error: the field's path (or, where the file has no
    /// field yet, what is wrong).
    pub names: &'static str,
    /// The error's `(line L, column C)` must fall on this token (the first
    /// occurrence in the text), for errors the parser can place.
    pub at: Option<&'static str>,
}

const CAMERA_JSON: &str = r#""camera": {"look_from": [0, 0, 0], "look_at": [0, 0, -1]}"#;
const CAMERA_TOML: &str = "[camera]\nlook_from = [0, 0, 0]\nlook_at = [0, 0, -1]\n";

/// A JSON scene: the default camera and one sphere with `sphere` as its body.
fn json_sphere(sphere: &str) -> String {
    format!("{{\n  {CAMERA_JSON},\n  \"spheres\": [\n    {{{sphere}}}\n  ]\n}}\n")
}

/// A TOML scene with one sphere whose `radius` and `material` lines are given.
fn toml_sphere(radius: &str, material: &str) -> String {
    format!("{CAMERA_TOML}\n[[spheres]]\ncenter = [0, 0, -1]\nradius = {radius}\nmaterial = {material}\n")
}

fn json_camera(camera: &str) -> String {
    format!("{{\n  \"camera\": {{{camera}}}\n}}\n")
}

fn json_render(render: &str) -> String {
    format!("{{\n  {CAMERA_JSON},\n  \"render\": {{{render}}}\n}}\n")
}

/// A JSON scene: the default camera and one medium with `medium` as its body.
fn json_media(medium: &str) -> String {
    format!("{{\n  {CAMERA_JSON},\n  \"media\": [\n    {{{medium}}}\n  ]\n}}\n")
}

fn case(file: &'static str, text: String, names: &'static str, at: Option<&'static str>) -> Case {
    Case { file, text, names, at }
}

pub fn cases() -> Vec<Case> {
    let lam = r#""material": {"type": "lambertian", "albedo": [0.5, 0.5, 0.5]}"#;
    vec![
        // Syntax.
        case(
            "missing_comma.json",
            json_sphere(&format!(r#""center": [0, 0, -1] "radius": 0.5, {lam}"#)),
            "spheres[0]",
            Some(r#""radius""#),
        ),
        case(
            "trailing_comma.json",
            json_sphere(r#""center": [0, 0, -1], "radius": 0.5, "material": {"type": "dielectric", "ior": 1.5,}"#),
            "spheres[0].material",
            Some("}}"),
        ),
        case("trailing_text.json", format!("{{{CAMERA_JSON}}}\n\n  oops\n"), "trailing characters", Some("oops")),
        case("empty.json", String::new(), "EOF while parsing", None),
        case(
            "unclosed_array.toml",
            "[camera]\nlook_from = [0, 0, 0]\nlook_at = [0, 0, -1\nvup = [0, 1, 0]\n".into(),
            "expected `,`",
            Some("vup"),
        ),
        case(
            "duplicate_key.toml",
            format!("{CAMERA_TOML}look_at = [1, 0, 0]\n"),
            "duplicate key",
            Some("look_at = [1"),
        ),
        // Unknown or missing fields, unknown material, wrong types.
        case(
            "unknown_field.json",
            json_camera(r#""look_from": [0, 0, 0], "look_at": [0, 0, -1], "zoom": 2"#),
            "camera.zoom",
            Some(r#""zoom""#),
        ),
        case("unknown_field.toml", format!("{CAMERA_TOML}zoom = 2\n"), "camera.zoom", Some("zoom")),
        case(
            "unknown_sphere_field.json",
            json_sphere(&format!(r#""center": [0, 0, -1], "radius": 0.5, "colour": 1, {lam}"#)),
            "spheres[0].colour",
            Some(r#""colour""#),
        ),
        case(
            "unknown_material.json",
            json_sphere(r#""center": [0, 0, -1], "radius": 0.5, "material": {"type": "plastic"}"#),
            "spheres[0].material.type",
            Some(r#""plastic""#),
        ),
        case(
            "unknown_material.toml",
            toml_sphere("0.5", r#"{ type = "glass", ior = 1.5 }"#),
            "spheres[0].material.type",
            Some(r#""glass""#),
        ),
        case(
            "unknown_material_field.json",
            json_sphere(
                r#""center": [0, 0, -1], "radius": 0.5, "material": {"type": "metal", "albedo": [1, 1, 1], "fuzz": 0, "shine": 1}"#,
            ),
            "spheres[0].material.shine",
            Some(r#""shine""#),
        ),
        case(
            "field_of_another_material.json",
            json_sphere(
                r#""center": [0, 0, -1], "radius": 0.5, "material": {"type": "dielectric", "ior": 1.5, "fuzz": 0}"#,
            ),
            "spheres[0].material: unknown field `fuzz` for a dielectric material",
            None,
        ),
        case(
            "missing_fuzz.toml",
            toml_sphere("0.5", r#"{ type = "metal", albedo = [1, 1, 1] }"#),
            "spheres[0].material: missing field `fuzz` for a metal material",
            None,
        ),
        case(
            "material_type_not_a_string.json",
            json_sphere(r#""center": [0, 0, -1], "radius": 0.5, "material": {"type": 3, "ior": 1.5}"#),
            "spheres[0].material.type",
            Some("3"),
        ),
        case(
            "ior_not_a_number.json",
            json_sphere(r#""center": [0, 0, -1], "radius": 0.5, "material": {"type": "dielectric", "ior": "1.5"}"#),
            "spheres[0].material.ior",
            Some(r#""1.5""#),
        ),
        case(
            "albedo_too_short.toml",
            toml_sphere("0.5", r#"{ type = "lambertian", albedo = [0.5, 0.5] }"#),
            "spheres[0].material.albedo",
            Some("[0.5, 0.5]"),
        ),
        case(
            "fuzz_overflow.json",
            json_sphere(
                r#""center": [0, 0, -1], "radius": 0.5, "material": {"type": "metal", "albedo": [1, 1, 1], "fuzz": -1e400}"#,
            ),
            "spheres[0].material.fuzz",
            Some("-1e400"),
        ),
        case("missing_camera.json", "{\"spheres\": []}\n".into(), "missing field `camera`", None),
        case(
            "wrong_type.toml",
            toml_sphere(r#""big""#, r#"{ type = "dielectric", ior = 1.5 }"#),
            "spheres[0].radius",
            Some(r#""big""#),
        ),
        case("negative_width.json", json_render(r#""width": -3"#), "render.width", Some("-3")),
        // Not finite: JSON can only overflow, TOML can say nan and inf.
        case(
            "overflow.json",
            json_sphere(&format!(r#""center": [0, 1e999, -1], "radius": 0.5, {lam}"#)),
            "spheres[0].center[1]",
            Some("1e999"),
        ),
        case(
            "f32_overflow.json",
            json_sphere(&format!(r#""center": [0, 0, -1], "radius": 1e39, {lam}"#)),
            "spheres[0].radius",
            None,
        ),
        case(
            "nan_center1.toml",
            format!(
                "{CAMERA_TOML}\n[[spheres]]\ncenter = [0, 0, -1]\ncenter1 = [0, nan, -1]\nradius = 0.5\nmaterial = {{ type = \"dielectric\", ior = 1.5 }}\n"
            ),
            "spheres[0].center1",
            None,
        ),
        case(
            "overflow_center1.json",
            json_sphere(&format!(r#""center": [0, 0, -1], "center1": [0, 1e999, -1], "radius": 0.5, {lam}"#)),
            "spheres[0].center1[1]",
            Some("1e999"),
        ),
        case("nan_radius.toml", toml_sphere("nan", r#"{ type = "dielectric", ior = 1.5 }"#), "spheres[0].radius", None),
        case(
            "inf_ior.toml",
            toml_sphere("0.5", r#"{ type = "dielectric", ior = inf }"#),
            "spheres[0].material.ior",
            None,
        ),
        case(
            "nan_albedo.toml",
            toml_sphere("0.5", r#"{ type = "lambertian", albedo = [0.5, nan, 0.5] }"#),
            "spheres[0].material.albedo",
            None,
        ),
        case(
            "inf_look_from.toml",
            "[camera]\nlook_from = [0, -inf, 0]\nlook_at = [0, 0, -1]\n".into(),
            "camera.look_from",
            None,
        ),
        case("nan_vfov.toml", format!("{CAMERA_TOML}vfov_deg = nan\n"), "camera.vfov_deg", None),
        case("nan_focus.toml", format!("{CAMERA_TOML}focus_dist = +nan\n"), "camera.focus_dist", None),
        case(
            "inf_sky.toml",
            format!("{CAMERA_TOML}[sky]\nhorizon = [1, 1, 1]\nzenith = [inf, 1, 1]\n"),
            "sky.zenith",
            None,
        ),
        // Values out of range.
        case(
            "radius_zero.json",
            json_sphere(&format!(r#""center": [0, 0, -1], "radius": 0, {lam}"#)),
            "spheres[0].radius",
            None,
        ),
        case(
            "radius_minus_zero.toml",
            toml_sphere("-0.0", r#"{ type = "dielectric", ior = 1.5 }"#),
            "spheres[0].radius",
            None,
        ),
        case(
            "fuzz_above_one.json",
            json_sphere(
                r#""center": [0, 0, -1], "radius": 0.5, "material": {"type": "metal", "albedo": [1, 1, 1], "fuzz": 1.5}"#,
            ),
            "spheres[0].material.fuzz",
            None,
        ),
        case(
            "fuzz_negative.toml",
            toml_sphere("0.5", r#"{ type = "metal", albedo = [1, 1, 1], fuzz = -0.1 }"#),
            "spheres[0].material.fuzz",
            None,
        ),
        case(
            "ior_zero.json",
            json_sphere(r#""center": [0, 0, -1], "radius": 0.5, "material": {"type": "dielectric", "ior": 0}"#),
            "spheres[0].material.ior",
            None,
        ),
        case(
            "ior_negative.toml",
            toml_sphere("0.5", r#"{ type = "dielectric", ior = -1.5 }"#),
            "spheres[0].material.ior",
            None,
        ),
        case(
            "negative_albedo.json",
            json_sphere(
                r#""center": [0, 0, -1], "radius": 0.5, "material": {"type": "lambertian", "albedo": [0.5, -0.5, 0.5]}"#,
            ),
            "spheres[0].material.albedo",
            None,
        ),
        case(
            "look_at_is_look_from.json",
            json_camera(r#""look_from": [1, 2, 3], "look_at": [1, 2, 3]"#),
            "camera.look_at",
            None,
        ),
        case("vup_parallel.json", json_camera(r#""look_from": [0, 0, 0], "look_at": [0, 5, 0]"#), "camera.vup", None),
        case(
            "vup_antiparallel.toml",
            "[camera]\nlook_from = [1, 1, 1]\nlook_at = [3, 3, 3]\nvup = [-2, -2, -2]\n".into(),
            "camera.vup",
            None,
        ),
        case(
            "vup_zero.json",
            json_camera(r#""look_from": [0, 0, 0], "look_at": [0, 0, -1], "vup": [0, 0, 0]"#),
            "camera.vup",
            None,
        ),
        case(
            "vfov_180.json",
            json_camera(r#""look_from": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 180"#),
            "camera.vfov_deg",
            None,
        ),
        case(
            "aperture_and_angle.json",
            json_camera(r#""look_from": [0, 0, 0], "look_at": [0, 0, -1], "aperture": 0.1, "defocus_angle_deg": 1"#),
            "camera.aperture",
            None,
        ),
        // The render table.
        case("width_zero.json", json_render(r#""width": 0"#), "render.width", None),
        case("height_zero.toml", format!("{CAMERA_TOML}[render]\nheight = 0\n"), "render.height", None),
        case("spp_zero.json", json_render(r#""width": 8, "samples_per_pixel": 0"#), "render.samples_per_pixel", None),
        case("depth_zero.toml", format!("{CAMERA_TOML}[render]\nmax_depth = 0\n"), "render.max_depth", None),
        case(
            "too_many_pixels.json",
            json_render(r#""width": 200000, "height": 100000"#),
            "render.width x render.height",
            None,
        ),
        case(
            "width_above_u32.toml",
            format!("{CAMERA_TOML}[render]\nwidth = 5000000000\n"),
            "render.width",
            Some("5000000000"),
        ),
        // Constant media.
        case(
            "medium_negative_density.json",
            json_media(r#""boundary": {"sphere": {"center": [0, 0, -1], "radius": 0.5}}, "density": -1, "albedo": [1, 1, 1]"#),
            "media[0].density",
            None,
        ),
        case(
            "medium_unknown_boundary.json",
            json_media(r#""boundary": {"cone": {"a": [0, 0, 0]}}, "density": 1, "albedo": [1, 1, 1]"#),
            "media[0].boundary",
            Some(r#""cone""#),
        ),
        // A boundary is one shape: two, or none, is said so.
        case(
            "medium_two_shapes.json",
            json_media(
                r#""boundary": {"sphere": {"center": [0, 0, -1], "radius": 0.5}, "box": {"a": [0, 0, 0], "b": [1, 1, 1]}}, "density": 1, "albedo": [1, 1, 1]"#,
            ),
            "media[0].boundary: gives two shapes, a sphere and a box; a medium's boundary is one of them",
            None,
        ),
        case(
            "medium_no_shape.toml",
            format!("{CAMERA_TOML}\n[[media]]\ndensity = 0.5\nalbedo = [1, 1, 1]\nboundary = {{}}\n"),
            "media[0].boundary: gives no shape; a medium's boundary is {\"sphere\"",
            None,
        ),
        case(
            "medium_flat_box.toml",
            format!(
                "{CAMERA_TOML}\n[[media]]\ndensity = 0.5\nalbedo = [1, 1, 1]\nboundary = {{ box = {{ a = [0, 0, 0], b = [1, 0, 1] }} }}\n"
            ),
            "media[0].boundary.box.b",
            None,
        ),
        case(
            "medium_zero_radius.json",
            json_media(r#""boundary": {"sphere": {"center": [0, 0, -1], "radius": 0}}, "density": 1, "albedo": [1, 1, 1]"#),
            "media[0].boundary.sphere.radius",
            None,
        ),
    ]
}

/// 1-based line and first/last column of the first occurrence of `token`.
pub fn token_span(text: &str, token: &str) -> (usize, usize, usize) {
    let at = text.find(token).unwrap_or_else(|| panic!("token {token:?} not in {text}"));
    let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let line = text[..at].matches('\n').count() + 1;
    let col = at - line_start + 1;
    (line, col, col + token.len() - 1)
}

/// The `(line L, column C)` an error message reports.
pub fn reported_position(msg: &str) -> Option<(usize, usize)> {
    let rest = &msg[msg.rfind("(line ")? + "(line ".len()..];
    let (line, rest) = rest.split_once(", column ")?;
    let col = rest.split_once(')')?.0;
    Some((line.parse().ok()?, col.parse().ok()?))
}

/// Checks that `msg` names the case's field and, where the case says, points
/// at its token (serde_json reports errors found once a value is read at the
/// column just after it, so that column counts too).
pub fn check_message(c: &Case, msg: &str) {
    assert!(msg.contains(c.names), "{}: error does not name `{}`: {msg}", c.file, c.names);
    if let Some(token) = c.at {
        let (line, first, last) = token_span(&c.text, token);
        let (l, col) = reported_position(msg).unwrap_or_else(|| panic!("{}: no line/column in: {msg}", c.file));
        assert!(
            l == line && (first..=last + 1).contains(&col),
            "{}: error at line {l}, column {col}; {token:?} is at line {line}, columns {first}-{last}: {msg}",
            c.file
        );
    }
}
