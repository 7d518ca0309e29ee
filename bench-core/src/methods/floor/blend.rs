//! `floor_blend`: the unsorted-blending floor (LucidRaster's yardstick, Jakubowski 2024: exact
//! OIT is reported as a multiple of *unordered hardware blending*). One pass, both faces, every
//! fragment blended premultiplied-over into an RGBA8 target in primitive order, no depth test,
//! no sort. Like the other floors it is a yardstick, not a method judged for error: the runner
//! measures floors without reading them back. `readback` still returns its image (RGBA8 read as
//! premultiplied f32) so a test can check it blends in primitive order; a study that judged it
//! would find it wrong wherever primitive order is not back to front, which is the point.

use crate::axes::Point;

use super::super::{Capture, Expected, FrameStats, Method, Prepared};
use crate::gpu::{read_texture, Gpu};
use crate::gpu_scene::{AllocCounter, Attrs, GpuScene};
use crate::gpu_util::{camera_entry, shader};
use crate::timing::GpuTimer;
use crate::Result;

const WGSL: &str = include_str!("blend.wgsl");
/// Position and colour: what a forward transparent pass reads at least.
const ATTRS: Attrs = Attrs {
    normal: false,
    color: true,
    object_id: false,
};

pub struct FloorBlend;

impl Method for FloorBlend {
    fn name(&self) -> &'static str {
        "floor_blend"
    }
    fn describe(&self) -> &'static str {
        "yardstick: every fragment alpha-blended (premultiplied over) into RGBA8 in primitive order, no depth test, no sort (an engine without OIT); not judged"
    }
    fn exact(&self) -> bool {
        false
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, _: &Point) -> Result<Box<dyn Prepared>> {
        Ok(Box::new(PreparedBlend::new(gpu, scene)))
    }
}

struct PreparedBlend {
    pipeline: wgpu::RenderPipeline,
    bind: wgpu::BindGroup,
    target: wgpu::Texture,
    view: wgpu::TextureView,
    alloc: AllocCounter,
}

impl PreparedBlend {
    fn new(gpu: &Gpu, scene: &GpuScene) -> Self {
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
        let layouts: Vec<_> = GpuScene::layouts(ATTRS).into_iter().map(Some).collect();
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
                entry_point: Some("vs_blend"),
                compilation_options: Default::default(),
                buffers: &layouts,
            },
            // Both faces, as every multi-fragment method sees them.
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_blend"),
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
            scene.draw(&mut pass, ATTRS);
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
        let g = gpu();
        let gs = GpuScene::upload(g, s, w, h);
        let mut m = crate::measure::measure(
            g,
            &gs,
            &FloorBlend,
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
}
