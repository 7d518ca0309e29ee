//! One door for a model file, whatever its format: the scene generator that reads it (`gltf` for
//! `.gltf`/`.glb`, `obj` for OBJ and PLY) and its mesh, as `mfx render --model` and `mfx model`
//! take it.

use std::path::Path;

use crate::scenes::scene::Mesh;
use crate::Result;

/// The scene generator that reads `path`, by its extension: `gltf` for `.gltf` and `.glb`,
/// `obj` for everything else (`.obj`, `.ply`, `.ply.gz`: the obj generator reads both).
pub fn generator_for(path: &Path) -> &'static str {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("gltf" | "glb") => "gltf",
        _ => "obj",
    }
}

/// Loads a model file as its scene generator would (before normalising).
pub fn load(path: &Path) -> Result<Mesh> {
    match generator_for(path) {
        "gltf" => crate::gltf::load(path),
        _ => crate::obj::load(path),
    }
}
