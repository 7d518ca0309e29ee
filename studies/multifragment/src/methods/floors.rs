//! The harness's floors ([`bench_core::floors`]) as methods of this study, so a suite can list one
//! among its methods (`floor_depth_vs`, the old depth floor, is only that). The runner's own
//! floor rows do not go through here: it times the floors itself.

use bench_core::axes::Point;
use bench_core::floors::{Floor, FloorFrame};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::timing::GpuTimer;
use bench_core::Result;

use super::{Capture, Expected, FrameStats, Method, Prepared, Timed};

/// A floor listed as a method: never exact, no capture but the blend floors' image.
pub struct FloorMethod(pub Floor);

impl Method for FloorMethod {
    fn name(&self) -> &'static str {
        self.0.name()
    }
    fn describe(&self) -> &'static str {
        self.0.describe()
    }
    fn exact(&self) -> bool {
        false
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, _: &Point) -> Result<Box<dyn Prepared>> {
        Ok(Box::new(PreparedFloor(self.0.prepare(gpu, scene))))
    }
}

struct PreparedFloor(FloorFrame);

impl Timed for PreparedFloor {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        self.0.frame(gpu, scene, timer)
    }
    fn bytes_allocated(&self) -> u64 {
        self.0.bytes_allocated()
    }
}

impl Prepared for PreparedFloor {
    fn readback(&mut self, gpu: &Gpu, _: &GpuScene) -> Result<Capture> {
        let mut cap = Capture::empty();
        if let Some(image) = self.0.image(gpu)? {
            cap.image = Some(image);
            cap.expected = Expected::All;
            cap.notes =
                "floor: blended in primitive order, unsorted (a yardstick, not judged)".into();
        }
        Ok(cap)
    }
}

#[cfg(test)]
mod tests {
    use scenarios::ParamValue::Int;

    use super::*;
    use crate::testing::{gpu, scene};
    use bench_core::floors::CONST_PREMUL;
    use mfx_reference::{composite, rasterize, FragmentLists};

    /// What the blender computes: fragments in primitive order, premultiplied over, the target
    /// rounded to 8 bits after each blend.
    fn blend_in_primitive_order(lists: &FragmentLists) -> Vec<[f64; 4]> {
        let q = |v: f64| (v * 255.0).round() / 255.0;
        (0..lists.pixels())
            .map(|p| {
                let mut frags: Vec<_> = lists.pixel(p).to_vec();
                frags.sort_by_key(|f| f.prim);
                let mut acc = [0.0f64; 4];
                for f in &frags {
                    let a = q(f.color[3]);
                    for (c, fc) in acc.iter_mut().zip(&f.color).take(3) {
                        *c = q(q(fc * a) + *c * (1.0 - a));
                    }
                    acc[3] = q(a + acc[3] * (1.0 - a));
                }
                acc
            })
            .collect()
    }

    fn render(s: &scenarios::Scene, w: u32, h: u32) -> (Vec<[f32; 4]>, FragmentLists) {
        render_with(&FloorMethod(Floor::Blend), s, w, h)
    }

    fn render_with(
        method: &dyn Method,
        s: &scenarios::Scene,
        w: u32,
        h: u32,
    ) -> (Vec<[f32; 4]>, FragmentLists) {
        let g = gpu();
        let gs = GpuScene::upload(g, s, w, h);
        let mut m = crate::method::measure(
            g,
            &gs,
            method,
            &Point::empty(),
            &bench_core::measure::TimingPlan::once(),
        )
        .unwrap();
        let cap = m.prepared.readback(g, &gs).unwrap();
        (cap.image.unwrap(), rasterize(s, w, h))
    }

    fn max_diff(a: &[[f64; 4]], b: &[[f32; 4]]) -> f64 {
        a.iter()
            .zip(b)
            .flat_map(|(r, g)| (0..4).map(move |c| (r[c] - g[c] as f64).abs()))
            .fold(0.0, f64::max)
    }

    #[test]
    fn one_layer_48px_equals_the_reference_composite_to_8_bits() {
        let s = scene("quads", &[("depth_complexity", Int(1))]);
        let (img, lists) = render(&s, 48, 40);
        assert_eq!(lists.max_depth_complexity(), 1);
        let reference = lists.composite();
        // One blend into RGBA8: the source rounds to 8 bits (≤ 0.5/255) and the blender's own
        // fixed-point product may round once more.
        let e = max_diff(&reference, &img);
        assert!(e <= 1.0 / 255.0, "max error {e}");
    }

    #[test]
    fn many_layers_48px_blend_in_primitive_order_not_depth_order() {
        // quads' primitives run nearest first, so primitive order is front to back: "over" in
        // that order is the wrong composite, and it must be exactly that wrong one.
        let s = scene("quads", &[("depth_complexity", Int(5))]);
        let (img, lists) = render(&s, 48, 40);
        let dc = lists.max_depth_complexity() as f64;
        let ordered = blend_in_primitive_order(&lists);
        // One 8-bit rounding per blend that the blender may place differently from the twin.
        let e = max_diff(&ordered, &img);
        assert!(
            e <= dc / 255.0,
            "max error {e} vs the primitive-order blend"
        );
        let sorted: Vec<[f64; 4]> = (0..lists.pixels())
            .map(|p| composite(lists.pixel(p).iter()))
            .collect();
        let wrong = max_diff(&sorted, &img);
        assert!(
            wrong > 0.05,
            "unsorted blending differs from the sorted composite ({wrong})"
        );
    }

    /// n fragments of one premultiplied colour blended "over", the target rounded to 8 bits
    /// after each blend: the same in any order.
    fn constant_blend(n: usize) -> [f64; 4] {
        let q = |v: f64| (v * 255.0).round() / 255.0;
        let c = CONST_PREMUL.map(|x| q(x as f64));
        let mut acc = [0.0f64; 4];
        for _ in 0..n {
            for (a, s) in acc.iter_mut().zip(c) {
                *a = q(s + *a * (1.0 - c[3]));
            }
        }
        acc
    }

    #[test]
    fn constant_floor_64px_shells_is_the_unordered_blend_of_the_reference_fragment_count() {
        // shells: closed surfaces, both faces, 2–8 fragments a pixel; every pixel's image is a
        // function of its f64 fragment count alone (one colour), whatever the order.
        let s = scene("shells", &[("count", Int(4)), ("segments", Int(16))]);
        let (img, lists) = render_with(&FloorMethod(Floor::BlendConst), &s, 64, 64);
        let dc = lists.max_depth_complexity();
        assert!(dc >= 2, "a scene with overlap ({dc})");
        let expected: Vec<[f64; 4]> = (0..lists.pixels())
            .map(|p| constant_blend(lists.pixel(p).len()))
            .collect();
        // One 8-bit rounding per blend that the blender may place differently from the twin.
        let e = max_diff(&expected, &img);
        assert!(
            e <= dc as f64 / 255.0,
            "max error {e} (depth complexity {dc})"
        );
        // Empty pixels stay clear, covered ones are not: the count, not just coverage, matters.
        let twice = constant_blend(2)[3] - constant_blend(1)[3];
        assert!(twice > 2.0 / 255.0, "one more layer is visible ({twice})");
    }

    #[test]
    fn attribute_floor_64px_shells_blends_the_reference_fragments_in_primitive_order() {
        // The methods' vertex stage (every attribute) must not change what is blended.
        let s = scene("shells", &[("count", Int(4)), ("segments", Int(16))]);
        let (img, lists) = render(&s, 64, 64);
        let dc = lists.max_depth_complexity() as f64;
        let e = max_diff(&blend_in_primitive_order(&lists), &img);
        assert!(
            e <= dc / 255.0,
            "max error {e} vs the primitive-order blend"
        );
    }
}
