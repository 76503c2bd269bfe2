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
    // A message quotes at most a bounded part of the input (a 20 MB string
    // in a scene file must not become a 20 MB error line).
    let parse_err = |message: String| Error::Parse { path: origin.to_path_buf(), message: bound_message(&message) };
    let scene: Scene = match format {
        Format::Json => {
            let mut de = serde_json::Deserializer::from_str(text);
            let scene = serde_path_to_error::deserialize(&mut de).map_err(|e| {
                let inner = e.inner();
                parse_err(format!(
                    "{}{} (line {}, column {})",
                    field_prefix(e.path()),
                    super::suggest::did_you_mean(&strip_position(&inner.to_string())),
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
    let mut msg = super::suggest::did_you_mean(&e.message().trim().replace('\n', "; "));
    match e.span() {
        Some(span) => {
            let (l, c) = line_col(text, span.start);
            // toml says only "duplicate key": name the key and its table.
            if msg.starts_with("duplicate key") {
                if let Some(key) = text.get(span.clone()) {
                    msg = format!("duplicate key `{}`", dotted(table_before(text, span.start), key.trim()));
                }
            }
            mk(format!("{prefix}{msg} (line {l}, column {c})"))
        }
        None => mk(format!("{prefix}{msg}")),
    }
}

/// The `[table]` header in force at byte `at` of a TOML text (empty at the top).
fn table_before(text: &str, at: usize) -> &str {
    let before = text.get(..at).unwrap_or_default();
    before
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| l.trim_start_matches('[').split(']').next().unwrap_or_default().trim())
        .unwrap_or_default()
}

fn dotted(table: &str, key: &str) -> String {
    let key = crate::output::clip(key);
    if table.is_empty() {
        key
    } else {
        format!("{}.{key}", crate::output::clip(table))
    }
}

/// A message of at most [`MESSAGE_CHARS`] characters: a longer one (it
/// quotes a long input) keeps its start and its end, with the cut said.
pub fn bound_message(message: &str) -> String {
    const HEAD: usize = 200;
    const TAIL: usize = 60;
    let n = message.chars().count();
    if n <= MESSAGE_CHARS {
        return message.to_string();
    }
    let head: String = message.chars().take(HEAD).collect();
    let tail: String = message.chars().skip(n - TAIL).collect();
    format!("{head}... ({} characters cut) ...{tail}", n - HEAD - TAIL)
}

/// The longest message about a scene file, in characters.
pub const MESSAGE_CHARS: usize = 320;

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

/// A scene file's text: compact (one sphere per line), loading back into
/// the identical scene.
pub fn scene_to_string(scene: &Scene, format: Format) -> String {
    match format {
        Format::Json => {
            let mut out = Vec::new();
            let mut ser = serde_json::Serializer::with_formatter(&mut out, SceneJson::default());
            serde::Serialize::serialize(scene, &mut ser).expect("a scene always serializes");
            String::from_utf8(out).expect("JSON is UTF-8") + "\n"
        }
        Format::Toml => {
            let pretty = toml::to_string_pretty(scene).expect("a scene always serializes");
            compact_toml(&pretty).unwrap_or(pretty)
        }
    }
}

/// Containers this deep or less are written one entry per line (the top
/// object and what is directly in it); deeper ones on one line, so a file
/// has one line per sphere.
const BROKEN_DEPTH: usize = 2;

/// serde_json's formatter for scene files (numbers as serde writes them: an
/// f32 in its shortest form).
#[derive(Default)]
struct SceneJson {
    /// Per open container: whether it has an entry yet.
    open: Vec<bool>,
}

impl SceneJson {
    fn begin<W: ?Sized + std::io::Write>(&mut self, w: &mut W, bracket: &[u8]) -> std::io::Result<()> {
        self.open.push(false);
        w.write_all(bracket)
    }

    fn end<W: ?Sized + std::io::Write>(&mut self, w: &mut W, bracket: &[u8]) -> std::io::Result<()> {
        let had = self.open.pop().unwrap_or(false);
        if had && self.open.len() < BROKEN_DEPTH {
            w.write_all(b"\n")?;
            w.write_all("  ".repeat(self.open.len()).as_bytes())?;
        }
        w.write_all(bracket)
    }

    fn entry<W: ?Sized + std::io::Write>(&mut self, w: &mut W, first: bool) -> std::io::Result<()> {
        if !first {
            w.write_all(b",")?;
        }
        if let Some(has) = self.open.last_mut() {
            *has = true;
        }
        if self.open.len() <= BROKEN_DEPTH {
            w.write_all(b"\n")?;
            w.write_all("  ".repeat(self.open.len()).as_bytes())
        } else if !first {
            w.write_all(b" ")
        } else {
            Ok(())
        }
    }
}

impl serde_json::ser::Formatter for SceneJson {
    fn begin_array<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        self.begin(w, b"[")
    }
    fn end_array<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        self.end(w, b"]")
    }
    fn begin_array_value<W: ?Sized + std::io::Write>(&mut self, w: &mut W, first: bool) -> std::io::Result<()> {
        self.entry(w, first)
    }
    fn begin_object<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        self.begin(w, b"{")
    }
    fn end_object<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        self.end(w, b"}")
    }
    fn begin_object_key<W: ?Sized + std::io::Write>(&mut self, w: &mut W, first: bool) -> std::io::Result<()> {
        self.entry(w, first)
    }
    fn begin_object_value<W: ?Sized + std::io::Write>(&mut self, w: &mut W) -> std::io::Result<()> {
        w.write_all(b": ")
    }
}

/// toml's own output (`pretty`) rewritten with one sphere per line: at each
/// level the plain values first (an array of tables as an array of inline
/// tables, one per line), then each table as a `[section]`. Numbers keep
/// the text toml wrote. `None` for anything this does not handle (the
/// pretty text is used then).
fn compact_toml(pretty: &str) -> Option<String> {
    let doc = toml::de::DeTable::parse(pretty).ok()?;
    let mut out = String::new();
    toml_section(&mut out, &[], doc.get_ref())?;
    Some(out.trim_start().to_string())
}

/// A table's entries in the order of the text they were read from.
fn toml_entries<'a, 'i>(t: &'a toml::de::DeTable<'i>) -> Vec<(&'a str, &'a toml::de::DeValue<'i>)> {
    let mut v: Vec<_> = t.iter().collect();
    v.sort_by_key(|(k, _)| k.span().start);
    v.into_iter().map(|(k, v)| (k.get_ref().as_ref(), v.get_ref())).collect()
}

fn toml_key(k: &str) -> String {
    if !k.is_empty() && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
        k.to_string()
    } else {
        toml::Value::String(k.to_string()).to_string()
    }
}

fn toml_section(out: &mut String, path: &[&str], t: &toml::de::DeTable) -> Option<()> {
    use toml::de::DeValue;
    let entries = toml_entries(t);
    if !path.is_empty() {
        let name: Vec<String> = path.iter().map(|k| toml_key(k)).collect();
        out.push_str(&format!("\n[{}]\n", name.join(".")));
    }
    for (k, v) in entries.iter().filter(|(_, v)| !matches!(v, DeValue::Table(_))) {
        match v {
            DeValue::Array(a) if !a.is_empty() && a.iter().all(|e| matches!(e.get_ref(), DeValue::Table(_))) => {
                out.push_str(&format!("{} = [\n", toml_key(k)));
                for e in a {
                    out.push_str(&format!("    {},\n", toml_inline(e.get_ref())?));
                }
                out.push_str("]\n");
            }
            v => out.push_str(&format!("{} = {}\n", toml_key(k), toml_inline(v)?)),
        }
    }
    for (k, v) in entries {
        if let DeValue::Table(sub) = v {
            let mut p = path.to_vec();
            p.push(k);
            toml_section(out, &p, sub)?;
        }
    }
    Some(())
}

fn toml_inline(v: &toml::de::DeValue) -> Option<String> {
    use toml::de::DeValue;
    Some(match v {
        DeValue::String(s) => toml::Value::String(s.to_string()).to_string(),
        DeValue::Integer(i) if i.radix() == 10 => i.as_str().to_string(),
        DeValue::Integer(_) => return None,
        DeValue::Float(f) => f.as_str().to_string(),
        DeValue::Boolean(b) => b.to_string(),
        DeValue::Datetime(d) => d.to_string(),
        DeValue::Array(a) => {
            let items: Option<Vec<String>> = a.iter().map(|e| toml_inline(e.get_ref())).collect();
            format!("[{}]", items?.join(", "))
        }
        DeValue::Table(t) => {
            let items: Option<Vec<String>> = toml_entries(t)
                .into_iter()
                .map(|(k, v)| Some(format!("{} = {}", toml_key(k), toml_inline(v)?)))
                .collect();
            let items = items?;
            if items.is_empty() {
                "{}".to_string()
            } else {
                format!("{{ {} }}", items.join(", "))
            }
        }
    })
}

/// Writes the scene's meshes, flattened into world space, as one Wavefront
/// OBJ file (`rtow export SCENE -o F.obj`): an object `mesh_K` per mesh in
/// flattening order (the scene's, then each group's), its material's type
/// in a comment; materials are not in the file. Refuses a scene without
/// meshes, and one with OBJ meshes (they are files already: this writes the
/// meshes rtow generates).
pub fn save_meshes_obj(scene: &Scene, path: &Path) -> Result<()> {
    crate::output::check_extension(path, &["obj"], "mesh file")?;
    if let Some((_, field)) = scene.obj_file_fields().first() {
        return Err(crate::error::Error::invalid(
            field.as_str(),
            "names an OBJ file: export writes only the meshes rtow generates (icospheres, --tessellate N)",
        ));
    }
    let flat = scene.flatten();
    if flat.meshes.is_empty() {
        return Err(crate::error::Error::Input(
            "the scene has no meshes to write as OBJ (--tessellate N turns its spheres into meshes)".into(),
        ));
    }
    let names: Vec<(String, String)> = flat
        .meshes
        .iter()
        .enumerate()
        .map(|(k, m)| (format!("mesh_{k}"), format!("material {}", m.material.type_name())))
        .collect();
    let objects: Vec<crate::mesh::ObjObject> = flat
        .meshes
        .iter()
        .zip(&names)
        .map(|(m, (name, comment))| crate::mesh::ObjObject {
            name,
            comment,
            positions: &m.positions,
            triangles: &m.triangles,
        })
        .collect();
    let mut bytes = Vec::new();
    let header =
        format!("rtow {}: {} meshes, {} triangles", env!("CARGO_PKG_VERSION"), objects.len(), flat.triangle_count());
    crate::mesh::write_obj(&mut bytes, &header, &objects)
        .map_err(|e| crate::error::Error::Output { path: path.to_path_buf(), message: e.to_string() })?;
    crate::output::write_atomic(path, &bytes)
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
    fn exported_files_have_one_line_per_sphere() {
        let scene = crate::scene::final_scene();
        for format in [Format::Json, Format::Toml] {
            let text = scene_to_string(&scene, format);
            let sphere_lines = text.lines().filter(|l| l.contains("center")).count();
            assert_eq!(sphere_lines, scene.spheres.len(), "{format:?}");
            // One line of about 145 bytes per sphere (the old exports wrote
            // one number per line: 128 KB for this scene).
            assert!(text.len() < 150 * scene.spheres.len() + 2000, "{format:?}: {} bytes", text.len());
            assert_eq!(scene_from_str(&text, format, Path::new("x")).unwrap(), scene, "{format:?}");
        }
    }

    #[test]
    fn line_and_column_are_one_based() {
        assert_eq!(line_col("ab\ncd", 0), (1, 1));
        assert_eq!(line_col("ab\ncd", 4), (2, 2));
    }
}
