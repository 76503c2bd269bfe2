//! `key=value` assignments to a scene (the command line's `--set`): the
//! scene as its JSON value, the value set at the key's dotted path, then read
//! back and validated as a scene file is, each assignment in turn so that an
//! error names the one that caused it.

use super::file::bound_message;
use super::{suggest, Scene};
use crate::error::{Error, Result};
use serde_json::Value;
use std::fmt;

/// One `key=value`: a dotted path (`camera.vfov_deg`, `spheres.3.radius` or
/// `spheres[3].radius`) and a JSON value (a bare word such as `lambertian`
/// is a string).
#[derive(Clone, Debug, PartialEq)]
pub struct Assignment {
    /// The text as given, for messages.
    text: String,
    path: Vec<Step>,
    value: Value,
}

/// One step of a key's path: a table's key or a list's index.
#[derive(Clone, Debug, PartialEq)]
enum Step {
    Key(String),
    Index(usize),
}

/// The longest key, in characters (a key names a path in a scene, not data).
const MAX_KEY_CHARS: usize = 256;

impl Assignment {
    /// Parses `key=value`. The value is JSON; text that is not JSON and does
    /// not start like a number, list, table or string is taken as a string.
    pub fn parse(text: &str) -> Result<Assignment> {
        let shown = crate::output::clip(text);
        let bad = |why: String| Error::Input(format!("--set {shown}: {why}"));
        let (key, raw) = text.split_once('=').ok_or_else(|| bad("expected KEY=VALUE (no `=`)".into()))?;
        let key = key.trim();
        if key.is_empty() {
            return Err(bad("the key is empty (KEY=VALUE, e.g. camera.vfov_deg=30)".into()));
        }
        if key.chars().count() > MAX_KEY_CHARS {
            return Err(bad(format!("the key is longer than {MAX_KEY_CHARS} characters")));
        }
        let path = parse_key(key).map_err(bad)?;
        let value = parse_value(raw.trim()).map_err(bad)?;
        Ok(Assignment { text: text.to_string(), path, value })
    }

    /// The key in the form error paths take (`spheres[3].radius`).
    fn dotted(&self) -> String {
        dotted(&self.path)
    }

    /// Sets the value in `root`. A key absent from a table is added (the
    /// scene's reading then refuses it if the table has no such field); an
    /// index must name an existing entry.
    fn assign(&self, root: &mut Value) -> std::result::Result<(), String> {
        let mut at = root;
        for (i, step) in self.path.iter().enumerate() {
            let here = || if i == 0 { "the scene".to_string() } else { format!("`{}`", dotted(&self.path[..i])) };
            at = match (step, at) {
                (Step::Key(k), Value::Object(map)) => map.entry(k.clone()).or_insert(Value::Object(Default::default())),
                (Step::Index(n), Value::Array(list)) => {
                    let len = list.len();
                    list.get_mut(*n).ok_or_else(|| {
                        format!(
                            "index {n} is out of range: {} has {len} entr{}",
                            here(),
                            if len == 1 { "y" } else { "ies" }
                        )
                    })?
                }
                (Step::Key(k), Value::Array(list)) => {
                    return Err(format!(
                        "{} is a list of {} entries: expected an index, got `{}`",
                        here(),
                        list.len(),
                        crate::output::clip(k)
                    ))
                }
                (step, other) => {
                    let what = match step {
                        Step::Key(_) => "a table",
                        Step::Index(_) => "a list",
                    };
                    return Err(format!("{} is {}, not {what}", here(), kind(other)));
                }
            };
        }
        *at = self.value.clone();
        Ok(())
    }
}

impl fmt::Display for Assignment {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(&crate::output::clip(&self.text))
    }
}

impl std::str::FromStr for Assignment {
    type Err = Error;
    fn from_str(s: &str) -> Result<Assignment> {
        Assignment::parse(s)
    }
}

/// `a.b[2].c` or `a.b.2.c` as steps: a segment of digits is an index.
fn parse_key(key: &str) -> std::result::Result<Vec<Step>, String> {
    let mut steps = Vec::new();
    for segment in key.split('.') {
        let (name, mut rest) = match segment.find('[') {
            Some(i) => segment.split_at(i),
            None => (segment, ""),
        };
        if name.is_empty() && (rest.is_empty() || steps.is_empty()) {
            return Err(format!("empty name in the key `{}`", crate::output::clip(key)));
        }
        if !name.is_empty() {
            steps.push(match name.parse::<usize>() {
                Ok(n) if name.bytes().all(|b| b.is_ascii_digit()) => Step::Index(n),
                _ if name.bytes().all(|b| b.is_ascii_digit()) => return Err(bad_index(name)),
                _ if name.contains(']') => return Err(format!("unmatched `]` in `{}`", crate::output::clip(segment))),
                _ => Step::Key(name.to_string()),
            });
        }
        while !rest.is_empty() {
            let inner = rest.strip_prefix('[').and_then(|r| r.split_once(']'));
            let Some((index, after)) = inner else {
                return Err(format!("expected `[index]` in `{}`", crate::output::clip(segment)));
            };
            if index.is_empty() || !index.bytes().all(|b| b.is_ascii_digit()) {
                return Err(bad_index(index));
            }
            steps.push(Step::Index(index.parse().map_err(|_| bad_index(index))?));
            rest = after;
        }
    }
    Ok(steps)
}

fn bad_index(index: &str) -> String {
    format!("`{}` is not an index (0, 1, 2, ...)", crate::output::clip(index))
}

/// The value as JSON, or a bare word as a string.
fn parse_value(raw: &str) -> std::result::Result<Value, String> {
    match serde_json::from_str(raw) {
        Ok(v) => Ok(v),
        Err(e) => {
            let json_like = raw.is_empty() || raw.starts_with(|c: char| c.is_ascii_digit() || "-+.[{\"".contains(c));
            if json_like {
                let message = e.to_string();
                let message = message.rfind(" at line ").map_or(message.as_str(), |i| &message[..i]);
                Err(bound_message(&format!("the value is not JSON: {message}")))
            } else {
                Ok(Value::String(raw.to_string()))
            }
        }
    }
}

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "a table",
    }
}

fn dotted(path: &[Step]) -> String {
    let mut s = String::new();
    for step in path {
        match step {
            Step::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Step::Index(n) => s.push_str(&format!("[{n}]")),
        }
    }
    s
}

/// `scene` with each assignment applied in turn. Each result is read as a
/// scene file's JSON is (unknown keys refused, did-you-mean included) and,
/// if `scene` itself is valid, validated ([`Scene::validate`]): the first
/// assignment that breaks either is named in the error (exit status 2).
/// No assignments: the scene unchanged (the same JSON, so the same identity).
pub fn apply(scene: &Scene, assignments: &[Assignment]) -> Result<Scene> {
    let mut scene = scene.clone();
    if assignments.is_empty() {
        return Ok(scene);
    }
    let checked = scene.validate().is_ok();
    let mut value = serde_json::to_value(&scene).expect("a scene is JSON");
    for a in assignments {
        let fail = |why: &str| Error::Input(bound_message(&format!("--set {a}: {why}")));
        a.assign(&mut value).map_err(|e| fail(&e))?;
        scene = serde_path_to_error::deserialize(&value).map_err(|e| {
            let path = e.path().to_string();
            let message = suggest::did_you_mean(&e.inner().to_string());
            if path == a.dotted() || path == "." {
                fail(&message)
            } else {
                fail(&format!("{path}: {message}"))
            }
        })?;
        if checked {
            scene.validate().map_err(|e| fail(&e.to_string()))?;
        }
    }
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steps(key: &str) -> Vec<Step> {
        parse_key(key).unwrap()
    }

    #[test]
    fn keys_take_dots_and_brackets_alike() {
        let want = vec![Step::Key("spheres".into()), Step::Index(3), Step::Key("radius".into())];
        assert_eq!(steps("spheres.3.radius"), want);
        assert_eq!(steps("spheres[3].radius"), want);
        assert_eq!(steps("a[1][2]"), vec![Step::Key("a".into()), Step::Index(1), Step::Index(2)]);
        for bad in ["a..b", ".a", "a.", "a[", "a[x]", "a[-1]", "a[]", "a[1]x", "a]", "99999999999999999999999"] {
            assert!(parse_key(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn values_are_json_or_bare_words() {
        assert_eq!(parse_value("30").unwrap(), serde_json::json!(30));
        assert_eq!(parse_value("[0.8, 0.1, 0.1]").unwrap(), serde_json::json!([0.8, 0.1, 0.1]));
        assert_eq!(parse_value("lambertian").unwrap(), serde_json::json!("lambertian"));
        assert_eq!(parse_value("\"sky\"").unwrap(), serde_json::json!("sky"));
        for bad in ["", "[1, 2", "1e999", "-", "{\"a\"}", "\"open"] {
            assert!(parse_value(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn an_assignment_changes_exactly_its_value() {
        let scene = crate::scene::preset("final").unwrap();
        let set = |texts: &[&str]| {
            let a: Vec<Assignment> = texts.iter().map(|t| Assignment::parse(t).unwrap()).collect();
            apply(&scene, &a)
        };
        let mut want = scene.clone();
        want.camera.vfov_deg = 30.0;
        want.spheres[3].radius = 2.0;
        want.render.samples_per_pixel = Some(16);
        assert_eq!(set(&["camera.vfov_deg=30", "spheres[3].radius=2", "render.samples_per_pixel=16"]).unwrap(), want);
        assert_eq!(set(&[]).unwrap(), scene);
    }

    #[test]
    fn a_wrong_assignment_is_named_with_the_nearest_key() {
        let scene = crate::scene::preset("final").unwrap();
        let err = |text: &str| apply(&scene, &[Assignment::parse(text).unwrap()]).unwrap_err().to_string();
        let e = err("camera.vfovv=30");
        assert!(e.starts_with("--set camera.vfovv=30: unknown field `vfovv`"), "{e}");
        assert!(e.ends_with("did you mean `vfov_deg`?"), "{e}");
        let e = err("spheres.99999.radius=1");
        assert!(e.contains("index 99999 is out of range: `spheres` has"), "{e}");
        let e = err("camera.vfov_deg.x=1");
        assert!(e.contains("`camera.vfov_deg` is a number, not a table"), "{e}");
        let e = err("camera.vfov_deg=NaN");
        assert!(e.contains("invalid type: string \"NaN\", expected a number"), "{e}");
        let e = err("camera.vfov_deg=1e30");
        assert!(e.starts_with("--set camera.vfov_deg=1e30: camera.vfov_deg: "), "{e}");
    }
}
