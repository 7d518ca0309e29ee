//! Bad input is a clear error naming the file and problem, never a panic.

use scenarios::{ParamValue, Params, SceneSpec, Suite};

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

fn obj(text: &str) -> TmpFile {
    let dir = tempfile::Builder::new()
        .prefix("mfx-obj-")
        .tempdir()
        .unwrap();
    let p = dir.path().join("m.obj");
    std::fs::write(&p, text).unwrap();
    TmpFile {
        path: p.display().to_string(),
        _dir: dir,
    }
}

fn build(path: &str) -> Result<scenarios::Scene, scenarios::SceneError> {
    SceneSpec::new(
        "obj",
        Params::new().with("path", ParamValue::Str(path.into())),
    )
    .build()
}

#[test]
fn missing_obj_names_the_file() {
    let e = build("/no/such/file.obj").unwrap_err().to_string();
    assert!(
        e.contains("/no/such/file.obj") && e.contains("not found"),
        "{e}"
    );
}

#[test]
fn obj_without_faces_is_an_error() {
    let p = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    let e = build(&p).unwrap_err().to_string();
    assert!(e.contains(p.as_str()) && e.contains("no triangles"), "{e}");
}

#[test]
fn obj_with_nan_vertex_is_an_error() {
    let p = obj("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
    let e = build(&p).unwrap_err().to_string();
    assert!(e.contains(p.as_str()), "{e}");
}

#[test]
fn malformed_obj_is_an_error() {
    let p = obj("v 0 0 0\nf 1 2 7\n");
    let e = build(&p).unwrap_err().to_string();
    assert!(e.contains(p.as_str()), "{e}");
}

#[test]
fn valid_obj_loads_and_normalises() {
    let p = obj("v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n");
    let s = build(&p).unwrap();
    assert_eq!(s.mesh.triangle_count(), 1);
    let r = s
        .mesh
        .positions
        .iter()
        .map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt())
        .fold(0.0f32, f32::max);
    assert!(
        (r - 1.0).abs() < 1e-5,
        "normalised into the unit sphere: {r}"
    );
}

#[test]
fn out_of_range_and_unknown_scene_params_are_errors() {
    let e = SceneSpec::new(
        "quads",
        Params::new().with("depth_complexity", ParamValue::Int(0)),
    )
    .build()
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("depth_complexity") && e.contains("out of range"),
        "{e}"
    );
    let e = SceneSpec::new(
        "quads",
        Params::new().with("depth_complexty", ParamValue::Int(3)),
    )
    .build()
    .unwrap_err()
    .to_string();
    assert!(e.contains("unknown parameter 'depth_complexty'"), "{e}");
    let e = SceneSpec::new("nope", Params::new())
        .build()
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown scene generator"), "{e}");
}

#[test]
fn generators_are_deterministic() {
    for g in ["grass", "quads", "shells", "particles", "hair"] {
        let a = SceneSpec::new(g, Params::new()).build().unwrap();
        let b = SceneSpec::new(g, Params::new()).build().unwrap();
        assert_eq!(a.mesh.positions, b.mesh.positions, "{g}");
    }
}

#[test]
fn builtin_suites_parse_and_bad_suites_say_why() {
    for (name, _) in scenarios::suite::BUILTIN {
        Suite::load(name).unwrap_or_else(|e| panic!("suite {name}: {e}"));
    }
    let e = Suite::parse("reps = 0\n[[study]]\nkind='methods'\n", "x.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("x.toml") && e.contains("reps"), "{e}");
    let e = Suite::parse(
        "resolutions = [[0, 5]]\n[[study]]\nkind='methods'\n",
        "x.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("out of range"), "{e}");
    let e = Suite::parse("bogus = 1\n[[study]]\nkind='methods'\n", "x.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("top level: 'bogus' = 1: unknown key"), "{e}");
}
