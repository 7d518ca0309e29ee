//! What a study is: what a suite's `[[study]]` tables run. Each study kind turns its table into
//! points per scene × resolution group and runs a group on the GPU, emitting one row per point.
//! The runner adds the floor rows, the run metadata and `x_floor` to every group, so every study
//! is read against the same yardstick. The harness names no study: the study crates implement
//! [`Study`], and the binary holds their table (`mfx::STUDIES`), which the runner and `check`
//! are given.

use scenarios::suite::{axes_for_method, axis_product};
use scenarios::{ParamValue, Params, Scene, SceneSpec, StudySpec, Suite, ValueKind};
pub use schema::StudyKind;

use crate::axes::{Axis, Point};
use crate::gpu::Gpu;
use crate::gpu_scene::GpuScene;
use crate::measure::TimingPlan;
use crate::record::cols;
use crate::record::Row;
use crate::Result;

/// One point of a group: a method (or path) name and its axis values, resolved against the
/// axes that method declares in this study.
#[derive(Clone, Debug)]
pub struct PointSpec {
    pub method: String,
    pub point: Point,
}

impl PointSpec {
    /// The values the suite gave (the point's identity).
    pub fn given(&self) -> &Params {
        self.point.given()
    }
}

/// A scene at a resolution with the points to run on it: the unit of sharding.
#[derive(Clone, Debug)]
pub struct Group {
    pub study_index: usize,
    pub kind: StudyKind,
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
    /// How every point of the group is timed (the suite's `[timing]`).
    pub plan: TimingPlan,
    /// Compute FLIP for image rows.
    pub flip: bool,
    /// floor_depth median GPU ms of this group, when measured.
    pub floor_ms: Option<f64>,
    /// floor_blend_const median GPU ms of this group, when measured (the `x_blend` yardstick).
    pub blend_ms: Option<f64>,
    /// Where `save_image` writes point images (`mfx sweep --save-images`); none = not saved.
    pub images_dir: Option<std::path::PathBuf>,
}

impl<'a> GroupCtx<'a> {
    pub fn new(
        gpu: &'a Gpu,
        suite: &'a Suite,
        study: &'a StudySpec,
        group: &'a Group,
        scene: &'a Scene,
        gscene: &'a GpuScene,
        plan: TimingPlan,
    ) -> Self {
        GroupCtx {
            gpu,
            suite,
            study,
            group,
            scene,
            gscene,
            plan,
            flip: true,
            floor_ms: None,
            blend_ms: None,
            images_dir: None,
        }
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

/// What a study's `methods` list may hold.
pub enum Methods {
    /// A list is required; these are the names it may hold.
    List(Vec<&'static str>),
    /// The study takes no list: every point runs this one (its `method` column).
    Implicit(&'static str),
}

/// A declared key of a study table besides the common ones (`kind`, `methods`, `axes`, …):
/// an option of the whole study, not a sweep axis.
#[derive(Clone, Copy, Debug)]
pub struct Opt {
    pub name: &'static str,
    pub doc: &'static str,
    pub kind: ValueKind,
}

impl Opt {
    /// The option's value in `spec` (checked by `check`), or its default.
    pub fn value(&self, spec: &StudySpec) -> Option<ParamValue> {
        match spec.extra.get(self.name).and_then(ParamValue::from_toml) {
            Some(v) => self.kind.check(&v).ok(),
            None => self.kind.default_value(),
        }
    }
    pub fn int(&self, spec: &StudySpec) -> i64 {
        match self.value(spec) {
            Some(ParamValue::Int(i)) => i,
            _ => 0,
        }
    }
    pub fn bool(&self, spec: &StudySpec) -> bool {
        matches!(self.value(spec), Some(ParamValue::Bool(true)))
    }
    pub fn text(&self, spec: &StudySpec) -> String {
        match self.value(spec) {
            Some(ParamValue::Str(s)) => s,
            _ => String::new(),
        }
    }
}

/// Why a point as a suite gives it cannot run: a bad suite, named before any GPU work (exit 2).
/// A study's `validate` and its methods' configuration readers return it; the harness reports it
/// with the method and the point's values.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum InvalidPoint {
    /// One axis's value that this point cannot take, though the axis's declared range admits it.
    #[error("{axis} = {value} {rule}")]
    Value {
        axis: String,
        value: String,
        rule: String,
    },
    /// Values of several axes (or an effect and a method) that cannot go together.
    #[error("{0}")]
    Combination(String),
    /// A method the study does not have.
    #[error("unknown method '{0}'")]
    UnknownMethod(String),
}

impl InvalidPoint {
    /// `axis = value rule`, e.g. `hist_bins = 33 must be a multiple of 32`.
    pub fn value(
        axis: impl Into<String>,
        value: impl std::fmt::Display,
        rule: impl Into<String>,
    ) -> InvalidPoint {
        InvalidPoint::Value {
            axis: axis.into(),
            value: value.to_string(),
            rule: rule.into(),
        }
    }
    pub fn combination(why: impl Into<String>) -> InvalidPoint {
        InvalidPoint::Combination(why.into())
    }
}

/// A point a method cannot configure is a point it cannot run: where a configuration is read
/// again at prepare or `supports` time, its problem is the skip's reason, word for word.
impl From<InvalidPoint> for crate::Unsupported {
    fn from(e: InvalidPoint) -> crate::Unsupported {
        crate::Unsupported::new(e.to_string())
    }
}

impl From<InvalidPoint> for crate::CoreError {
    fn from(e: InvalidPoint) -> crate::CoreError {
        crate::CoreError::Param(e.to_string())
    }
}

pub trait Study: Sync {
    /// The kind a suite's `[[study]]` names and its rows' `study` cell.
    fn kind(&self) -> StudyKind;
    fn describe(&self) -> &'static str;
    /// What `methods = [...]` may name, or the implicit method of a study that takes no list.
    fn methods(&self) -> Methods;
    /// The axes a point of `method` reads, declared (type, default, range): the suite's values
    /// are checked against them and its product is taken over them.
    fn axes(&self, method: &str) -> Vec<Axis>;
    /// Rules across axes of one point that the declarations cannot say (before any GPU work).
    fn validate(&self, method: &str, point: &Point) -> std::result::Result<(), InvalidPoint> {
        let _ = (method, point);
        Ok(())
    }
    /// The study table's own options, declared.
    fn options(&self) -> Vec<Opt> {
        Vec::new()
    }
    /// Whether the study renders its scenes' camera paths (`camera_path`, `scenarios::path`);
    /// elsewhere a path is a problem `mfx check` names (it would run at one view).
    fn moves_camera(&self) -> bool {
        false
    }
    /// Problems of a study table that its declarations cannot say (one message each).
    fn check_table(&self, spec: &StudySpec) -> Vec<String> {
        let _ = spec;
        Vec::new()
    }
    /// Runs one group, emitting each point's row (ok, skipped or failed) with its index.
    fn run_group(&self, ctx: &GroupCtx<'_>, emit: &mut Emit<'_>) -> Result<()>;
}

/// The methods a study table runs: its list, or the study's implicit one.
pub fn methods_of(study: &dyn Study, spec: &StudySpec) -> Vec<String> {
    match study.methods() {
        Methods::List(_) => spec.methods.clone(),
        Methods::Implicit(m) => vec![m.to_string()],
    }
}

/// The points of a study table: per method, the product of the table's axes that the method
/// declares, each resolved (defaults filled) and validated. `Err` lists every problem; `check`
/// reports them with their place in the file before this is called for a sweep.
pub fn points(
    study: &dyn Study,
    spec: &StudySpec,
) -> std::result::Result<Vec<PointSpec>, Vec<String>> {
    let mut out = Vec::new();
    let mut problems = Vec::new();
    for method in methods_of(study, spec) {
        let declared = study.axes(&method);
        let names: Vec<&str> = declared.iter().map(|a| a.name()).collect();
        let table = axes_for_method(spec, &method);
        for given in axis_product(&table, &names) {
            match Point::resolve(&declared, &given) {
                Ok(point) => {
                    if let Err(why) = study.validate(&method, &point) {
                        problems.push(format!("{method} at {}: {why}", given.label()));
                        continue;
                    }
                    // Values of an axis this point leaves unread are dropped from it, so points
                    // that differed only there are one configuration: run once.
                    if out
                        .iter()
                        .any(|o: &PointSpec| o.method == method && o.point.given() == point.given())
                    {
                        continue;
                    }
                    out.push(PointSpec {
                        method: method.clone(),
                        point,
                    });
                }
                Err(e) => problems.extend(e.into_iter().map(|m| format!("{method}: {m}"))),
            }
        }
    }
    if problems.is_empty() {
        Ok(out)
    } else {
        Err(problems)
    }
}

/// The study of `kind` among `studies` (the binary's `STUDIES` table, or a test's own list).
pub fn by_kind<'s>(studies: &[&'s dyn Study], kind: StudyKind) -> Option<&'s dyn Study> {
    studies.iter().copied().find(|s| s.kind() == kind)
}
