//! The CSV contract between measuring and reporting: one tidy row per sweep point.
//!
//! Every column is declared here with its meaning (units in the name); `results/README.md`
//! documents the same list and a test checks the two agree. A row may only set declared columns,
//! and cells of axes that do not apply stay empty. Rows are flushed as they are produced.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::Write;
use std::path::Path;

use crate::{CoreError, Result};

/// Bumped when a column is renamed or changes meaning; `mfx merge` refuses mixed versions.
pub const SCHEMA_VERSION: u32 = 1;

pub struct Column {
    pub name: &'static str,
    pub doc: &'static str,
}

const fn c(name: &'static str, doc: &'static str) -> Column {
    Column { name, doc }
}

/// Run and machine metadata, identical on every row of one run.
pub const META: &[Column] = &[
    c("schema", "CSV schema version (integer); `mfx merge` refuses to mix versions"),
    c("run_id", "identifier of the sweep run (UTC time + suite + shard)"),
    c("git_rev", "git commit of the mfx build (`unknown` outside a checkout); `+dirty` if modified"),
    c("timestamp_utc", "when the row was produced, RFC 3339 UTC"),
    c("suite", "suite name"),
    c("study", "study kind that produced the row (methods, geometry, deferred, prepass, shadows, stability)"),
    c("shard", "shard index I of `--shard I/N` (0 when unsharded)"),
    c("shards", "shard count N (1 when unsharded)"),
    c("point_key", "stable identity of the sweep point (study|scene|resolution|method|axes); duplicates are reported by merge"),
    c("adapter", "adapter name as the driver reports it"),
    c("backend", "wgpu backend (vulkan, gl)"),
    c("device_type", "discretegpu, integratedgpu, virtualgpu, cpu, other"),
    c("driver", "driver name"),
    c("driver_info", "driver version string"),
    c("adapter_features", "optional wgpu features granted, `|`-separated"),
    c("width", "render target width in pixels"),
    c("height", "render target height in pixels"),
    c("reps", "timed repetitions per point"),
    c("warmup", "untimed warm-up frames before the timed ones"),
];

/// What was measured: scene, method, outcome.
pub const POINT: &[Column] = &[
    c("scene", "scene generator name"),
    c("scene_label", "generator with all its parameters, e.g. quads(depth_complexity=8,seed=1)"),
    c("triangles", "triangles submitted per geometry pass"),
    c("vertices", "vertices in the vertex buffers"),
    c("depth_complexity_max", "true maximum fragments per pixel (CPU reference)"),
    c("depth_complexity_mean", "true mean fragments per covered pixel (CPU reference)"),
    c("true_fragments", "true total fragments of the frame (CPU reference)"),
    c("method", "method or path name (see `mfx list methods`); floor_depth / floor_opaque are the floors"),
    c("exact", "true if the method captures every fragment exactly when within capacity"),
    c("effect", "effect computed on the captured fragments (transparency, translucency, fresnel, csg_*, dof)"),
    c("status", "ok | skipped | failed"),
    c("reason", "why a point was skipped or failed (empty when ok)"),
    c("flag", "a known, reported failure mode: overflow, collision, lost_coplanar, precision, hazard (empty if none)"),
];

/// Sweep axes shared by several studies (empty where an axis does not apply).
pub const AXES: &[Column] = &[
    c(
        "layers",
        "k: fragments kept per pixel (k-buffer, buckets, linked-list capacity per pixel)",
    ),
    c(
        "max_layers",
        "upper bound on peeling passes (classic/dual depth peeling)",
    ),
    c(
        "payload",
        "what is stored per fragment: depth (signed linear depth) | rgba_depth | depth_normal | depth_id | rgba_viewz | all (uber)",
    ),
    c(
        "occlusion_stop",
        "true if peeling stops when an occlusion query counts no fragment",
    ),
    c(
        "specialisation",
        "uber (everything stored and computed) | specialised (only what the effect reads)",
    ),
    c(
        "variant",
        "method-specific variant (e.g. heuristics on/off, naive vs stable thickness)",
    ),
    c(
        "bucket_count",
        "bucket methods: buckets per pixel per pass (8/16/32; 8 attachments × 4 channels, paired uses 2 channels per bucket)",
    ),
    c(
        "bucket_mode",
        "bucket methods: uniform (depth range split evenly: bdp, bdp2) | adaptive (histogram-equalised: adp)",
    ),
    c(
        "bucket_pairing",
        "bucket methods: single (one fragment per bucket) | paired (nearest and farthest of each bucket)",
    ),
    c(
        "hist_bins",
        "adaptive bucket peeling: bins of the per-pixel depth-occupancy histogram (256/1024/2048)",
    ),
    c(
        "small_max",
        "compute_abuffer: largest triangle bounding box (pixels) one thread rasterises; larger ones are shared by workgroups",
    ),
    c(
        "transform",
        "compute_abuffer: vertex (every vertex transformed once into a 16 B-per-vertex clip buffer) | triangle (each triangle's corners transformed in every kernel)",
    ),
    c(
        "coverage",
        "compute_abuffer: stepped (exact integer edge functions stepped pixel to pixel; big triangles' 32×32 tiles classified empty/full/partial) | direct (three exact 64-bit products per bounding-box pixel)",
    ),
    c(
        "resolve_sort",
        "compute_abuffer: workgroup (lists of up to 32 fragments sorted in workgroup memory) | private (every list in a per-thread array)",
    ),
    c(
        "pool",
        "linked_list: counted (one sub-pool per 8×8-pixel tile, sized by a prepare-time count) | fixed (layers × pixels nodes, one cursor)",
    ),
    c(
        "pool_slack",
        "linked_list, counted pool: spare nodes per tile, percent of its prepare-time count",
    ),
    c(
        "node",
        "linked_list: compact (12 B: depth, primitive, next; attributes re-derived from the primitive) | full (32 B: colour, depths, object id, next)",
    ),
];

/// Measurements.
pub const METRICS: &[Column] = &[
    c("gpu_ms_median", "median GPU time per frame in ms: sum of the frame's timestamped passes"),
    c("gpu_ms_min", "minimum GPU time per frame, ms"),
    c("gpu_ms_max", "maximum GPU time per frame, ms"),
    c("gpu_ms_rel_noise", "relative spread of GPU time: (p90 − p10) / median"),
    c("cpu_ms_median", "median wall-clock time per frame in ms, from first encode to GPU idle (includes CPU waits)"),
    c("cpu_ms_min", "minimum wall-clock time per frame, ms"),
    c("cpu_ms_max", "maximum wall-clock time per frame, ms"),
    c("pass_ms", "median GPU ms per pass label, JSON object (e.g. {\"peel\":1.2,\"composite\":0.1})"),
    c("geometry_passes", "geometry passes per frame (times the scene was rasterized)"),
    c("layers_captured_max", "most fragments captured in any pixel"),
    c("bytes_allocated", "bytes of buffers and textures the method allocated (scene buffers excluded)"),
    c("bytes_true_fragments", "bytes the scene's true fragments need: true_fragments × 8 (RGBA8 + f32 depth)"),
    c("x_floor", "gpu_ms_median over the floor_depth gpu_ms_median of the same scene, resolution and run"),
    c("speedup_vs_depth_peel", "depth_peel gpu_ms_median over this row's, same scene, resolution and run"),
    c("rmse", "root-mean-square error of the premultiplied RGBA image vs the CPU reference"),
    c("psnr_db", "peak signal-to-noise ratio (peak 1) vs the CPU reference, dB (inf when identical)"),
    c("max_abs_err", "largest absolute channel error vs the CPU reference"),
    c("bad_pixel_frac", "fraction of pixels with any channel error above bad_pixel_tol"),
    c("bad_pixel_tol", "the per-channel tolerance used for bad_pixel_frac"),
    c("non_finite", "NaN/Inf channels in the output (never hidden: they also make the pixel bad)"),
    c("layer_count_accuracy", "fraction of pixels whose captured fragment count equals the expected count"),
    c("hazard_rate", "k-buffer: fraction of pixels whose captured set differs from the true k nearest, excluding pixels with an f32 depth tie among their k + 1 nearest (those are flagged lost_coplanar and counted in notes)"),
    c("collision_rate", "buckets: fraction of true fragments merged or lost by bucket collisions"),
    c("overflow_rate", "fraction of pixels whose fragments exceeded the method's capacity"),
    c("triangles_per_s", "triangles submitted per second of GPU time"),
    c("vertices_per_s", "vertices (index count for indexed draws) per second of GPU time"),
    c("vs_invocations", "vertex shader invocations per frame (pipeline statistics query)"),
    c("ps_invocations", "fragment shader invocations per frame (pipeline statistics query)"),
    c("image_file", "the point's image saved by `mfx sweep --save-images`: images/<hash>.npy, float32 H×W×4 premultiplied RGBA (empty otherwise)"),
    c("notes", "free text: anything a reader must know about this row"),
];

/// All columns in file order: metadata, point, shared axes, each study's own, metrics.
pub fn columns() -> Vec<&'static Column> {
    let mut v: Vec<&'static Column> = Vec::new();
    v.extend(META);
    v.extend(POINT);
    v.extend(AXES);
    for study in crate::studies::STUDY_COLUMNS {
        v.extend(study.iter());
    }
    v.extend(METRICS);
    v
}

/// One CSV row: declared column → cell text.
#[derive(Clone, Debug, Default)]
pub struct Row {
    pub cells: BTreeMap<&'static str, String>,
}

impl Row {
    pub fn new() -> Self {
        Row::default()
    }

    /// Sets a cell. The column must be declared; an unknown name is a programming error caught
    /// by the writer (and by tests), never silently written.
    pub fn set(&mut self, col: &'static str, v: impl ToString) -> &mut Self {
        self.cells.insert(col, v.to_string());
        self
    }

    pub fn set_opt<T: ToString>(&mut self, col: &'static str, v: Option<T>) -> &mut Self {
        if let Some(v) = v {
            self.set(col, v);
        }
        self
    }

    /// Sets a float with enough digits to round-trip.
    pub fn set_f(&mut self, col: &'static str, v: f64) -> &mut Self {
        self.cells.insert(col, fmt_f64(v));
        self
    }

    pub fn get(&self, col: &str) -> Option<&str> {
        self.cells.get(col).map(|s| s.as_str())
    }
}

pub fn fmt_f64(v: f64) -> String {
    if v.is_infinite() {
        if v > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        }
    } else if v.is_nan() {
        "nan".into()
    } else {
        format!("{v}")
    }
}

/// Receives finished rows: the CSV writer, the progress bar, a log…
pub trait Sink {
    fn point_done(&mut self, row: &Row) -> Result<()>;
}

/// Appends rows to `runs.csv`, flushing each one so an interrupted sweep loses nothing.
pub struct CsvSink {
    file: File,
    header: Vec<&'static str>,
    pub rows_written: usize,
}

impl CsvSink {
    pub fn create(path: &Path) -> Result<CsvSink> {
        let header: Vec<&'static str> = columns().iter().map(|c| c.name).collect();
        let mut file =
            File::create(path).map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?;
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(&header)
            .map_err(|e| CoreError::Io(e.to_string()))?;
        file.write_all(&w.into_inner().map_err(|e| CoreError::Io(e.to_string()))?)
            .map_err(|e| CoreError::Io(e.to_string()))?;
        Ok(CsvSink {
            file,
            header,
            rows_written: 0,
        })
    }
}

/// Serialises a row in header order, refusing undeclared columns.
pub fn row_record(header: &[&'static str], row: &Row) -> Result<Vec<String>> {
    if let Some(k) = row.cells.keys().find(|k| !header.contains(k)) {
        return Err(CoreError::Schema(format!(
            "row sets undeclared column '{k}'"
        )));
    }
    Ok(header
        .iter()
        .map(|h| row.cells.get(h).cloned().unwrap_or_default())
        .collect())
}

impl Sink for CsvSink {
    fn point_done(&mut self, row: &Row) -> Result<()> {
        let rec = row_record(&self.header, row)?;
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(&rec)
            .map_err(|e| CoreError::Io(e.to_string()))?;
        let bytes = w.into_inner().map_err(|e| CoreError::Io(e.to_string()))?;
        self.file
            .write_all(&bytes)
            .map_err(|e| CoreError::Io(e.to_string()))?;
        self.file
            .flush()
            .map_err(|e| CoreError::Io(e.to_string()))?;
        self.rows_written += 1;
        Ok(())
    }
}

pub const COLUMNS_BEGIN: &str =
    "<!-- columns:begin (generated by scripts/update-columns.sh; do not edit) -->";
pub const COLUMNS_END: &str = "<!-- columns:end -->";

/// The column table of results/README.md, generated from the declarations above.
pub fn columns_markdown() -> String {
    let mut s = String::from("| column | meaning |\n|---|---|\n");
    for c in columns() {
        s.push_str(&format!(
            "| `{}` | {} |\n",
            c.name,
            c.doc.replace('|', "\\|")
        ));
    }
    s
}

/// The declared column called `name`, as the `'static` name rows use.
pub fn column_name(name: &str) -> Option<&'static str> {
    columns()
        .into_iter()
        .find(|c| c.name == name)
        .map(|c| c.name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn column_names_are_unique_snake_case() {
        let cols = columns();
        let mut seen = std::collections::HashSet::new();
        for c in &cols {
            assert!(seen.insert(c.name), "duplicate column {}", c.name);
            assert!(
                c.name
                    .chars()
                    .all(|ch| ch.is_ascii_lowercase() || ch.is_ascii_digit() || ch == '_'),
                "{}",
                c.name
            );
            assert!(!c.doc.is_empty(), "column {} has no doc", c.name);
        }
    }

    #[test]
    fn results_readme_documents_every_column() {
        let readme =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../results/README.md"))
                .expect("results/README.md must exist");
        for c in columns() {
            assert!(
                readme.contains(&format!("`{}`", c.name)),
                "results/README.md does not document column `{}`",
                c.name
            );
        }
    }

    #[test]
    fn undeclared_column_is_refused() {
        let header: Vec<&'static str> = columns().iter().map(|c| c.name).collect();
        let mut r = Row::new();
        r.set("not_a_column", 1);
        assert!(row_record(&header, &r).is_err());
    }
}
