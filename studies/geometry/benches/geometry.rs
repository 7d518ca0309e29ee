//! CPU cost of geometry feeding that a user pays before the GPU sees a vertex: meshopt
//! reordering, batching (16-bit batches, strips) and quantised vertex encoding. Throughput is
//! in triangles (or vertices) per second, so criterion reports the time per million directly.
//!
//! `cargo bench -p bench-core --bench geometry` (MFX_BENCH_TRIANGLES sets the mesh size,
//! default 1,000,000).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mfx_geometry::prep::{
    batch, encode_streams, format_by_name, order_mesh, BatchSpec, FeedFormats, IndexFormat, Layout,
    MeshOrder, Primitive,
};
use scenarios::{ParamValue, Params, SceneSpec};

fn triangles() -> i64 {
    std::env::var("MFX_BENCH_TRIANGLES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000)
}

fn geometry(c: &mut Criterion) {
    let scene = SceneSpec::new(
        "mesh",
        Params::new().with("triangles", ParamValue::Int(triangles())),
    )
    .build()
    .expect("mesh scene");
    let mesh = &scene.mesh;
    let tris = mesh.triangle_count() as u64;

    let mut g = c.benchmark_group("order");
    g.sample_size(10).throughput(Throughput::Elements(tris));
    for (name, order) in [
        ("shuffled", MeshOrder::Shuffled),
        ("vcache", MeshOrder::Vcache),
        ("vcache_vfetch", MeshOrder::VcacheVfetch),
    ] {
        g.bench_function(name, |b| b.iter(|| black_box(order_mesh(mesh, order))));
    }
    g.finish();

    let ordered = order_mesh(mesh, MeshOrder::Vcache);
    let mut g = c.benchmark_group("batch");
    g.sample_size(10).throughput(Throughput::Elements(tris));
    for (name, batch_size, index_format, primitive) in [
        ("uint32_whole", 0, IndexFormat::Uint32, Primitive::List),
        ("uint16_64k", 65_536, IndexFormat::Uint16, Primitive::List),
        ("uint32_256", 256, IndexFormat::Uint32, Primitive::List),
        (
            "uint16_64k_strips",
            65_536,
            IndexFormat::Uint16,
            Primitive::Strip,
        ),
    ] {
        let spec = BatchSpec {
            batch_size,
            draw_triangles: 0,
            index_format,
            primitive,
            indexed: true,
        };
        g.bench_function(name, |b| b.iter(|| black_box(batch(mesh, &ordered, &spec))));
    }
    g.finish();

    let batched = batch(
        mesh,
        &ordered,
        &BatchSpec {
            batch_size: 65_536,
            draw_triangles: 0,
            index_format: IndexFormat::Uint16,
            primitive: Primitive::List,
            indexed: true,
        },
    );
    let mut g = c.benchmark_group("encode");
    g.sample_size(10)
        .throughput(Throughput::Elements(batched.verts.len() as u64));
    let f = |n: &str| format_by_name(n).expect("known format");
    for (name, position, normal, layout) in [
        (
            "float32_separate",
            "float32x3",
            "float32x3",
            Layout::Separate,
        ),
        (
            "snorm16_snorm8_interleaved",
            "snorm16x4",
            "snorm8x4",
            Layout::Interleaved,
        ),
        (
            "float16_1010102_interleaved",
            "float16x4",
            "unorm10_10_10_2",
            Layout::Interleaved,
        ),
    ] {
        let formats = FeedFormats {
            position: f(position),
            normal: Some(f(normal)),
            color: Some(f("unorm8x4")),
            texcoord: None,
            extra_attributes: 0,
            layout,
        };
        g.bench_function(name, |b| {
            b.iter(|| black_box(encode_streams(mesh, &batched, &formats)))
        });
    }
    g.finish();
}

criterion_group!(benches, geometry);
criterion_main!(benches);
