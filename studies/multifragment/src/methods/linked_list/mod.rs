//! Per-pixel linked-list A-buffer (Yang, Hensley, Grün & Thibieroz 2010): one geometry pass
//! appends every fragment to its pixel's list (atomic head pointers, a node pool); a compute
//! resolve sorts each list and folds it nearest first (the effects fold). Fragments that find
//! their pool full, or lists longer than the resolve's sort capacity (128), are counted on the
//! GPU and reported (`overflow_pixels`, flag `overflow`, lost fragments in notes), never silent.
//!
//! Axes:
//! - `pool = counted|fixed`. `counted` (default): prepare counts each 8×8-pixel tile's fragments
//!   once (a render pass of atomic increments, not timed) and gives every tile its own sub-pool
//!   of count + ⌈count · `pool_slack` / 100⌉ nodes with its own cursor, so the nodes are sized
//!   to the true fragments and a frame's allocations spread over one counter per tile instead of
//!   one for the screen; the lists stay dynamic (a fragment may land anywhere within its tile's
//!   sub-pool), and a frame with more fragments than prepare counted loses the extra ones,
//!   counted and flagged. `fixed`: one pool of `layers` × pixels nodes, one cursor. `pixel`
//!   (issue 41: the append pass is most of the frame on stacked scans): a counted pool per
//!   pixel, so a pixel's nodes lie one after another and the append pass takes a node (one
//!   returning atomic on the pixel's own cursor) and writes it, with no head exchange and no
//!   link (compact nodes of 8 B); the resolve reads the pixel's nodes in order. Single-sample;
//!   4 B a pixel of cursor and 8 B of range beside the heads.
//! - `pool_slack` (percent, default 0; counted pools): spare nodes per tile for scenes that
//!   change after prepare. 0 suffices for the static scenes measured here (the frame rasterises
//!   exactly the fragments prepare counted).
//! - `node = compact|full`. `compact` (default; needs PRIMITIVE_INDEX): 12 B nodes (depth,
//!   primitive | front, next) written by a fragment stage that reads no attributes; the resolve
//!   re-derives them from the primitive (every effect, Fresnel included). `full`: 32 B nodes with
//!   colour, depths and object id (every effect but Fresnel).
//!
//! - `tail = drop|blend` (default `drop`): `blend` sends the fragments that find their pool full
//!   (the append pass's fragment stage returns them to methods/shared/tail's blend targets; with compact
//!   nodes the append pass then runs the full vertex stage for their colour) and those beyond the
//!   resolve's sort capacity (summed in the resolve, which sees them) to an out-of-order tail
//!   composited behind the list. A pool fills in arrival order, so what a pixel keeps is its first
//!   arrivals (`keep = first` of the twin `oit::tail`); transparency only.
//!
//! - `aa = msaa2|msaa4|msaa8` (issue 22): `aa_capture = sample` runs the fragment stage per
//!   sample (sample shading) and gives each sample its own list (heads × samples, a counted pool
//!   counts per-sample fragments); `aa_capture = coverage` (compact nodes) appends one node per
//!   pixel-rate fragment with its coverage mask packed into the tag (12 B still: primitives in
//!   23 bits), and the resolve folds each sample over the fragments whose mask has its bit.
//!   Either resolve shades at the pixel centre and averages the samples. `ssaa2x2` wraps the
//!   single-sample list (`methods::shared::ssaa`). `tail = blend` is single-sample only.
//!
//! Memory: `bytes_overhead` is everything but the nodes (heads, per-pixel lost/resolved counts,
//! output images, the per-tile cursors and ranges, the stand-in depth attachment).

use wgpu::util::DeviceExt;

use super::shared::counted_capture::{MASKED_PRIM_BITS, VISIBILITY_WGSL};
use super::shared::store::{self, storage_pass_with};
use super::shared::tail::{self, TailTargets, TAIL_WGSL};
use super::{Capture, Expected, FrameStats, Method, Prepared};
use crate::aa::{self, AaCapture, AaConfig, AaMode, AaSupport};
use crate::effects::{self, Effect, EffectConfig, FOLD_WGSL as EFFECTS_WGSL};
use bench_core::axes::{Axis, Point};
use bench_core::bind::{
    mesh_buffers, pipeline_layout, pipeline_layout_gaps, Bindings, Kind as B, Res, FC, FLOAT,
};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};
use bench_core::gpu_util::{
    compute_pipeline, multisample, per_sample_source, read_vec, shader_source, COMMON_WGSL,
    STORAGE_RW,
};
use bench_core::limits::{self, Split};
use bench_core::record::{cols, Flag};
use bench_core::study::InvalidPoint;
use bench_core::timing::GpuTimer;
use bench_core::{CoreError, Result};

const WGSL: &str = include_str!("linked_list.wgsl");
const TAIL_RESOLVE_WGSL: &str = include_str!("tail.wgsl");
const FULL_WGSL: &str = include_str!("full_node.wgsl");
const COMPACT_WGSL: &str = include_str!("compact_node.wgsl");
/// The resolve's per-pixel sort capacity (`SORT_MAX` in the WGSL).
pub const SORT_MAX: u32 = 128;
/// Side (pixels) of a counted pool's tiles (`TILE_SIDE` in the WGSL).
pub const TILE_SIDE: u32 = 8;
/// Bytes of a `full` node (`NODE_WORDS` × 4 in full_node.wgsl).
pub const FULL_NODE_BYTES: u64 = 32;
/// Bytes of a `compact` node (compact_node.wgsl), and of one in a pixel pool (no link).
pub const COMPACT_NODE_BYTES: u64 = 12;
pub const PIXEL_NODE_BYTES: u64 = 8;
/// Storage buffers bound in the fragment stage (group 0) and in the compact resolve (+ mesh).
const STORAGE_BUFFERS: u32 = 7;
const MESH_BUFFERS: u32 = 5;

pub struct LinkedList;

const LAYERS: Axis = Axis::int(
    cols::LAYERS,
    "pool = fixed: nodes per pixel on average (pool = layers × pixels); unused by a counted pool",
    8,
    1,
    1024,
)
.only_when(&POOL, &["fixed"]);
const POOL: Axis = Axis::choice(
    cols::POOL,
    "counted: per-8×8-tile sub-pools sized by a prepare-time count; fixed: layers × pixels nodes; pixel: a pool per pixel sized by a prepare-time count, its nodes contiguous (no links; single-sample)",
    "counted",
    &["counted", "fixed", "pixel"],
);
const POOL_SLACK: Axis = Axis::int(
    cols::POOL_SLACK,
    "counted pool: spare nodes per tile, percent of its count",
    0,
    0,
    400,
)
.only_when(&POOL, &["counted", "pixel"]);
const NODE: Axis = Axis::choice(
    cols::NODE,
    "compact: 12 B nodes, attributes re-derived from the primitive; full: 32 B nodes",
    "compact",
    &["compact", "full"],
);

impl Method for LinkedList {
    fn name(&self) -> &'static str {
        "linked_list"
    }
    fn describe(&self) -> &'static str {
        "Yang et al. 2010: per-pixel linked lists, sorted in a compute resolve; node pool counted per 8×8 tile at prepare (pool=counted, default) or layers × pixels (pool=fixed); 12 B compact nodes re-derived from the primitive (node=compact, default) or 32 B full nodes; exact within the pool, overflow counted; 1 geometry pass + resolve"
    }
    fn exact(&self) -> bool {
        true
    }
    fn axes(&self) -> Vec<Axis> {
        let mut v = vec![LAYERS, POOL, POOL_SLACK, NODE, tail::TAIL];
        v.extend_from_slice(effects::AXES);
        v.extend([aa::AA, aa::AA_CAPTURE]);
        v
    }
    fn validate(&self, point: &Point) -> std::result::Result<(), InvalidPoint> {
        EffectConfig::from_point(point).map(|_| ())
    }
    fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        AA_SUPPORT.check(self.name(), AaConfig::from_point(point))?;
        let c = list_config(point);
        if c.pixel && c.aa.msaa() > 1 {
            return Err(
                "pool = pixel keeps one list a pixel: single-sample (aa = none or ssaa2x2)".into(),
            );
        }
        let e = effect_config(point, c.compact)?;
        if c.aa.msaa() > 1 {
            if c.tail {
                return Err("tail = blend is single-sample: its blend targets are not multisampled (use aa = none or ssaa2x2)".into());
            }
            if c.aa.capture == AaCapture::Coverage && !c.compact {
                return Err("aa_capture = coverage packs the mask into a compact node's tag: needs node = compact".into());
            }
            aa::check_adapter(gpu, c.aa, &[wgpu::TextureFormat::Depth32Float])?;
        }
        if c.tail {
            tail::supports(gpu, 0)?;
            if e.effect != Effect::Transparency {
                return Err(format!(
                    "tail = blend composites a transparency tail: not {}",
                    e.effect.name()
                )
                .into());
            }
        }
        if c.compact && !gpu.has(wgpu::Features::PRIMITIVE_INDEX) {
            return Err("node = compact needs PRIMITIVE_INDEX (use node = full)".into());
        }
        let need = STORAGE_BUFFERS + if c.compact { MESH_BUFFERS } else { 0 };
        let have = gpu.limits.max_storage_buffers_per_shader_stage;
        if have < need {
            return Err(format!(
                "needs {need} storage buffers per shader stage, {} allows {have}",
                gpu.profile.who()
            )
            .into());
        }
        Ok(())
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let layers = point.int(&LAYERS) as u64;
        let c = list_config(point);
        let effect = effect_config(point, c.compact)?;
        if c.aa.mode == AaMode::Ssaa2x2 {
            let c = ListConfig {
                aa: AaConfig::NONE,
                ..c
            };
            return super::shared::ssaa::prepare(gpu, scene, |big| {
                Ok(Box::new(PreparedList::new(gpu, big, layers, c, &effect)?))
            });
        }
        Ok(Box::new(PreparedList::new(gpu, scene, layers, c, &effect)?))
    }
}

/// Every variant: per-sample lists, coverage-mask nodes (compact only, checked in `supports`)
/// and supersampling.
const AA_SUPPORT: AaSupport = AaSupport {
    sample: true,
    coverage: true,
    ssaa: true,
    why: "",
};

/// The pool, node, tail and aa axes (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct ListConfig {
    /// `pool = counted` or `pixel`: sub-pools sized by a prepare-time count.
    counted: bool,
    /// `pool = pixel`: one sub-pool per pixel, its nodes contiguous (no head, no links).
    pixel: bool,
    /// `pool_slack`: spare nodes per counted tile, percent of its count.
    slack_pct: u64,
    /// `node = compact`: 12 B nodes, attributes re-derived from the primitive.
    compact: bool,
    /// `tail = blend`: what does not fit goes to a blended tail.
    tail: bool,
    /// `aa`, `aa_capture`: MSAA lists per sample or coverage-mask nodes.
    aa: AaConfig,
}

impl ListConfig {
    /// Lists per pixel: one per sample for per-sample capture, else one.
    fn lists_per_pixel(&self) -> u64 {
        if self.aa.msaa() > 1 && self.aa.capture == AaCapture::Sample {
            self.aa.msaa() as u64
        } else {
            1
        }
    }
}

fn list_config(point: &Point) -> ListConfig {
    ListConfig {
        counted: point.choice(&POOL) != "fixed",
        pixel: point.choice(&POOL) == "pixel",
        slack_pct: point.int(&POOL_SLACK) as u64,
        compact: point.choice(&NODE) == "compact",
        tail: tail::tail_mode(point) == mfx_reference::oit::TailMode::Blend,
        aa: AaConfig::from_point(point),
    }
}

/// The effect of a point: a full node stores colour, window depth, view depth, object id and
/// facing, so every effect but Fresnel (which needs the normal) folds from it; a compact node
/// re-derives everything.
fn effect_config(point: &Point, compact: bool) -> std::result::Result<EffectConfig, InvalidPoint> {
    let e = EffectConfig::from_point(point)?;
    if e.effect == Effect::Fresnel && !compact {
        return Err(InvalidPoint::combination("linked_list full nodes store no normal: fresnel needs one (node = compact re-derives it)"));
    }
    Ok(e)
}

/// A storage-only render pipeline over `vs` (both faces, the stand-in depth never tested).
fn list_pipeline(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    (vs, attrs): (&str, Attrs),
    (fs, targets): (&str, &[Option<wgpu::ColorTargetState>]),
    (constants, samples): (&[(&str, f64)], u32),
) -> wgpu::RenderPipeline {
    let layouts: Vec<_> = GpuScene::layouts(attrs).into_iter().map(Some).collect();
    let options = wgpu::PipelineCompilationOptions {
        constants,
        zero_initialize_workgroup_memory: false,
    };
    gpu.device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some(vs),
                compilation_options: options.clone(),
                buffers: &layouts,
            },
            // Both faces: transparency sees back faces too (like the reference).
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: multisample(samples),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(fs),
                compilation_options: options,
                targets,
            }),
            multiview_mask: None,
            cache: None,
        })
}

struct PreparedList {
    append: wgpu::RenderPipeline,
    resolve: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
    mesh_bind: Option<wgpu::BindGroup>,
    attrs: Attrs,
    depth: wgpu::TextureView,
    heads: wgpu::Buffer,
    image: wgpu::Buffer,
    counters: wgpu::Buffer,
    pix: wgpu::Buffer,
    cursors: wgpu::Buffer,
    pools: usize,
    pool_note: String,
    images: usize,
    /// `tail = blend`: the tail targets and the resolve's group 2 over them.
    tail: Option<(TailTargets, wgpu::BindGroup)>,
    /// Per pixel, fragments its pool turned away in the last frame (read back for `judge`).
    pool_lost: Vec<u32>,
    /// MSAA: the mode and capture the rows report (`None`: single-sample).
    aa: Option<AaConfig>,
    /// How the node pool lies over storage bindings (the `split` column).
    split: Split,
    /// The node pool's parts (bound in `bind`).
    _nodes: Vec<wgpu::Buffer>,
    alloc: AllocCounter,
    overhead: u64,
}

/// The module's source: the node pool's bindings over `split` (word accessors), the list, the
/// node variant (compact nodes re-derive attributes from the primitive), the fold and the tail;
/// per sample when a list is kept per sample.
fn list_source(c: &ListConfig, split: &Split) -> String {
    let variant = if c.compact {
        format!("{COMPACT_WGSL}\n{VISIBILITY_WGSL}")
    } else {
        FULL_WGSL.to_string()
    };
    // `enable` directives must open the module, before the common vertex stage.
    let enable = if c.compact {
        "enable primitive_index;\n"
    } else {
        ""
    };
    let pool = split.words().wgsl("nodes", "u32", 2);
    let src = format!(
        "{enable}{COMMON_WGSL}\n{pool}\n{WGSL}\n{variant}\n{EFFECTS_WGSL}\n{TAIL_WGSL}\n{TAIL_RESOLVE_WGSL}"
    );
    // Per-sample capture: every fragment entry runs per sample (SAMPLE = its index).
    if c.lists_per_pixel() > 1 {
        per_sample_source(&src)
    } else {
        src
    }
}

/// Counted pools laid end to end: (first node, nodes) per tile, each its count plus
/// `slack_pct` percent.
fn counted_ranges(counts: &[u32], slack_pct: u64) -> Vec<[u32; 2]> {
    let mut first = 0u64;
    let mut r = Vec::with_capacity(counts.len());
    for &n in counts {
        let cap = n as u64 + (n as u64 * slack_pct).div_ceil(100);
        r.push([
            first.min(u32::MAX as u64) as u32,
            cap.min(u32::MAX as u64) as u32,
        ]);
        first += cap;
    }
    r
}

fn flag(b: bool) -> f64 {
    if b {
        1.0
    } else {
        0.0
    }
}

/// Bytes of one node: full, compact, or compact without a link (pixel pools).
fn node_bytes(c: &ListConfig) -> u64 {
    match (c.compact, c.pixel) {
        (false, _) => FULL_NODE_BYTES,
        (true, false) => COMPACT_NODE_BYTES,
        (true, true) => PIXEL_NODE_BYTES,
    }
}

/// Coverage-mask tags keep [`MASKED_PRIM_BITS`] bits of primitive: refuse larger scenes.
fn check_tags(scene: &GpuScene, coverage: bool) -> Result<()> {
    let ntri = scene.index_count / 3;
    if coverage && ntri >= 1 << MASKED_PRIM_BITS {
        return Err(CoreError::Param(format!(
            "linked_list with coverage masks tags primitives in {MASKED_PRIM_BITS} bits: {ntri} triangles are too many"
        )));
    }
    Ok(())
}

/// Overrides the raster stages and the resolve share; the compact tag's primitive bits where
/// a mask is packed.
fn shared_constants(c: &ListConfig, coverage: bool) -> Vec<(&'static str, f64)> {
    let mut shared = vec![
        ("SAMPLES", c.aa.msaa() as f64),
        ("COVERAGE", flag(coverage)),
        ("PIXEL_POOLS", flag(c.pixel)),
    ];
    if c.compact {
        let bits = if coverage { MASKED_PRIM_BITS } else { 31 };
        shared.push(("TAG_PRIM_BITS", bits as f64));
        shared.push(("NODE_WORDS", (node_bytes(c) / 4) as f64));
    }
    shared
}

/// An entry point and what it uses.
type Stage<T> = (&'static str, T);

/// The append pass's vertex stage (attributes fetched) and fragment stage (targets).
fn append_stage(
    c: &ListConfig,
    coverage: bool,
) -> (Stage<Attrs>, Stage<Vec<Option<wgpu::ColorTargetState>>>) {
    let vs = if c.compact && !c.tail {
        ("vs_position", Attrs::POSITION_ONLY)
    } else {
        ("vs_full", Attrs::ALL)
    };
    let fs = if c.tail {
        ("fs_append_tail", TailTargets::color_targets())
    } else if coverage {
        ("fs_append_mask", Vec::new())
    } else {
        ("fs_append", Vec::new())
    };
    (vs, fs)
}

/// The resolve: sort and fold each list (per sample under MSAA), or with the tail behind.
fn resolve_kernel(
    gpu: &Gpu,
    (module, layout): (&wgpu::ShaderModule, &wgpu::PipelineLayout),
    c: &ListConfig,
    effect: &EffectConfig,
    shared: &[(&'static str, f64)],
) -> wgpu::ComputePipeline {
    let samples = c.aa.msaa();
    let mut rc = effect.constants();
    rc.push(("TAIL", flag(c.tail)));
    rc.extend_from_slice(shared);
    if c.compact {
        // Under MSAA a fragment may cover samples but not the centre it is shaded at.
        rc.push(("EXTRAPOLATE", flag(samples > 1)));
    }
    let entry = match (c.tail, samples > 1) {
        (true, _) => "resolve_tail",
        (false, true) => "resolve_ms",
        (false, false) => "resolve",
    };
    compute_pipeline(
        gpu,
        "linked_list resolve",
        layout,
        module,
        entry,
        &rc,
        false,
    )
}

/// Pool ranges, (first node, nodes) per pool, and the note saying how they were sized:
/// `counts` per tile (counted pools) or `layers` nodes per pixel; Err where the pool does not
/// fit 32-bit node indices.
fn pool_plan(
    counts: Option<&[u32]>,
    c: &ListConfig,
    layers: u64,
    px: u64,
) -> Result<(Vec<[u32; 2]>, String)> {
    let samples = c.aa.msaa();
    let coverage = samples > 1 && c.aa.capture == AaCapture::Coverage;
    let (ranges, note) = match counts {
        Some(counts) => {
            let true_frags: u64 = counts.iter().map(|&n| n as u64).sum();
            let pools = counts.len();
            let what = match (samples > 1, coverage) {
                (false, _) => String::new(),
                (true, true) => format!(" (pixel-rate, {samples}× coverage masks)"),
                (true, false) => format!(" ({samples} samples each, a list per sample)"),
            };
            let into = if c.pixel {
                format!("{pools} pixel pools (nodes contiguous, no links)")
            } else {
                format!("{pools} tiles of {TILE_SIDE}×{TILE_SIDE} px")
            };
            let note = format!(
                "counted pool: {true_frags} fragments{what} at prepare in {into}, {} % slack",
                c.slack_pct
            );
            (counted_ranges(counts, c.slack_pct), note)
        }
        None => {
            let pool = layers * px;
            let note = format!("fixed pool: {layers} nodes per pixel");
            (vec![[0, pool.min(u32::MAX as u64) as u32]], note)
        }
    };
    let pool_end = ranges
        .last()
        .map(|r| r[0] as u64 + r[1] as u64)
        .unwrap_or(0);
    if pool_end >= u32::MAX as u64 || (!c.counted && layers * px >= u32::MAX as u64) {
        return Err(CoreError::Param(format!(
            "linked_list pool of {} nodes does not fit 32-bit node indices",
            pool_end.max(layers * px * u64::from(!c.counted))
        )));
    }
    Ok((ranges, note))
}

/// What depends on how the node pool lies over storage bindings: the module (its `nodes`
/// declarations), group 0's table and the append and resolve pipelines.
struct Stages {
    module: wgpu::ShaderModule,
    table: Bindings,
    raster_layout: wgpu::PipelineLayout,
    append: wgpu::RenderPipeline,
    resolve: wgpu::ComputePipeline,
}

/// Everything a split leaves alone: the configuration, the effect, the resolve's other groups.
struct StageInputs<'a> {
    c: &'a ListConfig,
    effect: &'a EffectConfig,
    coverage: bool,
    mesh_table: Option<&'a Bindings>,
    tail_table: Option<&'a Bindings>,
}

impl Stages {
    fn new(gpu: &Gpu, i: &StageInputs<'_>, split: &Split) -> Stages {
        let c = i.c;
        let module = shader_source(gpu, "linked_list", list_source(c, split));
        // Group 0: camera, heads, nodes, image, counters, lost + resolved counts, pool cursors,
        // pool ranges (read only); the pool's further parts at limits::SPLIT_BINDING + 0, 1, ….
        let mut rows = vec![(0, B::Camera)];
        rows.extend((1..7).map(|b| (b, B::Storage)));
        rows.push((7, B::StorageRo));
        rows.extend(split.more_bindings().map(|b| (b, B::Storage)));
        let table = Bindings::new(gpu, "linked_list", FC, &rows);
        let raster_layout = pipeline_layout(gpu, "linked_list append", &[&table.layout]);
        // The compact resolve's group 1 (the mesh) and tail = blend's group 2 (its textures).
        let groups = [
            Some(&table.layout),
            i.mesh_table.map(|t| &t.layout),
            i.tail_table.map(|t| &t.layout),
        ];
        let resolve_layout = pipeline_layout_gaps(gpu, "linked_list resolve", &groups);
        let shared = shared_constants(c, i.coverage);
        let ((vs, attrs), (fs, targets)) = append_stage(c, i.coverage);
        let append = list_pipeline(
            gpu,
            "linked_list append",
            &raster_layout,
            &module,
            (vs, attrs),
            (fs, &targets),
            (&raster_constants(c, &shared), c.aa.msaa()),
        );
        let resolve = resolve_kernel(gpu, (&module, &resolve_layout), c, i.effect, &shared);
        Stages {
            module,
            table,
            raster_layout,
            append,
            resolve,
        }
    }
}

/// The raster stages' overrides: tiled pools and what the resolve shares.
fn raster_constants(c: &ListConfig, shared: &[(&'static str, f64)]) -> Vec<(&'static str, f64)> {
    let mut v = vec![("TILED", flag(c.counted))];
    v.extend_from_slice(shared);
    v
}

/// Storage buffers beside the node pool in its busiest stage: group 0's other six, and the
/// compact resolve's mesh.
fn others_beside_pool(c: &ListConfig) -> u32 {
    STORAGE_BUFFERS - 1 + if c.compact { MESH_BUFFERS } else { 0 }
}

impl PreparedList {
    fn new(
        gpu: &Gpu,
        scene: &GpuScene,
        layers: u64,
        c: ListConfig,
        effect: &EffectConfig,
    ) -> Result<Self> {
        let d = &gpu.device;
        let px = scene.pixels() as u64;
        let node_bytes = node_bytes(&c);
        let samples = c.aa.msaa();
        let coverage = samples > 1 && c.aa.capture == AaCapture::Coverage;
        let lists = c.lists_per_pixel();
        check_tags(scene, coverage)?;
        // Group 1 of the compact resolve: the mesh, to re-derive attributes.
        let mesh_rows = [B::StorageRo; MESH_BUFFERS as usize];
        let cs = wgpu::ShaderStages::COMPUTE;
        let mesh_table = c
            .compact
            .then(|| Bindings::seq(gpu, "linked_list mesh", cs, &mesh_rows));
        // tail = blend: the tail textures as group 2 of the resolve only (the append pass
        // renders into them).
        let tail_rows = TailTargets::rows(0, B::Texture(FLOAT));
        let tail_table = c
            .tail
            .then(|| Bindings::new(gpu, "linked_list tail", cs, &tail_rows));
        let inputs = StageInputs {
            c: &c,
            effect,
            coverage,
            mesh_table: mesh_table.as_ref(),
            tail_table: tail_table.as_ref(),
        };
        let images = effect.effect.image_count();
        let mut alloc = AllocCounter::default();
        let depth = super::shared::store::dummy_depth_ms(gpu, &mut alloc, scene, samples);
        let heads = alloc.buffer(gpu, "list heads", px * lists * 4, STORAGE_RW);
        let image = alloc.buffer(gpu, "list image", px * 16 * images as u64, STORAGE_RW);
        let counters = alloc.buffer(gpu, "list counters", 16, STORAGE_RW);
        let pix = alloc.buffer(gpu, "list lost + resolved counts", px * 8, STORAGE_RW);
        let tiles_x = scene.width.div_ceil(TILE_SIDE);
        let pools = match (c.counted, c.pixel) {
            (true, true) => px as usize,
            (true, false) => (tiles_x * scene.height.div_ceil(TILE_SIDE)) as usize,
            (false, _) => 1,
        };
        let cursors = alloc.buffer(gpu, "list pool cursors", pools as u64 * 4, STORAGE_RW);
        let bind_with = |table: &Bindings, nodes: &[wgpu::Buffer], ranges: &wgpu::Buffer| {
            let lists = [&scene.camera, &heads, &nodes[0], &image];
            let pools = [&counters, &pix, &cursors, ranges];
            let res: Vec<Res> = lists
                .into_iter()
                .chain(pools)
                .chain(&nodes[1..])
                .map(Res::Buf)
                .collect();
            table.group(gpu, &res)
        };
        // Pool ranges: (first node, nodes) per pool; a counted pool is counted with the pool
        // unsplit (the count touches only the cursors).
        let mut counting = None;
        let counts = match c.counted {
            true => {
                let st = Stages::new(gpu, &inputs, &Split::whole(1, node_bytes));
                let shared = shared_constants(&c, coverage);
                let counts = count_tiles(
                    gpu,
                    scene,
                    (
                        &st.module,
                        &st.raster_layout,
                        &raster_constants(&c, &shared),
                        samples,
                    ),
                    &depth,
                    &cursors,
                    |n, r| bind_with(&st.table, std::slice::from_ref(n), r),
                )?;
                counting = Some(st);
                Some(counts)
            }
            false => None,
        };
        let (ranges, pool_note) = pool_plan(counts.as_deref(), &c, layers, px)?;
        let pool: u64 = ranges.iter().map(|r| r[1] as u64).sum();
        let split = limits::split_storage(
            gpu.held(),
            "linked_list node pool",
            (pool.max(1), node_bytes),
            others_beside_pool(&c),
        )?;
        let stages = match counting {
            Some(st) if split.parts == 1 => st,
            _ => Stages::new(gpu, &inputs, &split),
        };
        let node_buffer_bytes = pool.max(1) * node_bytes;
        let nodes = store::split_buffers(gpu, &mut alloc, "list nodes", &split);
        let range_bytes: &[u8] = bytemuck::cast_slice(&ranges);
        alloc.bytes += range_bytes.len() as u64;
        let ranges_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("list pool ranges"),
            contents: range_bytes,
            usage: wgpu::BufferUsages::STORAGE,
        });
        let bind = bind_with(&stages.table, &nodes, &ranges_buf);
        let mesh_bind = mesh_table
            .as_ref()
            .map(|t| t.group(gpu, &mesh_buffers(scene).map(Res::Buf)));
        let tail = tail_table.as_ref().map(|table| {
            let t = TailTargets::new(gpu, &mut alloc, scene);
            let b = table.group(gpu, &t.views());
            (t, b)
        });
        let overhead = alloc.bytes - node_buffer_bytes;
        Ok(PreparedList {
            append: stages.append,
            resolve: stages.resolve,
            bind,
            mesh_bind,
            attrs: append_stage(&c, coverage).0 .1,
            depth,
            heads,
            image,
            counters,
            pix,
            cursors,
            pools,
            pool_note: format!("{pool_note}; {pool} nodes of {node_bytes} B"),
            images,
            tail,
            pool_lost: Vec::new(),
            aa: (samples > 1).then_some(c.aa),
            split,
            _nodes: nodes,
            alloc,
            overhead,
        })
    }
}

/// Per pixel: its first `nodes(p)` fragments in primitive order got nodes, of which the
/// resolve keeps the [`SORT_MAX`] nearest; everything else is blended into the tail (exact
/// opacity), composited behind them.
pub fn first_arrivals_with_tail(
    lists: &mfx_reference::FragmentLists,
    nodes: impl Fn(usize) -> usize + Sync,
) -> Vec<[f64; 4]> {
    use mfx_reference::oit::tail::{behind, split, TailSums};
    use mfx_reference::oit::{composite_sorted, frags, Frag, Keep, Order};
    use rayon::prelude::*;
    (0..lists.pixels())
        .into_par_iter()
        .map(|p| {
            let f: Vec<Frag<f64>> = frags(lists.pixel(p), Order::Arrival);
            let got = nodes(p).min(f.len());
            let (kept, mut rest) = split(&f[..got], SORT_MAX as usize, Keep::Nearest);
            rest.extend(got..f.len());
            let (c, t) = composite_sorted(kept.iter().map(|&i| &f[i]));
            let mut sums = TailSums::default();
            for &i in &rest {
                sums.add(&f[i]);
            }
            let o = sums.exact_opacity();
            behind(c, t, sums.premultiplied(o), o)
        })
        .collect()
}

/// Prepare-time count of each 8×8 tile's fragments: one render pass of `fs_count` (atomic
/// increments of the tile's cursor) over the scene, read back.
fn count_tiles(
    gpu: &Gpu,
    scene: &GpuScene,
    (module, layout, constants, samples): (
        &wgpu::ShaderModule,
        &wgpu::PipelineLayout,
        &[(&str, f64)],
        u32,
    ),
    depth: &wgpu::TextureView,
    cursors: &wgpu::Buffer,
    bind_with: impl Fn(&wgpu::Buffer, &wgpu::Buffer) -> wgpu::BindGroup,
) -> Result<Vec<u32>> {
    let pipeline = list_pipeline(
        gpu,
        "linked_list count",
        layout,
        module,
        ("vs_position", Attrs::POSITION_ONLY),
        ("fs_count", &[]),
        (constants, samples),
    );
    // The count touches only the cursors: stand-ins for the node pool and ranges.
    let stand_in = |label| {
        gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        })
    };
    let bind = bind_with(
        &stand_in("list nodes (sizing)"),
        &stand_in("list ranges (sizing)"),
    );
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    enc.clear_buffer(cursors, 0, None);
    {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("linked_list count"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        scene.draw(&mut pass, Attrs::POSITION_ONLY);
    }
    gpu.queue.submit([enc.finish()]);
    let n = (cursors.size() / 4) as usize;
    read_vec::<u32>(gpu, cursors, n)
}

impl bench_core::timed::Timed for PreparedList {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.heads, 0, None);
        enc.clear_buffer(&self.counters, 0, None);
        enc.clear_buffer(&self.pix, 0, None);
        enc.clear_buffer(&self.cursors, 0, None);
        {
            let colors = self
                .tail
                .as_ref()
                .map_or(Vec::new(), |(t, _)| t.attachments());
            let mut pass = storage_pass_with(&mut enc, &self.depth, &colors, timer, "append");
            pass.set_pipeline(&self.append);
            pass.set_bind_group(0, &self.bind, &[]);
            scene.draw(&mut pass, self.attrs);
        }
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("resolve"),
                timestamp_writes: timer.compute_pass("resolve"),
            });
            pass.set_pipeline(&self.resolve);
            pass.set_bind_group(0, &self.bind, &[]);
            if let Some(m) = &self.mesh_bind {
                pass.set_bind_group(1, m, &[]);
            }
            if let Some((_, b)) = &self.tail {
                pass.set_bind_group(2, b, &[]);
            }
            pass.dispatch_workgroups(scene.width.div_ceil(8), scene.height.div_ceil(8), 1);
        }
        gpu.queue.submit([enc.finish()]);
        Ok(FrameStats {
            geometry_passes: 1,
            layers: 0,
        })
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }

    /// The per-pixel structures (offsets or heads, counters, output images): everything but
    /// the fragments (or nodes) and what holds them.
    fn bytes_overhead(&self) -> Option<u64> {
        Some(self.overhead)
    }
}

impl Prepared for PreparedList {
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let n = scene.pixels();
        let mut cap = Capture::empty();
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.image, n * self.images)?);
        let pix = read_vec::<[u32; 2]>(gpu, &self.pix, n)?;
        if let Some(aa) = self.aa {
            // Per-pixel counts are single-sample by contract: an MSAA capture reports none.
            cap.aa = Some(aa.mode);
            cap.aa_capture = Some(aa.capture);
            cap.sample_positions = Some(aa::sample_positions(gpu, aa.msaa()));
        } else {
            cap.counts = Some(pix.iter().map(|p| p[1]).collect());
        }
        self.pool_lost = pix.iter().map(|p| p[0]).collect();
        cap.expected = Expected::All;
        let c = read_vec::<u32>(gpu, &self.counters, 2)?;
        let (ovf, lost) = (c[0] as u64, c[1] as u64);
        let arrived: u64 = read_vec::<u32>(gpu, &self.cursors, self.pools)?
            .iter()
            .map(|&k| k as u64)
            .sum();
        cap.overflow_pixels = Some(ovf);
        if ovf > 0 {
            cap.flag.add(Flag::Overflow);
        }
        cap.notes = format!(
            "{}; {arrived} fragments arrived, {ovf} overflowed pixels, {lost} lost fragments",
            self.pool_note
        );
        if self.tail.is_some() {
            cap.tailed_fragments = Some(lost);
            cap.dropped_fragments = Some(0);
            cap.notes = format!("{}, all blended into the tail", cap.notes);
        } else {
            cap.dropped_fragments = Some(lost);
        }
        Ok(cap)
    }

    /// `tail = blend`: the definition is the twin with each pixel's first arrivals kept (as many
    /// as its pool gave nodes; of those the resolve's SORT_MAX nearest) and the rest tailed.
    fn judge(&mut self, cap: &mut Capture, reference: &mfx_reference::FragmentLists) {
        if self.tail.is_none() || self.pool_lost.len() != reference.pixels() {
            return;
        }
        let lost = &self.pool_lost;
        cap.definition = Some(first_arrivals_with_tail(reference, |p| {
            reference.pixel(p).len().saturating_sub(lost[p] as usize)
        }));
    }

    fn image_buffer(&self) -> Option<&wgpu::Buffer> {
        Some(&self.image)
    }

    fn split(&self) -> Option<String> {
        self.split.column()
    }
}

#[cfg(test)]
mod tests {
    use crate::methods::Timed;
    use glam::DVec3;
    use scenarios::ParamValue::{Int, Str};
    use scenarios::{Camera, Scene, SceneSpec};

    use super::*;
    use crate::testing::{assert_matches_reference, gpu, params, run, scene};
    use mfx_reference::rasterize;
    use scenarios::Params;

    /// Composite of up to 16 layers in f32 vs f64: a few f32 ulps per step (compact nodes
    /// re-derive attributes in f32 from the primitive, as compute_abuffer does).
    const IMAGE_TOL: f64 = 5e-5;

    const POOLS: [&str; 3] = ["counted", "fixed", "pixel"];
    const NODES: [&str; 2] = ["compact", "full"];

    fn list_params(pool: &str, node: &str, layers: i64) -> Params {
        params(&[
            ("pool", Str(pool.into())),
            ("node", Str(node.into())),
            ("layers", Int(layers)),
        ])
    }

    #[test]
    fn equals_the_reference_within_the_pool_for_every_pool_and_node() {
        let shells = scene("shells", &[("count", Int(4)), ("segments", Int(12))]);
        let grass = scene("grass", &[("blades", Int(300))]);
        // 16 nodes per pixel on average (fixed pool) is far more than these scenes' mean depth;
        // the counted pool holds exactly their fragments.
        let points: Vec<Params> = POOLS
            .iter()
            .flat_map(|pool| NODES.iter().map(move |node| list_params(pool, node, 16)))
            .collect();
        assert_matches_reference(
            &LinkedList,
            &[&shells, &grass],
            &points,
            (48, 48),
            IMAGE_TOL,
            "16 layers composited in f32, compact nodes re-deriving attributes in f32",
            |name, cap| {
                assert_eq!(cap.overflow_pixels, Some(0), "{name}: {}", cap.notes);
                assert!(cap.flag.is_empty(), "{name}: {}", cap.flag);
            },
        );
    }

    #[test]
    fn lists_longer_than_the_workgroup_sort_equal_the_reference() {
        // 40 layers at the centre: over the resolve's 32 workgroup slots (those lists are walked
        // again into the per-thread arrays), under SORT_MAX; the rim's shorter lists stay in the
        // slots. The counted pool holds every fragment.
        let quads = scene("quads", &[("depth_complexity", Int(40))]);
        let (_, lists) = run(
            &LinkedList,
            &quads,
            48,
            40,
            &list_params("counted", "compact", 16),
        );
        assert!(lists.max_depth_complexity() > 32 && lists.max_depth_complexity() < SORT_MAX);
        let points: Vec<Params> = ["counted", "pixel"]
            .iter()
            .flat_map(|pool| NODES.iter().map(move |node| list_params(pool, node, 16)))
            .collect();
        assert_matches_reference(
            &LinkedList,
            &[&quads],
            &points,
            (48, 40),
            IMAGE_TOL,
            "40 layers composited in f32",
            |name, cap| {
                assert_eq!(cap.overflow_pixels, Some(0), "{name}: {}", cap.notes);
                assert!(cap.flag.is_empty(), "{name}: {}", cap.flag);
            },
        );
    }

    #[test]
    fn overflow_is_counted_on_a_scene_built_to_overflow() {
        // 12 full-screen-ish quads over the centre with a fixed pool of 1 node per pixel: the
        // pool holds fewer nodes than fragments, so some pixels must lose fragments.
        let s = scene("quads", &[("depth_complexity", Int(12))]);
        for node in NODES {
            let (cap, lists) = run(&LinkedList, &s, 32, 32, &list_params("fixed", node, 1));
            let total = lists.total_fragments();
            let pool = 32 * 32;
            assert!(
                total > pool,
                "the scene overflows the pool ({total} fragments)"
            );
            let ovf = cap.overflow_pixels.expect("reported");
            assert!(ovf > 0, "{node}: overflow must be counted: {}", cap.notes);
            assert_eq!(cap.flag, Flag::Overflow.into());
            // Pixels that kept every fragment are exact; the captured fragments fill the pool.
            let counts = cap.counts.as_ref().unwrap();
            assert_eq!(counts.iter().map(|&c| c as u64).sum::<u64>(), pool);
            let dc = lists.depth_complexity();
            let short = (0..dc.len()).filter(|&p| counts[p] < dc[p]).count() as u64;
            assert_eq!(
                short, ovf,
                "{node}: overflowed pixels are exactly those missing fragments"
            );
        }
    }

    #[test]
    fn a_counted_pool_holds_exactly_the_true_fragments_plus_the_declared_slack() {
        let s = scene("shells", &[("count", Int(3)), ("segments", Int(10))]);
        let (w, h) = (40u32, 36u32);
        let g = gpu();
        let gs = GpuScene::upload(g, &s, w, h);
        let total = rasterize(&s, w, h).total_fragments();
        assert!(total > 0);
        let px = (w * h) as u64;
        let tiles = (w.div_ceil(TILE_SIDE) * h.div_ceil(TILE_SIDE)) as u64;
        for (node, bytes) in [("compact", COMPACT_NODE_BYTES), ("full", FULL_NODE_BYTES)] {
            for slack in [0i64, 50] {
                let mut p = list_params("counted", node, 8);
                p.0.insert("pool_slack".into(), Int(slack));
                let pt = crate::testing::point(&LinkedList, &p);
                let c = list_config(&pt);
                let e = effect_config(&pt, c.compact).unwrap();
                let prepared = PreparedList::new(g, &gs, 8, c, &e).unwrap();
                let nodes = prepared.bytes_allocated() - prepared.bytes_overhead().unwrap();
                // Per tile ⌈count · slack / 100⌉ spare nodes: at most one more than the share.
                let most = total * (100 + slack as u64) / 100 + tiles;
                let least = total + total * slack as u64 / 100;
                assert!(
                    nodes >= least * bytes && nodes <= most * bytes,
                    "{node} slack {slack}: {nodes} B of nodes for {total} fragments"
                );
                if slack == 0 {
                    assert_eq!(nodes, total * bytes, "{node}: exactly the true fragments");
                }
                // Heads 4, lost + resolved counts 8, image 16, stand-in depth 4 B per pixel;
                // a cursor (4 B) and a range (8 B) per tile; 16 B of counters.
                assert_eq!(
                    prepared.bytes_overhead().unwrap(),
                    px * 32 + tiles * 12 + 16
                );
            }
        }
    }

    #[test]
    fn fragments_beyond_a_counted_pool_are_counted_not_written() {
        // Prepare on 6 quads of which 4 lie behind the eye, then (as a dynamic scene would) move
        // those into view with the same buffers: their tiles' sub-pools hold only what prepare
        // counted, so the extra fragments must be reported and the kept ones stay exact.
        let quads = |hidden_z: f32| {
            let m = crate::testing::quads_with_four_at(hidden_z);
            let cam = Camera::look_at(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, 60.0, 0.5, 100.0);
            Scene::new(SceneSpec::new("test", Params::new()), m, cam)
        };
        let (small, big) = (quads(10.0), quads(1.0));
        let total_small = rasterize(&small, 32, 32).total_fragments();
        let lists_big = rasterize(&big, 32, 32);
        assert!(lists_big.total_fragments() > total_small);
        let g = gpu();
        for node in NODES {
            let gs_small = GpuScene::upload(g, &small, 32, 32);
            let gs_big = GpuScene::upload(g, &big, 32, 32);
            let p = list_params("counted", node, 8);
            let mut prepared = LinkedList
                .prepare(g, &gs_small, &crate::testing::point(&LinkedList, &p))
                .unwrap();
            let mut enc = g.device.create_command_encoder(&Default::default());
            enc.copy_buffer_to_buffer(&gs_big.positions, 0, &gs_small.positions, 0, None);
            g.queue.submit([enc.finish()]);
            let mut timer = GpuTimer::new(g);
            prepared.frame(g, &gs_small, &mut timer).unwrap();
            let cap = prepared.readback(g, &gs_small).unwrap();
            assert_eq!(cap.flag, Flag::Overflow.into(), "{node}: {}", cap.notes);
            let counts = cap.counts.as_ref().unwrap();
            let kept: u64 = counts.iter().map(|&c| c as u64).sum();
            assert_eq!(
                kept, total_small,
                "{node}: every counted node is used, none twice"
            );
            let dc = lists_big.depth_complexity();
            let short = (0..dc.len()).filter(|&p| counts[p] < dc[p]).count() as u64;
            assert_eq!(cap.overflow_pixels, Some(short), "{node}: {}", cap.notes);
        }
    }

    #[test]
    fn compact_nodes_fold_fresnel_and_full_nodes_refuse_it() {
        // tests/effects.rs's Fresnel case (σ = 0.5, shells(3, 16) at 48²).
        let s = scene("shells", &[("count", Int(3)), ("segments", Int(16))]);
        let mut p = list_params("counted", "compact", 8);
        p.0.insert("effect".into(), Str("fresnel".into()));
        p.0.insert("sigma".into(), scenarios::ParamValue::Float(0.5));
        let (cap, lists) = run(&LinkedList, &s, 48, 48, &p);
        let reference =
            crate::effects::EffectConfig::from_point(&crate::testing::point(&LinkedList, &p))
                .unwrap()
                .reference(&s, &lists, cap.expected);
        let img = cap.image.as_ref().unwrap();
        let worst = reference
            .iter()
            .zip(img)
            .flat_map(|(r, g)| (0..4).map(move |c| (r[c] - g[c] as f64).abs()))
            .fold(0.0f64, f64::max);
        // As tests/effects.rs: view depth and normals interpolated from unsnapped vertices on
        // the GPU, snapped in the reference (σ·Δl up to ~1e-3 at sphere silhouettes).
        assert!(worst <= 2e-3, "fresnel error {worst}: {}", cap.notes);
        let mut full = p.clone();
        full.0.insert("node".into(), Str("full".into()));
        assert!(LinkedList
            .supports(gpu(), &crate::testing::point(&LinkedList, &full))
            .is_err());
    }

    #[test]
    fn a_fixed_pool_with_a_blended_tail_keeps_alpha_exact_and_equals_its_twin() {
        // The overflow scene above (12 quads, 1 node per pixel) and small particles (2 nodes
        // per pixel on average): fragments turned away by the pool go to the tail.
        let quads = scene("quads", &[("depth_complexity", Int(12))]);
        let particles = scene(
            "particles",
            &[
                ("count", Int(400)),
                ("size", scenarios::ParamValue::Float(0.5)),
            ],
        );
        for (s, layers) in [(&quads, 1), (&particles, 2)] {
            for node in NODES {
                let what = format!("{} node={node} layers={layers}", s.label());
                let mut p = list_params("fixed", node, layers);
                p.0.insert("tail".into(), Str("blend".into()));
                let (cap, lists) = run(&LinkedList, s, 32, 32, &p);
                let lost = cap.tailed_fragments.expect("tailed fragments reported");
                assert!(lost > 0, "{what}: the pool overflows: {}", cap.notes);
                assert_eq!(cap.dropped_fragments, Some(0), "{what}");
                let kept: u64 = cap.counts.as_ref().unwrap().iter().map(|&c| c as u64).sum();
                assert_eq!(kept + lost, lists.total_fragments(), "{what}");
                let def = cap.definition.as_ref().expect("the twin's image");
                let img = cap.image.as_ref().unwrap();
                let truth = lists.composite();
                for p in 0..lists.pixels() {
                    // ≤ 40 layers composited and summed in f32.
                    let e = (0..4)
                        .map(|c| (img[p][c] as f64 - def[p][c]).abs())
                        .fold(0.0, f64::max);
                    assert!(e <= IMAGE_TOL, "{what}: pixel {p}: {e:.2e} vs the twin");
                    // The tail's opacity is exact, so A is the ground truth's.
                    assert!(
                        (img[p][3] as f64 - truth[p][3]).abs() <= IMAGE_TOL,
                        "{what}: A at {p}"
                    );
                }
            }
        }
    }

    #[test]
    fn lists_beyond_the_sort_capacity_blend_the_farthest_into_the_tail() {
        let s = scene(
            "quads",
            &[
                ("depth_complexity", Int(140)),
                ("alpha", scenarios::ParamValue::Float(0.02)),
            ],
        );
        for node in NODES {
            let mut p = list_params("counted", node, 8);
            p.0.insert("tail".into(), Str("blend".into()));
            let (cap, lists) = run(&LinkedList, &s, 16, 16, &p);
            assert!(lists.max_depth_complexity() > SORT_MAX);
            let beyond: u64 = lists
                .depth_complexity()
                .iter()
                .map(|&d| d.saturating_sub(SORT_MAX) as u64)
                .sum();
            assert_eq!(cap.tailed_fragments, Some(beyond), "{node}: {}", cap.notes);
            let def = cap.definition.as_ref().unwrap();
            let img = cap.image.as_ref().unwrap();
            for p in 0..lists.pixels() {
                // 140 layers of α = 0.02 composited and summed in f32.
                let e = (0..4)
                    .map(|c| (img[p][c] as f64 - def[p][c]).abs())
                    .fold(0.0, f64::max);
                assert!(e <= 1e-4, "{node}: pixel {p}: {e:.2e}");
            }
        }
    }
}
