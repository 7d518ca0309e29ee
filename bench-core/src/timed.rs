//! What the harness times: a [`Timed`] frame (encode, submit, timestamp its passes) and what it
//! holds in memory. `measure::measure_timed` drives every study through it — the
//! multi-fragment methods (whose [`crate::method::Prepared`] adds a capture to judge), the
//! deferred shading paths, the geometry study's feeds, the light pre-pass and the shadow mapper
//! — so every row is timed by one stopping rule, canary and clock lift.

use crate::gpu::Gpu;
use crate::gpu_scene::GpuScene;
use crate::record::Col;
use crate::timing::GpuTimer;
use crate::Result;

/// What one frame did.
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameStats {
    /// Times the scene's geometry was submitted.
    pub geometry_passes: u32,
    /// Layers (or passes of capture) that produced fragments.
    pub layers: u32,
}

/// One pass of a frame on the GPU clock: (label, start ms, end ms), relative to the frame's
/// earliest timestamp ([`GpuTimer::read_spans`]).
pub type PassSpan = (String, f64, f64);

/// A frame that can be encoded, submitted and timed, with every GPU object made beforehand.
pub trait Timed {
    /// One frame's work: encode, submit (as often as it needs), timestamp each pass with `timer`.
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats>;
    /// Bytes of buffers and textures allocated for the frames.
    fn bytes_allocated(&self) -> u64;
    /// Of those, the per-pixel structures (heads, offsets, counters, output image), when known;
    /// the rest holds fragments.
    fn bytes_overhead(&self) -> Option<u64> {
        None
    }
    /// Bytes one frame moves through memory, as estimated for `bytes_per_s`: by default every
    /// allocated byte written once and read once (`2 × bytes_allocated`). An estimate, declared
    /// here so that a frame that knows better can say so.
    fn bytes_moved(&self) -> u64 {
        2 * self.bytes_allocated()
    }
    /// Named parts of the frame just run, in ms, that the GPU timestamps do not give: CPU work
    /// it did (e.g. lighting on CPU cores while the GPU renders) or intervals read off its
    /// passes' `spans`. The harness keeps them for the kept samples and reports their medians
    /// ([`crate::measure::Measured::parts`]). Each part is keyed by the column it fills
    /// (`cols::X`), or by a [`Col`] its study declares for a part that has no column.
    fn parts(&self, spans: &[PassSpan]) -> Vec<(Col, f64)> {
        let _ = spans;
        Vec::new()
    }
}
