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
//! - `capture = pixels|tiles`: `pixels` (default) is the count → scan → fill above; with
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
//!   where a triangle was clipped or spans over 126 px). They differ on slivers thinner than a
//!   pixel: on the ogre at 512² (lavapipe) `clip` is `image_differs` at 2 pixels and off at 347
//!   more within their order bound, `snapped` at none and 2. Not yet timed on a GPU.
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
use crate::methods::{Capture, Expected, FrameStats, Prepared};
use bench_core::bind::{mesh_buffers, pipeline_layout, Bindings, Kind as B, Res};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, GpuScene};
use bench_core::gpu_util::{check_storage_size, compute_pipeline, read_vec, shader, STORAGE_RW};
use bench_core::record::Flag;
use bench_core::timing::GpuTimer;
use bench_core::{CoreError, Result};

const WGSL: &str = include_str!("compute_abuffer.wgsl");
/// `capture = tiles`: triangles binned to 8×8 tiles, fragments kept in workgroup memory.
const BINNED_WGSL: &str = include_str!("binned.wgsl");
/// Attribute re-derivation from a primitive id (also used by `linked_list`'s compact nodes).
pub const VISIBILITY_WGSL: &str = include_str!("visibility.wgsl");
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
/// Storage buffers the kernels bind.
pub(crate) const STORAGE_BUFFERS: u32 = 10;
/// Workgroup memory of the resolve's `resolve_sort = workgroup` (2 × 2048 words).
const WG_SORT_BYTES: u32 = 16 * 1024;
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
        match (self.binned, self.wg_sort) {
            (true, _) => WG_SORT_BYTES + BIN_ENTRY_BYTES,
            (false, true) => WG_SORT_BYTES,
            (false, false) => 0,
        }
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
    offs: wgpu::Buffer,
    work: wgpu::Buffer,
    image: wgpu::Buffer,
    capacity: u64,
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
    _clipv: wgpu::Buffer,
    alloc: AllocCounter,
    #[allow(dead_code)]
    overhead: u64,
}

struct Layout {
    module: wgpu::ShaderModule,
    table: Bindings,
    pipeline: wgpu::PipelineLayout,
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
    /// The module (with `replay`'s kernel), its one bind group's table and pipeline layout.
    fn new(gpu: &Gpu, replay: Option<&Replay>) -> Layout {
        let extra = replay.map_or(String::new(), |r| format!("{REPLAY_WGSL}\n{}", r.wgsl));
        let src = format!(
            "{WGSL}\n{BINNED_WGSL}\n{DF32_WGSL}\n{VISIBILITY_WGSL}\n{EFFECTS_WGSL}\n{extra}"
        );
        let module = shader(gpu, "compute_abuffer", &src);
        // Camera; the mesh (positions, normals, colours, object ids, indices); offsets,
        // fragments, work, image; sizes; clip buffer.
        let mut rows = vec![B::Camera];
        rows.extend([B::StorageRo; 5]);
        rows.extend([B::Storage; 4]);
        rows.extend([B::Uniform, B::Storage]);
        let table = Bindings::seq(gpu, "compute_abuffer", wgpu::ShaderStages::COMPUTE, &rows);
        let pipeline = pipeline_layout(gpu, "compute_abuffer", &[&table.layout]);
        Layout {
            module,
            table,
            pipeline,
        }
    }
}

/// A kernel and its workgroups (x, y).
type Job<'a> = (&'a wgpu::ComputePipeline, (u32, u32));

/// A prepare-time count: clears the offsets and `counted`, runs `jobs` (label, dispatches),
/// waits, and reads back the counters at the head of `counted`.
fn sizing_count(
    gpu: &Gpu,
    bind: &wgpu::BindGroup,
    [offs, counted]: [&wgpu::Buffer; 2],
    jobs: &[(&str, &[Job])],
) -> Result<Vec<u32>> {
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    enc.clear_buffer(offs, 0, None);
    enc.clear_buffer(counted, 0, None);
    for (label, job) in jobs {
        dispatch(&mut enc, None, label, bind, job);
    }
    gpu.queue.submit([enc.finish()]);
    read_vec::<u32>(gpu, counted, COUNTERS as usize)
}

/// The fragment array for `total` counted slots of 8 B (fragments, and with `capture = tiles`
/// bin entries): (capacity, buffer); Err where the slot indices or the adapter's binding limit
/// cannot hold it.
fn fragment_buffer(gpu: &Gpu, alloc: &mut AllocCounter, total: u64) -> Result<(u64, wgpu::Buffer)> {
    let capacity = total.max(1);
    if capacity >= u32::MAX as u64 {
        return Err(CoreError::OutOfMemory(format!(
            "compute_abuffer: {total} fragments do not fit 32-bit slot indices"
        )));
    }
    check_storage_size(gpu, "compute_abuffer fragments", capacity * FRAG_BYTES)?;
    let usage = wgpu::BufferUsages::STORAGE;
    let frags = alloc.buffer(gpu, "abuffer fragments", capacity * FRAG_BYTES, usage);
    Ok((capacity, frags))
}

/// What the prepare-time counts found, for the rows' notes.
fn prep_note(v: Variants, total: u64, (nbig, nchunks): (u64, u64), freed: u64) -> String {
    if v.binned {
        return format!(
            "sized by prepare-time counts: {total} slots of 8 B (small triangles' fragments and the other triangles' entries in {BIN}×{BIN}-px tiles), {nbig} polygons binned by workgroups (big or clipped), {freed} B of sizing scratch freed"
        );
    }
    format!(
        "sized by prepare-time counts: {total} fragments, {nbig} shared (big or clipped) triangles in {nchunks} tiles of {TILE_PIXELS} px (≤ {TILE_W} wide), {freed} B of sizing scratch freed"
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
        };
        Self::new(gpu, scene, 256, &EffectConfig::default(), v, Some(replay))
    }

    /// The replay kernel's counters (`work[W_REPLAY..W_REPLAY + 6]`) after the last frame.
    pub(crate) fn replay_counters(&self, gpu: &Gpu) -> Result<[u32; 6]> {
        let c = read_vec::<u32>(gpu, &self.work, W_REPLAY + 6)?;
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
        let d = &gpu.device;
        let px = scene.pixels() as u64;
        let shape = check_scene(scene, v)?;
        let nblocks = shape.nblocks;
        let ntri = scene.index_count / 3;
        let nvert = (scene.positions.size() / 12) as u32;
        let l = Layout::new(gpu, replay);
        let sizes = |capacity: u64, big_cap: u64, chunk_cap: u64| Sizes {
            ntri,
            npix: shape.scanned as u32,
            nblocks: nblocks as u32,
            capacity: capacity as u32,
            big_cap: big_cap as u32,
            chunk_cap: chunk_cap as u32,
            small_max,
            nvert,
        };
        let sizes_buf = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("abuffer sizes"),
            size: std::mem::size_of::<Sizes>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let set_sizes = |s: Sizes| {
            gpu.queue
                .write_buffer(&sizes_buf, 0, bytemuck::bytes_of(&s))
        };
        let scan_groups = [(nblocks as u32, 1), (1, 1), (nblocks as u32, 1)];
        let scan = ["scan_blocks", "scan_sums", "scan_add"]
            .map(|e| compute_pipeline(gpu, e, &l.pipeline, &l.module, e, &[], false));
        let count = kernels(gpu, &l, false, v);
        let small_groups = (ntri.div_ceil(64).clamp(1, MAX_GROUPS), 1);
        let mut alloc = AllocCounter::default();
        // The clip buffer is kept (written each frame); a one-vertex stand-in when unused.
        let clip_bytes = if v.pretransform {
            nvert.max(1) as u64 * CLIP_BYTES
        } else {
            CLIP_BYTES
        };
        check_storage_size(gpu, "compute_abuffer clip buffer", clip_bytes)?;
        let clipv = alloc.buffer(gpu, "abuffer clip positions", clip_bytes, STORAGE_RW);
        let transform = v.pretransform.then(|| {
            let (pl, m) = (&l.pipeline, &l.module);
            let p = compute_pipeline(gpu, "transform", pl, m, "transform", &[], false);
            (p, (nvert.div_ceil(256).clamp(1, MAX_GROUPS), 1))
        });
        let pre: Vec<(&wgpu::ComputePipeline, (u32, u32))> =
            transform.iter().map(|(p, g)| (p, *g)).collect();

        // Sizing, in two counts read back: (1) list the big triangles (a list as long as the
        // scene, no chunk table) for their number and chunks; (2) with the exact list and table,
        // count every fragment. Each frame then runs (2) again before filling.
        let mut scratch = AllocCounter::default();
        let offs_bytes = shape.offs_words * 4;
        let offs = scratch.buffer(gpu, "abuffer offsets", offs_bytes, STORAGE_RW);
        let work_words =
            |big: u64, chunks: u64| COUNTERS + nblocks + 2 * big.max(1) + chunks.max(1);
        let listing_bytes = work_words(ntri as u64, 0) * 4;
        check_storage_size(gpu, "compute_abuffer work", listing_bytes)?;
        let label = "abuffer big-triangle listing (sizing)";
        let listing = scratch.buffer(gpu, label, listing_bytes, STORAGE_RW);
        let dummy = scratch.buffer(gpu, "abuffer fragments (sizing)", 8, STORAGE_RW);
        let images = effect.effect.image_count();
        let image_bytes = px * 16 * images as u64;
        let dummy_image = scratch.buffer(gpu, "abuffer image (sizing)", 16, STORAGE_RW);
        let bind_with = |frags: &wgpu::Buffer, work: &wgpu::Buffer, image: &wgpu::Buffer| {
            let mut bufs = vec![&scene.camera];
            bufs.extend(mesh_buffers(scene));
            bufs.extend([&offs, frags, work, image, &sizes_buf, &clipv]);
            let res: Vec<Res> = bufs.into_iter().map(Res::Buf).collect();
            l.table.group(gpu, &res)
        };
        set_sizes(sizes(0, ntri as u64, 0));
        let listing_bind = bind_with(&dummy, &listing, &dummy_image);
        let small = [(&count.small, small_groups)];
        let jobs = [("sizing: transform", &pre[..]), ("sizing: list", &small)];
        let c = sizing_count(gpu, &listing_bind, [&offs, &listing], &jobs)?;
        let (nbig, nchunks) = (c[0] as u64, c[6] as u64);
        drop(listing_bind);
        drop(listing);

        alloc.bytes += offs_bytes; // the offsets (allocated above, kept)
        let work_bytes = work_words(nbig, nchunks) * 4;
        check_storage_size(gpu, "compute_abuffer work", work_bytes)?;
        let work = alloc.buffer(gpu, "abuffer work", work_bytes, STORAGE_RW);
        let (big_cap, chunk_cap) = (nbig.max(1), nchunks.max(1));
        set_sizes(sizes(0, big_cap, chunk_cap));
        // Shared raster tiles, or (binned) one workgroup per listed triangle.
        let big_groups = groups_2d(if v.binned { nbig } else { nchunks } as u32);
        let sizing_bind = bind_with(&dummy, &work, &dummy_image);
        let counts = [(&count.small, small_groups), (&count.big, big_groups)];
        let scan_jobs: Vec<_> = scan.iter().zip(scan_groups).collect();
        let jobs = [
            ("sizing: transform", &pre[..]),
            ("sizing: count", &counts),
            ("sizing: scan", &scan_jobs),
        ];
        let c = sizing_count(gpu, &sizing_bind, [&offs, &work], &jobs)?;
        let total = c[4] as u64;
        drop(sizing_bind);
        drop((dummy, dummy_image));

        let (capacity, frags) = fragment_buffer(gpu, &mut alloc, total)?;
        let image = alloc.buffer(gpu, "abuffer image", image_bytes, STORAGE_RW);
        let bind = bind_with(&frags, &work, &image);
        set_sizes(sizes(capacity, big_cap, chunk_cap));
        let fill = kernels(gpu, &l, true, v);
        let resolve = resolve_kernel(gpu, &l, effect, v, replay);
        let prep_note = prep_note(v, total, (nbig, nchunks), scratch.bytes - offs_bytes);
        drop(pre);
        let overhead = offs_bytes + (COUNTERS + nblocks) * 4 + image_bytes;
        Ok(PreparedAbuffer {
            transform,
            count,
            fill,
            scan,
            resolve,
            bind,
            offs,
            work,
            image,
            capacity,
            small_groups,
            big_groups,
            scan_groups,
            images,
            prep_note,
            aa_samples: v.aa_samples,
            shape,
            binned: v.binned,
            _sizes: sizes_buf,
            _clipv: clipv,
            alloc,
            overhead,
        })
    }
}

impl bench_core::timed::Timed for PreparedAbuffer {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.offs, 0, None);
        enc.clear_buffer(&self.work, 0, Some(COUNTERS * 4));
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
        let c = read_vec::<u32>(gpu, &self.work, COUNTERS as usize)?;
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
}
