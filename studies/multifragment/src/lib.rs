//! mfx-multifragment: the multi-fragment study on the harness (`bench-core`). Capture methods
//! (depth peeling, k-buffers, linked lists, the compute A-buffer, the order-independent
//! approximations) judged against the exact f64 reference (`mfx-reference`), every effect
//! through one WGSL fold, antialiasing against the multisampled truth; the `methods`,
//! `stability` and `views` study kinds. Reading order for a newcomer: `methods/mod.rs` (what is measured),
//! `method.rs` (what a method hands back), `judge.rs` (how it is judged), `studies/methods.rs`
//! (how a group becomes rows).

pub mod aa;
pub mod effects;
pub mod judge;
pub mod method;
pub mod methods;
pub mod studies;
/// Method helpers for tests (render, run and judge one method on a scene): built for this
/// crate's unit tests and, through the `testing` feature its dev-dependency on itself turns
/// on, for its integration tests; not part of the release library.
#[cfg(any(test, feature = "testing"))]
pub mod testing;

pub use studies::methods::MethodsStudy;
pub use studies::stability::StabilityStudy;
pub use studies::views::ViewsStudy;

/// This crate's study kinds (the binary's table, `mfx::STUDIES`, lists them with the others).
pub const STUDIES: &[&dyn bench_core::study::Study] =
    &[&MethodsStudy, &StabilityStudy, &ViewsStudy];
