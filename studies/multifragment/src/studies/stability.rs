//! The `stability` study (issue 5): stiff and extreme inputs, per method, judged against the
//! f64 reference. It is the `methods` study (same points, same judging, same columns: one code
//! path decides what "right" means) plus three columns that say which case a row belongs to
//! and how stiff its input is, so a plot can draw error against stiffness per method:
//!
//! ```toml
//! [[study]]
//! kind = "stability"
//! case = "near_far"            # the case's name (→ stability_case)
//! stiffness = "far_over_near"  # how stiffness_value is computed (see `stiffness_value`)
//! methods = ["depth_peel"]
//! ```
//!
//! Why a study of its own rather than `methods` points with extra parameters: the case name and
//! stiffness are properties of the scene × method pair, not sweep axes of a method, and keeping
//! them out of `point_key`'s axes keeps the methods study's points comparable across suites.

use scenarios::{ParamValue, StudySpec};

use super::methods::{run_methods_group, GroupTruth, MethodsStudy};
use crate::effects;
use bench_core::axes::{Axis, Point};
use bench_core::record::cols;
use bench_core::record::Row;
use bench_core::study::InvalidPoint;
use bench_core::study::{Emit, GroupCtx, Methods, Opt, PointSpec, Study, StudyKind};
use bench_core::Result;
/// Computed stiffness measures; any other name is read from the scene's or the point's params.
pub const STIFFNESS: &[&str] = &[
    "far_over_near",
    "sigma_l",
    "distance_over_wall",
    "depth_gap_min",
    "depth_complexity",
];

pub struct StabilityStudy;

const CASE: Opt = Opt {
    name: "case",
    doc: "the stiff case's name (→ stability_case)",
    kind: scenarios::ValueKind::Text { default: None },
};
const STIFFNESS_OPT: Opt = Opt {
    name: "stiffness",
    doc: "how stiffness_value is computed: one of STIFFNESS, or a scene/axis parameter name",
    kind: scenarios::ValueKind::Text { default: None },
};

fn as_f64(v: &ParamValue) -> Option<f64> {
    match v {
        ParamValue::Int(i) => Some(*i as f64),
        ParamValue::Float(x) => Some(*x),
        ParamValue::Bool(b) => Some(*b as u8 as f64),
        ParamValue::Str(_) => None,
    }
}

/// The value of stiffness measure `name` for point `pt` of the group.
pub fn stiffness_value(
    ctx: &GroupCtx<'_>,
    truth: &GroupTruth<'_>,
    pt: &PointSpec,
    name: &str,
) -> Option<f64> {
    let cam = &ctx.scene.camera;
    match name {
        "far_over_near" => Some(cam.far / cam.near),
        "sigma_l" => {
            let sigma = pt.point.get(effects::SIGMA.name()).and_then(as_f64)?;
            let lists = truth.lists();
            let lmax = (0..lists.pixels())
                .map(|p| {
                    lists
                        .pixel(p)
                        .iter()
                        .map(crate::effects::signed_view_z)
                        .sum::<f64>()
                })
                .fold(0.0, f64::max);
            Some(sigma * lmax)
        }
        "distance_over_wall" => {
            let p = &ctx.group.scene.params;
            Some(as_f64(p.get("distance")?)? / as_f64(p.get("wall")?)?)
        }
        "depth_gap_min" => {
            let lists = truth.lists();
            (0..lists.pixels())
                .flat_map(|p| {
                    lists
                        .pixel(p)
                        .windows(2)
                        .map(|w| (w[1].depth - w[0].depth).abs())
                })
                .filter(|g| *g > 0.0)
                .min_by(f64::total_cmp)
        }
        "depth_complexity" => Some(truth.lists().max_depth_complexity() as f64),
        other => ctx
            .group
            .scene
            .params
            .get(other)
            .or_else(|| pt.point.get(other))
            .and_then(as_f64),
    }
}

impl Study for StabilityStudy {
    fn kind(&self) -> StudyKind {
        StudyKind::Stability
    }
    fn describe(&self) -> &'static str {
        "stiff and extreme inputs: finite output, error vs the f64 reference and a flag per method, against a stiffness parameter"
    }
    fn methods(&self) -> Methods {
        MethodsStudy.methods()
    }
    fn axes(&self, method: &str) -> Vec<Axis> {
        MethodsStudy.axes(method)
    }
    fn validate(&self, method: &str, point: &Point) -> std::result::Result<(), InvalidPoint> {
        MethodsStudy.validate(method, point)
    }
    fn options(&self) -> Vec<Opt> {
        vec![CASE, STIFFNESS_OPT]
    }
    fn check_table(&self, spec: &StudySpec) -> Vec<String> {
        let mut out = Vec::new();
        for o in [CASE, STIFFNESS_OPT] {
            if !spec.extra.contains_key(o.name) {
                out.push(format!(
                    "missing '{}' (e.g. case = \"near_far\", stiffness = \"far_over_near\")",
                    o.name
                ));
            }
        }
        // A parameter name is accepted only if some scene or axis defines it: a typo is an error.
        let s = STIFFNESS_OPT.text(spec);
        let defined = STIFFNESS.contains(&s.as_str())
            || spec.axes.contains_key(&s)
            || spec.scenes.iter().any(|sc| sc.params.get(&s).is_some());
        if !s.is_empty() && !defined {
            out.push(format!(
                "stiffness '{s}' is neither one of {} nor a scene or axis parameter",
                STIFFNESS.join(", ")
            ));
        }
        out
    }
    fn run_group(&self, ctx: &GroupCtx<'_>, emit: &mut Emit<'_>) -> Result<()> {
        let case = CASE.text(ctx.study);
        let stiffness = STIFFNESS_OPT.text(ctx.study);
        let add = |row: &mut Row, pt: &PointSpec, truth: &GroupTruth<'_>| {
            row.set(cols::STABILITY_CASE, &case)
                .set(cols::STIFFNESS, &stiffness);
            if let Some(v) = stiffness_value(ctx, truth, pt, &stiffness) {
                row.set_f(cols::STIFFNESS_VALUE, v);
            }
        };
        run_methods_group(ctx, emit, &add)
    }
}
