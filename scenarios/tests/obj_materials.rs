//! OBJ materials: an MTL file's dissolve gives per-material opacity, multiplied by `alpha`.

use scenarios::{ParamValue, Params, SceneSpec};

/// A model file in a temp folder that is removed with it (derefs to the file's path).
struct TmpFile {
    _dir: tempfile::TempDir,
    path: String,
}
impl std::ops::Deref for TmpFile {
    type Target = String;
    fn deref(&self) -> &String {
        &self.path
    }
}

/// Writes `files` (name, text) into a fresh directory and returns the path of the first.
fn write(tag: &str, files: &[(&str, &str)]) -> TmpFile {
    let dir = tempfile::Builder::new()
        .prefix(&format!("mfx-mtl-{tag}-"))
        .tempdir()
        .unwrap();
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    TmpFile {
        path: dir.path().join(files[0].0).display().to_string(),
        _dir: dir,
    }
}

fn build(path: &str, alpha: Option<f64>) -> Result<scenarios::Scene, scenarios::SceneError> {
    let mut p = Params::new().with("path", ParamValue::Str(path.into()));
    if let Some(a) = alpha {
        p.set("alpha", ParamValue::Float(a));
    }
    SceneSpec::new("obj", p).build()
}

/// Three separate triangles: no material (first: `usemtl` persists across objects), material
/// `half` (d 0.5), material `quarter` (Tr 0.75).
const OBJ: &str = "mtllib m.mtl
v 0 0 0
v 1 0 0
v 0 1 0
v 2 0 0
v 3 0 0
v 2 1 0
v 4 0 0
v 5 0 0
v 4 1 0
o c
f 7 8 9
o a
usemtl half
f 1 2 3
o b
usemtl quarter
f 4 5 6
";

const MTL: &str = "newmtl half
Kd 1 0 0
d 0.5
newmtl quarter
Kd 0 1 0
Tr 0.75
";

/// Opacity of each triangle, in file order (triangles keep their order through loading).
fn triangle_alphas(s: &scenarios::Scene) -> Vec<f32> {
    s.mesh
        .indices
        .chunks(3)
        .map(|t| s.mesh.colors[t[0] as usize][3])
        .collect()
}

#[test]
fn mtl_dissolve_and_tr_set_per_material_alpha_times_the_alpha_param() {
    let p = write("materials", &[("m.obj", OBJ), ("m.mtl", MTL)]);
    let s = build(&p, Some(0.8)).unwrap();
    let a = triangle_alphas(&s);
    // No material → opaque → 0.8; d 0.5 → 0.4; Tr 0.75 → opacity 0.25 → 0.2 (f32 products).
    let want = [0.8f32, 0.5 * 0.8, 0.25 * 0.8];
    assert_eq!(a.len(), 3);
    for (got, want) in a.iter().zip(want) {
        assert!((got - want).abs() < 1e-6, "{a:?} vs {want}");
    }
    let s = build(&p, Some(1.0)).unwrap();
    assert_eq!(triangle_alphas(&s), vec![1.0, 0.5, 0.25]);
}

#[test]
fn obj_without_its_mtl_keeps_the_uniform_alpha() {
    // mtllib names a file that is not there: today's behaviour, `alpha` (default 0.4) everywhere.
    let p = write("missing", &[("m.obj", OBJ)]);
    let s = build(&p, None).unwrap();
    assert_eq!(triangle_alphas(&s), vec![0.4, 0.4, 0.4]);
}

#[test]
fn bad_mtl_opacity_is_an_error_naming_file_and_material() {
    let p = write(
        "range",
        &[("m.obj", OBJ), ("m.mtl", "newmtl half\nd 1.5\n")],
    );
    let e = build(&p, None).unwrap_err().to_string();
    assert!(
        e.contains(p.as_str()) && e.contains("half") && e.contains("1.5"),
        "{e}"
    );
    let p = write(
        "nan",
        &[("m.obj", OBJ), ("m.mtl", "newmtl quarter\nTr abc\n")],
    );
    let e = build(&p, None).unwrap_err().to_string();
    assert!(e.contains("quarter") && e.contains("Tr"), "{e}");
    let p = write("parse", &[("m.obj", OBJ), ("m.mtl", "newmtl half\nd x\n")]);
    let e = build(&p, None).unwrap_err().to_string();
    assert!(e.contains("malformed MTL"), "{e}");
}
