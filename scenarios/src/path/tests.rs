use super::*;
use crate::{ParamValue as V, Params};

fn spec(generator: &str, keys: &[(&str, V)]) -> SceneSpec {
    let mut p = Params::new();
    for (k, v) in keys {
        p.set(k, v.clone());
    }
    SceneSpec::new(generator, p)
}

fn s(x: &str) -> V {
    V::Str(x.into())
}

/// The messages of a spec's path problems.
fn problems(sp: &SceneSpec) -> Vec<String> {
    match CameraPath::of(sp) {
        Ok(_) => Vec::new(),
        Err(v) => v.iter().map(|e| e.to_string()).collect(),
    }
}

#[test]
fn an_orbit_of_quads_turns_about_the_target_at_the_scene_cameras_distance_view_by_view() {
    let sp = spec(
        "quads",
        &[("camera_path", s("orbit")), ("path_views", V::Int(8))],
    );
    let plain = spec("quads", &[]).build().unwrap();
    let scene = sp.build().unwrap();
    assert_eq!(scene.views.len(), 8);
    assert_eq!(scene.camera, scene.views[0]);
    assert!(
        scene.label().contains("camera_path=orbit"),
        "{}",
        scene.label()
    );
    let target = DVec3::from(plain.camera.target);
    let d0 = (DVec3::from(plain.camera.eye) - target).length();
    // View 0 is the scene camera's eye and target; each later view 45° further about +y.
    assert!((DVec3::from(scene.views[0].eye) - DVec3::from(plain.camera.eye)).length() < 1e-9);
    for (i, v) in scene.views.iter().enumerate() {
        let off = DVec3::from(v.eye) - target;
        assert!((off.length() - d0).abs() < 1e-9, "view {i}");
        assert_eq!(DVec3::from(v.target), target);
        let az = off.x.atan2(off.z).to_degrees().rem_euclid(360.0);
        let want = (45.0 * i as f64).rem_euclid(360.0);
        let gap = (az - want).abs();
        assert!(gap.min(360.0 - gap) < 1e-6, "view {i}: azimuth {az}");
    }
    // Deterministic: the same keys give the same cameras.
    assert_eq!(sp.build().unwrap().views, scene.views);
}

#[test]
fn an_orbit_keeps_the_whole_scene_inside_the_depth_range_at_every_view() {
    // Grass is a wide field: from the side its far edge is farther than from the front.
    let sp = spec(
        "grass",
        &[
            ("blades", V::Int(200)),
            ("camera_path", s("orbit")),
            ("path_views", V::Int(12)),
            ("orbit_elevation", V::Float(35.0)),
            ("orbit_distance", V::Float(0.6)),
        ],
    );
    let scene = sp.build().unwrap();
    for (i, cam) in scene.views.iter().enumerate() {
        let m = cam.clip_from_world_f64(1.0);
        let off = DVec3::from(cam.eye) - DVec3::from(cam.target);
        assert!(((off.y / off.length()).asin().to_degrees() - 35.0).abs() < 1e-9);
        for p in &scene.mesh.positions {
            let c = m * glam::Vec3::from(*p).as_dvec3().extend(1.0);
            // In front of the near plane or not, nothing lies past the far plane.
            assert!(c.z <= c.w, "view {i}: a vertex past the far plane");
        }
    }
}

#[test]
fn a_fly_through_moves_eye_and_target_together_along_the_view() {
    let sp = spec(
        "shells",
        &[
            ("count", V::Int(2)),
            ("camera_path", s("fly")),
            ("path_views", V::Int(5)),
            ("fly_depth", V::Float(0.5)),
        ],
    );
    let plain = spec("shells", &[("count", V::Int(2))]).build().unwrap();
    let scene = sp.build().unwrap();
    let (e0, t0) = (
        DVec3::from(plain.camera.eye),
        DVec3::from(plain.camera.target),
    );
    for (i, v) in scene.views.iter().enumerate() {
        let step = (t0 - e0) * 0.5 * i as f64 / 4.0;
        assert!(
            (DVec3::from(v.eye) - (e0 + step)).length() < 1e-9,
            "view {i}"
        );
        assert!(
            (DVec3::from(v.target) - (t0 + step)).length() < 1e-9,
            "view {i}"
        );
        assert_eq!(v.fovy, plain.camera.fovy);
    }
}

#[test]
fn at_rest_is_the_scene_camera_every_view() {
    let sp = spec(
        "quads",
        &[("camera_path", s("at_rest")), ("path_views", V::Int(4))],
    );
    let plain = spec("quads", &[]).build().unwrap();
    let scene = sp.build().unwrap();
    assert_eq!(scene.views, vec![plain.camera.clone(); 4]);
    assert!(CameraPath::of(&sp).unwrap().unwrap().at_rest());
}

#[test]
fn keyframes_are_sampled_evenly_in_time_and_interpolated() {
    let text = "# time eye target fov\n0  0 0 4  0 0 0  40\n\n2  4 0 0  0 0 0  # fov: the scene's\n3, 0,4,0, 0,0,0, 60\n";
    let keys = parse_keyframes(text, Path::new("k.txt")).unwrap();
    assert_eq!(keys.len(), 3);
    assert_eq!(keys[1].line, 4);
    // Views at t = 0, 1, 2, 3.
    let (e, _, f) = sample_keyframes(&keys, 1.0 / 3.0);
    assert!((e - DVec3::new(2.0, 0.0, 2.0)).length() < 1e-12);
    assert_eq!(f, Some(40.0));
    let (e, _, f) = sample_keyframes(&keys, 1.0);
    assert_eq!(e, DVec3::new(0.0, 4.0, 0.0));
    assert_eq!(f, Some(60.0));
}

#[test]
fn a_bad_keyframe_line_is_an_error_naming_the_file_and_the_line() {
    let cases = [
        ("0 0 0 4 0 0 0\n1 0 0 4 0 0\n", 2, "6 fields"),
        (
            "0 0 0 4 0 0 0\n1 0 0 x 0 0 0\n",
            2,
            "eye z 'x' is not a finite number",
        ),
        (
            "0 0 0 4 0 0 0\n\n0 0 0 5 0 0 0\n",
            3,
            "is not after the previous keyframe's 0 (line 1)",
        ),
        ("0 1 1 1 1 1 1\n", 1, "the target is the eye"),
        ("0 0 0 4 0 0 0 200\n", 1, "fov 200 is outside"),
        ("0 0 0 inf 0 0 0\n", 1, "not a finite number"),
    ];
    for (text, line, says) in cases {
        let e = parse_keyframes(text, Path::new("dir/keys.txt"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("'dir/keys.txt':{line}:")),
            "{text:?}: {e}"
        );
        assert!(e.contains(says), "{text:?}: {e}");
    }
    let e = parse_keyframes("# only a comment\n", Path::new("k")).unwrap_err();
    assert!(e.to_string().contains("no keyframes"), "{e}");
}

#[test]
fn a_scene_reading_a_bad_keyframe_file_is_refused_by_its_check_naming_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("fly.keys");
    std::fs::write(&f, "0 0 0 4 0 0 0\n1 0 0 3 0 0 0\n0.5 0 0 2 0 0 0\n").unwrap();
    let sp = spec(
        "quads",
        &[
            ("camera_path", s("file")),
            ("path_file", s(f.to_str().unwrap())),
        ],
    );
    let p: Vec<String> = sp.check().iter().map(|e| e.to_string()).collect();
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].contains(&format!("{}':3:", f.display())), "{p:?}");
    // A good file builds: views along the keyframes.
    std::fs::write(&f, "0 0 0 4 0 0 0\n1 0 0 3 0 0 0\n").unwrap();
    assert!(sp.check().is_empty());
    let scene = sp.build().unwrap();
    assert_eq!(scene.views.len(), 32);
    assert_eq!(DVec3::from(scene.views[31].eye), DVec3::new(0.0, 0.0, 3.0));
    // A missing file is named too.
    let gone = spec(
        "quads",
        &[("camera_path", s("file")), ("path_file", s("no/such.keys"))],
    );
    let p: Vec<String> = gone.check().iter().map(|e| e.to_string()).collect();
    assert!(p.iter().any(|m| m.contains("no/such.keys")), "{p:?}");
}

#[test]
fn every_problem_of_the_path_keys_is_reported_at_once() {
    // No camera_path: its keys would do nothing.
    let p = problems(&spec("quads", &[("path_views", V::Int(8))]));
    assert!(p[0].contains("no camera_path"), "{p:?}");
    let p = problems(&spec(
        "quads",
        &[
            ("camera_path", s("fly")),
            ("path_views", V::Int(1)),
            ("orbit_step", V::Float(5.0)),
            ("fly_depth", V::Float(9.0)),
        ],
    ));
    assert_eq!(p.len(), 3, "{p:?}");
    assert!(p
        .iter()
        .any(|m| m.contains("path_views") && m.contains("2..=4096")));
    assert!(p
        .iter()
        .any(|m| m.contains("orbit_step") && m.contains("only with camera_path = orbit")));
    assert!(p.iter().any(|m| m.contains("fly_depth")));
    let p = problems(&spec("quads", &[("camera_path", s("spiral"))]));
    assert!(p[0].contains("orbit, fly, file, at_rest"), "{p:?}");
    let p = problems(&spec("quads", &[("camera_path", s("file"))]));
    assert!(p[0].contains("needs path_file"), "{p:?}");
    let p = problems(&spec(
        "quads",
        &[("camera_path", s("orbit")), ("orbit_step", V::Int(0))],
    ));
    assert!(p[0].contains("at_rest"), "{p:?}");
    // The generator never sees the path keys; its own typos are still its problems.
    let sp = spec(
        "quads",
        &[("camera_path", s("orbit")), ("depth_complexty", V::Int(3))],
    );
    let all: Vec<String> = sp.check().iter().map(|e| e.to_string()).collect();
    assert_eq!(all.len(), 1, "{all:?}");
    assert!(all[0].contains("depth_complexty"), "{all:?}");
}

/// A glTF scene (one quad, −1..1 in x and y) with a perspective camera node (yfov 0.8) moved by
/// a `interpolation` animation from (0, 0, 3) at t = 0 to (0, 0, 5) at t = 2, as a `data:` URI.
fn animated_gltf(dir: &Path, interpolation: &str, animated: bool) -> PathBuf {
    use base64::Engine as _;
    let mut bin: Vec<u8> = Vec::new();
    let f32s = |bin: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| bin.extend(x.to_le_bytes()));
    f32s(
        &mut bin,
        &[-1., -1., 0., 1., -1., 0., 1., 1., 0., -1., 1., 0.],
    );
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    f32s(&mut bin, &[0.0, 2.0]); // offset 60: times
    f32s(&mut bin, &[0., 0., 3., 0., 0., 5.]); // offset 68: translations
    let uri = base64::engine::general_purpose::STANDARD.encode(&bin);
    let animations = if animated {
        format!(
            r#","animations":[{{"channels":[{{"sampler":0,"target":{{"node":1,"path":"translation"}}}}],"samplers":[{{"input":2,"output":3,"interpolation":"{interpolation}"}}]}}]"#
        )
    } else {
        String::new()
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
"nodes":[{{"mesh":0}},{{"camera":0,"translation":[0,0,3]}}],
"cameras":[{{"type":"perspective","perspective":{{"yfov":0.8,"znear":0.1}}}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{uri}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}},{{"buffer":0,"byteOffset":60,"byteLength":8}},{{"buffer":0,"byteOffset":68,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,-1,0],"max":[1,1,0]}},{{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}},{{"bufferView":2,"componentType":5126,"count":2,"type":"SCALAR","min":[0],"max":[2]}},{{"bufferView":3,"componentType":5126,"count":2,"type":"VEC3"}}]{animations}}}"#,
        bin.len()
    );
    let p = dir.join("animated.gltf");
    std::fs::write(&p, json).unwrap();
    p
}

#[test]
fn a_gltf_scene_plays_its_files_camera_animation_in_the_normalised_space() {
    let dir = tempfile::tempdir().unwrap();
    let f = animated_gltf(dir.path(), "LINEAR", true);
    let cams = crate::gltf::camera_animation(&f, 5).unwrap();
    for (i, c) in cams.iter().enumerate() {
        let z = 3.0 + 0.5 * i as f64;
        assert!(
            (c.eye - DVec3::new(0.0, 0.0, z)).length() < 1e-6,
            "view {i}: {c:?}"
        );
        assert!((c.target - DVec3::new(0.0, 0.0, z - 1.0)).length() < 1e-6);
        assert!((c.yfov_deg - 0.8f64.to_degrees()).abs() < 1e-5);
    }
    // STEP holds the first value until the last key.
    std::fs::create_dir(dir.path().join("step")).unwrap();
    let f2 = animated_gltf(&dir.path().join("step"), "STEP", true);
    let step = crate::gltf::camera_animation(&f2, 3).unwrap();
    assert!((step[1].eye.z - 3.0).abs() < 1e-6 && (step[2].eye.z - 5.0).abs() < 1e-6);
    // As a scene: the quad normalised into the unit sphere (scale 1/√2), the eye with it.
    let sp = spec(
        "gltf",
        &[
            ("path", s(f.to_str().unwrap())),
            ("camera_path", s("file")),
            ("path_views", V::Int(5)),
        ],
    );
    assert!(sp.check().is_empty(), "{:?}", sp.check());
    let scene = sp.build().unwrap();
    let k = std::f64::consts::FRAC_1_SQRT_2;
    for (i, v) in scene.views.iter().enumerate() {
        let want = DVec3::new(0.0, 0.0, (3.0 + 0.5 * i as f64) * k);
        assert!((DVec3::from(v.eye) - want).length() < 1e-6, "view {i}");
        assert!((v.fovy - 0.8).abs() < 1e-6);
    }
}

#[test]
fn a_gltf_without_a_camera_animation_is_refused_before_any_gpu_work() {
    let dir = tempfile::tempdir().unwrap();
    let f = animated_gltf(dir.path(), "LINEAR", false);
    let sp = spec(
        "gltf",
        &[("path", s(f.to_str().unwrap())), ("camera_path", s("file"))],
    );
    let p: Vec<String> = sp.check().iter().map(|e| e.to_string()).collect();
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].contains("no animation moves camera node 1"), "{p:?}");
}
