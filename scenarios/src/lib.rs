//! Scenes as data and generators, OBJ and PLY loading, and sweep suites as files.
//!
//! Nothing here touches a GPU: a scene is plain vertex data plus a camera, built the same way
//! on every machine from its [`SceneSpec`] (generator name, parameters, seed).

pub mod camera;
pub mod gltf;
pub mod model;
pub mod obj;
pub mod papers;
pub mod params;
pub mod path;
pub mod ply;
pub mod problem;
pub mod scenes;
pub mod suite;

pub use camera::{Camera, CameraFileError};
pub use params::{NotExpected, ParamValue, Params, ValueKind};
pub use problem::Problem;
pub use scenes::{
    AreaLight, InvalidMesh, Light, LightKind, Material, Mesh, MeshProblem, ObjectInfo, Scene,
    SceneSpec, Sun,
};
pub use suite::{StudySpec, Suite, TimingSpec};

/// Errors from building scenes and reading suites. Each names the file, scene or value at fault.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("unknown scene generator '{0}' (known: {1})")]
    UnknownGenerator(String, String),
    #[error("scene '{scene}': parameter '{param}' = {value} is out of range: {why}")]
    OutOfRange {
        scene: String,
        param: String,
        value: String,
        why: String,
    },
    #[error("scene '{scene}': parameter '{param}' has the wrong type: expected {expected}")]
    WrongType {
        scene: String,
        param: String,
        expected: &'static str,
    },
    #[error("scene '{scene}': unknown parameter '{param}' (known: {known})")]
    UnknownParam {
        scene: String,
        param: String,
        known: String,
    },
    /// A model file (OBJ or PLY) that cannot be used.
    #[error("model file '{path}': {why}")]
    Obj { path: String, why: String },
    /// A model file with a problem on one line (`file:line: what is wrong`).
    #[error("{path}:{line}: {why}")]
    ModelLine {
        path: String,
        line: usize,
        why: String,
    },
    /// A model file that is not here but that a script of this repository fetches: the suite is
    /// valid, and its rows are skipped with this reason until the file is fetched.
    #[error("model file '{path}' not found: fetch it with `{fetch}`")]
    ModelMissing { path: String, fetch: String },
    #[error("glTF file '{path}': {why}")]
    Gltf { path: String, why: String },
    /// A camera path's keyframe file that cannot be used (`file:line: what is wrong`).
    #[error("camera path file '{path}'{}: {why}", .line.map(|l| format!(":{l}")).unwrap_or_default())]
    CameraFile {
        path: String,
        line: Option<usize>,
        why: String,
    },
    #[error("suite file '{path}': {why}")]
    Suite { path: String, why: String },
    /// Every problem found in a suite, one per line.
    #[error("{}", crate::problem::report(.0))]
    Problems(Vec<Problem>),
    /// Check mode: the parameters were read and are valid; nothing was built.
    #[error("parameters checked (nothing built)")]
    Checked,
    /// Check mode: every problem found in one scene's parameters.
    #[error("{}", .0.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("; "))]
    Many(Vec<SceneError>),
}

pub type Result<T, E = SceneError> = std::result::Result<T, E>;
