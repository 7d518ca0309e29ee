//! Writes `models/teapot-trio.glb`, the glTF scene of the `views` suite: three see-through
//! teapots (the Utah teapot of `models/teapot.obj`, one mesh's accessors under three BLEND
//! materials, placed by three nodes) over an opaque floor, and a camera on a pivot that the
//! file's animation turns once about the vertical (9 LINEAR rotation keys, 45° apart, 8 s). A
//! `camera_path = "file"` scene plays that animation (`scenarios::gltf::camera_animation`).
//!
//! `cargo run -p scenarios --example teapot_trio [OBJ] [OUT]` (defaults: models/teapot.obj,
//! models/teapot-trio.glb). The output is deterministic: the same OBJ gives the same bytes.

use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let obj = PathBuf::from(args.next().unwrap_or_else(|| "models/teapot.obj".into()));
    let out = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "models/teapot-trio.glb".into()),
    );
    let mesh = scenarios::obj::load(&obj)?;
    if mesh.vertex_count() > u16::MAX as usize {
        return Err(format!("{}: over 65535 vertices (u16 indices)", obj.display()).into());
    }
    let mut bin: Vec<u8> = Vec::new();
    let mut views: Vec<String> = Vec::new();
    let mut accessors: Vec<String> = Vec::new();
    // Appends a buffer view (4-byte aligned) and one accessor over it.
    let mut push = |bytes: &[u8], accessor: String| {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        views.push(format!(
            r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#,
            bin.len(),
            bytes.len()
        ));
        bin.extend_from_slice(bytes);
        accessors.push(accessor.replace("VIEW", &(views.len() - 1).to_string()));
        accessors.len() - 1
    };
    let f32s = |v: &mut dyn Iterator<Item = f32>| v.flat_map(f32::to_le_bytes).collect::<Vec<u8>>();
    let (lo, hi) = mesh.bounds();
    let pos = push(
        &f32s(&mut mesh.positions.iter().flatten().copied()),
        format!(
            r#"{{"bufferView":VIEW,"componentType":5126,"count":{},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}}"#,
            mesh.vertex_count(),
            lo.x,
            lo.y,
            lo.z,
            hi.x,
            hi.y,
            hi.z
        ),
    );
    let idx: Vec<u8> = mesh
        .indices
        .iter()
        .flat_map(|&i| (i as u16).to_le_bytes())
        .collect();
    let ind = push(
        &idx,
        format!(
            r#"{{"bufferView":VIEW,"componentType":5123,"count":{},"type":"SCALAR"}}"#,
            mesh.indices.len()
        ),
    );
    // The floor: a square at the teapots' feet (y = lo.y), 16 units wide.
    let (s, y) = (8.0f32, lo.y - 0.01);
    let floor_pos = push(
        &f32s(&mut [-s, y, -s, s, y, -s, s, y, s, -s, y, s].into_iter()),
        format!(
            r#"{{"bufferView":VIEW,"componentType":5126,"count":4,"type":"VEC3","min":[{},{y},{}],"max":[{s},{y},{s}]}}"#,
            -s, -s
        ),
    );
    let floor_ind = push(
        &[0u16, 2, 1, 0, 3, 2]
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect::<Vec<u8>>(),
        r#"{"bufferView":VIEW,"componentType":5123,"count":6,"type":"SCALAR"}"#.into(),
    );
    // One turn of the pivot about +y: quaternions (0, sin(θ/2), 0, cos(θ/2)) at θ = 0, 45°, …
    let keys = 9;
    let times = push(
        &f32s(&mut (0..keys).map(|k| k as f32)),
        format!(
            r#"{{"bufferView":VIEW,"componentType":5126,"count":{keys},"type":"SCALAR","min":[0],"max":[{}]}}"#,
            keys - 1
        ),
    );
    let rotations = push(
        &f32s(&mut (0..keys).flat_map(|k| {
            let half = (k as f64 * std::f64::consts::FRAC_PI_4 * 0.5) as f32;
            [0.0, half.sin(), 0.0, half.cos()]
        })),
        format!(r#"{{"bufferView":VIEW,"componentType":5126,"count":{keys},"type":"VEC4"}}"#),
    );
    let material = |rgba: [f32; 4], mode: &str| {
        format!(
            r#"{{"pbrMetallicRoughness":{{"baseColorFactor":[{},{},{},{}]}},"alphaMode":"{mode}"}}"#,
            rgba[0], rgba[1], rgba[2], rgba[3]
        )
    };
    let materials = [
        material([0.85, 0.25, 0.2, 0.45], "BLEND"),
        material([0.2, 0.75, 0.3, 0.45], "BLEND"),
        material([0.25, 0.35, 0.9, 0.45], "BLEND"),
        material([0.6, 0.6, 0.55, 1.0], "OPAQUE"),
    ]
    .join(",");
    let teapot = |m: u32| {
        format!(
            r#"{{"primitives":[{{"attributes":{{"POSITION":{pos}}},"indices":{ind},"material":{m}}}]}}"#
        )
    };
    let meshes = [
        teapot(0),
        teapot(1),
        teapot(2),
        format!(r#"{{"primitives":[{{"attributes":{{"POSITION":{floor_pos}}},"indices":{floor_ind},"material":3}}]}}"#),
    ]
    .join(",");
    // Pitch of a camera at height 2.5 and distance 9 looking at the trio's middle (y ≈ 1.2).
    let pitch = -(1.3f64 / 9.0).atan();
    let (ps, pc) = ((pitch * 0.5).sin(), (pitch * 0.5).cos());
    let json = format!(
        r#"{{"asset":{{"version":"2.0","generator":"mfx scenarios/examples/teapot_trio.rs"}},
"scene":0,"scenes":[{{"nodes":[0,4,6]}}],
"nodes":[
 {{"children":[1,2,3],"translation":[0,0,0]}},
 {{"mesh":0,"translation":[0,0,0]}},
 {{"mesh":1,"translation":[1.1,0.35,-0.9],"rotation":[0,0.3827,0,0.9239],"scale":[0.8,0.8,0.8]}},
 {{"mesh":2,"translation":[-0.9,0.2,1.0],"rotation":[0,-0.5,0,0.866],"scale":[0.7,0.7,0.7]}},
 {{"name":"pivot","translation":[0,1.2,0],"children":[5]}},
 {{"name":"camera","camera":0,"translation":[0,1.3,9],"rotation":[{ps},0,0,{pc}]}},
 {{"mesh":3}}],
"cameras":[{{"type":"perspective","perspective":{{"yfov":0.6,"znear":0.1}}}}],
"meshes":[{meshes}],
"materials":[{materials}],
"animations":[{{"name":"orbit","channels":[{{"sampler":0,"target":{{"node":4,"path":"rotation"}}}}],"samplers":[{{"input":{times},"output":{rotations},"interpolation":"LINEAR"}}]}}],
"buffers":[{{"byteLength":{}}}],
"bufferViews":[{}],
"accessors":[{}]}}"#,
        bin.len(),
        views.join(","),
        accessors.join(",")
    );
    // GLB: 12-byte header, a JSON chunk padded with spaces, a BIN chunk padded with zeros.
    let mut j = json.into_bytes();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + bin.len();
    let mut glb = Vec::with_capacity(total);
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(j.len() as u32).to_le_bytes());
    glb.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    glb.extend_from_slice(&j);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    glb.extend_from_slice(&bin);
    std::fs::write(&out, glb)?;
    println!(
        "{}: {} B, {} triangles per teapot",
        out.display(),
        total,
        mesh.triangle_count()
    );
    Ok(())
}
