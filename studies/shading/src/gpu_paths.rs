//! The GPU shading paths of the `deferred` study, all drawing the same HDR image (Rgba32Float)
//! from the same G-buffer (`gbuffer.rs`) with the same light model (`light.wgsl`):
//!
//! | path         | what                                                                     |
//! |--------------|--------------------------------------------------------------------------|
//! | `naive`      | fullscreen pass, every light at every pixel                               |
//! | `volumes`    | base pass (ambient, sun, sky) + one instanced cube per light, additive    |
//! | `tiled`      | compute: per-tile min/max depth, cull into a tile list, shade (tile 8–64) |
//! | `tiled` ×2   | cull_levels = 2: 64×64 tile, then 32×16 sub-tiles (BF3)                   |
//! | `classified` | Split/Second: 4×4 tile ids, count + prefix sum + scatter, one draw per id |
//! | `uber`       | the same tile list drawn with the uber-shader (every feature) in one draw |
//!
//! The classified and uber paths loop over every light (no culling): the comparison isolates
//! what classification saves. With `sun_shadow = taps8` (naive, classified, uber) the sun is
//! shaded through a shadow map (`sun_shadow.rs`): the uber-shader runs the 8-tap filter on every
//! sun-facing pixel, the classified path only in tiles of the fade class. With `msaa = x2`
//! (naive, classified, uber) the G-buffer has 2 samples per pixel (`msaa.rs`; x4: 4): naive and
//! the uber-shader shade every sample of every pixel and average, the classified path only in
//! tiles of the edge class (elsewhere a pixel's samples are equal: it shades sample 0).
//!
//! Split/Second's light-scattering and solid-shadow classes are not built: the chapter's copy
//! (`/work/shared/sources/002_…`, pp. 60–64) gives only the line that sets the scattering bit
//! from the shadow mask's green channel (Listing 4.2) and the `SOLID_SHADOW` define in the
//! uber-shader fragment where the copy ends (Listing 4.7); what sets them and what their
//! permutations shade is on pages it does not have (`scenarios/papers/splitsecond-geg2.toml`,
//! s4-light-scattering-class and s4-solid-shadow-class).

use bench_core::gpu_util::{compute_pipeline, read_vec, storage_entry, texture_entry_ms};
use scenarios::{ParamValue, Scene};
use wgpu::util::DeviceExt;

use super::gbuffer::{read_rgba32f, GBufferPass};
use super::msaa;
use super::sun_shadow::{self, SunShadow};
use super::{class, GBuffer, ShadeSetup, LIGHT_WGSL};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, GpuScene};
use bench_core::timed::{FrameStats, Timed};
use bench_core::timing::GpuTimer;
use bench_core::{CoreError, Result, Unsupported};

pub const PATHS_WGSL: &str = include_str!("paths.wgsl");

/// The paths' WGSL body (after light.wgsl): paths.wgsl and the sun shadow it calls.
pub fn paths_source() -> String {
    format!("{PATHS_WGSL}\n{}", sun_shadow::WGSL)
}

/// [`paths_source`] over a G-buffer of `samples` samples per pixel (> 1: multisampled textures
/// and `SAMPLES` = samples; `textureLoad`'s last argument becomes the sample index).
pub fn paths_source_ms(samples: u32) -> String {
    let mut src = paths_source();
    if samples == 1 {
        return src;
    }
    for (a, b) in [
        (
            "var t_depth: texture_depth_2d;",
            "var t_depth: texture_depth_multisampled_2d;",
        ),
        (
            "var t_normal: texture_2d<f32>;",
            "var t_normal: texture_multisampled_2d<f32>;",
        ),
        (
            "var t_albedo: texture_2d<f32>;",
            "var t_albedo: texture_multisampled_2d<f32>;",
        ),
        (
            "var t_spec: texture_2d<f32>;",
            "var t_spec: texture_multisampled_2d<f32>;",
        ),
        (
            "var t_mat: texture_2d<u32>;",
            "var t_mat: texture_multisampled_2d<u32>;",
        ),
    ] {
        assert!(src.contains(a), "paths.wgsl lost '{a}'");
        src = src.replace(a, b);
    }
    let a = "const SAMPLES: u32 = 1u;";
    assert!(src.contains(a), "paths.wgsl lost '{a}'");
    src.replace(a, &format!("const SAMPLES: u32 = {samples}u;"))
}
pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// Per-tile list capacity when lists are kept for inspection (tests, debug views).
pub const LIST_CAP: u32 = 1024;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    Naive,
    Volumes,
    Tiled { tile: u32, levels: u32 },
    Classified { uber: bool },
}

impl Path {
    pub fn name(&self) -> &'static str {
        match self {
            Path::Naive => "naive",
            Path::Volumes => "volumes",
            Path::Tiled { .. } => "tiled",
            Path::Classified { uber: false } => "classified",
            Path::Classified { uber: true } => "uber",
        }
    }
}

/// Shared shader module and bind groups of the G-buffer inputs.
pub struct ShadeInputs {
    pub module: wgpu::ShaderModule,
    pub bgl0: wgpu::BindGroupLayout,
    pub bgl1: wgpu::BindGroupLayout,
    pub bind0: wgpu::BindGroup,
    pub bind1: Option<wgpu::BindGroup>,
    pub uniform: wgpu::Buffer,
    pub lights: wgpu::Buffer,
}

pub fn module(gpu: &Gpu, label: &str, extra: &str) -> wgpu::ShaderModule {
    gpu.device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(format!("{LIGHT_WGSL}\n{extra}").into()),
        })
}

impl ShadeInputs {
    /// `shadow`: the sun's map and its range map (bindings 4, 5); `None` binds 1×1 stand-ins (the
    /// uniform then says the shadow is off and nothing reads them).
    #[allow(
        clippy::too_many_arguments,
        reason = "every input of the shading pass: set-up, G-buffer, tiles, shadow, allocation count"
    )]
    pub fn new(
        gpu: &Gpu,
        setup: &ShadeSetup,
        gb: &GBufferPass,
        tau: f64,
        tiles: (u32, u32),
        tile: u32,
        shadow: Option<&SunShadow>,
        alloc: &mut AllocCounter,
    ) -> ShadeInputs {
        let d = &gpu.device;
        let all = wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let ff = wgpu::TextureSampleType::Float { filterable: false };
        let ms = gb.samples > 1;
        let gtex = |b, t| texture_entry_ms(b, t, all, ms);
        let bgl0 = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shade inputs"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: all,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                storage_entry(1, true, all),
                gtex(2, wgpu::TextureSampleType::Depth),
                gtex(3, ff),
                texture_entry_ms(4, wgpu::TextureSampleType::Depth, all, false),
                storage_entry(5, true, all),
            ],
        });
        let bgl1 = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shade surface"),
            entries: &[
                gtex(0, ff),
                gtex(1, ff),
                gtex(2, wgpu::TextureSampleType::Uint),
            ],
        });
        let uniform = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shade uniform"),
            contents: bytemuck::bytes_of(&setup.uniform(tau, tiles, tile)),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let mut gl = setup.gpu_lights(tau);
        if gl.is_empty() {
            gl.push(Default::default()); // a zero-size storage binding is invalid; count is 0
        }
        let lights = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lights"),
            contents: bytemuck::cast_slice(&gl),
            usage: wgpu::BufferUsages::STORAGE,
        });
        alloc.bytes += lights.size() + uniform.size();
        let depth_view = gb.depth.create_view(&wgpu::TextureViewDescriptor {
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        });
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let stand_in;
        let stand_in_range;
        let (shadow_tex, shadow_range) = match shadow {
            Some(s) => (&s.texture, &s.range),
            None => {
                stand_in =
                    gpu.stand_in_texture("shadow stand-in", wgpu::TextureFormat::Depth32Float);
                stand_in_range = d.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("shadow range stand-in"),
                    size: 16,
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                });
                (&stand_in, &stand_in_range)
            }
        };
        let bind0 = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shade inputs"),
            layout: &bgl0,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: lights.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&depth_view),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&view(&gb.normal)),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::TextureView(&view(shadow_tex)),
                },
                bge(5, shadow_range),
            ],
        });
        let bind1 = match (&gb.albedo, &gb.spec, &gb.mat) {
            (Some(a), Some(s), Some(m)) => Some(d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shade surface"),
                layout: &bgl1,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&view(a)),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&view(s)),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(&view(m)),
                    },
                ],
            })),
            _ => {
                // Light pre-pass: no surface targets; 1×1 stand-ins keep one layout for all
                // paths (the LIGHT_BUFFER permutations never read them).
                let t = |f| gpu.stand_in_texture("surface stand-in", f);
                let (a, s, m) = (
                    t(wgpu::TextureFormat::Rgba8Unorm),
                    t(wgpu::TextureFormat::Rgba8Unorm),
                    t(wgpu::TextureFormat::R32Uint),
                );
                Some(d.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("surface stand-in"),
                    layout: &bgl1,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: wgpu::BindingResource::TextureView(&view(&a)),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::TextureView(&view(&s)),
                        },
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: wgpu::BindingResource::TextureView(&view(&m)),
                        },
                    ],
                }))
            }
        };
        ShadeInputs {
            module: module(gpu, "shading paths", &paths_source_ms(gb.samples)),
            bgl0,
            bgl1,
            bind0,
            bind1,
            uniform,
            lights,
        }
    }
}

/// Feature bits a scene can show at all: no sun → no SUN ids; a closed room → no SKY ids;
/// no shadow map → no FADE ids; no MSAA → no EDGE ids.
pub fn possible_features(scene: &Scene, shadow: sun_shadow::Mode, ms: msaa::Mode) -> u32 {
    let mut f = class::GEOM | class::SPEC;
    if ms != msaa::Mode::Off {
        f |= class::EDGE;
    }
    if scene.sun.is_some() {
        f |= class::SUN;
        if shadow != sun_shadow::Mode::Off {
            f |= class::FADE;
        }
    }
    let room = matches!(scene.spec.params.get("room"), Some(ParamValue::Bool(true)));
    if !room {
        f |= class::SKY;
    }
    f
}

fn consts(pairs: &[(&'static str, f64)]) -> Vec<(&'static str, f64)> {
    pairs.to_vec()
}

struct Tiled {
    pipeline: wgpu::ComputePipeline,
    bind2: wgpu::BindGroup,
    groups: (u32, u32),
    tile_counts: wgpu::Buffer,
    tile_lists: wgpu::Buffer,
    store_lists: bool,
}

struct Classified {
    classify: wgpu::ComputePipeline,
    offsets: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    draws: Vec<(u32, wgpu::RenderPipeline)>,
    bind_rw: wgpu::BindGroup,
    bind_ro: wgpu::BindGroup,
    counts: wgpu::Buffer,
    cursor: wgpu::Buffer,
    offsets_buf: wgpu::Buffer,
    args: wgpu::Buffer,
    list: wgpu::Buffer,
    tile_class: wgpu::Buffer,
    tiles: (u32, u32),
    uber: bool,
}

struct Raster {
    base: wgpu::RenderPipeline,
    volumes: Option<wgpu::RenderPipeline>,
}

enum Kind {
    Raster(Raster),
    Tiled(Tiled),
    Classified(Classified),
}

/// A deferred path ready to run: G-buffer pass + shading, and its read-backs.
pub struct Deferred {
    pub path: Path,
    pub gbuf: GBufferPass,
    pub inputs: ShadeInputs,
    pub hdr: wgpu::Texture,
    kind: Kind,
    alloc: AllocCounter,
    light_count: u32,
    pub permutations: u32,
    /// The sun's shadow map (`sun_shadow = taps8`), kept for its read-back twin.
    sun: Option<SunShadow>,
}

#[allow(
    clippy::too_many_arguments,
    reason = "a pipeline's layout, shader, entry points, constants, blend and cull, each named"
)]
pub fn render_pipeline(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    vs: &str,
    fs: &str,
    constants: &[(&str, f64)],
    blend: Option<wgpu::BlendState>,
    cull: Option<wgpu::Face>,
) -> wgpu::RenderPipeline {
    let copts = wgpu::PipelineCompilationOptions {
        constants,
        zero_initialize_workgroup_memory: true,
    };
    gpu.device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some(vs),
                compilation_options: copts.clone(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                cull_mode: cull,
                ..Default::default()
            },
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(fs),
                compilation_options: copts,
                targets: &[Some(wgpu::ColorTargetState {
                    format: HDR_FORMAT,
                    blend,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
}

pub fn storage_buf(
    gpu: &Gpu,
    alloc: &mut AllocCounter,
    label: &str,
    size: u64,
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    alloc.buffer(
        gpu,
        label,
        size.max(16),
        wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST
            | extra,
    )
}

pub fn bge(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: b.as_entire_binding(),
    }
}

/// Why a path cannot run here (a `skipped` row), checked before `Deferred::new`.
pub fn supports(gpu: &Gpu, path: Path) -> std::result::Result<(), Unsupported> {
    match path {
        Path::Volumes if !gpu.has(wgpu::Features::FLOAT32_BLENDABLE) => Err(
            "light volumes blend additively into Rgba32Float: adapter lacks FLOAT32_BLENDABLE"
                .into(),
        ),
        Path::Tiled { tile, levels } => {
            if ![8, 16, 32, 64].contains(&tile) {
                return Err(Unsupported::new(format!(
                    "tile_size {tile} is not one of 8, 16, 32, 64"
                )));
            }
            if levels == 2 && tile != 64 {
                return Err(Unsupported::new(format!(
                    "cull_levels = 2 is the BF3 64→32×16 hierarchy: needs tile_size 64, got {tile}"
                )));
            }
            if !(1..=2).contains(&levels) {
                return Err(Unsupported::new(format!(
                    "cull_levels {levels} is not 1 or 2"
                )));
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

impl Deferred {
    pub fn new(
        gpu: &Gpu,
        scene: &Scene,
        gscene: &GpuScene,
        path: Path,
        tau: f64,
        store_lists: bool,
    ) -> Result<Deferred> {
        Self::new_with(
            gpu,
            scene,
            gscene,
            path,
            tau,
            store_lists,
            0.0,
            sun_shadow::Mode::Off,
            msaa::Mode::Off,
        )
    }

    /// [`Deferred::new`] with `diffuse_only_frac` of the lights flagged diffuse-only
    /// ([`ShadeSetup::with_diffuse_only`]) and the sun shaded through a shadow map or not
    /// (rendered here, once, untimed: `sun_shadow.rs`), over a 2×MSAA G-buffer or not
    /// (`msaa.rs`).
    #[allow(
        clippy::too_many_arguments,
        reason = "a deferred path's scene, path and every axis it reads"
    )]
    pub fn new_with(
        gpu: &Gpu,
        scene: &Scene,
        gscene: &GpuScene,
        path: Path,
        tau: f64,
        store_lists: bool,
        diffuse_only_frac: f64,
        shadow: sun_shadow::Mode,
        ms: msaa::Mode,
    ) -> Result<Deferred> {
        supports(gpu, path).map_err(|e| CoreError::Param(e.into()))?;
        if ms != msaa::Mode::Off {
            if !matches!(path, Path::Naive | Path::Classified { .. }) {
                return Err(CoreError::Param(format!(
                    "msaa = {} is built for naive, classified and uber only, not {}",
                    ms.name(),
                    path.name()
                )));
            }
            msaa::supported(gpu, ms).map_err(|e| CoreError::Param(e.into()))?;
            if shadow != sun_shadow::Mode::Off {
                return Err(CoreError::Param(format!(
                    "msaa = {} with sun_shadow = {} is not built (each is tested alone)",
                    ms.name(),
                    shadow.name()
                )));
            }
        }
        if shadow != sun_shadow::Mode::Off && !matches!(path, Path::Naive | Path::Classified { .. })
        {
            return Err(CoreError::Param(format!(
                "sun_shadow = {} is built for naive, classified and uber only, not {}",
                shadow.name(),
                path.name()
            )));
        }
        let d = &gpu.device;
        let (w, h) = (gscene.width, gscene.height);
        let mut alloc = AllocCounter::default();
        let sun = match shadow {
            sun_shadow::Mode::Off => None,
            sun_shadow::Mode::Taps8 => SunShadow::new(gpu, scene, gscene, &mut alloc)?,
        };
        let setup = ShadeSetup::new(scene, w, h)
            .with_diffuse_only(diffuse_only_frac)
            .with_sun_shadow(sun.as_ref().map(|s| s.map.clone()));
        let gbuf = GBufferPass::new_ms(gpu, scene, gscene, false, ms.samples(), &mut alloc);
        let tile = match path {
            Path::Tiled { tile, .. } => tile,
            _ => class::TILE,
        };
        let tiles = (w.div_ceil(tile), h.div_ceil(tile));
        let inputs = ShadeInputs::new(
            gpu,
            &setup,
            &gbuf,
            tau,
            tiles,
            tile,
            sun.as_ref(),
            &mut alloc,
        );
        let hdr = alloc.texture(
            gpu,
            "hdr",
            w,
            h,
            HDR_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let m = &inputs.module;
        let mut permutations = 1;
        let kind = match path {
            Path::Naive | Path::Volumes => {
                let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("raster"),
                    bind_group_layouts: &[Some(&inputs.bgl0), Some(&inputs.bgl1)],
                    immediate_size: 0,
                });
                let vol = path == Path::Volumes;
                let base = render_pipeline(
                    gpu,
                    "base",
                    &layout,
                    m,
                    "vs_fullscreen",
                    "fs_shade",
                    &[("F_LIGHTS", if vol { 0.0 } else { 1.0 })],
                    None,
                    None,
                );
                let add = wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Add,
                };
                let volumes = vol.then(|| {
                    render_pipeline(
                        gpu,
                        "volumes",
                        &layout,
                        m,
                        "vs_volume",
                        "fs_volume",
                        &[],
                        Some(wgpu::BlendState {
                            color: add,
                            alpha: add,
                        }),
                        // Back faces only: each pixel inside the cube's footprint once, also
                        // with the eye inside the cube.
                        Some(wgpu::Face::Front),
                    )
                });
                Kind::Raster(Raster { base, volumes })
            }
            Path::Tiled { tile, levels } => {
                let (bgl2, layout) = tiled_layout(gpu, &inputs, "tiled", HDR_FORMAT);
                let n = (tiles.0 * tiles.1) as u64;
                let tile_counts = storage_buf(
                    gpu,
                    &mut alloc,
                    "tile counts",
                    n * 4,
                    wgpu::BufferUsages::empty(),
                );
                let tile_lists = storage_buf(
                    gpu,
                    &mut alloc,
                    "tile lists",
                    if store_lists {
                        n * LIST_CAP as u64 * 4
                    } else {
                        16
                    },
                    wgpu::BufferUsages::empty(),
                );
                let wg = if tile == 8 { 8 } else { 16 };
                let c = consts(&[
                    ("TILE", tile as f64),
                    ("WG", wg as f64),
                    ("PPT", (tile / wg) as f64),
                    ("STORE_LISTS", if store_lists { 1.0 } else { 0.0 }),
                    ("LIST_CAP", LIST_CAP as f64),
                ]);
                let entry = if levels == 2 { "cs_tiled2" } else { "cs_tiled" };
                let pipeline = compute_pipeline(gpu, "tiled", &layout, m, entry, &c, true);
                let hdr_view = hdr.create_view(&Default::default());
                let bind2 = d.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("tiled"),
                    layout: &bgl2,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: wgpu::BindingResource::TextureView(&hdr_view),
                        },
                        bge(1, &tile_counts),
                        bge(2, &tile_lists),
                    ],
                });
                Kind::Tiled(Tiled {
                    pipeline,
                    bind2,
                    groups: tiles,
                    tile_counts,
                    tile_lists,
                    store_lists,
                })
            }
            Path::Classified { uber } => {
                let cs = wgpu::ShaderStages::COMPUTE;
                let bgl_rw = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("classify"),
                    entries: &(0..6)
                        .map(|b| storage_entry(b, false, cs))
                        .collect::<Vec<_>>(),
                });
                let bgl_ro = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("tile draws"),
                    entries: &[
                        storage_entry(10, true, wgpu::ShaderStages::VERTEX),
                        storage_entry(11, true, wgpu::ShaderStages::VERTEX),
                    ],
                });
                let lc = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("classify"),
                    bind_group_layouts: &[Some(&inputs.bgl0), Some(&inputs.bgl1), Some(&bgl_rw)],
                    immediate_size: 0,
                });
                let ld = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("tile draws"),
                    bind_group_layouts: &[Some(&inputs.bgl0), Some(&inputs.bgl1), Some(&bgl_ro)],
                    immediate_size: 0,
                });
                let ct = (w.div_ceil(class::TILE), h.div_ceil(class::TILE));
                let n = (ct.0 * ct.1) as u64;
                let e = wgpu::BufferUsages::empty();
                let tile_class = storage_buf(gpu, &mut alloc, "tile class", n * 4, e);
                let ids = class::IDS as u64;
                let counts = storage_buf(gpu, &mut alloc, "class counts", ids * 4, e);
                let offsets_buf = storage_buf(gpu, &mut alloc, "class offsets", ids * 4, e);
                let cursor = storage_buf(gpu, &mut alloc, "class cursor", ids * 4, e);
                let args = storage_buf(
                    gpu,
                    &mut alloc,
                    "draw args",
                    ids * 16,
                    wgpu::BufferUsages::INDIRECT,
                );
                let list = storage_buf(gpu, &mut alloc, "tile list", n * 4, e);
                let bind_rw = d.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("classify"),
                    layout: &bgl_rw,
                    entries: &[
                        bge(0, &tile_class),
                        bge(1, &counts),
                        bge(2, &offsets_buf),
                        bge(3, &cursor),
                        bge(4, &args),
                        bge(5, &list),
                    ],
                });
                let bind_ro = d.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("tile draws"),
                    layout: &bgl_ro,
                    entries: &[bge(10, &list), bge(11, &offsets_buf)],
                });
                let classify = compute_pipeline(gpu, "classify", &lc, m, "cs_classify", &[], true);
                let offsets =
                    compute_pipeline(gpu, "class offsets", &lc, m, "cs_offsets", &[], true);
                let scatter =
                    compute_pipeline(gpu, "class scatter", &lc, m, "cs_scatter", &[], true);
                let possible = possible_features(scene, shadow, ms);
                let draws: Vec<(u32, wgpu::RenderPipeline)> = if uber {
                    vec![(
                        class::IDS,
                        render_pipeline(
                            gpu,
                            "uber",
                            &ld,
                            m,
                            "vs_tile",
                            "fs_shade",
                            &[("CLASS_ID", class::IDS as f64)],
                            None,
                            None,
                        ),
                    )]
                } else {
                    // Only ids the scene can produce get a permutation (a scene without sun
                    // or sky compiles and draws none of those).
                    (1..class::IDS)
                        .filter(|&id| class::valid(id) && id & !possible == 0)
                        .map(|id| {
                            let f = |b: u32| if id & b != 0 { 1.0 } else { 0.0 };
                            let p = render_pipeline(
                                gpu,
                                &format!("class {}", class::names(id)),
                                &ld,
                                m,
                                "vs_tile",
                                "fs_shade",
                                &[
                                    ("CLASS_ID", id as f64),
                                    ("F_SKY", f(class::SKY)),
                                    ("F_GEOM", f(class::GEOM)),
                                    ("F_SUN", f(class::SUN)),
                                    ("F_SPEC", f(class::SPEC)),
                                    ("F_SHADOW_FADE", f(class::FADE)),
                                    ("F_EDGE", f(class::EDGE)),
                                ],
                                None,
                                None,
                            );
                            (id, p)
                        })
                        .collect()
                };
                permutations = draws.len() as u32;
                Kind::Classified(Classified {
                    classify,
                    offsets,
                    scatter,
                    draws,
                    bind_rw,
                    bind_ro,
                    counts,
                    cursor,
                    offsets_buf,
                    args,
                    list,
                    tile_class,
                    tiles: ct,
                    uber,
                })
            }
        };
        Ok(Deferred {
            path,
            gbuf,
            inputs,
            hdr,
            kind,
            alloc,
            light_count: setup.lights.len() as u32,
            permutations,
            sun,
        })
    }

    /// Encodes the shading passes (after the G-buffer pass) into `enc`.
    pub fn encode_shading(&self, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) {
        self.encode_shading_labelled(enc, timer, "")
    }

    /// The same, with every pass label prefixed (a second view's passes stay apart).
    pub fn encode_shading_labelled(
        &self,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        prefix: &str,
    ) {
        let inp = &self.inputs;
        let bind1 = inp.bind1.as_ref().expect("deferred has the full G-buffer");
        let hdr_view = self.hdr.create_view(&Default::default());
        let target = |load| {
            [Some(wgpu::RenderPassColorAttachment {
                view: &hdr_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                },
            })]
        };
        match &self.kind {
            Kind::Raster(r) => {
                let att = target(wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT));
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("shade"),
                    color_attachments: &att,
                    depth_stencil_attachment: None,
                    timestamp_writes: timer.render_pass(&format!("{prefix}shade")),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_bind_group(0, &inp.bind0, &[]);
                pass.set_bind_group(1, bind1, &[]);
                pass.set_pipeline(&r.base);
                pass.draw(0..3, 0..1);
                if let Some(v) = &r.volumes {
                    pass.set_pipeline(v);
                    pass.draw(0..36, 0..self.light_count);
                }
            }
            Kind::Tiled(t) => {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("cull+shade"),
                    timestamp_writes: timer.compute_pass(&format!("{prefix}cull+shade")),
                });
                pass.set_pipeline(&t.pipeline);
                pass.set_bind_group(0, &inp.bind0, &[]);
                pass.set_bind_group(1, bind1, &[]);
                pass.set_bind_group(2, &t.bind2, &[]);
                pass.dispatch_workgroups(t.groups.0, t.groups.1, 1);
            }
            Kind::Classified(c) => {
                enc.clear_buffer(&c.counts, 0, None);
                enc.clear_buffer(&c.cursor, 0, None);
                {
                    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("classify"),
                        timestamp_writes: timer.compute_pass(&format!("{prefix}classify")),
                    });
                    pass.set_bind_group(0, &inp.bind0, &[]);
                    pass.set_bind_group(1, bind1, &[]);
                    pass.set_bind_group(2, &c.bind_rw, &[]);
                    pass.set_pipeline(&c.classify);
                    pass.dispatch_workgroups(c.tiles.0.div_ceil(8), c.tiles.1.div_ceil(8), 1);
                    pass.set_pipeline(&c.offsets);
                    pass.dispatch_workgroups(1, 1, 1);
                    pass.set_pipeline(&c.scatter);
                    pass.dispatch_workgroups((c.tiles.0 * c.tiles.1).div_ceil(64), 1, 1);
                }
                let att = target(wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT));
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("tile draws"),
                    color_attachments: &att,
                    depth_stencil_attachment: None,
                    timestamp_writes: timer.render_pass(&format!("{prefix}tile draws")),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_bind_group(0, &inp.bind0, &[]);
                pass.set_bind_group(1, bind1, &[]);
                pass.set_bind_group(2, &c.bind_ro, &[]);
                for (id, p) in &c.draws {
                    pass.set_pipeline(p);
                    if c.uber {
                        pass.draw(0..6, 0..c.tiles.0 * c.tiles.1);
                    } else {
                        pass.draw_indirect(&c.args, *id as u64 * 16);
                    }
                }
            }
        }
    }

    /// The read-back sun shadow map this path shades with (the reference's input).
    pub fn sun_shadow_map(&self) -> Option<std::sync::Arc<sun_shadow::ShadowMap>> {
        self.sun.as_ref().map(|s| s.map.clone())
    }

    pub fn read_image(&self, gpu: &Gpu) -> Result<Vec<[f32; 4]>> {
        read_rgba32f(gpu, &self.hdr)
    }

    /// The G-buffer (its sample 0 when multisampled).
    pub fn read_gbuffer(&self, gpu: &Gpu) -> Result<GBuffer> {
        Ok(msaa::read_samples(gpu, &self.gbuf)?.swap_remove(0))
    }

    /// Every sample's G-buffer (one without MSAA): the MSAA reference's input.
    pub fn read_samples(&self, gpu: &Gpu) -> Result<Vec<GBuffer>> {
        msaa::read_samples(gpu, &self.gbuf)
    }

    /// Tiled: lights kept per tile (before the list cap), tiles row-major.
    pub fn tile_counts(&self, gpu: &Gpu) -> Result<Option<Vec<u32>>> {
        match &self.kind {
            Kind::Tiled(t) => {
                let n = (t.groups.0 * t.groups.1) as usize;
                Ok(Some(read_vec(gpu, &t.tile_counts, n)?))
            }
            _ => Ok(None),
        }
    }

    /// Tiled with `store_lists`: the light list of every tile (at most LIST_CAP kept).
    pub fn tile_lists(&self, gpu: &Gpu) -> Result<Option<Vec<Vec<u32>>>> {
        match &self.kind {
            Kind::Tiled(t) if t.store_lists => {
                let n = (t.groups.0 * t.groups.1) as usize;
                let counts: Vec<u32> = read_vec(gpu, &t.tile_counts, n)?;
                let all: Vec<u32> = read_vec(gpu, &t.tile_lists, n * LIST_CAP as usize)?;
                Ok(Some(
                    (0..n)
                        .map(|i| {
                            let c = counts[i].min(LIST_CAP) as usize;
                            let base = i * LIST_CAP as usize;
                            all[base..base + c].to_vec()
                        })
                        .collect(),
                ))
            }
            _ => Ok(None),
        }
    }

    /// Classified: (id per 4×4 tile, count per id, offset per id, the scattered tile list).
    #[allow(
        clippy::type_complexity,
        reason = "the four read-back arrays of the classification, in pass order"
    )]
    pub fn classification(
        &self,
        gpu: &Gpu,
    ) -> Result<Option<(Vec<u32>, Vec<u32>, Vec<u32>, Vec<u32>)>> {
        match &self.kind {
            Kind::Classified(c) => {
                let n = (c.tiles.0 * c.tiles.1) as usize;
                Ok(Some((
                    read_vec(gpu, &c.tile_class, n)?,
                    read_vec(gpu, &c.counts, class::IDS as usize)?,
                    read_vec(gpu, &c.offsets_buf, class::IDS as usize)?,
                    read_vec(gpu, &c.list, n)?,
                )))
            }
            _ => Ok(None),
        }
    }

    pub fn class_tiles(&self) -> Option<(u32, u32)> {
        match &self.kind {
            Kind::Classified(c) => Some(c.tiles),
            _ => None,
        }
    }
}

impl Timed for Deferred {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        self.gbuf.encode(&mut enc, scene, timer, "gbuffer");
        self.encode_shading(&mut enc, timer);
        gpu.queue.submit([enc.finish()]);
        Ok(FrameStats {
            geometry_passes: 1,
            layers: 1,
        })
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }

    /// Render-target traffic, one touch per pixel (as the prepass study's `bytes_rt_*`): the
    /// G-buffer written and read once (every sample), the HDR colour written.
    fn bytes_moved(&self) -> u64 {
        let px = self.hdr.width() as u64 * self.hdr.height() as u64;
        let s = self.gbuf.samples as u64;
        px * (2 * s * super::gbuffer::FULL_BYTES_PER_PIXEL + 16)
    }
}

/// The tiled kernels' group 2 (the output storage texture, tile light counts and lists) and the
/// pipeline layout over the shared G-buffer inputs (groups 0 and 1).
pub fn tiled_layout(
    gpu: &Gpu,
    inputs: &ShadeInputs,
    label: &str,
    format: wgpu::TextureFormat,
) -> (wgpu::BindGroupLayout, wgpu::PipelineLayout) {
    let d = &gpu.device;
    let bgl2 = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::StorageTexture {
                    access: wgpu::StorageTextureAccess::WriteOnly,
                    format,
                    view_dimension: wgpu::TextureViewDimension::D2,
                },
                count: None,
            },
            storage_entry(1, false, wgpu::ShaderStages::COMPUTE),
            storage_entry(2, false, wgpu::ShaderStages::COMPUTE),
        ],
    });
    let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(&inputs.bgl0), Some(&inputs.bgl1), Some(&bgl2)],
        immediate_size: 0,
    });
    (bgl2, layout)
}
