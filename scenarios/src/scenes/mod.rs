//! The scene table of contents. A scene is a triangle list with per-vertex normal, colour
//! (straight RGBA, alpha = opacity) and object id, plus a camera, built deterministically from
//! a [`SceneSpec`]. Generators:
//!
//! | name     | what                                                        | known answer            |
//! |----------|-------------------------------------------------------------|-------------------------|
//! | `grass`  | the thesis's benchmark: N blades of 5 triangles             | —                       |
//! | `shells` | nested closed spheres or boxes around the view axis         | max depth complexity 2n |
//! | `quads`  | d overlapping screen-parallel quads at distinct depths      | max depth complexity d  |
//! | `mesh`   | a procedural large mesh (bumpy sphere or wavy grid), shared vertices | —     |
//! | `obj`    | an OBJ (tobj) or PLY (ply-rs-bw, .ply.gz too) file, normalised into view, grid-instanced | — |
//! | `city`   | ground + box buildings (or a closed room) with many lights  | — (shading studies)     |
//! | `slabs`  | tiles² stacks of nested thin closed boxes far away (stiff)  | max depth complexity 2n |
//! | `csg_pair` | two overlapping closed solids, ids 0 and 1 (CSG operands) | ≤ 4 per pixel           |
//! | `coplanar` | layers of exactly duplicated quads (z-fighting)          | layers · copies         |
//! | `extreme` | degenerate triangles, ±1e7 vertices, a view-covering triangle | —                    |
//! | `soft_shadow` | occluders over a ground plane under a square area light | ray-traced visibility |
//! | `particles` | N camera-facing low-alpha quads in a smoke column (stratified depths) | ≈ 0.022·N at the centre |
//! | `hair`   | many thin curved ribbons hanging from a scalp, facing the camera | —                 |
//! | `slivers` | N thin needles crossing the view at distinct depths: nearly every pixel an edge (AA) | — |
//! | `tets`   | the distinct faces of a tetrahedralised cube with a scalar field in the colour's red channel (§6.3, Fig. 6.4) | (4T + B)/2 faces |

pub mod city;
pub mod grass;
pub mod hair;
pub mod mesh;
pub mod model_camera;
pub mod particles;
pub mod quads;
pub mod scene;
pub mod shells;
pub mod slivers;
pub mod soft_shadow;
pub mod stiff;
pub mod tets;

#[cfg(test)]
use glam::Vec3;

pub use scene::{
    face_normals, frame_sphere, normalise, palette, AreaLight, InvalidMesh, Light, LightKind,
    Material, Mesh, MeshProblem, ObjectInfo, Scene, SceneSpec, Sun,
};

use crate::{obj, Result, SceneError};

impl SceneSpec {
    /// Checks the generator and every parameter without building any geometry (every problem
    /// at once); an OBJ file named by `path` is read and checked too.
    pub fn check(&self) -> Vec<SceneError> {
        if !GENERATORS.contains(&self.generator.as_str()) {
            return vec![SceneError::UnknownGenerator(
                self.generator.clone(),
                GENERATORS.join(", "),
            )];
        }
        let mut problems = crate::params::check_params(|| self.build_unchecked());
        if let Err(p) = crate::path::CameraPath::of(self) {
            problems.extend(p);
        }
        if let Some(crate::ParamValue::Str(path)) = self.params.get("path") {
            let path = std::path::Path::new(path);
            let loaded = match self.generator.as_str() {
                "gltf" => crate::gltf::load(path).map(drop),
                _ => obj::load(path).map(drop),
            };
            if let Err(e) = loaded {
                problems.push(e);
            }
        }
        problems
    }

    /// Builds the scene, or names the bad parameter / file.
    pub fn build(&self) -> Result<Scene> {
        let scene = self.build_unchecked()?;
        scene
            .mesh
            .validate(&self.label())
            .map_err(|why| SceneError::OutOfRange {
                scene: self.label(),
                param: "mesh".into(),
                value: String::new(),
                why: why.to_string(),
            })?;
        Ok(scene)
    }

    fn build_unchecked(&self) -> Result<Scene> {
        // The path keys are every scene's, not the generator's: it builds without them, and the
        // scene then takes its path's views (the first becoming its camera).
        let path_keys = self.params.0.keys().any(|k| crate::path::is_path_key(k));
        if path_keys {
            let own = SceneSpec::new(&self.generator, crate::path::generator_params(&self.params));
            let mut scene = own.build_unchecked()?;
            scene.spec = self.clone();
            let path = crate::path::CameraPath::of(self)
                .map_err(|mut p| match p.len() {
                    1 => p.remove(0),
                    _ => SceneError::Many(p),
                })?
                .expect("a scene with path keys has a path or problems");
            scene.views = path.cameras(&scene)?;
            scene.camera = scene.views[0].clone();
            scene.path = Some(path.name());
            return Ok(scene);
        }
        Ok(match self.generator.as_str() {
            "grass" => grass::build(self)?,
            "shells" => shells::build(self)?,
            "quads" => quads::build(self)?,
            "mesh" => mesh::build(self)?,
            "obj" => obj::build(self)?,
            "gltf" => crate::gltf::build(self)?,
            "city" => city::build(self)?,
            "slabs" => stiff::slabs(self)?,
            "csg_pair" => stiff::csg_pair(self)?,
            "coplanar" => stiff::coplanar(self)?,
            "extreme" => stiff::extreme(self)?,
            "soft_shadow" => soft_shadow::build(self)?,
            "particles" => particles::build(self)?,
            "hair" => hair::build(self)?,
            "slivers" => slivers::build(self)?,
            "tets" => tets::build(self)?,
            other => {
                return Err(SceneError::UnknownGenerator(
                    other.to_string(),
                    GENERATORS.join(", "),
                ))
            }
        })
    }
}

/// Generator names, for `mfx list scenes`.
pub const GENERATORS: &[&str] = &[
    "grass",
    "shells",
    "quads",
    "mesh",
    "obj",
    "gltf",
    "slabs",
    "csg_pair",
    "coplanar",
    "extreme",
    "soft_shadow",
    "city",
    "particles",
    "hair",
    "slivers",
    "tets",
];

/// One-line description per generator, for `mfx list scenes`.
pub fn describe(generator: &str) -> &'static str {
    match generator {
        "grass" => "blades=N (5 triangles each), alpha, seed: the thesis's grass benchmark",
        "shells" => "count, shape=sphere|box, segments, alpha, seed: nested closed shells, max depth complexity 2·count",
        "quads" => "depth_complexity=d, alpha, tilt, seed: d quads over the centre at distinct depths",
        "mesh" => "triangles=N, shape=sphere|grid, alpha: a procedural large mesh with shared vertices (geometry study)",
        "obj" => "path, instances, alpha, stand_in (the published scene it stands in for; a name only), eye, target, fov (the camera: \"x,y,z\" in the normalised scene, degrees): an OBJ file via tobj or a PLY file (.ply, .ply.gz; ASCII or binary) via ply-rs-bw, normalised, instanced on a grid; alpha × the MTL dissolve (d, or 1 − Tr) where the file has materials",
        "gltf" => "path, alpha, camera=frame|file, eye, target, fov: a glTF 2.0 file (.gltf + .bin, data: URIs or .glb) via the gltf crate: node transforms and instancing, normalised like obj; BLEND = transparent (baseColorFactor × baseColorTexture alpha per vertex × alpha), MASK = alpha-tested opaque per triangle, OPAQUE = occluder, KHR_materials_transmission = see-through (× 1 − transmission), no material = palette colour; camera = file takes the file's first perspective camera",
        "city" => "lights=N, blocks, room, sun, kinds=mixed|point|spot|line, range, seed: box city (or closed room) with N finite-range lights and materials",
        "slabs" => "count, tiles, distance, wall, alpha, reversed_z, seed: tiles² stacks of count nested thin closed boxes far away (thickness cancellation)",
        "csg_pair" => "offset, segments, shape=sphere|box, alpha: two overlapping closed solids, ids 0 (A) and 1 (B)",
        "coplanar" => "layers, copies, alpha, reversed_z: layers of exactly duplicated quads (z-fighting), max depth complexity layers·copies",
        "extreme" => "coord, degenerate, alpha, seed: zero-area triangles, a view-covering triangle and vertices at ±coord",
        "soft_shadow" => "case=spheres|leaves|slabs|tangent|quad|obj, light_size, light_height, …: occluders over a ground plane under a square area light",
        "particles" => "count, alpha_min, alpha_max, size, spread, seed: camera-facing low-alpha quads in a smoke column, ≈ 0.022·count layers at the centre",
        "hair" => "strands, segments, width, length, alpha, seed: thin curved ribbons hanging from a scalp, facing the camera",
        "slivers" => "count, width, alpha, span, distance, seed: thin needles crossing the view at distinct depths, nearly every covered pixel an edge (antialiasing)",
        "tets" => "cells, alpha, distance: the distinct faces of a cube of cells³ cells split into 6 tetrahedra each, a scalar field (two blobs) in the colour's red channel: the volume and isosurface effects (Bavoil 2007 §6.3, Fig. 6.4)",
        _ => "",
    }
}

/// True if every vertex of `scene` projects inside the view (|NDC x, y| ≤ 1, depth in [0, 1]) at
/// aspect 1: the generator's camera frames all of its geometry.
#[cfg(test)]
pub(crate) fn all_in_view(scene: &Scene) -> bool {
    let m = scene.camera.clip_from_world_f64(1.0);
    scene.mesh.positions.iter().all(|p| {
        let c = m * Vec3::from(*p).as_dvec3().extend(1.0);
        let n = c / c.w;
        c.w > 0.0 && n.x.abs() <= 1.0 && n.y.abs() <= 1.0 && (0.0..=1.0).contains(&n.z)
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_generator_is_described_and_built_by_name() {
        for g in super::GENERATORS {
            assert!(!super::describe(g).is_empty(), "{g} has no describe() line");
            // Building by name reaches the generator (obj needs a path: that error names it).
            let e = super::SceneSpec::new(
                g,
                crate::Params::new().with("bogus", crate::ParamValue::Int(1)),
            )
            .build()
            .unwrap_err()
            .to_string();
            assert!(!e.contains("unknown scene generator"), "{g}: {e}");
        }
    }
}
