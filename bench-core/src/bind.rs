//! Bindings declared once (in the spirit of vello's shader table, `add_shader!(name, [Uniform,
//! BufReadOnly, Buffer])`): every GPU pass (a method's, a shading path's, a shadow map's)
//! writes its bind group as one table of (binding, kind), and the table builds both the
//! `BindGroupLayout` and, given one resource per row in the same order, the `BindGroup`. A row
//! and its resource cannot drift apart: `group` checks the count and the kind of each.
//! [`pipeline_layout`] and [`render_pipeline`] make a stage a line.

use crate::gpu::Gpu;

/// What a binding is. Buffers and textures are read with `textureLoad` (no filtering).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// The camera uniform: visible to every stage whatever the table's stages (the vertex
    /// stage reads it), as [`crate::gpu_util::camera_entry`].
    Camera,
    Uniform,
    /// A uniform read `size` bytes at a time at a dynamic offset (one slice per pass).
    UniformDynamic(u64),
    /// `var<storage, read_write>`.
    Storage,
    /// `var<storage, read>`.
    StorageRo,
    Texture(wgpu::TextureSampleType),
    /// A multisampled texture (`texture_multisampled_2d`, `texture_depth_multisampled_2d`).
    TextureMs(wgpu::TextureSampleType),
    /// A `texture_2d_array`.
    TextureArray(wgpu::TextureSampleType),
}

/// Float texels read with `textureLoad`.
pub const FLOAT: wgpu::TextureSampleType = wgpu::TextureSampleType::Float { filterable: false };
/// Unsigned texels.
pub const UINT: wgpu::TextureSampleType = wgpu::TextureSampleType::Uint;
/// Depth texels.
pub const DEPTH: wgpu::TextureSampleType = wgpu::TextureSampleType::Depth;

/// Fragment and compute: where a method's per-pixel state is read and written.
pub const FC: wgpu::ShaderStages = wgpu::ShaderStages::FRAGMENT.union(wgpu::ShaderStages::COMPUTE);

impl Kind {
    fn entry(self, binding: u32, stages: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
        let buffer = |ty, dynamic, size: Option<u64>| wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: dynamic,
            min_binding_size: size.and_then(wgpu::BufferSize::new),
        };
        let texture = |sample_type, view_dimension, multisampled| wgpu::BindingType::Texture {
            sample_type,
            view_dimension,
            multisampled,
        };
        let d2 = wgpu::TextureViewDimension::D2;
        let (visibility, ty) = match self {
            Kind::Camera => (
                wgpu::ShaderStages::VERTEX
                    | wgpu::ShaderStages::FRAGMENT
                    | wgpu::ShaderStages::COMPUTE,
                buffer(wgpu::BufferBindingType::Uniform, false, None),
            ),
            Kind::Uniform => (
                stages,
                buffer(wgpu::BufferBindingType::Uniform, false, None),
            ),
            Kind::UniformDynamic(size) => (
                stages,
                buffer(wgpu::BufferBindingType::Uniform, true, Some(size)),
            ),
            Kind::Storage => (
                stages,
                buffer(
                    wgpu::BufferBindingType::Storage { read_only: false },
                    false,
                    None,
                ),
            ),
            Kind::StorageRo => (
                stages,
                buffer(
                    wgpu::BufferBindingType::Storage { read_only: true },
                    false,
                    None,
                ),
            ),
            Kind::Texture(s) => (stages, texture(s, d2, false)),
            Kind::TextureMs(s) => (stages, texture(s, d2, true)),
            Kind::TextureArray(s) => (
                stages,
                texture(s, wgpu::TextureViewDimension::D2Array, false),
            ),
        };
        wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty,
            count: None,
        }
    }

    fn is_buffer(self) -> bool {
        !matches!(
            self,
            Kind::Texture(_) | Kind::TextureMs(_) | Kind::TextureArray(_)
        )
    }
}

/// One resource per table row.
#[derive(Clone, Copy)]
pub enum Res<'a> {
    /// A whole buffer.
    Buf(&'a wgpu::Buffer),
    /// `size` bytes of a buffer from offset 0 (a dynamic-offset uniform's window).
    Window(&'a wgpu::Buffer, u64),
    View(&'a wgpu::TextureView),
}

impl<'a> From<&'a wgpu::Buffer> for Res<'a> {
    fn from(b: &'a wgpu::Buffer) -> Self {
        Res::Buf(b)
    }
}

impl<'a> From<&'a wgpu::TextureView> for Res<'a> {
    fn from(v: &'a wgpu::TextureView) -> Self {
        Res::View(v)
    }
}

/// A bind group's table: its layout, and the rows its groups are checked against.
pub struct Bindings {
    pub layout: wgpu::BindGroupLayout,
    label: String,
    rows: Vec<(u32, Kind)>,
}

impl Bindings {
    /// The layout of `rows` (binding, kind), visible to `stages` (the camera to all).
    pub fn new(gpu: &Gpu, label: &str, stages: wgpu::ShaderStages, rows: &[(u32, Kind)]) -> Self {
        let entries: Vec<_> = rows.iter().map(|&(b, k)| k.entry(b, stages)).collect();
        gpu.note_layout(label, &entries);
        let layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &entries,
            });
        Bindings {
            layout,
            label: label.to_string(),
            rows: rows.to_vec(),
        }
    }

    /// Rows 0, 1, 2, … of `kinds` in order.
    pub fn seq(gpu: &Gpu, label: &str, stages: wgpu::ShaderStages, kinds: &[Kind]) -> Self {
        let rows: Vec<_> = (0..).zip(kinds.iter().copied()).collect();
        Self::new(gpu, label, stages, &rows)
    }

    /// A bind group of `res`, one per row in the table's order. Panics naming the table when
    /// the count or a kind (buffer or texture) does not match: a programming error.
    pub fn group(&self, gpu: &Gpu, res: &[Res]) -> wgpu::BindGroup {
        assert_eq!(
            res.len(),
            self.rows.len(),
            "bind group '{}': {} resources for {} bindings",
            self.label,
            res.len(),
            self.rows.len()
        );
        let entries: Vec<_> = self
            .rows
            .iter()
            .zip(res)
            .map(|(&(binding, kind), r)| {
                let resource = match *r {
                    Res::Buf(b) => b.as_entire_binding(),
                    Res::Window(b, size) => wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: b,
                        offset: 0,
                        size: wgpu::BufferSize::new(size),
                    }),
                    Res::View(v) => wgpu::BindingResource::TextureView(v),
                };
                assert_eq!(
                    kind.is_buffer(),
                    !matches!(r, Res::View(_)),
                    "bind group '{}': binding {binding} is {kind:?}",
                    self.label
                );
                wgpu::BindGroupEntry { binding, resource }
            })
            .collect();
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&self.label),
            layout: &self.layout,
            entries: &entries,
        })
    }
}

/// A pipeline layout of `groups` (group 0, 1, …).
pub fn pipeline_layout(
    gpu: &Gpu,
    label: &str,
    groups: &[&wgpu::BindGroupLayout],
) -> wgpu::PipelineLayout {
    let g: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().map(|g| Some(*g)).collect();
    pipeline_layout_gaps(gpu, label, &g)
}

/// A pipeline layout whose groups may be absent (a variant that binds no group there).
pub fn pipeline_layout_gaps(
    gpu: &Gpu,
    label: &str,
    groups: &[Option<&wgpu::BindGroupLayout>],
) -> wgpu::PipelineLayout {
    gpu.device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: groups,
            immediate_size: 0,
        })
}

/// The mesh buffers in the order the visibility kernels bind them: positions, normals,
/// colours, object ids, indices.
pub fn mesh_buffers(scene: &crate::gpu_scene::GpuScene) -> [&wgpu::Buffer; 5] {
    let s = scene;
    [
        &s.positions,
        &s.normals,
        &s.colors,
        &s.object_ids,
        &s.indices,
    ]
}

/// What a render pipeline draws with: module, entry points, vertex buffers, targets.
pub struct Raster<'a> {
    pub module: &'a wgpu::ShaderModule,
    pub vs: &'a str,
    pub buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub fs: &'a str,
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    pub constants: &'a [(&'a str, f64)],
    pub depth: Option<wgpu::DepthStencilState>,
    pub samples: u32,
}

/// A render pipeline of one `Raster` description.
pub fn render_pipeline(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::PipelineLayout,
    r: Raster,
) -> wgpu::RenderPipeline {
    let opts = || wgpu::PipelineCompilationOptions {
        constants: r.constants,
        zero_initialize_workgroup_memory: false,
    };
    gpu.device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module: r.module,
                entry_point: Some(r.vs),
                compilation_options: opts(),
                buffers: r.buffers,
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: r.depth,
            multisample: crate::gpu_util::multisample(r.samples),
            fragment: Some(wgpu::FragmentState {
                module: r.module,
                entry_point: Some(r.fs),
                compilation_options: opts(),
                targets: r.targets,
            }),
            multiview_mask: None,
            cache: None,
        })
}

/// Additive blending (sums: weighted colour, counts, moments).
pub const ADD: wgpu::BlendComponent = wgpu::BlendComponent {
    src_factor: wgpu::BlendFactor::One,
    dst_factor: wgpu::BlendFactor::One,
    operation: wgpu::BlendOperation::Add,
};

/// dst · (1 − src): the revealage (transmittance) product.
pub const TRANSMIT: wgpu::BlendComponent = wgpu::BlendComponent {
    src_factor: wgpu::BlendFactor::Zero,
    dst_factor: wgpu::BlendFactor::OneMinusSrc,
    operation: wgpu::BlendOperation::Add,
};

/// A colour target of `format` blended by `c` in colour and alpha alike.
pub fn blended(
    format: wgpu::TextureFormat,
    c: wgpu::BlendComponent,
) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend: Some(wgpu::BlendState { color: c, alpha: c }),
        write_mask: wgpu::ColorWrites::ALL,
    })
}
