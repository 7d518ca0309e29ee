//! Scenes as data and generators, OBJ loading, and sweep suites as files.
//!
//! Nothing here touches a GPU: a scene is plain vertex data plus a camera, built the same way
//! on every machine from its [`SceneSpec`] (generator name, parameters, seed).

pub mod camera;
pub mod obj;
pub mod params;
pub mod scenes;
pub mod suite;

pub use camera::Camera;
pub use params::{ParamValue, Params};
pub use scenes::{AreaLight, Light, LightKind, Material, Mesh, ObjectInfo, Scene, SceneSpec, Sun};
pub use suite::{StudySpec, Suite};

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
    #[error("OBJ file '{path}': {why}")]
    Obj { path: String, why: String },
    #[error("suite file '{path}': {why}")]
    Suite { path: String, why: String },
}

pub type Result<T, E = SceneError> = std::result::Result<T, E>;
