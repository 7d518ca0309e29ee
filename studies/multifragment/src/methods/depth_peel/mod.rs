//! Classic depth peeling (Everitt 2001, "Interactive Order-Independent Transparency"): the exact
//! baseline. One geometry pass per layer, front to back; after each, a compute pass feeds the
//! layer's fragments to the effects fold (`effects.wgsl`), whose per-pixel `FoldState` (64 B)
//! stays in a storage buffer between passes, so depth peeling supplies every effect. With
//! `occlusion_stop` (default) an occlusion query per pass ends peeling at the first pass that
//! writes nothing (a CPU round trip per pass, as in the original); otherwise exactly
//! `max_layers` passes run in one submission.
//!
//! Axes: `max_layers`, `occlusion_stop`, the effect axes (`effects::AXES`, incl. `thickness`),
//! `specialisation` (`specialised`, default: store, fetch and read only the effect's payload;
//! `uber`: all attributes fetched and colour + normal + view depth + id stored every pass) and
//! `tiebreak` (peel on (depth, object id) pairs so coplanar fragments with distinct ids are not
//! lost, at the cost of the full payload).
//!
//! Antialiasing (`aa`): MSAA peels every sample (`aa_capture = sample` only: each sample's depth
//! is compared with the previous layer's at that sample, so the fragment stage runs per sample);
//! the depth, layer and id targets are multisampled, the fold keeps one state per sample (64 B ×
//! samples) and its end averages the samples' images. `ssaa2x2` peels at twice the width and
//! height and box-filters.

use super::shared::axes::{MAX_LAYERS, OCCLUSION_STOP, SPECIALISATION};
use super::{Capture, Expected, FrameStats, Method, Prepared};
use crate::aa::{self, AaConfig, AaMode, AaSupport};
use crate::effects::{self, EffectConfig, Payload};
use crate::effects::{FOLD_STATE_BYTES, FOLD_WGSL};
use bench_core::axes::{Axis, Point};
use bench_core::bind::{
    pipeline_layout, render_pipeline, Bindings, Kind as B, Raster, Res, DEPTH, FLOAT, UINT,
};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};
use bench_core::gpu_util::{
    clear_depth, compute_pipeline, depth_state, per_sample_source, read_vec, shader_source,
    COMMON_WGSL, STORAGE_RW,
};
use bench_core::record::cols;
use bench_core::study::InvalidPoint;
use bench_core::timing::GpuTimer;
use bench_core::Result;

const WGSL: &str = include_str!("depth_peel.wgsl");
const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const Z_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
const ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

pub struct DepthPeel;

const TIEBREAK: Axis = Axis::bool(
    cols::TIEBREAK,
    "peel (depth, object id) pairs so coplanar fragments of distinct objects are kept",
    false,
);

const AA_SUPPORT: AaSupport = AaSupport {
    sample: true,
    coverage: false,
    ssaa: true,
    why: "peeling compares each sample's depth with the previous layer's at that sample, so it shades per sample (aa_capture = sample)",
};

/// A point's configuration, read from its axes.
#[derive(Clone, Copy, Debug)]
struct Config {
    max_layers: u32,
    occlusion_stop: bool,
    uber: bool,
    tiebreak: bool,
    effect: EffectConfig,
    aa: AaConfig,
}

impl Config {
    fn read(point: &Point) -> std::result::Result<Config, InvalidPoint> {
        Ok(Config {
            max_layers: point.int(&MAX_LAYERS) as u32,
            occlusion_stop: point.bool(&OCCLUSION_STOP),
            uber: point.choice(&SPECIALISATION) == "uber",
            tiebreak: point.bool(&TIEBREAK),
            effect: EffectConfig::from_point(point)?,
            aa: AaConfig::from_point(point),
        })
    }

    /// What each layer stores: the effect's payload, or everything (uber; tiebreak needs ids
    /// and is kept on the full payload rather than multiplying the variants).
    fn payload(&self) -> Payload {
        if self.uber || self.tiebreak {
            Payload::ALL
        } else {
            self.effect.effect.payload()
        }
    }
}

impl Method for DepthPeel {
    fn name(&self) -> &'static str {
        "depth_peel"
    }
    fn describe(&self) -> &'static str {
        "Everitt 2001: exact front-to-back peeling, one geometry pass per layer (+1 empty pass with occlusion_stop); every effect via a per-pixel fold state"
    }
    fn exact(&self) -> bool {
        true
    }
    fn axes(&self) -> Vec<Axis> {
        let mut v = vec![MAX_LAYERS, OCCLUSION_STOP, SPECIALISATION, TIEBREAK];
        v.extend_from_slice(effects::AXES);
        v.extend([aa::AA, aa::AA_CAPTURE]);
        v
    }
    fn validate(&self, point: &Point) -> std::result::Result<(), InvalidPoint> {
        Config::read(point).map(|_| ())
    }
    fn payload(&self, point: &Point) -> Option<&'static str> {
        Config::read(point).ok().map(|c| c.payload().name())
    }
    fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        let cfg = Config::read(point)?;
        // naga's GLSL writer cannot translate `textureLoad` from a depth texture (the previous
        // layer's depth): a GL pipeline would fail to build, so it is an adapter limit, not a failure.
        if gpu.adapter.get_info().backend == wgpu::Backend::Gl {
            return Err(
                "reads the previous layer's depth with textureLoad from a depth texture, \
                        which naga's GLSL writer (wgpu's GL backends) cannot translate"
                    .into(),
            );
        }
        let p = cfg.payload();
        for (need, f) in [
            (p.color || p.normal, COLOR_FORMAT),
            (p.view_z, Z_FORMAT),
            (p.object_id, ID_FORMAT),
        ] {
            if need && !gpu.renderable(f) {
                return Err(format!("{f:?} is not renderable on this adapter").into());
            }
        }
        AA_SUPPORT.check(self.name(), cfg.aa)?;
        let mut formats = vec![wgpu::TextureFormat::Depth32Float];
        formats.extend(variant(p).targets.iter().map(|&(f, _)| f));
        aa::check_adapter(gpu, cfg.aa, &formats)
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let cfg = Config::read(point)?;
        if cfg.aa.mode == AaMode::Ssaa2x2 {
            let inner = Config {
                aa: AaConfig::NONE,
                ..cfg
            };
            return super::shared::ssaa::prepare(gpu, scene, |big| {
                Ok(Box::new(PreparedPeel::new(gpu, big, inner)))
            });
        }
        Ok(Box::new(PreparedPeel::new(gpu, scene, cfg)))
    }
}

/// The peeling module: `depth_peel.wgsl` after the fold, or its per-sample form under MSAA.
fn peel_module(gpu: &Gpu, ms: bool) -> wgpu::ShaderModule {
    if ms {
        // Every texture multisampled, every fragment entry per sample (module doc).
        let body = WGSL
            .replace("texture_depth_2d", "texture_depth_multisampled_2d")
            .replace("texture_2d<", "texture_multisampled_2d<");
        let body = ms_depth_source(&body);
        let src = per_sample_source(&format!("{COMMON_WGSL}\n{FOLD_WGSL}\n{body}"));
        shader_source(gpu, "depth_peel (per sample)", src)
    } else {
        shader_source(
            gpu,
            "depth_peel",
            format!("{COMMON_WGSL}\n{FOLD_WGSL}\n{WGSL}"),
        )
    }
}

/// The ping-pong depth buffers and layer targets of the peel passes.
struct Targets {
    depth_views: [wgpu::TextureView; 2],
    /// Per target, its views for parity 0 and 1 (the same view unless it alternates).
    views: Vec<[wgpu::TextureView; 2]>,
    /// Bound as the previous ids when there are none to read.
    dummy_id: wgpu::TextureView,
}

impl Targets {
    fn new(
        gpu: &Gpu,
        alloc: &mut AllocCounter,
        scene: &GpuScene,
        cfg: &Config,
        var: &Variant,
    ) -> Targets {
        let (w, h) = (scene.width, scene.height);
        let samples = cfg.aa.msaa();
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let mut texture = |label: &str, format| {
            alloc
                .texture_ms(gpu, label, w, h, format, usage, samples)
                .create_view(&Default::default())
        };
        let depth_views = [0, 1].map(|i| {
            texture(
                &format!("peel depth {i}"),
                wgpu::TextureFormat::Depth32Float,
            )
        });
        // One texture per target; the id target gets a second one when the tie-break reads
        // the previous layer's ids.
        let mut views: Vec<[wgpu::TextureView; 2]> = Vec::new();
        for &(f, binding) in var.targets {
            let a = texture(&format!("peel layer {binding}"), f);
            let b = if cfg.tiebreak && f == ID_FORMAT {
                texture(&format!("peel layer {binding}'"), f)
            } else {
                a.clone()
            };
            views.push([a, b]);
        }
        let dummy_id = gpu
            .create_texture(&wgpu::TextureDescriptor {
                label: Some("peel no ids"),
                size: wgpu::Extent3d {
                    width: 1,
                    height: 1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format: ID_FORMAT,
                // A multisampled texture must be renderable.
                usage: if samples > 1 {
                    usage
                } else {
                    wgpu::TextureUsages::TEXTURE_BINDING
                },
                view_formats: &[],
            })
            .create_view(&Default::default());
        Targets {
            depth_views,
            views,
            dummy_id,
        }
    }
}

/// One occlusion query, its resolve buffer and its read-back buffer.
fn occlusion_query(gpu: &Gpu) -> (wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer) {
    let d = &gpu.device;
    let occlusion = d.create_query_set(&wgpu::QuerySetDescriptor {
        label: Some("peel occlusion"),
        ty: wgpu::QueryType::Occlusion,
        count: 1,
    });
    let occ_resolve = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("occlusion resolve"),
        size: 256,
        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let occ_read = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("occlusion read"),
        size: 8,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    (occlusion, occ_resolve, occ_read)
}

/// The entry points and formats of one payload.
struct Variant {
    vs: &'static str,
    attrs: Attrs,
    fs: &'static str,
    resolve: &'static str,
    /// Colour targets in location order, each with the resolve binding that reads it.
    targets: &'static [(wgpu::TextureFormat, u32)],
}

fn variant(p: Payload) -> Variant {
    let attrs = |normal, color, object_id| Attrs {
        normal,
        color,
        object_id,
    };
    match p {
        Payload::RGBA => Variant {
            vs: "vs_pc",
            attrs: attrs(false, true, false),
            fs: "fs_rgba",
            resolve: "resolve_rgba",
            targets: &[(COLOR_FORMAT, 0)],
        },
        Payload::DEPTH => Variant {
            vs: "vs_p",
            attrs: Attrs::POSITION_ONLY,
            fs: "fs_z",
            resolve: "resolve_z",
            targets: &[(Z_FORMAT, 2)],
        },
        Payload::DEPTH_NORMAL => Variant {
            vs: "vs_pn",
            attrs: attrs(true, false, false),
            fs: "fs_zn",
            resolve: "resolve_zn",
            targets: &[(COLOR_FORMAT, 3)],
        },
        Payload::DEPTH_ID => Variant {
            vs: "vs_pi",
            attrs: attrs(false, false, true),
            fs: "fs_id",
            resolve: "resolve_id",
            targets: &[(ID_FORMAT, 4)],
        },
        Payload::RGBA_VIEWZ => Variant {
            vs: "vs_pc",
            attrs: attrs(false, true, false),
            fs: "fs_rgbaz",
            resolve: "resolve_rgbaz",
            targets: &[(COLOR_FORMAT, 0), (Z_FORMAT, 2)],
        },
        _ => Variant {
            vs: "vs_full",
            attrs: Attrs::ALL,
            fs: "fs_all",
            resolve: "resolve_all",
            targets: &[(COLOR_FORMAT, 0), (COLOR_FORMAT, 3), (ID_FORMAT, 4)],
        },
    }
}

struct PreparedPeel {
    first: wgpu::RenderPipeline,
    peel: wgpu::RenderPipeline,
    resolve: wgpu::ComputePipeline,
    begin: wgpu::ComputePipeline,
    end: wgpu::ComputePipeline,
    attrs: Attrs,
    /// Per parity p: pass i (i % 2 == p) writes depth[p] (and ids[p]) and reads the other.
    peel_bind: [wgpu::BindGroup; 2],
    resolve_bind: [wgpu::BindGroup; 2],
    depth_views: [wgpu::TextureView; 2],
    /// Colour attachments per parity (only the id target alternates, for the tie-break).
    target_views: [Vec<wgpu::TextureView>; 2],
    image: wgpu::Buffer,
    counts: wgpu::Buffer,
    images: usize,
    occlusion: wgpu::QuerySet,
    occ_resolve: wgpu::Buffer,
    occ_read: wgpu::Buffer,
    cfg: Config,
    reversed: bool,
    samples: u32,
    sample_positions: Option<String>,
    alloc: AllocCounter,
}

impl PreparedPeel {
    fn new(gpu: &Gpu, scene: &GpuScene, cfg: Config) -> Self {
        let samples = cfg.aa.msaa();
        let ms = samples > 1;
        let module = peel_module(gpu, ms);
        let var = variant(cfg.payload());
        let mut alloc = AllocCounter::default();
        // Every texture multisampled under MSAA (module doc).
        let tex = |s| if ms { B::TextureMs(s) } else { B::Texture(s) };
        let sample_type = |f: wgpu::TextureFormat| if f == ID_FORMAT { UINT } else { FLOAT };
        // Group 0 of every pass: camera, the previous layer's depth and ids (tie-break).
        let peel_rows = [(0, B::Camera), (1, tex(DEPTH)), (2, tex(UINT))];
        let peel_table = Bindings::new(gpu, "peel", wgpu::ShaderStages::FRAGMENT, &peel_rows);
        // Group 1 of the fold: this layer's depth and targets, fold state, counts, image.
        let mut rows = vec![(1, tex(DEPTH))];
        rows.extend(var.targets.iter().map(|&(f, b)| (b, tex(sample_type(f)))));
        rows.extend([(5, B::Storage), (6, B::Storage), (7, B::Storage)]);
        let resolve_table = Bindings::new(gpu, "peel resolve", wgpu::ShaderStages::COMPUTE, &rows);
        let peel_layout = pipeline_layout(gpu, "peel", &[&peel_table.layout]);
        let comp_layout = pipeline_layout(
            gpu,
            "peel resolve",
            &[&peel_table.layout, &resolve_table.layout],
        );
        let layouts: Vec<_> = GpuScene::layouts(var.attrs).into_iter().map(Some).collect();
        let targets: Vec<_> = var
            .targets
            .iter()
            .map(|&(format, _)| Some(format.into()))
            .collect();
        let make = |peel: bool| {
            let constants = [
                ("PEEL", if peel { 1.0 } else { 0.0 }),
                ("TIEBREAK", if cfg.tiebreak { 1.0 } else { 0.0 }),
                ("SAMPLES", samples as f64),
            ];
            let label = if peel { "peel" } else { "peel first layer" };
            let r = Raster {
                module: &module,
                vs: var.vs,
                buffers: &layouts,
                fs: var.fs,
                targets: &targets,
                constants: &constants,
                depth: Some(depth_state(scene.reversed_z, true)),
                samples,
            };
            render_pipeline(gpu, label, &peel_layout, r)
        };
        let first = make(false);
        let peel = make(true);
        let mut fold_constants = cfg.effect.constants();
        fold_constants.push(("SAMPLES", samples as f64));
        let compute = |entry: &str| {
            compute_pipeline(
                gpu,
                entry,
                &comp_layout,
                &module,
                entry,
                &fold_constants,
                false,
            )
        };
        let resolve = compute(var.resolve);
        let begin = compute("fold_begin");
        let end = compute("fold_end");

        let t = Targets::new(gpu, &mut alloc, scene, &cfg, &var);
        let px = scene.pixels() as u64;
        let images = cfg.effect.effect.image_count();
        let slots = px * samples as u64;
        let fold = alloc.buffer(gpu, "peel fold state", slots * FOLD_STATE_BYTES, STORAGE_RW);
        let counts = alloc.buffer(gpu, "peel counts", slots * 4, STORAGE_RW);
        let image = alloc.buffer(gpu, "peel image", px * 16 * images as u64, STORAGE_RW);
        let id_target = var.targets.iter().position(|&(f, _)| f == ID_FORMAT);
        let peel_bind = [0usize, 1].map(|p| {
            let prev_id = match (cfg.tiebreak, id_target) {
                (true, Some(i)) => &t.views[i][1 - p],
                _ => &t.dummy_id,
            };
            let depth = &t.depth_views[1 - p];
            peel_table.group(gpu, &[(&scene.camera).into(), depth.into(), prev_id.into()])
        });
        let resolve_bind = [0usize, 1].map(|p| {
            let mut res: Vec<Res> = vec![(&t.depth_views[p]).into()];
            res.extend(t.views.iter().map(|v| Res::View(&v[p])));
            res.extend([&fold, &counts, &image].map(Res::Buf));
            resolve_table.group(gpu, &res)
        });
        let (occlusion, occ_resolve, occ_read) = occlusion_query(gpu);
        let target_views = [0, 1].map(|p| t.views.iter().map(|v| v[p].clone()).collect::<Vec<_>>());
        PreparedPeel {
            first,
            peel,
            resolve,
            begin,
            end,
            attrs: var.attrs,
            peel_bind,
            resolve_bind,
            depth_views: t.depth_views,
            target_views,
            image,
            counts,
            images,
            occlusion,
            occ_resolve,
            occ_read,
            cfg,
            reversed: scene.reversed_z,
            samples,
            sample_positions: ms.then(|| aa::sample_positions(gpu, samples)),
            alloc,
        }
    }

    #[allow(
        clippy::too_many_arguments,
        reason = "one peel dispatch: encoder, scene, timer, pipeline and which peel and sample"
    )]
    fn dispatch(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &mut GpuTimer,
        label: &str,
        pipeline: &wgpu::ComputePipeline,
        p: usize,
        per_sample: bool,
    ) {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: timer.compute_pass(label),
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.peel_bind[p], &[]);
        pass.set_bind_group(1, &self.resolve_bind[p], &[]);
        let z = if per_sample { self.samples } else { 1 };
        pass.dispatch_workgroups(scene.width.div_ceil(8), scene.height.div_ceil(8), z);
    }

    /// Encodes peel pass `i` and its resolve into the fold.
    fn encode_layer(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &mut GpuTimer,
        i: u32,
    ) {
        let p = (i % 2) as usize;
        let occlusion_stop = self.cfg.occlusion_stop;
        {
            let color_attachments: Vec<_> = self.target_views[p]
                .iter()
                .map(|view| {
                    Some(wgpu::RenderPassColorAttachment {
                        view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })
                })
                .collect();
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("peel"),
                color_attachments: &color_attachments,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth_views[p],
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear_depth(self.reversed)),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.render_pass("peel"),
                occlusion_query_set: occlusion_stop.then_some(&self.occlusion),
                multiview_mask: None,
            });
            pass.set_pipeline(if i == 0 { &self.first } else { &self.peel });
            pass.set_bind_group(0, &self.peel_bind[p], &[]);
            if occlusion_stop {
                pass.begin_occlusion_query(0);
            }
            scene.draw(&mut pass, self.attrs);
            if occlusion_stop {
                pass.end_occlusion_query();
            }
        }
        self.dispatch(enc, scene, timer, "resolve", &self.resolve, p, true);
        if occlusion_stop {
            enc.resolve_query_set(&self.occlusion, 0..1, &self.occ_resolve, 0);
            enc.copy_buffer_to_buffer(&self.occ_resolve, 0, &self.occ_read, 0, 8);
        }
    }
}

impl bench_core::timed::Timed for PreparedPeel {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        self.dispatch(&mut enc, scene, timer, "fold_begin", &self.begin, 0, false);
        let mut stats = FrameStats::default();
        for i in 0..self.cfg.max_layers {
            self.encode_layer(&mut enc, scene, timer, i);
            stats.geometry_passes += 1;
            if self.cfg.occlusion_stop {
                // The classic algorithm: the CPU reads the query before deciding on another pass.
                gpu.queue.submit([enc.finish()]);
                let bytes = gpu.map_read(&self.occ_read)?;
                let samples = u64::from_le_bytes(bytes[..8].try_into().unwrap());
                enc = gpu.device.create_command_encoder(&Default::default());
                if samples == 0 {
                    break;
                }
            }
            stats.layers += 1;
        }
        self.dispatch(&mut enc, scene, timer, "fold_end", &self.end, 0, false);
        gpu.queue.submit([enc.finish()]);
        Ok(stats)
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }
}

impl Prepared for PreparedPeel {
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let n = scene.pixels();
        let mut cap = Capture::empty();
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.image, n * self.images)?);
        cap.expected = Expected::FirstK(self.cfg.max_layers);
        if self.samples > 1 {
            // One count per sample: the most layers any sample peeled, in the notes.
            let c = read_vec::<u32>(gpu, &self.counts, n * self.samples as usize)?;
            let most = c.iter().max().copied().unwrap_or(0);
            cap.notes = format!("most layers at one sample: {most}");
            cap.aa = self.cfg.aa.capture_mode();
            cap.aa_capture = Some(self.cfg.aa.capture);
            cap.sample_positions = self.sample_positions.clone();
        } else {
            cap.counts = Some(read_vec::<u32>(gpu, &self.counts, n)?);
        }
        Ok(cap)
    }

    fn image_buffer(&self) -> Option<&wgpu::Buffer> {
        Some(&self.image)
    }
}

/// The MSAA build's fragment entries also write `FRAG_Z` (the `@builtin(position).z` the keep
/// test compared) as `frag_depth`. Vulkan leaves where FragCoord.z is interpolated open under
/// sample shading (its x, y are the sample's); the depth test uses each sample's own depth. If
/// the two differ (the centre's z on a sloped triangle), a pass compares one depth and stores
/// another, and peels a fragment twice or never. Writing it makes them one value everywhere.
/// Each `-> @location(0) T` entry returns a `<entry>_Ms { v: T, depth }`, each entry returning a
/// struct `S(…)` returns `S_Ms(…, depth)`; every `return` of an entry is rewritten.
fn ms_depth_source(src: &str) -> String {
    let mut structs = String::new();
    let mut out = String::with_capacity(src.len() + 1024);
    let mut rest = src;
    while let Some(i) = rest.find("@fragment") {
        let head_end = i + rest[i..].find('{').expect("fragment entry body") + 1;
        let head = &rest[i..head_end];
        let name = head["@fragment".len()..]
            .trim_start()
            .strip_prefix("fn ")
            .and_then(|h| h.split('(').next())
            .expect("fragment entry name")
            .trim()
            .to_string();
        let ret = head[head.rfind("->").expect("fragment entry return type") + 2..head.len() - 1]
            .trim()
            .to_string();
        let body_end = head_end + rest[head_end..].find("\n}").expect("end of entry") + 2;
        let body = &rest[head_end..body_end];
        let (new_ret, new_body) = if let Some(t) = ret.strip_prefix("@location(0)") {
            let ms = format!("{name}_Ms");
            structs.push_str(&format!(
                "struct {ms} {{\n    @location(0) v: {},\n    @builtin(frag_depth) depth: f32,\n}};\n",
                t.trim()
            ));
            let b = rewrite_returns(body, |e| format!("{ms}({e}, FRAG_Z)"));
            (ms, b)
        } else {
            let fields = struct_fields(src, &ret);
            let ms = format!("{ret}_Ms");
            if !structs.contains(&format!("struct {ms} ")) {
                structs.push_str(&format!(
                    "struct {ms} {{\n{fields}    @builtin(frag_depth) depth: f32,\n}};\n"
                ));
            }
            let b = rewrite_returns(body, |e| {
                let args = e
                    .strip_prefix(&format!("{ret}("))
                    .and_then(|a| a.strip_suffix(')'))
                    .expect("an entry returning a struct returns its constructor");
                format!("{ms}({args}, FRAG_Z)")
            });
            (ms, b)
        };
        out.push_str(&rest[..i]);
        out.push_str(&head[..head.rfind("->").unwrap()]);
        out.push_str(&format!("-> {new_ret} {{"));
        out.push_str(&new_body);
        rest = &rest[body_end..];
    }
    out.push_str(rest);
    format!("{structs}\n{out}")
}

/// `return EXPR;` → `return f(EXPR);` in one function body.
fn rewrite_returns(body: &str, f: impl Fn(&str) -> String) -> String {
    let mut out = String::new();
    let mut rest = body;
    while let Some(i) = rest.find("return ") {
        let end = i + rest[i..].find(';').expect("return ends");
        out.push_str(&rest[..i]);
        out.push_str(&format!("return {};", f(rest[i + 7..end].trim())));
        rest = &rest[end + 1..];
    }
    out.push_str(rest);
    out
}

/// The field lines of `struct NAME { … }` in `src`.
fn struct_fields(src: &str, name: &str) -> String {
    let start = src
        .find(&format!("struct {name} {{"))
        .unwrap_or_else(|| panic!("struct {name} returned by a fragment entry"));
    let open = start + src[start..].find('{').unwrap() + 1;
    let close = open + src[open..].find('}').unwrap();
    let mut f = String::new();
    for line in src[open..close].lines().filter(|l| !l.trim().is_empty()) {
        f.push_str(line.trim_end());
        f.push('\n');
    }
    f
}

#[cfg(test)]
mod ms_depth_tests {
    #[test]
    fn every_fragment_entry_of_the_msaa_build_writes_the_depth_it_compared() {
        let src = super::ms_depth_source(super::WGSL);
        let entries = super::WGSL.matches("@fragment").count();
        assert_eq!(src.matches("@fragment").count(), entries);
        assert_eq!(src.matches("@builtin(frag_depth)").count(), entries);
        // Every return of an entry passes FRAG_Z; the structs keep their own fields.
        assert_eq!(src.matches(", FRAG_Z)").count(), entries);
        assert!(src.contains("struct RgbaZOut_Ms {\n    @location(0) color: vec4<f32>,"));
        assert!(src.contains("-> fs_rgba_Ms {"));
        // Its validity is tested where it compiles: the MSAA peeling tests (tests/aa.rs).
    }
}
