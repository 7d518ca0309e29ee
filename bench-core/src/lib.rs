//! bench-core: the GPU context, timing, the multi-fragment methods, the exact CPU reference,
//! error metrics, CSV records and the sweep runner. Reading order for a newcomer:
//! `methods/mod.rs` (what is measured), `reference/mod.rs` (what it is judged against),
//! `record.rs` (what is written), `runner.rs` (how a suite becomes rows).

pub mod aa;
pub mod axes;
pub mod build_info;
pub mod check;
pub mod clocks;
pub mod effects;
pub mod gles;
pub mod gpu;
pub mod gpu_scene;
pub mod gpu_util;
pub mod image_io;
pub mod interrupt;
pub mod judge;
pub mod limits;
pub mod manifest;
pub mod measure;
pub mod merge;
pub mod method;
pub mod methods;
pub mod metrics;
pub mod oit;
pub mod papers;
pub mod record;
pub mod reference;
pub mod runner;
pub mod shading;
pub mod shard;
pub mod studies;
/// Test helpers (a shared adapter, scenes, run-and-compare): built for this crate's unit tests
/// and, through the `testing` feature its dev-dependency on itself turns on, for its
/// integration tests; not part of the release library.
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
