//! What a method is and what it hands back: the [`Method`] and [`Prepared`] traits, the
//! [`Capture`] a frame produces and the [`Expected`] set it is judged against. The methods
//! themselves live in `methods/`; this module is below them, so the study can time (through
//! the harness's `measure_timed`: [`measure`]) and judge any method without knowing which ones
//! exist.

use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::measure::{measure_timed, Measured, TimingPlan};
use bench_core::record::FlagSet;
use bench_core::study::InvalidPoint;
pub use bench_core::timed::{FrameStats, Timed};
use bench_core::Result;

/// Which reference a capture is judged against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Expected {
    /// Every fragment of every pixel.
    All,
    /// The `k` nearest fragments of every pixel.
    FirstK(u32),
}

/// What a method hands back after a frame, read from the GPU.
#[derive(Clone, Debug)]
pub struct Capture {
    /// Premultiplied RGBA per pixel (row-major, top-left first), A = 1 − transmittance;
    /// `None` for methods that make no image (the floors).
    pub image: Option<Vec<[f32; 4]>>,
    /// Fragments captured per pixel.
    pub counts: Option<Vec<u32>>,
    pub expected: Expected,
    /// Pixels whose fragments exceeded capacity (reported, never silent).
    pub overflow_pixels: Option<u64>,
    /// True fragments merged or lost by bucket collisions.
    pub collision_fragments: Option<u64>,
    /// Pixels whose captured set differs from the true k nearest (k-buffer RMW hazards).
    pub hazard_pixels: Option<u64>,
    /// Knowingly-failed modes (overflow, collision, lost_coplanar, precision, hazard…): only added to.
    pub flag: FlagSet,
    pub notes: String,
    /// The image the method's own definition gives (its CPU twin run on the reference's
    /// fragments, e.g. k nearest plus a blended tail, or MLAB in primitive order), when that is
    /// not the k-truncated composite `expected` names: judged into the `*_vs_k` columns. Set in
    /// `Prepared::judge`, which sees the reference.
    pub definition: Option<Vec<[f64; 4]>>,
    /// Fragments a bounded capture dropped this frame (`fragments_dropped`).
    pub dropped_fragments: Option<u64>,
    /// Fragments a bounded capture blended into its out-of-order tail (`fragments_tailed`).
    pub tailed_fragments: Option<u64>,
    /// The antialiasing the image was made with; `None` for a single-sample capture. When set
    /// (and not `AaMode::None`) the image is judged against the multisampled ground truth of
    /// that mode (`aa::ground_truth`), `counts` is `None` (a pixel has one count per sample),
    /// and `overflow_pixels` counts output pixels with any overflowing sample.
    pub aa: Option<mfx_reference::AaMode>,
    /// How an MSAA capture took its samples (per sample or coverage masks): selects its own
    /// definition (`aa::definition`) for the `*_vs_k` columns.
    pub aa_capture: Option<mfx_reference::multisample::AaCapture>,
    /// MSAA captures: what the sample-position probe found on this adapter
    /// (`aa::sample_positions`: `standard`, `differs: …`, `unverified: …`).
    pub sample_positions: Option<String>,
}

impl Capture {
    pub fn empty() -> Capture {
        Capture {
            image: None,
            counts: None,
            expected: Expected::All,
            overflow_pixels: None,
            collision_fragments: None,
            hazard_pixels: None,
            flag: FlagSet::new(),
            notes: String::new(),
            definition: None,
            dropped_fragments: None,
            tailed_fragments: None,
            aa: None,
            aa_capture: None,
            sample_positions: None,
        }
    }
}

/// A multi-fragment method (or a floor): description, declared axes, requirements, preparation.
pub trait Method: Send + Sync {
    fn name(&self) -> &'static str;
    /// One line: source, exact or approximate, passes, memory.
    fn describe(&self) -> &'static str;
    /// True when the method captures every fragment (within its capacity).
    fn exact(&self) -> bool;
    /// The axes this method reads, declared once (type, default, range): a suite's values are
    /// checked against them before any GPU work, and its product is taken over these only.
    fn axes(&self) -> Vec<Axis> {
        Vec::new()
    }
    /// Optional adapter features it cannot run without (the runner checks them before
    /// `supports`, so an override of `supports` cannot drop the check).
    fn required_features(&self) -> wgpu::Features {
        wgpu::Features::empty()
    }
    /// Rules across axes that one axis's range cannot say (e.g. `dof_near ≤ dof_far`); checked
    /// before any GPU work, so a violation is a bad suite, not a skipped row.
    fn validate(&self, point: &Point) -> std::result::Result<(), InvalidPoint> {
        let _ = point;
        Ok(())
    }
    /// Whether this point can run on this adapter (limits, memory) or with this method at all
    /// (an effect it cannot supply); `Err(reason)` becomes a `skipped` row.
    fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        let _ = (gpu, point);
        Ok(())
    }
    /// The `payload` column: what this point stores per fragment, for methods that specialise it.
    fn payload(&self, point: &Point) -> Option<&'static str> {
        let _ = point;
        None
    }
    /// Creates every pipeline, buffer and texture the frames need (never inside a timed region).
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>>;
}

/// Whether `method` can run `point` on `gpu`: its required features first, then its own rule.
pub fn supports(
    method: &dyn Method,
    gpu: &Gpu,
    point: &Point,
) -> std::result::Result<(), bench_core::Unsupported> {
    let missing = method.required_features() - gpu.features;
    if !missing.is_empty() {
        let names = bench_core::gpu::feature_names(missing);
        return Err(match gpu.profile {
            bench_core::limits::Profile::Adapter => format!("adapter lacks {names}"),
            p => format!("the `{p}` limits profile grants no {names}"),
        }
        .into());
    }
    method.supports(gpu, point)
}

/// A multi-fragment method ready to run on one scene at one resolution: a [`Timed`] frame
/// whose capture can be read back and judged.
pub trait Prepared: Timed {
    /// Reads the last frame's output.
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture>;
    /// The storage buffer the frame's output image is written to (premultiplied RGBA as
    /// `vec4<f32>` per pixel, every effect image one after another), for methods that keep it
    /// in one: the 2×2 supersampling wrapper box-filters it on the GPU.
    fn image_buffer(&self) -> Option<&wgpu::Buffer> {
        None
    }
    /// How a buffer over the largest storage binding was split (the `split` column,
    /// [`bench_core::limits::Split::column`]); None where nothing was.
    fn split(&self) -> Option<String> {
        None
    }
    /// Judges what only the method can judge against the exact reference (e.g. the k-buffer's
    /// captured depths vs the true k nearest → `hazard_pixels`); called after `readback`.
    fn judge(&mut self, cap: &mut Capture, reference: &mfx_reference::FragmentLists) {
        let _ = (cap, reference);
    }
    /// Frames to capture and judge for hazards in all (kbuffer_rmw's `hazard_captures`): the
    /// study runs and judges the extra ones after the first, for an interval on hazard_rate.
    fn hazard_captures(&self) -> u32 {
        1
    }
}

/// Prepares `method` (untimed), warms up, then samples frames until `plan`'s rule stops: the
/// harness's [`bench_core::measure::measure_timed`] on the method's [`Prepared`] frame.
pub fn measure(
    gpu: &Gpu,
    scene: &GpuScene,
    method: &dyn Method,
    point: &Point,
    plan: &TimingPlan,
) -> Result<Measured<dyn Prepared>> {
    measure_timed(gpu, scene, &|s| method.prepare(gpu, s, point), plan)
}

/// Several methods' points of one group timed interleaved (`[timing] interleave = true`):
/// [`bench_core::measure::measure_interleaved`] on their [`Prepared`] frames.
pub fn measure_interleaved(
    gpu: &Gpu,
    scene: &GpuScene,
    items: &[(&dyn Method, &Point)],
    plan: &TimingPlan,
) -> Vec<Result<Measured<dyn Prepared>>> {
    type Make<'a> = dyn Fn(&GpuScene) -> Result<Box<dyn Prepared>> + 'a;
    type Prepare<'a> = Box<Make<'a>>;
    let makes: Vec<Prepare<'_>> = items
        .iter()
        .map(|&(m, p)| Box::new(move |s: &GpuScene| m.prepare(gpu, s, p)) as Prepare<'_>)
        .collect();
    let makes: Vec<&Make<'_>> = makes.iter().map(|m| m.as_ref()).collect();
    bench_core::measure::measure_interleaved(gpu, scene, &makes, plan)
}
