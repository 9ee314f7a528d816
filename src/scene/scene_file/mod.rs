//! TOML scene files (see assets/SCENE_FORMAT.md): models, procedural
//! primitives, materials, lights, cameras, a camera path and the environment.
//! Paths inside a scene file are relative to the file's directory.
//!
//! `schema` is the file structure serde reads; `builder` turns it into a
//! [`Scene`] with `elements` (lights, materials, transforms, procedural
//! primitives, the HDR environment), `merge` (imported glTF models), `orbit`
//! (the orbit animation) and `checks` (value validation).

mod builder;
mod checks;
mod elements;
mod merge;
mod orbit;
#[cfg(test)]
mod orbit_tests;
mod schema;
#[cfg(test)]
mod terrain_tests;
#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::path::Path;

use anyhow::{anyhow, Context, Result};

use super::Scene;
use builder::Builder;
pub use elements::{load_env_map, load_hdr};
pub use orbit::SCENE_ANIMATION;
use schema::SceneFile;

/// Loads a scene file. `Scene::load` calls `finish()` afterwards.
pub fn load(path: &Path) -> Result<Scene> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read scene file", path.display()))?;
    let file: SceneFile = toml::from_str(&text).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut builder = Builder {
        scene: Scene::default(),
        dir,
        file: path,
        text: &text,
        materials: HashMap::new(),
        default_material: None,
        orbits: Vec::new(),
    };
    builder.build(file)?;
    Ok(builder.scene)
}
