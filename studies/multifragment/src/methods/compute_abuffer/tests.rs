use crate::methods::Timed;
use glam::{DVec3, Vec3};
use scenarios::ParamValue::{Int, Str};
use scenarios::{Camera, Mesh, Params, Scene, SceneSpec};

use super::*;
use crate::methods::shared::counted_capture::*;
use crate::testing::{count_mismatch, gpu, max_err, params, run, scene};
use bench_core::record::Flag;
use mfx_reference::rasterize;

/// Composite of up to ~16 layers in f32 vs f64, attributes re-derived from the primitive in f32.
const IMAGE_TOL: f64 = 5e-5;

fn check(name: &str, s: &Scene, w: u32, h: u32, p: &Params) {
    let (cap, lists) = run(&ComputeAbuffer, s, w, h, p);
    assert_eq!(cap.overflow_pixels, Some(0), "{name}: {}", cap.notes);
    assert!(cap.flag.is_empty(), "{name}: {} {}", cap.flag, cap.notes);
    let (bad, first) = count_mismatch(&cap, &lists, u32::MAX);
    assert_eq!(bad, 0, "{name}: counts differ first at {first:?}");
    let (e, at) = max_err(&cap, &lists);
    assert!(e <= IMAGE_TOL, "{name}: error {e} at pixel {at}");
}

/// The default variant (`capture = auto`, which picks pixels or tiles per scene), the pixel
/// capture with each non-default speed axis value alone (one factor at a time), and the tiles'.
const VARIANTS: &[&[(&str, &str)]] = &[
    &[],
    &[("capture", "pixels")],
    &[("capture", "pixels"), ("transform", "triangle")],
    &[("capture", "pixels"), ("coverage", "direct")],
    &[("capture", "pixels"), ("resolve_sort", "private")],
    &[("capture", "tiles")],
    &[("capture", "tiles"), ("resolve_sort", "private")],
    &[("capture", "pixels"), ("attributes", "snapped")],
    &[("attributes", "snapped"), ("capture", "tiles")],
    // The snapped weights without the clip buffer (screen positions computed per fragment).
    &[
        ("capture", "pixels"),
        ("attributes", "snapped"),
        ("transform", "triangle"),
    ],
    // Within WebGPU's 8 storage buffers: mesh packed, work after the offsets.
    &[("capture", "pixels"), ("bindings", "packed")],
    &[("bindings", "packed"), ("capture", "tiles")],
];

fn variant_params(v: &[(&str, &str)], small: i64) -> (String, Params) {
    let mut kv: Vec<(&str, scenarios::ParamValue)> = vec![("small_max", Int(small))];
    kv.extend(v.iter().map(|(k, s)| (*k, Str(s.to_string()))));
    let label = v
        .iter()
        .map(|(k, s)| format!("{k}={s}"))
        .collect::<Vec<_>>()
        .join(",");
    (label, params(&kv))
}

#[test]
fn equals_the_reference_with_small_big_and_all_shared_triangles_in_every_variant() {
    let shells = scene("shells", &[("count", Int(4)), ("segments", Int(12))]);
    let grass = scene("grass", &[("blades", Int(300))]);
    let quads = scene("quads", &[("depth_complexity", Int(6))]);
    // small_max 1: (almost) every triangle takes the shared path; 1 << 20: every unclipped one
    // that spans at most 126 px (all of these at 48×40) is rasterised by a single thread.
    for v in VARIANTS {
        for small in [1, 128, 1 << 20] {
            let (label, p) = variant_params(v, small);
            for (name, s) in [("shells", &shells), ("grass", &grass), ("quads", &quads)] {
                check(&format!("{name} small_max {small} {label}"), s, 48, 40, &p);
            }
        }
    }
}

/// Runs `s` and returns the capture's big-triangle tile counts (empty, full, partial) from its
/// notes.
fn tile_classes(notes: &str) -> [u64; 3] {
    let at = notes
        .find("big-triangle tiles ")
        .expect("tile counts in the notes")
        + 19;
    let words: Vec<u64> = notes[at..]
        .split(|c: char| !c.is_ascii_digit())
        .filter(|w| !w.is_empty())
        .take(3)
        .map(|w| w.parse().unwrap())
        .collect();
    [words[0], words[1], words[2]]
}

#[test]
fn big_triangles_tiles_empty_full_and_partial_equal_the_reference() {
    // 160×128: the quads span up to ~150 px, so a triangle's 32×32 tiles fall wholly outside
    // it, wholly inside it and across its edges; 40 layers exceed the workgroup sort's 32 slots
    // at the centre, so the resolve's fallback to the per-thread array runs too.
    let quads = scene("quads", &[("depth_complexity", Int(40))]);
    for v in VARIANTS {
        let (label, p) = variant_params(v, 1);
        let (cap, lists) = run(&ComputeAbuffer, &quads, 160, 128, &p);
        assert!(lists.max_depth_complexity() > 32);
        // The tile classes are the pixel capture's shared raster; the binned one has none
        // (capture = tiles, or auto where it took the tiles).
        let binned = label.contains("tiles") || cap.notes.contains("capture auto: tiles");
        if !label.contains("direct") && !binned {
            let [empty, full, partial] = tile_classes(&cap.notes);
            assert!(
                empty > 0 && full > 0 && partial > 0,
                "{label}: every tile class occurs: {}",
                cap.notes
            );
        }
        check(&format!("quads(40) 160×128 {label}"), &quads, 160, 128, &p);
    }
}

#[test]
fn long_slivers_take_the_shared_path_and_equal_the_reference() {
    // Thin triangles spanning ~350 px with bounding boxes of a few hundred pixels: with
    // small_max 1 << 20 their span (over 126 px) still sends them to the tiles, whose stepped
    // 64-bit edges must decide every pixel as the reference does. Horizontal ones get 32-wide
    // tiles; vertical ones (the mesh turned 90°, bounding boxes under 32 px wide) narrow, tall
    // tiles.
    for vertical in [false, true] {
        let mut m = Mesh::default();
        for k in 0..6 {
            let y = -0.3 + 0.1 * k as f32;
            let mut v = [
                [-2.5, y, 0.1 * k as f32],
                [2.5, y + 0.013, 0.0],
                [-2.4, y + 0.031, 0.0],
            ];
            if vertical {
                v = v.map(|[x, y, z]| [y, x, z]);
            }
            tri(&mut m, v, [0.2 + 0.1 * k as f32, 0.5, 0.7, 0.5], k);
        }
        let s = scene_with(m, 5.0, 0.5);
        let (w, h) = if vertical { (48, 400) } else { (400, 48) };
        for v in VARIANTS {
            for small in [1 << 20, 256] {
                let (label, p) = variant_params(v, small);
                let name = format!("slivers vertical {vertical} small_max {small} {label}");
                check(&name, &s, w, h, &p);
            }
        }
    }
}

fn scene_with(mesh: Mesh, eye_z: f64, near: f64) -> Scene {
    let cam = Camera::look_at(DVec3::new(0.0, 0.0, eye_z), DVec3::ZERO, 60.0, near, 100.0);
    Scene::new(SceneSpec::new("test", Params::new()), mesh, cam)
}

fn tri(mesh: &mut Mesh, v: [[f32; 3]; 3], color: [f32; 4], id: u32) {
    let base = mesh.positions.len() as u32;
    for p in v {
        mesh.positions.push(p);
        mesh.normals.push([0.0, 0.0, 1.0]);
        mesh.colors.push(color);
        mesh.object_ids.push(id);
    }
    mesh.indices.extend_from_slice(&[base, base + 1, base + 2]);
}

#[test]
fn clips_at_the_near_plane_and_the_guard_band_like_the_reference() {
    let mut m = Mesh::default();
    // A floor reaching behind the eye (eye at z = 5): clipped by the near plane into a polygon.
    let c = [Vec3::new(-3.0, -1.0, 20.0), Vec3::new(3.0, -1.0, 20.0)];
    let f = [Vec3::new(3.0, -1.0, -30.0), Vec3::new(-3.0, -1.0, -30.0)];
    m.push_quad([c[0], c[1], f[0], f[1]], [0.2, 0.6, 0.3, 0.5], 0);
    // Vertices at ±1e20: guard-band clipped (without it the edge functions overflow f32).
    tri(
        &mut m,
        [[-1e20, -1e20, 0.0], [1e20, -1e20, 0.0], [0.0, 1e20, 0.0]],
        [0.8, 0.2, 0.1, 0.4],
        1,
    );
    // An ordinary triangle in front, partly off screen.
    tri(
        &mut m,
        [[-0.5, -0.5, 1.0], [4.0, 0.0, 1.0], [0.0, 0.7, 1.0]],
        [0.1, 0.3, 0.9, 0.6],
        2,
    );
    let s = scene_with(m, 5.0, 0.5);
    for v in VARIANTS {
        for small in [1, 128] {
            let (label, p) = variant_params(v, small);
            check(
                &format!("clipped small_max {small} {label}"),
                &s,
                40,
                32,
                &p,
            );
        }
    }
}

#[test]
fn pixel_centres_on_shared_edges_are_covered_once_by_the_top_left_rule() {
    // Vertices projected exactly onto pixel centres (eye at z = 5, 60°, 32×32): a fan of four
    // triangles about (15, 15) whose edges run through whole rows, columns and diagonals of
    // pixel centres, and a quad split along its diagonal on a nearer plane. Every centre on a
    // shared edge must be covered exactly once, boundary centres as the top-left rule says.
    let (w, h) = (32u32, 32u32);
    let at = |i: f64, j: f64, z: f64| -> [f32; 3] {
        let half = (5.0 - z) * 30f64.to_radians().tan();
        let x = ((i + 0.5) / (w as f64 / 2.0) - 1.0) * half;
        let y = (1.0 - (j + 0.5) / (h as f64 / 2.0)) * half;
        [x as f32, y as f32, z as f32]
    };
    let mut m = Mesh::default();
    let e = at(15.0, 15.0, 0.0);
    let ring = [(4.0, 4.0), (27.0, 4.0), (27.0, 27.0), (4.0, 27.0)].map(|(i, j)| at(i, j, 0.0));
    for k in 0..4 {
        tri(
            &mut m,
            [e, ring[k], ring[(k + 1) % 4]],
            [0.3, 0.6, 0.2, 0.5],
            k as u32,
        );
    }
    let q = [(8.0, 10.0), (20.0, 10.0), (20.0, 22.0), (8.0, 22.0)].map(|(i, j)| at(i, j, 1.0));
    tri(&mut m, [q[0], q[1], q[2]], [0.8, 0.1, 0.1, 0.4], 4);
    tri(&mut m, [q[0], q[2], q[3]], [0.1, 0.1, 0.8, 0.4], 5);
    let s = scene_with(m, 5.0, 0.5);
    let lists = rasterize(&s, w, h);
    // The scene does put centres on edges: the fan's 4 diagonals alone hold 4 × 11 of them.
    let covered = lists.depth_complexity().iter().filter(|&&d| d > 0).count();
    assert_eq!(covered, 23 * 23, "the fan covers rows and columns 4..=26");
    for v in VARIANTS {
        for small in [1, 1 << 20] {
            let (label, p) = variant_params(v, small);
            check(
                &format!("edges on centres small_max {small} {label}"),
                &s,
                w,
                h,
                &p,
            );
        }
    }
}

#[test]
fn allocates_exactly_eight_bytes_per_true_fragment_beside_the_declared_overhead() {
    let s = scene("shells", &[("count", Int(3)), ("segments", Int(10))]);
    let (w, h) = (40u32, 36u32);
    let g = gpu();
    let gs = GpuScene::upload(g, &s, w, h);
    let total = rasterize(&s, w, h).total_fragments();
    assert!(total > 0);
    let px = (w * h) as u64;
    let blocks = px.div_ceil(SCAN_BLOCK);
    let overhead = px * 4 + px * 16 + (COUNTERS + blocks) * 4;
    let nvert = s.mesh.positions.len() as u64;
    // The big-triangle list (2 words) and tile table per triangle: tiles are at most 32 wide
    // and at least 32 tall, so ≤ ⌈w/32⌉·⌈h/32⌉ of them.
    let ntri = s.mesh.indices.len() as u64 / 3;
    let tiles = (w.div_ceil(TILE_W) * h.div_ceil(TILE_W)) as u64;
    let list_max = ntri * (2 + tiles) * 4 + 3 * 4;
    for (transform, clip) in [("vertex", nvert * CLIP_BYTES), ("triangle", CLIP_BYTES)] {
        let p = params(&[("transform", Str(transform.into()))]);
        let pt = crate::testing::point(&ComputeAbuffer, &p);
        let v = variants(&pt);
        let e = EffectConfig::from_point(&pt).unwrap();
        let prepared = PreparedAbuffer::new(g, &gs, 256, &e, v, None).unwrap();
        assert_eq!(prepared.bytes_overhead().unwrap(), overhead, "{transform}");
        let bytes = prepared.bytes_allocated();
        let least = overhead + total * FRAG_BYTES + clip;
        assert!(
            bytes >= least && bytes <= least + list_max,
            "{transform}: {bytes} B for {total} fragments ({} B of them, {overhead} B per pixel, {clip} B clip positions)",
            total * FRAG_BYTES
        );
    }
}

#[test]
fn a_fragment_beyond_the_allocation_is_counted_not_written() {
    // Prepare on a scene whose 4 far quads lie behind the eye, then (as a dynamic scene would)
    // move them into view with the same buffers: the extra fragments must be reported.
    let quads = |hidden_z: f32| {
        let m = crate::testing::quads_with_four_at(hidden_z);
        scene_with(m, 5.0, 0.5)
    };
    let (small, big) = (quads(10.0), quads(1.0));
    let (total_small, total_big) = (
        rasterize(&small, 32, 32).total_fragments(),
        rasterize(&big, 32, 32).total_fragments(),
    );
    assert!(total_big > total_small);
    let g = gpu();
    // small_max 1 << 20: every triangle on the one-thread path, so fragments past the allocation
    // are counted one by one; at the default the moved quads become shared triangles that the
    // list (sized for none) cannot hold, which is flagged too.
    for small_max in [1 << 20, 128] {
        let gs_small = GpuScene::upload(g, &small, 32, 32);
        let gs_big = GpuScene::upload(g, &big, 32, 32);
        let p = params(&[("small_max", Int(small_max))]);
        let mut prepared = ComputeAbuffer
            .prepare(g, &gs_small, &crate::testing::point(&ComputeAbuffer, &p))
            .unwrap();
        // The bind group holds the small scene's buffers: copy the moved positions over them.
        let mut enc = g.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&gs_big.positions, 0, &gs_small.positions, 0, None);
        g.queue.submit([enc.finish()]);
        let mut timer = bench_core::timing::GpuTimer::new(g);
        prepared.frame(g, &gs_small, &mut timer).unwrap();
        let cap = prepared.readback(g, &gs_small).unwrap();
        assert_eq!(cap.flag, Flag::Overflow.into(), "{}", cap.notes);
        if small_max == 128 {
            assert!(cap.notes.contains("0 shared"), "{}", cap.notes);
            assert!(
                !cap.notes.contains(" 0 big triangles unlisted"),
                "{}",
                cap.notes
            );
            continue;
        }
        assert!(cap.overflow_pixels.unwrap() > 0, "{}", cap.notes);
        let kept: u64 = cap.counts.unwrap().iter().map(|&c| c as u64).sum();
        assert_eq!(
            kept, total_small,
            "every allocated slot is used, none twice"
        );
        let beyond = format!(" {} beyond the allocation", total_big - total_small);
        assert!(cap.notes.contains(&beyond), "{}", cap.notes);
    }
}

#[test]
fn slivers_of_snapped_degenerate_triangles_stay_finite() {
    // The extreme scene's "collinear" triangles are not collinear after f32 rounding: snapped,
    // some cover pixels while their clip-space vertices are (nearly) collinear, where the
    // perspective-correct weights are 0/0.
    let s = scene(
        "extreme",
        &[
            ("coord", scenarios::ParamValue::Float(1e3)),
            ("degenerate", Int(3000)),
        ],
    );
    for attributes in ["clip", "snapped"] {
        let p = params(&[("attributes", Str(attributes.into()))]);
        let (cap, _) = run(&ComputeAbuffer, &s, 96, 96, &p);
        let img = cap.image.unwrap();
        let bad = img.iter().flatten().filter(|v| !v.is_finite()).count();
        assert_eq!(
            bad, 0,
            "attributes {attributes}: {bad} non-finite channels; {}",
            cap.notes
        );
    }
}

/// Runs `main` of `body` (after df32.wgsl) over `n` threads with read-only storage buffers
/// `inputs` at bindings 0.. and a read-write output of `out_bytes` after them; returns the output.
fn run_kernel(body: &str, inputs: &[&[u8]], out_bytes: u64, n: u32) -> Vec<u8> {
    use bench_core::gpu_util::{bind_buffers, compute_pipeline, shader, storage_entry};
    use wgpu::util::DeviceExt;
    let g = gpu();
    let module = shader(g, "kernel test", &format!("{DF32_WGSL}\n{body}"));
    let cs = wgpu::ShaderStages::COMPUTE;
    let k = inputs.len() as u32;
    let mut entries: Vec<_> = (0..k).map(|b| storage_entry(b, true, cs)).collect();
    entries.push(storage_entry(k, false, cs));
    let bgl = g
        .device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: None,
            entries: &entries,
        });
    let layout = g
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: None,
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
    let pipe = compute_pipeline(g, "kernel test", &layout, &module, "main", &[], false);
    let mut bufs: Vec<wgpu::Buffer> = inputs
        .iter()
        .map(|b| {
            g.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: None,
                    contents: b,
                    usage: wgpu::BufferUsages::STORAGE,
                })
        })
        .collect();
    bufs.push(g.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: out_bytes,
        usage: bench_core::gpu_util::STORAGE_RW,
        mapped_at_creation: false,
    }));
    let refs: Vec<&wgpu::Buffer> = bufs.iter().collect();
    let bind = bind_buffers(g, "kernel test", &bgl, &refs);
    let mut enc = g.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipe);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(n.div_ceil(64), 1, 1);
    }
    g.queue.submit([enc.finish()]);
    g.read_buffer(refs[k as usize], out_bytes).unwrap()
}

/// The driver keeps f32 adds and multiplies correctly rounded and unreassociated, as the
/// double-f32 snap needs: TwoSum and TwoProd are exact on this adapter (a driver that fused,
/// reassociated or flushed them would fail here, and the snap would silently lose precision).
#[test]
fn double_f32_error_free_transformations_are_exact_on_this_adapter() {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut rnd = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    // Random signs and mantissas; exponents within ±30 of 1, and within 20 of each other in a
    // pair, so that both a + b and a · b are exact in f64.
    let mut input = Vec::new();
    for _ in 0..4096 {
        let e = (rnd() % 40 + 107) as u32;
        for d in [0, rnd() % 21] {
            let r = rnd() as u32;
            input.push(f32::from_bits(
                (r & 0x807f_ffff) | (e + d as u32 - 10) << 23,
            ));
        }
    }
    let n = input.len() / 2;
    let body = "
@group(0) @binding(0) var<storage, read> inp: array<vec2<f32>>;
@group(0) @binding(1) var<storage, read_write> outp: array<vec4<f32>>;
fn df_one() -> f32 { return f32(min(arrayLength(&inp), 1u)); }
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&inp) { return; }
    let v = inp[id.x];
    outp[2u * id.x] = vec4<f32>(two_sum(v.x, v.y), two_prod(v.x, v.y));
    outp[2u * id.x + 1u] = vec4<f32>(df_div(vec2<f32>(v.x, 0.0), vec2<f32>(v.y, 0.0)), 0.0, 0.0);
}";
    let out = run_kernel(
        body,
        &[bytemuck::cast_slice(&input)],
        n as u64 * 32,
        n as u32,
    );
    let got: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let (mut sum_bad, mut prod_bad, mut div_worst) = (0, 0, 0.0f64);
    for i in 0..n {
        let (a, b) = (input[2 * i] as f64, input[2 * i + 1] as f64);
        let [s, se, p, pe] = got[2 * i];
        sum_bad += usize::from(s as f64 + se as f64 != a + b);
        prod_bad += usize::from(p as f64 + pe as f64 != a * b);
        let q = got[2 * i + 1][0] as f64 + got[2 * i + 1][1] as f64;
        div_worst = div_worst.max(((q - a / b) / (a / b)).abs());
    }
    assert_eq!(
        (sum_bad, prod_bad),
        (0, 0),
        "of {n} pairs, inexact TwoSum, TwoProd"
    );
    assert!(
        div_worst < 1e-12,
        "double-f32 division relative error {div_worst:e}"
    );
}

/// `df_screen` on the GPU snaps every vertex of a dense scene to the reference's 1/256 px.
#[test]
fn double_f32_screen_positions_equal_the_f64_references_snapped_ones() {
    let grass = scene("grass", &[("blades", Int(10000))]);
    let (w, h) = (128u32, 96u32);
    let m = grass.camera.clip_from_world_gpu(w as f64 / h as f64);
    let mut consts: Vec<f32> = m.to_cols_array().to_vec();
    consts.extend([w as f32, h as f32, 0.0, 0.0]);
    let pos: Vec<f32> = grass.mesh.positions.iter().flatten().copied().collect();
    let n = grass.mesh.positions.len();
    let body = "
@group(0) @binding(0) var<storage, read> k: array<vec4<f32>, 5>;
@group(0) @binding(1) var<storage, read> pos: array<f32>;
@group(0) @binding(2) var<storage, read_write> outp: array<vec2<f32>>;
fn df_one() -> f32 { return sign(k[4].x); }
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&outp) { return; }
    let m = mat4x4<f32>(k[0], k[1], k[2], k[3]);
    let p = vec3<f32>(pos[3u * i], pos[3u * i + 1u], pos[3u * i + 2u]);
    outp[i] = df_screen(m, p, k[4].xy);
}";
    let out = run_kernel(
        body,
        &[bytemuck::cast_slice(&consts), bytemuck::cast_slice(&pos)],
        n as u64 * 8,
        n as u32,
    );
    let got: &[[f32; 2]] = bytemuck::cast_slice(&out);
    let md = m.as_dmat4();
    let snap = |v: f64| (v * 256.0).round() / 256.0;
    let mut bad = Vec::new();
    for (i, p) in grass.mesh.positions.iter().enumerate() {
        let c = md * Vec3::from(*p).as_dvec3().extend(1.0);
        let inv_w = 1.0 / c.w;
        let want = [
            snap((c.x * inv_w * 0.5 + 0.5) * w as f64),
            snap((0.5 - c.y * inv_w * 0.5) * h as f64),
        ];
        if [got[i][0] as f64, got[i][1] as f64] != want {
            bad.push((i, got[i], want));
        }
    }
    assert!(
        bad.is_empty(),
        "{} of {n} vertices, first {:?}",
        bad.len(),
        &bad[..bad.len().min(4)]
    );
}

/// Every fragment of 10 000 grass blades at 128², where f32 snapping put two vertices on the other
/// side of a 1/512-px rounding boundary and so two fragments beyond the reference's.
#[test]
fn snaps_vertices_as_the_f64_reference_does_on_dense_grass() {
    let grass = scene("grass", &[("blades", Int(10000))]);
    for v in VARIANTS {
        let (label, p) = variant_params(v, 256);
        let (cap, lists) = run(&ComputeAbuffer, &grass, 128, 128, &p);
        let (bad, first) = count_mismatch(&cap, &lists, u32::MAX);
        assert_eq!(bad, 0, "{label}: counts differ first at {first:?}");
    }
}

#[test]
fn full_tiles_of_big_triangles_keep_each_fragments_facing() {
    // Effects that read facing (translucency's thickness, CSG's in/out) over triangles that
    // take the shared path's full tiles: a single-sample full tile's all-samples mask once
    // landed on the tag's front-facing bit, so every back face there read as front (0.3 % of
    // pixels off by up to 0.93 here; transparency, which ignores facing, stayed exact). 256²
    // with small_max 1: two shells' back faces span whole tiles.
    let shells = scene("shells", &[("count", Int(2)), ("segments", Int(12))]);
    for (effect, extra) in [
        ("translucency", ("sigma", scenarios::ParamValue::Float(0.8))),
        ("csg_sub", ("csg_b", Int(1))),
    ] {
        for (small, capture) in [(1, "pixels"), (1 << 20, "pixels"), (1, "tiles")] {
            let p = params(&[
                ("small_max", Int(small)),
                ("capture", Str(capture.into())),
                ("effect", Str(effect.into())),
                extra.clone(),
            ]);
            let (cap, lists) = run(&ComputeAbuffer, &shells, 256, 256, &p);
            if small == 1 && capture == "pixels" {
                let [_, full, _] = tile_classes(&cap.notes);
                assert!(full > 0, "full tiles occur: {}", cap.notes);
            }
            let fx = crate::effects::EffectConfig::from_point(&crate::testing::point(
                &ComputeAbuffer,
                &p,
            ))
            .unwrap();
            let reference = fx.reference(&shells, &lists, cap.expected);
            let (worst, at) = crate::testing::max_err_vs(&cap, &reference);
            // View depth re-derived in f32 from unsnapped vertices vs the reference's snapped
            // ones (tests/effects.rs: ≤ 2e-3); a flipped facing is ≥ 0.1.
            assert!(
                worst <= 2e-3,
                "{effect} small_max {small} capture {capture}: max error {worst:.3e} at pixel {at}: {}",
                cap.notes
            );
        }
    }
}

#[test]
fn lists_in_depth_order_reverse_order_or_shuffled_sort_alike_in_workgroup_memory() {
    // The workgroup resolve inserts into a ring from the nearer end: lists that arrive front to
    // back, back to front or shuffled must all come out in depth order. 24 screen-filling
    // layers (under the 32-entry workgroup capacity) and 40 (over it: the private sort).
    for layers in [24, 40] {
        let base = scene("quads", &[("depth_complexity", Int(layers))]);
        let tris: Vec<[u32; 3]> = base
            .mesh
            .indices
            .chunks(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let mut reversed = tris.clone();
        reversed.reverse();
        // A fixed interleave of near and far: 0, n−1, 1, n−2, …
        let mut zigzag = Vec::new();
        let (mut a, mut b) = (0usize, tris.len());
        while a < b {
            zigzag.push(tris[a]);
            a += 1;
            if a < b {
                b -= 1;
                zigzag.push(tris[b]);
            }
        }
        for (label, order) in [
            ("given", &tris),
            ("reversed", &reversed),
            ("zigzag", &zigzag),
        ] {
            let mut s = base.clone();
            s.mesh.indices = order.iter().flatten().copied().collect();
            // capture = tiles: a pixel's ring fills in bin order (small_max 128: every quad is
            // binned) or from its stored fragments (1 << 20: none is); past 32 the tile resolves
            // again with per-thread arrays.
            for (small, capture) in [
                (1, "pixels"),
                (1 << 20, "pixels"),
                (128, "tiles"),
                (1 << 20, "tiles"),
            ] {
                let (_, p) = variant_params(&[("capture", capture)], small);
                check(
                    &format!("quads({layers}) {label} small_max {small} capture {capture}"),
                    &s,
                    48,
                    40,
                    &p,
                );
            }
        }
    }
}

#[test]
fn binned_triangles_decide_pixels_alike_stepped_in_i32_or_in_64_bits() {
    // capture = tiles steps a binned triangle's edges from each tile's first pixel in i32 when
    // every edge spans under FAST_SPAN units (586k px); longer ones (guard-band sizes, which no
    // small viewport reaches) test every pixel in 64 bits. With FAST_SPAN lowered to 1 unit
    // every binned triangle takes the 64-bit path here; both must equal the reference. Also a
    // triangle reaching ~5,000 px off screen (inside the guard band: not clipped).
    let mut m = Mesh::default();
    tri(
        &mut m,
        [[-0.9, -0.2, 0.0], [600.0, 0.35, 0.0], [-0.8, 0.6, 0.0]],
        [0.9, 0.4, 0.1, 0.5],
        0,
    );
    tri(
        &mut m,
        [[-0.6, -0.7, 0.5], [0.7, -0.5, 0.5], [0.0, 0.8, 0.5]],
        [0.1, 0.5, 0.9, 0.5],
        1,
    );
    tri(
        &mut m,
        [[0.6, -0.7, -0.5], [-0.7, -0.5, -0.5], [0.2, 0.9, -0.5]],
        [0.3, 0.9, 0.2, 0.5],
        2,
    );
    let s = scene_with(m, 5.0, 0.5);
    let quads = scene("quads", &[("depth_complexity", Int(6))]);
    let lists = rasterize(&s, 64, 48);
    assert!(lists.max_depth_complexity() >= 3, "the triangles overlap");
    let span = |v| FAST_SPAN.store(v, std::sync::atomic::Ordering::Relaxed);
    for fast_span in [150_000_000, 1] {
        span(fast_span);
        for sort in ["workgroup", "private"] {
            let (label, p) = variant_params(&[("capture", "tiles"), ("resolve_sort", sort)], 1);
            check(
                &format!("long edges {label} span {fast_span}"),
                &s,
                64,
                48,
                &p,
            );
            check(
                &format!("quads {label} span {fast_span}"),
                &quads,
                48,
                40,
                &p,
            );
        }
    }
    span(150_000_000);
}

#[test]
fn binned_capture_stores_an_entry_per_touched_tile_instead_of_big_triangles_fragments() {
    // 256² shells(2, 8): big triangles, hundreds of fragments each, all binned: the bins (one
    // 8 B entry per touched 8×8 tile) are far smaller than the 8 B per fragment the pixel
    // capture stores, and the offsets hold the pixels' and tiles' ends, then each pixel's count.
    let s = scene("shells", &[("count", Int(2)), ("segments", Int(8))]);
    let (w, h) = (256u32, 256u32);
    let g = gpu();
    let gs = GpuScene::upload(g, &s, w, h);
    let total = rasterize(&s, w, h).total_fragments();
    let p = params(&[("capture", Str("tiles".into()))]);
    let pt = crate::testing::point(&ComputeAbuffer, &p);
    let e = EffectConfig::from_point(&pt).unwrap();
    let prepared = PreparedAbuffer::new(g, &gs, 256, &e, variants(&pt), None).unwrap();
    let px = (w * h) as u64;
    let tiles = (w.div_ceil(BIN) * h.div_ceil(BIN)) as u64;
    let overhead =
        (px + tiles + px) * 4 + px * 16 + (COUNTERS + (px + tiles).div_ceil(SCAN_BLOCK)) * 4;
    assert_eq!(prepared.bytes_overhead().unwrap(), overhead);
    let rest = prepared.bytes_allocated() - overhead;
    assert!(
        rest < total * FRAG_BYTES / 4,
        "{rest} B beside the per-pixel part for {total} fragments"
    );
    check("shells(2, 8) 256² tiles", &s, w, h, &p);
}

#[test]
fn a_sliver_takes_its_snapped_triangles_attributes_with_attributes_snapped() {
    // A sliver thinner than a pixel across pixel (21, 21)'s centre, its corners where an ogre
    // scan's had them at 512² (the same fractions of a pixel): snapping to 1/256 px moves them by
    // a fair share of its width, so the snapped screen triangle's barycentrics at the centre
    // (the reference's, a hardware rasteriser's) are far from the unsnapped clip-space triangle's
    // (0.34, 0.41, 0.25 against 0.20, 0.71, 0.09 on the ogre). Red, green and blue corners at
    // three depths make both the weights and their perspective correction show in the colour.
    let (w, h) = (64u32, 64u32);
    let at = |sx: f64, sy: f64, z: f64| -> [f32; 3] {
        let half = (5.0 - z) * 30f64.to_radians().tan();
        let x = (sx / (w as f64 / 2.0) - 1.0) * half;
        let y = (1.0 - sy / (h as f64 / 2.0)) * half;
        [x as f32, y as f32, z as f32]
    };
    let mut m = Mesh::default();
    let corners = [
        (at(20.80171, 20.98571, 0.0), [1.0, 0.0, 0.0, 0.5]),
        (at(21.60347, 21.57705, 0.5), [0.0, 1.0, 0.0, 0.5]),
        (at(22.31393, 22.09241, 1.0), [0.0, 0.0, 1.0, 0.5]),
    ];
    for (p, c) in corners {
        m.positions.push(p);
        m.normals.push([0.0, 0.0, 1.0]);
        m.colors.push(c);
        m.object_ids.push(0);
    }
    m.indices.extend_from_slice(&[0, 1, 2]);
    let s = scene_with(m, 5.0, 0.5);
    for capture in ["pixels", "tiles"] {
        let (_, snapped) = variant_params(&[("attributes", "snapped"), ("capture", capture)], 1);
        check(
            &format!("sliver, attributes snapped, capture {capture}"),
            &s,
            w,
            h,
            &snapped,
        );
        // The scene bites: the clip-space weights miss the reference at the sliver's pixel.
        let (_, clip) = variant_params(&[("capture", capture)], 1);
        let (cap, lists) = run(&ComputeAbuffer, &s, w, h, &clip);
        assert_eq!(
            lists.total_fragments(),
            1,
            "the sliver covers one pixel centre"
        );
        let (e, at) = max_err(&cap, &lists);
        assert!(
            e > 1e-2,
            "attributes clip, capture {capture}: error {e} at {at}"
        );
    }
}

#[test]
fn capture_auto_takes_tiles_from_three_binned_fragments_a_pixel_and_stays_exact() {
    // Every quad is bigger than small_max 16 at 64×64, so every fragment is a binned one; the
    // census counts them per pixel of the image (quads cover about a third of it).
    for (dc, want) in [(4, "pixels"), (16, "tiles")] {
        let quads = scene("quads", &[("depth_complexity", Int(dc))]);
        let p = params(&[("small_max", Int(16)), ("capture", Str("auto".into()))]);
        let (cap, lists) = run(&ComputeAbuffer, &quads, 64, 64, &p);
        let at = cap
            .notes
            .find("capture auto: ")
            .unwrap_or_else(|| panic!("quads({dc}): no choice in the notes: {}", cap.notes));
        let said = &cap.notes[at + 14..];
        let per_px: f64 = said
            .split(['(', ' '])
            .find_map(|w| w.parse().ok())
            .expect("the count in the note");
        assert!(said.starts_with(want), "quads({dc}): {said}");
        assert_eq!(
            per_px >= AUTO_BINNED_PER_PIXEL,
            want == "tiles",
            "quads({dc}): {per_px} a pixel: {said}"
        );
        let (e, at) = max_err(&cap, &lists);
        assert!(e <= IMAGE_TOL, "quads({dc}) auto: error {e} at pixel {at}");
    }
}
