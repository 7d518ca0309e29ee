//! Model loading: OBJ through tobj, PLY (`.ply`, `.ply.gz`) through [`crate::ply`]; validated,
//! normalised into the unit sphere, optionally instanced on a grid to reach millions of
//! triangles. Bad files are errors naming the file and the problem.

use std::path::Path;

use glam::{DMat4, DVec3, Vec3};

use crate::scenes::{frame_sphere, Mesh, ObjectInfo, Scene, SceneSpec};
use crate::{Result, SceneError};

/// Model files this repository's scripts fetch (they are not committed): a path starting with
/// the prefix, when missing, is [`SceneError::ModelMissing`] naming the command.
pub const FETCHABLE: &[(&str, &str)] = &[("models/dragon_vrip", "bash scripts/fetch-dragon.sh")];

/// The command that fetches `path`, if a script of this repository provides it.
pub fn fetch_command(path: &str) -> Option<&'static str> {
    let p = path.trim_start_matches("./");
    FETCHABLE
        .iter()
        .find(|(prefix, _)| p.starts_with(prefix))
        .map(|(_, cmd)| *cmd)
}

/// Loads one model file into a single mesh: a PLY file (`.ply`, `.ply.gz`) through
/// [`crate::ply`], anything else as OBJ.
///
/// OBJ: all models merged, normals computed where missing; vertex alpha is the opacity of the
/// face's MTL material ([`material_alpha`]), 1 where the OBJ names no material or its MTL file is
/// absent.
pub fn load(path: &Path) -> Result<Mesh> {
    let err = |why: String| SceneError::Obj {
        path: path.display().to_string(),
        why,
    };
    if !path.exists() {
        if let Some(fetch) = fetch_command(&path.to_string_lossy()) {
            return Err(SceneError::ModelMissing {
                path: path.display().to_string(),
                fetch: fetch.into(),
            });
        }
        return Err(err("file not found".into()));
    }
    if path.is_dir() {
        return Err(err("is a directory, not a model file".into()));
    }
    if crate::ply::is_ply(&path.to_string_lossy()) {
        return crate::ply::load(path).map_err(err);
    }
    scan_faces(path).map_err(err)?;
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, materials) =
        tobj::load_obj(path, &opts).map_err(|e| err(format!("malformed OBJ: {e}")))?;
    let alphas = match materials {
        Ok(materials) => materials
            .iter()
            .map(|m| material_alpha(m).map_err(|why| err(format!("material '{}': {why}", m.name))))
            .collect::<Result<Vec<f32>>>()?,
        // No MTL file next to the OBJ: every face is opaque (alpha 1), as without materials.
        Err(tobj::LoadError::OpenFileFailed) => Vec::new(),
        Err(e) => return Err(err(format!("malformed MTL: {e}"))),
    };
    let mut mesh = Mesh::default();
    for model in &models {
        // A model without a (known) material is opaque.
        let alpha = model
            .mesh
            .material_id
            .and_then(|i| alphas.get(i))
            .copied()
            .unwrap_or(1.0);
        let m = &model.mesh;
        if m.positions.len() % 3 != 0 {
            return Err(err(format!(
                "model '{}': position array is not xyz triples",
                model.name
            )));
        }
        let base = mesh.positions.len() as u32;
        let nverts = m.positions.len() / 3;
        for v in 0..nverts {
            let p = [
                m.positions[3 * v],
                m.positions[3 * v + 1],
                m.positions[3 * v + 2],
            ];
            if p.iter().any(|c| !c.is_finite()) {
                return Err(err(format!(
                    "model '{}': vertex {v} has a non-finite coordinate {p:?}",
                    model.name
                )));
            }
            mesh.positions.push(p);
            mesh.colors.push([0.8, 0.8, 0.8, alpha]);
            mesh.object_ids.push(0);
        }
        for &i in &m.indices {
            if i as usize >= nverts {
                return Err(err(format!(
                    "model '{}': face index {i} out of range ({nverts} vertices)",
                    model.name
                )));
            }
            mesh.indices.push(base + i);
        }
        if m.normals.len() == m.positions.len() {
            mesh.normals
                .extend(m.normals.chunks_exact(3).map(|n| [n[0], n[1], n[2]]));
        } else {
            mesh.normals
                .extend(face_normals(&mesh.positions[base as usize..], &m.indices));
        }
    }
    if mesh.indices.is_empty() {
        return Err(err("no triangles (no faces found)".into()));
    }
    Ok(mesh)
}

/// Reads the file's `f`, `l` and `p` statements before tobj does: a face of fewer than three
/// vertices is malformed (tobj would drop or mis-triangulate it), and a file with lines or points
/// but no faces has no triangle to render. Names the line.
fn scan_faces(path: &Path) -> std::result::Result<(), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read: {e}"))?;
    let (mut faces, mut lines, mut points) = (0usize, 0usize, 0usize);
    for (n, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("f") => {
                let verts = it.take_while(|t| !t.starts_with('#')).count();
                if verts < 3 {
                    return Err(format!(
                        "line {}: face with {verts} vertices (a face needs at least 3): '{}'",
                        n + 1,
                        line.trim()
                    ));
                }
                faces += 1;
            }
            Some("l") => lines += 1,
            Some("p") => points += 1,
            _ => {}
        }
    }
    if faces == 0 {
        return Err(format!(
            "no triangles: no faces ('f' lines) found ({lines} line and {points} point elements, which have no area)"
        ));
    }
    Ok(())
}

/// Opacity of an MTL material: its dissolve `d` if given, else 1 − `Tr` (the MTL spec's
/// transparency, which tobj leaves in `unknown_param`), else 1. `d` wins when both are present.
pub fn material_alpha(m: &tobj::Material) -> std::result::Result<f32, String> {
    let (what, alpha) = match (m.dissolve, m.unknown_param.get("Tr")) {
        (Some(d), _) => ("d", d),
        (None, Some(tr)) => {
            let tr: f32 = tr
                .split_whitespace()
                .next()
                .and_then(|v| v.parse().ok())
                .ok_or_else(|| format!("Tr '{tr}' is not a number"))?;
            ("Tr", 1.0 - tr)
        }
        (None, None) => return Ok(1.0),
    };
    if !(0.0..=1.0).contains(&alpha) {
        return Err(format!("{what} gives opacity {alpha}, outside [0, 1]"));
    }
    Ok(alpha)
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

/// Centres the mesh at the origin and scales it into the unit sphere.
pub fn normalise(mesh: &mut Mesh) {
    let (centre, s) = normalisation(mesh);
    for p in &mut mesh.positions {
        *p = ((Vec3::from(*p) - centre) * s).into();
    }
}

/// The centre and scale `normalise` applies: p' = (p − centre) · scale.
fn normalisation(mesh: &Mesh) -> (Vec3, f32) {
    let (lo, hi) = mesh.bounds();
    let centre = (lo + hi) * 0.5;
    let radius = mesh
        .positions
        .iter()
        .map(|p| (Vec3::from(*p) - centre).length())
        .fold(0.0f32, f32::max);
    let s = if radius > 0.0 { 1.0 / radius } else { 1.0 };
    (centre, s)
}

fn affine(centre: Vec3, s: f32) -> DMat4 {
    DMat4::from_scale(DVec3::splat(s as f64)) * DMat4::from_translation(-centre.as_dvec3())
}

/// Grid offset of instance `k` of `n` in `instance_grid`.
fn grid_offset(k: u32, n: u32) -> Vec3 {
    let cols = (n as f32).sqrt().ceil() as u32;
    Vec3::new(
        (k % cols) as f32 * 1.6,
        (k / cols) as f32 * 1.6,
        (k % 3) as f32 * 0.3,
    )
}

/// For an `obj` scene: per instance, the matrix taking the OBJ file's own vertex coordinates to
/// the scene's world coordinates (the normalisation and grid placement `build` applies, in f64;
/// the GPU's positions are these in f32, so they agree to f32 rounding).
pub fn world_from_file(spec: &SceneSpec) -> Result<Vec<DMat4>> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let path = r.opt_string("path")?.unwrap_or_default();
    let instances = r.int("instances", 1, 1, 4096)? as u32;
    let mut mesh = load(Path::new(&path))?;
    let (c1, s1) = normalisation(&mesh);
    let first = affine(c1, s1);
    if instances <= 1 {
        return Ok(vec![first]);
    }
    normalise(&mut mesh);
    let grid = instance_grid_raw(&mesh, instances);
    let (c2, s2) = normalisation(&grid);
    Ok((0..instances)
        .map(|k| {
            affine(c2, s2) * DMat4::from_translation(grid_offset(k, instances).as_dvec3()) * first
        })
        .collect())
}

/// Replicates `mesh` on a √n×√n grid in the x–y plane (object id = instance), renormalised.
pub fn instance_grid(mesh: &Mesh, n: u32) -> Mesh {
    if n <= 1 {
        return mesh.clone();
    }
    let mut out = instance_grid_raw(mesh, n);
    normalise(&mut out);
    out
}

fn instance_grid_raw(mesh: &Mesh, n: u32) -> Mesh {
    let mut out = Mesh::default();
    for k in 0..n {
        let offset = grid_offset(k, n);
        let mut inst = mesh.clone();
        for p in &mut inst.positions {
            *p = (Vec3::from(*p) + offset).into();
        }
        inst.object_ids.iter_mut().for_each(|id| *id = k);
        out.append(&inst);
    }
    out
}

/// The `obj` generator: `path` (required; an OBJ or PLY file), `instances` (grid), `alpha`
/// (opacity, multiplied by the MTL material's where the OBJ has one), `stand_in` (a name only).
pub fn build(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let path = r.opt_string("path")?;
    if path.is_none() {
        r.problem(SceneError::OutOfRange {
            scene: label.clone(),
            param: "path".into(),
            value: String::new(),
            why: "the obj generator needs path = \"file.obj\" (or .ply, .ply.gz)".into(),
        })?;
    }
    let instances = r.int("instances", 1, 1, 4096)? as u32;
    let alpha = r.float("alpha", 0.4, 0.0, 1.0)? as f32;
    // The published scene this one stands in for (e.g. "powerplant-12.7M" for the Dragon ×15):
    // it only names the scene, so the rows' label says what they stand in for.
    r.opt_string("stand_in")?;
    r.finish()?;
    let path = path.unwrap_or_default();
    let mut mesh = load(Path::new(&path))?;
    normalise(&mut mesh);
    let mut mesh = instance_grid(&mesh, instances);
    // Colour from the normal so layers are distinguishable in images; opacity is `alpha` times
    // the material's (1 without an MTL file).
    for (c, n) in mesh.colors.iter_mut().zip(&mesh.normals) {
        *c = [
            0.2 + 0.6 * (0.5 + 0.5 * n[0]),
            0.2 + 0.6 * (0.5 + 0.5 * n[1]),
            0.2 + 0.6 * (0.5 + 0.5 * n[2]),
            alpha * c[3],
        ];
    }
    let objects = (0..instances)
        .map(|k| ObjectInfo {
            name: format!("instance{k}"),
            closed: false,
        })
        .collect();
    let mut scene = Scene::new(spec.clone(), mesh, frame_sphere(1.0, 45.0));
    scene.objects = objects;
    Ok(scene)
}
