//! The type of every column's cells, declared once: what a typed reader (`runs.parquet`,
//! pandas, polars, DuckDB) stores each column as. A column not listed here is free text; a
//! test ([`tests`]) fails on a name that says it holds a number (a unit suffix) but is not
//! declared as one, so a new numeric column cannot slip through as text.

use std::fmt;

use crate::{cols, Col};

/// What one column's non-empty cells are. An empty cell is a missing value in every type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CellType {
    /// A signed 64-bit integer (`42`, `-3`).
    Int,
    /// An unsigned 64-bit integer (seeds up to `u64::MAX`).
    UInt,
    /// A 64-bit float; `inf`, `-inf` and `nan` are written as such.
    Float,
    /// `true` or `false`.
    Bool,
    /// Free text.
    Text,
    /// A [`crate::Status`] word.
    Status,
    /// A [`crate::FlagSet`]: `|`-joined flag words (unknown words kept).
    Flags,
    /// A [`crate::GpuMsInterval`] word.
    GpuMsInterval,
    /// A [`crate::PointKey`]: `study|scene|WxH|method|axes`.
    PointKey,
}

impl CellType {
    /// The name written in docs and in a Parquet file's `mfx.column_types` metadata.
    pub fn name(self) -> &'static str {
        match self {
            CellType::Int => "int",
            CellType::UInt => "uint",
            CellType::Float => "float",
            CellType::Bool => "bool",
            CellType::Text => "text",
            CellType::Status => "status",
            CellType::Flags => "flags",
            CellType::GpuMsInterval => "gpu_ms_interval",
            CellType::PointKey => "point_key",
        }
    }

    /// Whether cells are stored as text (free text and the typed words of `values.rs`).
    pub fn is_text(self) -> bool {
        matches!(
            self,
            CellType::Text
                | CellType::Status
                | CellType::Flags
                | CellType::GpuMsInterval
                | CellType::PointKey
        )
    }

    /// Checks one non-empty cell against the type; the error says what it is not.
    pub fn check(self, cell: &str) -> Result<(), NotOfType> {
        let ok = match self {
            CellType::Int => cell.parse::<i64>().is_ok(),
            CellType::UInt => cell.parse::<u64>().is_ok(),
            CellType::Float => cell.parse::<f64>().is_ok(),
            CellType::Bool => cell == "true" || cell == "false",
            CellType::Text | CellType::Flags => true,
            CellType::Status => cell.parse::<crate::Status>().is_ok(),
            CellType::GpuMsInterval => cell.parse::<crate::GpuMsInterval>().is_ok(),
            CellType::PointKey => cell.parse::<crate::PointKey>().is_ok(),
        };
        if ok {
            Ok(())
        } else {
            Err(NotOfType {
                cell: cell.to_string(),
                ty: self,
            })
        }
    }
}

/// A cell that does not read as its column's type.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("'{cell}' is not a {ty}")]
pub struct NotOfType {
    pub cell: String,
    pub ty: CellType,
}

impl fmt::Display for CellType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Integer columns: counts, sizes in pixels or bytes, ids, integer axes.
const INT: &[Col] = &[
    cols::SCHEMA,
    cols::SHARD,
    cols::SHARDS,
    cols::WIDTH,
    cols::HEIGHT,
    cols::TRIANGLES,
    cols::VERTICES,
    cols::DEPTH_COMPLEXITY_MAX,
    cols::TRUE_FRAGMENTS,
    cols::LAYERS,
    cols::MAX_LAYERS,
    cols::BUCKET_COUNT,
    cols::HIST_BINS,
    cols::SMALL_MAX,
    cols::POOL_SLACK,
    cols::MOMENT_COUNT,
    cols::AA_SAMPLES,
    cols::ST_SAMPLES,
    cols::ST_PASSES,
    cols::ST_SEED,
    cols::CSG_A,
    cols::CSG_B,
    cols::BATCH_SIZE,
    cols::DRAW_TRIANGLES,
    cols::EXTRA_ATTRIBUTES,
    cols::BATCHES,
    cols::BATCH_VERTICES,
    cols::INDEX_COUNT,
    cols::VERTEX_STRIDE_BYTES,
    cols::VERTEX_BYTES,
    cols::INDEX_BYTES,
    cols::LOST_FRAGMENTS,
    cols::LIGHT_COUNT,
    cols::TILE_SIZE,
    cols::CULL_LEVELS,
    cols::THREAD_COUNT,
    cols::LIGHTS_PER_TILE_MAX,
    cols::CLASS_IDS_PRESENT,
    cols::PERMUTATIONS,
    cols::BYTES_RT_WRITTEN,
    cols::BYTES_RT_READ,
    cols::SHADOW_MAP_RES,
    cols::MAX_NSPP,
    cols::SHADOW_RAYS,
    cols::SHADOW_PIXELS,
    cols::GPU_MS_OUTLIERS,
    cols::SAMPLES,
    cols::SAMPLES_DISCARDED,
    cols::CANARY_DISCARDED,
    cols::WARMUP_FRAMES,
    cols::GEOMETRY_PASSES,
    cols::LAYERS_CAPTURED_MAX,
    cols::BYTES_ALLOCATED,
    cols::BYTES_OVERHEAD,
    cols::BYTES_TRUE_FRAGMENTS,
    cols::NON_FINITE,
    cols::FRAGMENTS_MISSING,
    cols::FRAGMENTS_EXTRA,
    cols::DEPTH_TIE_PIXELS,
    cols::FRAGMENTS_DROPPED,
    cols::FRAGMENTS_TAILED,
    cols::VS_INVOCATIONS,
    cols::PS_INVOCATIONS,
    cols::GPU_OTHER_PROCESSES,
    cols::FLICKER_BEYOND_BOUND,
    cols::FLICKER_WORST_VIEW,
    cols::POPPING_WORST_VIEW,
    cols::FLIP_WORST_VIEW,
    cols::GPU_MS_WORST_VIEW,
    cols::RMSE_WORST_VIEW,
    cols::PATH_IMAGES_POP_VIEW,
    cols::PATH_IMAGES_WORST_VIEW,
    cols::HAZARD_CAPTURES,
    cols::PATH_VIEWS,
    cols::VIEWS_EXACT,
    cols::WORKING_SET_BYTES,
];

/// Unsigned integer columns: seeds that use all 64 bits.
const UINT: &[Col] = &[cols::ORDER_SEED];

/// Boolean columns.
const BOOL: &[Col] = &[
    cols::CLAIMS_EXACT,
    cols::EXACT,
    cols::OCCLUSION_STOP,
    cols::TIEBREAK,
    cols::MOMENT_NORMALIZE,
    cols::ST_CORRECTION,
    cols::INDEXED,
    cols::CONE_CULL,
    cols::DIFFUSE_SKIP,
    cols::QUAD_SKIP,
    cols::SPEC_SKIP,
    cols::HSM,
    cols::SECOND_VIEW,
    cols::OVERLAP,
    cols::LIT_WITHIN_FRAME,
    cols::TARGET_REACHED,
    cols::GPU_TIME_TRUSTED,
    cols::MATCHES_TRUTH,
    cols::L2_RESIDENT,
];

/// Float columns: times, rates, fractions, ratios, errors, clocks, float axes.
const FLOAT: &[Col] = &[
    cols::DEPTH_COMPLEXITY_MEAN,
    cols::EXACT_BOUND,
    cols::SIGMA,
    cols::DOF_NEAR,
    cols::DOF_FAR,
    cols::ISO_VALUE,
    cols::ACMR,
    cols::ATVR,
    cols::VS_ACMR,
    cols::POST_TRANSFORM_HIT_RATE,
    cols::GPU_MS_SMALL_VIEWPORT,
    cols::RASTER_BOUND_RATIO,
    cols::PREP_MS,
    cols::STIFFNESS_VALUE,
    cols::ATTENUATION_THRESHOLD,
    cols::SPEC_SKIP_FRAC,
    cols::PERM_NARROW_FRAC,
    cols::CONE_CULL_FRAC,
    cols::DIFFUSE_ONLY_FRAC,
    cols::DIFFUSE_SKIP_FRAC,
    cols::LIGHTS_PER_TILE_MEAN,
    cols::SHADOW_FADE_TILE_FRAC,
    cols::MSAA_EDGE_TILE_FRAC,
    cols::CPU_LIGHT_MS,
    cols::CPU_CULL_MS,
    cols::CPU_UNPACK_MS,
    cols::CPU_SHADE_MS,
    cols::CPU_PACK_MS,
    cols::CPU_PHASES_MS,
    cols::SHADE_NS_PER_LIGHT_QUAD,
    cols::QUAD_SKIP_FRAC,
    cols::SPEEDUP_VS_NAIVE,
    cols::REL_ERR_MAX,
    cols::SPEC_COLOR_LOSS_RMSE,
    cols::FORMAT_RMSE,
    cols::FRAME_MS,
    cols::FRAME_MS_CI_LO,
    cols::FRAME_MS_CI_HI,
    cols::GPU_IDLE_MS,
    cols::LATENCY_MS,
    cols::LIGHT_READY_MS,
    cols::GPU_GAP_MS,
    cols::GPU_BUSY_IN_GAP_MS,
    cols::MAP_WAIT_MS,
    cols::GSCALE,
    cols::GMAX,
    cols::VIS_RMSE,
    cols::VIS_BIAS,
    cols::VIS_MAX_ABS_ERR,
    cols::VIS_BLEED_MEAN,
    cols::VIS_OVERSHADOW_MEAN,
    cols::REFERENCE_MS,
    cols::GPU_MS_MEDIAN,
    cols::GPU_MS_MIN,
    cols::GPU_MS_MAX,
    cols::GPU_MS_P50,
    cols::GPU_MS_P95,
    cols::GPU_MS_P99,
    cols::FRAGMENTS_PER_S,
    cols::BYTES_PER_S,
    cols::PEAK_BANDWIDTH_FRAC,
    cols::GPU_MS_REL_NOISE,
    cols::GPU_MS_MEAN,
    cols::GPU_MS_CI_LO,
    cols::GPU_MS_CI_HI,
    cols::GPU_MS_MEAN_CI_LO,
    cols::GPU_MS_MEAN_CI_HI,
    cols::GPU_MS_REL_CI,
    cols::CANARY_RATIO_MAX,
    cols::CLOCK_LIFT_MS,
    cols::CLOCK_LIFT_FROM_MHZ,
    cols::CLOCK_LIFT_TO_MHZ,
    cols::MEASURE_MS,
    cols::PREPARE_MS,
    cols::SESSION_SPREAD,
    cols::JUDGE_MS,
    cols::FRAGMENT_REFERENCE_MS,
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
    cols::BYTES_PER_PIXEL,
    cols::FRAGMENT_BYTES_RATIO,
    cols::X_FLOOR,
    cols::X_BLEND,
    cols::SPEEDUP_VS_DEPTH_PEEL,
    cols::RMSE,
    cols::PSNR_DB,
    cols::MAX_ABS_ERR,
    cols::BAD_PIXEL_FRAC,
    cols::BAD_PIXEL_TOL,
    cols::RMSE_VS_K,
    cols::PSNR_DB_VS_K,
    cols::MAX_ABS_ERR_VS_K,
    cols::BAD_PIXEL_FRAC_VS_K,
    cols::FLIP_MEAN,
    cols::FLIP_P99,
    cols::LAYER_COUNT_ACCURACY,
    cols::HAZARD_RATE,
    cols::COLLISION_RATE,
    cols::OVERFLOW_RATE,
    cols::TRIANGLES_PER_S,
    cols::VERTICES_PER_S,
    cols::AT_REST_CHANGED_MAX,
    cols::AT_REST_CHANGED_MEAN,
    cols::BIAS_MAX,
    cols::FLICKER_BOUND_MEAN,
    cols::FLICKER_MAX,
    cols::FLICKER_MEAN,
    cols::FLIP_PATH_WORST,
    cols::GPU_MS_PATH_P99,
    cols::GPU_MS_PATH_WORST,
    cols::HAZARD_RATE_CI_HI,
    cols::HAZARD_RATE_CI_LO,
    cols::POP_EPSILON,
    cols::POPPING_MAX,
    cols::POPPING_MEAN,
    cols::RMSE_PATH_WORST,
    cols::ROOF_BYTES_PER_S,
    cols::SHADE_NS_PER_LIGHT_QUAD_CI_HI,
    cols::SHADE_NS_PER_LIGHT_QUAD_CI_LO,
];

/// The type of `col`'s cells ([`CellType::Text`] for a column not declared numeric, boolean or
/// one of the typed words).
pub fn cell_type(col: Col) -> CellType {
    let name = col.name;
    let in_ = |list: &[Col]| list.iter().any(|c| c.name == name);
    if name == cols::STATUS.name {
        CellType::Status
    } else if name == cols::FLAG.name {
        CellType::Flags
    } else if name == cols::GPU_MS_INTERVAL.name {
        CellType::GpuMsInterval
    } else if name == cols::POINT_KEY.name {
        CellType::PointKey
    } else if in_(INT) {
        CellType::Int
    } else if in_(UINT) {
        CellType::UInt
    } else if in_(BOOL) {
        CellType::Bool
    } else if in_(FLOAT) {
        CellType::Float
    } else {
        CellType::Text
    }
}

/// The type of the column called `name` (a header read from a file): declared columns by their
/// declaration, any other name (a column of an older schema) `None`.
pub fn cell_type_of(name: &str) -> Option<CellType> {
    crate::by_name(name).map(cell_type)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_typed_column_is_declared_and_listed_once() {
        let lists = [INT, UINT, BOOL, FLOAT];
        let mut seen = std::collections::HashSet::new();
        for list in lists {
            for c in list {
                assert!(
                    crate::by_name(c.name).is_some(),
                    "{} is typed but not in GROUPS",
                    c.name
                );
                assert!(seen.insert(c.name), "{} has two types", c.name);
            }
        }
    }

    /// Names end in their unit (STYLE.md): such a column holds a number. Text columns with a
    /// unit-like ending, each with its reason.
    #[test]
    fn a_column_named_with_a_unit_is_declared_numeric() {
        const UNITS: &[&str] = &[
            "_ms", "_frac", "_rate", "_mhz", "_bytes", "_per_s", "_ratio", "_db", "_pixels",
            "_count", "_max", "_min", "_mean", "_rmse", "_c_max", "_w_mean",
        ];
        // JSON of per-pass times, WxH text.
        const TEXT_OK: &[&str] = &["pass_ms", "small_viewport"];
        let mut bad = Vec::new();
        for c in crate::all() {
            let t = cell_type(c);
            if t.is_text()
                && UNITS.iter().any(|u| c.name.ends_with(u))
                && !TEXT_OK.contains(&c.name)
            {
                bad.push(c.name);
            }
        }
        assert!(
            bad.is_empty(),
            "columns named with a unit but typed as text (add them to INT, UINT or FLOAT in schema/src/types.rs): {bad:?}"
        );
    }

    #[test]
    fn cells_are_checked_against_their_type() {
        assert!(CellType::Int.check("-3").is_ok());
        assert!(CellType::Int.check("1.5").is_err());
        assert!(CellType::UInt.check("18446744073709551615").is_ok());
        assert!(CellType::UInt.check("-1").is_err());
        for x in ["inf", "-inf", "nan", "NaN", "1e-7", "3"] {
            assert!(CellType::Float.check(x).is_ok(), "{x}");
        }
        assert!(CellType::Bool.check("True").is_err());
        assert!(CellType::Status
            .check(crate::Status::Skipped.name())
            .is_ok());
        assert!(CellType::Status.check("fine").is_err());
        assert!(CellType::PointKey.check("m|s|64x64|floor_depth|").is_ok());
        assert!(CellType::PointKey.check("k1").is_err());
        assert_eq!(cell_type(cols::GPU_MS_MEDIAN), CellType::Float);
        assert_eq!(cell_type(cols::SAMPLES), CellType::Int);
        assert_eq!(cell_type(cols::ADAPTER), CellType::Text);
        assert_eq!(cell_type_of("reps"), None, "a column of schema 1 only");
    }
}
