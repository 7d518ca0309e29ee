//! The GPU side: layered soft shadow maps as a [`Timed`] frame, so `measure` times it like
//! every other study's (its `prepare_ssm` builds everything, its `frame` only encodes and
//! submits). Not a [`crate::methods::Method`]: it captures no fragments.
//!
//! Passes per frame (labels in `pass_ms`): `sm_peel` ×k (depth peeling from the light's centre,
//! one geometry pass per layer), `sm_pack` (k layers → one RGBA32F texel, plus slopes and the
//! pyramid's base), `hsm_build` (min pyramid, one dispatch per level), `gbuffer` (eye positions),
//! `shade` (search, HSM, backprojection per pixel). The shading is a compute pass, not a
//! fullscreen fragment pass: it is a pure per-pixel gather with a data-dependent loop (up to
//! max_nspp samples × k layers), needs no raster state or derivatives (slopes were taken at peel
//! time), and writes its f32 visibility straight into a storage buffer that is read back exactly.

use bench_core::gpu_util::{
    camera_entry, clear_depth, depth_state, read_vec, shader, storage_entry, texture_entry,
};
use std::sync::{Arc, Mutex};

use bytemuck::{Pod, Zeroable};
use scenarios::AreaLight;
use wgpu::util::DeviceExt;

use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, CameraUniform, GpuScene};

use bench_core::axes::{Axis, Point};
use bench_core::record::cols;
use bench_core::timed::{FrameStats, Timed};
use bench_core::timing::GpuTimer;
use bench_core::{Result, Unsupported};

use super::twin::LightUniform;

const WGSL: &str = include_str!("shadows.wgsl");
const LAYER_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
const PACKED_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const GBUFFER_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// Matches `FAR` in shadows.wgsl: the clear value of an empty layer texel.
const FAR: f64 = 1.0e30;
/// Pyramid levels the uniform can address (a 32768² map needs 16).
const MAX_LEVELS: u32 = 16;

pub const BIAS_MODES: &[&str] = &["midpoint", "slope", "hybrid"];
/// Where the search region starts (§5.3.2): `near` is the thesis's initial region kr(n);
/// `global_min` is mfx's first choice, kr of the pyramid's global minimum with a lit early-out.
pub const SEARCH_STARTS: &[&str] = &["near", "global_min"];

/// One sweep point's settings, read from its axes with defaults and ranges.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    pub shadow_map_res: u32,
    pub layers: u32,
    pub max_nspp: u32,
    pub bias_mode: String,
    pub gscale: f64,
    pub gmax: f64,
    pub hsm: bool,
    pub search_start: String,
    pub bias_max: f64,
}

const SHADOW_MAP_RES: Axis = Axis::int(
    cols::SHADOW_MAP_RES,
    "shadow map side in texels",
    512,
    8,
    16384,
);
// Four depths fill one RGBA32F texel: the single-fetch layout caps k at 4.
const LAYERS: Axis = Axis::int(
    cols::LAYERS,
    "depth layers peeled into the shadow map (k ≤ 4)",
    3,
    1,
    4,
);
const MAX_NSPP: Axis = Axis::int(
    cols::MAX_NSPP,
    "most shadow-map samples per pixel",
    289,
    1,
    65536,
);
const BIAS_MODE: Axis = Axis::choice(cols::BIAS_MODE, "depth bias rule", "hybrid", BIAS_MODES);
const GSCALE: Axis = Axis::float(cols::GSCALE, "gradient bias scale", 2.0, 0.0, 1e6);
const GMAX: Axis = Axis::float(cols::GMAX, "gradient bias cap", 0.1, 0.0, 1e6);
const HSM: Axis = Axis::bool(
    cols::HSM,
    "hierarchical min pyramid to shrink the search region",
    true,
);

// §5.3.2: "The initial search region is the intersection of the light plane with the shadow
// frustum from the shading point to the square light ... The width (in pixels) of the region is
// kr(n)". The default stays mfx's first choice so the CI suites' rows are unchanged; the
// seeds-shadows suite names `near`, the thesis's.
const SEARCH_START: Axis = Axis::choice(
    cols::SEARCH_START,
    "where the search region starts: near (kr(n)) or global_min (the pyramid's top)",
    "global_min",
    SEARCH_STARTS,
);
// §5.2.2: midpoints bleed "when the midpoint and the original point are too far away. This can
// be fixed using a maximum depth bias". 0 keeps mfx's first choice (no maximum).
const BIAS_MAX: Axis = Axis::float(
    cols::BIAS_MAX,
    "maximum midpoint bias, world units (0 = none)",
    0.0,
    0.0,
    1e6,
);

/// The axes of a layered soft shadow map point, declared.
pub const AXES: &[Axis] = &[
    SHADOW_MAP_RES,
    LAYERS,
    MAX_NSPP,
    BIAS_MODE,
    GSCALE,
    GMAX,
    HSM,
    SEARCH_START,
    BIAS_MAX,
];

impl Config {
    pub fn from_point(p: &Point) -> Config {
        Config {
            shadow_map_res: p.int(&SHADOW_MAP_RES) as u32,
            layers: p.int(&LAYERS) as u32,
            max_nspp: p.int(&MAX_NSPP) as u32,
            bias_mode: p.choice(&BIAS_MODE),
            gscale: p.float(&GSCALE),
            gmax: p.float(&GMAX),
            hsm: p.bool(&HSM),
            search_start: p.choice(&SEARCH_START),
            bias_max: p.float(&BIAS_MAX),
        }
    }

    /// Samples per axis of the search region: floor(sqrt(max_nspp)).
    pub fn samples_per_axis(&self) -> u32 {
        ((self.max_nspp as f64).sqrt().floor() as u32).max(1)
    }

    fn bias_code(&self) -> u32 {
        BIAS_MODES
            .iter()
            .position(|m| *m == self.bias_mode)
            .unwrap_or(2) as u32
    }

    /// The shader's `cfg.w`: bit 0 the HSM, bit 1 the global-minimum start.
    fn search_flags(&self) -> u32 {
        self.hsm as u32 | ((self.search_start == "global_min") as u32) << 1
    }

    /// Pyramid levels above the base: the top one is 1×1.
    pub fn top_level(&self) -> u32 {
        let mut l = 0;
        while (self.shadow_map_res + (1 << l) - 1) >> l > 1 {
            l += 1;
        }
        l
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ReduceUniform {
    level: u32,
    size: u32,
    src_size: u32,
    pad: u32,
}

/// Layered soft shadow maps for one scene's area light.
pub struct LayeredSsm {
    pub light: AreaLight,
    /// Compiled on the first `prepare` and shared by every later one (same device, same scene).
    pipelines: Mutex<Option<Arc<Pipelines>>>,
}

/// Bavoil 2007 ch. 5: k depth-peeled light layers, HSM search region, backprojection;
/// approximate.
impl LayeredSsm {
    /// The declared axes of a configuration.
    pub fn axes(&self) -> Vec<Axis> {
        AXES.to_vec()
    }
    /// Whether this configuration can run on this adapter; `Err(reason)`: a `skipped` row.
    pub fn supports(&self, gpu: &Gpu, point: &Point) -> std::result::Result<(), Unsupported> {
        let c = Config::from_point(point);
        let max = gpu.limits.max_texture_dimension_2d;
        if c.shadow_map_res > max {
            return Err(Unsupported::new(format!(
                "shadow_map_res {} exceeds this adapter's max texture size {max}",
                c.shadow_map_res
            )));
        }
        if c.top_level() >= MAX_LEVELS {
            return Err(Unsupported::new(format!(
                "shadow_map_res {} needs more than {MAX_LEVELS} pyramid levels",
                c.shadow_map_res
            )));
        }
        for f in [LAYER_FORMAT, GBUFFER_FORMAT] {
            if !gpu.renderable(f) {
                return Err(Unsupported::new(format!(
                    "{f:?} is not renderable on this adapter"
                )));
            }
        }
        if !gpu
            .adapter
            .get_texture_format_features(PACKED_FORMAT)
            .allowed_usages
            .contains(wgpu::TextureUsages::STORAGE_BINDING)
        {
            return Err(Unsupported::new(format!(
                "{PACKED_FORMAT:?} storage textures are not supported"
            )));
        }
        Ok(())
    }
}

impl LayeredSsm {
    pub fn new(light: AreaLight) -> Self {
        LayeredSsm {
            light,
            pipelines: Mutex::new(None),
        }
    }

    /// Creates every GPU object of one configuration (never inside a timed region).
    pub fn prepare_ssm(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<PreparedSsm> {
        let cfg = Config::from_point(point);
        let pipes = {
            let mut cached = self.pipelines.lock().unwrap();
            match &*cached {
                Some(p) if p.reversed_z == scene.reversed_z => p.clone(),
                _ => {
                    let p = Arc::new(Pipelines::new(gpu, scene.reversed_z));
                    *cached = Some(p.clone());
                    p
                }
            }
        };
        Ok(PreparedSsm::new(gpu, scene, &self.light, cfg, pipes))
    }
}

/// Shader, layouts and pipelines: the same for every configuration (the configuration lives in
/// uniforms), so one set is compiled per scene group and shared by all its points.
pub struct Pipelines {
    reversed_z: bool,
    cam_bgl: wgpu::BindGroupLayout,
    prev_bgl: wgpu::BindGroupLayout,
    light_bgl: wgpu::BindGroupLayout,
    pack_bgl: wgpu::BindGroupLayout,
    reduce_bgl: wgpu::BindGroupLayout,
    shade_bgl: wgpu::BindGroupLayout,
    peel_first: wgpu::RenderPipeline,
    peel: wgpu::RenderPipeline,
    gbuffer: wgpu::RenderPipeline,
    pack: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
    export: wgpu::ComputePipeline,
}

pub struct PreparedSsm {
    cfg: Config,
    pipes: Arc<Pipelines>,
    light_cam_bg: wgpu::BindGroup,
    eye_cam_bg: wgpu::BindGroup,
    prev_bg: Vec<wgpu::BindGroup>,
    light_bg: wgpu::BindGroup,
    pack_bg: wgpu::BindGroup,
    reduce_bg: Vec<(wgpu::BindGroup, u32)>,
    shade_bg: wgpu::BindGroup,
    layer_views: Vec<wgpu::TextureView>,
    sm_depth: wgpu::TextureView,
    gbuffer_view: wgpu::TextureView,
    eye_depth: wgpu::TextureView,
    visibility: wgpu::Buffer,
    points: wgpu::Buffer,
    packed_tex: [wgpu::Texture; 2],
    pyramid: wgpu::Buffer,
    light_uniform: LightUniform,
    reversed: bool,
    alloc: AllocCounter,
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn storage_texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format: PACKED_FORMAT,
            view_dimension: wgpu::TextureViewDimension::D2,
        },
        count: None,
    }
}

fn entry(binding: u32, resource: wgpu::BindingResource<'_>) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource }
}

impl Pipelines {
    fn new(gpu: &Gpu, reversed_z: bool) -> Self {
        let d = &gpu.device;
        let module = shader(gpu, "layered_ssm", WGSL);
        let comp = wgpu::ShaderStages::COMPUTE;
        let nf = wgpu::TextureSampleType::Float { filterable: false };
        let bgl = |label: &str, entries: &[wgpu::BindGroupLayoutEntry]| {
            d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            })
        };
        let cam_bgl = bgl("ssm camera", &[camera_entry(0)]);
        let prev_bgl = bgl(
            "ssm prev layer",
            &[texture_entry(0, nf, wgpu::ShaderStages::FRAGMENT)],
        );
        let light_bgl = bgl(
            "ssm light",
            &[uniform_entry(1), storage_entry(2, false, comp)],
        );
        let pack_bgl = bgl(
            "ssm pack",
            &[
                texture_entry(0, nf, comp),
                texture_entry(1, nf, comp),
                texture_entry(2, nf, comp),
                texture_entry(3, nf, comp),
                storage_texture_entry(4),
                storage_texture_entry(5),
            ],
        );
        let reduce_bgl = bgl("ssm reduce", &[uniform_entry(6)]);
        let shade_bgl = bgl(
            "ssm shade",
            &[
                texture_entry(7, nf, comp),
                texture_entry(8, nf, comp),
                texture_entry(9, nf, comp),
                storage_entry(10, false, comp),
                storage_entry(11, false, comp),
            ],
        );
        let layout = |label: &str, groups: &[&wgpu::BindGroupLayout]| {
            let g: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().map(|b| Some(*b)).collect();
            d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &g,
                immediate_size: 0,
            })
        };
        let peel_layout = layout("ssm peel", &[&cam_bgl, &prev_bgl]);
        let gbuffer_layout = layout("ssm gbuffer", &[&cam_bgl]);
        let pack_layout = layout("ssm pack", &[&cam_bgl, &light_bgl, &pack_bgl]);
        let reduce_layout = layout("ssm reduce", &[&cam_bgl, &light_bgl, &reduce_bgl]);
        let shade_layout = layout("ssm shade", &[&cam_bgl, &light_bgl, &shade_bgl]);

        let all_layouts: Vec<_> = GpuScene::layouts(Attrs::ALL)
            .into_iter()
            .map(Some)
            .collect();
        let pos_layouts: Vec<_> = GpuScene::layouts(Attrs::POSITION_ONLY)
            .into_iter()
            .map(Some)
            .collect();
        let peel_targets = [Some(wgpu::ColorTargetState {
            format: LAYER_FORMAT,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let make_peel = |peel: bool| {
            let constants = [("PEEL", if peel { 1.0 } else { 0.0 })];
            d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(if peel { "ssm peel" } else { "ssm first layer" }),
                layout: Some(&peel_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_full"),
                    compilation_options: Default::default(),
                    buffers: &all_layouts,
                },
                // No culling: thin occluders cast shadows from both faces.
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(depth_state(false, true)),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_peel"),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        zero_initialize_workgroup_memory: false,
                    },
                    targets: &peel_targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let peel_first = make_peel(false);
        let peel = make_peel(true);
        let gbuffer = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("ssm gbuffer"),
            layout: Some(&gbuffer_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_world"),
                compilation_options: Default::default(),
                buffers: &pos_layouts,
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(depth_state(reversed_z, true)),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_gbuffer"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: GBUFFER_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let compute = |label: &str, layout: &wgpu::PipelineLayout, entry: &str| {
            d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let pack = compute("ssm pack", &pack_layout, "pack");
        let reduce = compute("ssm reduce", &reduce_layout, "hsm_reduce");
        let shade = compute("ssm shade", &shade_layout, "shade");
        let export = compute("ssm export", &shade_layout, "export_points");

        Pipelines {
            reversed_z,
            cam_bgl,
            prev_bgl,
            light_bgl,
            pack_bgl,
            reduce_bgl,
            shade_bgl,
            peel_first,
            peel,
            gbuffer,
            pack,
            reduce,
            shade,
            export,
        }
    }
}

impl PreparedSsm {
    fn new(
        gpu: &Gpu,
        scene: &GpuScene,
        light: &AreaLight,
        cfg: Config,
        pipes: Arc<Pipelines>,
    ) -> Self {
        let d = &gpu.device;
        let r = cfg.shadow_map_res;
        let (w, h) = (scene.width, scene.height);
        let p = &*pipes;
        let (cam_bgl, prev_bgl, light_bgl, pack_bgl, reduce_bgl, shade_bgl) = (
            &p.cam_bgl,
            &p.prev_bgl,
            &p.light_bgl,
            &p.pack_bgl,
            &p.reduce_bgl,
            &p.shade_bgl,
        );
        // ---- resources ----
        let mut alloc = AllocCounter::default();
        let rt = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let layer_views: Vec<wgpu::TextureView> = (0..cfg.layers)
            .map(|j| {
                alloc
                    .texture(gpu, &format!("ssm layer {j}"), r, r, LAYER_FORMAT, rt)
                    .create_view(&Default::default())
            })
            .collect();
        // Bound where a layer is absent (k < 4, and the first pass's unused "previous" layer).
        let dummy = gpu
            .stand_in_texture("ssm dummy layer", LAYER_FORMAT)
            .create_view(&Default::default());
        let sm_depth = alloc
            .texture(
                gpu,
                "ssm depth",
                r,
                r,
                wgpu::TextureFormat::Depth32Float,
                rt,
            )
            .create_view(&Default::default());
        // COPY_SRC: the CPU twin's test reads the packed maps back.
        let st = wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let packed_tex = [
            alloc.texture(gpu, "ssm packed depths", r, r, PACKED_FORMAT, st),
            alloc.texture(gpu, "ssm packed slopes", r, r, PACKED_FORMAT, st),
        ];
        let packed_depth = packed_tex[0].create_view(&Default::default());
        let packed_slope = packed_tex[1].create_view(&Default::default());
        let top = cfg.top_level();
        let mut offsets = [[0u32; 4]; 4];
        let mut total = 0u32;
        for l in 0..=top {
            offsets[(l / 4) as usize][(l % 4) as usize] = total;
            let s = (r + (1 << l) - 1) >> l;
            total += s * s;
        }
        let sb = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let pyramid = alloc.buffer(gpu, "ssm pyramid", total as u64 * 4, sb);
        let gbuffer_view = alloc
            .texture(gpu, "ssm gbuffer", w, h, GBUFFER_FORMAT, rt)
            .create_view(&Default::default());
        let eye_depth = alloc
            .texture(
                gpu,
                "ssm eye depth",
                w,
                h,
                wgpu::TextureFormat::Depth32Float,
                rt,
            )
            .create_view(&Default::default());
        let px = (w * h) as u64;
        let visibility = alloc.buffer(gpu, "ssm visibility", px * 4, sb);
        // Harness-only (the reference's start points): not charged to the method.
        let points = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ssm points"),
            size: px * 16,
            usage: sb,
            mapped_at_creation: false,
        });

        let cam = &light.camera;
        let light_cam = CameraUniform {
            clip_from_world: cam.clip_from_world_gpu(1.0).to_cols_array_2d(),
            view_from_world: cam.view().as_mat4().to_cols_array_2d(),
            viewport: [r as f32, r as f32, 1.0 / r as f32, 1.0 / r as f32],
            near_far: [cam.near as f32, cam.far as f32, 0.0, 1.0],
        };
        let light_cam_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ssm light camera"),
            contents: bytemuck::bytes_of(&light_cam),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let lu = LightUniform {
            view_from_world: light_cam.view_from_world,
            map: [
                r as f32,
                cam.near as f32,
                (1.0 / (cam.fovy * 0.5).tan()) as f32,
                light.size as f32,
            ],
            cfg: [
                cfg.layers,
                cfg.samples_per_axis(),
                cfg.bias_code(),
                cfg.search_flags(),
            ],
            bias: [
                cfg.gscale as f32,
                cfg.gmax as f32,
                top as f32,
                cfg.bias_max as f32,
            ],
            level_offset: offsets,
        };
        let light_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ssm light"),
            contents: bytemuck::bytes_of(&lu),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bg = |label: &str, layout: &wgpu::BindGroupLayout, entries: &[wgpu::BindGroupEntry]| {
            d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout,
                entries,
            })
        };
        let light_cam_bg = bg(
            "ssm light camera",
            cam_bgl,
            &[entry(0, light_cam_buf.as_entire_binding())],
        );
        let eye_cam_bg = bg(
            "ssm eye camera",
            cam_bgl,
            &[entry(0, scene.camera.as_entire_binding())],
        );
        let prev_bg = (0..cfg.layers as usize)
            .map(|j| {
                let v = if j == 0 { &dummy } else { &layer_views[j - 1] };
                bg(
                    "ssm prev layer",
                    prev_bgl,
                    &[entry(0, wgpu::BindingResource::TextureView(v))],
                )
            })
            .collect();
        let light_bg = bg(
            "ssm light",
            light_bgl,
            &[
                entry(1, light_buf.as_entire_binding()),
                entry(2, pyramid.as_entire_binding()),
            ],
        );
        let layer_or_dummy = |j: usize| layer_views.get(j).unwrap_or(&dummy);
        let pack_bg = bg(
            "ssm pack",
            pack_bgl,
            &[
                entry(0, wgpu::BindingResource::TextureView(layer_or_dummy(0))),
                entry(1, wgpu::BindingResource::TextureView(layer_or_dummy(1))),
                entry(2, wgpu::BindingResource::TextureView(layer_or_dummy(2))),
                entry(3, wgpu::BindingResource::TextureView(layer_or_dummy(3))),
                entry(4, wgpu::BindingResource::TextureView(&packed_depth)),
                entry(5, wgpu::BindingResource::TextureView(&packed_slope)),
            ],
        );
        let reduce_bg = (1..=top)
            .map(|l| {
                let size = (r + (1 << l) - 1) >> l;
                let src_size = (r + (1 << (l - 1)) - 1) >> (l - 1);
                let u = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("ssm reduce level"),
                    contents: bytemuck::bytes_of(&ReduceUniform {
                        level: l,
                        size,
                        src_size,
                        pad: 0,
                    }),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                (
                    bg("ssm reduce", reduce_bgl, &[entry(6, u.as_entire_binding())]),
                    size,
                )
            })
            .collect();
        let shade_bg = bg(
            "ssm shade",
            shade_bgl,
            &[
                entry(7, wgpu::BindingResource::TextureView(&gbuffer_view)),
                entry(8, wgpu::BindingResource::TextureView(&packed_depth)),
                entry(9, wgpu::BindingResource::TextureView(&packed_slope)),
                entry(10, visibility.as_entire_binding()),
                entry(11, points.as_entire_binding()),
            ],
        );
        PreparedSsm {
            cfg,
            pipes,
            light_cam_bg,
            eye_cam_bg,
            prev_bg,
            light_bg,
            pack_bg,
            reduce_bg,
            shade_bg,
            layer_views,
            sm_depth,
            gbuffer_view,
            eye_depth,
            visibility,
            points,
            packed_tex,
            pyramid,
            light_uniform: lu,
            reversed: scene.reversed_z,
            alloc,
        }
    }

    /// The eye's G-buffer world positions (None where no surface), after at least one frame.
    pub fn read_points(&self, gpu: &Gpu, scene: &GpuScene) -> Result<Vec<Option<[f32; 3]>>> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipes.export);
            pass.set_bind_group(0, &self.eye_cam_bg, &[]);
            pass.set_bind_group(1, &self.light_bg, &[]);
            pass.set_bind_group(2, &self.shade_bg, &[]);
            pass.dispatch_workgroups(scene.width.div_ceil(8), scene.height.div_ceil(8), 1);
        }
        gpu.queue.submit([enc.finish()]);
        let pts = read_vec::<[f32; 4]>(gpu, &self.points, scene.pixels())?;
        Ok(pts
            .into_iter()
            .map(|p| (p[3] != 0.0).then_some([p[0], p[1], p[2]]))
            .collect())
    }

    /// Visibility per pixel in [0, 1], or −1 where the point could not be evaluated.
    pub fn read_visibility(&self, gpu: &Gpu, scene: &GpuScene) -> Result<Vec<f32>> {
        read_vec::<f32>(gpu, &self.visibility, scene.pixels())
    }

    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// The shading inputs as the GPU holds them after a frame, for the CPU twin.
    pub fn read_maps(&self, gpu: &Gpu) -> Result<super::twin::Maps> {
        let mut out = Vec::new();
        for tex in &self.packed_tex {
            out.push(bench_core::gpu::read_rgba32f(gpu, tex)?);
        }
        let pyramid = read_vec::<f32>(gpu, &self.pyramid, (self.pyramid.size() / 4) as usize)?;
        let slope = out.pop().unwrap_or_default();
        let depth = out.pop().unwrap_or_default();
        Ok(super::twin::Maps {
            light: self.light_uniform,
            depth,
            slope,
            pyramid,
        })
    }
}

impl Timed for PreparedSsm {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let r = self.cfg.shadow_map_res;
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        for (j, view) in self.layer_views.iter().enumerate() {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("sm_peel"),
                color_attachments: &[bench_core::gpu::cleared(
                    view,
                    wgpu::Color {
                        r: FAR,
                        g: 0.0,
                        b: 0.0,
                        a: 0.0,
                    },
                )],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.sm_depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.render_pass("sm_peel"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(if j == 0 {
                &self.pipes.peel_first
            } else {
                &self.pipes.peel
            });
            pass.set_bind_group(0, &self.light_cam_bg, &[]);
            pass.set_bind_group(1, &self.prev_bg[j], &[]);
            scene.draw(&mut pass, Attrs::ALL);
        }
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("sm_pack"),
                timestamp_writes: timer.compute_pass("sm_pack"),
            });
            pass.set_pipeline(&self.pipes.pack);
            pass.set_bind_group(0, &self.eye_cam_bg, &[]);
            pass.set_bind_group(1, &self.light_bg, &[]);
            pass.set_bind_group(2, &self.pack_bg, &[]);
            pass.dispatch_workgroups(r.div_ceil(8), r.div_ceil(8), 1);
        }
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("hsm_build"),
                timestamp_writes: timer.compute_pass("hsm_build"),
            });
            pass.set_pipeline(&self.pipes.reduce);
            pass.set_bind_group(0, &self.eye_cam_bg, &[]);
            pass.set_bind_group(1, &self.light_bg, &[]);
            for (bgr, size) in &self.reduce_bg {
                pass.set_bind_group(2, bgr, &[]);
                pass.dispatch_workgroups(size.div_ceil(8), size.div_ceil(8), 1);
            }
        }
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("gbuffer"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.gbuffer_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.eye_depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear_depth(self.reversed)),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.render_pass("gbuffer"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipes.gbuffer);
            pass.set_bind_group(0, &self.eye_cam_bg, &[]);
            scene.draw(&mut pass, Attrs::POSITION_ONLY);
        }
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("shade"),
                timestamp_writes: timer.compute_pass("shade"),
            });
            pass.set_pipeline(&self.pipes.shade);
            pass.set_bind_group(0, &self.eye_cam_bg, &[]);
            pass.set_bind_group(1, &self.light_bg, &[]);
            pass.set_bind_group(2, &self.shade_bg, &[]);
            pass.dispatch_workgroups(scene.width.div_ceil(8), scene.height.div_ceil(8), 1);
        }
        gpu.queue.submit([enc.finish()]);
        Ok(FrameStats {
            geometry_passes: self.cfg.layers + 1,
            layers: self.cfg.layers,
        })
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }
}
