//! glTF 2.0 scenes through the `gltf` crate, as users ship them: `.gltf` with external buffers,
//! `.gltf` with `data:` URIs (base64, the Khronos samples' "glTF-Embedded" form) and `.glb`
//! alike (the crate's import reads each source). Every triangle primitive of the default scene's
//! node hierarchy, node transforms applied (a mesh used by several nodes is instanced),
//! normalised and framed as OBJ scenes are.
//!
//! Materials map onto how scenes carry opacity (vertex colour and alpha; alpha 1 is an opaque
//! occluder). A vertex's colour is `baseColorFactor` × its `baseColorTexture` texel (sampled
//! per vertex, nearest, at the texture's TEXCOORD set with its sampler's wrap; the per-vertex
//! value is interpolated across the triangle as every scene's colours are):
//! - `OPAQUE`: alpha 1, whatever the factor or texture say (the spec ignores alpha then);
//! - `MASK`: alpha-tested against `alphaCutoff` (default 0.5) per triangle: a triangle whose
//!   vertices' mean alpha passes is drawn opaque (alpha 1), one that fails is dropped (mfx
//!   captures fragments of triangles, so the test cannot be per texel);
//! - `BLEND`: transparent, opacity = the vertex's alpha × the scene's `alpha`;
//! - `KHR_materials_transmission` (any mode): transparent, opacity × (1 − transmissionFactor):
//!   a multi-fragment capture has no refraction, so transmitted light is read as see-through.
//! - No material (glTF's default: opaque white): white on the white background would show
//!   nothing and every method would "match" it, so such primitives get mfx's palette colour of
//!   their node (as OBJ objects without materials do) and stay opaque; a warning says so.
//!
//! Bad files are errors naming the file and the element: unreadable, invalid glTF, a buffer
//! missing, short or a bad `data:` URI, an accessor whose count × stride runs past its buffer
//! view, a view past its buffer, an image that does not decode, no triangles.

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Vec3};

use crate::scenes::scene::{face_normals, normalise, palette, Mesh, ObjectInfo, Scene, SceneSpec};
use crate::{Result, SceneError};

fn err(path: &Path, why: impl Into<String>) -> SceneError {
    SceneError::Gltf {
        path: path.display().to_string(),
        why: why.into(),
    }
}

/// Loads a glTF/GLB file into one mesh in the file's world space (materials as above); object
/// id = the node instance (in traversal order), so repeated meshes stay apart. Warnings go to
/// stderr, once per file and message.
pub fn load(path: &Path) -> Result<Mesh> {
    let (mesh, warnings) = load_with_warnings(path)?;
    static SAID: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    let mut said = SAID.lock().unwrap_or_else(|e| e.into_inner());
    for w in warnings {
        if !said.contains(&w) {
            eprintln!("warning: {w}");
            said.push(w);
        }
    }
    Ok(mesh)
}

/// Where a buffer's bytes come from, for messages.
fn source_name(src: &::gltf::buffer::Source) -> String {
    match src {
        ::gltf::buffer::Source::Bin => "the GLB BIN chunk".into(),
        ::gltf::buffer::Source::Uri(u) if u.starts_with("data:") => "a data: URI".into(),
        ::gltf::buffer::Source::Uri(u) => u.to_string(),
    }
}

/// Every buffer view inside its buffer and every accessor (and sparse part) inside its view,
/// before any reader touches them: `count` × stride past the view is an error naming both.
fn check_accessors(
    path: &Path,
    doc: &::gltf::Document,
    buffers: &[::gltf::buffer::Data],
) -> Result<()> {
    for v in doc.views() {
        let b = v.buffer();
        let have = buffers.get(b.index()).map_or(0, |d| d.len()) as u128;
        let end = v.offset() as u128 + v.length() as u128;
        if end > b.length() as u128 || end > have {
            return Err(err(
                path,
                format!(
                    "buffer view {}: bytes {}..{end} run past buffer {} ({} B)",
                    v.index(),
                    v.offset(),
                    b.index(),
                    b.length().min(have as usize)
                ),
            ));
        }
    }
    // (view, offset, count, element size, stride) of one stored array.
    let fits = |what: String,
                view: &::gltf::buffer::View,
                offset: usize,
                count: usize,
                elem: usize| {
        let stride = view.stride().unwrap_or(elem).max(elem);
        let need = if count == 0 {
            0
        } else {
            offset as u128 + (count as u128 - 1) * stride as u128 + elem as u128
        };
        if need > view.length() as u128 {
            return Err(err(
                path,
                format!(
                    "{what}: count {count} × stride {stride} B from offset {offset} needs {need} B, past buffer view {} ({} B)",
                    view.index(),
                    view.length()
                ),
            ));
        }
        Ok(())
    };
    for a in doc.accessors() {
        let elem = a.size();
        if let Some(view) = a.view() {
            fits(
                format!("accessor {}", a.index()),
                &view,
                a.offset(),
                a.count(),
                elem,
            )?;
        }
        if let Some(sp) = a.sparse() {
            let ix = sp.indices();
            let ix_size = match ix.index_type() {
                ::gltf::accessor::sparse::IndexType::U8 => 1,
                ::gltf::accessor::sparse::IndexType::U16 => 2,
                ::gltf::accessor::sparse::IndexType::U32 => 4,
            };
            fits(
                format!("accessor {} sparse indices", a.index()),
                &ix.view(),
                ix.offset(),
                sp.count(),
                ix_size,
            )?;
            let vals = sp.values();
            fits(
                format!("accessor {} sparse values", a.index()),
                &vals.view(),
                vals.offset(),
                sp.count(),
                elem,
            )?;
        }
    }
    Ok(())
}

/// One texel's RGBA in [0, 1] of a decoded image, nearest to `uv` under the sampler's wrap.
fn sample(img: &::gltf::image::Data, sampler: &::gltf::texture::Sampler, uv: [f32; 2]) -> [f32; 4] {
    use ::gltf::image::Format as F;
    use ::gltf::texture::WrappingMode as W;
    let wrap = |t: f32, mode: W, n: u32| -> u32 {
        let n_f = n as f32;
        let x = match mode {
            W::ClampToEdge => t.clamp(0.0, 1.0) * n_f,
            W::Repeat => t.rem_euclid(1.0) * n_f,
            W::MirroredRepeat => {
                let m = t.rem_euclid(2.0);
                (if m > 1.0 { 2.0 - m } else { m }) * n_f
            }
        };
        (x.floor() as i64).clamp(0, n as i64 - 1) as u32
    };
    let (x, y) = (
        wrap(uv[0], sampler.wrap_s(), img.width),
        wrap(uv[1], sampler.wrap_t(), img.height),
    );
    let (channels, bytes) = match img.format {
        F::R8 => (1, 1),
        F::R8G8 => (2, 1),
        F::R8G8B8 => (3, 1),
        F::R8G8B8A8 => (4, 1),
        F::R16 => (1, 2),
        F::R16G16 => (2, 2),
        F::R16G16B16 => (3, 2),
        F::R16G16B16A16 => (4, 2),
        F::R32G32B32FLOAT => (3, 4),
        F::R32G32B32A32FLOAT => (4, 4),
    };
    let at = ((y as usize * img.width as usize) + x as usize) * channels * bytes;
    let c = |k: usize| -> f32 {
        let o = at + k * bytes;
        match bytes {
            1 => img.pixels.get(o).map_or(0.0, |&v| v as f32 / 255.0),
            2 => img
                .pixels
                .get(o..o + 2)
                .map_or(0.0, |b| u16::from_ne_bytes([b[0], b[1]]) as f32 / 65535.0),
            _ => img
                .pixels
                .get(o..o + 4)
                .map_or(0.0, |b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]])),
        }
    };
    match channels {
        // Grey, and grey with alpha (how the decoder gives luma PNGs).
        1 => [c(0), c(0), c(0), 1.0],
        2 => [c(0), c(0), c(0), c(1)],
        3 => [c(0), c(1), c(2), 1.0],
        _ => [c(0), c(1), c(2), c(3)],
    }
}

/// The file's document and its buffers, every accessor checked to lie inside its buffer.
fn open(path: &Path) -> Result<(::gltf::Gltf, Vec<::gltf::buffer::Data>)> {
    if !path.exists() {
        return Err(err(path, "file not found"));
    }
    if path.is_dir() {
        return Err(err(path, "is a directory, not a glTF file"));
    }
    let bytes = std::fs::read(path).map_err(|e| err(path, e.to_string()))?;
    let gltf =
        ::gltf::Gltf::from_slice(&bytes).map_err(|e| err(path, format!("invalid glTF: {e}")))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut blob = gltf.blob.clone();
    let mut buffers: Vec<::gltf::buffer::Data> = Vec::new();
    for b in gltf.document.buffers() {
        let from = source_name(&b.source());
        let data = ::gltf::buffer::Data::from_source_and_blob(b.source(), Some(dir), &mut blob)
            .map_err(|e| err(path, format!("buffer {} ({from}): {e}", b.index())))?;
        if data.len() < b.length() {
            return Err(err(
                path,
                format!(
                    "buffer {} ({from}) holds {} B, the file says {} B",
                    b.index(),
                    data.len(),
                    b.length()
                ),
            ));
        }
        buffers.push(data);
    }
    check_accessors(path, &gltf.document, &buffers)?;
    Ok((gltf, buffers))
}

/// [`load`] without printing: the mesh and what a user should be told.
pub fn load_with_warnings(path: &Path) -> Result<(Mesh, Vec<String>)> {
    let (gltf, buffers) = open(path)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut images: HashMap<usize, ::gltf::image::Data> = HashMap::new();
    let mut warnings = Vec::new();
    let mut unmaterialled = 0usize;
    let scene = gltf
        .document
        .default_scene()
        .or_else(|| gltf.document.scenes().next())
        .ok_or_else(|| err(path, "no scene"))?;
    let mut mesh = Mesh::default();
    let mut instance = 0u32;
    let mut stack: Vec<(::gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        for c in node.children() {
            stack.push((c, world));
        }
        let Some(m) = node.mesh() else { continue };
        for prim in m.primitives() {
            let at = format!("mesh {} primitive {}", m.index(), prim.index());
            if prim.mode() != ::gltf::mesh::Mode::Triangles {
                return Err(err(
                    path,
                    format!("{at}: mode {:?}, only triangles are read", prim.mode()),
                ));
            }
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| d.0.as_slice()));
            let positions: Vec<[f32; 3]> = reader
                .read_positions()
                .ok_or_else(|| err(path, format!("{at}: no POSITION")))?
                .collect();
            let n = positions.len();
            let indices: Vec<u32> = match reader.read_indices() {
                Some(ix) => ix.into_u32().collect(),
                None => (0..n as u32).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                return Err(err(
                    path,
                    format!("{at}: {} indices, not triangles", indices.len()),
                ));
            }
            if let Some(&i) = indices.iter().find(|&&i| i as usize >= n) {
                return Err(err(
                    path,
                    format!("{at}: index {i} out of range ({n} vertices)"),
                ));
            }
            // Per-vertex base colour: factor × texture (or the palette without a material).
            let mat = prim.material();
            let pbr = mat.pbr_metallic_roughness();
            let factor = pbr.base_color_factor();
            let mut colors: Vec<[f32; 4]> = if mat.index().is_none() {
                unmaterialled += 1;
                vec![palette(instance, 1.0); n]
            } else {
                vec![factor; n]
            };
            if let Some(info) = pbr.base_color_texture() {
                let tex = info.texture();
                let src = tex.source();
                let img = match images.entry(src.index()) {
                    std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
                    std::collections::hash_map::Entry::Vacant(e) => e.insert(
                        ::gltf::image::Data::from_source(src.source(), Some(dir), &buffers)
                            .map_err(|x| {
                                err(
                                    path,
                                    format!("image {} (texture {}): {x}", src.index(), tex.index()),
                                )
                            })?,
                    ),
                };
                let set = info.tex_coord();
                let uvs: Vec<[f32; 2]> = reader
                    .read_tex_coords(set)
                    .ok_or_else(|| {
                        err(
                            path,
                            format!(
                                "{at}: material {}'s baseColorTexture reads TEXCOORD_{set}, which the primitive lacks",
                                mat.index().unwrap_or(0)
                            ),
                        )
                    })?
                    .into_f32()
                    .collect();
                if uvs.len() != n {
                    return Err(err(
                        path,
                        format!(
                            "{at}: TEXCOORD_{set} has {} entries for {n} vertices",
                            uvs.len()
                        ),
                    ));
                }
                let sampler = tex.sampler();
                for (c, uv) in colors.iter_mut().zip(&uvs) {
                    let t = sample(img, &sampler, *uv);
                    for k in 0..4 {
                        c[k] *= t[k];
                    }
                }
            }
            let transmission = mat
                .transmission()
                .map_or(0.0, |t| t.transmission_factor().clamp(0.0, 1.0));
            let mut indices = indices;
            match mat.alpha_mode() {
                ::gltf::material::AlphaMode::Opaque => colors.iter_mut().for_each(|c| c[3] = 1.0),
                ::gltf::material::AlphaMode::Mask => {
                    let cutoff = mat.alpha_cutoff().unwrap_or(0.5);
                    indices = indices
                        .chunks(3)
                        .filter(|t| {
                            t.iter().map(|&i| colors[i as usize][3]).sum::<f32>() / 3.0 >= cutoff
                        })
                        .flatten()
                        .copied()
                        .collect();
                    colors.iter_mut().for_each(|c| c[3] = 1.0);
                }
                ::gltf::material::AlphaMode::Blend => {}
            }
            if transmission > 0.0 {
                colors.iter_mut().for_each(|c| c[3] *= 1.0 - transmission);
            }
            if indices.is_empty() {
                continue; // every triangle fails the alpha test
            }
            let base = mesh.positions.len() as u32;
            for (p, c) in positions.iter().zip(&colors) {
                let w = world.transform_point3(Vec3::from(*p));
                if !w.is_finite() {
                    return Err(err(
                        path,
                        format!("mesh {}: a non-finite vertex {p:?}", m.index()),
                    ));
                }
                mesh.positions.push(w.into());
                mesh.colors.push(*c);
                mesh.object_ids.push(instance);
            }
            // Normals from the transformed faces: right under any node transform.
            mesh.normals
                .extend(face_normals(&mesh.positions[base as usize..], &indices));
            mesh.indices.extend(indices.iter().map(|i| base + i));
        }
        instance += 1;
    }
    if mesh.indices.is_empty() {
        return Err(err(
            path,
            "no triangles (every primitive empty or alpha-tested away)",
        ));
    }
    if unmaterialled > 0 {
        warnings.push(format!(
            "glTF file '{}': {unmaterialled} primitive(s) have no material (glTF's default, opaque white, would be white on the white background): drawn opaque in mfx's palette colour of their node",
            path.display()
        ));
    }
    Ok((mesh, warnings))
}

/// The `gltf` generator: `path` (required, `.gltf` or `.glb`), `alpha` (multiplies BLEND
/// materials' opacity; default 1).
pub fn build(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let path = r.opt_string("path")?;
    if path.is_none() {
        r.problem(SceneError::OutOfRange {
            scene: label.clone(),
            param: "path".into(),
            value: String::new(),
            why: "the gltf generator needs path = \"file.gltf\" (or .glb)".into(),
        })?;
    }
    let alpha = r.float("alpha", 1.0, 0.0, 1.0)? as f32;
    // `camera = "file"`: the file's first perspective camera; else the suite's eye/target/fov.
    let from_file = r.string("camera", "frame", &["frame", "file"])? == "file";
    let keys = crate::scenes::model_camera::read(&mut r, &label)?;
    if from_file && keys.placed() {
        r.problem(SceneError::OutOfRange {
            scene: label.clone(),
            param: "camera".into(),
            value: "file".into(),
            why: "the file's camera and an eye both given: choose one".into(),
        })?;
    }
    r.finish()?;
    let path = path.unwrap_or_default();
    let mut mesh = load(Path::new(&path))?;
    let (centre, scale) = crate::scenes::scene::normalisation(&mesh);
    let camera = if from_file {
        let (eye, target, up, yfov) = file_camera(Path::new(&path))?;
        let to_unit = |p: glam::DVec3| (p - centre) * scale;
        crate::scenes::model_camera::look_at_unit_sphere(
            to_unit(eye),
            to_unit(target),
            up,
            yfov.to_degrees(),
        )
    } else {
        keys.camera()
    };
    normalise(&mut mesh);
    for c in &mut mesh.colors {
        if c[3] < 1.0 {
            c[3] *= alpha;
        }
    }
    let instances = mesh.object_ids.iter().max().map_or(0, |m| m + 1);
    let objects = (0..instances)
        .map(|k| ObjectInfo {
            name: format!("node{k}"),
            closed: false,
        })
        .collect();
    let mut scene = Scene::new(spec.clone(), mesh, camera);
    scene.objects = objects;
    scene.file_normalisation = Some((centre, scale));
    Ok(scene)
}

/// The file's first perspective camera in the default scene's traversal, in the file's world
/// space: eye, a target one unit down its −z, its +y as up, and its vertical field of view.
pub fn file_camera(path: &Path) -> Result<(glam::DVec3, glam::DVec3, glam::DVec3, f64)> {
    let bytes = std::fs::read(path).map_err(|e| err(path, e.to_string()))?;
    let gltf =
        ::gltf::Gltf::from_slice(&bytes).map_err(|e| err(path, format!("invalid glTF: {e}")))?;
    let scene = gltf
        .document
        .default_scene()
        .or_else(|| gltf.document.scenes().next())
        .ok_or_else(|| err(path, "no scene"))?;
    let mut stack: Vec<(::gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(cam) = node.camera() {
            if let ::gltf::camera::Projection::Perspective(p) = cam.projection() {
                let w = world.as_dmat4();
                let eye = w.transform_point3(glam::DVec3::ZERO);
                let target = w.transform_point3(glam::DVec3::NEG_Z);
                let up = w.transform_vector3(glam::DVec3::Y).normalize_or_zero();
                if !(eye.is_finite() && target.is_finite()) || (target - eye).length() < 1e-12 {
                    return Err(err(
                        path,
                        format!("camera {}: its node's transform is degenerate", cam.index()),
                    ));
                }
                return Ok((eye, target, up, p.yfov() as f64));
            }
        }
        for c in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((c, world));
        }
    }
    Err(err(
        path,
        "camera = \"file\": the file has no perspective camera in its scene",
    ))
}

/// A camera of a glTF file at one moment, in the file's world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FileCamera {
    pub eye: glam::DVec3,
    /// One unit down the camera's −z.
    pub target: glam::DVec3,
    pub up: glam::DVec3,
    pub yfov_deg: f64,
}

/// One animated property of a node: its keyframe times and values (x, y, z[, w]).
struct Track {
    node: usize,
    property: ::gltf::animation::Property,
    interpolation: ::gltf::animation::Interpolation,
    times: Vec<f64>,
    /// Per key; a cubic spline's are (in-tangent, value, out-tangent) triples.
    values: Vec<[f64; 4]>,
}

impl Track {
    /// The value at time `t` (held before the first key and after the last).
    fn at(&self, t: f64) -> [f64; 4] {
        use ::gltf::animation::Interpolation as I;
        let cubic = self.interpolation == I::CubicSpline;
        let value = |k: usize| {
            if cubic {
                self.values[3 * k + 1]
            } else {
                self.values[k]
            }
        };
        let n = self.times.len();
        if t <= self.times[0] {
            return value(0);
        }
        if t >= self.times[n - 1] {
            return value(n - 1);
        }
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let dt = self.times[k + 1] - self.times[k];
        let u = (t - self.times[k]) / dt;
        let rotation = self.property == ::gltf::animation::Property::Rotation;
        let out = match self.interpolation {
            I::Step => value(k),
            I::Linear if rotation => {
                let q = |v: [f64; 4]| glam::DQuat::from_xyzw(v[0], v[1], v[2], v[3]);
                let r = q(value(k)).slerp(q(value(k + 1)), u);
                [r.x, r.y, r.z, r.w]
            }
            I::Linear => std::array::from_fn(|c| value(k)[c] + (value(k + 1)[c] - value(k)[c]) * u),
            // glTF 2.0 Appendix C: the cubic Hermite spline with tangents scaled by the interval.
            I::CubicSpline => {
                let (u2, u3) = (u * u, u * u * u);
                let (v0, b0) = (self.values[3 * k + 1], self.values[3 * k + 2]);
                let (a1, v1) = (self.values[3 * (k + 1)], self.values[3 * (k + 1) + 1]);
                std::array::from_fn(|c| {
                    (2.0 * u3 - 3.0 * u2 + 1.0) * v0[c]
                        + (u3 - 2.0 * u2 + u) * dt * b0[c]
                        + (-2.0 * u3 + 3.0 * u2) * v1[c]
                        + (u3 - u2) * dt * a1[c]
                })
            }
        };
        if rotation {
            let q = glam::DQuat::from_xyzw(out[0], out[1], out[2], out[3]).normalize();
            return [q.x, q.y, q.z, q.w];
        }
        out
    }
}

/// The file's first perspective camera (as [`file_camera`] finds it) played by the file's first
/// animation that moves it or a node above it: `views` cameras at evenly spaced times from that
/// animation's first keyframe to its last. An error names the file and what is missing (no
/// camera, no animation of it, a sampler whose times are not increasing).
pub fn camera_animation(path: &Path, views: u32) -> Result<Vec<FileCamera>> {
    let (gltf, buffers) = open(path)?;
    let doc = &gltf.document;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| err(path, "no scene"))?;
    // The chain of nodes from a root to the first perspective camera, depth first in file order.
    let mut chain: Option<Vec<::gltf::Node>> = None;
    let mut stack: Vec<Vec<::gltf::Node>> = scene.nodes().map(|n| vec![n]).collect();
    stack.reverse();
    while let Some(nodes) = stack.pop() {
        let node = nodes.last().expect("non-empty").clone();
        if let Some(cam) = node.camera() {
            if matches!(cam.projection(), ::gltf::camera::Projection::Perspective(_)) {
                chain = Some(nodes);
                break;
            }
        }
        for c in node.children().collect::<Vec<_>>().into_iter().rev() {
            let mut next = nodes.clone();
            next.push(c);
            stack.push(next);
        }
    }
    let chain = chain.ok_or_else(|| {
        err(
            path,
            "camera_path = \"file\": the file has no perspective camera in its scene",
        )
    })?;
    let cam_node = chain.last().expect("non-empty");
    let yfov = match cam_node.camera().as_ref().map(|c| c.projection()) {
        Some(::gltf::camera::Projection::Perspective(p)) => p.yfov() as f64,
        _ => unreachable!("found as a perspective camera"),
    };
    let in_chain = |n: usize| chain.iter().any(|c| c.index() == n);
    let animation = doc
        .animations()
        .find(|a| a.channels().any(|c| in_chain(c.target().node().index())))
        .ok_or_else(|| {
            err(
                path,
                format!(
                    "camera_path = \"file\": no animation moves camera node {} or a node above it",
                    cam_node.index()
                ),
            )
        })?;
    let mut tracks = Vec::new();
    for ch in animation.channels() {
        let node = ch.target().node().index();
        let property = ch.target().property();
        if !in_chain(node) || property == ::gltf::animation::Property::MorphTargetWeights {
            continue;
        }
        let at = format!(
            "animation {} channel {} (node {node})",
            animation.index(),
            ch.index()
        );
        let reader = ch.reader(|b| buffers.get(b.index()).map(|d| d.0.as_slice()));
        let times: Vec<f64> = reader
            .read_inputs()
            .ok_or_else(|| err(path, format!("{at}: no input times")))?
            .map(f64::from)
            .collect();
        if times.is_empty() || times.iter().any(|t| !t.is_finite()) {
            return Err(err(path, format!("{at}: no finite input times")));
        }
        if let Some(w) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(err(
                path,
                format!(
                    "{at}: input time {} at key {} is not after {}: times must increase",
                    times[w + 1],
                    w + 1,
                    times[w]
                ),
            ));
        }
        use ::gltf::animation::util::ReadOutputs as O;
        let widen3 = |v: [f32; 3]| [v[0] as f64, v[1] as f64, v[2] as f64, 0.0];
        let values: Vec<[f64; 4]> = match reader.read_outputs() {
            Some(O::Translations(it)) | Some(O::Scales(it)) => it.map(widen3).collect(),
            Some(O::Rotations(r)) => r.into_f32().map(|q| q.map(f64::from)).collect(),
            _ => return Err(err(path, format!("{at}: no output values"))),
        };
        let interpolation = ch.sampler().interpolation();
        let per_key = match interpolation {
            ::gltf::animation::Interpolation::CubicSpline => 3,
            _ => 1,
        };
        if values.len() != times.len() * per_key || values.iter().flatten().any(|v| !v.is_finite())
        {
            return Err(err(
                path,
                format!(
                    "{at}: {} finite output values for {} input times ({per_key} a key)",
                    values.len(),
                    times.len()
                ),
            ));
        }
        tracks.push(Track {
            node,
            property,
            interpolation,
            times,
            values,
        });
    }
    let t0 = tracks
        .iter()
        .map(|t| t.times[0])
        .fold(f64::INFINITY, f64::min);
    let t1 = tracks
        .iter()
        .map(|t| t.times[t.times.len() - 1])
        .fold(f64::NEG_INFINITY, f64::max);
    let n = views.max(1) as usize;
    (0..n)
        .map(|i| {
            let t = t0 + (t1 - t0) * i as f64 / (n - 1).max(1) as f64;
            let mut world = glam::DMat4::IDENTITY;
            for node in &chain {
                let (tr, rot, sc) = node.transform().decomposed();
                let mut tr = glam::DVec3::from(tr.map(f64::from));
                let r = rot.map(f64::from);
                let mut rot = glam::DQuat::from_xyzw(r[0], r[1], r[2], r[3]);
                let mut sc = glam::DVec3::from(sc.map(f64::from));
                for track in tracks.iter().filter(|k| k.node == node.index()) {
                    let v = track.at(t);
                    match track.property {
                        ::gltf::animation::Property::Translation => {
                            tr = glam::DVec3::new(v[0], v[1], v[2])
                        }
                        ::gltf::animation::Property::Rotation => {
                            rot = glam::DQuat::from_xyzw(v[0], v[1], v[2], v[3])
                        }
                        ::gltf::animation::Property::Scale => {
                            sc = glam::DVec3::new(v[0], v[1], v[2])
                        }
                        ::gltf::animation::Property::MorphTargetWeights => {}
                    }
                }
                world *= glam::DMat4::from_scale_rotation_translation(sc, rot, tr);
            }
            let eye = world.transform_point3(glam::DVec3::ZERO);
            let target = world.transform_point3(glam::DVec3::NEG_Z);
            let up = world.transform_vector3(glam::DVec3::Y).normalize_or_zero();
            if !(eye.is_finite() && target.is_finite()) || (target - eye).length() < 1e-12 {
                return Err(err(
                    path,
                    format!(
                        "camera node {} at time {t}: its transform is degenerate",
                        cam_node.index()
                    ),
                ));
            }
            Ok(FileCamera {
                eye,
                target,
                up,
                yfov_deg: yfov.to_degrees(),
            })
        })
        .collect()
}

/// How [`write_example_as`] stores the buffer: as users ship glTF.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Form {
    /// `example.gltf` + `example.bin`.
    Separate,
    /// `example-embedded.gltf`, the buffer a base64 `data:` URI inside it.
    Embedded,
    /// `example.glb`: one binary file.
    Glb,
}

/// [`write_example_as`] `.gltf` + `.bin`, or `.glb` when `glb`.
pub fn write_example(dir: &Path, glb: bool) -> std::io::Result<std::path::PathBuf> {
    write_example_as(dir, if glb { Form::Glb } else { Form::Separate })
}

/// Writes a small glTF scene for tests and examples (no downloads), in the given [`Form`]. One quad mesh per material: BLEND (alpha 0.5,
/// used by two nodes: instancing), MASK passing its cutoff (alpha 0.8 ≥ 0.5: opaque), MASK
/// failing it (0.3 < 0.5: dropped), OPAQUE (factor alpha 0.1, ignored: an occluder behind),
/// under a root node whose transform the children inherit. Returns the file's path.
pub fn write_example_as(dir: &Path, form: Form) -> std::io::Result<std::path::PathBuf> {
    use base64::Engine as _;
    let mut bin: Vec<u8> = Vec::new();
    for p in [
        [-1.0f32, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ] {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let buffer = match form {
        Form::Glb => format!(r#"{{"byteLength":{}}}"#, bin.len()),
        Form::Separate => format!(r#"{{"byteLength":{},"uri":"example.bin"}}"#, bin.len()),
        Form::Embedded => format!(
            r#"{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}"#,
            bin.len(),
            base64::engine::general_purpose::STANDARD.encode(&bin)
        ),
    };
    let material = |mode: &str, rgba: [f32; 4], cutoff: &str| {
        format!(
            r#"{{"pbrMetallicRoughness":{{"baseColorFactor":[{},{},{},{}]}},"alphaMode":"{mode}"{cutoff}}}"#,
            rgba[0], rgba[1], rgba[2], rgba[3]
        )
    };
    let mesh = |m: u32| {
        format!(
            r#"{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":{m}}}]}}"#
        )
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0","generator":"mfx write_example"}},
"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[
 {{"children":[1,2,3,4,5],"rotation":[0,0.0998,0,0.995],"scale":[2,2,2]}},
 {{"mesh":0,"translation":[0,0,0.2]}},
 {{"mesh":0,"translation":[0.4,0.3,0.5],"scale":[0.7,0.7,0.7]}},
 {{"mesh":1,"translation":[-0.3,-0.2,-0.3],"scale":[0.6,0.6,0.6]}},
 {{"mesh":2,"translation":[0,0,0.35]}},
 {{"mesh":3,"translation":[0,0,-0.8],"scale":[1.2,1.2,1.2]}}],
"meshes":[{},{},{},{}],
"materials":[{},{},{},{}],
"buffers":[{buffer}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48,"target":34962}},{{"buffer":0,"byteOffset":48,"byteLength":12,"target":34963}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,-1,0],"max":[1,1,0]}},{{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}}]}}"#,
        mesh(0),
        mesh(1),
        mesh(2),
        mesh(3),
        material("BLEND", [0.9, 0.3, 0.2, 0.5], ""),
        material("MASK", [0.2, 0.8, 0.3, 0.8], r#","alphaCutoff":0.5"#),
        material("MASK", [0.2, 0.3, 0.9, 0.3], r#","alphaCutoff":0.5"#),
        material("OPAQUE", [0.7, 0.7, 0.7, 0.1], ""),
    );
    std::fs::create_dir_all(dir)?;
    match form {
        Form::Separate => {
            std::fs::write(dir.join("example.bin"), &bin)?;
            let p = dir.join("example.gltf");
            std::fs::write(&p, json)?;
            return Ok(p);
        }
        Form::Embedded => {
            let p = dir.join("example-embedded.gltf");
            std::fs::write(&p, json)?;
            return Ok(p);
        }
        Form::Glb => {}
    }
    // GLB: 12-byte header, a JSON chunk padded with spaces, a BIN chunk padded with zeros.
    let mut j = json.into_bytes();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&j);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    out.extend_from_slice(&bin);
    let p = dir.join("example.glb");
    std::fs::write(&p, out)?;
    Ok(p)
}
