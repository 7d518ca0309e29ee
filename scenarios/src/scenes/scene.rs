//! What a scene is (the mesh, its objects, materials and lights, the camera, the spec it was
//! built from) and the geometry helpers every loader shares (normals, normalising). Apart from
//! scenes/mod.rs, which builds scenes from specs, so the loaders (obj, ply, gltf) and the
//! generators can use these types without a dependency cycle through the builder.

use glam::{DVec3, Vec3};

use crate::{Camera, Params};

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
    pub fn validate(&self, what: &str) -> std::result::Result<(), InvalidMesh> {
        let n = self.positions.len();
        let fail = |problem| {
            Err(InvalidMesh {
                what: what.to_string(),
                problem,
            })
        };
        if self.indices.is_empty() {
            return fail(MeshProblem::NoTriangles);
        }
        if !self.indices.len().is_multiple_of(3) {
            return fail(MeshProblem::IndexCount(self.indices.len()));
        }
        if self.normals.len() != n || self.colors.len() != n || self.object_ids.len() != n {
            return fail(MeshProblem::AttributeLengths(n));
        }
        if let Some(&index) = self.indices.iter().find(|&&i| i as usize >= n) {
            return fail(MeshProblem::IndexOutOfRange { index, vertices: n });
        }
        if let Some(v) = self
            .positions
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return fail(MeshProblem::NonFinite {
                vertex: v,
                p: self.positions[v],
            });
        }
        Ok(())
    }
}

/// A mesh that breaks an invariant of [`Mesh`]: `what` names the mesh (the scene's label).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{what}: {problem}")]
pub struct InvalidMesh {
    pub what: String,
    pub problem: MeshProblem,
}

/// The first invariant of [`Mesh`] a mesh breaks.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshProblem {
    #[error("no triangles")]
    NoTriangles,
    #[error("index count {0} is not a multiple of 3")]
    IndexCount(usize),
    #[error("attribute arrays differ in length from positions ({0})")]
    AttributeLengths(usize),
    #[error("index {index} out of range (vertices: {vertices})")]
    IndexOutOfRange { index: u32, vertices: usize },
    #[error("vertex {vertex} has a non-finite coordinate {p:?}")]
    NonFinite { vertex: usize, p: [f32; 3] },
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
    /// The views of the scene's camera path (`crate::path`), `camera` being the first; empty
    /// when the scene has no path (one view: `camera`).
    pub views: Vec<Camera>,
    /// The kind of camera path `views` came from (`CameraPath::name`: orbit, fly, file,
    /// at_rest); None: one view. A name, not the path, so this file stays below `path`.
    pub path: Option<&'static str>,
    /// A model scene's file space → this scene's (p' = (p − centre) · scale), for cameras the
    /// file gives (a glTF camera animation); None for generated scenes.
    pub file_normalisation: Option<(DVec3, f64)>,
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
            views: Vec::new(),
            path: None,
            file_normalisation: None,
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

/// Area-weighted vertex normals.
pub fn face_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut acc = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| Vec3::from(positions[i as usize]));
        let n = (b - a).cross(c - a);
        for &i in t {
            acc[i as usize] += n;
        }
    }
    acc.into_iter()
        .map(|n| n.normalize_or(Vec3::Y).into())
        .collect()
}

/// Centres the mesh at the origin and scales it into the unit sphere. Computed in f64: a mesh
/// at ±1e38 has a radius whose square overflows f32 (its scale would round to 0).
pub fn normalise(mesh: &mut Mesh) {
    let (centre, s) = normalisation(mesh);
    for p in &mut mesh.positions {
        *p = ((Vec3::from(*p).as_dvec3() - centre) * s).as_vec3().into();
    }
}

/// The centre and scale `normalise` applies: p' = (p − centre) · scale, in f64. A mesh of one
/// point (refused by the loaders) keeps scale 1.
pub(crate) fn normalisation(mesh: &Mesh) -> (DVec3, f64) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in &mesh.positions {
        let p = Vec3::from(*p).as_dvec3();
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let centre = (lo + hi) * 0.5;
    let radius = mesh
        .positions
        .iter()
        .map(|p| (Vec3::from(*p).as_dvec3() - centre).length())
        .fold(0.0f64, f64::max);
    let s = if radius > 0.0 && radius.is_finite() {
        1.0 / radius
    } else {
        1.0
    };
    (centre, s)
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
