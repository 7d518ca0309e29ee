//! A model scene's camera, given in its suite (the `obj` and `gltf` generators): `eye` and
//! `target` as "x,y,z" in the normalised scene's space (the model fits the unit sphere about the
//! origin; instanced grids too) and `fov`, the vertical field of view in degrees. Each is checked
//! like every scene key (a malformed vector or a target at the eye is a problem naming the key);
//! without `eye` the default frame (the unit sphere in view, from +z) at `fov`.

use glam::DVec3;

use crate::camera::Camera;
use crate::params::ParamReader;
use crate::scenes::scene::frame_sphere;
use crate::{Result, SceneError};

/// What the suite gave: read before the reader's `finish`.
pub(crate) struct CameraKeys {
    eye: Option<DVec3>,
    target: DVec3,
    fov: f64,
}

fn vector(r: &mut ParamReader, label: &str, key: &'static str) -> Result<Option<DVec3>> {
    let Some(text) = r.opt_string(key)? else {
        return Ok(None);
    };
    let v: Vec<f64> = text
        .split(',')
        .filter_map(|c| c.trim().parse::<f64>().ok())
        .filter(|c| c.is_finite())
        .collect();
    if v.len() != 3 || text.split(',').count() != 3 {
        r.problem(SceneError::OutOfRange {
            scene: label.into(),
            param: key.into(),
            value: text,
            why: "must be three finite numbers \"x,y,z\"".into(),
        })?;
        return Ok(None);
    }
    Ok(Some(DVec3::new(v[0], v[1], v[2])))
}

/// Reads `eye`, `target` and `fov`.
pub(crate) fn read(r: &mut ParamReader, label: &str) -> Result<CameraKeys> {
    let fov = r.float("fov", 45.0, 1.0, 170.0)?;
    let eye = vector(r, label, "eye")?;
    let target = vector(r, label, "target")?;
    if let (Some(e), Some(t)) = (eye, target) {
        if (e - t).length() < 1e-9 {
            r.problem(SceneError::OutOfRange {
                scene: label.into(),
                param: "target".into(),
                value: format!("{},{},{}", t.x, t.y, t.z),
                why: "is the eye: the camera looks nowhere".into(),
            })?;
        }
    }
    if target.is_some() && eye.is_none() {
        r.problem(SceneError::OutOfRange {
            scene: label.into(),
            param: "target".into(),
            value: String::new(),
            why: "needs an eye = \"x,y,z\" too".into(),
        })?;
    }
    Ok(CameraKeys {
        eye,
        target: target.unwrap_or(DVec3::ZERO),
        fov,
    })
}

impl CameraKeys {
    /// Whether the suite placed the camera (then a file's own camera may not also be asked for).
    pub(crate) fn placed(&self) -> bool {
        self.eye.is_some()
    }

    /// The camera: the suite's, or the default frame at its `fov`.
    pub(crate) fn camera(&self) -> Camera {
        match self.eye {
            None => frame_sphere(1.0, self.fov),
            Some(eye) => look_at_unit_sphere(eye, self.target, DVec3::Y, self.fov),
        }
    }
}

/// A camera at `eye` looking at `target` whose depth range holds the unit sphere (the model).
pub(crate) fn look_at_unit_sphere(eye: DVec3, target: DVec3, up: DVec3, fov: f64) -> Camera {
    let far = eye.length() + 2.0;
    let mut c = Camera::look_at(eye, target, fov, far / 80.0, far);
    // An up along the view direction would make look_at degenerate: fall back to another axis.
    let dir = (target - eye).normalize_or_zero();
    let up = if dir.cross(up).length() < 1e-6 {
        DVec3::Z
    } else {
        up
    };
    c.up = up.into();
    c
}
