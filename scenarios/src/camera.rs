//! The camera: one projection shared by the GPU and the f64 CPU reference.
//!
//! Conventions (wgpu's): right-handed view space looking down −z, clip depth in [0, 1]
//! (reversed-Z maps near to 1), NDC y up, pixel (0,0) at the top-left, samples at pixel centres.

use glam::{DMat4, DVec3, Mat4};

#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Camera {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    /// Vertical field of view in radians.
    pub fovy: f64,
    pub near: f64,
    pub far: f64,
    /// Reversed-Z: near plane at depth 1, far at 0 (better f32 depth precision far away).
    pub reversed_z: bool,
    /// When set, this matrix (clip from world, row-major as JSON gives it) replaces eye/target/fov.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clip_from_world_override: Option<[[f64; 4]; 4]>,
}

impl Camera {
    pub fn look_at(eye: DVec3, target: DVec3, fovy_deg: f64, near: f64, far: f64) -> Self {
        Camera {
            eye: eye.into(),
            target: target.into(),
            up: [0.0, 1.0, 0.0],
            fovy: fovy_deg.to_radians(),
            near,
            far,
            reversed_z: false,
            clip_from_world_override: None,
        }
    }

    pub fn view(&self) -> DMat4 {
        DMat4::look_at_rh(self.eye.into(), self.target.into(), self.up.into())
    }

    pub fn proj(&self, aspect: f64) -> DMat4 {
        if self.reversed_z {
            DMat4::perspective_rh(self.fovy, aspect, self.far, self.near)
        } else {
            DMat4::perspective_rh(self.fovy, aspect, self.near, self.far)
        }
    }

    /// Clip from world in f64, before rounding to f32.
    pub fn clip_from_world_f64(&self, aspect: f64) -> DMat4 {
        match self.clip_from_world_override {
            Some(rows) => DMat4::from_cols_array_2d(&rows).transpose(),
            None => self.proj(aspect) * self.view(),
        }
    }

    /// The f32 matrix the GPU receives. The CPU reference widens exactly this matrix to f64,
    /// so both project with the same numbers and only the arithmetic precision differs.
    pub fn clip_from_world_gpu(&self, aspect: f64) -> Mat4 {
        self.clip_from_world_f64(aspect).as_mat4()
    }

    /// Row-major rows of the GPU's matrix, for the camera JSON given to outside tools.
    pub fn clip_from_world_rows(&self, aspect: f64) -> [[f64; 4]; 4] {
        self.clip_from_world_gpu(aspect)
            .as_dmat4()
            .transpose()
            .to_cols_array_2d()
    }

    /// True if clip depth `a` is nearer the eye than `b` under this camera's depth convention.
    pub fn nearer(&self, a: f64, b: f64) -> bool {
        if self.reversed_z {
            a > b
        } else {
            a < b
        }
    }

    /// Depth value of an empty (cleared) pixel.
    pub fn clear_depth(&self) -> f32 {
        if self.reversed_z {
            0.0
        } else {
            1.0
        }
    }
}

/// Why a camera file cannot be applied (the caller names the file).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CameraFileError {
    #[error("clip_from_world has a non-finite entry")]
    NonFinite,
    #[error("near {near} and far {far} must satisfy 0 < near < far")]
    NearFar { near: f64, far: f64 },
    #[error("width {width} × height {height} is empty")]
    Empty { width: u32, height: u32 },
}

/// The camera as JSON for outside tools (`mfx render --camera-out / --camera-in`).
///
/// Matrices are row-major: `clip = M · [x, y, z, 1]ᵀ` with `M[row][col]`. Clip space is wgpu's:
/// x, y ∈ [−w, w] (NDC y up), depth z/w ∈ [0, 1] (with `reversed_z`, 1 at the near plane).
/// Pixel (px, py), (0,0) top-left, samples NDC x = (2(px + ½)/width) − 1,
/// y = 1 − 2(py + ½)/height.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CameraFile {
    /// A one-line reminder of the conventions above (ignored when read).
    #[serde(default)]
    pub conventions: String,
    pub width: u32,
    pub height: u32,
    pub near: f64,
    pub far: f64,
    #[serde(default)]
    pub reversed_z: bool,
    /// Scene world coordinates → clip space: the f32 matrix the GPU uses, widened to f64.
    pub clip_from_world: [[f64; 4]; 4],
    /// For OBJ scenes, per instance: the OBJ file's own vertex coordinates → clip space
    /// (clip_from_world · world_from_object). Empty for generated scenes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub clip_from_object: Vec<[[f64; 4]; 4]>,
    /// For OBJ scenes, per instance: file coordinates → world (normalisation + grid placement).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub world_from_object: Vec<[[f64; 4]; 4]>,
    /// The look-at camera the matrix came from (informative; absent for matrix-only cameras).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eye: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fovy_rad: Option<f64>,
}

pub const CAMERA_CONVENTIONS: &str = "row-major M, clip = M*[x,y,z,1]; wgpu clip space: \
     depth z/w in [0,1] (reversed_z: near=1), NDC y up; pixel (0,0) top-left, samples at pixel \
     centres: ndc_x = 2(px+0.5)/width-1, ndc_y = 1-2(py+0.5)/height";

fn rows(m: DMat4) -> [[f64; 4]; 4] {
    m.transpose().to_cols_array_2d()
}

impl CameraFile {
    /// The file of `camera` at width × height; `world_from_object` per OBJ instance (or none).
    pub fn of(camera: &Camera, width: u32, height: u32, world_from_object: &[DMat4]) -> Self {
        let aspect = width as f64 / height as f64;
        let clip = camera.clip_from_world_gpu(aspect).as_dmat4();
        let look = camera.clip_from_world_override.is_none();
        CameraFile {
            conventions: CAMERA_CONVENTIONS.into(),
            width,
            height,
            near: camera.near,
            far: camera.far,
            reversed_z: camera.reversed_z,
            clip_from_world: rows(clip),
            clip_from_object: world_from_object.iter().map(|w| rows(clip * *w)).collect(),
            world_from_object: world_from_object.iter().map(|w| rows(*w)).collect(),
            eye: look.then_some(camera.eye),
            target: look.then_some(camera.target),
            up: look.then_some(camera.up),
            fovy_rad: look.then_some(camera.fovy),
        }
    }

    /// Applies this file to a scene's camera: the matrix overrides the look-at camera (whose
    /// eye/target stay for view-space quantities unless the file gives its own).
    pub fn apply(&self, camera: &mut Camera) -> Result<(), CameraFileError> {
        if self
            .clip_from_world
            .iter()
            .flatten()
            .any(|v| !v.is_finite())
        {
            return Err(CameraFileError::NonFinite);
        }
        if !(self.near > 0.0 && self.far > self.near) {
            return Err(CameraFileError::NearFar {
                near: self.near,
                far: self.far,
            });
        }
        if self.width == 0 || self.height == 0 {
            return Err(CameraFileError::Empty {
                width: self.width,
                height: self.height,
            });
        }
        camera.clip_from_world_override = Some(self.clip_from_world);
        camera.near = self.near;
        camera.far = self.far;
        camera.reversed_z = self.reversed_z;
        if let (Some(e), Some(t)) = (self.eye, self.target) {
            camera.eye = e;
            camera.target = t;
        }
        if let Some(u) = self.up {
            camera.up = u;
        }
        if let Some(f) = self.fovy_rad {
            camera.fovy = f;
        }
        Ok(())
    }
}
