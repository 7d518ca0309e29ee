//! What the `mfx` binary knows above the harness: the table of studies a run can name (as
//! wgpu's examples binary holds `EXAMPLES` and nvbench's benchmarks register themselves; the
//! harness, `bench-core`, names none), and the papers check that reads it. A library so the
//! root package's tests use the same table as the binary.
//!
//! | kind      | what it measures                                                     |
//! |-----------|----------------------------------------------------------------------|
//! | `methods` | multi-fragment capture methods vs the exact CPU reference            |
//! | `geometry`| geometry feeding (Bavoil ch. 3): batches, formats, layout, indices, order |
//! | `deferred`| deferred shading paths (naive, volumes, tiled, classified, CPU tiles) |
//! | `prepass` | light pre-pass vs deferred; light buffer on CPU cores, overlapped     |
//! | `stability` | stiff/extreme inputs: methods study + case, stiffness, lost fragments |
//! | `shadows` | layered soft shadow maps from an area light vs a ray-traced reference |
//! | `views`   | the methods study along each scene's camera path: flicker, popping, time per view |

pub mod papers;

use bench_core::study::Study;
use mfx_geometry::GeometryStudy;
use mfx_multifragment::studies::methods::MethodsStudy;
use mfx_multifragment::studies::stability::StabilityStudy;
use mfx_multifragment::studies::views::ViewsStudy;
use mfx_shading::studies::deferred::DeferredStudy;
use mfx_shading::studies::prepass::PrepassStudy;
use mfx_shadows::ShadowsStudy;

/// Every study kind a suite's `[[study]]` may name, in listing order (one row each).
pub const STUDIES: &[&dyn Study] = &[
    &MethodsStudy,
    &GeometryStudy,
    &DeferredStudy,
    &PrepassStudy,
    &StabilityStudy,
    &ViewsStudy,
    &ShadowsStudy,
];
