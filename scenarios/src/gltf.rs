//! glTF 2.0 scenes through the `gltf` crate (`.gltf` with external buffers, or `.glb`): every
//! triangle primitive of the default scene's node hierarchy, node transforms applied (a mesh
//! used by several nodes is instanced), normalised and framed as OBJ scenes are.
//!
//! Materials map onto how scenes carry opacity (vertex alpha; alpha 1 is an opaque occluder):
//! - `OPAQUE`: alpha 1, whatever `baseColorFactor` says (the spec ignores alpha then);
//! - `MASK`: alpha-tested against `alphaCutoff` (default 0.5). mfx reads no textures, so the
//!   test is on `baseColorFactor` alpha alone: a primitive passes whole (opaque, alpha 1) or is
//!   dropped whole;
//! - `BLEND`: transparent, opacity `baseColorFactor` alpha × the scene's `alpha`.
//!
//! Bad files are errors naming the file and the problem (unreadable, invalid glTF, a buffer
//! missing or short, a data: URI, no triangles).

use std::path::Path;

use glam::{Mat4, Vec3};

use crate::scenes::scene::{
    face_normals, frame_sphere, normalise, Mesh, ObjectInfo, Scene, SceneSpec,
};
use crate::{Result, SceneError};

fn err(path: &Path, why: impl Into<String>) -> SceneError {
    SceneError::Gltf {
        path: path.display().to_string(),
        why: why.into(),
    }
}

/// Loads a glTF/GLB file into one mesh in the file's world space. Colours are the material's
/// `baseColorFactor` with the alpha rule above; object id = the node instance (in traversal
/// order), so repeated meshes stay apart.
pub fn load(path: &Path) -> Result<Mesh> {
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
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    for b in gltf.document.buffers() {
        let data = match b.source() {
            ::gltf::buffer::Source::Bin => gltf.blob.clone().ok_or_else(|| {
                err(
                    path,
                    format!("buffer {} is the GLB BIN chunk, absent", b.index()),
                )
            })?,
            ::gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                return Err(err(
                    path,
                    format!(
                        "buffer {}: data: URIs are not supported (write a .bin or a .glb)",
                        b.index()
                    ),
                ))
            }
            ::gltf::buffer::Source::Uri(uri) => {
                let p = dir.join(uri);
                std::fs::read(&p).map_err(|e| {
                    err(path, format!("buffer {} ({}): {e}", b.index(), p.display()))
                })?
            }
        };
        if data.len() < b.length() {
            return Err(err(
                path,
                format!(
                    "buffer {} holds {} B, the file says {} B",
                    b.index(),
                    data.len(),
                    b.length()
                ),
            ));
        }
        buffers.push(data);
    }
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
            if prim.mode() != ::gltf::mesh::Mode::Triangles {
                return Err(err(
                    path,
                    format!(
                        "mesh {} primitive {}: mode {:?}, only triangles are read",
                        m.index(),
                        prim.index(),
                        prim.mode()
                    ),
                ));
            }
            let mat = prim.material();
            let factor = mat.pbr_metallic_roughness().base_color_factor();
            let alpha = match mat.alpha_mode() {
                ::gltf::material::AlphaMode::Opaque => 1.0,
                ::gltf::material::AlphaMode::Mask => {
                    if factor[3] < mat.alpha_cutoff().unwrap_or(0.5) {
                        continue; // every fragment fails the alpha test
                    }
                    1.0
                }
                ::gltf::material::AlphaMode::Blend => factor[3],
            };
            let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
            let positions: Vec<[f32; 3]> = reader
                .read_positions()
                .ok_or_else(|| {
                    err(
                        path,
                        format!("mesh {} primitive {}: no POSITION", m.index(), prim.index()),
                    )
                })?
                .collect();
            let n = positions.len();
            let indices: Vec<u32> = match reader.read_indices() {
                Some(ix) => ix.into_u32().collect(),
                None => (0..n as u32).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                return Err(err(
                    path,
                    format!(
                        "mesh {} primitive {}: {} indices, not triangles",
                        m.index(),
                        prim.index(),
                        indices.len()
                    ),
                ));
            }
            if let Some(&i) = indices.iter().find(|&&i| i as usize >= n) {
                return Err(err(
                    path,
                    format!(
                        "mesh {} primitive {}: index {i} out of range ({n} vertices)",
                        m.index(),
                        prim.index()
                    ),
                ));
            }
            let base = mesh.positions.len() as u32;
            for p in &positions {
                let w = world.transform_point3(Vec3::from(*p));
                if !w.is_finite() {
                    return Err(err(
                        path,
                        format!("mesh {}: a non-finite vertex {p:?}", m.index()),
                    ));
                }
                mesh.positions.push(w.into());
                mesh.colors.push([factor[0], factor[1], factor[2], alpha]);
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
    Ok(mesh)
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
    r.finish()?;
    let mut mesh = load(Path::new(&path.unwrap_or_default()))?;
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
    let mut scene = Scene::new(spec.clone(), mesh, frame_sphere(1.0, 45.0));
    scene.objects = objects;
    Ok(scene)
}

/// Writes a small glTF scene for tests and examples (no downloads): `example.gltf` +
/// `example.bin`, or `example.glb` when `glb`. One quad mesh per material: BLEND (alpha 0.5,
/// used by two nodes: instancing), MASK passing its cutoff (alpha 0.8 ≥ 0.5: opaque), MASK
/// failing it (0.3 < 0.5: dropped), OPAQUE (factor alpha 0.1, ignored: an occluder behind),
/// under a root node whose transform the children inherit. Returns the file's path.
pub fn write_example(dir: &Path, glb: bool) -> std::io::Result<std::path::PathBuf> {
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
    let buffer = if glb {
        format!(r#"{{"byteLength":{}}}"#, bin.len())
    } else {
        format!(r#"{{"byteLength":{},"uri":"example.bin"}}"#, bin.len())
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
    if !glb {
        std::fs::write(dir.join("example.bin"), &bin)?;
        let p = dir.join("example.gltf");
        std::fs::write(&p, json)?;
        return Ok(p);
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
