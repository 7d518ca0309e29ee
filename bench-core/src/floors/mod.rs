//! The floors: the harness's own timed frames, the yardsticks every row of a group is read
//! against. One depth-only pass (`floor_depth`), one opaque single-colour pass
//! (`floor_opaque`) and two unsorted alpha-blended passes (`floor_blend`, `floor_blend_const`,
//! in `blend.rs`) over exactly the scene's geometry and resolution. Every row's `x_floor` is its
//! time over `floor_depth` of the same scene in the same run (`x_blend`: over
//! `floor_blend_const`). The runner times them ([`crate::runner`]) and never judges them; a
//! study that wants a floor as one of its points wraps it (the multi-fragment methods list
//! each floor as a method).

mod blend;
mod pass;

pub use blend::CONST_PREMUL;

use crate::gpu::Gpu;
use crate::gpu_scene::{Attrs, GpuScene};
use crate::timed::{FrameStats, Timed};
use crate::timing::GpuTimer;
use crate::Result;

/// A floor: one pass over the scene's geometry, timed like any other frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Floor {
    /// One depth-only pass (positions only, an empty fragment shader).
    Depth,
    /// The depth-only pass without a fragment stage: `floor_depth` until 2026-12-02. Measured
    /// on the H200 (`results/reference/2026-12-02-h200-floors`): its time depended on which
    /// render pipeline the process had run last — shells(16, 256) at 1024² took 1.041 ms right
    /// after WBOIT or the compute A-buffer and 1.465 ms right after the RMW k-buffer or ADP,
    /// settled or not, pooled or dedicated memory — as if a pipeline without a fragment stage
    /// inherited state the one before it left. Kept (as a method of the multi-fragment study,
    /// not a floor row) to watch that.
    DepthVs,
    /// One opaque single-colour pass (positions only, RGBA8 + depth).
    Opaque,
    /// The methods' vertex stage and every fragment's colour blended unordered.
    Blend,
    /// Positions only and one constant colour blended unordered: `x_blend`'s yardstick.
    BlendConst,
}

/// The floor rows of every group, in the order the runner measures them. (`floor_blend_const`:
/// every fragment blended unordered in hardware, positions only: what an engine without OIT
/// pays at least, the ratio LucidRaster reports and `x_blend`'s yardstick; `floor_blend`: the
/// same through the methods' own vertex stage.)
pub const FLOORS: [Floor; 4] = [Floor::Depth, Floor::Opaque, Floor::Blend, Floor::BlendConst];

impl Floor {
    /// Every floor, the ones without a row of their own included.
    pub const ALL: [Floor; 5] = [
        Floor::Depth,
        Floor::DepthVs,
        Floor::Opaque,
        Floor::Blend,
        Floor::BlendConst,
    ];

    /// Its name: the `method` column of its rows.
    pub fn name(self) -> &'static str {
        match self {
            Floor::Depth => "floor_depth",
            Floor::DepthVs => "floor_depth_vs",
            Floor::Opaque => "floor_opaque",
            Floor::Blend => "floor_blend",
            Floor::BlendConst => "floor_blend_const",
        }
    }

    pub fn describe(self) -> &'static str {
        match self {
            Floor::Depth => {
                "yardstick: one depth-only pass (positions only, an empty fragment shader); no image"
            }
            Floor::DepthVs => {
                "yardstick variant: one depth-only pass with no fragment stage at all (the old floor_depth); no image"
            }
            Floor::Opaque => {
                "yardstick: one opaque single-colour pass (positions only, RGBA8 + depth); no image"
            }
            Floor::Blend => {
                "yardstick: the methods' vertex stage (position, normal, colour, object id) and every fragment's colour blended premultiplied-over into RGBA8 in primitive order, no depth test, no sort; not judged"
            }
            Floor::BlendConst => {
                "yardstick of x_blend: positions only and one constant colour blended premultiplied-over into RGBA8, no depth test, no sort (the cheapest unordered blend); not judged"
            }
        }
    }

    /// The floor called `name`.
    pub fn by_name(name: &str) -> Option<Floor> {
        Floor::ALL.into_iter().find(|f| f.name() == name)
    }

    /// Creates the floor's GPU objects on `scene` (untimed).
    pub fn prepare(self, gpu: &Gpu, scene: &GpuScene) -> FloorFrame {
        FloorFrame(match self {
            Floor::Depth => Inner::Pass(pass::PreparedFloor::new(gpu, scene, pass::Kind::Depth)),
            Floor::DepthVs => {
                Inner::Pass(pass::PreparedFloor::new(gpu, scene, pass::Kind::DepthVs))
            }
            Floor::Opaque => Inner::Pass(pass::PreparedFloor::new(gpu, scene, pass::Kind::Opaque)),
            Floor::Blend => Inner::Blend(blend::PreparedBlend::new(gpu, scene, Attrs::ALL)),
            Floor::BlendConst => {
                Inner::Blend(blend::PreparedBlend::new(gpu, scene, Attrs::POSITION_ONLY))
            }
        })
    }
}

impl std::fmt::Display for Floor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A prepared floor: a [`Timed`] frame, and the blended image of the blend floors.
pub struct FloorFrame(Inner);

enum Inner {
    Pass(pass::PreparedFloor),
    Blend(blend::PreparedBlend),
}

impl FloorFrame {
    /// The blend floors' target after the last frame (RGBA8 read as premultiplied f32); the
    /// depth and opaque floors keep no image.
    pub fn image(&self, gpu: &Gpu) -> Result<Option<Vec<[f32; 4]>>> {
        match &self.0 {
            Inner::Pass(_) => Ok(None),
            Inner::Blend(b) => b.image(gpu).map(Some),
        }
    }

    fn timed(&mut self) -> &mut dyn Timed {
        match &mut self.0 {
            Inner::Pass(p) => p,
            Inner::Blend(b) => b,
        }
    }
}

impl Timed for FloorFrame {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        self.timed().frame(gpu, scene, timer)
    }
    fn bytes_allocated(&self) -> u64 {
        match &self.0 {
            Inner::Pass(p) => p.bytes_allocated(),
            Inner::Blend(b) => b.bytes_allocated(),
        }
    }
}
