//! A scene named the way a user names one: a preset or a scene file.

use super::{load_scene, preset, presets, Scene};
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// A scene with where it came from: its name (for default output names) and
/// the file it was read from, if any (errors about the scene name it).
#[derive(Clone, Debug)]
pub struct SceneSource {
    pub scene: Scene,
    /// The preset's name, or the file's stem.
    pub name: String,
    /// The scene file (`None` for a preset).
    pub file: Option<PathBuf>,
}

impl SceneSource {
    /// A preset name (see [`crate::scene::presets`]) or a `.json` / `.toml` scene file.
    pub fn open(spec: &str) -> Result<SceneSource> {
        if let Some(scene) = preset(spec) {
            return Ok(SceneSource { scene, name: spec.to_string(), file: None });
        }
        let path = Path::new(spec);
        if path.extension().is_some() || path.exists() {
            let scene = load_scene(path)?;
            let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into());
            return Ok(SceneSource { scene, name, file: Some(path.to_path_buf()) });
        }
        let hint = nearest_preset(spec).map_or(String::new(), |p| format!("did you mean '{p}'? "));
        Err(Error::Input(format!(
            "unknown scene '{}': not a preset ({hint}see `rtow scenes`) and not a .json/.toml file",
            crate::output::clip(spec)
        )))
    }

    /// A scene built in code, named `name`.
    pub fn built(scene: Scene, name: impl Into<String>) -> SceneSource {
        SceneSource { scene, name: name.into(), file: None }
    }
}

/// The preset a mistyped name most likely meant: the most similar name
/// (Jaro-Winkler, as the command line's own suggestions), if similar enough.
pub fn nearest_preset(spec: &str) -> Option<&'static str> {
    super::suggest::nearest(spec, presets().iter().map(|p| p.name))
}

#[cfg(test)]
mod tests {
    use super::nearest_preset;

    #[test]
    fn a_mistyped_preset_gets_the_nearest_name() {
        assert_eq!(nearest_preset("fnal"), Some("final"));
        assert_eq!(nearest_preset("nw-cornel-box"), Some("nw-cornell-box"));
        assert_eq!(nearest_preset("rol-cornell"), Some("rol-cornell-box"));
        assert_eq!(nearest_preset("ch7-diffuse"), Some("ch07-diffuse"));
        assert_eq!(nearest_preset("teapot"), None);
        assert_eq!(nearest_preset(""), None);
    }
}
