//! The study kinds these tests run and check suites with (the binary's own table is
//! `mfx::STUDIES`; the harness names none).

use bench_core::studies::Study;

pub const STUDIES: &[&dyn Study] = &[
    &bench_core::studies::methods::MethodsStudy,
    &bench_core::studies::geometry::GeometryStudy,
    &bench_core::studies::deferred::DeferredStudy,
    &bench_core::studies::prepass::PrepassStudy,
    &bench_core::studies::stability::StabilityStudy,
    &bench_core::studies::shadows::ShadowsStudy,
];
