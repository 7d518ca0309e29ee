//! Where a render target's memory comes from: wgpu's pool, or an allocation of its own.
//!
//! wgpu (30) sub-allocates every texture from 128–256 MiB blocks shared with other resources
//! (`gpu-allocator`, `GpuAllocatorManaged`). Vulkan's dedicated allocations exist because
//! memory that may be aliased or sparsely bound can stand in the way of framebuffer compression
//! and efficient page tables (VK_NV_dedicated_allocation's rationale, which names render
//! targets). With [`TextureMemory::Dedicated`] every 2-D
//! render target gets a `VkDeviceMemory` of its own, made with `VkMemoryDedicatedAllocateInfo`.
//!
//! Measured on the H200 (`results/reference/2026-12-02-h200-floors`): dedicated targets did not
//! move the depth-only floor's history-dependent time (1.043 ms in `methods`, 1.466 ms in a
//! shorter suite, pooled or dedicated alike), and two back-to-back `methods` runs agreed worse
//! with them (SAME 175 of 220 against 207–208 pooled: the second run's k-buffers 4–18 % slower, as
//! if fresh allocations landed on worse memory after the first run). So the default stays
//! wgpu's pool; `dedicated` is kept to repeat that comparison on other GPUs.

use ash::vk;
use wgpu::hal;

/// The `texture_memory` a run uses (`mfx sweep --texture-memory`), recorded on every row.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TextureMemory {
    /// wgpu's sub-allocated pool for every texture.
    Pooled,
    /// 2-D render targets (single level and layer) in dedicated allocations (Vulkan only; other
    /// backends fall back to the pool and record `pooled`).
    Dedicated,
}

impl TextureMemory {
    pub fn as_str(self) -> &'static str {
        match self {
            TextureMemory::Pooled => "pooled",
            TextureMemory::Dedicated => "dedicated",
        }
    }
}

impl std::str::FromStr for TextureMemory {
    type Err = crate::UnknownWord;
    fn from_str(s: &str) -> std::result::Result<Self, crate::UnknownWord> {
        match s.to_ascii_lowercase().as_str() {
            "pooled" | "pool" => Ok(TextureMemory::Pooled),
            "dedicated" => Ok(TextureMemory::Dedicated),
            other => Err(crate::UnknownWord {
                what: "texture memory",
                text: other.to_string(),
                known: "pooled, dedicated".into(),
            }),
        }
    }
}

impl std::fmt::Display for TextureMemory {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Whether `desc` takes the dedicated path: a plain 2-D render target (the textures whose
/// compression the pool can cost), without view formats, one level and one layer.
fn dedicated_candidate(desc: &wgpu::TextureDescriptor) -> bool {
    desc.usage.contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
        && desc.dimension == wgpu::TextureDimension::D2
        && desc.size.depth_or_array_layers == 1
        && desc.mip_level_count == 1
        && desc.view_formats.is_empty()
        && !desc.format.is_multi_planar_format()
}

/// The hal usage wgpu-core gives a texture of `desc` (its `map_texture_usage_for_texture`), so
/// the Vulkan image carries exactly the usage bits wgpu will use it with.
fn hal_usage(adapter: &wgpu::Adapter, desc: &wgpu::TextureDescriptor) -> wgpu::wgt::TextureUses {
    use wgpu::{wgt::TextureUses as U, TextureUsages as T};
    let flags = adapter.get_texture_format_features(desc.format).flags;
    let mut u = U::empty();
    u.set(U::COPY_SRC, desc.usage.contains(T::COPY_SRC));
    u.set(U::COPY_DST, desc.usage.contains(T::COPY_DST));
    u.set(U::RESOURCE, desc.usage.contains(T::TEXTURE_BINDING));
    if desc.usage.contains(T::STORAGE_BINDING) {
        use wgpu::TextureFormatFeatureFlags as F;
        u.set(U::STORAGE_READ_ONLY, flags.contains(F::STORAGE_READ_ONLY));
        u.set(U::STORAGE_WRITE_ONLY, flags.contains(F::STORAGE_WRITE_ONLY));
        u.set(U::STORAGE_READ_WRITE, flags.contains(F::STORAGE_READ_WRITE));
    }
    if desc.format.is_depth_stencil_format() {
        u |= U::DEPTH_STENCIL_READ | U::DEPTH_STENCIL_WRITE;
    } else {
        u |= U::COLOR_TARGET;
    }
    u
}

/// A texture for `desc` in a dedicated allocation, zeroed once as wgpu would have initialised
/// it (so a method sees the same contents either way); `None` when the texture does not qualify,
/// the device is not Vulkan, or the allocation failed (logged): the caller takes the pool.
pub fn dedicated_texture(
    adapter: &wgpu::Adapter,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    desc: &wgpu::TextureDescriptor,
) -> Option<wgpu::Texture> {
    if !dedicated_candidate(desc) {
        return None;
    }
    match dedicated(adapter, device, desc) {
        Ok(Some(t)) => {
            clear_once(device, queue, &t);
            Some(t)
        }
        Ok(None) => None,
        Err(e) => {
            log::warn!(
                "dedicated allocation for '{}' failed ({e}); taken from the pool",
                desc.label.unwrap_or("texture")
            );
            None
        }
    }
}

/// Why a dedicated allocation failed (the texture is then taken from the pool).
#[derive(Debug, thiserror::Error)]
enum DedicatedError {
    #[error("vkCreateImage: {0}")]
    CreateImage(vk::Result),
    #[error("no device-local memory type for the image")]
    NoDeviceLocalMemory,
    #[error("vkAllocateMemory: {0}")]
    Allocate(vk::Result),
    #[error("vkBindImageMemory: {0}")]
    Bind(vk::Result),
}

/// Creates the Vulkan image, its own memory and the wgpu texture over them; `None` when the
/// device is not Vulkan.
fn dedicated(
    adapter: &wgpu::Adapter,
    device: &wgpu::Device,
    desc: &wgpu::TextureDescriptor,
) -> std::result::Result<Option<wgpu::Texture>, DedicatedError> {
    // SAFETY: the raw device is used only to create, bind and hand over one image and its
    // memory; wgpu owns both afterwards (TextureMemory::Dedicated is freed with the texture).
    let Some(dev) = (unsafe { device.as_hal::<hal::api::Vulkan>() }) else {
        return Ok(None);
    };
    let raw = dev.raw_device();
    let instance = dev.shared_instance().raw_instance();
    // SAFETY: read-only use of the adapter's format table.
    let format = match unsafe { adapter.as_hal::<hal::api::Vulkan>() } {
        Some(a) => a.texture_format_as_raw(desc.format),
        None => return Ok(None),
    };
    let usage = hal_usage(adapter, desc);
    let info = vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(vk::Extent3D {
            width: desc.size.width,
            height: desc.size.height,
            depth: 1,
        })
        .mip_levels(1)
        .array_layers(1)
        .samples(vk::SampleCountFlags::from_raw(desc.sample_count))
        .tiling(vk::ImageTiling::OPTIMAL)
        .usage(hal::vulkan::conv::map_texture_usage(usage))
        .sharing_mode(vk::SharingMode::EXCLUSIVE)
        .initial_layout(vk::ImageLayout::UNDEFINED);
    // SAFETY: a valid create info on this device.
    let image = unsafe { raw.create_image(&info, None) }.map_err(DedicatedError::CreateImage)?;
    let mut dedicated_req = vk::MemoryDedicatedRequirements::default();
    let mut req2 = vk::MemoryRequirements2::default().push_next(&mut dedicated_req);
    let req_info = vk::ImageMemoryRequirementsInfo2::default().image(image);
    // SAFETY: the image was made on this device (Vulkan 1.1 core, which wgpu requires).
    unsafe { raw.get_image_memory_requirements2(&req_info, &mut req2) };
    let req = req2.memory_requirements;
    // SAFETY: the physical device of this device.
    let props =
        unsafe { instance.get_physical_device_memory_properties(dev.raw_physical_device()) };
    let wanted = vk::MemoryPropertyFlags::DEVICE_LOCAL;
    let ty = (0..props.memory_type_count).find(|&i| {
        req.memory_type_bits & (1 << i) != 0
            && props.memory_types[i as usize]
                .property_flags
                .contains(wanted)
    });
    let Some(ty) = ty else {
        // SAFETY: nothing is bound to the image yet.
        unsafe { raw.destroy_image(image, None) };
        return Err(DedicatedError::NoDeviceLocalMemory);
    };
    let mut ded = vk::MemoryDedicatedAllocateInfo::default().image(image);
    let alloc = vk::MemoryAllocateInfo::default()
        .allocation_size(req.size)
        .memory_type_index(ty)
        .push_next(&mut ded);
    // SAFETY: a valid allocate info; the image is dedicated to this memory.
    let memory = match unsafe { raw.allocate_memory(&alloc, None) } {
        Ok(m) => m,
        Err(e) => {
            unsafe { raw.destroy_image(image, None) };
            return Err(DedicatedError::Allocate(e));
        }
    };
    // SAFETY: fresh image and memory of the required size and type.
    if let Err(e) = unsafe { raw.bind_image_memory(image, memory, 0) } {
        unsafe {
            raw.destroy_image(image, None);
            raw.free_memory(memory, None);
        }
        return Err(DedicatedError::Bind(e));
    }
    let hal_desc = hal::TextureDescriptor {
        label: desc.label,
        size: desc.size,
        mip_level_count: 1,
        sample_count: desc.sample_count,
        dimension: desc.dimension,
        format: desc.format,
        usage,
        memory_flags: hal::MemoryFlags::empty(),
        view_formats: Vec::new(),
    };
    // SAFETY: image and memory were made on this device for exactly `hal_desc`.
    let hal_tex = unsafe {
        dev.texture_from_raw(
            image,
            &hal_desc,
            None,
            hal::vulkan::TextureMemory::Dedicated(memory),
        )
    };
    drop(dev);
    // SAFETY: the hal texture respects `desc` (same size, format, samples, usage); it is
    // initialised by `clear_once` before any method sees it.
    let tex = unsafe {
        device.create_texture_from_hal::<hal::api::Vulkan>(
            hal_tex,
            desc,
            wgpu::wgt::TextureUses::UNINITIALIZED,
        )
    };
    Ok(Some(tex))
}

/// One render pass that clears `t` to zero (colour 0, depth 0, stencil 0): the contents wgpu's
/// lazy initialisation gives its own textures.
fn clear_once(device: &wgpu::Device, queue: &wgpu::Queue, t: &wgpu::Texture) {
    let view = t.create_view(&Default::default());
    let format = t.format();
    let is_depth = format.is_depth_stencil_format();
    let color = [(!is_depth).then_some(wgpu::RenderPassColorAttachment {
        view: &view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
            store: wgpu::StoreOp::Store,
        },
    })];
    let depth = is_depth.then_some(wgpu::RenderPassDepthStencilAttachment {
        view: &view,
        depth_ops: format.has_depth_aspect().then_some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(0.0),
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: format.has_stencil_aspect().then_some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(0),
            store: wgpu::StoreOp::Store,
        }),
    });
    let mut enc = device.create_command_encoder(&Default::default());
    drop(enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("zero a dedicated render target"),
        color_attachments: if is_depth { &[] } else { &color },
        depth_stencil_attachment: depth,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    }));
    queue.submit([enc.finish()]);
}
