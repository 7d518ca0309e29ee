//! Split/Second's MSAA edge class (GEG2 ch. 4): a 2×MSAA G-buffer (`msaa = x2`; naive,
//! classified, uber) whose pixels are shaded per sample (the average of both) only where the
//! two samples differ, once elsewhere. `msaa = x4` is the same with 4 samples: lavapipe (the
//! test adapter) multisamples only 4×, so the tests run x4 and x2 rows are skipped there with
//! the adapter's reason ([`supported`]); the code is the same for any sample count.
//!
//! The G-buffer pass runs once per pixel (no sample-rate shading), so colour targets hold the
//! same value in every sample a triangle covers; its MSAA entry point also writes the depth at
//! the pixel centre (`frag_depth`), so depth is per pixel as well. Two samples then differ only
//! where different triangles (or a triangle and the sky) cover them: the edge bit
//! ([`class::EDGE`]) compares everything the shading reads (depth, normal + smoothness, albedo,
//! specular, material id) exactly. Every sample is shaded at its pixel's centre, so where the
//! samples are equal shading once equals the average of shading each, and the f64 reference
//! ([`reference`]) simply averages per-sample shading everywhere.
//!
//! Multisampled textures cannot be copied to a buffer: [`read_samples`] runs a compute pass
//! that loads every sample into a storage buffer, giving each sample's G-buffer exactly as the
//! shaders see it (the reference's and the CPU edge twin's input).

use bench_core::gpu::Gpu;
use bench_core::gpu_scene::AllocCounter;
use bench_core::gpu_util::{
    compute_pipeline, read_vec, shader_source, storage_entry, texture_entry_ms,
};
use bench_core::study::InvalidPoint;
use bench_core::{Result, Unsupported};

use super::gbuffer::GBufferPass;
use super::{class, pixel_class, reference, GBuffer, ShadeSetup};

/// Whether a deferred point renders a 2×MSAA G-buffer (axis `msaa`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Mode {
    #[default]
    Off,
    X2,
    X4,
}

impl Mode {
    pub const NAMES: &'static [&'static str] = &["off", "x2", "x4"];
    pub fn parse(s: &str) -> std::result::Result<Mode, InvalidPoint> {
        match s {
            "off" => Ok(Mode::Off),
            "x2" => Ok(Mode::X2),
            "x4" => Ok(Mode::X4),
            o => Err(InvalidPoint::value(
                "msaa",
                format!("'{o}'"),
                "is not one of off, x2, x4",
            )),
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Mode::Off => "off",
            Mode::X2 => "x2",
            Mode::X4 => "x4",
        }
    }
    pub fn samples(self) -> u32 {
        match self {
            Mode::Off => 1,
            Mode::X2 => 2,
            Mode::X4 => 4,
        }
    }
}

/// Whether every G-buffer format can be multisampled `mode.samples()`× on this adapter
/// (WebGPU guarantees 4×; 2× needs the adapter's own capabilities: NVIDIA has it, lavapipe not).
pub fn supported(gpu: &Gpu, mode: Mode) -> std::result::Result<(), Unsupported> {
    use super::gbuffer::{ALBEDO_FORMAT, MAT_FORMAT, NORMAL_FORMAT, SPEC_FORMAT};
    for f in [
        wgpu::TextureFormat::Depth32Float,
        NORMAL_FORMAT,
        ALBEDO_FORMAT,
        SPEC_FORMAT,
        MAT_FORMAT,
    ] {
        bench_core::gpu_util::check_msaa_format(gpu, f, mode.samples())
            .map_err(|e| Unsupported::new(format!("msaa = {}: {e}", mode.name())))?;
    }
    Ok(())
}

const READ_WGSL: &str = r#"
@group(0) @binding(0) var t_depth: texture_depth_multisampled_2d;
@group(0) @binding(1) var t_normal: texture_multisampled_2d<f32>;
@group(0) @binding(2) var t_albedo: texture_multisampled_2d<f32>;
@group(0) @binding(3) var t_spec: texture_multisampled_2d<f32>;
@group(0) @binding(4) var t_mat: texture_multisampled_2d<u32>;
@group(0) @binding(5) var<storage, read_write> out: array<vec4<u32>>;

// Every sample as the shading paths load it, bit for bit: 3 vec4 per (sample, pixel).
@compute @workgroup_size(8, 8)
fn cs_read_samples(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(t_normal);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    let p = gid.xy;
    let n = size.x * size.y;
    let i = p.y * size.x + p.x;
    for (var s = 0u; s < textureNumSamples(t_normal); s++) {
        let o = (s * n + i) * 3u;
        out[o] = bitcast<vec4<u32>>(textureLoad(t_normal, p, s));
        out[o + 1u] = vec4<u32>(bitcast<vec3<u32>>(textureLoad(t_albedo, p, s).xyz),
                                bitcast<u32>(textureLoad(t_depth, p, s)));
        out[o + 2u] = vec4<u32>(bitcast<vec3<u32>>(textureLoad(t_spec, p, s).xyz),
                                textureLoad(t_mat, p, s).x);
    }
}
"#;

/// Every sample of a multisampled full G-buffer, one [`GBuffer`] per sample (a single-sample
/// G-buffer: its one read-back).
pub fn read_samples(gpu: &Gpu, gb: &GBufferPass) -> Result<Vec<GBuffer>> {
    if gb.samples == 1 {
        return Ok(vec![gb.read(gpu)?]);
    }
    let d = &gpu.device;
    let (w, h) = (gb.depth.width(), gb.depth.height());
    let n = (w * h) as usize;
    let s = gb.samples as usize;
    let cs = wgpu::ShaderStages::COMPUTE;
    let ff = wgpu::TextureSampleType::Float { filterable: false };
    let bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("msaa read"),
        entries: &[
            texture_entry_ms(0, wgpu::TextureSampleType::Depth, cs, true),
            texture_entry_ms(1, ff, cs, true),
            texture_entry_ms(2, ff, cs, true),
            texture_entry_ms(3, ff, cs, true),
            texture_entry_ms(4, wgpu::TextureSampleType::Uint, cs, true),
            storage_entry(5, false, cs),
        ],
    });
    let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("msaa read"),
        bind_group_layouts: &[Some(&bgl)],
        immediate_size: 0,
    });
    let module = shader_source(gpu, "msaa read", READ_WGSL.to_string());
    let pipeline = compute_pipeline(
        gpu,
        "msaa read",
        &layout,
        &module,
        "cs_read_samples",
        &[],
        true,
    );
    let mut alloc = AllocCounter::default();
    // Not gpu_paths' helpers: gpu_paths reads the samples through this module.
    let buf = alloc.buffer(
        gpu,
        "msaa samples",
        ((s * n * 48) as u64).max(16),
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    );
    let surface = |t: &Option<wgpu::Texture>| -> wgpu::TextureView {
        t.as_ref()
            .expect("the MSAA G-buffer is a full one")
            .create_view(&Default::default())
    };
    let views = [
        gb.depth.create_view(&wgpu::TextureViewDescriptor {
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        }),
        gb.normal.create_view(&Default::default()),
        surface(&gb.albedo),
        surface(&gb.spec),
        surface(&gb.mat),
    ];
    let mut entries: Vec<wgpu::BindGroupEntry> = views
        .iter()
        .enumerate()
        .map(|(b, v)| wgpu::BindGroupEntry {
            binding: b as u32,
            resource: wgpu::BindingResource::TextureView(v),
        })
        .collect();
    entries.push(wgpu::BindGroupEntry {
        binding: 5,
        resource: buf.as_entire_binding(),
    });
    let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("msaa read"),
        layout: &bgl,
        entries: &entries,
    });
    let mut enc = d.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
    }
    gpu.queue.submit([enc.finish()]);
    gpu.wait()?;
    let raw: Vec<[u32; 12]> = read_vec(gpu, &buf, s * n)?;
    let f = f32::from_bits;
    Ok((0..s)
        .map(|k| {
            let px = &raw[k * n..(k + 1) * n];
            GBuffer {
                width: w,
                height: h,
                depth: px.iter().map(|r| f(r[7])).collect(),
                normal: px
                    .iter()
                    .map(|r| [f(r[0]), f(r[1]), f(r[2]), f(r[3])])
                    .collect(),
                albedo: px.iter().map(|r| [f(r[4]), f(r[5]), f(r[6])]).collect(),
                spec: px.iter().map(|r| [f(r[8]), f(r[9]), f(r[10])]).collect(),
                material: px.iter().map(|r| r[11]).collect(),
            }
        })
        .collect())
}

/// True when pixel `i`'s samples differ in anything the shading reads (the CPU twin of
/// `samples_differ` in paths.wgsl; exact comparisons of the values the shaders load).
pub fn samples_differ(samples: &[GBuffer], i: usize) -> bool {
    let a = &samples[0];
    samples[1..].iter().any(|b| {
        a.depth[i].to_bits() != b.depth[i].to_bits()
            || a.normal[i] != b.normal[i]
            || a.albedo[i] != b.albedo[i]
            || a.spec[i] != b.spec[i]
            || a.material[i] != b.material[i]
    })
}

/// The feature bits of pixel `i` of a multisampled G-buffer: every sample's bits, and
/// [`class::EDGE`] where the samples differ (the CPU twin of the GPU classification).
pub fn pixel_class_ms(setup: &ShadeSetup, samples: &[GBuffer], i: usize) -> u32 {
    let mut bits = samples
        .iter()
        .fold(0, |b, gb| b | pixel_class(setup, gb, i));
    if samples.len() > 1 && samples_differ(samples, i) {
        bits |= class::EDGE;
    }
    bits
}

/// The f64 reference of a multisampled G-buffer: the average of shading each sample (equal to
/// shading once where the samples are equal, which is what the classified path does there).
pub fn reference(setup: &ShadeSetup, samples: &[GBuffer]) -> Vec<[f64; 4]> {
    let per: Vec<Vec<[f64; 4]>> = samples
        .iter()
        .map(|gb| reference::shade(setup, gb))
        .collect();
    let k = per.len() as f64;
    (0..per[0].len())
        .map(|i| std::array::from_fn(|c| per.iter().map(|p| p[i][c]).sum::<f64>() / k))
        .collect()
}
