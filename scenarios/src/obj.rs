//! Model loading: OBJ through tobj, PLY (`.ply`, `.ply.gz`) through [`crate::ply`]; validated,
//! normalised into the unit sphere, optionally instanced on a grid to reach millions of
//! triangles. Bad files are errors naming the file and the problem.

use std::path::Path;

use glam::{DMat4, DVec3, Vec3};

use crate::scenes::scene::{
    face_normals, normalisation, normalise, Mesh, ObjectInfo, Scene, SceneSpec,
};
use crate::{Result, SceneError};

/// Model files this repository's scripts fetch (they are not committed): a path starting with
/// the prefix, when missing, is [`SceneError::ModelMissing`] naming the command.
pub const FETCHABLE: &[(&str, &str)] = &[
    ("models/dragon_vrip", "bash scripts/fetch-dragon.sh"),
    ("models/ogre.obj", "bash scripts/fetch-models.sh"),
    ("models/cow.obj", "bash scripts/fetch-models.sh"),
    ("models/bunny-stack16.obj", "bash scripts/bake-bunny-stack.sh"),
    (
        "models/ogre-stack16.obj",
        "bash scripts/fetch-models.sh && bash scripts/bake-bunny-stack.sh models/ogre.obj models/ogre-stack16.obj",
    ),
];

/// The command that fetches `path`, if a script of this repository provides it.
pub fn fetch_command(path: &str) -> Option<&'static str> {
    let p = path.trim_start_matches("./");
    FETCHABLE
        .iter()
        .find(|(prefix, _)| p.starts_with(prefix))
        .map(|(_, cmd)| *cmd)
}

/// Loads one model file into a single mesh: a PLY file (`.ply`, `.ply.gz`) through
/// [`crate::ply`], anything else as OBJ. Warnings ([`load_with_warnings`]) go to stderr, once
/// per file and message.
///
/// OBJ: all models merged, normals computed where missing; vertex alpha is the opacity of the
/// face's MTL material ([`material_alpha`]), 1 where the OBJ names no material or its MTL file is
/// absent (a warning).
pub fn load(path: &Path) -> Result<Mesh> {
    let (mesh, warnings) = load_with_warnings(path)?;
    // A suite checks, builds and places the same file several times: say each thing once.
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

/// [`load`], returning its warnings (`file:line: what`) instead of printing them: a missing MTL
/// file (every face opaque).
pub fn load_with_warnings(path: &Path) -> Result<(Mesh, Vec<String>)> {
    let name = path.display().to_string();
    let err = |why: String| SceneError::Obj {
        path: name.clone(),
        why,
    };
    if !path.exists() {
        if let Some(fetch) = fetch_command(&path.to_string_lossy()) {
            return Err(SceneError::ModelMissing {
                path: name.clone(),
                fetch: fetch.into(),
            });
        }
        return Err(err("file not found".into()));
    }
    if path.is_dir() {
        return Err(err("is a directory, not a model file".into()));
    }
    if crate::ply::is_ply(&path.to_string_lossy()) {
        let mesh = crate::ply::load(path).map_err(|e| err(e.to_string()))?;
        check_extent(&mesh).map_err(|e| err(e.to_string()))?;
        return Ok((mesh, Vec::new()));
    }
    let text = std::fs::read_to_string(path).map_err(|e| err(format!("cannot read: {e}")))?;
    let scanned = scan(&text).map_err(|(line, why)| SceneError::ModelLine {
        path: name.clone(),
        line,
        why,
    })?;
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, materials) =
        tobj::load_obj(path, &opts).map_err(|e| err(format!("malformed OBJ: {e}")))?;
    let mut warnings = Vec::new();
    let alphas = match materials {
        Ok(materials) => materials
            .iter()
            .map(|m| material_alpha(m).map_err(|why| err(format!("material '{}': {why}", m.name))))
            .collect::<Result<Vec<f32>>>()?,
        // No MTL file next to the OBJ: every face is opaque (alpha 1), as without materials.
        Err(tobj::LoadError::OpenFileFailed) => {
            let dir = path.parent().unwrap_or(Path::new(""));
            for (line, lib) in &scanned.mtllibs {
                if !dir.join(lib).is_file() {
                    warnings.push(format!(
                        "{name}:{line}: material library '{lib}' not found: its materials' opacity is not applied (every face opaque)"
                    ));
                }
            }
            Vec::new()
        }
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
    check_extent(&mesh).map_err(|e| err(e.to_string()))?;
    Ok((mesh, warnings))
}

/// What is wrong with one value of an OBJ statement, an MTL material or a loaded mesh; the
/// loader adds the file, and the line and statement where there is one
/// ([`SceneError::ModelLine`], [`SceneError::Obj`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ObjError {
    #[error("{what} '{token}' is not a number")]
    NotANumber { what: &'static str, token: String },
    #[error(
        "{what} {token} is outside the f32 range (±{:e}) that the mesh is held in",
        f32::MAX
    )]
    OutsideF32 { what: &'static str, token: String },
    #[error("face vertex '{0}' has more than v/vt/vn")]
    TooManyIndices(String),
    #[error("face vertex '{0}' has no vertex index")]
    NoVertexIndex(String),
    #[error("{what} index '{token}' is not an integer")]
    NotAnInteger { what: &'static str, token: String },
    /// A negative index beyond the elements defined before its line.
    #[error("{what} index {index} out of range (-{so_far}..=-1 counts back over the {so_far} defined before this line)")]
    BackOutOfRange {
        what: &'static str,
        index: i64,
        so_far: usize,
    },
    #[error("{what} index {index} out of range (1..={total}: the file has {total})")]
    OutOfRange {
        what: &'static str,
        index: i64,
        total: usize,
    },
    #[error("zero extent: every vertex is at {0:?}, so the mesh cannot be scaled into view")]
    ZeroExtent([f32; 3]),
    #[error("Tr '{0}' is not a number")]
    TrNotANumber(String),
    #[error("{what} gives opacity {alpha}, outside [0, 1]")]
    OpacityOutOfRange { what: &'static str, alpha: f32 },
}

/// What [`scan`] learns besides the file being well formed: the material libraries it names.
struct Scanned {
    /// (line, file name) of each `mtllib`.
    mtllibs: Vec<(usize, String)>,
}

/// Reads the file's statements before tobj does, which names no line: numbers that are not
/// numbers (or overflow the f32 that tobj and the GPU hold), face indices out of range or not
/// indices, faces of fewer than three vertices (tobj would drop or mis-triangulate them), and a
/// file with lines or points but no faces (no triangle to render). `Err` is (line, what).
fn scan(text: &str) -> std::result::Result<Scanned, (usize, String)> {
    // Totals first: tobj resolves positive indices against the whole file's vertices.
    let (mut nv, mut nvt, mut nvn) = (0usize, 0usize, 0usize);
    for line in text.lines() {
        match line.split_whitespace().next() {
            Some("v") => nv += 1,
            Some("vt") => nvt += 1,
            Some("vn") => nvn += 1,
            _ => {}
        }
    }
    let number = |t: &str, what: &'static str| -> std::result::Result<f64, ObjError> {
        let x: f64 = t.parse().map_err(|_| ObjError::NotANumber {
            what,
            token: t.to_string(),
        })?;
        if x.is_finite() && x.abs() > f32::MAX as f64 {
            return Err(ObjError::OutsideF32 {
                what,
                token: t.to_string(),
            });
        }
        Ok(x)
    };
    let (mut sv, mut svt, mut svn) = (0usize, 0usize, 0usize);
    let (mut faces, mut lines, mut points) = (0usize, 0usize, 0usize);
    let mut mtllibs = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let at = |why: &dyn std::fmt::Display| (n + 1, format!("{why}: '{}'", line.trim()));
        let mut it = line.split_whitespace();
        let Some(head) = it.next() else { continue };
        let rest: Vec<&str> = it.collect();
        match head {
            "v" | "vt" | "vn" => {
                let need = if head == "vt" { 2 } else { 3 };
                if rest.len() < need {
                    return Err(at(&format!(
                        "'{head}' needs {need} numbers, has {}",
                        rest.len()
                    )));
                }
                for t in &rest[..need] {
                    number(t, "coordinate").map_err(|e| at(&e))?;
                }
                if head == "v" {
                    // tobj reads x y z, then w (a divisor) or r g b.
                    match rest.len() - 3 {
                        0 => {}
                        1 => {
                            if number(rest[3], "w").map_err(|e| at(&e))? == 0.0 {
                                return Err(at(&"w is 0 (the coordinates are divided by it)"));
                            }
                        }
                        3 => {
                            for t in &rest[3..] {
                                number(t, "colour").map_err(|e| at(&e))?;
                            }
                        }
                        k => {
                            return Err(at(&format!(
                                "'v' takes x y z and then w or r g b, not {k} more values"
                            )))
                        }
                    }
                }
                match head {
                    "v" => sv += 1,
                    "vt" => svt += 1,
                    _ => svn += 1,
                }
            }
            "f" | "l" | "p" => {
                if head == "f" && rest.len() < 3 {
                    return Err(at(&format!(
                        "face with {} vertices (a face needs at least 3)",
                        rest.len()
                    )));
                }
                if head != "p" {
                    for r in &rest {
                        face_vertex(
                            r,
                            [
                                (nv, sv, "vertex"),
                                (nvt, svt, "texture coordinate"),
                                (nvn, svn, "normal"),
                            ],
                        )
                        .map_err(|e| at(&e))?;
                    }
                }
                match head {
                    "f" => faces += 1,
                    "l" => lines += 1,
                    _ => points += 1,
                }
            }
            "mtllib" => {
                // tobj takes the rest of the line as one file name (names may hold spaces).
                let lib = line
                    .trim()
                    .split_once(char::is_whitespace)
                    .map(|(_, l)| l.trim());
                if let Some(lib) = lib.filter(|l| !l.is_empty()) {
                    mtllibs.push((n + 1, lib.to_string()));
                }
            }
            _ => {}
        }
    }
    if faces == 0 {
        return Err((
            0,
            format!(
                "no triangles: no faces ('f' lines) found ({lines} line and {points} point elements, which have no area)"
            ),
        ));
    }
    Ok(Scanned { mtllibs })
}

/// One `v[/vt[/vn]]` of a face: each given index an integer, not 0, within the file's elements
/// of its kind (`(total in the file, defined so far, name)`; a negative index counts back from
/// the last one defined so far).
fn face_vertex(
    r: &str,
    kinds: [(usize, usize, &'static str); 3],
) -> std::result::Result<(), ObjError> {
    let parts: Vec<&str> = r.split('/').collect();
    if parts.len() > 3 {
        return Err(ObjError::TooManyIndices(r.to_string()));
    }
    for (i, t) in parts.iter().enumerate() {
        let (total, so_far, what) = kinds[i];
        if t.is_empty() {
            if i == 0 {
                return Err(ObjError::NoVertexIndex(r.to_string()));
            }
            continue;
        }
        let x: i64 = t.parse().map_err(|_| ObjError::NotAnInteger {
            what,
            token: t.to_string(),
        })?;
        let ok = match x {
            0 => false,
            x if x > 0 => x as u64 <= total as u64,
            x => x.unsigned_abs() <= so_far as u64,
        };
        if !ok {
            return Err(if x < 0 {
                ObjError::BackOutOfRange {
                    what,
                    index: x,
                    so_far,
                }
            } else {
                ObjError::OutOfRange {
                    what,
                    index: x,
                    total,
                }
            });
        }
    }
    Ok(())
}

/// What normalising needs: a finite extent above zero (the loaders refuse non-finite values).
fn check_extent(mesh: &Mesh) -> std::result::Result<(), ObjError> {
    let first = mesh.positions.first().copied().unwrap_or_default();
    if mesh.positions.iter().all(|p| *p == first) {
        return Err(ObjError::ZeroExtent(first));
    }
    Ok(())
}

/// Opacity of an MTL material: its dissolve `d` if given, else 1 − `Tr` (the MTL spec's
/// transparency, which tobj leaves in `unknown_param`), else 1. `d` wins when both are present.
pub fn material_alpha(m: &tobj::Material) -> std::result::Result<f32, ObjError> {
    let (what, alpha) = match (m.dissolve, m.unknown_param.get("Tr")) {
        (Some(d), _) => ("d", d),
        (None, Some(tr)) => {
            let tr: f32 = tr
                .split_whitespace()
                .next()
                .and_then(|v| v.parse().ok())
                .ok_or_else(|| ObjError::TrNotANumber(tr.clone()))?;
            ("Tr", 1.0 - tr)
        }
        (None, None) => return Ok(1.0),
    };
    if !(0.0..=1.0).contains(&alpha) {
        return Err(ObjError::OpacityOutOfRange { what, alpha });
    }
    Ok(alpha)
}

fn affine(centre: DVec3, s: f64) -> DMat4 {
    DMat4::from_scale(DVec3::splat(s)) * DMat4::from_translation(-centre)
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
    let camera = crate::scenes::model_camera::read(&mut r, &label)?;
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
    let mut scene = Scene::new(spec.clone(), mesh, camera.camera());
    scene.objects = objects;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ParamValue, Params};

    /// Writes `text` as `name` in a fresh directory of this test (`tag`) and returns its path.
    /// A temp folder removed when the test ends, pass or fail (derefs to its path).
    struct Tmp(tempfile::TempDir);
    impl std::ops::Deref for Tmp {
        type Target = std::path::Path;
        fn deref(&self) -> &std::path::Path {
            self.0.path()
        }
    }
    impl AsRef<std::path::Path> for Tmp {
        fn as_ref(&self) -> &std::path::Path {
            self.0.path()
        }
    }
    fn tmp_dir(prefix: &str) -> Tmp {
        Tmp(tempfile::Builder::new()
            .prefix(&format!("{prefix}-"))
            .tempdir()
            .expect("a temp folder"))
    }

    fn file(tag: &str, name: &str, text: &str) -> TmpFile {
        let dir = tmp_dir(&format!("mfx-objunit-{tag}"));
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        TmpFile { _dir: dir, path: p }
    }

    /// A file in a temp folder removed with it (derefs to the file's path).
    struct TmpFile {
        _dir: Tmp,
        path: std::path::PathBuf,
    }
    impl std::ops::Deref for TmpFile {
        type Target = std::path::Path;
        fn deref(&self) -> &std::path::Path {
            &self.path
        }
    }

    fn spec(path: &Path) -> SceneSpec {
        SceneSpec::new(
            "obj",
            Params::new().with("path", ParamValue::Str(path.display().to_string())),
        )
    }

    fn load_err(tag: &str, text: &str) -> (String, String) {
        let p = file(tag, "m.obj", text);
        let e = load(&p).map(|_| ()).unwrap_err().to_string();
        (p.display().to_string(), e)
    }

    #[test]
    fn a_mesh_at_1e38_is_normalised_in_f64_not_collapsed_to_a_point() {
        // In f32 the radius's square overflows, the scale rounds to 0 and every vertex lands on
        // the origin (an empty image that "matches").
        let p = file(
            "huge",
            "m.obj",
            "v -1e38 -1e38 0\nv 1e38 -1e38 0\nv 0 1e38 0\nv 0 0 1e38\nf 1 2 3\nf 1 2 4\n",
        );
        let scene = spec(&p).build().unwrap();
        let r = scene
            .mesh
            .positions
            .iter()
            .map(|p| Vec3::from(*p).length())
            .fold(0.0f32, f32::max);
        assert!((r - 1.0).abs() < 1e-5, "normalised radius {r}");
        let w = world_from_file(&spec(&p)).unwrap();
        let m = w[0];
        assert!(
            m.determinant().abs() > 0.0,
            "world_from_object is singular: {m}"
        );
        // The matrix takes the file's vertex to the built one (f32 rounding apart).
        let got = m.transform_point3(DVec3::new(0.0, 1e38, 0.0));
        let want = Vec3::from(scene.mesh.positions[2]).as_dvec3();
        assert!((got - want).length() < 1e-6, "{got} vs {want}");
    }

    #[test]
    fn what_cannot_be_normalised_is_refused_with_the_reason() {
        let (p, e) = load_err("point", "v 2 2 2\nv 2 2 2\nv 2 2 2\nf 1 2 3\n");
        assert!(e.contains(&p) && e.contains("zero extent"), "{e}");
        let (p, e) = load_err("f32", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n");
        assert!(
            e.contains(&format!("{p}:2: ")) && e.contains("f32 range"),
            "{e}"
        );
        let (p, e) = load_err("inf", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n");
        assert!(e.contains(&p), "{e}");
    }

    #[test]
    fn obj_errors_name_the_file_and_line() {
        let cases = [
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
                4,
                "vertex index 7 out of range",
            ),
            (
                "v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n",
                2,
                "coordinate 'x' is not a number",
            ),
            (
                "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n",
                2,
                "needs 3 numbers, has 2",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 a\n",
                4,
                "vertex index 'a' is not an integer",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n",
                4,
                "vertex index 0 out of range",
            ),
            (
                "v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0\n",
                2,
                "vertex index -2 out of range (-1..=-1",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n",
                5,
                "normal index 2 out of range",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n",
                5,
                "face with 2 vertices",
            ),
        ];
        for (i, (text, line, what)) in cases.into_iter().enumerate() {
            let (p, e) = load_err(&format!("line{i}"), text);
            assert!(
                e.starts_with(&format!("{p}:{line}: ")) && e.contains(what),
                "case {i}: {e}"
            );
        }
    }

    #[test]
    fn a_missing_mtl_file_is_a_warning_naming_the_line() {
        let text =
            "# a triangle\nmtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n";
        let p = file("mtl", "m.obj", text);
        let (mesh, w) = load_with_warnings(&p).unwrap();
        assert_eq!(mesh.triangle_count(), 1);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with(&format!("{}:2: ", p.display())) && w[0].contains("gone.mtl"),
            "{w:?}"
        );
        // With its MTL file there, nothing to say.
        std::fs::write(p.with_file_name("gone.mtl"), "newmtl red\nd 0.5\n").unwrap();
        let (_, w) = load_with_warnings(&p).unwrap();
        assert!(w.is_empty(), "{w:?}");
    }

    #[test]
    fn ply_coordinates_beyond_f32_are_refused_and_1e38_is_normalised() {
        let ply = |x: &str| {
            format!("ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n{x} 0 0\n0 {x} 0\n3 0 1 2\n")
        };
        let p = file("ply", "big.ply", &ply("1e300"));
        let e = load(&p).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("f32 range"), "{e}");
        let p = file("ply", "huge.ply", &ply("1e38"));
        let scene = spec(&p).build().unwrap();
        let r = scene
            .mesh
            .positions
            .iter()
            .map(|p| Vec3::from(*p).length())
            .fold(0.0f32, f32::max);
        assert!((r - 1.0).abs() < 1e-5, "normalised radius {r}");
    }
}
