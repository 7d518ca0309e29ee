//! bench-core: the harness. It opens the device ([`Gpu`]), uploads a scene ([`gpu_scene::GpuScene`]),
//! times any frame a study hands it ([`timed::Timed`] driven by [`measure::measure_timed`] under a
//! suite's [`measure::TimingPlan`], passes stamped by [`timing::GpuTimer`]), measures its own
//! yardsticks ([`floors`]), writes rows ([`record::Row`] to a [`record::Sink`]) and runs a suite
//! ([`runner`]) through whatever studies the caller registers ([`study::Study`], given a
//! [`study::GroupCtx`] and an [`study::Emit`]). It names no study: the study families are crates
//! on top of it (`studies/*`), and the binary holds the table of them (`mfx::STUDIES`).
//!
//! Reading order for a newcomer: `study.rs` (what a study implements), `timed.rs` and
//! `measure.rs` (how a frame is timed), `record.rs` (what is written), `runner.rs` (how a suite
//! becomes rows), `bind.rs` (how a pass declares its bindings).

pub mod axes;
pub mod bind;
pub mod build_info;
pub mod check;
pub mod clocks;
pub mod floors;
pub mod gles;
pub mod gpu;
pub mod gpu_scene;
pub mod gpu_util;
pub mod image_io;
pub mod interrupt;
pub mod limits;
pub mod manifest;
pub mod measure;
pub mod merge;
pub mod record;
pub mod roofs;
pub mod runner;
pub mod shard;
pub mod study;
/// Test helpers (a shared adapter, small scenes): built for this crate's unit tests and,
/// through the `testing` feature, for the study crates' tests; not part of the release library.
#[cfg(any(test, feature = "testing"))]
pub mod testing;
pub mod texture_memory;
pub mod timed;
pub mod timing;

pub use gpu::{BackendChoice, Gpu, GpuOptions};

/// Errors that cross the crate boundary; the CLI prints each as one line with context.
#[derive(Debug, thiserror::Error)]
pub enum CoreError {
    #[error("no usable adapter: {0}")]
    NoAdapter(String),
    #[error("GPU error: {0}")]
    Gpu(String),
    #[error("GPU out of memory: {0}")]
    OutOfMemory(String),
    /// A limit of the adapter or of the run's limits profile, known before any GPU work, rules
    /// the point out (a buffer over the largest storage binding): a `skipped` row naming it,
    /// not a `failed` one.
    #[error("limit: {0}")]
    Limit(String),
    #[error("{0}")]
    DeviceLost(String),
    #[error("bad sweep value: {0}")]
    Param(String),
    #[error(transparent)]
    Scene(#[from] scenarios::SceneError),
    #[error("CSV schema: {0}")]
    Schema(String),
    #[error("I/O: {0}")]
    Io(String),
    /// A signal asked the run to stop after the row in flight.
    #[error("interrupted by {0}")]
    Interrupted(String),
}

pub type Result<T, E = CoreError> = std::result::Result<T, E>;

/// A command-line word that is none of its option's values (`--backend`, `--limits`,
/// `--texture-memory`): names the option, the word and the words it takes.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown {what} '{text}' ({known})")]
pub struct UnknownWord {
    pub what: &'static str,
    pub text: String,
    /// The words it takes, comma-separated.
    pub known: String,
}

/// Why a point cannot run here: an adapter feature, format, sample count or limit it lacks, or
/// a configuration a method cannot supply. Known before the point's GPU work, it is not an
/// error of the run: its text is the `reason` of the point's `skipped` row, word for word.
/// (`Method::supports`, `Study` skip paths and the harness's adapter checks return it; the text
/// reads as a `&str` through `Deref`, and converts from and to `String` where a caller still
/// speaks `String`.)
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct Unsupported(String);

impl Unsupported {
    pub fn new(why: impl Into<String>) -> Unsupported {
        Unsupported(why.into())
    }
    /// The reason, as the `skipped` row says it.
    pub fn reason(&self) -> &str {
        &self.0
    }
}

impl std::ops::Deref for Unsupported {
    type Target = str;
    fn deref(&self) -> &str {
        &self.0
    }
}

impl From<String> for Unsupported {
    fn from(why: String) -> Unsupported {
        Unsupported(why)
    }
}

impl From<&str> for Unsupported {
    fn from(why: &str) -> Unsupported {
        Unsupported(why.to_string())
    }
}

impl From<Unsupported> for String {
    fn from(u: Unsupported) -> String {
        u.0
    }
}
