//! What the `mfx` binary knows above the harness: the table of studies a run can name (as
//! wgpu's examples binary holds `EXAMPLES` and nvbench's benchmarks register themselves; the
//! harness, `bench-core`, names none), and the papers check that reads it. A library so the
//! root package's tests use the same table as the binary.

pub mod papers;

use bench_core::studies::deferred::DeferredStudy;
use bench_core::studies::geometry::GeometryStudy;
use bench_core::studies::methods::MethodsStudy;
use bench_core::studies::prepass::PrepassStudy;
use bench_core::studies::shadows::ShadowsStudy;
use bench_core::studies::stability::StabilityStudy;
use bench_core::studies::Study;

/// Every study kind a suite's `[[study]]` may name, in listing order (one row each).
pub const STUDIES: &[&dyn Study] = &[
    &MethodsStudy,
    &GeometryStudy,
    &DeferredStudy,
    &PrepassStudy,
    &StabilityStudy,
    &ShadowsStudy,
];
