//! Tests of the geometry study: exact invariants of batching and strips on the CPU, the
//! quantisation bounds of every format, and on lavapipe every format/layout/order rendered by
//! the GPU against the f64 CPU reference of the CPU-decoded vertices (and a wrong decode caught).

use std::collections::HashMap;

use scenarios::{ParamValue, Params, Scene, SceneSpec};

use super::prep::*;
use super::*;
use bench_core::gpu::GpuOptions;
use mfx_reference::rasterize;

fn mesh_scene(triangles: i64, shape: &str) -> Scene {
    SceneSpec::new(
        "mesh",
        Params::new()
            .with("triangles", ParamValue::Int(triangles))
            .with("shape", ParamValue::Str(shape.into())),
    )
    .build()
    .expect("mesh scene builds")
}

fn sorted_canonical(tris: impl IntoIterator<Item = [u32; 3]>) -> Vec<[u32; 3]> {
    let mut v: Vec<[u32; 3]> = tris.into_iter().map(canonical).collect();
    v.sort_unstable();
    v
}

fn original_triangles(mesh: &Mesh) -> Vec<[u32; 3]> {
    sorted_canonical(mesh.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]))
}

fn spec_with(pairs: &[(&str, ParamValue)]) -> FeedSpec {
    let mut p = Params::new();
    for (k, v) in pairs {
        p.set(k, v.clone());
    }
    FeedSpec::from_point(&bench_core::axes::Point::resolve(AXES, &p).expect("valid point"))
}

fn s(v: &str) -> ParamValue {
    ParamValue::Str(v.into())
}
fn i(v: i64) -> ParamValue {
    ParamValue::Int(v)
}

/// mesh(150k triangles, > 65,536 vertices): 16-bit batching keeps every triangle exactly once,
/// every batch within 65,536 vertices, every local index inside its batch.
#[test]
fn uint16_batching_keeps_every_triangle_exactly_once_mesh_150k() {
    let scene = mesh_scene(150_000, "sphere");
    let mesh = &scene.mesh;
    assert!(
        mesh.vertex_count() > 65_536,
        "the test needs more vertices than 16 bits index"
    );
    let want = original_triangles(mesh);
    for order in [
        MeshOrder::Original,
        MeshOrder::Shuffled,
        MeshOrder::VcacheVfetch,
    ] {
        let ordered = order_mesh(mesh, order);
        for batch_size in [0usize, 1000, 7] {
            let spec = BatchSpec {
                batch_size,
                draw_triangles: 0,
                index_format: IndexFormat::Uint16,
                primitive: Primitive::List,
                indexed: true,
            };
            let b = batch(mesh, &ordered, &spec);
            for bt in &b.batches {
                assert!(
                    bt.vertex_count <= 65_536,
                    "{order:?}/{batch_size}: batch of {} vertices",
                    bt.vertex_count
                );
                if batch_size > 0 {
                    assert!(bt.triangles as usize <= batch_size);
                }
                let idx =
                    &b.indices[bt.first_index as usize..(bt.first_index + bt.index_count) as usize];
                assert!(idx.iter().all(|&l| l < bt.vertex_count));
            }
            if batch_size == 0 {
                assert!(
                    b.batches.len() >= 2,
                    "75k vertices cannot fit one 16-bit batch"
                );
            }
            let got = sorted_canonical(source_triangles(&b, 0xFFFF, Primitive::List));
            assert_eq!(
                got.len(),
                want.len(),
                "{order:?}/{batch_size}: triangle count"
            );
            assert!(
                got == want,
                "{order:?}/{batch_size}: triangle multiset differs"
            );
        }
    }
    // Non-indexed batches: each corner its own vertex, same triangles.
    let ordered = order_mesh(mesh, MeshOrder::Original);
    let b = batch(
        mesh,
        &ordered,
        &BatchSpec {
            batch_size: 999,
            draw_triangles: 0,
            index_format: IndexFormat::Uint16,
            primitive: Primitive::List,
            indexed: false,
        },
    );
    let got = sorted_canonical(b.verts.chunks_exact(3).map(|t| [t[0], t[1], t[2]]));
    assert!(
        got == want,
        "non-indexed batching lost or changed triangles"
    );
}

/// mesh(6k triangles): meshopt strips with primitive restart, per batch, unroll to exactly the
/// list's triangles (as a multiset, winding kept), for both restart values.
#[test]
fn strips_with_restart_reproduce_the_list_triangles_mesh_6k() {
    let scene = mesh_scene(6_000, "grid");
    let mesh = &scene.mesh;
    let want = original_triangles(mesh);
    for order in [MeshOrder::Original, MeshOrder::Vcache, MeshOrder::Shuffled] {
        let ordered = order_mesh(mesh, order);
        for fmt in [IndexFormat::Uint16, IndexFormat::Uint32] {
            for batch_size in [0usize, 333] {
                let spec = BatchSpec {
                    batch_size,
                    draw_triangles: 0,
                    index_format: fmt,
                    primitive: Primitive::Strip,
                    indexed: true,
                };
                let b = batch(mesh, &ordered, &spec);
                let got = sorted_canonical(source_triangles(&b, fmt.restart(), Primitive::Strip));
                assert!(
                    got == want,
                    "{order:?}/{fmt:?}/{batch_size}: strips differ from the list"
                );
                if order == MeshOrder::Vcache && batch_size == 0 {
                    // A cache-optimised grid strips well: fewer indices than the list's 3 per triangle.
                    assert!(
                        b.indices.len() < 3 * want.len(),
                        "strips are no shorter than the list"
                    );
                }
            }
        }
    }
}

/// Every format of every attribute decodes within the derived bound: half a quantisation step
/// (× 2 for remapped signed values in unorm formats, × the half extent for box-quantised
/// positions), plus f32 rounding of the box arithmetic.
#[test]
fn every_format_decodes_within_half_a_quantisation_step() {
    let scene = mesh_scene(3_000, "sphere");
    let mesh = &scene.mesh;
    let ordered = order_mesh(mesh, MeshOrder::Original);
    let kinds = [
        AttrKind::Position,
        AttrKind::Normal,
        AttrKind::Color,
        AttrKind::Texcoord,
        AttrKind::Extra(2),
    ];
    for kind in kinds {
        for name in kind.allowed() {
            let fmt = format_by_name(name).expect("allowed formats are known");
            let formats = FeedFormats {
                position: if kind == AttrKind::Position {
                    fmt
                } else {
                    format_by_name("float32x3").unwrap()
                },
                normal: (kind == AttrKind::Normal).then_some(fmt),
                color: (kind == AttrKind::Color).then_some(fmt),
                texcoord: (kind == AttrKind::Texcoord).then_some(fmt),
                extra_attributes: if matches!(kind, AttrKind::Extra(_)) {
                    3
                } else {
                    0
                },
                layout: Layout::Interleaved,
            };
            let spec = BatchSpec {
                batch_size: 500,
                draw_triangles: 0,
                index_format: IndexFormat::Uint32,
                primitive: Primitive::List,
                indexed: true,
            };
            let b = batch(mesh, &ordered, &spec);
            let streams = encode_streams(mesh, &b, &formats);
            let slots = formats.slots();
            let si = slots
                .iter()
                .position(|s| s.kind == kind)
                .expect("slot present");
            let mut worst = 0.0f64;
            for bt in &b.batches {
                for vi in bt.first_vertex as usize..(bt.first_vertex + bt.vertex_count) as usize {
                    let got = decode_slot(&streams, &slots[si], si, bt, vi);
                    let want = natural(kind, mesh, b.verts[vi]);
                    let stored_comps = fmt.comps as usize;
                    let natural_comps = match kind {
                        AttrKind::Position | AttrKind::Normal => 3,
                        AttrKind::Texcoord => 2,
                        _ => 4,
                    };
                    for c in 0..natural_comps {
                        let err = (got[c] as f64 - want[c] as f64).abs();
                        let bound = if c >= stored_comps {
                            // A dropped component (float32x3 colour: alpha) decodes as 0.
                            want[c].abs() as f64
                        } else {
                            let scale = if kind == AttrKind::Position && position_quantised(fmt) {
                                bt.half[c] as f64
                            } else if remapped(kind, fmt) {
                                2.0
                            } else {
                                1.0
                            };
                            // f32 rounding of the decode arithmetic: a few ulps of |value| ≤ 2.
                            quantisation_step(fmt, c) * scale + 4.0 * f32::EPSILON as f64 * 2.0
                        };
                        assert!(
                            err <= bound,
                            "{} in {name}: component {c} of vertex {vi}: |{} − {}| = {err:e} > {bound:e}",
                            kind.name(),
                            got[c],
                            want[c]
                        );
                        worst = worst.max(err);
                    }
                }
            }
            if fmt.enc != Enc::F32 {
                assert!(
                    worst > 0.0,
                    "{name}: a quantised format showed no error at all (not encoded?)"
                );
            }
        }
    }
}

fn gpu() -> Gpu {
    Gpu::new(&GpuOptions::default()).expect("a Vulkan adapter (lavapipe on CI: scripts/setup.sh)")
}

/// How a GPU check image compares with the CPU reference of the decoded vertices.
#[derive(Debug)]
struct Comparison {
    value_tol: f64,
    pixels: usize,
    covered: usize,
    coverage_mismatch: usize,
    value_bad: usize,
    max_value_err: f64,
    max_depth_err: f64,
}

/// Value tolerance: llvmpipe evaluates attribute plane equations in f32 from the tile origin,
/// so the check value (magnitude ≤ ~3) differs from the f64 reference by up to 5.1e-4 on these
/// scenes (measured, 60 combinations); 1e-3 is a quarter of an 8-bit step (3.9e-3), so a decode
/// that is wrong by a quarter of the coarsest format's step or more cannot pass.
const VALUE_TOL: f64 = 1e-3;
/// Window depth from the same f32 clip coordinates: measured ≤ 5.7e-6 (f32 plane equations);
/// 1e-5 is under twice that; the wrong position decode below moves whole triangles off their pixels.
const DEPTH_TOL: f64 = 1e-5;

impl Comparison {
    /// Edge pixels may flip where an f32 decode on the GPU and on the CPU differ by an ulp
    /// across a sub-pixel snap boundary: allow 0.5% of pixels either way, nothing more.
    fn passes(&self) -> bool {
        let allowed = (self.pixels as f64 * 0.005).ceil() as usize;
        self.coverage_mismatch <= allowed
            && self.value_bad <= allowed
            && self.covered > self.pixels / 10
    }
}

const W: u32 = 64;
const H: u32 = 64;

fn render_and_compare(
    gpu: &Gpu,
    scene: &Scene,
    ordered: &Ordered,
    spec: &FeedSpec,
    wrong: Option<WrongDecode>,
) -> Comparison {
    render_and_compare_to(gpu, scene, ordered, spec, wrong, Twin::Decoded)
}

/// What the CPU twin's non-position attributes are.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Twin {
    /// The stored bytes decoded as the GPU should: the comparison allows only f32 noise.
    Decoded,
    /// The mesh's own f32 values (the Float32 reference): the comparison allows f32 noise plus
    /// the derived quantisation bound of the check value.
    Float32,
}

/// Derived bound of |check(decoded) − check(float32)| at any vertex, hence (barycentric
/// interpolation is a convex combination) at any covered pixel of the same triangles: per slot
/// k, w_k · (e_c + e_w · |m_c|) with e the per-component decode bound of
/// `every_format_decodes_within_half_a_quantisation_step` (a dropped component: its value).
fn check_bound(mesh: &Mesh, b: &Batched, formats: &FeedFormats) -> f64 {
    let slots = formats.slots();
    let mut worst = 0.0f64;
    for bt in &b.batches {
        for vi in bt.first_vertex as usize..(bt.first_vertex + bt.vertex_count) as usize {
            let mut acc = [0.0f64; 3];
            for (k, sl) in slots.iter().skip(1).enumerate() {
                let (w, m) = check_coeffs(k);
                let nat = natural(sl.kind, mesh, b.verts[vi]);
                let e = |c: usize| {
                    if c >= sl.format.comps as usize {
                        nat[c].abs() as f64
                    } else {
                        let scale = if remapped(sl.kind, sl.format) {
                            2.0
                        } else {
                            1.0
                        };
                        quantisation_step(sl.format, c) * scale + 8.0 * f32::EPSILON as f64
                    }
                };
                for (c, a) in acc.iter_mut().enumerate() {
                    *a += w as f64 * (e(c) + e(3) * m[c].abs() as f64);
                }
            }
            worst = acc.iter().copied().fold(worst, f64::max);
        }
    }
    worst
}

fn render_and_compare_to(
    gpu: &Gpu,
    scene: &Scene,
    ordered: &Ordered,
    spec: &FeedSpec,
    wrong: Option<WrongDecode>,
    twin_kind: Twin,
) -> Comparison {
    let feed = prepare_feed(&scene.mesh, ordered, spec);
    let gscene = GpuScene::upload(gpu, scene, W, H);
    let image = scoped(gpu, "check render", || {
        let fg = FeedGpu::new(
            gpu,
            &gscene,
            spec,
            &feed.batched,
            &feed.streams,
            Mode::Check,
            &[(W, H)],
            wrong,
        );
        fg.frame(gpu, 0, None, false);
        fg.read_check(gpu, 0)
    })
    .unwrap_or_else(|e| panic!("{spec:?}: {e}"));

    // The CPU twin: decode every vertex as the GPU should, rasterize in f64.
    let b = &feed.batched;
    let slots = spec.formats.slots();
    let mut twin = Mesh::default();
    for bt in &b.batches {
        for vi in bt.first_vertex as usize..(bt.first_vertex + bt.vertex_count) as usize {
            let p = decode_slot(&feed.streams, &slots[0], 0, bt, vi);
            let others: Vec<[f32; 4]> = (1..slots.len())
                .map(|si| match twin_kind {
                    Twin::Decoded => decode_slot(&feed.streams, &slots[si], si, bt, vi),
                    Twin::Float32 => natural(slots[si].kind, &scene.mesh, b.verts[vi]),
                })
                .collect();
            let cv = check_value(&others);
            twin.positions.push([p[0], p[1], p[2]]);
            twin.normals.push([0.0, 0.0, 1.0]);
            twin.colors.push([cv[0], cv[1], cv[2], 1.0]);
            twin.object_ids.push(0);
        }
        if spec.batch.indexed {
            let idx =
                &b.indices[bt.first_index as usize..(bt.first_index + bt.index_count) as usize];
            let list = match spec.batch.primitive {
                Primitive::List => idx.to_vec(),
                Primitive::Strip => {
                    meshopt::unstripify(idx, spec.batch.index_format.restart()).unwrap()
                }
            };
            twin.indices
                .extend(list.iter().map(|&l| l + bt.first_vertex));
        } else {
            twin.indices
                .extend(bt.first_vertex..bt.first_vertex + bt.vertex_count);
        }
    }
    let twin_scene = Scene::new(scene.spec.clone(), twin, scene.camera.clone());
    let lists = rasterize(&twin_scene, W, H);
    let value_tol = match twin_kind {
        Twin::Decoded => VALUE_TOL,
        Twin::Float32 => VALUE_TOL + check_bound(&scene.mesh, b, &spec.formats),
    };
    let mut c = Comparison {
        value_tol,
        pixels: (W * H) as usize,
        covered: 0,
        coverage_mismatch: 0,
        value_bad: 0,
        max_value_err: 0.0,
        max_depth_err: 0.0,
    };
    for (p, px) in image.iter().enumerate() {
        let gpu_covered = px[3] >= 0.0;
        let reference = lists.pixel(p).first();
        match (gpu_covered, reference) {
            (true, Some(f)) => {
                c.covered += 1;
                let ve = (0..3)
                    .map(|k| (px[k] as f64 - f.color[k]).abs())
                    .fold(0.0, f64::max);
                let de = (px[3] as f64 - f.depth).abs();
                if ve > c.value_tol || de > DEPTH_TOL {
                    c.value_bad += 1;
                }
                c.max_value_err = c.max_value_err.max(ve);
                c.max_depth_err = c.max_depth_err.max(de);
            }
            (false, None) => {}
            _ => c.coverage_mismatch += 1,
        }
    }
    c
}

/// The points the GPU test renders: each attribute in each of its formats, both layouts, 0–8
/// extra attributes, both index formats × list/strip × batch sizes, every mesh order, and
/// non-indexed draws.
fn combinations() -> Vec<Vec<(&'static str, ParamValue)>> {
    let mut v: Vec<Vec<(&str, ParamValue)>> = Vec::new();
    let base = || {
        vec![
            ("normal_format", s("float32x3")),
            ("color_format", s("unorm8x4")),
            ("texcoord_format", s("float32x2")),
            ("extra_attributes", i(1)),
        ]
    };
    for pos in AttrKind::Position.allowed() {
        for layout in ["interleaved", "separate"] {
            for batch_size in [0, 97] {
                let mut p = base();
                p.extend([
                    ("vertex_format", s(pos)),
                    ("layout", s(layout)),
                    ("batch_size", i(batch_size)),
                ]);
                v.push(p);
            }
        }
    }
    for (axis, kind) in [
        ("normal_format", AttrKind::Normal),
        ("color_format", AttrKind::Color),
        ("texcoord_format", AttrKind::Texcoord),
    ] {
        for f in kind.allowed().iter().chain(&["none"]) {
            let mut p: Vec<(&str, ParamValue)> =
                base().into_iter().filter(|(k, _)| *k != axis).collect();
            p.extend([
                (axis, s(f)),
                ("layout", s("interleaved")),
                ("vertex_format", s("snorm16x4")),
            ]);
            v.push(p);
        }
    }
    for extras in [0, 4, 8] {
        for layout in ["interleaved", "separate"] {
            v.push(vec![("extra_attributes", i(extras)), ("layout", s(layout))]);
        }
    }
    for order in MESH_ORDERS {
        for index_format in ["uint16", "uint32"] {
            for primitive in ["list", "strip"] {
                for batch_size in [0, 150] {
                    v.push(vec![
                        ("mesh_order", s(order)),
                        ("index_format", s(index_format)),
                        ("primitive", s(primitive)),
                        ("batch_size", i(batch_size)),
                    ]);
                }
            }
        }
    }
    for batch_size in [0, 150] {
        v.push(vec![
            ("indexed", ParamValue::Bool(false)),
            ("batch_size", i(batch_size)),
            ("vertex_format", s("float16x4")),
        ]);
    }
    v.push(vec![
        ("draw_triangles", i(500)),
        ("vertex_format", s("snorm16x4")),
    ]);
    v
}

/// mesh(1200-triangle bumpy sphere) at 64×64 on lavapipe: every format/layout/order/batching
/// renders, fragment for fragment, what the CPU twin's decoded vertices give the f64 reference
/// (depth within 1e-5, attributes within 1e-3; ≤ 0.5% edge pixels may flip). With the
/// quantisation bounds above this makes each image the Float32 image within quantisation error.
#[test]
fn every_format_and_layout_matches_the_cpu_reference_mesh_1200_at_64px() {
    let gpu = gpu();
    let scene = mesh_scene(1_200, "grid");
    let mut orders: HashMap<MeshOrder, Ordered> = HashMap::new();
    let mut failures = Vec::new();
    for combo in combinations() {
        let spec = spec_with(&combo);
        if let Some(why) = spec.unsupported(&gpu, &scene.mesh) {
            panic!("{combo:?} unsupported on the test adapter: {why}");
        }
        let ordered = orders
            .entry(spec.order)
            .or_insert_with(|| order_mesh(&scene.mesh, spec.order));
        let c = render_and_compare(&gpu, &scene, ordered, &spec, None);
        if !c.passes() {
            failures.push(format!("{combo:?}: {c:?}"));
        }
    }
    assert!(
        failures.is_empty(),
        "{} combinations differ from the CPU reference:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// mesh(1200) at 64×64: every normal, colour and texcoord format (beside float32x4 extras), in both
/// layouts, renders the Float32 image: each GPU image against the f64 reference of the mesh's own
/// f32 attribute values, within f32 noise plus the format's derived quantisation bound of the
/// check value (positions stay float32 here, so coverage and depth must match as tightly as in
/// the test above; quantised positions are covered by that test and the CPU decode bound).
/// The bound is reported; an unremapped unorm normal (error ≈ 1) is far outside every one.
#[test]
fn every_attribute_format_renders_the_float32_image_within_its_quantisation_bound() {
    let gpu = gpu();
    let scene = mesh_scene(1_200, "grid");
    let ordered = order_mesh(&scene.mesh, MeshOrder::Original);
    let mut failures = Vec::new();
    for (axis, kind) in [
        ("normal_format", AttrKind::Normal),
        ("color_format", AttrKind::Color),
        ("texcoord_format", AttrKind::Texcoord),
    ] {
        for f in kind.allowed() {
            for layout in ["interleaved", "separate"] {
                let spec = spec_with(&[
                    (axis, s(f)),
                    ("layout", s(layout)),
                    (
                        "extra_attributes",
                        i(if axis == "normal_format" { 2 } else { 0 }),
                    ),
                ]);
                let c = render_and_compare_to(&gpu, &scene, &ordered, &spec, None, Twin::Float32);
                eprintln!(
                    "{axis} {f} {layout}: tol {:.2e}, max err {:.2e}",
                    c.value_tol, c.max_value_err
                );
                if !c.passes() {
                    failures.push(format!("{axis} = {f}, {layout}: {c:?}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The bound is not vacuous: the wrong normal decode breaks it.
    let nrm = spec_with(&[("normal_format", s("unorm8x4"))]);
    let wrong = render_and_compare_to(
        &gpu,
        &scene,
        &ordered,
        &nrm,
        Some(WrongDecode::NormalWithoutRemap),
        Twin::Float32,
    );
    assert!(!wrong.passes(), "{wrong:?}");
}

/// The same comparison fails for deliberately wrong decodes: positions read with the unorm
/// convention, and a unorm8 normal used without its ·2 − 1 remap. So the tolerances above are
/// tight enough that a wrong decode cannot pass.
#[test]
fn a_wrong_decode_fails_the_comparison_mesh_1200_at_64px() {
    let gpu = gpu();
    let scene = mesh_scene(1_200, "grid");
    let ordered = order_mesh(&scene.mesh, MeshOrder::Original);
    let pos = spec_with(&[("vertex_format", s("snorm16x4")), ("batch_size", i(97))]);
    let right = render_and_compare(&gpu, &scene, &ordered, &pos, None);
    assert!(right.passes(), "the right decode must pass: {right:?}");
    let wrong = render_and_compare(
        &gpu,
        &scene,
        &ordered,
        &pos,
        Some(WrongDecode::PositionUnormConvention),
    );
    assert!(
        !wrong.passes(),
        "a unorm-convention position decode passed: {wrong:?}"
    );
    eprintln!("wrong position decode: {wrong:?}");
    let nrm = spec_with(&[("normal_format", s("unorm8x4"))]);
    let right = render_and_compare(&gpu, &scene, &ordered, &nrm, None);
    assert!(
        right.passes(),
        "the right normal decode must pass: {right:?}"
    );
    let wrong = render_and_compare(
        &gpu,
        &scene,
        &ordered,
        &nrm,
        Some(WrongDecode::NormalWithoutRemap),
    );
    assert!(
        !wrong.passes(),
        "a normal decode without its remap passed: {wrong:?}"
    );
    eprintln!("wrong normal decode: {wrong:?}");
}
