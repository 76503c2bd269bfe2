//! Scene files: JSON or TOML by extension, one schema (the `Scene` type).

use super::Scene;
use crate::error::{Error, Result};
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Json,
    Toml,
}

impl Format {
    pub fn from_path(path: &Path) -> Result<Format> {
        match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
            Some("json") => Ok(Format::Json),
            Some("toml") => Ok(Format::Toml),
            _ => Err(Error::Input(format!("{}: unknown scene file type (use .json or .toml)", path.display()))),
        }
    }
}

/// 1-based line and column of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, col)
}

fn field_prefix(path: &serde_path_to_error::Path) -> String {
    let mut p = path.to_string();
    // A syntax error inside an object ends the path in `?` (the key it could not read).
    while let Some(rest) = p.strip_suffix(".?") {
        p.truncate(rest.len());
    }
    if p == "." || p == "?" || p.is_empty() {
        String::new()
    } else {
        format!("{p}: ")
    }
}

impl Format {
    /// The largest file of this format rtow reads (see [`crate::limits`]).
    pub fn max_bytes(self) -> u64 {
        match self {
            Format::Json => crate::limits::MAX_JSON_BYTES,
            Format::Toml => crate::limits::MAX_TOML_BYTES,
        }
    }
}

/// Parses a scene file's bytes (values are checked when a render job is
/// resolved, or by [`Scene::validate`]): a UTF-8 byte-order mark is
/// skipped; bytes that are not UTF-8 are reported with their offset, line and
/// column; more than [`Format::max_bytes`] are refused before parsing.
pub fn scene_from_bytes(bytes: &[u8], format: Format, origin: &Path) -> Result<Scene> {
    let parse_err = |message: String| Error::Parse { path: origin.to_path_buf(), message };
    if bytes.len() as u64 > format.max_bytes() {
        return Err(parse_err(format!("{} bytes is too large: at most {}", bytes.len(), format.max_bytes())));
    }
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let at = e.valid_up_to();
        // The valid prefix is text: place the bad byte in it.
        let (l, c) = line_col(std::str::from_utf8(&bytes[..at]).unwrap_or_default(), at);
        parse_err(format!("not UTF-8: byte 0x{:02x} at byte offset {at} (line {l}, column {c})", bytes[at]))
    })?;
    scene_from_str(text, format, origin)
}

/// Parses a scene; `origin` names the source in errors. A leading
/// byte-order mark is skipped (JSON and TOML alike). The sphere list is
/// bounded while it is read ([`crate::limits::MAX_SPHERES`]); the values are
/// checked by [`Scene::validate`] (which resolving a render job runs).
pub fn scene_from_str(text: &str, format: Format, origin: &Path) -> Result<Scene> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let parse_err = |message: String| Error::Parse { path: origin.to_path_buf(), message };
    let scene: Scene = match format {
        Format::Json => {
            let mut de = serde_json::Deserializer::from_str(text);
            let scene = serde_path_to_error::deserialize(&mut de).map_err(|e| {
                let inner = e.inner();
                parse_err(format!(
                    "{}{} (line {}, column {})",
                    field_prefix(e.path()),
                    strip_position(&inner.to_string()),
                    inner.line(),
                    inner.column()
                ))
            })?;
            de.end().map_err(|e| {
                parse_err(format!("{} (line {}, column {})", strip_position(&e.to_string()), e.line(), e.column()))
            })?;
            scene
        }
        Format::Toml => {
            let de = toml::de::Deserializer::parse(text).map_err(|e| toml_err(text, &e, "", &parse_err))?;
            serde_path_to_error::deserialize(de)
                .map_err(|e| toml_err(text, e.inner(), &field_prefix(e.path()), &parse_err))?
        }
    };
    Ok(scene)
}

fn toml_err(text: &str, e: &toml::de::Error, prefix: &str, mk: &dyn Fn(String) -> Error) -> Error {
    let msg = e.message().trim().replace('\n', "; ");
    match e.span() {
        Some(span) => {
            let (l, c) = line_col(text, span.start);
            mk(format!("{prefix}{msg} (line {l}, column {c})"))
        }
        None => mk(format!("{prefix}{msg}")),
    }
}

/// serde_json appends " at line L column C"; we print position our own way.
fn strip_position(s: &str) -> String {
    match s.rfind(" at line ") {
        Some(i) => s[..i].to_string(),
        None => s.to_string(),
    }
}

/// Reads and parses a scene file (.json or .toml), reading at most
/// [`Format::max_bytes`].
pub fn load_scene(path: &Path) -> Result<Scene> {
    let format = Format::from_path(path)?;
    let bytes = crate::limits::read_bounded(path, format.max_bytes(), "scene file")?;
    scene_from_bytes(&bytes, format, path)
}

pub fn scene_to_string(scene: &Scene, format: Format) -> String {
    match format {
        Format::Json => serde_json::to_string_pretty(scene).expect("a scene always serializes") + "\n",
        Format::Toml => toml::to_string_pretty(scene).expect("a scene always serializes"),
    }
}

/// Writes a scene file, atomically, in the format its extension names.
/// A path without .json / .toml is a usage error (exit status 2) naming them.
pub fn save_scene(scene: &Scene, path: &Path) -> Result<()> {
    crate::output::check_extension(path, &["json", "toml"], "scene file")?;
    let format = Format::from_path(path)?;
    crate::output::write_atomic(path, scene_to_string(scene, format).as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::presets;

    #[test]
    fn every_preset_round_trips_through_both_formats() {
        for p in presets() {
            let scene = (p.build)();
            for format in [Format::Json, Format::Toml] {
                let text = scene_to_string(&scene, format);
                let back = scene_from_str(&text, format, Path::new("x"))
                    .unwrap_or_else(|e| panic!("{} {format:?}: {e}\n{text}", p.name));
                assert_eq!(back, scene, "{} {format:?}", p.name);
            }
        }
    }

    #[test]
    fn line_and_column_are_one_based() {
        assert_eq!(line_col("ab\ncd", 0), (1, 1));
        assert_eq!(line_col("ab\ncd", 4), (2, 2));
    }
}
