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
