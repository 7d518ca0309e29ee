//! The unordered-blend floors (LucidRaster's yardstick, Jakubowski 2024: exact OIT is reported
//! as a multiple of *unordered hardware blending*). One pass, both faces, every fragment blended
//! premultiplied-over into an RGBA8 target in primitive order, no depth test, no sort. Two of
//! them, differing only in what the vertex and fragment stages read:
//! - `floor_blend_const`: positions only (12 B a vertex) and one constant colour: the cheapest
//!   honest unordered blend of the scene's fragments, and what `x_blend` divides by. An
//!   independent wgpu probe of this shape agreed with `floor_depth` within 0.1 % on 1.1–1.6M
//!   triangle stacks (issue 33), where the old `floor_blend` took 1.06–1.81× as long.
//! - `floor_blend`: the methods' own vertex stage (`vs_full`: position, normal, colour, object
//!   id, 44 B a vertex in four streams) and each fragment's interpolated colour: what the
//!   methods read before they store a fragment, and no more. Until issue 33 it read position
//!   and colour (28 B, two streams) and was the `x_blend` yardstick; on geometry-bound scenes
//!   the extra vertex streams and varyings, not the blend, made it slower than the probe.
//!
//! Like the other floors they are yardsticks, not methods judged for error: the runner measures
//! them without reading them back. `readback` still returns the image (RGBA8 read as
//! premultiplied f32) so a test can check each is the unordered blend it claims.

use crate::axes::Point;

use super::super::{Capture, Expected, FrameStats, Method, Prepared};
use crate::gpu::{read_texture, Gpu};
use crate::gpu_scene::{AllocCounter, Attrs, GpuScene};
use crate::gpu_util::{camera_entry, shader};
use crate::timing::GpuTimer;
use crate::Result;

const WGSL: &str = include_str!("blend.wgsl");

/// `fs_const`'s colour, premultiplied (blend.wgsl).
pub const CONST_PREMUL: [f32; 4] = [0.25, 0.125, 0.0625, 0.25];

pub struct FloorBlend;
pub struct FloorBlendConst;

impl Method for FloorBlend {
    fn name(&self) -> &'static str {
        "floor_blend"
    }
    fn describe(&self) -> &'static str {
        "yardstick: the methods' vertex stage (position, normal, colour, object id) and every fragment's colour blended premultiplied-over into RGBA8 in primitive order, no depth test, no sort; not judged"
    }
    fn exact(&self) -> bool {
        false
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, _: &Point) -> Result<Box<dyn Prepared>> {
        Ok(Box::new(PreparedBlend::new(gpu, scene, Attrs::ALL)))
    }
}

impl Method for FloorBlendConst {
    fn name(&self) -> &'static str {
        "floor_blend_const"
    }
    fn describe(&self) -> &'static str {
        "yardstick of x_blend: positions only and one constant colour blended premultiplied-over into RGBA8, no depth test, no sort (the cheapest unordered blend); not judged"
    }
    fn exact(&self) -> bool {
        false
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, _: &Point) -> Result<Box<dyn Prepared>> {
        Ok(Box::new(PreparedBlend::new(
            gpu,
            scene,
            Attrs::POSITION_ONLY,
        )))
    }
}

struct PreparedBlend {
    attrs: Attrs,
    pipeline: wgpu::RenderPipeline,
    bind: wgpu::BindGroup,
    target: wgpu::Texture,
    view: wgpu::TextureView,
    alloc: AllocCounter,
}

impl PreparedBlend {
    /// `Attrs::ALL`: `vs_full` + `fs_blend`; `Attrs::POSITION_ONLY`: `vs_position` + `fs_const`.
    fn new(gpu: &Gpu, scene: &GpuScene, attrs: Attrs) -> Self {
        let constant = attrs == Attrs::POSITION_ONLY;
        let d = &gpu.device;
        let module = shader(gpu, "floor_blend", WGSL);
        let bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("floor_blend"),
            entries: &[camera_entry(0)],
        });
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("floor_blend"),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("floor_blend"),
            layout: &bgl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: scene.camera.as_entire_binding(),
            }],
        });
        let layouts: Vec<_> = GpuScene::layouts(attrs).into_iter().map(Some).collect();
        let targets = [Some(wgpu::ColorTargetState {
            format: wgpu::TextureFormat::Rgba8Unorm,
            blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("floor_blend"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some(if constant { "vs_position" } else { "vs_full" }),
                compilation_options: Default::default(),
                buffers: &layouts,
            },
            // Both faces, as every multi-fragment method sees them.
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(if constant { "fs_const" } else { "fs_blend" }),
                compilation_options: Default::default(),
                targets: &targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        let mut alloc = AllocCounter::default();
        let target = alloc.texture(
            gpu,
            "floor_blend colour",
            scene.width,
            scene.height,
            wgpu::TextureFormat::Rgba8Unorm,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let view = target.create_view(&Default::default());
        PreparedBlend {
            attrs,
            pipeline,
            bind,
            target,
            view,
            alloc,
        }
    }
}

impl crate::timed::Timed for PreparedBlend {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("floor_blend"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: timer.render_pass("floor"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind, &[]);
            scene.draw(&mut pass, self.attrs);
        }
        gpu.queue.submit([enc.finish()]);
        Ok(FrameStats {
            geometry_passes: 1,
            layers: 1,
        })
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }
}

impl Prepared for PreparedBlend {
    fn readback(&mut self, gpu: &Gpu, _: &GpuScene) -> Result<Capture> {
        let bytes = read_texture(gpu, &self.target, 4, wgpu::TextureAspect::All)?;
        let mut cap = Capture::empty();
        cap.image = Some(
            bytes
                .chunks_exact(4)
                .map(|p| [0, 1, 2, 3].map(|c| p[c] as f32 / 255.0))
                .collect(),
        );
        cap.expected = Expected::All;
        cap.notes = "floor: blended in primitive order, unsorted (a yardstick, not judged)".into();
        Ok(cap)
    }
}

#[cfg(test)]
mod tests {
    use scenarios::ParamValue::Int;

    use super::*;
    use crate::reference::{composite, rasterize, FragmentLists};
    use crate::testing::{gpu, scene};

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
        render_with(&FloorBlend, s, w, h)
    }

    fn render_with(
        method: &dyn Method,
        s: &scenarios::Scene,
        w: u32,
        h: u32,
    ) -> (Vec<[f32; 4]>, FragmentLists) {
        let g = gpu();
        let gs = GpuScene::upload(g, s, w, h);
        let mut m = crate::measure::measure(
            g,
            &gs,
            method,
            &Point::empty(),
            &crate::measure::TimingPlan::once(),
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
        let (img, lists) = render_with(&FloorBlendConst, &s, 64, 64);
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
