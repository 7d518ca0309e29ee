//! The `geometry` study: how fast the GPU takes in geometry (Bavoil 2007, ch. 3, on today's
//! GPUs through wgpu). Every point draws the scene's triangles with a constant-colour fragment
//! shader and the depth test on, through a vertex shader that touches every attribute, and
//! sweeps how the geometry is fed:
//!
//! | axis               | values                                                                 |
//! |--------------------|------------------------------------------------------------------------|
//! | `batch_size`       | triangles per draw call (0 = whole mesh), at a fixed total             |
//! | `draw_triangles`   | triangles drawn (a prefix of the ordered mesh; 0 = all): the throughput curve |
//! | `vertex_format`    | position: float32x3, float16x4, snorm16x4 (quantised to the batch's box) |
//! | `normal_format`    | float32x3/x4, float16x4, snorm16x4, snorm8x4, unorm8x4, unorm10_10_10_2, none |
//! | `color_format`     | float32x4/x3, float16x4, unorm16x4, snorm16x4, unorm8x4, snorm8x4, unorm10_10_10_2, none |
//! | `texcoord_format`  | float32x2/x3, float16x2, snorm16x2, unorm16x2, none                    |
//! | `layout`           | interleaved (one buffer) or separate (one buffer per attribute)        |
//! | `extra_attributes` | 0…8 extra float32x4 attributes (the thesis's Fig. 3.3)                  |
//! | `index_format`     | uint16 (batches of ≤ 65,536 vertices, built) or uint32                 |
//! | `mesh_order`       | original, shuffled, vcache, vcache_vfetch (meshopt)                     |
//! | `indexed`          | true, false (every corner its own vertex)                              |
//! | `primitive`        | list, strip (meshopt stripify + primitive restart; indexed only)       |
//!
//! Each row records triangles/s and vertices/s, meshopt's ACMR/ATVR of the exact index stream
//! drawn, the measured vertex-shader invocations (pipeline statistics, where the adapter has
//! them) and so the post-transform cache hit rate, and the time at a small viewport over the
//! time at the suite's, which is ≈ 1 when the raster stage is not the bottleneck (the thesis's
//! check). Study options in the `[[study]]` table: `raster_check = true|false` (default true),
//! `small_viewport_divisor = N` (default 8).

pub mod prep;
#[cfg(test)]
mod tests;

use bench_core::gpu_util::{camera_entry, clear_depth, depth_state, shader};
use std::collections::HashMap;

use scenarios::Mesh;
use wgpu::util::DeviceExt;

use self::prep::{
    AttrFormat, AttrKind, BatchSpec, Batched, FeedFormats, IndexFormat, Layout, MeshOrder, Ordered,
    Primitive, Streams,
};
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, GpuScene};
use bench_core::study::{Emit, GroupCtx, Methods, Opt, Study, StudyKind};

use bench_core::measure::{measure_timed, set_timing, Measured};
use bench_core::record::cols;
use bench_core::record::Row;
use bench_core::record::{error_row, one_line, set_params, skipped_row};
use bench_core::timed::{FrameStats, Timed};
use bench_core::timing::GpuTimer;
use bench_core::Result;

const WGSL: &str = include_str!("geometry.wgsl");

const BATCH_SIZE: Axis = Axis::int(
    cols::BATCH_SIZE,
    "triangles per draw call (0 = the whole mesh)",
    0,
    0,
    i32::MAX as i64,
);
const DRAW_TRIANGLES: Axis = Axis::int(
    cols::DRAW_TRIANGLES,
    "triangles drawn, a prefix of the ordered mesh (0 = all)",
    0,
    0,
    i32::MAX as i64,
);
const VERTEX_FORMAT: Axis = Axis::choice(
    cols::VERTEX_FORMAT,
    "position format",
    "float32x3",
    &["float32x3", "float16x4", "snorm16x4"],
);
const NORMAL_FORMAT: Axis = Axis::choice(
    cols::NORMAL_FORMAT,
    "normal format, or none",
    "float32x3",
    &[
        "float32x3",
        "float32x4",
        "float16x4",
        "snorm16x4",
        "snorm8x4",
        "unorm8x4",
        "unorm10_10_10_2",
        "none",
    ],
);
const COLOR_FORMAT: Axis = Axis::choice(
    cols::COLOR_FORMAT,
    "colour format, or none",
    "none",
    &[
        "float32x4",
        "float32x3",
        "float16x4",
        "unorm16x4",
        "snorm16x4",
        "unorm8x4",
        "snorm8x4",
        "unorm10_10_10_2",
        "none",
    ],
);
const TEXCOORD_FORMAT: Axis = Axis::choice(
    cols::TEXCOORD_FORMAT,
    "texture-coordinate format, or none",
    "none",
    &[
        "float32x2",
        "float32x3",
        "float16x2",
        "snorm16x2",
        "unorm16x2",
        "none",
    ],
);
const LAYOUT: Axis = Axis::choice(
    cols::LAYOUT,
    "one interleaved vertex buffer or one per attribute",
    "separate",
    &["interleaved", "separate"],
);
const EXTRA_ATTRIBUTES: Axis = Axis::int(
    cols::EXTRA_ATTRIBUTES,
    "extra float32x4 attributes per vertex",
    0,
    0,
    8,
);
const INDEX_FORMAT: Axis = Axis::choice(
    cols::INDEX_FORMAT,
    "index precision",
    "uint32",
    &["uint16", "uint32"],
);
const MESH_ORDER: Axis = Axis::choice(
    cols::MESH_ORDER,
    "triangle order",
    "original",
    prep::MESH_ORDERS,
);
const INDEXED: Axis = Axis::bool(
    cols::INDEXED,
    "indexed draws (false: one vertex per triangle corner)",
    true,
);
const PRIMITIVE: Axis = Axis::choice(
    cols::PRIMITIVE,
    "triangle list, or strips with primitive restart",
    "list",
    &["list", "strip"],
);

/// The axes of a geometry point, declared.
pub const AXES: &[Axis] = &[
    BATCH_SIZE,
    DRAW_TRIANGLES,
    VERTEX_FORMAT,
    NORMAL_FORMAT,
    COLOR_FORMAT,
    TEXCOORD_FORMAT,
    LAYOUT,
    EXTRA_ATTRIBUTES,
    INDEX_FORMAT,
    MESH_ORDER,
    INDEXED,
    PRIMITIVE,
];

const RASTER_CHECK: Opt = Opt {
    name: "raster_check",
    doc: "also time each point at a small viewport (raster-bound check)",
    kind: scenarios::ValueKind::Bool { default: true },
};
const SMALL_VIEWPORT_DIVISOR: Opt = Opt {
    name: "small_viewport_divisor",
    doc: "the small viewport is the suite's resolution divided by this",
    kind: scenarios::ValueKind::Int {
        default: 8,
        min: 2,
        max: 1024,
    },
};

/// One point, parsed.
#[derive(Clone, Debug)]
pub struct FeedSpec {
    pub formats: FeedFormats,
    pub batch: BatchSpec,
    pub order: MeshOrder,
}

fn format(point: &Point, axis: &Axis) -> Option<AttrFormat> {
    prep::format_by_name(&point.choice(axis))
}

impl FeedSpec {
    /// Reads a resolved point's axes through their declarations.
    pub fn from_point(p: &Point) -> FeedSpec {
        let position = format(p, &VERTEX_FORMAT).expect("positions always have a format");
        let normal = format(p, &NORMAL_FORMAT);
        let color = format(p, &COLOR_FORMAT);
        let texcoord = format(p, &TEXCOORD_FORMAT);
        let layout = match p.choice(&LAYOUT).as_str() {
            "interleaved" => Layout::Interleaved,
            _ => Layout::Separate,
        };
        let extra_attributes = p.int(&EXTRA_ATTRIBUTES) as u32;
        let batch_size = p.int(&BATCH_SIZE) as usize;
        let draw_triangles = p.int(&DRAW_TRIANGLES) as usize;
        let index_format = match p.choice(&INDEX_FORMAT).as_str() {
            "uint16" => IndexFormat::Uint16,
            _ => IndexFormat::Uint32,
        };
        let order = MeshOrder::parse(&p.choice(&MESH_ORDER)).expect("a declared choice");
        let indexed = p.bool(&INDEXED);
        let primitive = match p.choice(&PRIMITIVE).as_str() {
            "strip" => Primitive::Strip,
            _ => Primitive::List,
        };
        FeedSpec {
            formats: FeedFormats {
                position,
                normal,
                color,
                texcoord,
                extra_attributes,
                layout,
            },
            batch: BatchSpec {
                batch_size,
                draw_triangles,
                index_format,
                primitive,
                indexed,
            },
            order,
        }
    }

    /// Writes the effective value of every axis (defaults included), so each row says exactly
    /// what was fed without the reader knowing the defaults.
    pub fn set_columns(&self, row: &mut Row) {
        let f = &self.formats;
        let name = |o: Option<AttrFormat>| o.map_or("none", |f| f.name);
        row.set(cols::BATCH_SIZE, self.batch.batch_size)
            .set(cols::DRAW_TRIANGLES, self.batch.draw_triangles)
            .set(cols::VERTEX_FORMAT, f.position.name)
            .set(cols::NORMAL_FORMAT, name(f.normal))
            .set(cols::COLOR_FORMAT, name(f.color))
            .set(cols::TEXCOORD_FORMAT, name(f.texcoord))
            .set(
                cols::LAYOUT,
                match f.layout {
                    Layout::Interleaved => "interleaved",
                    Layout::Separate => "separate",
                },
            )
            .set(cols::EXTRA_ATTRIBUTES, f.extra_attributes)
            .set(
                cols::INDEX_FORMAT,
                match self.batch.index_format {
                    IndexFormat::Uint16 => "uint16",
                    IndexFormat::Uint32 => "uint32",
                },
            )
            .set(
                cols::MESH_ORDER,
                prep::MESH_ORDERS[[
                    MeshOrder::Original,
                    MeshOrder::Shuffled,
                    MeshOrder::Vcache,
                    MeshOrder::VcacheVfetch,
                ]
                .iter()
                .position(|o| *o == self.order)
                .expect("every order is listed")],
            )
            .set(cols::INDEXED, self.batch.indexed)
            .set(
                cols::PRIMITIVE,
                match self.batch.primitive {
                    Primitive::List => "list",
                    Primitive::Strip => "strip",
                },
            );
    }

    /// Why this point cannot run on this adapter (a `skipped` row), if it cannot.
    pub fn unsupported(&self, gpu: &Gpu, mesh: &Mesh) -> Option<String> {
        if !self.batch.indexed && self.batch.primitive == Primitive::Strip {
            return Some(
                "strips are stitched with primitive restart, which needs indexed draws".into(),
            );
        }
        let slots = self.formats.slots().len() as u32;
        if slots > gpu.limits.max_vertex_attributes {
            return Some(format!(
                "{slots} vertex attributes exceed this adapter's max_vertex_attributes = {}",
                gpu.limits.max_vertex_attributes
            ));
        }
        let bufs = self.formats.buffer_count() as u32;
        if bufs > gpu.limits.max_vertex_buffers {
            return Some(format!(
                "{bufs} separate vertex buffers exceed this adapter's max_vertex_buffers = {}",
                gpu.limits.max_vertex_buffers
            ));
        }
        if self.batch.draw_triangles > mesh.triangle_count() {
            return Some(format!(
                "draw_triangles = {} but the scene has only {} triangles",
                self.batch.draw_triangles,
                mesh.triangle_count()
            ));
        }
        None
    }
}

/// Deliberately wrong decodes, for the test that proves a wrong decode cannot pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WrongDecode {
    /// Quantised positions read as if stored in [0, 1] (unorm convention) instead of [−1, 1].
    PositionUnormConvention,
    /// A normal stored in a unorm format used without its s·2 − 1 remap.
    NormalWithoutRemap,
}

fn wgsl_type(f: AttrFormat) -> &'static str {
    match f.comps {
        2 => "vec2<f32>",
        3 => "vec3<f32>",
        _ => "vec4<f32>",
    }
}

fn pad4(expr: &str, comps: u32) -> String {
    match comps {
        2 => format!("vec4<f32>({expr}, 0.0, 0.0)"),
        3 => format!("vec4<f32>({expr}, 0.0)"),
        _ => expr.to_string(),
    }
}

/// The WGSL of a feed: a generated prelude (the vertex input struct and the decodes, from the
/// same rules as the CPU twin in `prep.rs`) then `geometry.wgsl`.
pub fn shader_source(formats: &FeedFormats, wrong: Option<WrongDecode>) -> String {
    let slots = formats.slots();
    let mut s = String::from("struct FeedIn {\n");
    for sl in &slots {
        s += &format!(
            "    @location({}) {}: {},\n",
            sl.location,
            sl.kind.name(),
            wgsl_type(sl.format)
        );
    }
    s += "};\n\n";
    s += "fn decode_position(v: FeedIn, batch: u32) -> vec3<f32> {\n";
    if prep::position_quantised(formats.position) {
        s += "    let b = boxes[batch];\n";
        if wrong == Some(WrongDecode::PositionUnormConvention) {
            s += "    return b.centre.xyz - b.half.xyz + 2.0 * b.half.xyz * v.position.xyz;\n";
        } else {
            s += "    return b.centre.xyz + b.half.xyz * v.position.xyz;\n";
        }
    } else {
        s += "    return v.position;\n";
    }
    s += "}\n\nfn attribute_check(v: FeedIn) -> vec3<f32> {\n    var acc = vec3<f32>(0.0);\n";
    for (k, sl) in slots.iter().skip(1).enumerate() {
        let field = format!("v.{}", sl.kind.name());
        let decoded = if prep::remapped(sl.kind, sl.format)
            && !(wrong == Some(WrongDecode::NormalWithoutRemap) && sl.kind == AttrKind::Normal)
        {
            format!("({field} * 2.0 - 1.0)")
        } else {
            field
        };
        let (w, m) = prep::check_coeffs(k);
        s += &format!(
            "    {{\n        let d = {};\n        acc += {w:?} * (d.xyz + d.w * vec3<f32>({:?}, {:?}, {:?}));\n    }}\n",
            pad4(&decoded, sl.format.comps),
            m[0],
            m[1],
            m[2]
        );
    }
    s += "    return acc;\n}\n\n";
    s + WGSL
}

/// What the fragment stage writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// The benchmark: constant colour into RGBA8, depth test on.
    Bench,
    /// Tests: decoded attributes and depth into RGBA32F.
    Check,
}

struct Target {
    color: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
}

/// A feed ready to draw: every buffer, pipeline, target and query exists before the first frame.
pub struct FeedGpu {
    pipeline: wgpu::RenderPipeline,
    bind: wgpu::BindGroup,
    vertex_buffers: Vec<wgpu::Buffer>,
    index_buffer: Option<(wgpu::Buffer, wgpu::IndexFormat)>,
    draws: Vec<prep::Batch>,
    targets: Vec<Target>,
    stats: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
    reversed: bool,
    pub alloc: AllocCounter,
}

impl FeedGpu {
    /// Creates everything for one point. `sizes` are the render targets (the suite's viewport,
    /// then the small one of the raster check).
    #[allow(
        clippy::too_many_arguments,
        reason = "each input of the geometry frame is a different stream or buffer"
    )]
    pub fn new(
        gpu: &Gpu,
        scene: &GpuScene,
        spec: &FeedSpec,
        batched: &Batched,
        streams: &Streams,
        mode: Mode,
        sizes: &[(u32, u32)],
        wrong: Option<WrongDecode>,
    ) -> FeedGpu {
        let d = &gpu.device;
        let mut alloc = AllocCounter::default();
        let src = shader_source(&spec.formats, wrong);
        let module = shader(gpu, "geometry feed", &src);
        let bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("geometry feed"),
            entries: &[
                camera_entry(0),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: true },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("geometry feed"),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        let boxes: Vec<[f32; 8]> = batched
            .batches
            .iter()
            .map(|b| {
                [
                    b.centre[0],
                    b.centre[1],
                    b.centre[2],
                    0.0,
                    b.half[0],
                    b.half[1],
                    b.half[2],
                    0.0,
                ]
            })
            .collect();
        alloc.bytes += (boxes.len() * 32) as u64 + 16;
        let box_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("batch boxes"),
            contents: bytemuck::cast_slice(&boxes),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let feed_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("feed touch"),
            contents: bytemuck::cast_slice(&[0.0f32; 4]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("geometry feed"),
            layout: &bgl,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: scene.camera.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: box_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: feed_buf.as_entire_binding(),
                },
            ],
        });
        let vertex_buffers: Vec<wgpu::Buffer> = streams
            .buffers
            .iter()
            .map(|b| {
                alloc.bytes += b.len() as u64;
                d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("feed vertices"),
                    // A zero-sized buffer cannot be bound; an empty mesh never reaches here.
                    contents: b,
                    usage: wgpu::BufferUsages::VERTEX,
                })
            })
            .collect();
        let index_buffer = spec.batch.indexed.then(|| {
            let fmt = spec.batch.index_format;
            let bytes: Vec<u8> = match fmt {
                IndexFormat::Uint32 => bytemuck::cast_slice(&batched.indices).to_vec(),
                IndexFormat::Uint16 => {
                    let v: Vec<u16> = batched.indices.iter().map(|&i| i as u16).collect();
                    let mut b: Vec<u8> = bytemuck::cast_slice(&v).to_vec();
                    // Buffer sizes must be a multiple of 4 (COPY_BUFFER_ALIGNMENT).
                    b.resize(b.len().next_multiple_of(4), 0);
                    b
                }
            };
            alloc.bytes += bytes.len() as u64;
            let buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("feed indices"),
                contents: &bytes,
                usage: wgpu::BufferUsages::INDEX,
            });
            (buf, fmt.wgpu())
        });
        let vlayouts: Vec<Option<wgpu::VertexBufferLayout>> = streams
            .strides
            .iter()
            .zip(&streams.attributes)
            .map(|(&stride, attrs)| {
                Some(wgpu::VertexBufferLayout {
                    array_stride: stride,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: attrs,
                })
            })
            .collect();
        let color_format = match mode {
            Mode::Bench => wgpu::TextureFormat::Rgba8Unorm,
            Mode::Check => wgpu::TextureFormat::Rgba32Float,
        };
        let targets_state = [Some(wgpu::ColorTargetState {
            format: color_format,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let (topology, strip_index_format) = match spec.batch.primitive {
            Primitive::List => (wgpu::PrimitiveTopology::TriangleList, None),
            Primitive::Strip => (
                wgpu::PrimitiveTopology::TriangleStrip,
                Some(spec.batch.index_format.wgpu()),
            ),
        };
        let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("geometry feed"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_feed"),
                compilation_options: Default::default(),
                buffers: &vlayouts,
            },
            primitive: wgpu::PrimitiveState {
                topology,
                strip_index_format,
                // Both faces drawn: strips alternate winding, and culling would hide work.
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(depth_state(scene.reversed_z, true)),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(match mode {
                    Mode::Bench => "fs_constant",
                    Mode::Check => "fs_check",
                }),
                compilation_options: Default::default(),
                targets: &targets_state,
            }),
            multiview_mask: None,
            cache: None,
        });
        let targets = sizes
            .iter()
            .map(|&(w, h)| {
                let color = alloc.texture(
                    gpu,
                    "feed colour",
                    w,
                    h,
                    color_format,
                    wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                );
                let depth = alloc.texture(
                    gpu,
                    "feed depth",
                    w,
                    h,
                    wgpu::TextureFormat::Depth32Float,
                    wgpu::TextureUsages::RENDER_ATTACHMENT,
                );
                Target {
                    color_view: color.create_view(&Default::default()),
                    color,
                    depth_view: depth.create_view(&Default::default()),
                }
            })
            .collect();
        let stats = gpu.has(wgpu::Features::PIPELINE_STATISTICS_QUERY).then(|| {
            let set = d.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("feed statistics"),
                ty: wgpu::QueryType::PipelineStatistics(
                    wgpu::PipelineStatisticsTypes::VERTEX_SHADER_INVOCATIONS
                        | wgpu::PipelineStatisticsTypes::FRAGMENT_SHADER_INVOCATIONS,
                ),
                count: 1,
            });
            let resolve = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("statistics resolve"),
                size: 256,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let read = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("statistics read"),
                size: 256,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            (set, resolve, read)
        });
        FeedGpu {
            pipeline,
            bind,
            vertex_buffers,
            index_buffer,
            draws: batched.batches.clone(),
            targets,
            stats,
            reversed: scene.reversed_z,
            alloc,
        }
    }

    /// Encodes and submits one frame into target `t`; with `stats`, wraps it in the pipeline
    /// statistics query (never in a timed frame).
    pub fn frame(&self, gpu: &Gpu, t: usize, timer: Option<&mut GpuTimer>, stats: bool) {
        let target = &self.targets[t];
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("geometry feed"),
                color_attachments: &[
                    // Check mode: alpha −1 marks "no fragment" (depth is in [0, 1]).
                    bench_core::gpu::cleared(
                        &target.color_view,
                        wgpu::Color {
                            r: 0.0,
                            g: 0.0,
                            b: 0.0,
                            a: -1.0,
                        },
                    ),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &target.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear_depth(self.reversed)),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.and_then(|t| t.render_pass("feed")),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let query = if stats { self.stats.as_ref() } else { None };
            if let Some((set, _, _)) = query {
                pass.begin_pipeline_statistics_query(set, 0);
            }
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind, &[]);
            for (i, b) in self.vertex_buffers.iter().enumerate() {
                pass.set_vertex_buffer(i as u32, b.slice(..));
            }
            if let Some((ib, fmt)) = &self.index_buffer {
                pass.set_index_buffer(ib.slice(..), *fmt);
            }
            for (i, b) in self.draws.iter().enumerate() {
                // instance_index = batch: the vertex shader's key into the per-batch boxes.
                let inst = i as u32..i as u32 + 1;
                if self.index_buffer.is_some() {
                    pass.draw_indexed(
                        b.first_index..b.first_index + b.index_count,
                        b.first_vertex as i32,
                        inst,
                    );
                } else {
                    pass.draw(b.first_vertex..b.first_vertex + b.vertex_count, inst);
                }
            }
            if query.is_some() {
                pass.end_pipeline_statistics_query();
            }
        }
        if let (true, Some((set, resolve, read))) = (stats, &self.stats) {
            enc.resolve_query_set(set, 0..1, resolve, 0);
            enc.copy_buffer_to_buffer(resolve, 0, read, 0, 16);
        }
        gpu.queue.submit([enc.finish()]);
    }

    /// Vertex- and fragment-shader invocations of one untimed frame, where the adapter counts them.
    pub fn invocations(&self, gpu: &Gpu) -> Result<Option<(u64, u64)>> {
        if self.stats.is_none() {
            return Ok(None);
        }
        self.frame(gpu, 0, None, true);
        gpu.wait()?;
        let (_, _, read) = self.stats.as_ref().expect("checked");
        let bytes = gpu.map_read_range(read, 16)?;
        let v: &[u64] = bytemuck::cast_slice(&bytes);
        Ok(Some((v[0], v[1])))
    }

    /// Reads target `t`'s colour (check mode: RGBA32F; bench mode is RGBA8 and not read).
    pub fn read_check(&self, gpu: &Gpu, t: usize) -> Result<Vec<[f32; 4]>> {
        bench_core::gpu::read_rgba32f(gpu, &self.targets[t].color)
    }
}

/// Validation and out-of-memory error scopes around untimed GPU work (the harness's own).
pub use bench_core::measure::scoped;

/// One feed drawn into one of its targets (0: the suite's viewport, 1: the raster check's
/// small one): the frame `measure` times for a geometry point.
pub struct FeedFrame {
    pub feed: FeedGpu,
    pub target: usize,
}

impl Timed for FeedFrame {
    fn frame(&mut self, gpu: &Gpu, _: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        self.feed.frame(gpu, self.target, Some(timer), false);
        Ok(FrameStats {
            geometry_passes: 1,
            layers: 1,
        })
    }
    fn bytes_allocated(&self) -> u64 {
        self.feed.alloc.bytes
    }
}

pub struct GeometryStudy;

/// The CPU-side product of one point.
pub struct PreparedFeed {
    pub batched: Batched,
    pub streams: Streams,
}

/// Orders (cached by the caller), batches and encodes one point.
pub fn prepare_feed(mesh: &Mesh, ordered: &Ordered, spec: &FeedSpec) -> PreparedFeed {
    let batched = prep::batch(mesh, ordered, &spec.batch);
    let streams = prep::encode_streams(mesh, &batched, &spec.formats);
    PreparedFeed { batched, streams }
}

impl Study for GeometryStudy {
    fn kind(&self) -> StudyKind {
        StudyKind::Geometry
    }
    fn describe(&self) -> &'static str {
        "geometry feeding (Bavoil ch. 3): batch size, vertex formats, layout, index precision, mesh order, strips; triangles/s and post-transform cache hits"
    }
    fn methods(&self) -> Methods {
        Methods::Implicit("geometry")
    }
    fn axes(&self, _: &str) -> Vec<Axis> {
        AXES.to_vec()
    }
    fn options(&self) -> Vec<Opt> {
        vec![RASTER_CHECK, SMALL_VIEWPORT_DIVISOR]
    }

    fn run_group(&self, ctx: &GroupCtx<'_>, emit: &mut Emit<'_>) -> Result<()> {
        let raster_check = RASTER_CHECK.bool(ctx.study);
        let div = SMALL_VIEWPORT_DIVISOR.int(ctx.study) as u32;
        let gpu = ctx.gpu;
        let mesh = &ctx.scene.mesh;
        let (w, h) = (ctx.group.width, ctx.group.height);
        let small = ((w / div).max(1), (h / div).max(1));
        let mut orders: HashMap<MeshOrder, Ordered> = HashMap::new();
        for (i, pt) in ctx.group.points.iter().enumerate() {
            let mut row = Row::new();
            row.set(cols::METHOD, "geometry");
            set_params(&mut row, &pt.point.recorded())?;
            let spec = FeedSpec::from_point(&pt.point);
            spec.set_columns(&mut row);
            if let Some(why) = spec.unsupported(gpu, mesh) {
                emit(i, skipped_row(row, &why))?;
                continue;
            }
            let t0 = std::time::Instant::now();
            let ordered = orders
                .entry(spec.order)
                .or_insert_with(|| prep::order_mesh(mesh, spec.order));
            let feed = prepare_feed(mesh, ordered, &spec);
            let prep_ms = t0.elapsed().as_secs_f64() * 1e3;
            match measure_feed(ctx, &spec, &feed, raster_check.then_some(small)) {
                Ok(m) => {
                    set_timing(&mut row, &m.main, mesh);
                    fill_row(&mut row, &spec, &feed, &m, prep_ms, small, ctx.floor_ms);
                    emit(i, row)?;
                }
                Err(e) => emit(i, error_row(row, &e))?,
            }
        }
        Ok(())
    }
}

/// What one point measured on the GPU: the feed at the suite's viewport and, for the raster
/// check, at the small one (both timed by `measure`, each under the suite's plan).
pub struct FeedMeasured {
    pub main: Measured<FeedFrame>,
    pub small: Option<Measured<FeedFrame>>,
    pub invocations: Option<(u64, u64)>,
}

fn measure_feed(
    ctx: &GroupCtx<'_>,
    spec: &FeedSpec,
    feed: &PreparedFeed,
    small: Option<(u32, u32)>,
) -> Result<FeedMeasured> {
    let gpu = ctx.gpu;
    let mut sizes = vec![(ctx.group.width, ctx.group.height)];
    sizes.extend(small);
    // Both targets are made for either timing, so bytes_allocated is the point's as before.
    let make_for = |target: usize| {
        let sizes = &sizes;
        move |gs: &GpuScene| -> Result<Box<FeedFrame>> {
            let feed = FeedGpu::new(
                gpu,
                gs,
                spec,
                &feed.batched,
                &feed.streams,
                Mode::Bench,
                sizes,
                None,
            );
            Ok(Box::new(FeedFrame { feed, target }))
        }
    };
    let main = measure_timed(gpu, ctx.gscene, &make_for(0), &ctx.plan)?;
    let small = match small {
        Some(_) => Some(measure_timed(gpu, ctx.gscene, &make_for(1), &ctx.plan)?),
        None => None,
    };
    let invocations = scoped(gpu, "statistics frame", || {
        main.prepared.feed.invocations(gpu)
    })?;
    Ok(FeedMeasured {
        main,
        small,
        invocations,
    })
}

fn fill_row(
    row: &mut Row,
    spec: &FeedSpec,
    feed: &PreparedFeed,
    m: &FeedMeasured,
    prep_ms: f64,
    small: (u32, u32),
    floor_ms: Option<f64>,
) {
    let b = &feed.batched;
    let tris = b.triangles as f64;
    let index_count: u64 = if spec.batch.indexed {
        b.indices.len() as u64
    } else {
        0
    };
    // Vertices per draw in the thesis's sense: indices for indexed draws, corners otherwise.
    let submitted = if spec.batch.indexed {
        index_count as f64
    } else {
        3.0 * tris
    };
    let index_bytes = match (spec.batch.indexed, spec.batch.index_format) {
        (false, _) => 0,
        (true, IndexFormat::Uint16) => 2 * index_count,
        (true, IndexFormat::Uint32) => 4 * index_count,
    };
    row.set(cols::EFFECT, "none")
        .set(cols::CLAIMS_EXACT, false)
        .set(cols::BATCHES, b.batches.len())
        .set(cols::BATCH_VERTICES, b.verts.len())
        .set(cols::INDEX_COUNT, index_count)
        .set(
            cols::VERTEX_STRIDE_BYTES,
            feed.streams.strides.iter().sum::<u64>(),
        )
        .set(cols::VERTEX_BYTES, feed.streams.bytes())
        .set(cols::INDEX_BYTES, index_bytes)
        .set_f(cols::PREP_MS, prep_ms);
    if let Some(s) = &b.cache {
        row.set_f(cols::ACMR, s.acmr as f64)
            .set_f(cols::ATVR, s.atvr as f64);
    }
    // The timing columns are `set_timing`'s; the rates count what this point drew (a prefix
    // of the mesh, corners or indices), not the scene's whole mesh.
    if let Some(g) = &m.main.gpu {
        if g.median > 0.0 {
            let secs = g.median * 1e-3;
            row.set_f(cols::TRIANGLES_PER_S, tris / secs)
                .set_f(cols::VERTICES_PER_S, submitted / secs);
        }
        if let Some(s) = m.small.as_ref().and_then(|s| s.gpu.as_ref()) {
            row.set(cols::SMALL_VIEWPORT, format!("{}x{}", small.0, small.1))
                .set_f(cols::GPU_MS_SMALL_VIEWPORT, s.median);
            if s.median > 0.0 {
                row.set_f(cols::RASTER_BOUND_RATIO, g.median / s.median);
            }
        }
        let _ = floor_ms; // x_floor is added by the runner
    }
    if let Some((vs, fs)) = m.invocations {
        row.set(cols::VS_INVOCATIONS, vs)
            .set(cols::PS_INVOCATIONS, fs);
        if tris > 0.0 {
            row.set_f(cols::VS_ACMR, vs as f64 / tris).set_f(
                cols::POST_TRANSFORM_HIT_RATE,
                1.0 - vs as f64 / (3.0 * tris),
            );
        }
    }
    let mut notes = Vec::new();
    if m.main.gpu.is_none() {
        notes.push("no TIMESTAMP_QUERY: only wall-clock times".to_string());
    }
    if m.invocations.is_none() {
        notes.push("no PIPELINE_STATISTICS_QUERY: post-transform hits not measured".to_string());
    }
    if spec.batch.batch_size > 0 && b.batches.len() > 1 {
        let asked = (b.triangles).div_ceil(spec.batch.batch_size);
        if asked != b.batches.len() {
            notes.push(format!(
                "{} batches instead of {asked}: 16-bit indices cap a batch at {} vertices",
                b.batches.len(),
                spec.batch
                    .index_format
                    .max_batch_vertices(spec.batch.primitive)
            ));
        }
    }
    if !notes.is_empty() {
        row.set(cols::NOTES, one_line(&notes.join("; ")));
    }
}

/// This crate's study kind (the binary's table, `mfx::STUDIES`, lists it with the others).
pub const STUDIES: &[&dyn bench_core::study::Study] = &[&GeometryStudy];
