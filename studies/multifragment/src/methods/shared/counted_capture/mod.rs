//! Exact A-buffer by software rasterisation in compute (no render pass): count every pixel's
//! fragments, prefix-sum the counts into per-pixel offsets, rasterise again to fill a fragment
//! array sized exactly (8 B per fragment: depth + primitive id), then sort and fold each pixel,
//! re-deriving its fragments' attributes from their primitives (every effect, Fresnel included).
//!
//! Sources: the count → scan → fill layout is the "dynamic fragment buffer" (Maule, Comba,
//! Torchelsen & Bastos 2012); rasterising in compute follows Laine & Karras 2011 (cudaraster) in
//! spirit only — one thread per small triangle, a shared list for large ones; storing primitive
//! ids instead of attributes is the visibility buffer (Burns & Hunt 2013). It exists because the
//! mission's GPU (an H100) has few raster units: the same capture in compute may beat the
//! fragment pipeline there, which the rows measure rather than assume.
//!
//! The fragment array is sized by one count at prepare time (the scene is static); every frame
//! counts again and a fragment beyond the allocation is counted as lost (flag `overflow`), never
//! silent — a dynamic scene would grow the array from that count, as engines do.
//!
//! Speed axes (each exact; what they trade is in results/reference/2026-12-03-h200-resolve/perf-abuffer/PERF.md, beside the run that measured them):
//! - `transform = vertex|triangle`: `vertex` (default) transforms every vertex once into a
//!   16 B-per-vertex clip buffer that count, fill and resolve read; `triangle` transforms each
//!   triangle's corners in every kernel (the first version).
//! - `coverage = stepped|direct`: `stepped` (default) steps exact integer edge functions from
//!   pixel to pixel (i32 for triangles spanning ≤ 126 px, emulated 64-bit otherwise) and
//!   classifies big triangles' 32×32 tiles as empty/full/partial from their corners; `direct`
//!   evaluates three 64-bit products per bounding-box pixel (the first version).
//! - `resolve_sort = workgroup|private`: `workgroup` (default) insertion-sorts lists of up to 32
//!   fragments in workgroup memory (16 KiB per 8×8 pixels) — into a ring, from its nearer end,
//!   so lists that arrive in depth order or reversed cost no moves — longer ones in a per-thread
//!   array; `private` sorts every list in the per-thread array (the first version).
//! - `capture = pixels|tiles|auto`: `pixels` is the count → scan → fill above (`auto`, compute_abuffer's
//!   default, picks one of the two at prepare from a census of the scene's fragments); with
//!   `tiles` (binned.wgsl) what one thread would not rasterise (bounding box over `small_max`,
//!   long or clipped) is binned to 8×8-pixel tiles instead of shared by tiles of the raster
//!   (an 8 B entry per tile it may touch, counted, scanned and filled with the fragments), and
//!   the resolve, one workgroup per tile, sets each binned triangle up once and tests every pixel
//!   against it, inserting covered fragments straight into the sort: a big triangle costs no
//!   per-fragment atomic, store or reload. Passes keep their labels (`count`, `fill` of
//!   fragments and entries). Single-sample only.
//! - `attributes = clip|snapped`: the resolve re-derives a fragment's attributes from its
//!   triangle; `clip` (default) weights them by the 2D homogeneous weights of the unsnapped
//!   clip-space triangle, `snapped` by the perspective-corrected barycentrics of the snapped
//!   screen triangle from exact i32 edge functions, as the reference does (clip-space weights
//!   where a triangle was clipped or spans over 126 px). Snapped reads each vertex's screen
//!   position and clip w (two 8 B loads, as many as the clip-space weights' x, y and z, w; the
//!   transform marks a vertex outside the depth range or guard band, so no clip test is made
//!   per fragment) and divides once (e·w·w normalised: the area and the w cancel). They differ on slivers thinner than a
//!   pixel: on the ogre at 512² (lavapipe) `clip` is `image_differs` at 2 pixels and off at 347
//!   more within their order bound, `snapped` at none and 2. Not yet timed on a GPU.
//!
//! - `bindings = auto|packed` (plan.rs): `auto` keeps the native ten storage buffers per stage
//!   where the device allows them and packs them into six where it does not (WebGPU's default
//!   eight: the mesh packed at prepare into one 48 B-a-vertex buffer, the work counters after the
//!   offsets), so the fragments can take three bindings of WebGPU's 128 MiB; `packed` forces it.
//!   Where workgroup memory is short (WebGPU's 16 KiB with `capture = tiles`) the resolve's ring
//!   holds 16 fragments instead of 32; where a workgroup may have only 128 threads (WebGPU's
//!   compatibility mode) the transform and the scan run 128 wide.
//!
//! Antialiasing (`aa`): `aa_capture = coverage` tests coverage at the MSAA sample positions
//! (Vulkan's standard locations) by the same exact integer rule, in the count and fill passes
//! alike, and stores one fragment per pixel with its coverage mask packed into the tag (8 B
//! still: primitive in 23 bits, so at most 2^23 triangles); the resolve folds each sample over
//! the fragments covering it (attributes and depth at the pixel centre) and averages. No MSAA
//! hardware is involved: every sample count runs on every adapter. `ssaa2x2` rasterises at twice
//! the width and height and box-filters.
//!
//! Memory: `bytes_overhead` is the per-pixel part (offsets, scan block sums, counters, output
//! images); the rest is the fragments (8 B each), the clip buffer (24 B per vertex with
//! `transform = vertex`) and the big-triangle list (2 words per big triangle + 1 per tile).

use crate::aa::{AaCapture, AaMode};
use crate::effects::{EffectConfig, FOLD_WGSL as EFFECTS_WGSL};
use crate::methods::shared::store;
use crate::methods::{Capture, Expected, FrameStats, Prepared};
use bench_core::bind::{mesh_buffers, pipeline_layout, Bindings, Kind as B, Res};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, GpuScene};
use bench_core::gpu_util::{check_storage_size, compute_pipeline, read_vec, shader, STORAGE_RW};
use bench_core::record::Flag;
use bench_core::timing::GpuTimer;
use bench_core::{CoreError, Result};
use plan::Plan;

pub(crate) mod plan;

const WGSL: &str = include_str!("compute_abuffer.wgsl");
/// `capture = tiles`: triangles binned to 8×8 tiles, fragments kept in workgroup memory.
const BINNED_WGSL: &str = include_str!("binned.wgsl");
/// Attribute re-derivation from a primitive id, over the scene's own mesh buffers (for
/// `linked_list`'s compact nodes; the capture's own mesh accessors come with its binding plan).
pub const VISIBILITY_WGSL: &str = concat!(
    include_str!("visibility.wgsl"),
    "\n",
    include_str!("mesh.wgsl")
);
/// Attribute re-derivation without the mesh accessors (the binding plan gives them).
const VISIBILITY_CORE_WGSL: &str = include_str!("visibility.wgsl");
/// Double-f32 arithmetic (error-free transformations), for the snapped screen positions.
pub const DF32_WGSL: &str = include_str!("df32.wgsl");
/// Helpers of replay kernels (a pixel's slots, sorted into primitive order in place).
const REPLAY_WGSL: &str = include_str!("replay.wgsl");
/// First `work` word a replay kernel may use for its counters (`W_REPLAY` in replay.wgsl).
const W_REPLAY: usize = 10;

/// A kernel that replaces the resolve (the ideal-order twins `mlab_ideal`, `adaptive_ideal`):
/// it sees every captured fragment of its pixel, so it can run an order-dependent rule in
/// primitive order, which is what the rule gives with ordering hardware. `wgsl` is appended to
/// the module (with `replay.wgsl`); `entry` runs on 8×8 pixel workgroups; it may use the `work`
/// words `W_REPLAY..W_REPLAY + 6` as counters (read back by [`PreparedAbuffer::replay_counters`]).
pub(crate) struct Replay {
    pub wgsl: String,
    pub entry: &'static str,
    pub constants: Vec<(&'static str, f64)>,
}
/// The resolve's per-pixel sort capacity (`SORT_MAX` in the WGSL).
pub const SORT_MAX: u32 = 128;
/// Bytes per stored fragment: f32 window depth + u32 primitive id (bit 31: front facing).
pub const FRAG_BYTES: u64 = 8;
/// Words of counters at the head of the `work` buffer (`W_BLOCKS` in the WGSL).
pub(crate) const COUNTERS: u64 = 16;
/// Pixels per scan block (256 threads × 4).
pub(crate) const SCAN_BLOCK: u64 = 1024;
/// Largest dispatch dimension wgpu guarantees.
const MAX_GROUPS: u32 = 65_535;
/// Pixels of a shared triangle's tiles, and their widest width (`TILE_PIXELS`, `TILE_W` in the
/// WGSL; a narrower box gets narrower, taller tiles, so no tile is under 32 px tall).
const TILE_PIXELS: u32 = 1024;
pub(crate) const TILE_W: u32 = 32;
/// Bytes per vertex of the clip buffer (`transform = vertex`): clip position and snapped screen
/// position.
pub(crate) const CLIP_BYTES: u64 = 24;

/// Primitive bits of a tag that carries an 8-bit coverage mask.
pub(crate) const MASKED_PRIM_BITS: u32 = 23;

/// The speed axes (module doc): each choice is exact, they trade work against memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Variants {
    /// `transform = vertex`: one clip-space transform per vertex, into a buffer.
    pub pretransform: bool,
    /// `coverage = stepped`: edge functions stepped, big triangles' tiles classified.
    pub stepped: bool,
    /// `resolve_sort = workgroup`: short lists sorted in workgroup memory.
    pub wg_sort: bool,
    /// MSAA coverage-mask samples (1: pixel centres).
    pub aa_samples: u32,
    /// `capture = tiles`: triangles binned to 8×8 tiles, each tile's pixels test its triangles
    /// and sort what covers them in workgroup memory (no fragment array); single-sample only.
    pub binned: bool,
    /// `attributes = snapped`: attributes weighted as the snapped screen triangle's.
    pub snapped_attrs: bool,
    /// `bindings = packed`: within eight storage buffers per stage on any adapter (plan.rs).
    pub packed: bool,
    /// Fragments a pixel's workgroup ring holds ([`plan::RING`], or [`plan::RING_SHORT`]
    /// where workgroup memory is short).
    pub ring: u32,
}

/// Pixels per side of a bin tile (`BIN` in binned.wgsl; one resolve workgroup).
pub(crate) const BIN: u32 = 8;
/// `FAST_SPAN` of binned.wgsl (edges stepped in i32 within a tile); a test lowers it to send
/// every binned triangle down the 64-bit path, which no small test scene reaches otherwise.
#[cfg(test)]
pub(crate) static FAST_SPAN: std::sync::atomic::AtomicI32 =
    std::sync::atomic::AtomicI32::new(150_000_000);
/// Primitive bits of a bin entry (`FAN_SHIFT`: a clipped polygon's fan triangle above them).
const BIN_PRIM_BITS: u32 = 28;

/// Workgroup memory of the binned resolve's triangle entries (`be_*`, the tile's range and its
/// overflow flag).
const BIN_ENTRY_BYTES: u32 = 3 * 64 * 16 + 192 * 16 + 8 + 8 + 2 * 64 * 4;

impl Variants {
    /// Workgroup memory the resolve needs: the sort rings (any binned resolve declares them),
    /// and the binned resolve's triangle entries.
    pub(crate) fn workgroup_bytes(&self) -> u32 {
        let rings = plan::ring_bytes(self.ring);
        match (self.binned, self.wg_sort) {
            (true, _) => rings + BIN_ENTRY_BYTES,
            (false, true) => rings,
            (false, false) => 0,
        }
    }

    /// These variants with the largest workgroup ring that fits `have` bytes of workgroup memory
    /// ([`plan::RING`], else [`plan::RING_SHORT`]); None where neither does.
    pub(crate) fn fit_workgroup(self, have: u32) -> Option<Variants> {
        [plan::RING, plan::RING_SHORT]
            .into_iter()
            .map(|ring| Variants { ring, ..self })
            .find(|v| v.workgroup_bytes() <= have)
    }

    /// The axis value that needs [`Self::workgroup_bytes`], for a skip reason.
    pub(crate) fn name(&self) -> &'static str {
        if self.binned {
            "capture = tiles"
        } else {
            "resolve_sort = workgroup"
        }
    }

    /// The override constants every kernel of this variant shares.
    fn aa_constants(&self) -> [(&'static str, f64); 3] {
        let ms = self.aa_samples > 1;
        let bits = if ms { MASKED_PRIM_BITS } else { 31 };
        [
            ("AA_SAMPLES", self.aa_samples as f64),
            ("TAG_PRIM_BITS", bits as f64),
            ("EXTRAPOLATE", flag(ms)),
        ]
    }
}

fn flag(b: bool) -> f64 {
    if b {
        1.0
    } else {
        0.0
    }
}

/// `struct Sizes` of the WGSL: what varies with the scene, read at run time.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Sizes {
    ntri: u32,
    npix: u32,
    nblocks: u32,
    capacity: u32,
    big_cap: u32,
    chunk_cap: u32,
    small_max: u32,
    nvert: u32,
    /// Word of the work counters in their buffer (after the offsets where packed).
    work_base: u32,
    _pad: [u32; 3],
}

/// The two raster kernels of one mode (count or fill).
struct Kernels {
    small: wgpu::ComputePipeline,
    big: wgpu::ComputePipeline,
}

pub(crate) struct PreparedAbuffer {
    transform: Option<(wgpu::ComputePipeline, (u32, u32))>,
    count: Kernels,
    fill: Kernels,
    scan: [wgpu::ComputePipeline; 3],
    resolve: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
    /// The offsets, and the buffer holding the work counters from word `work_base` (the same
    /// buffer where packed).
    offs: wgpu::Buffer,
    work: wgpu::Buffer,
    work_base: u64,
    image: wgpu::Buffer,
    capacity: u64,
    /// The bindings the capture was prepared with (the `split` column).
    plan: Plan,
    /// Workgroups of `raster_small` (one thread per triangle).
    small_groups: (u32, u32),
    /// Workgroups of `raster_big`: one per chunk of the prepare-time big triangles.
    big_groups: (u32, u32),
    /// Workgroups of the three scan kernels.
    scan_groups: [(u32, u32); 3],
    images: usize,
    prep_note: String,
    pub aa_samples: u32,
    shape: ScanShape,
    binned: bool,
    _sizes: wgpu::Buffer,
    /// The clip buffer, the fragments and (packed) the packed mesh, kept for the bind group.
    _kept: Vec<wgpu::Buffer>,
    alloc: AllocCounter,
    overhead: u64,
}

struct Layout {
    module: wgpu::ShaderModule,
    table: Bindings,
    pipeline: wgpu::PipelineLayout,
    /// The plan's `WIDE` (threads a transform and scan workgroup).
    wide: u32,
}

/// What the scan runs over and how `offs` is laid out: every pixel's fragment count (the pixel
/// capture), or every bin tile's entries followed by each pixel's fragment count, which the
/// resolve writes (`capture = tiles`).
#[derive(Clone, Copy)]
struct ScanShape {
    scanned: u64,
    nblocks: u64,
    offs_words: u64,
}

/// Scenes the capture cannot take: more pixels than one scan dispatch, or more triangles than
/// a coverage-mask tag can name. Ok: what the scan runs over.
fn check_scene(scene: &GpuScene, v: Variants) -> Result<ScanShape> {
    let px = scene.pixels() as u64;
    let tiles = (scene.width.div_ceil(BIN) * scene.height.div_ceil(BIN)) as u64;
    let shape = if v.binned {
        ScanShape {
            scanned: px + tiles,
            nblocks: (px + tiles).div_ceil(SCAN_BLOCK),
            offs_words: px + tiles + px,
        }
    } else {
        ScanShape {
            scanned: px,
            nblocks: px.div_ceil(SCAN_BLOCK),
            offs_words: px,
        }
    };
    if shape.nblocks > MAX_GROUPS as u64 {
        return Err(CoreError::Param(format!(
            "compute_abuffer scans at most {} pixels (and tiles), not {}",
            MAX_GROUPS as u64 * SCAN_BLOCK,
            shape.scanned
        )));
    }
    let ntri = scene.index_count / 3;
    if v.binned && ntri >= 1 << BIN_PRIM_BITS {
        return Err(CoreError::Param(format!(
            "compute_abuffer with capture = tiles names primitives in {BIN_PRIM_BITS} bits of a bin entry: {ntri} triangles are too many"
        )));
    }
    if v.aa_samples > 1 && ntri >= 1 << MASKED_PRIM_BITS {
        return Err(CoreError::Param(format!(
            "compute_abuffer with coverage masks tags primitives in {MASKED_PRIM_BITS} bits: {ntri} triangles are too many"
        )));
    }
    Ok(shape)
}

impl Layout {
    /// The module (with `replay`'s kernel) over `plan`'s bindings, its one bind group's table
    /// and pipeline layout.
    fn new(gpu: &Gpu, replay: Option<&Replay>, plan: &Plan) -> Layout {
        let extra = replay.map_or(String::new(), |r| format!("{REPLAY_WGSL}\n{}", r.wgsl));
        let src = format!(
            "{}\n{WGSL}\n{BINNED_WGSL}\n{DF32_WGSL}\n{VISIBILITY_CORE_WGSL}\n{EFFECTS_WGSL}\n{extra}",
            plan.wgsl()
        );
        let module = shader(gpu, "compute_abuffer", &src);
        let rows = plan.rows();
        let table = Bindings::new(gpu, "compute_abuffer", wgpu::ShaderStages::COMPUTE, &rows);
        let pipeline = pipeline_layout(gpu, "compute_abuffer", &[&table.layout]);
        Layout {
            module,
            table,
            pipeline,
            wide: plan.wide,
        }
    }
}

/// The offsets and the work counters: two buffers, or (packed) one with the counters after
/// the offsets.
struct Counters {
    offs: wgpu::Buffer,
    work: wgpu::Buffer,
    /// Word of the counters in `work`.
    base: u64,
}

impl Counters {
    /// `offs_words` of offsets and `work_words` of work, as `plan` lays them; Err names a
    /// binding over the limit.
    fn new(
        gpu: &Gpu,
        alloc: &mut AllocCounter,
        plan: &Plan,
        (offs_words, work_words): (u64, u64),
    ) -> Result<Counters> {
        if plan.packed {
            let bytes = (offs_words + work_words) * 4;
            check_storage_size(gpu, "compute_abuffer offsets and work", bytes)?;
            let b = alloc.buffer(gpu, "abuffer offsets and work", bytes, STORAGE_RW);
            return Ok(Counters {
                offs: b.clone(),
                work: b,
                base: offs_words,
            });
        }
        check_storage_size(gpu, "compute_abuffer work", work_words * 4)?;
        Ok(Counters {
            offs: alloc.buffer(gpu, "abuffer offsets", offs_words * 4, STORAGE_RW),
            work: alloc.buffer(gpu, "abuffer work", work_words * 4, STORAGE_RW),
            base: 0,
        })
    }
}

/// The scene's mesh packed for `bindings = packed` (pack.wgsl), counted in `alloc`.
fn packed_mesh(
    gpu: &Gpu,
    alloc: &mut AllocCounter,
    scene: &GpuScene,
    nvert: u32,
) -> Result<wgpu::Buffer> {
    let bytes = nvert.max(1) as u64 * plan::PACKED_VERTEX_BYTES;
    check_storage_size(gpu, "compute_abuffer packed mesh", bytes)?;
    let verts = alloc.buffer(gpu, "abuffer packed mesh", bytes, STORAGE_RW);
    let module = shader(gpu, "compute_abuffer pack", plan::PACK_WGSL);
    let rows: Vec<(u32, B)> = (0..4)
        .map(|b| (b, B::StorageRo))
        .chain([(4, B::Storage)])
        .collect();
    let table = Bindings::new(gpu, "abuffer pack", wgpu::ShaderStages::COMPUTE, &rows);
    let layout = pipeline_layout(gpu, "abuffer pack", &[&table.layout]);
    let p = compute_pipeline(gpu, "pack_mesh", &layout, &module, "pack_mesh", &[], false);
    let [pos, nrm, col, ids, _] = mesh_buffers(scene);
    let bind = table.group(gpu, &[pos, nrm, col, ids, &verts].map(Res::Buf));
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    let groups = [(&p, (nvert.div_ceil(64).clamp(1, MAX_GROUPS), 1))];
    dispatch(&mut enc, None, "pack mesh", &bind, &groups);
    gpu.queue.submit([enc.finish()]);
    Ok(verts)
}

/// A uniform buffer the size of `T`, written later.
fn uniform_of<T>(gpu: &Gpu, label: &str) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: std::mem::size_of::<T>() as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The clip buffer (`transform = vertex`: written each frame), or a one-vertex stand-in.
fn clip_buffer(
    gpu: &Gpu,
    alloc: &mut AllocCounter,
    v: Variants,
    nvert: u32,
) -> Result<wgpu::Buffer> {
    let bytes = if v.pretransform {
        nvert.max(1) as u64 * CLIP_BYTES
    } else {
        CLIP_BYTES
    };
    check_storage_size(gpu, "compute_abuffer clip buffer", bytes)?;
    Ok(alloc.buffer(gpu, "abuffer clip positions", bytes, STORAGE_RW))
}

/// What every bind group of one capture shares: the scene (or its packed mesh), the sizes and
/// the clip buffer.
struct Fixed<'a> {
    scene: &'a GpuScene,
    verts: Option<&'a wgpu::Buffer>,
    sizes: &'a wgpu::Buffer,
    clipv: &'a wgpu::Buffer,
}

impl Fixed<'_> {
    /// The bind group of `l` (its plan's rows) over `frags`' parts, `c` and `image`.
    fn group(
        &self,
        gpu: &Gpu,
        l: &Layout,
        frags: &[wgpu::Buffer],
        c: &Counters,
        image: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        let mut bufs = vec![&self.scene.camera];
        match self.verts {
            Some(vs) => bufs.extend([vs, &self.scene.indices, &c.offs, &frags[0], image]),
            None => {
                bufs.extend(mesh_buffers(self.scene));
                bufs.extend([&c.offs, &frags[0], &c.work, image]);
            }
        }
        bufs.extend([self.sizes, self.clipv]);
        bufs.extend(&frags[1..]);
        let res: Vec<Res> = bufs.into_iter().map(Res::Buf).collect();
        l.table.group(gpu, &res)
    }
}

/// The kernels of a frame that run before the fill, on one layout.
struct Front {
    transform: Option<(wgpu::ComputePipeline, (u32, u32))>,
    count: Kernels,
    scan: [wgpu::ComputePipeline; 3],
}

impl Front {
    fn new(gpu: &Gpu, l: &Layout, v: Variants, nvert: u32) -> Front {
        let scan = ["scan_blocks", "scan_sums", "scan_add"]
            .map(|e| compute_pipeline(gpu, e, &l.pipeline, &l.module, e, &[], false));
        let transform = v.pretransform.then(|| {
            let (pl, m) = (&l.pipeline, &l.module);
            let p = compute_pipeline(gpu, "transform", pl, m, "transform", &[], false);
            (p, (nvert.div_ceil(l.wide).clamp(1, MAX_GROUPS), 1))
        });
        Front {
            transform,
            count: kernels(gpu, l, false, v),
            scan,
        }
    }

    fn pre(&self) -> Vec<Job<'_>> {
        self.transform.iter().map(|(p, g)| (p, *g)).collect()
    }
}

/// Reads `count` words of `buf` from word `at`.
fn read_words_at(gpu: &Gpu, buf: &wgpu::Buffer, at: u64, count: u64) -> Result<Vec<u32>> {
    let tmp = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("abuffer counters read-back"),
        size: count * 4,
        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(buf, at * 4, &tmp, 0, count * 4);
    gpu.queue.submit([enc.finish()]);
    read_vec::<u32>(gpu, &tmp, count as usize)
}

/// A kernel and its workgroups (x, y).
type Job<'a> = (&'a wgpu::ComputePipeline, (u32, u32));

/// A prepare-time count: clears the offsets and the counters, runs `jobs` (label, dispatches),
/// waits, and reads back the counters.
fn sizing_count(
    gpu: &Gpu,
    bind: &wgpu::BindGroup,
    c: &Counters,
    jobs: &[(&str, &[Job])],
) -> Result<Vec<u32>> {
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    enc.clear_buffer(&c.offs, 0, None);
    enc.clear_buffer(&c.work, 0, None);
    for (label, job) in jobs {
        dispatch(&mut enc, None, label, bind, job);
    }
    gpu.queue.submit([enc.finish()]);
    read_words_at(gpu, &c.work, c.base, COUNTERS)
}

/// The fragment slots for `total` counted slots of 8 B (fragments, and with `capture = tiles`
/// bin entries) over `plan`'s bindings: (capacity, the plan sized, its buffers); Err where the
/// slot indices or the adapter's bindings cannot hold them.
fn fragment_buffers(
    gpu: &Gpu,
    alloc: &mut AllocCounter,
    plan: &Plan,
    total: u64,
) -> Result<(u64, Plan, Vec<wgpu::Buffer>)> {
    let capacity = total.max(1);
    if capacity >= u32::MAX as u64 {
        return Err(CoreError::OutOfMemory(format!(
            "compute_abuffer: {total} fragments do not fit 32-bit slot indices"
        )));
    }
    let plan = plan.sized(gpu, capacity)?;
    let frags = store::split_buffers(gpu, alloc, "abuffer fragments", &plan.frags);
    Ok((capacity, plan, frags))
}

/// What the prepare-time counts found, for the rows' notes.
fn prep_note(
    v: Variants,
    plan: &Plan,
    total: u64,
    (nbig, nchunks): (u64, u64),
    freed: u64,
) -> String {
    let bindings = match (plan.packed, plan.frags.parts) {
        (false, 1) => String::new(),
        (p, n) => format!(
            "; bindings {} (fragments over {n})",
            if p { "packed" } else { "native" }
        ),
    };
    let ring = format!("; workgroup ring of {}", v.ring);
    if v.binned {
        return format!(
            "sized by prepare-time counts: {total} slots of 8 B (small triangles' fragments and the other triangles' entries in {BIN}×{BIN}-px tiles), {nbig} polygons binned by workgroups (big or clipped), {freed} B of sizing scratch freed{bindings}{ring}"
        );
    }
    format!(
        "sized by prepare-time counts: {total} fragments, {nbig} shared (big or clipped) triangles in {nchunks} tiles of {TILE_PIXELS} px (≤ {TILE_W} wide), {freed} B of sizing scratch freed{bindings}{ring}"
    )
}

/// The resolve, or a replay kernel in its place (the ideal-order twins). A replay runs
/// single-sample, so the override defaults (one sample, 31 primitive bits) are its tag layout.
fn resolve_kernel(
    gpu: &Gpu,
    l: &Layout,
    effect: &EffectConfig,
    v: Variants,
    replay: Option<&Replay>,
) -> wgpu::ComputePipeline {
    let (entry, rc) = match replay {
        None => {
            let mut rc = effect.constants();
            rc.push(("PRETRANSFORM", flag(v.pretransform)));
            rc.push(("WG_SORT", flag(v.wg_sort)));
            rc.push(("SNAPPED_ATTRS", flag(v.snapped_attrs)));
            rc.extend(v.aa_constants());
            #[cfg(test)]
            rc.push((
                "FAST_SPAN",
                FAST_SPAN.load(std::sync::atomic::Ordering::Relaxed) as f64,
            ));
            (
                if v.binned {
                    "resolve_binned"
                } else {
                    "resolve"
                },
                rc,
            )
        }
        Some(r) => {
            let mut c = r.constants.clone();
            c.push(("PRETRANSFORM", flag(v.pretransform)));
            (r.entry, c)
        }
    };
    compute_pipeline(gpu, entry, &l.pipeline, &l.module, entry, &rc, false)
}

/// Workgroups (x, y) for `n` one-dimensional jobs within the dispatch limit; none for 0.
fn groups_2d(n: u32) -> (u32, u32) {
    let x = n.min(MAX_GROUPS);
    if x == 0 {
        (0, 0)
    } else {
        (x, n.div_ceil(x))
    }
}

fn kernels(gpu: &Gpu, l: &Layout, fill: bool, v: Variants) -> Kernels {
    let [aa_n, aa_bits, aa_x] = v.aa_constants();
    let c = [
        ("FILL", flag(fill)),
        ("TILES", flag(v.binned)),
        ("PRETRANSFORM", flag(v.pretransform)),
        ("STEPPED", flag(v.stepped)),
        aa_n,
        aa_bits,
        aa_x,
    ];
    let mk = |entry: &str| compute_pipeline(gpu, entry, &l.pipeline, &l.module, entry, &c, false);
    let (small, big) = if v.binned {
        ("raster_small", "bin_big")
    } else {
        ("raster_small", "raster_big")
    };
    Kernels {
        small: mk(small),
        big: mk(big),
    }
}

fn dispatch(
    enc: &mut wgpu::CommandEncoder,
    timer: Option<&mut GpuTimer>,
    label: &str,
    bind: &wgpu::BindGroup,
    jobs: &[(&wgpu::ComputePipeline, (u32, u32))],
) {
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: timer.and_then(|t| t.compute_pass(label)),
    });
    pass.set_bind_group(0, bind, &[]);
    for (p, (x, y)) in jobs {
        if *x > 0 && *y > 0 {
            pass.set_pipeline(p);
            pass.dispatch_workgroups(*x, *y, 1);
        }
    }
}

impl PreparedAbuffer {
    /// The exact capture with `replay` in place of the resolve (default speed axes).
    pub(crate) fn replay(gpu: &Gpu, scene: &GpuScene, replay: &Replay) -> Result<Self> {
        let v = Variants {
            pretransform: true,
            stepped: true,
            wg_sort: false,
            aa_samples: 1,
            binned: false,
            snapped_attrs: false,
            packed: false,
            ring: plan::RING,
        };
        Self::new(gpu, scene, 256, &EffectConfig::default(), v, Some(replay))
    }

    /// The replay kernel's counters (`work[W_REPLAY..W_REPLAY + 6]`) after the last frame.
    pub(crate) fn replay_counters(&self, gpu: &Gpu) -> Result<[u32; 6]> {
        let c = read_words_at(gpu, &self.work, self.work_base, W_REPLAY as u64 + 6)?;
        Ok(std::array::from_fn(|i| c[W_REPLAY + i]))
    }

    pub(crate) fn new(
        gpu: &Gpu,
        scene: &GpuScene,
        small_max: u32,
        effect: &EffectConfig,
        v: Variants,
        replay: Option<&Replay>,
    ) -> Result<Self> {
        let px = scene.pixels() as u64;
        let shape = check_scene(scene, v)?;
        let nblocks = shape.nblocks;
        let ntri = scene.index_count / 3;
        let nvert = (scene.positions.size() / 12) as u32;
        let plan = Plan::before_sizing(gpu, v);
        let mut l = Layout::new(gpu, replay, &plan);
        let sizes = |capacity: u64, big_cap: u64, chunk_cap: u64, work_base: u64| Sizes {
            ntri,
            npix: shape.scanned as u32,
            nblocks: nblocks as u32,
            capacity: capacity as u32,
            big_cap: big_cap as u32,
            chunk_cap: chunk_cap as u32,
            small_max,
            nvert,
            work_base: work_base as u32,
            _pad: [0; 3],
        };
        let sizes_buf = uniform_of::<Sizes>(gpu, "abuffer sizes");
        let set_sizes = |s: Sizes| {
            gpu.queue
                .write_buffer(&sizes_buf, 0, bytemuck::bytes_of(&s))
        };
        let scan_groups = [(nblocks as u32, 1), (1, 1), (nblocks as u32, 1)];
        let mut front = Front::new(gpu, &l, v, nvert);
        let small_groups = (ntri.div_ceil(64).clamp(1, MAX_GROUPS), 1);
        let mut alloc = AllocCounter::default();
        let clipv = clip_buffer(gpu, &mut alloc, v, nvert)?;
        let verts = match plan.packed {
            true => Some(packed_mesh(gpu, &mut alloc, scene, nvert)?),
            false => None,
        };
        let images = effect.effect.image_count();
        let image_bytes = px * 16 * images as u64;
        check_storage_size(gpu, "compute_abuffer image", image_bytes)?;
        let fixed = Fixed {
            scene,
            verts: verts.as_ref(),
            sizes: &sizes_buf,
            clipv: &clipv,
        };
        let bind_with = |l: &Layout, frags: &[wgpu::Buffer], c: &Counters, image: &wgpu::Buffer| {
            fixed.group(gpu, l, frags, c, image)
        };

        // Sizing, in two counts read back: (1) list the big triangles (a list as long as the
        // scene, no chunk table) for their number and chunks; (2) with the exact list and table,
        // count every fragment. Each frame then runs (2) again before filling.
        let mut scratch = AllocCounter::default();
        let work_words =
            |big: u64, chunks: u64| COUNTERS + nblocks + 2 * big.max(1) + chunks.max(1);
        let stand_in =
            |s: &mut AllocCounter, what: &str, bytes| s.buffer(gpu, what, bytes, STORAGE_RW);
        let dummy = vec![stand_in(&mut scratch, "abuffer fragments (sizing)", 8)];
        let dummy_image = stand_in(&mut scratch, "abuffer image (sizing)", 16);
        let listing = Counters::new(
            gpu,
            &mut scratch,
            &plan,
            (shape.offs_words, work_words(ntri as u64, 0)),
        )?;
        set_sizes(sizes(0, ntri as u64, 0, listing.base));
        let listing_bind = bind_with(&l, &dummy, &listing, &dummy_image);
        let pre = front.pre();
        let small = [(&front.count.small, small_groups)];
        let jobs = [("sizing: transform", &pre[..]), ("sizing: list", &small)];
        let c = sizing_count(gpu, &listing_bind, &listing, &jobs)?;
        let (nbig, nchunks) = (c[0] as u64, c[6] as u64);
        drop((listing_bind, listing));

        let counters = Counters::new(
            gpu,
            &mut alloc,
            &plan,
            (shape.offs_words, work_words(nbig, nchunks)),
        )?;
        let (big_cap, chunk_cap) = (nbig.max(1), nchunks.max(1));
        set_sizes(sizes(0, big_cap, chunk_cap, counters.base));
        // Shared raster tiles, or (binned) one workgroup per listed triangle.
        let big_groups = groups_2d(if v.binned { nbig } else { nchunks } as u32);
        let sizing_bind = bind_with(&l, &dummy, &counters, &dummy_image);
        let counts = [
            (&front.count.small, small_groups),
            (&front.count.big, big_groups),
        ];
        let scan_jobs: Vec<_> = front.scan.iter().zip(scan_groups).collect();
        let jobs = [
            ("sizing: transform", &pre[..]),
            ("sizing: count", &counts),
            ("sizing: scan", &scan_jobs),
        ];
        let c = sizing_count(gpu, &sizing_bind, &counters, &jobs)?;
        let total = c[4] as u64;
        drop((sizing_bind, pre, dummy, dummy_image));

        let (capacity, plan, frags) = fragment_buffers(gpu, &mut alloc, &plan, total)?;
        if plan.frags.parts > 1 {
            // More bindings than the sizing module declared: the kernels again over them.
            l = Layout::new(gpu, replay, &plan);
            front = Front::new(gpu, &l, v, nvert);
        }
        let image = alloc.buffer(gpu, "abuffer image", image_bytes, STORAGE_RW);
        let bind = bind_with(&l, &frags, &counters, &image);
        set_sizes(sizes(capacity, big_cap, chunk_cap, counters.base));
        let fill = kernels(gpu, &l, true, v);
        let resolve = resolve_kernel(gpu, &l, effect, v, replay);
        let prep_note = prep_note(v, &plan, total, (nbig, nchunks), scratch.bytes);
        let offs_bytes = shape.offs_words * 4;
        let overhead = offs_bytes + (COUNTERS + nblocks) * 4 + image_bytes;
        let mut kept = vec![clipv];
        kept.extend(frags);
        kept.extend(verts);
        Ok(PreparedAbuffer {
            transform: front.transform,
            count: front.count,
            fill,
            scan: front.scan,
            resolve,
            bind,
            offs: counters.offs,
            work: counters.work,
            work_base: counters.base,
            image,
            capacity,
            plan,
            small_groups,
            big_groups,
            scan_groups,
            images,
            prep_note,
            aa_samples: v.aa_samples,
            shape,
            binned: v.binned,
            _sizes: sizes_buf,
            _kept: kept,
            alloc,
            overhead,
        })
    }
}

impl bench_core::timed::Timed for PreparedAbuffer {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.offs, 0, Some(self.shape.offs_words * 4));
        enc.clear_buffer(&self.work, self.work_base * 4, Some(COUNTERS * 4));
        if let Some((p, g)) = &self.transform {
            dispatch(&mut enc, Some(timer), "transform", &self.bind, &[(p, *g)]);
        }
        dispatch(
            &mut enc,
            Some(timer),
            "count",
            &self.bind,
            &[
                (&self.count.small, self.small_groups),
                (&self.count.big, self.big_groups),
            ],
        );
        let jobs: Vec<_> = self.scan.iter().zip(self.scan_groups).collect();
        dispatch(&mut enc, Some(timer), "scan", &self.bind, &jobs);
        dispatch(
            &mut enc,
            Some(timer),
            "fill",
            &self.bind,
            &[
                (&self.fill.small, self.small_groups),
                (&self.fill.big, self.big_groups),
            ],
        );
        dispatch(
            &mut enc,
            Some(timer),
            "resolve",
            &self.bind,
            &[(
                &self.resolve,
                (scene.width.div_ceil(8), scene.height.div_ceil(8)),
            )],
        );
        gpu.queue.submit([enc.finish()]);
        Ok(FrameStats {
            // Binned, the resolve sets every binned triangle up again.
            geometry_passes: if self.binned { 3 } else { 2 },
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

impl PreparedAbuffer {
    /// Fragments per pixel (cut to what the resolve could sort) and the pixels that lost
    /// fragments to the allocation.
    fn pixel_counts(&self, gpu: &Gpu, n: usize) -> Result<(Vec<u32>, u64)> {
        let words = read_vec::<u32>(gpu, &self.offs, self.shape.offs_words as usize)?;
        if self.binned {
            // The resolve wrote each pixel's count after the tiles' ends; lost bin entries are
            // counted (and flagged) by the fill.
            let counts = words[self.shape.scanned as usize..][..n].iter();
            return Ok((counts.map(|&c| c.min(SORT_MAX)).collect(), 0));
        }
        // After the fill, offs[p] is one past pixel p's last slot: counts are the differences,
        // cut to the slots that exist and to what the resolve could sort.
        let cap_slots = self.capacity.min(u32::MAX as u64) as u32;
        let (mut prev, mut short) = (0u32, 0u64);
        let mut counts = Vec::with_capacity(n);
        for &end in &words[..n] {
            // A pixel whose slots run past the allocation lost fragments.
            short += u64::from(end > cap_slots && prev < end);
            let e = end.min(cap_slots);
            counts.push((e - prev.min(e)).min(SORT_MAX));
            prev = end;
        }
        Ok((counts, short))
    }
}

impl PreparedAbuffer {
    /// Appends to the rows' notes (what `capture = auto` chose).
    pub(crate) fn add_note(&mut self, note: &str) {
        self.prep_note = format!("{}; {note}", self.prep_note);
    }

    /// `capture = tiles`: one untimed frame's fragments, (all, stored by pixel slots): those of
    /// the triangles `raster_small` took, the rest being the binned triangles'.
    pub(crate) fn fragment_census(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<(u64, u64)> {
        assert!(self.binned, "a census of the binned capture");
        let mut timer = GpuTimer::new(gpu);
        bench_core::timed::Timed::frame(self, gpu, scene, &mut timer)?;
        let px = scene.pixels();
        let words = read_vec::<u32>(gpu, &self.offs, self.shape.offs_words as usize)?;
        // After the fill, the last pixel's word is one past the pixels' slots (they come first);
        // the resolve wrote every pixel's fragment total after the tiles' words.
        let stored = words[px - 1].min(self.capacity as u32) as u64;
        let all = words[self.shape.scanned as usize..][..px]
            .iter()
            .map(|&n| n as u64)
            .sum();
        Ok((all, stored))
    }
}

impl Prepared for PreparedAbuffer {
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let n = scene.pixels();
        let mut cap = Capture::empty();
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.image, n * self.images)?);
        let (counts, short) = self.pixel_counts(gpu, n)?;
        cap.expected = Expected::All;
        if self.aa_samples > 1 {
            // Counts are fragments per pixel (coverage masks), not per sample.
            cap.aa = Some(AaMode::Msaa(self.aa_samples));
            cap.aa_capture = Some(AaCapture::Coverage);
            cap.sample_positions =
                Some("standard (rasterised in compute at the standard positions)".into());
        } else {
            cap.counts = Some(counts);
        }
        let c = read_words_at(gpu, &self.work, self.work_base, COUNTERS)?;
        let (lost, ovf_px, dropped, total, big_lost) = (
            c[1] as u64,
            c[2] as u64,
            c[3] as u64,
            c[4] as u64,
            c[5] as u64,
        );
        let (empty, full, partial) = (c[7], c[8], c[9]);
        cap.overflow_pixels = Some(ovf_px + short);
        if lost + dropped + big_lost > 0 {
            cap.flag.add(Flag::Overflow);
        }
        let what = if self.binned {
            "bin entries"
        } else {
            "fragments"
        };
        cap.notes = format!(
            "{}; this frame {total} {what}, {lost} beyond the allocation, {dropped} beyond the sort capacity ({SORT_MAX}) in {ovf_px} pixels, {big_lost} big triangles unlisted; big-triangle tiles {empty} empty, {full} full, {partial} partial",
            self.prep_note
        );
        Ok(cap)
    }

    fn image_buffer(&self) -> Option<&wgpu::Buffer> {
        Some(&self.image)
    }

    fn split(&self) -> Option<String> {
        self.plan.column()
    }
}
