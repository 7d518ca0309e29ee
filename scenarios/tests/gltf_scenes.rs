//! glTF scenes: the generated example loads from `.gltf` + `.bin`, from `.gltf` with a `data:`
//! URI and from `.glb` alike, node transforms instance a mesh, materials map to opacity (BLEND
//! alpha, MASK cutoff, OPAQUE, baseColorTexture alpha per vertex, KHR_materials_transmission,
//! no material), and bad files are refused naming the element (accessor, view, buffer, image).

use base64::Engine as _;
use scenarios::gltf::Form;
use scenarios::{ParamValue, Params, SceneSpec};

/// A temp folder removed when the test ends, pass or fail.
fn tmp(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("mfx-gltf-{name}-"))
        .tempdir()
        .unwrap()
}

#[test]
fn gltf_and_glb_load_the_same_instanced_scene_with_material_alpha() {
    let t = tmp("instanced");
    let d = t.path();
    let a = scenarios::gltf::load(&scenarios::gltf::write_example(d, false).unwrap()).unwrap();
    let b = scenarios::gltf::load(&scenarios::gltf::write_example(d, true).unwrap()).unwrap();
    let e = scenarios::gltf::load(&scenarios::gltf::write_example_as(d, Form::Embedded).unwrap())
        .unwrap();
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.colors, b.colors);
    assert_eq!(a.positions, e.positions, "data: URI = external buffer");
    assert_eq!(a.colors, e.colors);
    assert_eq!(a.indices, e.indices);
    // Four quads drawn: BLEND twice (two nodes, one mesh), MASK-pass, OPAQUE; MASK-fail dropped.
    assert_eq!(a.indices.len(), 4 * 6);
    let mut alphas: Vec<f32> = a.colors.chunks(4).map(|q| q[0][3]).collect();
    alphas.sort_by(f32::total_cmp);
    assert_eq!(alphas, vec![0.5, 0.5, 1.0, 1.0]);
    let ids: std::collections::BTreeSet<u32> = a.object_ids.iter().copied().collect();
    assert_eq!(ids.len(), 4, "each drawn node is its own object");
    // The two BLEND instances sit apart: the root's scale and the children's offsets applied.
    let blend: Vec<[f32; 3]> = a
        .colors
        .iter()
        .zip(&a.positions)
        .filter(|(c, _)| c[3] == 0.5)
        .map(|(_, p)| *p)
        .collect();
    assert_eq!(blend.len(), 8);
    assert_ne!(blend[0], blend[4]);
    assert!(
        blend.iter().any(|p| p[0].abs() > 1.5),
        "root scale 2 applied: {blend:?}"
    );

    let spec = SceneSpec::new(
        "gltf",
        Params::new().with(
            "path",
            ParamValue::Str(d.join("example.glb").display().to_string()),
        ),
    );
    assert!(spec.check().is_empty(), "{:?}", spec.check());
    let scene = spec.build().unwrap();
    let r = scene
        .mesh
        .positions
        .iter()
        .map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt())
        .fold(0.0f32, f32::max);
    assert!(
        (r - 1.0).abs() < 1e-4,
        "normalised into the unit sphere like obj: {r}"
    );
}

#[test]
fn bad_gltf_files_are_refused_with_the_reason() {
    let t = tmp("bad");
    let d = t.path();
    let p = scenarios::gltf::write_example(d, false).unwrap();
    let why = |path: &std::path::Path| scenarios::gltf::load(path).unwrap_err().to_string();
    assert!(why(&d.join("none.gltf")).contains("file not found"));
    std::fs::write(d.join("short.bin"), [0u8; 8]).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    std::fs::write(
        d.join("short.gltf"),
        text.replace("example.bin", "short.bin"),
    )
    .unwrap();
    let w = why(&d.join("short.gltf"));
    assert!(w.contains("buffer 0 (short.bin) holds 8 B"), "{w}");
    std::fs::write(
        d.join("missing.gltf"),
        text.replace("example.bin", "gone.bin"),
    )
    .unwrap();
    assert!(why(&d.join("missing.gltf")).contains("gone.bin"));
    std::fs::write(d.join("junk.gltf"), "{ not json").unwrap();
    assert!(why(&d.join("junk.gltf")).contains("invalid glTF"));
    std::fs::write(
        d.join("v1.gltf"),
        text.replace(r#""mesh":0,"#, r#""mesh":9,"#),
    )
    .unwrap();
    assert!(why(&d.join("v1.gltf")).contains("invalid glTF"));
    assert!(why(&d.join("v1.gltf")).starts_with("glTF file"));
}

/// The example's JSON with `from` replaced by `to` (exactly once), written beside it as `name`.
fn variant(d: &std::path::Path, name: &str, from: &str, to: &str) -> std::path::PathBuf {
    let text = std::fs::read_to_string(d.join("example.gltf")).unwrap();
    assert_eq!(text.matches(from).count(), 1, "{from} once in the example");
    let p = d.join(name);
    std::fs::write(&p, text.replace(from, to)).unwrap();
    p
}

#[test]
fn accessors_past_their_views_and_views_past_buffers_are_refused_naming_them() {
    let t = tmp("accessors");
    let d = t.path();
    scenarios::gltf::write_example(d, false).unwrap();
    let why = |p: &std::path::Path| scenarios::gltf::load(p).unwrap_err().to_string();
    // Indices: 2e9 u16 entries on a 12-byte view (the issue's file rendered the valid image).
    let w = why(&variant(
        d,
        "ix.gltf",
        r#""count":6,"#,
        r#""count":2000000000,"#,
    ));
    assert!(
        w.contains("accessor 1") && w.contains("count 2000000000") && w.contains("buffer view 1"),
        "{w}"
    );
    // POSITION: 4e9 VEC3 entries (was "no POSITION").
    let w = why(&variant(
        d,
        "pos.gltf",
        r#""count":4,"#,
        r#""count":4000000000,"#,
    ));
    assert!(
        w.contains("accessor 0") && w.contains("stride 12 B") && w.contains("buffer view 0"),
        "{w}"
    );
    // An accessor offset that pushes the last element out by one byte.
    let w = why(&variant(
        d,
        "off.gltf",
        r#""componentType":5123,"count":6,"#,
        r#""byteOffset":2,"componentType":5123,"count":6,"#,
    ));
    assert!(w.contains("accessor 1") && w.contains("needs 14 B"), "{w}");
    // A view past the end of its buffer.
    let w = why(&variant(
        d,
        "view.gltf",
        r#""byteOffset":48,"byteLength":12"#,
        r#""byteOffset":52,"byteLength":12"#,
    ));
    assert!(w.contains("buffer view 1") && w.contains("buffer 0"), "{w}");
    // A data: URI that is not base64.
    let w = why(&variant(
        d,
        "uri.gltf",
        r#""uri":"example.bin""#,
        r#""uri":"data:application/octet-stream;base64,@@@""#,
    ));
    assert!(w.contains("buffer 0 (a data: URI)"), "{w}");
}

/// A one-quad glTF (UVs 0..1) whose material is `material` (JSON), with a 2×2 RGBA PNG texture
/// embedded as a data: URI: texels (u, v) = (0,0) alpha 0.2, (1,0) 0.4, (0,1) 0.6, (1,1) 1.0.
fn textured_quad(d: &std::path::Path, name: &str, material: &str) -> std::path::PathBuf {
    let mut png = Vec::new();
    let img = image::RgbaImage::from_raw(
        2,
        2,
        vec![
            255, 0, 0, 51, 0, 255, 0, 102, //
            0, 0, 255, 153, 255, 255, 255, 255,
        ],
    )
    .unwrap();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let mut bin: Vec<u8> = Vec::new();
    for p in [
        [-1.0f32, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ] {
        p.iter()
            .for_each(|c| bin.extend_from_slice(&c.to_le_bytes()));
    }
    // Texel centres, so nearest sampling picks one texel each: (0,0) (1,0) (1,1) (0,1).
    for uv in [[0.25f32, 0.25], [0.75, 0.25], [0.75, 0.75], [0.25, 0.75]] {
        uv.iter()
            .for_each(|c| bin.extend_from_slice(&c.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":2,"material":0}}]}}],
"materials":[{material}],
"textures":[{{"source":0,"sampler":0}}],"samplers":[{{"magFilter":9728,"minFilter":9728}}],
"images":[{{"uri":"data:image/png;base64,{}"}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":32}},{{"buffer":0,"byteOffset":80,"byteLength":12}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,-1,0],"max":[1,1,0]}},{{"bufferView":1,"componentType":5126,"count":4,"type":"VEC2"}},{{"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}}]}}"#,
        b64(&png),
        bin.len(),
        b64(&bin)
    );
    let p = d.join(name);
    std::fs::write(&p, json).unwrap();
    p
}

#[test]
fn base_color_texture_alpha_is_sampled_per_vertex_and_transmission_is_transparent() {
    let t = tmp("texture");
    let d = t.path();
    let tex = r#""baseColorTexture":{"index":0}"#;
    let blend = textured_quad(
        d,
        "blend.gltf",
        &format!(
            r#"{{"pbrMetallicRoughness":{{"baseColorFactor":[1,1,1,0.5],{tex}}},"alphaMode":"BLEND"}}"#
        ),
    );
    let m = scenarios::gltf::load(&blend).unwrap();
    let alphas: Vec<f32> = m.colors.iter().map(|c| c[3]).collect();
    let want = [0.2f32, 0.4, 1.0, 0.6].map(|a| a * 0.5);
    for (a, w) in alphas.iter().zip(want) {
        assert!(
            (a - w).abs() < 1.0 / 255.0,
            "alpha per vertex {alphas:?} vs {want:?}"
        );
    }
    assert!(
        (m.colors[0][0] - 1.0).abs() < 1e-6 && m.colors[0][1] < 1e-6,
        "texel (0,0) is red"
    );

    // OPAQUE ignores the texture's alpha; KHR_materials_transmission 0.75 leaves 0.25 of it.
    let glass = textured_quad(
        d,
        "glass.gltf",
        &format!(
            r#"{{"pbrMetallicRoughness":{{{tex}}},"extensions":{{"KHR_materials_transmission":{{"transmissionFactor":0.75}}}}}}"#
        ),
    );
    let g = scenarios::gltf::load(&glass).unwrap();
    assert!(
        g.colors.iter().all(|c| (c[3] - 0.25).abs() < 1e-6),
        "{:?}",
        g.colors
    );

    // MASK per triangle: (0.2 + 0.4 + 1.0) / 3 ≥ 0.5 kept, (0.2 + 1.0 + 0.6) / 3 ≥ 0.5 kept;
    // with cutoff 0.55 the first (0.533) goes.
    let mask = textured_quad(
        d,
        "mask.gltf",
        &format!(r#"{{"pbrMetallicRoughness":{{{tex}}},"alphaMode":"MASK","alphaCutoff":0.55}}"#),
    );
    let k = scenarios::gltf::load(&mask).unwrap();
    assert_eq!(k.indices.len(), 3, "one triangle passes the cutoff");
    assert!(
        k.colors.iter().all(|c| c[3] == 1.0),
        "a passing triangle is opaque"
    );

    // A texture whose TEXCOORD set the primitive lacks is refused naming it.
    let bad = textured_quad(
        d,
        "set.gltf",
        r#"{"pbrMetallicRoughness":{"baseColorTexture":{"index":0,"texCoord":1}}}"#,
    );
    let w = scenarios::gltf::load(&bad).unwrap_err().to_string();
    assert!(
        w.contains("TEXCOORD_1") && w.contains("mesh 0 primitive 0"),
        "{w}"
    );
}

#[test]
fn a_primitive_without_material_is_not_white_on_white_and_is_said_so() {
    let t = tmp("nomaterial");
    let d = t.path();
    scenarios::gltf::write_example(d, false).unwrap();
    let p = variant(d, "plain.gltf", r#","material":3}"#, "}");
    let (m, warnings) = scenarios::gltf::load_with_warnings(&p).unwrap();
    assert!(
        m.colors.iter().all(|c| c[..3] != [1.0, 1.0, 1.0]),
        "no vertex is the default white"
    );
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("no material") && w.contains("palette")),
        "{warnings:?}"
    );
}

#[test]
fn a_suite_places_a_model_scenes_camera_or_takes_the_gltf_files_own() {
    let t = tmp("camera");
    let d = t.path();
    let sep = scenarios::gltf::write_example(d, false).unwrap();
    let spec = |extra: &[(&str, ParamValue)]| {
        let mut p = Params::new().with("path", ParamValue::Str(sep.display().to_string()));
        for (k, v) in extra {
            p.set(k, v.clone());
        }
        SceneSpec::new("gltf", p)
    };
    let s = spec(&[
        ("eye", ParamValue::Str("0, 1, 3".into())),
        ("target", ParamValue::Str("0,0,0".into())),
        ("fov", ParamValue::Float(30.0)),
    ]);
    assert!(s.check().is_empty(), "{:?}", s.check());
    let c = s.build().unwrap().camera;
    assert_eq!(c.eye, [0.0, 1.0, 3.0]);
    assert!((c.fovy - 30f64.to_radians()).abs() < 1e-12);
    // Checked like every key, naming it.
    for (k, v) in [("eye", "1,2"), ("eye", "1,nan,2"), ("fov", "wide")] {
        let s = spec(&[(k, ParamValue::Str(v.into()))]);
        let p: Vec<String> = s.check().iter().map(|e| e.to_string()).collect();
        assert!(
            p.iter().any(|m| m.contains(&format!("'{k}'"))),
            "{k} = {v}: {p:?}"
        );
    }
    // The file's camera: a node 5 units in front of the model, yfov 0.5.
    let text = std::fs::read_to_string(&sep).unwrap();
    let with_cam = text
        .replace(r#""scenes":[{"nodes":[0]}]"#, r#""scenes":[{"nodes":[0,6]}],"cameras":[{"type":"perspective","perspective":{"yfov":0.5,"znear":0.1}}]"#)
        .replace(
            r#"{"mesh":3,"translation":[0,0,-0.8],"scale":[1.2,1.2,1.2]}]"#,
            r#"{"mesh":3,"translation":[0,0,-0.8],"scale":[1.2,1.2,1.2]},{"camera":0,"translation":[0,0,5]}]"#,
        );
    assert_ne!(text, with_cam);
    let camfile = d.join("cam.gltf");
    std::fs::write(&camfile, with_cam).unwrap();
    let s = SceneSpec::new(
        "gltf",
        Params::new()
            .with("path", ParamValue::Str(camfile.display().to_string()))
            .with("camera", ParamValue::Str("file".into())),
    );
    assert!(s.check().is_empty(), "{:?}", s.check());
    let c = s.build().unwrap().camera;
    assert!((c.fovy - 0.5).abs() < 1e-6, "{c:?}");
    // The node sits on +z, outside the model's bounding sphere, and looks straight down −z.
    assert!(c.eye[2] > 1.0, "in front of the unit sphere: {c:?}");
    assert!(c.target[2] < c.eye[2], "looking down −z: {c:?}");
    assert!((c.target[0] - c.eye[0]).abs() < 1e-9 && (c.target[1] - c.eye[1]).abs() < 1e-9);
    // Without a camera in the file, asking for it is an error naming the file.
    let s = spec(&[("camera", ParamValue::Str("file".into()))]);
    let e = s.build().unwrap_err().to_string();
    assert!(e.contains("no perspective camera"), "{e}");
}
