//! GPU plumbing shared by methods, studies and shading: bind-group layout entries, shader
//! modules with the common vertex stage, pipelines, buffer read-back, the depth state. It knows
//! nothing of methods or studies (it is below both in the module graph).

use crate::gpu::Gpu;
use crate::Result;

/// WGSL shared by every raster pipeline: the camera uniform and the standard vertex stage.
pub const COMMON_WGSL: &str = include_str!("common.wgsl");

/// Bind group layout entry for the camera uniform at `binding`.
pub fn camera_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX
            | wgpu::ShaderStages::FRAGMENT
            | wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Storage buffer entry (compute and fragment visible).
pub fn storage_entry(
    binding: u32,
    read_only: bool,
    stages: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: stages,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Texture entry for `textureLoad` (no sampler).
pub fn texture_entry(
    binding: u32,
    sample_type: wgpu::TextureSampleType,
    stages: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: stages,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// Texture entry for `textureLoad` of a multisampled texture (`texture_multisampled_2d`,
/// `texture_depth_multisampled_2d`) when `multisampled`, else [`texture_entry`].
pub fn texture_entry_ms(
    binding: u32,
    sample_type: wgpu::TextureSampleType,
    stages: wgpu::ShaderStages,
    multisampled: bool,
) -> wgpu::BindGroupLayoutEntry {
    let mut e = texture_entry(binding, sample_type, stages);
    if let wgpu::BindingType::Texture {
        multisampled: m, ..
    } = &mut e.ty
    {
        *m = multisampled;
    }
    e
}

/// The MSAA state of a pipeline drawing into `samples`-sample targets.
pub fn multisample(samples: u32) -> wgpu::MultisampleState {
    wgpu::MultisampleState {
        count: samples,
        mask: !0,
        alpha_to_coverage_enabled: false,
    }
}

/// The sample-rate form of a raster module's source: each fragment entry point also takes
/// `@builtin(sample_index)` and stores it in the module's `var<private> SAMPLE: i32` as its first
/// statement, so it runs once per covered sample (Vulkan: SampleId enables sample shading at
/// rate 1) and can `textureLoad` a multisampled texture at its own sample. Coverage, window
/// depth (`@builtin(position).z`) and the depth test are then per sample; other inputs keep
/// their interpolation, which Vulkan lets the driver evaluate anywhere in the pixel without the
/// `Sample` decoration (lavapipe: the centre). `@interpolate(perspective, sample)` is not used:
/// lavapipe's perspective-correct per-sample interpolation scales even a constant colour by up
/// to 1.5× on grazing triangles (measured on nested spheres; `linear, sample` is exact there).
/// Panics if the source has no fragment entry: the rewrite must not silently do nothing.
pub fn per_sample_source(src: &str) -> String {
    let mut out = String::with_capacity(src.len() + 256);
    let mut rest = src;
    let mut entries = 0;
    while let Some(i) = rest.find("@fragment") {
        let open = i + rest[i..].find('(').expect("fragment entry parameters");
        let mut depth = 0;
        let close = open
            + rest[open..]
                .char_indices()
                .find(|&(_, c)| {
                    depth += (c == '(') as i32 - (c == ')') as i32;
                    depth == 0
                })
                .expect("end of parameters")
                .0;
        let body = close + rest[close..].find('{').expect("fragment entry body") + 1;
        out.push_str(&rest[..=open]);
        out.push_str("@builtin(sample_index) sample_index_: u32, ");
        out.push_str(&rest[open + 1..body]);
        out.push_str("\n    SAMPLE = i32(sample_index_);");
        rest = &rest[body..];
        entries += 1;
    }
    out.push_str(rest);
    assert!(entries > 0, "no @fragment entry point to make per-sample");
    out
}

/// Compiles `COMMON_WGSL` + `body` into one module.
pub fn shader(gpu: &Gpu, label: &str, body: &str) -> wgpu::ShaderModule {
    shader_source(gpu, label, format!("{COMMON_WGSL}\n{body}"))
}

/// Compiles a whole WGSL source (e.g. a [`per_sample_source`] of `COMMON_WGSL` + body).
pub fn shader_source(gpu: &Gpu, label: &str, src: String) -> wgpu::ShaderModule {
    gpu.device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(src.into()),
        })
}

/// Reads a storage buffer of `T` back to the CPU.
pub fn read_vec<T: bytemuck::Pod>(gpu: &Gpu, buf: &wgpu::Buffer, count: usize) -> Result<Vec<T>> {
    let bytes = gpu.read_buffer(buf, (count * std::mem::size_of::<T>()) as u64)?;
    Ok(bytemuck::cast_slice(&bytes).to_vec())
}

/// A compute pipeline with override `constants`. `zero_initialize_workgroup_memory`: whether
/// workgroup memory starts zeroed (the shading kernels rely on it; the methods' kernels
/// initialise what they use and skip the cost).
pub fn compute_pipeline(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    constants: &[(&str, f64)],
    zero_initialize_workgroup_memory: bool,
) -> wgpu::ComputePipeline {
    gpu.device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(label),
            layout: Some(layout),
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                zero_initialize_workgroup_memory,
            },
            cache: None,
        })
}

/// Storage usage for per-pixel buffers that are cleared per frame and read back.
pub const STORAGE_RW: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

/// A bind group over whole buffers at bindings 0, 1, 2, … in order.
pub fn bind_buffers(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let entries: Vec<_> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// Whether a buffer of `bytes` can be bound as one storage buffer here; Err names the limit
/// (of the run's limits profile: [`crate::limits::check_storage`]).
pub fn check_storage_size(gpu: &Gpu, what: &str, bytes: u64) -> crate::Result<()> {
    crate::limits::check_storage(gpu.held(), what, bytes)
}

/// Depth test "nearer passes", with or without writes, for the scene's depth convention.
pub fn depth_state(reversed: bool, write: bool) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: wgpu::TextureFormat::Depth32Float,
        depth_write_enabled: Some(write),
        depth_compare: Some(if reversed {
            wgpu::CompareFunction::Greater
        } else {
            wgpu::CompareFunction::Less
        }),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// Clear value of the depth buffer for the scene's depth convention.
pub fn clear_depth(reversed: bool) -> f32 {
    if reversed {
        0.0
    } else {
        1.0
    }
}

/// A timed compute pass of one 8×8-pixel workgroup per screen tile (resolves, composites): the
/// pass every per-pixel kernel of a method runs after its geometry passes.
pub fn pixel_pass(
    enc: &mut wgpu::CommandEncoder,
    timer: &mut crate::timing::GpuTimer,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    bind: &wgpu::BindGroup,
    scene: &crate::gpu_scene::GpuScene,
) {
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: timer.compute_pass(label),
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind, &[]);
    pass.dispatch_workgroups(scene.width.div_ceil(8), scene.height.div_ceil(8), 1);
}

/// Whether `format` can be a `samples`× multisampled render target here (WebGPU guarantees 4×
/// for most formats; 2× and 8× need the adapter's own format capabilities).
pub fn check_msaa_format(
    gpu: &Gpu,
    format: wgpu::TextureFormat,
    samples: u32,
) -> Result<(), crate::Unsupported> {
    if samples <= 1 {
        return Ok(());
    }
    let flags = if gpu.has(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES) {
        gpu.adapter.get_texture_format_features(format).flags
    } else {
        format.guaranteed_format_features(gpu.features).flags
    };
    if flags.sample_count_supported(samples) {
        Ok(())
    } else {
        Err(format!(
            "{format:?} cannot be multisampled {samples}× on this adapter (it allows {:?})",
            flags.supported_sample_counts()
        )
        .into())
    }
}
