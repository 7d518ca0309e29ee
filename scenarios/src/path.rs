//! Camera paths: any scene may move its camera along a declared path, for the `views` study
//! (issue 42: flicker, popping and time over a moving view, each view judged against its own
//! exact truth). A path is a scene's keys in its `[[study.scenes]]` table, beside the
//! generator's own, so it is swept, labelled and checked like every scene key:
//!
//! | key               | kinds     | what                                                        |
//! |-------------------|-----------|-------------------------------------------------------------|
//! | `camera_path`     | —         | `orbit`, `fly`, `file` or `at_rest`                          |
//! | `path_views`      | all       | views along the path (default 32)                           |
//! | `orbit_step`      | orbit     | degrees of azimuth per view about the target's vertical (default one turn over the views) |
//! | `orbit_elevation` | orbit     | degrees above the target's horizontal plane (default the scene camera's) |
//! | `orbit_distance`  | orbit     | eye–target distance as a multiple of the scene camera's (default 1) |
//! | `fly_depth`       | fly       | how far the eye travels along its view, as a multiple of its distance to the target (default 1: it ends at the target) |
//! | `path_file`       | file      | a keyframe file (format below); a glTF scene without one plays its file's camera animation |
//!
//! Every path is deterministic: the same keys give the same cameras on every machine. View 0 of
//! an orbit or a fly-through with default keys is the scene camera's eye and target; `at_rest`
//! is the scene camera itself, `path_views` times. The moving paths frame each view with the
//! scene camera's field of view and near/far ratio, the far plane just past the scene's bounding
//! sphere as seen from that eye, so geometry never leaves the depth range as the eye moves.
//!
//! Keyframe files (`path_file`): one keyframe per line, `#` starts a comment; each line is
//! `time eye_x eye_y eye_z target_x target_y target_z [fov_degrees]`, in the scene's world space
//! (a model scene's normalised space, as its `eye`/`target` keys), times strictly increasing.
//! The views sample the keyframes at evenly spaced times from the first to the last, eye, target
//! and field of view interpolated linearly. A bad line is an error naming the file and the line,
//! found by `mfx check` before any GPU work.

use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::{Camera, ParamValue, Params, Scene, SceneError, SceneSpec, ValueKind};

/// The path kinds `camera_path` may name.
pub const KINDS: &[&str] = &["orbit", "fly", "file", AT_REST];

/// The path kind whose views are one camera repeated (the at-rest measures apply).
pub const AT_REST: &str = "at_rest";

/// One declared path key: its name, what it means, its type and range, and the path kinds that
/// read it (a key given for another kind is a problem: it would change nothing).
#[derive(Clone, Copy, Debug)]
pub struct PathKey {
    pub name: &'static str,
    pub doc: &'static str,
    pub kind: ValueKind,
    pub read_by: &'static [&'static str],
}

/// The key that chooses the path.
pub const CAMERA_PATH: PathKey = PathKey {
    name: "camera_path",
    doc: "the camera path: orbit, fly, file or at_rest (absent: the scene's one view)",
    kind: ValueKind::Choice {
        default: "orbit",
        choices: KINDS,
    },
    read_by: KINDS,
};

/// Every key of a path, declared once (`mfx check` reads these).
pub const KEYS: &[PathKey] = &[
    CAMERA_PATH,
    PathKey {
        name: "path_views",
        doc: "views along the path",
        kind: ValueKind::Int {
            default: 32,
            min: 2,
            max: 4096,
        },
        read_by: KINDS,
    },
    PathKey {
        name: "orbit_step",
        doc: "degrees of azimuth per view (default: one turn over the views, 360 / path_views)",
        kind: ValueKind::Float {
            default: 11.25,
            min: -360.0,
            max: 360.0,
        },
        read_by: &["orbit"],
    },
    PathKey {
        name: "orbit_elevation",
        doc: "degrees above the target's horizontal plane (default: the scene camera's)",
        kind: ValueKind::Float {
            default: 0.0,
            min: -89.0,
            max: 89.0,
        },
        read_by: &["orbit"],
    },
    PathKey {
        name: "orbit_distance",
        doc: "eye–target distance, a multiple of the scene camera's",
        kind: ValueKind::Float {
            default: 1.0,
            min: 0.05,
            max: 100.0,
        },
        read_by: &["orbit"],
    },
    PathKey {
        name: "fly_depth",
        doc: "distance the eye travels along its view, a multiple of its distance to the target",
        kind: ValueKind::Float {
            default: 1.0,
            min: 0.01,
            max: 4.0,
        },
        read_by: &["fly"],
    },
    PathKey {
        name: "path_file",
        doc: "keyframe file (time, eye, target, [fov] per line); a glTF scene without one plays its file's camera animation",
        kind: ValueKind::Text { default: None },
        read_by: &["file"],
    },
];

/// Whether `key` is a path key (the generators never see these).
pub fn is_path_key(key: &str) -> bool {
    KEYS.iter().any(|k| k.name == key)
}

/// The generator's own parameters of `params` (the path keys left out).
pub fn generator_params(params: &Params) -> Params {
    Params(
        params
            .0
            .iter()
            .filter(|(k, _)| !is_path_key(k))
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect(),
    )
}

/// One keyframe of a path file, in the scene's world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Keyframe {
    pub time: f64,
    pub eye: DVec3,
    pub target: DVec3,
    /// Vertical field of view in degrees; `None`: the scene camera's.
    pub fov_deg: Option<f64>,
    /// Its line in the file (for messages).
    pub line: usize,
}

/// Where the views of a path come from.
#[derive(Clone, Debug, PartialEq)]
pub enum PathKind {
    /// Around the scene camera's target, about the vertical (world +y).
    Orbit {
        /// Degrees per view; `None`: 360 / views.
        step_deg: Option<f64>,
        /// Degrees; `None`: the scene camera's.
        elevation_deg: Option<f64>,
        distance: f64,
    },
    /// Along the scene camera's view, the target moving with the eye.
    Fly { depth: f64 },
    /// Keyframes read from a file.
    Keyframes { file: PathBuf, keys: Vec<Keyframe> },
    /// The first perspective camera of a glTF scene's file, played by the file's animation.
    GltfAnimation { file: PathBuf },
    /// The scene camera, every view.
    AtRest,
}

/// A scene's camera path: what the `views` study renders, one view after another.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    pub kind: PathKind,
    pub views: u32,
}

impl CameraPath {
    /// The path a scene's keys declare: `Ok(None)` without `camera_path`; `Err` lists every
    /// problem of the keys (a bad value, a key the chosen kind does not read, a keyframe file that
    /// cannot be read, naming its line).
    pub fn of(spec: &SceneSpec) -> Result<Option<CameraPath>, Vec<SceneError>> {
        let label = spec.label();
        let mut problems = Vec::new();
        let mut value = |key: &PathKey| -> Option<ParamValue> {
            let v = spec.params.get(key.name)?;
            match key.kind.check(v) {
                Ok(v) => Some(v),
                Err(why) => {
                    problems.push(SceneError::OutOfRange {
                        scene: label.clone(),
                        param: key.name.into(),
                        value: v.to_string(),
                        why: why.to_string(),
                    });
                    None
                }
            }
        };
        let given: Vec<(&PathKey, Option<ParamValue>)> = KEYS
            .iter()
            .filter(|k| spec.params.get(k.name).is_some())
            .map(|k| (k, value(k)))
            .collect();
        let get = |name: &str| {
            given
                .iter()
                .find(|(k, _)| k.name == name)
                .and_then(|(_, v)| v.clone())
        };
        let float = |name: &str| match get(name) {
            Some(ParamValue::Float(x)) => Some(x),
            _ => None,
        };
        if spec.params.get(CAMERA_PATH.name).is_none() {
            for (k, _) in &given {
                problems.push(SceneError::OutOfRange {
                    scene: label.clone(),
                    param: k.name.into(),
                    value: String::new(),
                    why: "is a camera path key, but the scene has no camera_path".into(),
                });
            }
            return if problems.is_empty() {
                Ok(None)
            } else {
                Err(problems)
            };
        }
        // A bad camera_path is already a problem: the other keys' values were checked above.
        let Some(ParamValue::Str(kind)) = get(CAMERA_PATH.name) else {
            return Err(problems);
        };
        for (k, _) in &given {
            if !k.read_by.contains(&kind.as_str()) {
                problems.push(SceneError::OutOfRange {
                    scene: label.clone(),
                    param: k.name.into(),
                    value: String::new(),
                    why: format!(
                        "is read only with camera_path = {}: with {kind} it would change nothing",
                        k.read_by.join(" | ")
                    ),
                });
            }
        }
        let views = match get("path_views") {
            Some(ParamValue::Int(n)) => n as u32,
            _ => 32,
        };
        let path_kind = match kind.as_str() {
            "orbit" => {
                let step_deg = float("orbit_step");
                if step_deg == Some(0.0) {
                    problems.push(SceneError::OutOfRange {
                        scene: label.clone(),
                        param: "orbit_step".into(),
                        value: "0".into(),
                        why: "an orbit that does not turn: use camera_path = \"at_rest\"".into(),
                    });
                }
                Some(PathKind::Orbit {
                    step_deg,
                    elevation_deg: float("orbit_elevation"),
                    distance: float("orbit_distance").unwrap_or(1.0),
                })
            }
            "fly" => Some(PathKind::Fly {
                depth: float("fly_depth").unwrap_or(1.0),
            }),
            AT_REST => Some(PathKind::AtRest),
            "file" => match (get("path_file"), spec.params.get("path")) {
                (Some(ParamValue::Str(f)), _) => match read_keyframes(Path::new(&f)) {
                    Ok(keys) => Some(PathKind::Keyframes {
                        file: PathBuf::from(f),
                        keys,
                    }),
                    Err(e) => {
                        problems.push(e);
                        None
                    }
                },
                (None, Some(ParamValue::Str(model))) if spec.generator == "gltf" => {
                    let file = PathBuf::from(model);
                    // Only when the file itself is readable: its own problem is the generator's.
                    if file.is_file() {
                        if let Err(e) = crate::gltf::camera_animation(&file, views) {
                            problems.push(e);
                        }
                    }
                    Some(PathKind::GltfAnimation { file })
                }
                _ => {
                    problems.push(SceneError::OutOfRange {
                        scene: label.clone(),
                        param: "path_file".into(),
                        value: String::new(),
                        why: "camera_path = \"file\" needs path_file = \"keys.txt\" (a glTF scene may play its own camera animation instead)".into(),
                    });
                    None
                }
            },
            _ => None,
        };
        match path_kind {
            Some(kind) if problems.is_empty() => Ok(Some(CameraPath { kind, views })),
            _ => Err(problems),
        }
    }

    /// The path's kind as `camera_path` names it.
    pub fn name(&self) -> &'static str {
        match self.kind {
            PathKind::Orbit { .. } => "orbit",
            PathKind::Fly { .. } => "fly",
            PathKind::Keyframes { .. } | PathKind::GltfAnimation { .. } => "file",
            PathKind::AtRest => AT_REST,
        }
    }

    /// Whether every view is the same camera (the at-rest measures apply).
    pub fn at_rest(&self) -> bool {
        self.kind == PathKind::AtRest
    }

    /// The cameras of the path for `scene`, whose own camera (the generator's, or the suite's
    /// eye/target) is where orbits and fly-throughs start.
    pub fn cameras(&self, scene: &Scene) -> crate::Result<Vec<Camera>> {
        let base = &scene.camera;
        let n = self.views as usize;
        let bounds = bounding_sphere(scene);
        let eye0 = DVec3::from(base.eye);
        let target0 = DVec3::from(base.target);
        let fov = base.fovy.to_degrees();
        let frame = |eye: DVec3, target: DVec3, fov: f64| framed(base, bounds, eye, target, fov);
        // Position along the path in [0, 1], view by view.
        let s = |i: usize| i as f64 / (n - 1).max(1) as f64;
        Ok(match &self.kind {
            PathKind::AtRest => vec![base.clone(); n],
            PathKind::Orbit {
                step_deg,
                elevation_deg,
                distance,
            } => {
                let off = eye0 - target0;
                let d0 = off.length();
                let az0 = off.x.atan2(off.z);
                let el0 = (off.y / d0.max(f64::MIN_POSITIVE)).clamp(-1.0, 1.0).asin();
                let el = elevation_deg.map_or(el0, f64::to_radians);
                let step = step_deg.unwrap_or(360.0 / n as f64).to_radians();
                let d = d0 * distance;
                (0..n)
                    .map(|i| {
                        let az = az0 + step * i as f64;
                        let dir = DVec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
                        frame(target0 + dir * d, target0, fov)
                    })
                    .collect()
            }
            PathKind::Fly { depth } => {
                let travel = (target0 - eye0) * *depth;
                (0..n)
                    .map(|i| frame(eye0 + travel * s(i), target0 + travel * s(i), fov))
                    .collect()
            }
            PathKind::Keyframes { keys, .. } => (0..n)
                .map(|i| {
                    let (eye, target, f) = sample_keyframes(keys, s(i));
                    frame(eye, target, f.unwrap_or(fov))
                })
                .collect(),
            PathKind::GltfAnimation { file } => {
                let Some((centre, scale)) = scene.file_normalisation else {
                    return Err(SceneError::Gltf {
                        path: file.display().to_string(),
                        why: "camera_path = \"file\" plays a glTF camera animation only on a gltf scene".into(),
                    });
                };
                crate::gltf::camera_animation(file, self.views)?
                    .into_iter()
                    .map(|c| {
                        let to_scene = |p: DVec3| (p - centre) * scale;
                        let mut cam = frame(to_scene(c.eye), to_scene(c.target), c.yfov_deg);
                        cam.up = pick_up(c.up, c.target - c.eye).into();
                        cam
                    })
                    .collect()
            }
        })
    }
}

/// The mesh's bounding sphere (centre of its box, farthest vertex), in f64.
fn bounding_sphere(scene: &Scene) -> (DVec3, f64) {
    let (lo, hi) = scene.mesh.bounds();
    let c = ((lo + hi) * 0.5).as_dvec3();
    let r = scene
        .mesh
        .positions
        .iter()
        .map(|p| (glam::Vec3::from(*p).as_dvec3() - c).length())
        .fold(0.0f64, f64::max);
    (c, r)
}

/// An up vector for a view along `dir`: `up`, or another axis where they are parallel (look_at
/// would be degenerate).
fn pick_up(up: DVec3, dir: DVec3) -> DVec3 {
    let d = dir.normalize_or_zero();
    if d.cross(up).length() < 1e-6 {
        if d.cross(DVec3::Z).length() < 1e-6 {
            DVec3::X
        } else {
            DVec3::Z
        }
    } else {
        up
    }
}

/// A view of a moving path: look-at from `eye` to `target` at `fov`, with the scene camera's up
/// and depth convention; the far plane just past the bounding sphere as seen from `eye`, the near
/// plane at the scene camera's near/far ratio of it (each generator chose that ratio for its
/// depth precision).
fn framed(base: &Camera, (c, r): (DVec3, f64), eye: DVec3, target: DVec3, fov: f64) -> Camera {
    let far = ((eye - c).length() + r) * 1.05;
    let ratio = (base.near / base.far).clamp(1e-7, 0.5);
    let mut cam = Camera::look_at(eye, target, fov, far * ratio, far);
    cam.up = pick_up(DVec3::from(base.up), target - eye).into();
    cam.reversed_z = base.reversed_z;
    cam
}

/// Eye, target and field of view at `s` ∈ [0, 1] of the keyframes' time span, linearly
/// interpolated between the keyframes around it.
fn sample_keyframes(keys: &[Keyframe], s: f64) -> (DVec3, DVec3, Option<f64>) {
    let first = &keys[0];
    let last = &keys[keys.len() - 1];
    let t = first.time + (last.time - first.time) * s;
    let i = keys.partition_point(|k| k.time <= t).clamp(1, keys.len()) - 1;
    let a = &keys[i];
    let Some(b) = keys.get(i + 1) else {
        return (a.eye, a.target, a.fov_deg);
    };
    let u = ((t - a.time) / (b.time - a.time)).clamp(0.0, 1.0);
    let fov = match (a.fov_deg, b.fov_deg) {
        (Some(x), Some(y)) => Some(x + (y - x) * u),
        (x, y) => x.or(y),
    };
    (a.eye.lerp(b.eye, u), a.target.lerp(b.target, u), fov)
}

fn file_error(path: &Path, line: Option<usize>, why: impl Into<String>) -> SceneError {
    SceneError::CameraFile {
        path: path.display().to_string(),
        line,
        why: why.into(),
    }
}

/// Reads a keyframe file (format in the module doc). The first problem is an error naming the
/// file and its line.
pub fn read_keyframes(path: &Path) -> crate::Result<Vec<Keyframe>> {
    if path.is_dir() {
        return Err(file_error(
            path,
            None,
            "is a directory, not a keyframe file",
        ));
    }
    let text = std::fs::read_to_string(path).map_err(|e| file_error(path, None, e.to_string()))?;
    parse_keyframes(&text, path)
}

/// Parses keyframe text (`path` names it in errors).
pub fn parse_keyframes(text: &str, path: &Path) -> crate::Result<Vec<Keyframe>> {
    let mut keys: Vec<Keyframe> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let body = raw.split('#').next().unwrap_or("").trim();
        if body.is_empty() {
            continue;
        }
        let fields: Vec<&str> = body
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|f| !f.is_empty())
            .collect();
        if !(7..=8).contains(&fields.len()) {
            return Err(file_error(
                path,
                Some(line),
                format!(
                    "{} fields; a keyframe is 7 or 8 numbers: time, eye x y z, target x y z, [fov in degrees]",
                    fields.len()
                ),
            ));
        }
        const NAMES: [&str; 8] = [
            "time", "eye x", "eye y", "eye z", "target x", "target y", "target z", "fov",
        ];
        let mut v = [0.0f64; 8];
        for (k, f) in fields.iter().enumerate() {
            v[k] = match f.parse::<f64>() {
                Ok(x) if x.is_finite() => x,
                _ => {
                    return Err(file_error(
                        path,
                        Some(line),
                        format!("{} '{f}' is not a finite number", NAMES[k]),
                    ))
                }
            };
        }
        let key = Keyframe {
            time: v[0],
            eye: DVec3::new(v[1], v[2], v[3]),
            target: DVec3::new(v[4], v[5], v[6]),
            fov_deg: (fields.len() == 8).then_some(v[7]),
            line,
        };
        if (key.eye - key.target).length() < 1e-9 {
            return Err(file_error(
                path,
                Some(line),
                "the target is the eye: the camera looks nowhere",
            ));
        }
        if let Some(f) = key.fov_deg.filter(|f| !(1.0..=170.0).contains(f)) {
            return Err(file_error(
                path,
                Some(line),
                format!("fov {f} is outside 1..=170 degrees"),
            ));
        }
        if let Some(prev) = keys.last() {
            if key.time <= prev.time {
                return Err(file_error(
                    path,
                    Some(line),
                    format!(
                        "time {} is not after the previous keyframe's {} (line {}): times must increase",
                        key.time, prev.time, prev.line
                    ),
                ));
            }
        }
        keys.push(key);
    }
    if keys.is_empty() {
        return Err(file_error(
            path,
            None,
            "no keyframes (every line empty or a comment)",
        ));
    }
    Ok(keys)
}

#[cfg(test)]
mod tests;
