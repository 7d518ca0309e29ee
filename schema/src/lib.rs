//! The CSV contract between measuring (`bench-core`) and reporting (`report`): every column of
//! `runs.csv` is declared here once, as a typed constant both crates use, so a misspelt column
//! does not compile and a renamed one is renamed everywhere. This crate is a leaf: it depends on
//! nothing and nothing here knows about GPUs, methods or studies.
//!
//! `results/README.md` documents the same list (generated from [`markdown`] by
//! `scripts/update-columns.sh`; a test checks the two agree).

use std::fmt;

mod types;
mod values;
pub use types::{cell_type, cell_type_of, CellType, NotOfType};
pub use values::{
    Flag, FlagSet, GpuMsInterval, ParseError, PointKey, Status, StudyKind, MIN_SAMPLES_CI95,
};

/// Bumped when a column is renamed or changes meaning; `mfx merge` and `mfx compare` refuse to
/// mix versions (see `results/README.md` for what changed between versions).
///
/// - 1: the first schema.
/// - 2: `variant` split into named axes (`heuristics`, `tiebreak`, `thickness`); every axis a
///   method reads is written to its row, defaults included; errors are vs the ground truth (the
///   whole composite) with `*_vs_k` for a method's own definition; `flag` is a `|`-joined set;
///   fixed `reps`/`warmup` replaced by a stopping rule (`timing_rule`, `samples`, CIs, clocks);
///   the `floor_blend` floor and `x_blend`.
/// - 3: `exact` is now a verdict on the row (no fragment lost or merged and the image within
///   `exact_bound` of the truth); the method's claim that was called `exact` is `claims_exact`.
///   New: `exact_bound`, `gpu_time_trusted`, `gpu_ms_interval`. Later in 3: `exact_bound` no
///   longer allows near-equal-depth fragments in any order (they are `depth_ties`, counted in
///   `depth_tie_pixels`), so `exact` implies `matches_truth`.
pub const SCHEMA_VERSION: u32 = 3;

/// One declared column: its name in the CSV header and what it means (units in the name).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Col {
    pub name: &'static str,
    pub doc: &'static str,
}

impl Col {
    pub const fn new(name: &'static str, doc: &'static str) -> Col {
        Col { name, doc }
    }

    /// The type of this column's cells (declared in `types.rs`).
    pub fn cell_type(self) -> CellType {
        types::cell_type(self)
    }
}

impl fmt::Display for Col {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name)
    }
}

impl AsRef<str> for Col {
    fn as_ref(&self) -> &str {
        self.name
    }
}

/// A set of columns that belong together, in file order.
#[derive(Clone, Copy, Debug)]
pub struct Group {
    pub name: &'static str,
    pub title: &'static str,
    pub cols: &'static [Col],
}

/// Every column, by group, in file order.
pub mod cols {
    use super::Col;

    // ---- Run and machine metadata, identical on every row of one run ----
    pub const SCHEMA: Col = Col::new(
        "schema",
        "CSV schema version (integer); `mfx merge` refuses to mix versions",
    );
    pub const RUN_ID: Col = Col::new(
        "run_id",
        "identifier of the sweep run (UTC time + suite + shard)",
    );
    pub const GIT_REV: Col = Col::new(
        "git_rev",
        "git commit of the mfx build (`unknown` outside a checkout); `+dirty` if modified",
    );
    pub const TIMESTAMP_UTC: Col =
        Col::new("timestamp_utc", "when the row was produced, RFC 3339 UTC");
    pub const SUITE: Col = Col::new("suite", "suite name");
    pub const STUDY: Col = Col::new(
        "study",
        "study kind that produced the row (methods, geometry, deferred, prepass, shadows, stability)",
    );
    pub const SHARD: Col = Col::new("shard", "shard index I of `--shard I/N` (0 when unsharded)");
    pub const SHARDS: Col = Col::new("shards", "shard count N (1 when unsharded)");
    pub const POINT_KEY: Col = Col::new(
        "point_key",
        "stable identity of the sweep point (study|scene|resolution|method|axes); duplicates are reported by merge",
    );
    pub const ADAPTER: Col = Col::new("adapter", "adapter name as the driver reports it");
    pub const BACKEND: Col = Col::new("backend", "wgpu backend (vulkan, gl)");
    pub const DEVICE_TYPE: Col = Col::new(
        "device_type",
        "discretegpu, integratedgpu, virtualgpu, cpu, other",
    );
    pub const DRIVER: Col = Col::new("driver", "driver name");
    pub const DRIVER_INFO: Col = Col::new("driver_info", "driver version string");
    pub const GPU_UUID: Col = Col::new(
        "gpu_uuid",
        "the physical GPU's UUID as NVML reports it (`GPU-…`, as `nvidia-smi -L`); empty without NVML (lavapipe, other vendors)",
    );
    pub const GPU_SERIAL: Col = Col::new(
        "gpu_serial",
        "the board's serial number as NVML reports it; empty where NVML has none (most non-datacentre boards) or without NVML",
    );
    pub const PCI_BUS_ID: Col = Col::new(
        "pci_bus_id",
        "the adapter's PCI address (domain:bus:device.function): NVML's where it has the device, else wgpu's adapter info; empty where neither says (lavapipe)",
    );
    pub const SLURM_JOB_ID: Col = Col::new(
        "slurm_job_id",
        "the Slurm job that ran the sweep (`SLURM_JOB_ID`); empty outside Slurm",
    );
    pub const SLURM_ARRAY_JOB_ID: Col = Col::new(
        "slurm_array_job_id",
        "the Slurm job array the job belongs to (`SLURM_ARRAY_JOB_ID`); empty outside an array",
    );
    pub const SLURM_ARRAY_TASK_ID: Col = Col::new(
        "slurm_array_task_id",
        "the task of that array (`SLURM_ARRAY_TASK_ID`; scripts/slurm runs shard I as task I); empty outside an array",
    );
    pub const ADAPTER_FEATURES: Col = Col::new(
        "adapter_features",
        "optional wgpu features granted, `|`-separated",
    );
    pub const TEXTURE_MEMORY: Col = Col::new(
        "texture_memory",
        "where render targets' memory came from: `pooled` (wgpu's shared blocks, the default) or `dedicated` (`mfx sweep --texture-memory dedicated`: each single-level, single-layer 2-D render target in a Vulkan allocation of its own; other textures, or one whose dedicated allocation failed, logged, stay pooled)",
    );
    pub const LIMITS: Col = Col::new(
        "limits",
        "the limits profile the device was requested with (`mfx sweep --limits`): `adapter` (the adapter's own, the default), `webgpu` (WebGPU's default limits and optional features only), `webgpu-compat` (WebGPU's compatibility-mode defaults: no storage buffers in vertex shaders, 4 in fragment shaders (checked by mfx: wgpu has no per-stage limit), 128 invocations a workgroup, 4096² textures) or `downlevel` (a WebGL2-class device: no compute, no storage buffers); what does not fit is a `skipped` row naming the limit",
    );
    pub const WIDTH: Col = Col::new("width", "render target width in pixels");
    pub const HEIGHT: Col = Col::new("height", "render target height in pixels");
    pub const TIMING_RULE: Col = Col::new(
        "timing_rule",
        "how each point was timed: warm-up bounds, sample bounds, the noise target on the 95 % CI of the median, the time cap (the suite's [timing])",
    );
    pub const ORDER_SEED: Col = Col::new(
        "order_seed",
        "seed of the seeded random order in which the points of a group were measured (empty: suite order)",
    );

    // ---- What was measured: scene, method, outcome ----
    pub const SCENE: Col = Col::new("scene", "scene generator name");
    pub const SCENE_LABEL: Col = Col::new(
        "scene_label",
        "generator with all its parameters, e.g. quads(depth_complexity=8,seed=1)",
    );
    pub const TRIANGLES: Col = Col::new("triangles", "triangles submitted per geometry pass");
    pub const VERTICES: Col = Col::new("vertices", "vertices in the vertex buffers");
    pub const DEPTH_COMPLEXITY_MAX: Col = Col::new(
        "depth_complexity_max",
        "true maximum fragments per pixel (CPU reference)",
    );
    pub const DEPTH_COMPLEXITY_MEAN: Col = Col::new(
        "depth_complexity_mean",
        "true mean fragments per covered pixel (CPU reference)",
    );
    pub const TRUE_FRAGMENTS: Col = Col::new(
        "true_fragments",
        "true total fragments of the frame (CPU reference)",
    );
    pub const METHOD: Col = Col::new(
        "method",
        "method or path name (see `mfx list methods`); floor_depth / floor_opaque are the floors",
    );
    pub const CLAIMS_EXACT: Col = Col::new(
        "claims_exact",
        "true if the method claims to capture every fragment exactly when within capacity (schema ≤ 2 called this `exact`)",
    );
    pub const EXACT: Col = Col::new(
        "exact",
        "true only when no fragment was lost or merged (no overflow, hazard, collision, precision, lost_coplanar, fragments_differ, image_differs), the image is within exact_bound of the f64 ground truth at every pixel (so fragments at near-equal depths composited in another order are not exact: depth_ties) and matches_truth holds; empty for rows without a judged image. matches_truth is the weaker within-tolerance label",
    );
    pub const EXACT_BOUND: Col = Col::new(
        "exact_bound",
        "the max-abs error bound `exact` was judged with: the f32 rounding of the effect's compositing over the pixel's fragments (derived in studies/multifragment/src/judge.rs); the order of fragments at near-equal depths is not part of it (depth_ties)",
    );
    pub const EFFECT: Col = Col::new(
        "effect",
        "effect computed on the captured fragments (transparency, translucency, fresnel, csg_*, dof, volume, isosurface)",
    );
    pub const STATUS: Col = Col::new("status", "ok | skipped | failed");
    pub const REASON: Col = Col::new(
        "reason",
        "why a point was skipped or failed (empty when ok)",
    );
    pub const FLAG: Col = Col::new(
        "flag",
        "known failure modes of this row, |-joined: overflow, hazard, collision, precision, lost_coplanar, fragments_differ, image_differs, depth_ties, timestamps_incomplete, noisy, throttled, gpu_shared (empty if none; each is defined in results/README.md)",
    );

    // ---- Sweep axes shared by several methods (empty where an axis does not apply) ----
    pub const LAYERS: Col = Col::new(
        "layers",
        "k: fragments kept per pixel (k-buffer, buckets, linked-list capacity per pixel; MLAB blend layers, adaptive-transparency nodes, hybrid transparency's exact core)",
    );
    pub const MAX_LAYERS: Col = Col::new(
        "max_layers",
        "upper bound on peeling passes (classic/dual depth peeling)",
    );
    pub const PAYLOAD: Col = Col::new(
        "payload",
        "what is stored per fragment: depth (signed linear depth) | rgba_depth | depth_normal | depth_id | rgba_viewz | all (uber)",
    );
    pub const OCCLUSION_STOP: Col = Col::new(
        "occlusion_stop",
        "true if peeling stops when an occlusion query counts no fragment",
    );
    pub const SPECIALISATION: Col = Col::new(
        "specialisation",
        "uber (everything stored and computed) | specialised (only what the effect reads)",
    );
    pub const HEURISTICS: Col = Col::new(
        "heuristics",
        "kbuffer_rmw: the thesis's heuristics against read-modify-write hazards: false (mesh order) | sort (centroid-sorted order) | sort_flush (sorted on the CPU every frame, 32-triangle batches, a flush after each) | true (sorted once, batches as draws of one pass, no flush)",
    );
    pub const HAZARD_CAPTURES: Col = Col::new(
        "hazard_captures",
        "kbuffer_rmw: frames captured and judged for hazards after timing (1: the one capture; more give hazard_rate_ci_lo/hi)",
    );
    pub const TIEBREAK: Col = Col::new(
        "tiebreak",
        "depth_peel: true to peel fragments at an equal depth one per pass by primitive id (keeps coplanar ties that strict peeling loses)",
    );
    pub const THICKNESS: Col = Col::new(
        "thickness",
        "translucency/fresnel: thickness arithmetic, naive (the seed's f32 running sum of ±z) or stable (per-pair differences, Kahan-summed)",
    );
    pub const BUCKET_COUNT: Col = Col::new(
        "bucket_count",
        "bucket methods: buckets per pixel per pass (8/16/32; 8 attachments × 4 channels, paired uses 2 channels per bucket)",
    );
    pub const BUCKET_MODE: Col = Col::new(
        "bucket_mode",
        "bucket methods: uniform (depth range split evenly: bdp, bdp2) | adaptive (histogram-equalised: adp)",
    );
    pub const BUCKET_PAIRING: Col = Col::new(
        "bucket_pairing",
        "bucket methods: single (one fragment per bucket) | paired (nearest and farthest of each bucket)",
    );
    pub const RANGE_PASS: Col = Col::new(
        "range_pass",
        "bucket methods: what the per-pixel depth-range pre-pass draws: mesh (every triangle) | bounding_box (the scene's 12-triangle box, GPU Pro ch. 1 §1.3)",
    );
    pub const HIST_BINS: Col = Col::new(
        "hist_bins",
        "adaptive bucket peeling: bins of the per-pixel depth-occupancy histogram (256/1024/2048)",
    );
    pub const SMALL_MAX: Col = Col::new(
        "small_max",
        "compute_abuffer: largest triangle bounding box (pixels) one thread rasterises; larger ones are shared by workgroups",
    );
    pub const TRANSFORM: Col = Col::new(
        "transform",
        "compute_abuffer: vertex (every vertex transformed once into a 16 B-per-vertex clip buffer) | triangle (each triangle's corners transformed in every kernel)",
    );
    pub const COVERAGE: Col = Col::new(
        "coverage",
        "compute_abuffer: stepped (exact integer edge functions stepped pixel to pixel; big triangles' tiles classified empty/full/partial) | direct (three exact 64-bit products per bounding-box pixel)",
    );
    pub const CAPTURE: Col = Col::new(
        "capture",
        "compute_abuffer: pixels (count → scan → fill: an 8 B fragment per pixel slot, then sort) | tiles (triangles over small_max binned to 8×8-pixel tiles instead, 8 B per tile and triangle; each tile's pixels test them and sort in workgroup memory: their fragments are never stored) | auto (the default: the method's choice at prepare, tiles where the triangles over small_max make at least 3 fragments a pixel, else pixels; the notes say which)",
    );
    pub const ATTRIBUTES: Col = Col::new(
        "attributes",
        "compute_abuffer: clip (a fragment's attributes weighted by the 2D homogeneous weights of its unsnapped clip-space triangle) | snapped (by the perspective-corrected barycentrics of its snapped screen triangle, from exact integer edge functions, as the reference and a hardware rasteriser; clip-space weights where the triangle was clipped or spans over 126 px)",
    );
    pub const RESOLVE_SORT: Col = Col::new(
        "resolve_sort",
        "compute_abuffer: workgroup (lists of up to 32 fragments sorted in workgroup memory; 16 where workgroup memory is short, as WebGPU's 16 KiB with capture = tiles) | private (every list in a per-thread array)",
    );
    pub const BINDINGS: Col = Col::new(
        "bindings",
        "compute_abuffer: auto (native bindings where the device allows 10 storage buffers per stage, else packed) | packed (6 storage buffers: the mesh packed at prepare into one 48 B-a-vertex buffer, the work counters after the offsets, so the fragments may take 3 bindings: within WebGPU's default 8). Which one ran is in `split` (`packed`) and the notes",
    );
    pub const POOL: Col = Col::new(
        "pool",
        "linked_list: counted (one sub-pool per 8×8-pixel tile, sized by a prepare-time count) | fixed (layers × pixels nodes, one cursor) | pixel (one sub-pool per pixel, sized by a prepare-time count: its nodes contiguous, so no head exchange and no link; 8 B compact nodes; single-sample)",
    );
    pub const POOL_SLACK: Col = Col::new(
        "pool_slack",
        "linked_list, counted pool: spare nodes per tile, percent of its prepare-time count",
    );
    pub const NODE: Col = Col::new(
        "node",
        "linked_list: compact (12 B: depth, primitive, next; attributes re-derived from the primitive) | full (32 B: colour, depths, object id, next)",
    );
    pub const TAIL: Col = Col::new(
        "tail",
        "bounded captures (kbuffer_rmw, kbuffer_atomic, linked_list, mlab): what happens to fragments that do not fit: drop | blend (blended out of order into a tail composited behind the kept ones); mlab also merge (its own rule, the default)",
    );
    pub const KEEP: Col = Col::new(
        "keep",
        "k-buffers: which k fragments are kept exactly: nearest (the k nearest) | first (the first k to arrive)",
    );
    pub const MOMENT_KIND: Col = Col::new(
        "moment_kind",
        "moments: power | trigonometric moments of the absorbance over warped depth",
    );
    pub const MOMENT_COUNT: Col = Col::new(
        "moment_count",
        "moments: moments besides b0: power 4, 6, 8 or trigonometric 2, 3, 4 (the paper's naming)",
    );
    pub const MOMENT_PRECISION: Col = Col::new(
        "moment_precision",
        "moments: f32 (additive blending into 32-bit float targets) | unorm16 (the paper's quantised 16-bit moments, unguarded read-modify-write in storage)",
    );
    pub const MOMENT_BIAS: Col = Col::new(
        "moment_bias",
        "moments: bias β: paper (the paper's value for the kind, count and precision) or a number",
    );
    pub const MOMENT_NORMALIZE: Col = Col::new(
        "moment_normalize",
        "moments: true to normalise the resolved colour by the total absorbance (exact for one layer)",
    );

    pub const AA: Col = Col::new(
        "aa",
        "antialiasing: none (one sample at the pixel centre) | msaa2 | msaa4 | msaa8 (MSAA at the standard sample positions) | ssaa2x2 (rendered at 2× width and height, 2×2 box filter); such rows are judged against the multisampled ground truth (the mean of the samples' exact composites)",
    );
    pub const AA_CAPTURE: Col = Col::new(
        "aa_capture",
        "MSAA capture: sample (sample shading: one fragment per covered sample, memory × samples) | coverage (one fragment per pixel with its coverage mask, resolved per sample: nvpro's OIT_COVERAGE_SHADING)",
    );
    pub const AA_SAMPLES: Col = Col::new(
        "aa_samples",
        "samples per output pixel of the row's antialiasing (1, 2, 4, 8; 4 for ssaa2x2; stochastic: st_samples)",
    );
    pub const SAMPLE_POSITIONS: Col = Col::new(
        "sample_positions",
        "MSAA rows: standard (a probe render's per-sample coverage matched the reference at Vulkan's standard sample locations) | differs: <measured positions, 1/16 px> | unverified: <why>",
    );
    pub const ST_SAMPLES: Col = Col::new(
        "st_samples",
        "stochastic: MSAA samples per pass S (4 or 8); each fragment covers ≈ α·S of them",
    );
    pub const ST_PASSES: Col = Col::new(
        "st_passes",
        "stochastic: passes accumulated (independent masks each), st_samples × st_passes samples in all",
    );
    pub const ST_CORRECTION: Col = Col::new(
        "st_correction",
        "stochastic: true to apply Enderton et al.'s alpha correction (colour × exact total alpha / stochastic alpha, from an extra accumulation pass)",
    );
    pub const ST_SEED: Col = Col::new(
        "st_seed",
        "stochastic: seed of the per-fragment sample masks (the same seed gives the same frame)",
    );

    // ---- Effect parameters (axes of the effects fold) ----
    pub const SIGMA: Col = Col::new(
        "sigma",
        "translucency/fresnel: extinction coefficient σ per world unit (Beer–Lambert exp(−σ·l)); volume: σ·s per unit of linear view depth at scalar s",
    );
    pub const CSG_A: Col = Col::new("csg_a", "csg_*: object id of operand A");
    pub const CSG_B: Col = Col::new("csg_b", "csg_*: object id of operand B");
    pub const DOF_NEAR: Col = Col::new(
        "dof_near",
        "dof: linear view depth (world units) between the foreground and midground partitions",
    );
    pub const DOF_FAR: Col = Col::new(
        "dof_far",
        "dof: linear view depth (world units) between the midground and background partitions",
    );

    pub const ISO_VALUE: Col = Col::new(
        "iso_value",
        "isosurface: the iso-value cut on the scalar field (the fragment colour's red channel) between consecutive fragments (Bavoil 2007 §6.3.1)",
    );

    // ---- The geometry study ----
    pub const BATCH_SIZE: Col = Col::new(
        "batch_size",
        "geometry: triangles per draw call asked for (0 = the whole mesh; 16-bit indices may split further, see batches)",
    );
    pub const DRAW_TRIANGLES: Col = Col::new(
        "draw_triangles",
        "geometry: triangles drawn per frame, a prefix of the ordered mesh (0 = all of it)",
    );
    pub const VERTEX_FORMAT: Col = Col::new(
        "vertex_format",
        "geometry: position format: float32x3, float16x4 or snorm16x4 (both quantised to the batch's bounding box, decoded in the vertex shader)",
    );
    pub const NORMAL_FORMAT: Col = Col::new(
        "normal_format",
        "geometry: normal format (wgpu name) or none; unorm formats store n·½+½",
    );
    pub const COLOR_FORMAT: Col = Col::new(
        "color_format",
        "geometry: colour format (wgpu name) or none",
    );
    pub const TEXCOORD_FORMAT: Col = Col::new(
        "texcoord_format",
        "geometry: texture-coordinate format (wgpu name) or none",
    );
    pub const LAYOUT: Col = Col::new(
        "layout",
        "geometry: interleaved (one vertex buffer) or separate (one buffer per attribute)",
    );
    pub const EXTRA_ATTRIBUTES: Col = Col::new(
        "extra_attributes",
        "geometry: extra float32x4 attributes per vertex (0..8; the thesis's Fig. 3.3)",
    );
    pub const INDEX_FORMAT: Col = Col::new("index_format", "geometry: uint16 or uint32 indices");
    pub const MESH_ORDER: Col = Col::new(
        "mesh_order",
        "geometry: triangle order: original, shuffled, vcache (meshopt), vcache_vfetch (meshopt cache + fetch)",
    );
    pub const INDEXED: Col = Col::new(
        "indexed",
        "geometry: true for indexed draws, false for one vertex per triangle corner",
    );
    pub const PRIMITIVE: Col = Col::new(
        "primitive",
        "geometry: list, or strip (meshopt stripify, primitive restart)",
    );
    pub const BATCHES: Col = Col::new("batches", "geometry: draw calls per frame");
    pub const BATCH_VERTICES: Col = Col::new(
        "batch_vertices",
        "geometry: vertices in the vertex buffers after batching (shared vertices are duplicated across batches)",
    );
    pub const INDEX_COUNT: Col = Col::new(
        "index_count",
        "geometry: indices submitted per frame (restart indices included; 0 for non-indexed)",
    );
    pub const VERTEX_STRIDE_BYTES: Col = Col::new(
        "vertex_stride_bytes",
        "geometry: bytes per vertex, summed over the vertex buffers",
    );
    pub const VERTEX_BYTES: Col = Col::new("vertex_bytes", "geometry: bytes of vertex buffers");
    pub const INDEX_BYTES: Col = Col::new("index_bytes", "geometry: bytes of the index buffer");
    pub const ACMR: Col = Col::new(
        "acmr",
        "geometry: meshopt ACMR (vertices transformed per triangle, FIFO cache of 16) of the batched triangle list (for strips: the list they were made from); best ≈ 0.5, worst 3",
    );
    pub const ATVR: Col = Col::new(
        "atvr",
        "geometry: meshopt ATVR (vertices transformed per vertex, FIFO 16); best 1",
    );
    pub const VS_ACMR: Col = Col::new(
        "vs_acmr",
        "geometry: measured vertex-shader invocations per triangle (pipeline statistics)",
    );
    pub const POST_TRANSFORM_HIT_RATE: Col = Col::new(
        "post_transform_hit_rate",
        "geometry: measured 1 − vs_invocations / (3 × triangles): the share of triangle corners served without a vertex-shader run",
    );
    pub const SMALL_VIEWPORT: Col = Col::new(
        "small_viewport",
        "geometry: WxH of the raster-bound check's small viewport",
    );
    pub const GPU_MS_SMALL_VIEWPORT: Col = Col::new(
        "gpu_ms_small_viewport",
        "geometry: median GPU ms of the same point at the small viewport",
    );
    pub const RASTER_BOUND_RATIO: Col = Col::new(
        "raster_bound_ratio",
        "geometry: gpu_ms_median / gpu_ms_small_viewport; ≈ 1 when the raster stage is not the bottleneck",
    );
    pub const PREP_MS: Col = Col::new(
        "prep_ms",
        "geometry: CPU ms to order, batch, stripify and encode this point's buffers (untimed on the GPU)",
    );

    // ---- The stability study ----
    pub const STABILITY_CASE: Col = Col::new(
        "stability_case",
        "stability: the stiff case (near_far, coplanar, close_layers, high_complexity, thickness, alpha, packing, extreme_geometry)",
    );
    pub const STIFFNESS: Col = Col::new(
        "stiffness",
        "stability: what stiffness_value measures (far_over_near, sigma_l, distance_over_wall, depth_gap_min, depth_complexity, or a scene/axis parameter name)",
    );
    pub const STIFFNESS_VALUE: Col = Col::new(
        "stiffness_value",
        "stability: the case's stiffness parameter (e.g. far/near ratio, σ·l, layer separation in window depth)",
    );
    pub const LOST_FRAGMENTS: Col = Col::new(
        "lost_fragments",
        "fragments within the method's capacity that it did not capture (sum over pixels; coplanar loss when the reference has depth ties)",
    );

    // ---- The views study (camera paths) ----
    pub const CAMERA_PATH: Col = Col::new(
        "camera_path",
        "views: the scene's camera path (orbit | fly | file | at_rest; its keys are in scene_label)",
    );
    pub const PATH_VIEWS: Col = Col::new("path_views", "views: views rendered along the path");
    pub const POP_EPSILON: Col = Col::new(
        "pop_epsilon",
        "views: ε of popping (a pixel pops when its max-channel error against the truth changes by more than ε between consecutive views)",
    );
    pub const GPU_MS_PATH_P99: Col = Col::new(
        "gpu_ms_path_p99",
        "views: nearest-rank 99th percentile over the views of each view's median GPU ms (gpu_ms_median is the median over the views)",
    );
    pub const GPU_MS_PATH_WORST: Col = Col::new(
        "gpu_ms_path_worst",
        "views: the slowest view's median GPU ms",
    );
    pub const GPU_MS_WORST_VIEW: Col = Col::new(
        "gpu_ms_worst_view",
        "views: the slowest view (index along the path, from 0)",
    );
    pub const RMSE_PATH_WORST: Col = Col::new(
        "rmse_path_worst",
        "views: the largest RMSE of a view against its own truth (rmse is the mean over the views)",
    );
    pub const RMSE_WORST_VIEW: Col =
        Col::new("rmse_worst_view", "views: the view of rmse_path_worst");
    pub const FLIP_PATH_WORST: Col = Col::new(
        "flip_path_worst",
        "views: the largest FLIP mean of a view (flip_mean is the mean over the views)",
    );
    pub const FLIP_WORST_VIEW: Col =
        Col::new("flip_worst_view", "views: the view of flip_path_worst");
    pub const VIEWS_EXACT: Col = Col::new(
        "views_exact",
        "views: views judged exact (exact = every view exact)",
    );
    pub const FLICKER_MEAN: Col = Col::new(
        "flicker_mean",
        "views: mean over consecutive views t−1 → t of the mean over pixels of max-channel |(I_t − I_{t−1}) − (T_t − T_{t−1})|: the frame-to-frame change of the method's image that its truth's change does not explain (0 for an exact method, within flicker_bound_mean)",
    );
    pub const FLICKER_MAX: Col = Col::new("flicker_max", "views: the largest step's flicker");
    pub const FLICKER_WORST_VIEW: Col = Col::new(
        "flicker_worst_view",
        "views: the view t of the step t−1 → t with flicker_max (empty when no step flickered)",
    );
    pub const FLICKER_BOUND_MEAN: Col = Col::new(
        "flicker_bound_mean",
        "views: mean over steps of the mean over pixels of b_{t−1} + b_t, each view's f32 bound of an exact composite (exact_bound's per pixel): the flicker an exact method stays within",
    );
    pub const FLICKER_BEYOND_BOUND: Col = Col::new(
        "flicker_beyond_bound",
        "views: pixels, summed over steps, whose unexplained change exceeds b_{t−1} + b_t (0 for an exact method)",
    );
    pub const POPPING_MEAN: Col = Col::new(
        "popping_mean",
        "views: mean over steps of the share of pixels whose error against the truth changes by more than pop_epsilon",
    );
    pub const POPPING_MAX: Col = Col::new("popping_max", "views: the largest step's popping share");
    pub const POPPING_WORST_VIEW: Col = Col::new(
        "popping_worst_view",
        "views: the view t of the step t−1 → t with popping_max (empty when no pixel popped)",
    );
    pub const AT_REST_CHANGED_MEAN: Col = Col::new(
        "at_rest_changed_mean",
        "views, camera_path = at_rest: mean over consecutive repeated frames of the share of pixels whose value differs (0 without timing-dependent hazards)",
    );
    pub const AT_REST_CHANGED_MAX: Col = Col::new(
        "at_rest_changed_max",
        "views, camera_path = at_rest: the largest such share",
    );
    pub const PATH_SERIES: Col = Col::new(
        "path_series",
        "views: every view's numbers, JSON arrays indexed by view: gpu_ms, rmse, flip, flicker, popping, changed (the step arriving at the view; null at view 0), exact",
    );
    pub const PATH_IMAGES: Col = Col::new(
        "path_images",
        "views, with --save-images: prefix of the row's PNG crops (views/<hash>-worst-{method,truth,flip}.png of the worst view; views/<hash>-pop-{method-before,method-after,truth-before,truth-after,popped}.png of its largest pop)",
    );
    pub const PATH_IMAGES_WORST_VIEW: Col = Col::new(
        "path_images_worst_view",
        "views: the view of the -worst- crops",
    );
    pub const PATH_IMAGES_POP_VIEW: Col = Col::new(
        "path_images_pop_view",
        "views: the view t of the -pop- crops (the step t−1 → t)",
    );

    // ---- The deferred-shading study ----
    pub const LIGHT_COUNT: Col = Col::new(
        "light_count",
        "lights in the scene (point, spot and line lights, each with a finite range)",
    );
    pub const TILE_SIZE: Col = Col::new(
        "tile_size",
        "screen tile side in pixels for light culling (8, 16, 32, 64)",
    );
    pub const CULL_LEVELS: Col = Col::new(
        "cull_levels",
        "light culling levels: 1 = per tile; 2 = 64×64 tile then 32×16 sub-tiles (BF3)",
    );
    pub const ATTENUATION_THRESHOLD: Col = Col::new(
        "attenuation_threshold",
        "τ: a light is culled from a tile where peak intensity × attenuation ≤ τ at every point of it (0: only beyond its range)",
    );
    pub const THREAD_COUNT: Col = Col::new(
        "thread_count",
        "CPU worker threads taking tiles from an atomic counter (CPU lighting paths)",
    );
    pub const QUAD_SKIP: Col = Col::new(
        "quad_skip",
        "CPU tile path: skip a light for a 4×4 quad when all 16 attenuations are 0 (BF3's per-quad cull); false = evaluate every kept light",
    );
    pub const SPEC_SKIP: Col = Col::new(
        "spec_skip",
        "CPU tile path: BF3's no-specular fast path per 4×4 quad (no pixel with a specular colour: the specular term is not evaluated); exact",
    );
    pub const SPEC_SKIP_FRAC: Col = Col::new(
        "spec_skip_frac",
        "CPU tile path: fraction of non-sky 4×4 quads shaded without the specular term",
    );
    pub const CONE_CULL: Col = Col::new(
        "cone_cull",
        "CPU tile path: BF3's normal-cone cull per 32×16 sub-tile (drop a light no pixel of the sub-tile can face: N·L ≤ 0 for the normal cone × position box); exact",
    );
    pub const CONE_CULL_FRAC: Col = Col::new(
        "cone_cull_frac",
        "CPU tile path: fraction of (light, sub-tile) pairs that survived the frustum culls and were dropped by the normal-cone cull",
    );
    pub const DIFFUSE_ONLY_FRAC: Col = Col::new(
        "diffuse_only_frac",
        "fraction of the scene's lights flagged diffuse-only (no specular term, in every path and the reference)",
    );
    pub const DIFFUSE_SKIP: Col = Col::new(
        "diffuse_skip",
        "CPU tile path: skip the specular evaluation of diffuse-only lights (false: evaluate it and discard it); exact",
    );
    pub const DIFFUSE_SKIP_FRAC: Col = Col::new(
        "diffuse_skip_frac",
        "CPU tile path: fraction of (light, 4×4 quad) evaluations done without the specular term because the light is diffuse-only",
    );
    pub const LIGHTS_PER_TILE_MEAN: Col = Col::new(
        "lights_per_tile_mean",
        "mean lights kept per culling tile (level 1)",
    );
    pub const LIGHTS_PER_TILE_MAX: Col = Col::new(
        "lights_per_tile_max",
        "most lights kept in any culling tile (level 1)",
    );
    pub const CLASS_IDS_PRESENT: Col = Col::new(
        "class_ids_present",
        "classified: classification ids with at least one 4×4 tile this frame",
    );
    pub const SUN_SHADOW: Col = Col::new(
        "sun_shadow",
        "deferred: sun shadow map (off, or taps8: an orthographic sun depth map read with an 8-tap bilinear PCF filter where a pixel's footprint straddles a shadow edge, one tap elsewhere; in the paths and the f64 reference)",
    );
    pub const SHADOW_FADE_TILE_FRAC: Col = Col::new(
        "shadow_fade_tile_frac",
        "classified, sun_shadow = taps8: fraction of 4×4 tiles in the shadow-fade class (some pixel's filter footprint straddles a shadow edge: only these run the 8-tap filter)",
    );
    pub const MSAA: Col = Col::new(
        "msaa",
        "deferred: G-buffer samples per pixel (off, or x2: a 2×MSAA G-buffer; naive and uber shade both samples of every pixel and average, classified only in its MSAA-edge tiles, once elsewhere; the f64 reference averages per-sample shading)",
    );
    pub const MSAA_EDGE_TILE_FRAC: Col = Col::new(
        "msaa_edge_tile_frac",
        "classified, msaa = x2: fraction of 4×4 tiles in the MSAA-edge class (some pixel's two samples differ in depth, normal, albedo, specular or material: only these are shaded per sample)",
    );
    pub const PERMUTATIONS: Col = Col::new(
        "permutations",
        "shader permutations compiled and drawn (classified: one per id the scene can produce; uber: 1; cpu_tiled: the code permutations that shaded at least one sub-tile)",
    );
    pub const CLASSIFY: Col = Col::new(
        "classify",
        "CPU tile path: BF3's material classification: materials (each 32×16 sub-tile's material + light mask from the G-buffer and its light list picks a compiled code permutation: sky/edge lanes, specular, spot and line attenuation compiled in only where present) | none (the catch-all übershader on every quad); same image bit for bit",
    );
    pub const PERM_NARROW_FRAC: Col = Col::new(
        "perm_narrow_frac",
        "CPU tile path: fraction of sub-tiles shaded by a permutation narrower than the übershader (0 with classify = none)",
    );
    pub const CPU_LIGHT_MS: Col = Col::new(
        "cpu_light_ms",
        "median wall-clock ms of the CPU lighting of one frame (threads start to last tile done)",
    );
    pub const CPU_CULL_MS: Col = Col::new(
        "cpu_cull_ms",
        "CPU tile path, one extra frame with phase clocks (wall clock per worker thread, so time a thread is descheduled counts: run with thread_count ≤ free cores): ms summed over worker threads culling lights (tile and sub-tile frusta, normal cone); BF3 gives 1–4 ms of a 40 ms budget",
    );
    pub const CPU_UNPACK_MS: Col = Col::new(
        "cpu_unpack_ms",
        "CPU tile path, the phase-clock frame: thread-summed ms reading the G-buffer, reconstructing positions and filling the 4×4 quads' SoA lanes",
    );
    pub const CPU_SHADE_MS: Col = Col::new(
        "cpu_shade_ms",
        "CPU tile path, the phase-clock frame: thread-summed ms in the light loop and the sun",
    );
    pub const CPU_PACK_MS: Col = Col::new(
        "cpu_pack_ms",
        "CPU tile path, the phase-clock frame: thread-summed ms writing the quads' pixels and reordering tiles into rows",
    );
    pub const CPU_PHASES_MS: Col = Col::new(
        "cpu_phases_ms",
        "cpu_cull_ms + cpu_unpack_ms + cpu_shade_ms + cpu_pack_ms (thread-summed; with clock reads, so above cpu_light_ms × threads only by their cost)",
    );
    pub const SHADE_NS_PER_LIGHT_QUAD: Col = Col::new(
        "shade_ns_per_light_quad",
        "CPU tile path, the phase-clock frame: light-loop ns per (light, 4×4 quad) evaluation (sun excluded): the per-light cost BF3 compares for diffuse-only and specular lights",
    );
    pub const SHADE_NS_PER_LIGHT_QUAD_CI_LO: Col = Col::new(
        "shade_ns_per_light_quad_ci_lo",
        "CPU tile path: lower end of the 95 % interval of the median of shade_ns_per_light_quad over the phase-clock frames (phase_reps ≥ 6; empty below)",
    );
    pub const SHADE_NS_PER_LIGHT_QUAD_CI_HI: Col = Col::new(
        "shade_ns_per_light_quad_ci_hi",
        "CPU tile path: upper end of that interval",
    );
    pub const LIGHT_LOOP: Col = Col::new(
        "light_loop",
        "CPU tile path's light loop: bf3 (DICE's: every light evaluated on all 16 SoA lanes of a 4×4 quad with masks, no per-lane early-outs, after a whole-quad branch on the attenuation) | mfx (per-lane early-outs on N·L and attenuation); same image bit for bit",
    );
    pub const QUAD_SKIP_FRAC: Col = Col::new(
        "quad_skip_frac",
        "CPU path: fraction of (light, 4×4 quad) pairs skipped because all 16 attenuations were 0",
    );
    pub const SPEEDUP_VS_NAIVE: Col = Col::new(
        "speedup_vs_naive",
        "naive gpu_ms_median over this row's (GPU paths) or over cpu_light_ms (CPU paths), same scene, resolution and run",
    );
    pub const REL_ERR_MAX: Col = Col::new(
        "rel_err_max",
        "largest per-channel error vs the f64 reference, relative to max(1, |reference|)",
    );

    // ---- The light pre-pass study ----
    pub const LIGHT_ACCUM: Col = Col::new(
        "light_accum",
        "how the lighting is accumulated: naive (every light, fullscreen) | tiled (GPU tile culling) | cpu (CPU tiles)",
    );
    pub const LIGHT_BUFFER_FORMAT: Col = Col::new(
        "light_buffer_format",
        "light pre-pass light buffer: rgba8 (light ÷ 8, clamped) | rgba16f | rg11b10 (+ r16f for the specular term)",
    );
    pub const SECOND_VIEW: Col = Col::new(
        "second_view",
        "true: an independent second-camera view (full deferred, tiled) is rendered in the same frame",
    );
    pub const OVERLAP: Col = Col::new(
        "overlap",
        "CPU lighting: true = the second view is submitted before the CPU lights, so the GPU renders it meanwhile; false = after",
    );
    pub const BYTES_RT_WRITTEN: Col = Col::new(
        "bytes_rt_written",
        "render-target bytes written per frame by the main view, one touch per pixel (overdraw not counted)",
    );
    pub const BYTES_RT_READ: Col = Col::new(
        "bytes_rt_read",
        "render-target bytes read per frame by the main view, one touch per pixel (overdraw not counted)",
    );
    pub const SPEC_COLOR_LOSS_RMSE: Col = Col::new(
        "spec_color_loss_rmse",
        "RMSE of the f64 light pre-pass image (diffuse RGB + specular luminance packing) vs the f64 full reference: colour lost by the packing alone",
    );
    pub const FORMAT_RMSE: Col = Col::new(
        "format_rmse",
        "RMSE vs the f64 light pre-pass image: what the light-buffer format and f32 arithmetic add",
    );
    pub const FRAME_MS: Col = Col::new(
        "frame_ms",
        "median wall-clock ms per frame, first submit to all GPU work done (both views when second_view)",
    );
    pub const FRAME_MS_CI_LO: Col = Col::new(
        "frame_ms_ci_lo",
        "lower end of the 95 % interval of frame_ms's median over the kept frames (order statistics; 6 or more kept frames, empty below)",
    );
    pub const FRAME_MS_CI_HI: Col = Col::new("frame_ms_ci_hi", "upper end of that interval");
    pub const HOST_WORK: Col = Col::new(
        "host_work",
        "CPU-lit light pre-pass: the host work around the lighting (depth/normal decode, the tiles' reorder into rows, the light buffer's pack): parallel (on the lighting's own worker threads, rayon) | serial (one thread, mfx's earlier host); same image",
    );
    pub const GPU_IDLE_MS: Col = Col::new(
        "gpu_idle_ms",
        "median frame_ms minus the frame's summed GPU pass times: time the GPU had no timed work",
    );
    pub const LATENCY_MS: Col = Col::new(
        "latency_ms",
        "median ms from submitting the pre-pass to the main view's final image being complete",
    );
    pub const LIGHT_READY_MS: Col = Col::new(
        "light_ready_ms",
        "CPU lighting: median ms from submitting the pre-pass to the CPU-lit light buffer uploaded (before the material pass that reads it is submitted)",
    );
    pub const LIT_WITHIN_FRAME: Col = Col::new(
        "lit_within_frame",
        "CPU lighting: true when in every kept sample light_ready_ms ≤ latency_ms ≤ that frame's wall time: the frame's own light buffer lit and consumed within the frame (no added frame of latency); measured per sample",
    );
    pub const GPU_GAP_MS: Col = Col::new(
        "gpu_gap_ms",
        "median GPU-clock ms from the end of the pre-pass to the start of the material pass: the lights pass, or (CPU lighting) copy + map + CPU lighting + upload",
    );
    pub const GPU_BUSY_IN_GAP_MS: Col = Col::new(
        "gpu_busy_in_gap_ms",
        "median timed GPU pass ms inside gpu_gap_ms: the lights pass, or (CPU lighting) the independent view that ran while the CPU lit — the measured overlap",
    );
    pub const MAP_WAIT_MS: Col = Col::new(
        "map_wait_ms",
        "CPU lighting: median ms from submitting the pre-pass to the depth/normal read-back being mapped (blocking wait)",
    );

    // ---- The layered soft-shadows study ----
    pub const SHADOW_MAP_RES: Col = Col::new(
        "shadow_map_res",
        "shadows: shadow-map side in texels (square; one texture per light layer)",
    );
    pub const MAX_NSPP: Col = Col::new(
        "max_nspp",
        "shadows: most shadow-map samples per pixel in the search region; above it the stride grows (floor(sqrt) per axis)",
    );
    pub const BIAS_MODE: Col = Col::new(
        "bias_mode",
        "shadows: depth bias: midpoint (half-way to the next layer; the last layer falls back to gmax) | slope (gscale·max(|ddx|,|ddy|) clamped by gmax) | hybrid (the larger)",
    );
    pub const GSCALE: Col = Col::new(
        "gscale",
        "shadows: slope-bias scale, times the layer's depth change per texel",
    );
    pub const GMAX: Col = Col::new(
        "gmax",
        "shadows: clamp of the slope bias and the midpoint fallback, world units",
    );
    pub const HSM: Col = Col::new(
        "hsm",
        "shadows: true if the search region is refined by two iterations over the min-depth pyramid",
    );
    pub const SEARCH_START: Col = Col::new(
        "search_start",
        "shadows: where the search region starts: near (kr(n), the light's near plane: §5.3.2's initial region) | global_min (kr of the pyramid's global minimum depth, with a lit early-out: mfx's first choice)",
    );
    pub const BIAS_MAX: Col = Col::new(
        "bias_max",
        "shadows: maximum of the layers' midpoint bias, world units (§5.2.2's maximum depth bias); 0 = no maximum",
    );
    pub const SHADOW_RAYS: Col = Col::new(
        "shadow_rays",
        "shadows: reference rays per pixel (m×m jittered strata on the light square)",
    );
    pub const SHADOW_PIXELS: Col = Col::new(
        "shadow_pixels",
        "shadows: pixels evaluated (a visible surface inside the light's frustum)",
    );
    pub const VIS_RMSE: Col = Col::new(
        "vis_rmse",
        "shadows: RMSE of light visibility (0..1) vs the ray-traced reference, over evaluated pixels",
    );
    pub const VIS_BIAS: Col = Col::new(
        "vis_bias",
        "shadows: mean signed visibility error (GPU − reference): > 0 light bleeding, < 0 overshadowing",
    );
    pub const VIS_MAX_ABS_ERR: Col = Col::new(
        "vis_max_abs_err",
        "shadows: largest absolute visibility error of any evaluated pixel",
    );
    pub const VIS_BLEED_MEAN: Col = Col::new(
        "vis_bleed_mean",
        "shadows: mean of max(GPU − reference, 0): light bleeding alone",
    );
    pub const VIS_OVERSHADOW_MEAN: Col = Col::new(
        "vis_overshadow_mean",
        "shadows: mean of max(reference − GPU, 0): overshadowing alone",
    );
    pub const REFERENCE_MS: Col = Col::new(
        "reference_ms",
        "shadows: CPU wall time of the ray-traced reference of this scene and resolution, ms (computed once, cached)",
    );

    // ---- Measurements ----
    pub const GPU_MS_MEDIAN: Col = Col::new(
        "gpu_ms_median",
        "median GPU time per frame in ms (sum of the frame's timestamped passes) over the kept samples",
    );
    pub const GPU_MS_MIN: Col = Col::new(
        "gpu_ms_min",
        "minimum GPU time per frame over the kept samples, ms",
    );
    pub const GPU_MS_MAX: Col = Col::new(
        "gpu_ms_max",
        "maximum GPU time per frame over the kept samples, ms",
    );
    pub const GPU_MS_P50: Col = Col::new(
        "gpu_ms_p50",
        "50th percentile of per-sample GPU time over the kept samples, ms (the median: equal to gpu_ms_median)",
    );
    pub const GPU_MS_P95: Col = Col::new(
        "gpu_ms_p95",
        "95th percentile of per-sample GPU time over the kept samples, ms (nearest rank: s[round((n−1)·0.95)] of the sorted samples; with under 20 samples it is one of the top two)",
    );
    pub const GPU_MS_P99: Col = Col::new(
        "gpu_ms_p99",
        "99th percentile of per-sample GPU time over the kept samples, ms (nearest rank, as gpu_ms_p95; with under 50 samples it is the max or next to it)",
    );
    pub const FRAGMENTS_PER_S: Col = Col::new(
        "fragments_per_s",
        "true_fragments (the CPU reference's fragment total of the frame) / gpu_ms_median: fragments resolved per second of GPU time, however many passes a method takes over them; empty where the study has no fragment reference",
    );
    pub const BYTES_PER_S: Col = Col::new(
        "bytes_per_s",
        "an estimate of bytes moved per second of GPU time: the frame's declared traffic / gpu_ms_median. Declared traffic (Timed::bytes_moved): by default bytes_allocated written once and read once (2 × bytes_allocated); the light pre-pass (bytes_rt_written + bytes_rt_read) and the deferred shading paths (G-buffer written and read once, HDR colour written: pixels × (2 × 24 + 16)) declare their render-target bytes. Not a measured count: a declared scale for peak_bandwidth_frac",
    );
    pub const PEAK_BANDWIDTH_FRAC: Col = Col::new(
        "peak_bandwidth_frac",
        "bytes_per_s / roof_bytes_per_s: the declared traffic's share of the measured roof of the row's working set (the L2's where l2_resident, else the DRAM's; run.json `roofs`); in a run without measured roofs, / the adapter's peak memory bandwidth (NVML: memory bus width × max memory clock × 2, DDR), and empty where NVML does not give both",
    );
    pub const WORKING_SET_BYTES: Col = Col::new(
        "working_set_bytes",
        "the bytes a frame touches, as declared: what the method allocated (bytes_allocated) plus the scene's geometry buffers",
    );
    pub const L2_RESIDENT: Col = Col::new(
        "l2_resident",
        "true where the declared working set fits the adapter's L2 (run.json `roofs.l2_bytes`: the adapter's published size, else the knee of the roofs' sweep) and the samples were warm: the row is read against the L2 roof; false beyond it, and with `[timing] cold = true` (the L2 flushed before each sample); empty without measured roofs",
    );
    pub const ROOF_BYTES_PER_S: Col = Col::new(
        "roof_bytes_per_s",
        "the memory roof the row is read against (peak_bandwidth_frac's denominator): the copy kernel's measured bytes per second (read + written) with its working set in the L2 (l2_resident) or far beyond it (run.json `roofs`, measured once per run); empty without measured roofs",
    );
    pub const GPU_MS_REL_NOISE: Col = Col::new(
        "gpu_ms_rel_noise",
        "within-run spread of GPU time: (p90 − p10) / median of the kept samples (it says nothing of run-to-run spread: see gpu_ms_rel_ci and mfx compare)",
    );
    pub const GPU_MS_MEAN: Col = Col::new(
        "gpu_ms_mean",
        "mean GPU time per frame over the kept samples, ms",
    );
    pub const GPU_MS_CI_LO: Col = Col::new(
        "gpu_ms_ci_lo",
        "lower end of the bootstrap 95 % confidence interval of the median GPU time, ms",
    );
    pub const GPU_MS_CI_HI: Col = Col::new(
        "gpu_ms_ci_hi",
        "upper end of the bootstrap 95 % confidence interval of the median GPU time, ms",
    );
    pub const GPU_MS_INTERVAL: Col = Col::new(
        "gpu_ms_interval",
        "what gpu_ms_ci_lo/hi are: ci95 (a 95 % interval of the median) | range (min and max: fewer samples than an order-statistic interval needs to reach 95 % coverage, see schema::MIN_SAMPLES_CI95)",
    );
    pub const GPU_MS_MEAN_CI_LO: Col = Col::new(
        "gpu_ms_mean_ci_lo",
        "lower end of the bootstrap 95 % confidence interval of the mean GPU time, ms",
    );
    pub const GPU_MS_MEAN_CI_HI: Col = Col::new(
        "gpu_ms_mean_ci_hi",
        "upper end of the bootstrap 95 % confidence interval of the mean GPU time, ms",
    );
    pub const GPU_MS_REL_CI: Col = Col::new(
        "gpu_ms_rel_ci",
        "half-width of the median's bootstrap 95 % confidence interval over the median",
    );
    pub const GPU_MS_OUTLIERS: Col = Col::new(
        "gpu_ms_outliers",
        "samples outside Tukey's fences (1.5 IQR beyond the quartiles); kept, counted",
    );
    pub const SAMPLES: Col = Col::new(
        "samples",
        "timed samples kept (discarded ones excluded); 0 beside a median means every sample was discarded and the statistics use them all (the row is then throttled and noisy)",
    );
    pub const SAMPLES_DISCARDED: Col = Col::new(
        "samples_discarded",
        "timed samples discarded: the SM clock was below 75 % of the reference clock (nvbench's rule), or the canary timed right after the sample ran over canary_max_ratio × its baseline (canary_discarded of them)",
    );
    pub const CANARY_DISCARDED: Col = Col::new(
        "canary_discarded",
        "of samples_discarded, those whose canary (a fixed 16 MiB-read + FMA kernel timed right after the sample) took over [timing] canary_max_ratio × the fifth-fastest canary of the process: the GPU as a whole ran slow though its clocks did not say so (empty: no canary, e.g. a software adapter)",
    );
    pub const CANARY_RATIO_MAX: Col = Col::new(
        "canary_ratio_max",
        "largest canary ratio over the point's samples, discarded ones included (1 = as fast as the run's baseline; empty: no canary)",
    );
    pub const CLOCK_LIFT_MS: Col = Col::new(
        "clock_lift_ms",
        "ms of untimed busy GPU work run before the warm-up because the SM clock read under 97 % of the adapter's maximum (empty: none needed, or no NVML)",
    );
    pub const CLOCK_LIFT_FROM_MHZ: Col =
        Col::new("clock_lift_from_mhz", "SM clock before the clock lift, MHz");
    pub const CLOCK_LIFT_TO_MHZ: Col = Col::new(
        "clock_lift_to_mhz",
        "SM clock after the clock lift, MHz (below 97 % of the maximum: the lift ran out of time)",
    );
    pub const WARMUP_FRAMES: Col = Col::new(
        "warmup_frames",
        "untimed frames run before the first sample, until frame times and the SM clock were steady",
    );
    pub const MEASURE_MS: Col = Col::new(
        "measure_ms",
        "wall-clock ms spent on warm-up and samples of this point",
    );
    pub const SESSION_SPREAD: Col = Col::new(
        "session_spread",
        "with [timing] sessions > 1: (max − min) / median of the sessions' GPU medians, each session prepared afresh (new buffers, pipelines, warm-up); the CI columns are widened to cover every session's median, and a spread over twice max_noise makes the row noisy",
    );
    pub const PREPARE_MS: Col = Col::new(
        "prepare_ms",
        "wall-clock ms of the method's prepare for this point (pipelines compiled, buffers allocated and filled; untimed), so a sweep's wall time can be attributed",
    );
    pub const JUDGE_MS: Col = Col::new(
        "judge_ms",
        "wall-clock ms of reading this point back and judging it on the CPU (the effect's reference composites, errors, FLIP)",
    );
    pub const FRAGMENT_REFERENCE_MS: Col = Col::new(
        "fragment_reference_ms",
        "CPU ms of the scene × resolution group's f64 fragment lists, on the one row that first needed them (empty elsewhere: they are cached)",
    );
    pub const TARGET_REACHED: Col = Col::new(
        "target_reached",
        "true if the stopping rule met its noise target (false: max samples/time or drift; the row is flagged noisy)",
    );
    pub const STOP_REASON: Col = Col::new(
        "stop_reason",
        "why sampling stopped: target_reached, max_samples, max_time, no_improvement (the two halves of the samples differ: drift)",
    );
    pub const GPU_WALL_RATIO: Col = Col::new(
        "gpu_wall_ratio",
        "gpu_ms_median / cpu_ms_median: the share of the frame's wall-clock time that timestamps account for",
    );
    pub const CPU_MS_MEDIAN: Col = Col::new(
        "cpu_ms_median",
        "median wall-clock time per frame in ms, from first encode to GPU idle (includes CPU waits)",
    );
    pub const CPU_MS_MIN: Col = Col::new("cpu_ms_min", "minimum wall-clock time per frame, ms");
    pub const CPU_MS_MAX: Col = Col::new("cpu_ms_max", "maximum wall-clock time per frame, ms");
    pub const SM_CLOCK_MHZ_MEAN: Col = Col::new(
        "sm_clock_mhz_mean",
        "mean SM clock over the kept samples (NVML), MHz",
    );
    pub const SM_CLOCK_MHZ_MIN: Col = Col::new(
        "sm_clock_mhz_min",
        "lowest SM clock read during the point, MHz",
    );
    pub const SM_CLOCK_MHZ_MAX: Col = Col::new(
        "sm_clock_mhz_max",
        "highest SM clock read during the point, MHz",
    );
    pub const MEM_CLOCK_MHZ_MEAN: Col = Col::new(
        "mem_clock_mhz_mean",
        "mean memory clock over the kept samples, MHz",
    );
    pub const GPU_TEMP_C_MAX: Col = Col::new(
        "gpu_temp_c_max",
        "highest GPU temperature read during the point, °C",
    );
    pub const GPU_POWER_W_MEAN: Col = Col::new(
        "gpu_power_w_mean",
        "mean board power over the kept samples, W",
    );
    pub const THROTTLE_REASONS: Col = Col::new(
        "throttle_reasons",
        "NVML clock-throttle reasons seen during the point, |-joined (empty: none)",
    );
    pub const CLOCK_SOURCE: Col = Col::new(
        "clock_source",
        "nvml, or none: <why no clock was read> (then the clock columns are empty)",
    );
    pub const GPU_OTHER_PROCESSES: Col = Col::new(
        "gpu_other_processes",
        "the most processes other than this one that held the GPU at once while the point was timed (NVML's compute and graphics process lists, read after every timed frame; flag gpu_shared when above 0); empty without a process list",
    );
    pub const PASS_MS: Col = Col::new(
        "pass_ms",
        "median GPU ms per pass label, JSON object (e.g. {\"peel\":1.2,\"composite\":0.1})",
    );
    pub const PASS_MS_CI: Col = Col::new(
        "pass_ms_ci",
        "95 % interval of each pass's median ms, JSON object label → [lo, hi] (the bootstrap CI of the median from 6 samples, else the min–max range, as gpu_ms_ci_lo/hi): what a claim about one pass is ruled with",
    );
    pub const GEOMETRY_PASSES: Col = Col::new(
        "geometry_passes",
        "geometry passes per frame (times the scene was rasterized)",
    );
    pub const LAYERS_CAPTURED_MAX: Col = Col::new(
        "layers_captured_max",
        "most fragments captured in any pixel",
    );
    pub const BYTES_ALLOCATED: Col = Col::new(
        "bytes_allocated",
        "bytes of buffers and textures the method allocated (scene buffers excluded)",
    );
    pub const BYTES_PER_PIXEL: Col = Col::new("bytes_per_pixel", "bytes_allocated / pixels");
    pub const SPLIT: Col = Col::new(
        "split",
        "how a buffer over the largest storage binding was split to fit (`bindings:N`: one array over N storage bindings, indexed through a switch; the k-buffers' entries, MLAB's layers, the linked list's node pool, the compute A-buffer's fragments), and `packed` where the compute A-buffer packed its bindings into WebGPU's 8 (`packed,bindings:N` both); empty where nothing was. Compare with the unsplit row of a larger limit for the cost",
    );
    pub const BYTES_OVERHEAD: Col = Col::new(
        "bytes_overhead",
        "of bytes_allocated, the per-pixel structures (heads, offsets, counters, output image) where the method reports them",
    );
    pub const FRAGMENT_BYTES_RATIO: Col = Col::new(
        "fragment_bytes_ratio",
        "(bytes_allocated − bytes_overhead) / bytes_true_fragments: fragment storage over what the true fragments need",
    );
    pub const BYTES_TRUE_FRAGMENTS: Col = Col::new(
        "bytes_true_fragments",
        "bytes the scene's true fragments need: true_fragments × 8 (RGBA8 + f32 depth)",
    );
    pub const GPU_TIME_TRUSTED: Col = Col::new(
        "gpu_time_trusted",
        "false when the GPU timestamps do not cover the frame (flag timestamps_incomplete): then x_floor, x_blend and speedup_vs_* stay empty",
    );
    pub const X_FLOOR: Col = Col::new(
        "x_floor",
        "gpu_ms_median over the floor_depth gpu_ms_median of the same scene, resolution and run",
    );
    pub const X_BLEND: Col = Col::new(
        "x_blend",
        "gpu_ms_median over the floor_blend_const gpu_ms_median (unordered hardware blending of every fragment, positions only and one constant colour: the cheapest) of the same scene, resolution and run (before issue 33: over floor_blend, which reads colour too)",
    );
    pub const SPEEDUP_VS_DEPTH_PEEL: Col = Col::new(
        "speedup_vs_depth_peel",
        "depth_peel gpu_ms_median over this row's, same scene, resolution and run",
    );
    pub const RMSE: Col = Col::new(
        "rmse",
        "root-mean-square error of the image vs the ground truth: the same effect over every fragment (f64 CPU reference)",
    );
    pub const PSNR_DB: Col = Col::new(
        "psnr_db",
        "peak signal-to-noise ratio (peak 1) vs the ground truth, dB (inf when identical)",
    );
    pub const MAX_ABS_ERR: Col = Col::new(
        "max_abs_err",
        "largest absolute channel error vs the ground truth",
    );
    pub const BAD_PIXEL_FRAC: Col = Col::new(
        "bad_pixel_frac",
        "fraction of pixels with any channel error above bad_pixel_tol vs the ground truth",
    );
    pub const BAD_PIXEL_TOL: Col = Col::new(
        "bad_pixel_tol",
        "the per-channel tolerance used for bad_pixel_frac",
    );
    pub const NON_FINITE: Col = Col::new(
        "non_finite",
        "NaN/Inf channels in the output (never hidden: they also make the pixel bad)",
    );
    pub const MATCHES_TRUTH: Col = Col::new(
        "matches_truth",
        "true when the image equals the ground truth within bad_pixel_tol at every pixel and nothing is non-finite: within tolerance, a weaker label than `exact` (a capture that lost fragments can still match)",
    );
    pub const RMSE_VS_K: Col = Col::new(
        "rmse_vs_k",
        "methods that keep k fragments per pixel: RMSE vs the same effect over the k nearest (or first) fragments, i.e. fidelity to the method's own truncated definition (empty for methods that keep everything)",
    );
    pub const PSNR_DB_VS_K: Col =
        Col::new("psnr_db_vs_k", "as psnr_db, vs the k-truncated reference");
    pub const MAX_ABS_ERR_VS_K: Col = Col::new(
        "max_abs_err_vs_k",
        "as max_abs_err, vs the k-truncated reference",
    );
    pub const BAD_PIXEL_FRAC_VS_K: Col = Col::new(
        "bad_pixel_frac_vs_k",
        "as bad_pixel_frac, vs the k-truncated reference",
    );
    pub const FLIP_MEAN: Col = Col::new(
        "flip_mean",
        "mean FLIP error (NVIDIA LDR-FLIP, 67 pixels per degree) of the image composited over white vs the ground truth composited the same way; 0 = identical, 1 = maximal",
    );
    pub const FLIP_P99: Col = Col::new(
        "flip_p99",
        "99th percentile over pixels of the FLIP error map",
    );
    pub const FRAGMENTS_MISSING: Col = Col::new(
        "fragments_missing",
        "exact methods: true fragments the capture lacks, summed over pixels",
    );
    pub const FRAGMENTS_EXTRA: Col = Col::new(
        "fragments_extra",
        "exact methods: fragments the capture has beyond the true ones, summed over pixels",
    );
    pub const DEPTH_TIE_PIXELS: Col = Col::new(
        "depth_tie_pixels",
        "pixels whose image is off the f64 ground truth beyond the f32 bound of its arithmetic (exact_bound) by what compositing fragments within the method's depth precision in another order makes: the truth has no defined order there (flag depth_ties). Transparency: every order of the pixel's near-equal-depth runs is tried (each channel held to the range of the orders beyond 5040 of them), so a fragment's colour off is not a tie however near its depths; translucency and Fresnel: none (no order changes them); csg and dof: within the order bound. Judged for methods that claim every fragment (claims_exact), at pixels within capacity; empty otherwise",
    );
    pub const FRAGMENTS_DROPPED: Col = Col::new(
        "fragments_dropped",
        "bounded captures: fragments that did not fit and were dropped this frame",
    );
    pub const FRAGMENTS_TAILED: Col = Col::new(
        "fragments_tailed",
        "bounded captures with tail = blend: fragments that did not fit and were blended out of order into the tail this frame",
    );
    pub const LAYER_COUNT_ACCURACY: Col = Col::new(
        "layer_count_accuracy",
        "fraction of pixels whose captured fragment count equals the expected count",
    );
    pub const HAZARD_RATE: Col = Col::new(
        "hazard_rate",
        "unguarded read-modify-write captures: k-buffer: fraction of pixels whose captured set differs from the true k nearest (each captured depth matched to a true fragment within 1e-5 plus its triangle's depth slope times 1/256 px: a GPU may set depth up from unsnapped vertices), excluding pixels with an f32 depth tie among their k + 1 nearest (those are flagged lost_coplanar and counted in notes); mlab, adaptive: fraction of pixels whose image differs from the ideal-order (primitive order) twin by more than 1e-4",
    );
    pub const HAZARD_RATE_CI_LO: Col = Col::new(
        "hazard_rate_ci_lo",
        "with hazard_captures > 1: the lowest hazard rate of the captures (hazard_rate is the first's); with 5 or more captures [lo, hi] holds the median hazard rate with ≥ 94 % confidence",
    );
    pub const HAZARD_RATE_CI_HI: Col = Col::new(
        "hazard_rate_ci_hi",
        "with hazard_captures > 1: the highest hazard rate of the captures",
    );
    pub const COLLISION_RATE: Col = Col::new(
        "collision_rate",
        "buckets: fraction of true fragments merged or lost by bucket collisions",
    );
    pub const OVERFLOW_RATE: Col = Col::new(
        "overflow_rate",
        "fraction of pixels whose fragments exceeded the method's capacity",
    );
    pub const TRIANGLES_PER_S: Col = Col::new(
        "triangles_per_s",
        "triangles submitted per second of GPU time",
    );
    pub const VERTICES_PER_S: Col = Col::new(
        "vertices_per_s",
        "vertices (index count for indexed draws) per second of GPU time",
    );
    pub const VS_INVOCATIONS: Col = Col::new(
        "vs_invocations",
        "vertex shader invocations per frame (pipeline statistics query)",
    );
    pub const PS_INVOCATIONS: Col = Col::new(
        "ps_invocations",
        "fragment shader invocations per frame (pipeline statistics query)",
    );
    pub const IMAGE_FILE: Col = Col::new(
        "image_file",
        "the point's image saved by `mfx sweep --save-images`: images/<hash>.npy, float32 H×W×4 premultiplied RGBA (empty otherwise)",
    );
    pub const NOTES: Col = Col::new(
        "notes",
        "free text: anything a reader must know about this row",
    );
}

/// The column groups in file order: metadata, point, shared axes, each study's own, metrics.
pub const GROUPS: &[Group] = &[
    Group {
        name: "meta",
        title: "Run and machine metadata, identical on every row of one run",
        cols: &[
            cols::SCHEMA,
            cols::RUN_ID,
            cols::GIT_REV,
            cols::TIMESTAMP_UTC,
            cols::SUITE,
            cols::STUDY,
            cols::SHARD,
            cols::SHARDS,
            cols::POINT_KEY,
            cols::ADAPTER,
            cols::BACKEND,
            cols::DEVICE_TYPE,
            cols::DRIVER,
            cols::DRIVER_INFO,
            cols::GPU_UUID,
            cols::GPU_SERIAL,
            cols::PCI_BUS_ID,
            cols::SLURM_JOB_ID,
            cols::SLURM_ARRAY_JOB_ID,
            cols::SLURM_ARRAY_TASK_ID,
            cols::ADAPTER_FEATURES,
            cols::TEXTURE_MEMORY,
            cols::LIMITS,
            cols::WIDTH,
            cols::HEIGHT,
            cols::TIMING_RULE,
            cols::ORDER_SEED,
        ],
    },
    Group {
        name: "point",
        title: "What was measured: scene, method, outcome",
        cols: &[
            cols::SCENE,
            cols::SCENE_LABEL,
            cols::TRIANGLES,
            cols::VERTICES,
            cols::DEPTH_COMPLEXITY_MAX,
            cols::DEPTH_COMPLEXITY_MEAN,
            cols::TRUE_FRAGMENTS,
            cols::METHOD,
            cols::CLAIMS_EXACT,
            cols::EXACT,
            cols::EXACT_BOUND,
            cols::EFFECT,
            cols::STATUS,
            cols::REASON,
            cols::FLAG,
        ],
    },
    Group {
        name: "axes",
        title: "Sweep axes shared by several methods (empty where an axis does not apply)",
        cols: &[
            cols::LAYERS,
            cols::MAX_LAYERS,
            cols::PAYLOAD,
            cols::OCCLUSION_STOP,
            cols::SPECIALISATION,
            cols::HEURISTICS,
            cols::HAZARD_CAPTURES,
            cols::TIEBREAK,
            cols::THICKNESS,
            cols::BUCKET_COUNT,
            cols::BUCKET_MODE,
            cols::BUCKET_PAIRING,
            cols::RANGE_PASS,
            cols::HIST_BINS,
            cols::SMALL_MAX,
            cols::TRANSFORM,
            cols::COVERAGE,
            cols::CAPTURE,
            cols::ATTRIBUTES,
            cols::RESOLVE_SORT,
            cols::BINDINGS,
            cols::POOL,
            cols::POOL_SLACK,
            cols::NODE,
            cols::TAIL,
            cols::KEEP,
            cols::MOMENT_KIND,
            cols::MOMENT_COUNT,
            cols::MOMENT_PRECISION,
            cols::MOMENT_BIAS,
            cols::MOMENT_NORMALIZE,
            cols::AA,
            cols::AA_CAPTURE,
            cols::AA_SAMPLES,
            cols::SAMPLE_POSITIONS,
            cols::ST_SAMPLES,
            cols::ST_PASSES,
            cols::ST_CORRECTION,
            cols::ST_SEED,
        ],
    },
    Group {
        name: "effects",
        title: "Effect parameters (axes of the effects fold)",
        cols: &[
            cols::SIGMA,
            cols::CSG_A,
            cols::CSG_B,
            cols::DOF_NEAR,
            cols::DOF_FAR,
            cols::ISO_VALUE,
        ],
    },
    Group {
        name: "geometry",
        title: "The geometry study",
        cols: &[
            cols::BATCH_SIZE,
            cols::DRAW_TRIANGLES,
            cols::VERTEX_FORMAT,
            cols::NORMAL_FORMAT,
            cols::COLOR_FORMAT,
            cols::TEXCOORD_FORMAT,
            cols::LAYOUT,
            cols::EXTRA_ATTRIBUTES,
            cols::INDEX_FORMAT,
            cols::MESH_ORDER,
            cols::INDEXED,
            cols::PRIMITIVE,
            cols::BATCHES,
            cols::BATCH_VERTICES,
            cols::INDEX_COUNT,
            cols::VERTEX_STRIDE_BYTES,
            cols::VERTEX_BYTES,
            cols::INDEX_BYTES,
            cols::ACMR,
            cols::ATVR,
            cols::VS_ACMR,
            cols::POST_TRANSFORM_HIT_RATE,
            cols::SMALL_VIEWPORT,
            cols::GPU_MS_SMALL_VIEWPORT,
            cols::RASTER_BOUND_RATIO,
            cols::PREP_MS,
        ],
    },
    Group {
        name: "stability",
        title: "The stability study",
        cols: &[
            cols::STABILITY_CASE,
            cols::STIFFNESS,
            cols::STIFFNESS_VALUE,
            cols::LOST_FRAGMENTS,
        ],
    },
    Group {
        name: "views",
        title: "The views study (camera paths)",
        cols: &[
            cols::CAMERA_PATH,
            cols::PATH_VIEWS,
            cols::POP_EPSILON,
            cols::GPU_MS_PATH_P99,
            cols::GPU_MS_PATH_WORST,
            cols::GPU_MS_WORST_VIEW,
            cols::RMSE_PATH_WORST,
            cols::RMSE_WORST_VIEW,
            cols::FLIP_PATH_WORST,
            cols::FLIP_WORST_VIEW,
            cols::VIEWS_EXACT,
            cols::FLICKER_MEAN,
            cols::FLICKER_MAX,
            cols::FLICKER_WORST_VIEW,
            cols::FLICKER_BOUND_MEAN,
            cols::FLICKER_BEYOND_BOUND,
            cols::POPPING_MEAN,
            cols::POPPING_MAX,
            cols::POPPING_WORST_VIEW,
            cols::AT_REST_CHANGED_MEAN,
            cols::AT_REST_CHANGED_MAX,
            cols::PATH_SERIES,
            cols::PATH_IMAGES,
            cols::PATH_IMAGES_WORST_VIEW,
            cols::PATH_IMAGES_POP_VIEW,
        ],
    },
    Group {
        name: "deferred",
        title: "The deferred-shading study",
        cols: &[
            cols::LIGHT_COUNT,
            cols::TILE_SIZE,
            cols::CULL_LEVELS,
            cols::ATTENUATION_THRESHOLD,
            cols::THREAD_COUNT,
            cols::QUAD_SKIP,
            cols::SPEC_SKIP,
            cols::SPEC_SKIP_FRAC,
            cols::CONE_CULL,
            cols::CONE_CULL_FRAC,
            cols::DIFFUSE_ONLY_FRAC,
            cols::DIFFUSE_SKIP,
            cols::DIFFUSE_SKIP_FRAC,
            cols::LIGHTS_PER_TILE_MEAN,
            cols::LIGHTS_PER_TILE_MAX,
            cols::CLASS_IDS_PRESENT,
            cols::SUN_SHADOW,
            cols::SHADOW_FADE_TILE_FRAC,
            cols::MSAA,
            cols::MSAA_EDGE_TILE_FRAC,
            cols::PERMUTATIONS,
            cols::CPU_LIGHT_MS,
            cols::CPU_CULL_MS,
            cols::CPU_UNPACK_MS,
            cols::CPU_SHADE_MS,
            cols::CPU_PACK_MS,
            cols::CPU_PHASES_MS,
            cols::SHADE_NS_PER_LIGHT_QUAD,
            cols::SHADE_NS_PER_LIGHT_QUAD_CI_LO,
            cols::SHADE_NS_PER_LIGHT_QUAD_CI_HI,
            cols::LIGHT_LOOP,
            cols::CLASSIFY,
            cols::PERM_NARROW_FRAC,
            cols::QUAD_SKIP_FRAC,
            cols::SPEEDUP_VS_NAIVE,
            cols::REL_ERR_MAX,
        ],
    },
    Group {
        name: "prepass",
        title: "The light pre-pass study",
        cols: &[
            cols::LIGHT_ACCUM,
            cols::LIGHT_BUFFER_FORMAT,
            cols::SECOND_VIEW,
            cols::OVERLAP,
            cols::HOST_WORK,
            cols::BYTES_RT_WRITTEN,
            cols::BYTES_RT_READ,
            cols::SPEC_COLOR_LOSS_RMSE,
            cols::FORMAT_RMSE,
            cols::FRAME_MS,
            cols::FRAME_MS_CI_LO,
            cols::FRAME_MS_CI_HI,
            cols::GPU_IDLE_MS,
            cols::LATENCY_MS,
            cols::LIGHT_READY_MS,
            cols::LIT_WITHIN_FRAME,
            cols::GPU_GAP_MS,
            cols::GPU_BUSY_IN_GAP_MS,
            cols::MAP_WAIT_MS,
        ],
    },
    Group {
        name: "shadows",
        title: "The layered soft-shadows study",
        cols: &[
            cols::SHADOW_MAP_RES,
            cols::MAX_NSPP,
            cols::BIAS_MODE,
            cols::GSCALE,
            cols::GMAX,
            cols::HSM,
            cols::SEARCH_START,
            cols::BIAS_MAX,
            cols::SHADOW_RAYS,
            cols::SHADOW_PIXELS,
            cols::VIS_RMSE,
            cols::VIS_BIAS,
            cols::VIS_MAX_ABS_ERR,
            cols::VIS_BLEED_MEAN,
            cols::VIS_OVERSHADOW_MEAN,
            cols::REFERENCE_MS,
        ],
    },
    Group {
        name: "metrics",
        title: "Measurements",
        cols: &[
            cols::GPU_MS_MEDIAN,
            cols::GPU_MS_MIN,
            cols::GPU_MS_MAX,
            cols::GPU_MS_P50,
            cols::GPU_MS_P95,
            cols::GPU_MS_P99,
            cols::FRAGMENTS_PER_S,
            cols::BYTES_PER_S,
            cols::PEAK_BANDWIDTH_FRAC,
            cols::WORKING_SET_BYTES,
            cols::L2_RESIDENT,
            cols::ROOF_BYTES_PER_S,
            cols::GPU_MS_REL_NOISE,
            cols::GPU_MS_MEAN,
            cols::GPU_MS_CI_LO,
            cols::GPU_MS_CI_HI,
            cols::GPU_MS_INTERVAL,
            cols::GPU_MS_MEAN_CI_LO,
            cols::GPU_MS_MEAN_CI_HI,
            cols::GPU_MS_REL_CI,
            cols::GPU_MS_OUTLIERS,
            cols::SAMPLES,
            cols::SAMPLES_DISCARDED,
            cols::CANARY_DISCARDED,
            cols::CANARY_RATIO_MAX,
            cols::CLOCK_LIFT_MS,
            cols::CLOCK_LIFT_FROM_MHZ,
            cols::CLOCK_LIFT_TO_MHZ,
            cols::WARMUP_FRAMES,
            cols::MEASURE_MS,
            cols::PREPARE_MS,
            cols::SESSION_SPREAD,
            cols::JUDGE_MS,
            cols::FRAGMENT_REFERENCE_MS,
            cols::TARGET_REACHED,
            cols::STOP_REASON,
            cols::GPU_WALL_RATIO,
            cols::CPU_MS_MEDIAN,
            cols::CPU_MS_MIN,
            cols::CPU_MS_MAX,
            cols::SM_CLOCK_MHZ_MEAN,
            cols::SM_CLOCK_MHZ_MIN,
            cols::SM_CLOCK_MHZ_MAX,
            cols::MEM_CLOCK_MHZ_MEAN,
            cols::GPU_TEMP_C_MAX,
            cols::GPU_POWER_W_MEAN,
            cols::THROTTLE_REASONS,
            cols::CLOCK_SOURCE,
            cols::GPU_OTHER_PROCESSES,
            cols::PASS_MS,
            cols::PASS_MS_CI,
            cols::GEOMETRY_PASSES,
            cols::LAYERS_CAPTURED_MAX,
            cols::BYTES_ALLOCATED,
            cols::BYTES_PER_PIXEL,
            cols::SPLIT,
            cols::BYTES_OVERHEAD,
            cols::FRAGMENT_BYTES_RATIO,
            cols::BYTES_TRUE_FRAGMENTS,
            cols::GPU_TIME_TRUSTED,
            cols::X_FLOOR,
            cols::X_BLEND,
            cols::SPEEDUP_VS_DEPTH_PEEL,
            cols::RMSE,
            cols::PSNR_DB,
            cols::MAX_ABS_ERR,
            cols::BAD_PIXEL_FRAC,
            cols::BAD_PIXEL_TOL,
            cols::NON_FINITE,
            cols::MATCHES_TRUTH,
            cols::RMSE_VS_K,
            cols::PSNR_DB_VS_K,
            cols::MAX_ABS_ERR_VS_K,
            cols::BAD_PIXEL_FRAC_VS_K,
            cols::FLIP_MEAN,
            cols::FLIP_P99,
            cols::FRAGMENTS_MISSING,
            cols::FRAGMENTS_EXTRA,
            cols::DEPTH_TIE_PIXELS,
            cols::FRAGMENTS_DROPPED,
            cols::FRAGMENTS_TAILED,
            cols::LAYER_COUNT_ACCURACY,
            cols::HAZARD_RATE,
            cols::HAZARD_RATE_CI_LO,
            cols::HAZARD_RATE_CI_HI,
            cols::COLLISION_RATE,
            cols::OVERFLOW_RATE,
            cols::TRIANGLES_PER_S,
            cols::VERTICES_PER_S,
            cols::VS_INVOCATIONS,
            cols::PS_INVOCATIONS,
            cols::IMAGE_FILE,
            cols::NOTES,
        ],
    },
];

/// `samples.csv`, beside `runs.csv`: one row per timed sample (long format), so anyone can
/// re-analyse a run. A separate file with its own columns: not part of [`GROUPS`].
pub mod samples {
    use super::Col;
    pub const POINT_KEY: Col = Col::new("point_key", "the sample's point (runs.csv point_key)");
    pub const RUN_ID: Col = Col::new("run_id", "the run (runs.csv run_id)");
    pub const ADAPTER: Col = Col::new("adapter", "adapter name");
    pub const SAMPLE: Col = Col::new(
        "sample",
        "index of the sample within its point, from 0 (warm-up frames excluded)",
    );
    pub const GPU_MS: Col = Col::new(
        "gpu_ms",
        "GPU time of the frame: sum of its timestamped passes, ms",
    );
    pub const CPU_MS: Col = Col::new(
        "cpu_ms",
        "wall-clock time of the frame from first encode to GPU idle, ms",
    );
    pub const SM_CLOCK_MHZ: Col = Col::new(
        "sm_clock_mhz",
        "SM clock read right after the frame (NVML), MHz; empty without NVML",
    );
    pub const MEM_CLOCK_MHZ: Col = Col::new(
        "mem_clock_mhz",
        "memory clock read right after the frame, MHz; empty without NVML",
    );
    pub const DISCARDED: Col = Col::new(
        "discarded",
        "true if the sample was dropped: SM clock below 75 % of the reference (throttled), or canary_ratio over [timing] canary_max_ratio",
    );
    pub const ORDER: Col = Col::new(
        "order",
        "position of the frame in the group's measurement order (interleaved runs mix points)",
    );
    pub const CANARY_RATIO: Col = Col::new(
        "canary_ratio",
        "GPU time of the canary kernel run right after the frame over the process's baseline canary time (empty: no canary)",
    );
    pub const UNIX_MS: Col = Col::new(
        "unix_ms",
        "wall clock when the frame was done, ms since the Unix epoch (to line samples up with nvidia-smi logs)",
    );
    pub const SESSION: Col = Col::new(
        "session",
        "the [timing] sessions session that took the sample, from 0 (each prepared afresh elsewhere in memory; mfx compare matches frame-time modes, else compares the median sessions, else resamples sessions: stats::compare_matched)",
    );
    /// The header of `samples.csv`.
    pub const ALL: &[Col] = &[
        POINT_KEY,
        RUN_ID,
        ADAPTER,
        SAMPLE,
        GPU_MS,
        CPU_MS,
        SM_CLOCK_MHZ,
        MEM_CLOCK_MHZ,
        DISCARDED,
        ORDER,
        CANARY_RATIO,
        UNIX_MS,
        SESSION,
    ];
}

/// `flip/worst.csv`: the run's worst image rows by FLIP mean, with the PNGs beside it (paths
/// relative to the run folder). Written by the sweep, read by the report.
pub mod flip_worst {
    use super::Col;
    pub const RANK: Col = Col::new("rank", "1 = the largest flip_mean of the run");
    pub const POINT_KEY: Col = Col::new("point_key", "the row's point (runs.csv point_key)");
    pub const METHOD: Col = Col::new("method", "the row's method");
    pub const SCENE_LABEL: Col = Col::new("scene_label", "the row's scene");
    pub const FLIP_MEAN: Col = Col::new("flip_mean", "mean FLIP error vs the ground truth");
    pub const FLIP_P99: Col = Col::new("flip_p99", "99th percentile of the FLIP map");
    pub const METHOD_PNG: Col = Col::new("method_png", "the method's image over white");
    pub const TRUTH_PNG: Col = Col::new("truth_png", "the ground truth over white");
    pub const FLIP_PNG: Col = Col::new("flip_png", "the FLIP map in the magma colour map");
    /// The header of `flip/worst.csv`.
    pub const ALL: [Col; 9] = [
        RANK,
        POINT_KEY,
        METHOD,
        SCENE_LABEL,
        FLIP_MEAN,
        FLIP_P99,
        METHOD_PNG,
        TRUTH_PNG,
        FLIP_PNG,
    ];
}

/// Every column in file order.
pub fn all() -> impl Iterator<Item = Col> {
    GROUPS.iter().flat_map(|g| g.cols.iter().copied())
}

/// The header of `runs.csv`.
pub fn header() -> Vec<&'static str> {
    all().map(|c| c.name).collect()
}

/// The declared column called `name` (for names that come from data, e.g. an axis of a suite).
pub fn by_name(name: &str) -> Option<Col> {
    all().find(|c| c.name == name)
}

pub const COLUMNS_BEGIN: &str =
    "<!-- columns:begin (generated by scripts/update-columns.sh; do not edit) -->";
pub const COLUMNS_END: &str = "<!-- columns:end -->";

/// The column table of `results/README.md`, generated from the declarations.
pub fn markdown() -> String {
    let mut s = String::new();
    for g in GROUPS {
        s.push_str(&format!(
            "\n**{}**\n\n| column | type | meaning |\n|---|---|---|\n",
            g.title
        ));
        for c in g.cols {
            s.push_str(&format!(
                "| `{}` | {} | {} |\n",
                c.name,
                c.cell_type(),
                c.doc.replace('|', "\\|")
            ));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn column_names_are_unique_documented_snake_case() {
        let mut seen = std::collections::HashSet::new();
        for c in all() {
            assert!(seen.insert(c.name), "duplicate column {}", c.name);
            assert!(
                c.name
                    .chars()
                    .all(|ch| ch.is_ascii_lowercase() || ch.is_ascii_digit() || ch == '_'),
                "{} is not snake_case",
                c.name
            );
            assert!(!c.doc.is_empty(), "column {} has no doc", c.name);
        }
    }

    #[test]
    fn results_readme_is_generated_from_the_declarations() {
        let readme =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../results/README.md"))
                .expect("results/README.md must exist");
        let (Some(b), Some(e)) = (readme.find(COLUMNS_BEGIN), readme.find(COLUMNS_END)) else {
            panic!("results/README.md lacks the columns:begin/end markers");
        };
        let table = &readme[b + COLUMNS_BEGIN.len()..e];
        assert_eq!(
            table.trim(),
            markdown().trim(),
            "results/README.md's column table is stale: run scripts/update-columns.sh"
        );
    }
}
