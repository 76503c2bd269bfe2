//! A scene named the way a user names one: a preset or a scene file.

use super::{load_scene, preset, Scene};
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
        Err(Error::Input(format!(
            "unknown scene '{spec}': not a preset (see `rtow scenes`) and not a .json/.toml file"
        )))
    }

    /// A scene built in code, named `name`.
    pub fn built(scene: Scene, name: impl Into<String>) -> SceneSource {
        SceneSource { scene, name: name.into(), file: None }
    }
}
