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

pub mod city;
pub mod grass;
pub mod hair;
pub mod mesh;
pub mod particles;
pub mod quads;
pub mod shells;
pub mod slivers;
pub mod soft_shadow;
pub mod stiff;

use glam::{DVec3, Vec3};

use crate::{obj, Camera, Params, Result, SceneError};

/// Vertex data of a whole scene (one triangle list). Attributes are per vertex.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    /// Straight (not premultiplied) RGBA; alpha is opacity.
    pub colors: Vec<[f32; 4]>,
    pub object_ids: Vec<u32>,
    pub indices: Vec<u32>,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Appends `other`, offsetting its indices.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.colors.extend_from_slice(&other.colors);
        self.object_ids.extend_from_slice(&other.object_ids);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    /// Adds a quad (two triangles, a b c / a c d) with one colour, normal and object id.
    pub fn push_quad(&mut self, corners: [Vec3; 4], color: [f32; 4], object_id: u32) {
        let n = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .normalize_or_zero();
        let base = self.positions.len() as u32;
        for c in corners {
            self.positions.push(c.into());
            self.normals.push(n.into());
            self.colors.push(color);
            self.object_ids.push(object_id);
        }
        self.indices
            .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }

    /// Axis-aligned bounds of the positions.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in &self.positions {
            lo = lo.min(Vec3::from(*p));
            hi = hi.max(Vec3::from(*p));
        }
        (lo, hi)
    }

    /// Checks the invariants every consumer relies on; names the first violation.
    pub fn validate(&self, what: &str) -> std::result::Result<(), String> {
        let n = self.positions.len();
        if self.indices.is_empty() {
            return Err(format!("{what}: no triangles"));
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(format!(
                "{what}: index count {} is not a multiple of 3",
                self.indices.len()
            ));
        }
        if self.normals.len() != n || self.colors.len() != n || self.object_ids.len() != n {
            return Err(format!(
                "{what}: attribute arrays differ in length from positions ({n})"
            ));
        }
        if let Some(i) = self.indices.iter().find(|&&i| i as usize >= n) {
            return Err(format!("{what}: index {i} out of range (vertices: {n})"));
        }
        if let Some(v) = self
            .positions
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(format!(
                "{what}: vertex {v} has a non-finite coordinate {:?}",
                self.positions[v]
            ));
        }
        Ok(())
    }
}

/// One object of the scene (object ids index this table).
#[derive(Clone, Debug)]
pub struct ObjectInfo {
    pub name: String,
    /// Closed (watertight) surface: a ray enters and leaves it an equal number of times.
    pub closed: bool,
}

/// Surface material, per object id (used by the shading studies).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub albedo: [f32; 3],
    pub specular: [f32; 3],
    /// 0..1; specular power is 2^(1 + 10·smoothness) (BF3).
    pub smoothness: f32,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            albedo: [0.7, 0.7, 0.7],
            specular: [0.04, 0.04, 0.04],
            smoothness: 0.5,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightKind {
    Point,
    Spot,
    /// A capsule (line) light from `position` to `position + direction·length`.
    Line,
}

/// A light with finite range (used by the shading studies).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub kind: LightKind,
    pub position: [f32; 3],
    pub direction: [f32; 3],
    pub color: [f32; 3],
    pub range: f32,
    /// Spot: cosine of the outer cone half-angle.
    pub cos_outer: f32,
    /// Line: segment length.
    pub length: f32,
}

/// A directional light (the sun) for the shading studies; `None` on a scene without one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Unit vector from the surface towards the sun, world space.
    pub direction: [f32; 3],
    pub color: [f32; 3],
}

/// A square area light (the `shadows` study): the light's camera sits at the square's centre and
/// looks along its normal; the square's sides follow the camera's x and y axes. `camera.fovy`
/// and `camera.near`/`far` frame the shadow map (aspect 1).
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLight {
    pub camera: Camera,
    /// Side length of the square, world units.
    pub size: f64,
}

/// A scene ready to render.
#[derive(Clone, Debug)]
pub struct Scene {
    pub spec: SceneSpec,
    pub mesh: Mesh,
    pub camera: Camera,
    pub objects: Vec<ObjectInfo>,
    /// Maximum fragments per pixel when the generator knows it in closed form.
    pub analytic_max_depth_complexity: Option<u32>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    /// Directional light of the shading studies (none: no sun feature anywhere).
    pub sun: Option<Sun>,
    /// The square area light of soft-shadow scenes (None elsewhere).
    pub area_light: Option<AreaLight>,
}

impl Scene {
    pub fn new(spec: SceneSpec, mesh: Mesh, camera: Camera) -> Self {
        Scene {
            spec,
            mesh,
            camera,
            objects: Vec::new(),
            analytic_max_depth_complexity: None,
            materials: Vec::new(),
            lights: Vec::new(),
            sun: None,
            area_light: None,
        }
    }
    pub fn name(&self) -> &str {
        &self.spec.generator
    }
    pub fn label(&self) -> String {
        self.spec.label()
    }
}

/// What to build: a generator name and its parameters.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SceneSpec {
    pub generator: String,
    pub params: Params,
}

impl SceneSpec {
    pub fn new(generator: &str, params: Params) -> Self {
        SceneSpec {
            generator: generator.to_string(),
            params,
        }
    }
    /// `generator(k=v,...)`: stable across runs and machines.
    pub fn label(&self) -> String {
        format!("{}({})", self.generator, self.params.label())
    }
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
                why,
            })?;
        Ok(scene)
    }

    fn build_unchecked(&self) -> Result<Scene> {
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
];

/// One-line description per generator, for `mfx list scenes`.
pub fn describe(generator: &str) -> &'static str {
    match generator {
        "grass" => "blades=N (5 triangles each), alpha, seed: the thesis's grass benchmark",
        "shells" => "count, shape=sphere|box, segments, alpha, seed: nested closed shells, max depth complexity 2·count",
        "quads" => "depth_complexity=d, alpha, tilt, seed: d quads over the centre at distinct depths",
        "mesh" => "triangles=N, shape=sphere|grid, alpha: a procedural large mesh with shared vertices (geometry study)",
        "obj" => "path, instances, alpha, stand_in (the published scene it stands in for; a name only): an OBJ file via tobj or a PLY file (.ply, .ply.gz; ASCII or binary) via ply-rs-bw, normalised, instanced on a grid; alpha × the MTL dissolve (d, or 1 − Tr) where the file has materials",
        "gltf" => "path, alpha: a glTF 2.0 file (.gltf + .bin, or .glb) via the gltf crate: node transforms and instancing, normalised like obj; BLEND = transparent (baseColorFactor alpha × alpha), MASK = alpha-tested opaque, OPAQUE = occluder",
        "city" => "lights=N, blocks, room, sun, kinds=mixed|point|spot|line, range, seed: box city (or closed room) with N finite-range lights and materials",
        "slabs" => "count, tiles, distance, wall, alpha, reversed_z, seed: tiles² stacks of count nested thin closed boxes far away (thickness cancellation)",
        "csg_pair" => "offset, segments, shape=sphere|box, alpha: two overlapping closed solids, ids 0 (A) and 1 (B)",
        "coplanar" => "layers, copies, alpha, reversed_z: layers of exactly duplicated quads (z-fighting), max depth complexity layers·copies",
        "extreme" => "coord, degenerate, alpha, seed: zero-area triangles, a view-covering triangle and vertices at ±coord",
        "soft_shadow" => "case=spheres|leaves|slabs|tangent|quad|obj, light_size, light_height, …: occluders over a ground plane under a square area light",
        "particles" => "count, alpha_min, alpha_max, size, spread, seed: camera-facing low-alpha quads in a smoke column, ≈ 0.022·count layers at the centre",
        "hair" => "strands, segments, width, length, alpha, seed: thin curved ribbons hanging from a scalp, facing the camera",
        "slivers" => "count, width, alpha, span, distance, seed: thin needles crossing the view at distinct depths, nearly every covered pixel an edge (antialiasing)",
        _ => "",
    }
}

/// Deterministic colour for index `i` (golden-ratio hue walk), with the given alpha.
pub fn palette(i: u32, alpha: f32) -> [f32; 4] {
    let h = (i as f32 * 0.618_034).fract() * 6.0;
    let x = 1.0 - (h % 2.0 - 1.0).abs();
    let (r, g, b) = match h as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    // Keep channels away from 0 and 1 so compositing errors show in every channel.
    [0.15 + 0.7 * r, 0.15 + 0.7 * g, 0.15 + 0.7 * b, alpha]
}

/// A camera on +z looking at the origin, framing a sphere of `radius`.
pub fn frame_sphere(radius: f64, fovy_deg: f64) -> Camera {
    let dist = radius / (fovy_deg.to_radians() * 0.5).sin() * 1.05;
    Camera::look_at(
        DVec3::new(0.0, 0.0, dist),
        DVec3::ZERO,
        fovy_deg,
        dist * 0.05,
        dist * 4.0,
    )
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
