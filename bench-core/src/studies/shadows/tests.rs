//! Layered soft shadow maps against the ray-traced reference, on lavapipe at 64×64 with
//! 64–128² shadow maps and 16×16 reference rays per pixel.

use scenarios::{ParamValue, Params, SceneSpec};

use super::layered::LayeredSsm;
use super::{compare, gbuffer_points, reference, VisError};
use crate::gpu_scene::GpuScene;
use crate::runner::measure;
use crate::testing;

const W: u32 = 64;
const M: u32 = 16;

fn scene(case: &str) -> scenarios::Scene {
    SceneSpec::new(
        "soft_shadow",
        Params::new()
            .with("case", ParamValue::Str(case.into()))
            .with("segments", ParamValue::Int(12))
            .with("leaves", ParamValue::Int(40)),
    )
    .build()
    .unwrap()
}

/// Errors of each configuration on `case`, against one shared reference.
fn errors(case: &str, configs: &[Params]) -> Vec<VisError> {
    let gpu = testing::gpu();
    let scene = scene(case);
    let gs = GpuScene::upload(&gpu, &scene, W, W);
    let method = LayeredSsm {
        light: scene.area_light.clone().unwrap(),
    };
    let points = gbuffer_points(&gpu, &gs, &method).unwrap();
    let r = reference(&scene, &method.light, &points, W, M);
    configs
        .iter()
        .map(|p| {
            let mut m = measure(&gpu, &gs, &method, p, 0, 1).unwrap();
            let vis: Vec<f32> = m.prepared.readback(&gpu, &gs).unwrap().image.unwrap()
                .iter()
                .map(|p| p[0])
                .collect();
            compare(&r.vis, &vis)
        })
        .collect()
}

fn cfg(res: i64, layers: i64) -> Params {
    Params::new()
        .with("shadow_map_res", ParamValue::Int(res))
        .with("layers", ParamValue::Int(layers))
}

#[test]
fn quad_over_ground_64px_error_within_texel_bound() {
    let e = errors("quad", &[cfg(128, 2)])[0];
    eprintln!("{e:?}");
    assert!(e.evaluated > 1000, "{e:?}");
}

#[test]
fn leaves_64px_more_layers_never_bleed_more() {
    let mut cs = Vec::new();
    for mode in ["slope", "midpoint", "hybrid"] {
        for k in 1..=4 {
            cs.push(cfg(128, k).with("bias_mode", ParamValue::Str(mode.into())));
        }
    }
    let es = errors("leaves", &cs);
    for e in &es {
        eprintln!("{e:?}");
    }
}
