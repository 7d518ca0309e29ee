//! Studies: what a suite's `[[study]]` tables run. Each study kind turns its table into points
//! per scene × resolution group and runs a group on the GPU, emitting one row per point. The
//! runner adds the floor rows, the run metadata and `x_floor` to every group, so every study
//! is read against the same yardstick.
//!
//! | kind      | what it measures                                                     |
//! |-----------|----------------------------------------------------------------------|
//! | `methods` | multi-fragment capture methods vs the exact CPU reference            |
//! | `geometry`| geometry feeding (Bavoil ch. 3): batches, formats, layout, indices, order |
//! | `deferred`| deferred shading paths (naive, volumes, tiled, classified, CPU tiles) |
//! | `prepass` | light pre-pass vs deferred; light buffer on CPU cores, overlapped     |
//! | `stability` | stiff/extreme inputs: methods study + case, stiffness, lost fragments |
//! | `shadows` | layered soft shadow maps from an area light vs a ray-traced reference |

pub mod deferred;
pub mod geometry;
pub mod methods;
pub mod prepass;
pub mod shadows;
pub mod stability;

use std::cell::OnceCell;

use scenarios::{Params, Scene, SceneSpec, StudySpec, Suite};

use crate::gpu::Gpu;
use crate::gpu_scene::GpuScene;
use crate::record::cols;
use crate::record::Row;
use crate::reference::{rasterize, FragmentLists};
use crate::Result;

/// One point of a group: a method (or path/variant) name and its axis values.
#[derive(Clone, Debug)]
pub struct PointSpec {
    pub method: String,
    pub params: Params,
}

/// A scene at a resolution with the points to run on it: the unit of sharding.
#[derive(Clone, Debug)]
pub struct Group {
    pub study_index: usize,
    pub kind: String,
    pub scene: SceneSpec,
    pub width: u32,
    pub height: u32,
    pub points: Vec<PointSpec>,
}

impl Group {
    /// Stable identity of a point: study|scene|resolution|method|axes.
    pub fn point_key(&self, method: &str, params: &Params) -> String {
        format!(
            "{}|{}|{}x{}|{}|{}",
            self.kind,
            self.scene.label(),
            self.width,
            self.height,
            method,
            params.label()
        )
    }
}

/// Everything a study needs to run one group.
pub struct GroupCtx<'a> {
    pub gpu: &'a Gpu,
    pub suite: &'a Suite,
    pub study: &'a StudySpec,
    pub group: &'a Group,
    pub scene: &'a Scene,
    pub gscene: &'a GpuScene,
    pub reps: u32,
    pub warmup: u32,
    /// floor_depth median GPU ms of this group, when measured.
    pub floor_ms: Option<f64>,
    /// Where `save_image` writes point images (`mfx sweep --save-images`); none = not saved.
    pub images_dir: Option<std::path::PathBuf>,
    reference: OnceCell<FragmentLists>,
}

impl<'a> GroupCtx<'a> {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        gpu: &'a Gpu,
        suite: &'a Suite,
        study: &'a StudySpec,
        group: &'a Group,
        scene: &'a Scene,
        gscene: &'a GpuScene,
        reps: u32,
        warmup: u32,
    ) -> Self {
        GroupCtx {
            gpu,
            suite,
            study,
            group,
            scene,
            gscene,
            reps,
            warmup,
            floor_ms: None,
            images_dir: None,
            reference: OnceCell::new(),
        }
    }

    /// The exact fragment lists of this scene and resolution, computed once per group.
    pub fn reference(&self) -> &FragmentLists {
        self.reference
            .get_or_init(|| rasterize(self.scene, self.group.width, self.group.height))
    }

    pub fn has_reference(&self) -> bool {
        self.reference.get().is_some()
    }

    /// Saves a point's image when `--save-images` is on and records it in `image_file`, so the
    /// report can compare the same point across adapters and backends. The name hashes the
    /// point key, adapter and backend: runs from many machines merge into one `images/`.
    pub fn save_image(
        &self,
        row: &mut Row,
        method: &str,
        params: &Params,
        img: &[[f32; 4]],
    ) -> Result<()> {
        let Some(dir) = &self.images_dir else {
            return Ok(());
        };
        let f = &self.gpu.facts;
        let key = self.group.point_key(method, params);
        let name = format!(
            "images/{}.npy",
            crate::image_io::point_hash(&key, &f.name, &f.backend)
        );
        std::fs::create_dir_all(dir.join("images"))
            .map_err(|e| crate::CoreError::Io(format!("{}: {e}", dir.display())))?;
        crate::image_io::write_npy_rgba(
            &dir.join(&name),
            self.group.width,
            self.group.height,
            img,
        )?;
        row.set(cols::IMAGE_FILE, name);
        Ok(())
    }
}

/// Emits the row of point `index` of the group.
pub type Emit<'e> = dyn FnMut(usize, Row) -> Result<()> + 'e;

pub trait Study: Sync {
    fn kind(&self) -> &'static str;
    fn describe(&self) -> &'static str;
    /// The points to run on every scene × resolution of `spec`; unknown names are errors here,
    /// before any GPU work.
    fn points(&self, spec: &StudySpec) -> Result<Vec<PointSpec>>;
    /// Runs one group, emitting each point's row (ok, skipped or failed) with its index.
    fn run_group(&self, ctx: &GroupCtx<'_>, emit: &mut Emit<'_>) -> Result<()>;
}

pub fn all() -> Vec<Box<dyn Study>> {
    vec![
        Box::new(methods::MethodsStudy),
        Box::new(geometry::GeometryStudy),
        Box::new(deferred::DeferredStudy),
        Box::new(prepass::PrepassStudy),
        Box::new(stability::StabilityStudy),
        Box::new(shadows::ShadowsStudy),
    ]
}

pub fn by_kind(kind: &str) -> Option<Box<dyn Study>> {
    all().into_iter().find(|s| s.kind() == kind)
}
