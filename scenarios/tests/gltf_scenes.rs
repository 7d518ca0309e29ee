//! glTF scenes: the generated example loads from `.gltf` + `.bin` and from `.glb` alike, node
//! transforms instance a mesh, materials map to opacity (BLEND alpha, MASK cutoff, OPAQUE),
//! and bad files are refused naming the problem.

use scenarios::{ParamValue, Params, SceneSpec};

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("mfx-gltf-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn gltf_and_glb_load_the_same_instanced_scene_with_material_alpha() {
    let d = tmp("instanced");
    let a = scenarios::gltf::load(&scenarios::gltf::write_example(&d, false).unwrap()).unwrap();
    let b = scenarios::gltf::load(&scenarios::gltf::write_example(&d, true).unwrap()).unwrap();
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.colors, b.colors);
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
    let d = tmp("bad");
    let p = scenarios::gltf::write_example(&d, false).unwrap();
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
    assert!(w.contains("buffer 0 holds 8 B"), "{w}");
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
