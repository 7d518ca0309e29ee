//! A scene uploaded once per sweep group: separate vertex buffers per attribute (so a pass can
//! bind only what it reads), a 32-bit index buffer and the camera uniform. Shared WGSL for the
//! standard vertex stage is in `methods/common.wgsl`.

use bytemuck::{Pod, Zeroable};
use scenarios::Scene;
use wgpu::util::DeviceExt;

use crate::gpu::Gpu;
use crate::Result;

/// Matches `struct Camera` in `methods/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct CameraUniform {
    pub clip_from_world: [[f32; 4]; 4],
    pub view_from_world: [[f32; 4]; 4],
    /// width, height, 1/width, 1/height
    pub viewport: [f32; 4],
    /// near, far, reversed_z (0|1), clear depth
    pub near_far: [f32; 4],
}

/// Which vertex attributes a pipeline reads (the rest are not bound: nothing fetches them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Attrs {
    pub normal: bool,
    pub color: bool,
    pub object_id: bool,
}

impl Attrs {
    pub const POSITION_ONLY: Attrs = Attrs {
        normal: false,
        color: false,
        object_id: false,
    };
    pub const ALL: Attrs = Attrs {
        normal: true,
        color: true,
        object_id: true,
    };
}

const POS: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![0 => Float32x3];
const NRM: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![1 => Float32x3];
const COL: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![2 => Float32x4];
const OID: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![3 => Uint32];

pub struct GpuScene {
    pub positions: wgpu::Buffer,
    pub normals: wgpu::Buffer,
    pub colors: wgpu::Buffer,
    pub object_ids: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub index_count: u32,
    pub camera: wgpu::Buffer,
    pub camera_data: CameraUniform,
    pub width: u32,
    pub height: u32,
    pub reversed_z: bool,
    /// Bytes of the buffers above (the scene's own cost, not charged to methods).
    pub bytes: u64,
}

impl GpuScene {
    pub fn upload(gpu: &Gpu, scene: &Scene, width: u32, height: u32) -> GpuScene {
        let d = &gpu.device;
        let vb = |label: &str, data: &[u8]| {
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: data,
                // COPY_DST: a test moves geometry under a prepared method (a dynamic scene).
                usage: wgpu::BufferUsages::VERTEX
                    | wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
            })
        };
        let m = &scene.mesh;
        let positions = vb("positions", bytemuck::cast_slice(&m.positions));
        let normals = vb("normals", bytemuck::cast_slice(&m.normals));
        let colors = vb("colors", bytemuck::cast_slice(&m.colors));
        let object_ids = vb("object_ids", bytemuck::cast_slice(&m.object_ids));
        let indices = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("indices"),
            contents: bytemuck::cast_slice(&m.indices),
            // COPY_SRC: kbuffer_rmw's heuristics read the indices back to sort triangles.
            usage: wgpu::BufferUsages::INDEX
                | wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC,
        });
        let camera_data = camera_uniform(scene, width, height);
        let camera = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("camera"),
            contents: bytemuck::bytes_of(&camera_data),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let bytes = [&positions, &normals, &colors, &object_ids, &indices]
            .iter()
            .map(|b| b.size())
            .sum();
        GpuScene {
            positions,
            normals,
            colors,
            object_ids,
            indices,
            index_count: m.indices.len() as u32,
            camera,
            camera_data,
            width,
            height,
            reversed_z: scene.camera.reversed_z,
            bytes,
        }
    }

    /// The same scene in new buffers (copied on the GPU), allocated after whatever is alive now:
    /// a `[timing] sessions` session measures a method on geometry that lies elsewhere in memory.
    pub fn relocated(&self, gpu: &Gpu) -> Result<GpuScene> {
        let d = &gpu.device;
        let mut enc = d.create_command_encoder(&Default::default());
        // The copy keeps the source's usages, plus COPY_DST to be filled here (the index buffer
        // has none) and COPY_SRC to be read.
        let mut copy = |b: &wgpu::Buffer, label: &str| {
            let n = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: b.size(),
                usage: b.usage() | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            enc.copy_buffer_to_buffer(b, 0, &n, 0, b.size());
            n
        };
        let positions = copy(&self.positions, "positions");
        let normals = copy(&self.normals, "normals");
        let colors = copy(&self.colors, "colors");
        let object_ids = copy(&self.object_ids, "object_ids");
        let indices = copy(&self.indices, "indices");
        gpu.queue.submit([enc.finish()]);
        let camera = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("camera"),
            contents: bytemuck::bytes_of(&self.camera_data),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        gpu.wait()?;
        Ok(GpuScene {
            positions,
            normals,
            colors,
            object_ids,
            indices,
            camera,
            ..*self
        })
    }

    pub fn pixels(&self) -> usize {
        (self.width * self.height) as usize
    }

    /// The same scene (vertex and index buffers shared) seen at `width`×`height` with the same
    /// aspect: its own camera uniform, whose viewport is the new size (the projection depends on
    /// the aspect only, so it is unchanged). Supersampling renders into one of these.
    pub fn at_resolution(&self, gpu: &Gpu, width: u32, height: u32) -> GpuScene {
        assert_eq!(
            width as u64 * self.height as u64,
            height as u64 * self.width as u64,
            "at_resolution keeps the aspect"
        );
        let mut camera_data = self.camera_data;
        camera_data.viewport = [
            width as f32,
            height as f32,
            1.0 / width as f32,
            1.0 / height as f32,
        ];
        self.sharing_buffers(
            gpu,
            "camera (resized)",
            camera_data,
            (width, height),
            self.reversed_z,
        )
    }

    /// The same scene (vertex and index buffers shared) seen by `cam`: its own camera uniform.
    /// A camera path renders each view through one of these, every method prepared on it.
    pub fn with_camera(&self, gpu: &Gpu, cam: &scenarios::Camera) -> GpuScene {
        let camera_data = camera_uniform_of(cam, self.width, self.height);
        self.sharing_buffers(
            gpu,
            "camera (view)",
            camera_data,
            (self.width, self.height),
            cam.reversed_z,
        )
    }

    /// This scene's vertex and index buffers with a camera uniform of its own.
    fn sharing_buffers(
        &self,
        gpu: &Gpu,
        label: &str,
        camera_data: CameraUniform,
        (width, height): (u32, u32),
        reversed_z: bool,
    ) -> GpuScene {
        let camera = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::bytes_of(&camera_data),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            });
        GpuScene {
            positions: self.positions.clone(),
            normals: self.normals.clone(),
            colors: self.colors.clone(),
            object_ids: self.object_ids.clone(),
            indices: self.indices.clone(),
            index_count: self.index_count,
            camera,
            camera_data,
            width,
            height,
            reversed_z,
            bytes: self.bytes,
        }
    }

    /// Vertex buffer layouts for the attributes `a` (slot order: position, then the enabled ones).
    pub fn layouts(a: Attrs) -> Vec<wgpu::VertexBufferLayout<'static>> {
        let mut v = vec![wgpu::VertexBufferLayout {
            array_stride: 12,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &POS,
        }];
        if a.normal {
            v.push(wgpu::VertexBufferLayout {
                array_stride: 12,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &NRM,
            });
        }
        if a.color {
            v.push(wgpu::VertexBufferLayout {
                array_stride: 16,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &COL,
            });
        }
        if a.object_id {
            v.push(wgpu::VertexBufferLayout {
                array_stride: 4,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &OID,
            });
        }
        v
    }

    /// Binds the attributes `a` in the slot order of [`Self::layouts`] and draws every triangle.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, a: Attrs) {
        let mut slot = 0;
        pass.set_vertex_buffer(slot, self.positions.slice(..));
        for (on, buf) in [
            (a.normal, &self.normals),
            (a.color, &self.colors),
            (a.object_id, &self.object_ids),
        ] {
            if on {
                slot += 1;
                pass.set_vertex_buffer(slot, buf.slice(..));
            }
        }
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }
}

pub fn camera_uniform(scene: &Scene, width: u32, height: u32) -> CameraUniform {
    camera_uniform_of(&scene.camera, width, height)
}

/// The uniform of `cam` at width × height.
pub fn camera_uniform_of(cam: &scenarios::Camera, width: u32, height: u32) -> CameraUniform {
    let aspect = width as f64 / height as f64;
    CameraUniform {
        clip_from_world: cam.clip_from_world_gpu(aspect).to_cols_array_2d(),
        view_from_world: cam.view().as_mat4().to_cols_array_2d(),
        viewport: [
            width as f32,
            height as f32,
            1.0 / width as f32,
            1.0 / height as f32,
        ],
        near_far: [
            cam.near as f32,
            cam.far as f32,
            if cam.reversed_z { 1.0 } else { 0.0 },
            cam.clear_depth(),
        ],
    }
}

/// Adds up the bytes a method allocates, so every row can report its memory.
#[derive(Default, Debug, Clone, Copy)]
pub struct AllocCounter {
    pub bytes: u64,
}

impl AllocCounter {
    pub fn buffer(
        &mut self,
        gpu: &Gpu,
        label: &str,
        size: u64,
        usage: wgpu::BufferUsages,
    ) -> wgpu::Buffer {
        self.bytes += size;
        gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage,
            mapped_at_creation: false,
        })
    }

    pub fn texture(
        &mut self,
        gpu: &Gpu,
        label: &str,
        w: u32,
        h: u32,
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
    ) -> wgpu::Texture {
        self.texture_ms(gpu, label, w, h, format, usage, 1)
    }

    /// A texture of `samples` samples per texel (MSAA), counted as `samples` texels' bytes.
    #[allow(
        clippy::too_many_arguments,
        reason = "a texture's label, size, format, usage and samples, as wgpu's descriptor has them"
    )]
    pub fn texture_ms(
        &mut self,
        gpu: &Gpu,
        label: &str,
        w: u32,
        h: u32,
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
        samples: u32,
    ) -> wgpu::Texture {
        let bpp = format.block_copy_size(None).unwrap_or(4) as u64;
        self.bytes += w as u64 * h as u64 * bpp * samples as u64;
        gpu.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: samples,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    }
}
