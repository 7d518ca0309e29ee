//! Limits profiles (`mfx sweep --limits`): the device limits and features a run is held to,
//! and how a buffer larger than one storage binding is split across several.
//!
//! A profile is applied by requesting the device with its limits and no feature beyond what it
//! allows, on whatever adapter runs: wgpu then refuses what does not fit, and the checks here
//! name the limit before any GPU work where the size can be computed (`skipped` rows).

use crate::{CoreError, Result};

/// What a device was granted, as the checks below read it: its limits and the profile they
/// came from (`Gpu::held`; this module sits below `gpu`, so it takes no `Gpu`).
pub type Held<'a> = (&'a wgpu::Limits, Profile);

/// The limits a run is held to: the adapter's own, or a browser's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Profile {
    /// Everything the adapter offers (mfx's default).
    #[default]
    Adapter,
    /// WebGPU's default limits (`wgpu::Limits::defaults()`: 128 MiB per storage binding,
    /// 256 MiB per buffer, 8 storage buffers per stage, 16 KiB of workgroup memory, 32 B of
    /// colour attachments per sample) and WebGPU's optional features only.
    WebGpu,
    /// A WebGL2-class device (`wgpu::Limits::downlevel_webgl2_defaults()`): no compute shaders,
    /// no storage buffers in any stage, 2048² textures, 4 colour attachments.
    Downlevel,
    /// WebGPU's compatibility mode (OpenGL ES 3.1 / D3D11-class devices), its defaults as the
    /// WebGPU specification gives them ("compatibility mode default", gpuweb `spec/index.bs`,
    /// since gpuweb#5295, 2025-09): no storage buffers in the vertex stage, 4 in the fragment
    /// stage (8 in compute, as WebGPU), 4 colour attachments, 128 invocations a workgroup
    /// (128 × 128 × 64), 15 inter-stage variables, 4096² textures, 16 KiB uniform bindings.
    /// wgpu has no per-stage storage limits: mfx checks those itself ([`check_stage_storage`]).
    #[serde(rename = "webgpu-compat")]
    WebGpuCompat,
}

/// Every profile with its name (the `--limits` value and the `limits` column) and one line.
pub const PROFILES: &[(Profile, &str, &str)] = &[
    (
        Profile::Adapter,
        "adapter",
        "the adapter's own limits and every optional feature mfx uses (default)",
    ),
    (
        Profile::WebGpu,
        "webgpu",
        "WebGPU's default limits (what a browser grants without asking): 128 MiB per storage binding, 256 MiB per buffer, 8 storage buffers per stage; WebGPU's optional features only",
    ),
    (
        Profile::Downlevel,
        "downlevel",
        "a WebGL2-class device: no compute shaders, no storage buffers, 2048² textures",
    ),
    (
        Profile::WebGpuCompat,
        "webgpu-compat",
        "WebGPU's compatibility mode defaults: WebGPU's, with no storage buffers in vertex shaders, 4 in fragment shaders, 128 invocations a workgroup, 4 colour attachments, 4096² textures",
    ),
];

/// Features the harness needs to time any frame (timestamps around and inside passes). They are
/// the measuring instrument, not part of a method, so every profile keeps them where the
/// adapter has them; a browser's `timestamp-query` is coarser, which changes no method's work.
const HARNESS_FEATURES: wgpu::Features = wgpu::Features::TIMESTAMP_QUERY
    .union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS)
    .union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES);

impl std::str::FromStr for Profile {
    type Err = crate::UnknownWord;
    fn from_str(s: &str) -> std::result::Result<Self, crate::UnknownWord> {
        let s = s.to_ascii_lowercase();
        PROFILES
            .iter()
            .find(|(_, n, _)| *n == s)
            .map(|(p, _, _)| *p)
            .ok_or_else(|| {
                let names: Vec<&str> = PROFILES.iter().map(|(_, n, _)| *n).collect();
                crate::UnknownWord {
                    what: "limits profile",
                    text: s.clone(),
                    known: names.join(", "),
                }
            })
    }
}

impl std::fmt::Display for Profile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Profile {
    pub fn name(self) -> &'static str {
        PROFILES.iter().find(|(p, _, _)| *p == self).unwrap().1
    }

    /// Whose limits these are, as a skipped row's reason says it.
    pub fn owner(self) -> &'static str {
        match self {
            Profile::Adapter => "the adapter's",
            Profile::WebGpu => "WebGPU's default",
            Profile::Downlevel => "WebGL2's (downlevel)",
            Profile::WebGpuCompat => "WebGPU compatibility mode's default",
        }
    }

    /// Who sets the limits, as "… allows N" says it.
    pub fn who(self) -> &'static str {
        match self {
            Profile::Adapter => "the adapter",
            Profile::WebGpu => "WebGPU's default limit set",
            Profile::Downlevel => "WebGL2's (downlevel) limit set",
            Profile::WebGpuCompat => "WebGPU compatibility mode's default limit set",
        }
    }

    /// The limits to request on an adapter whose own are `adapter`.
    pub fn limits(self, adapter: &wgpu::Limits) -> wgpu::Limits {
        match self {
            Profile::Adapter => adapter.clone(),
            Profile::WebGpu => wgpu::Limits::defaults(),
            Profile::Downlevel => wgpu::Limits::downlevel_webgl2_defaults(),
            Profile::WebGpuCompat => wgpu::Limits {
                max_color_attachments: 4,
                max_compute_invocations_per_workgroup: 128,
                max_compute_workgroup_size_x: 128,
                max_compute_workgroup_size_y: 128,
                max_inter_stage_shader_variables: 15,
                max_texture_dimension_1d: 4096,
                max_texture_dimension_2d: 4096,
                max_uniform_buffer_binding_size: 16 << 10,
                ..wgpu::Limits::defaults()
            },
        }
    }

    /// Storage buffers a pipeline may make visible to the vertex and to the fragment stage,
    /// where the profile sets them below `maxStorageBuffersPerShaderStage` (compatibility
    /// mode's `maxStorageBuffersInVertexStage` 0 and `maxStorageBuffersInFragmentStage` 4).
    pub fn stage_storage(self) -> Option<(u32, u32)> {
        (self == Profile::WebGpuCompat).then_some((0, 4))
    }

    /// The features to request out of `wanted` (what the adapter has of mfx's list).
    pub fn features(self, wanted: wgpu::Features) -> wgpu::Features {
        match self {
            Profile::Adapter => wanted,
            Profile::WebGpu | Profile::WebGpuCompat => {
                wanted & (wgpu::Features::all_webgpu_mask() | HARNESS_FEATURES)
            }
            // WebGL2 has none of WebGPU's optional features (no float32 blending, no f16).
            Profile::Downlevel => wanted & HARNESS_FEATURES,
        }
    }

    /// The downlevel capabilities methods see: a WebGL2-class device lacks compute, storage in
    /// vertex and fragment shaders, and indirect execution whatever the adapter has.
    pub fn downlevel(self, adapter: wgpu::DownlevelCapabilities) -> wgpu::DownlevelCapabilities {
        match self {
            Profile::Adapter | Profile::WebGpu => adapter,
            Profile::WebGpuCompat => wgpu::DownlevelCapabilities {
                flags: adapter.flags - wgpu::DownlevelFlags::VERTEX_STORAGE,
                ..adapter
            },
            Profile::Downlevel => wgpu::DownlevelCapabilities {
                flags: adapter.flags
                    - (wgpu::DownlevelFlags::COMPUTE_SHADERS
                        | wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE
                        | wgpu::DownlevelFlags::FRAGMENT_STORAGE
                        | wgpu::DownlevelFlags::VERTEX_STORAGE
                        | wgpu::DownlevelFlags::INDIRECT_EXECUTION),
                ..adapter
            },
        }
    }

    /// Whether a wgpu error under this profile says a limit was exceeded: wgpu's limit errors
    /// all name the limit ("… limit is 0, count was 2. Check the limit `…`", "exceeds the
    /// limit"), and with the adapter's own limits the same point would have been prepared.
    pub fn explains(self, message: &str) -> bool {
        self != Profile::Adapter && message.to_ascii_lowercase().contains("limit")
    }
}

/// `bytes` in the unit a reader checks against a limit: MiB for powers of two, else MB.
pub fn human_bytes(bytes: u64) -> String {
    const MIB: u64 = 1 << 20;
    if bytes >= 1 << 30 && bytes.is_multiple_of(1 << 30) {
        format!("{} GiB", bytes >> 30)
    } else if bytes >= MIB && bytes.is_multiple_of(MIB) {
        format!("{} MiB", bytes / MIB)
    } else {
        format!("{:.1} MB", bytes as f64 / 1e6)
    }
}

/// The largest storage binding here, and the name of the limit that sets it.
pub fn storage_binding_limit((limits, _): Held<'_>) -> (u64, &'static str) {
    let b = limits.max_storage_buffer_binding_size;
    let s = limits.max_buffer_size;
    if s < b {
        (s, "maxBufferSize")
    } else {
        (b, "maxStorageBufferBindingSize")
    }
}

/// Whether a buffer of `bytes` can be bound as one storage buffer here; Err names the limit.
pub fn check_storage(gpu: Held<'_>, what: &str, bytes: u64) -> Result<()> {
    let (lim, name) = storage_binding_limit(gpu);
    if lim == 0 || gpu.0.max_storage_buffers_per_shader_stage == 0 {
        return Err(no_storage(gpu, what));
    }
    if bytes > lim {
        return Err(CoreError::Limit(format!(
            "{what} needs {bytes} B ({}) in one storage binding, over {} {name} of {lim} B ({})",
            human_bytes(bytes),
            gpu.1.owner(),
            human_bytes(lim)
        )));
    }
    Ok(())
}

/// A device without storage buffers (WebGL2-class).
fn no_storage((limits, profile): Held<'_>, what: &str) -> CoreError {
    CoreError::Limit(format!(
        "{what} needs a storage buffer; {} allows none (maxStorageBuffersPerShaderStage {}, maxStorageBufferBindingSize {})",
        profile.who(),
        limits.max_storage_buffers_per_shader_stage,
        limits.max_storage_buffer_binding_size
    ))
}

/// Whether a bind group layout's `entries` stay within `profile`'s per-stage storage limits
/// ([`Profile::stage_storage`]); Err names the limit, the stage and the layout. wgpu checks
/// only `maxStorageBuffersPerShaderStage`, so mfx's layout helpers call this (counted per bind
/// group layout: every mfx pipeline keeps its vertex and fragment storage in one group).
pub fn check_stage_storage(
    profile: Profile,
    what: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> std::result::Result<(), crate::Unsupported> {
    let Some((vertex, fragment)) = profile.stage_storage() else {
        return Ok(());
    };
    let storage = |stage: wgpu::ShaderStages| {
        entries
            .iter()
            .filter(|e| e.visibility.contains(stage))
            .filter(|e| {
                matches!(
                    e.ty,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { .. },
                        ..
                    }
                )
            })
            .count() as u32
    };
    for (stage, name, limit) in [
        (
            wgpu::ShaderStages::VERTEX,
            "maxStorageBuffersInVertexStage",
            vertex,
        ),
        (
            wgpu::ShaderStages::FRAGMENT,
            "maxStorageBuffersInFragmentStage",
            fragment,
        ),
    ] {
        let n = storage(stage);
        if n > limit {
            return Err(format!(
                "{what} binds {n} storage buffers to the {} stage, over {} {name} of {limit}",
                if stage == wgpu::ShaderStages::VERTEX {
                    "vertex"
                } else {
                    "fragment"
                },
                profile.owner()
            )
            .into());
        }
    }
    Ok(())
}

/// A split buffer is spread over at most this many storage bindings: WebGPU's whole
/// per-stage allowance (8), and 8 × 2 GiB covers 16 layers of 32 B entries at 4K with 4 samples.
pub const MAX_PARTS: u32 = 8;

/// Bindings of a split buffer's second, third, … parts (its first keeps the buffer's own
/// binding): clear of every method's fixed bindings.
pub const SPLIT_BINDING: u32 = 16;

/// How an array of `elems` elements of `elem_bytes` is laid over storage bindings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Split {
    pub parts: u32,
    /// Elements in every part but the last (which holds the rest).
    pub per_part: u64,
    pub elems: u64,
    pub elem_bytes: u64,
}

impl Split {
    /// One binding, unsplit.
    pub fn whole(elems: u64, elem_bytes: u64) -> Split {
        Split {
            parts: 1,
            per_part: elems.max(1),
            elems,
            elem_bytes,
        }
    }

    /// Element count of part `i`.
    pub fn part_elems(&self, i: u32) -> u64 {
        let start = self.per_part * i as u64;
        self.elems.saturating_sub(start).min(self.per_part)
    }

    /// The same split over 4-byte words (`elem_bytes` a multiple of 4), for WGSL that indexes
    /// an `array<u32>`: every element's words stay in one part.
    pub fn words(&self) -> Split {
        let k = self.elem_bytes / 4;
        Split {
            parts: self.parts,
            per_part: self.per_part * k,
            elems: self.elems * k,
            elem_bytes: 4,
        }
    }

    /// Bindings of the parts after the first ([`SPLIT_BINDING`] + 0, 1, …).
    pub fn more_bindings(&self) -> impl Iterator<Item = u32> {
        (1..self.parts).map(|i| SPLIT_BINDING + i - 1)
    }

    /// The `split` column: empty when unsplit, else `bindings:N`.
    pub fn column(&self) -> Option<String> {
        (self.parts > 1).then(|| format!("bindings:{}", self.parts))
    }

    /// WGSL declaring the parts of `name: array<ty>` (the first at `binding`, the rest at
    /// [`SPLIT_BINDING`] + 0, 1, …) and `{name}_load(i)` / `{name}_store(i, v)` over them; with
    /// one part they index the array directly.
    pub fn wgsl(&self, name: &str, ty: &str, binding: u32) -> String {
        let mut s = format!(
            "@group(0) @binding({binding}) var<storage, read_write> {name}: array<{ty}>;\n"
        );
        for (i, b) in (1..).zip(self.more_bindings()) {
            s += &format!(
                "@group(0) @binding({b}) var<storage, read_write> {name}_{i}: array<{ty}>;\n"
            );
        }
        let part = |i: u32| {
            if i == 0 {
                name.to_string()
            } else {
                format!("{name}_{i}")
            }
        };
        let mut load = format!("fn {name}_load(i: u32) -> {ty} {{\n");
        let mut store = format!("fn {name}_store(i: u32, v: {ty}) {{\n");
        if self.parts == 1 {
            load += &format!("    return {name}[i];\n}}\n");
            store += &format!("    {name}[i] = v;\n}}\n");
        } else {
            let per = self.per_part;
            load +=
                &format!("    let p = i / {per}u;\n    let j = i - p * {per}u;\n    switch p {{\n");
            store +=
                &format!("    let p = i / {per}u;\n    let j = i - p * {per}u;\n    switch p {{\n");
            for i in 1..self.parts {
                load += &format!("        case {i}u: {{ return {}[j]; }}\n", part(i));
                store += &format!("        case {i}u: {{ {}[j] = v; }}\n", part(i));
            }
            load += &format!("        default: {{ return {name}[j]; }}\n    }}\n}}\n");
            store += &format!("        default: {{ {name}[j] = v; }}\n    }}\n}}\n");
        }
        s + &load + &store
    }
}

/// How `elems` elements of `elem_bytes` (a multiple of 4) fit this device's storage bindings,
/// beside `others` storage buffers the same shader stage binds: one binding where it fits,
/// else the fewest equal parts under the largest binding, at most [`MAX_PARTS`] and within
/// `maxStorageBuffersPerShaderStage`. Err (a `skipped` row) names the limit it is over.
pub fn split_storage(
    gpu: Held<'_>,
    what: &str,
    (elems, elem_bytes): (u64, u64),
    others: u32,
) -> Result<Split> {
    let bytes = elems * elem_bytes;
    let (lim, name) = storage_binding_limit(gpu);
    if lim == 0 || gpu.0.max_storage_buffers_per_shader_stage == 0 {
        return Err(no_storage(gpu, what));
    }
    if bytes <= lim {
        return Ok(Split::whole(elems, elem_bytes));
    }
    // lim ≥ 4 and elem_bytes a small struct: at least one element fits a binding.
    let parts = elems.div_ceil((lim / elem_bytes).max(1));
    let stage = gpu.0.max_storage_buffers_per_shader_stage as u64;
    let cap = (MAX_PARTS as u64).min(stage.saturating_sub(others as u64));
    if parts > cap {
        return Err(CoreError::Limit(format!(
            "{what} needs {bytes} B ({}): {} bindings under {} {name} of {lim} B ({}), over the {cap} a split may use (mfx splits over at most {MAX_PARTS}; maxStorageBuffersPerShaderStage {stage} with {others} other storage buffers in the stage)",
            human_bytes(bytes),
            parts,
            gpu.1.owner(),
            human_bytes(lim)
        )));
    }
    let parts = parts as u32;
    Ok(Split {
        parts,
        per_part: elems.div_ceil(parts as u64),
        elems,
        elem_bytes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profiles_parse_by_name_and_webgpu_is_the_webgpu_default_set() {
        for (p, n, _) in PROFILES {
            assert_eq!(n.parse::<Profile>().unwrap(), *p);
            assert_eq!(p.name(), *n);
        }
        let e = "browser".parse::<Profile>().unwrap_err();
        assert_eq!(e.text, "browser");
        assert!(
            e.to_string().contains("unknown limits profile 'browser'"),
            "{e}"
        );
        assert!(e.to_string().contains("webgpu"), "{e}");
        // The WebGPU specification's default limits (gpuweb "Limits" table).
        let l = Profile::WebGpu.limits(&wgpu::Limits::unlimited());
        assert_eq!(l.max_storage_buffer_binding_size, 128 << 20);
        assert_eq!(l.max_buffer_size, 256 << 20);
        assert_eq!(l.max_storage_buffers_per_shader_stage, 8);
        assert_eq!(l.max_compute_workgroup_storage_size, 16 << 10);
        assert_eq!(l.max_color_attachment_bytes_per_sample, 32);
        assert_eq!(l.max_texture_dimension_2d, 8192);
        let d = Profile::Downlevel.limits(&wgpu::Limits::unlimited());
        assert_eq!(d.max_storage_buffers_per_shader_stage, 0);
        assert_eq!(d.max_compute_invocations_per_workgroup, 0);
        assert_eq!(d.max_texture_dimension_2d, 2048);
        let wanted = wgpu::Features::SHADER_INT64 | wgpu::Features::FLOAT32_BLENDABLE;
        let f = Profile::WebGpu.features(wanted);
        assert!(!f.contains(wgpu::Features::SHADER_INT64));
        assert!(f.contains(wgpu::Features::FLOAT32_BLENDABLE));
        assert!(!Profile::Downlevel
            .features(wanted)
            .contains(wgpu::Features::FLOAT32_BLENDABLE));
        // Compatibility mode (the WebGPU spec's "compatibility mode default" column).
        let c = Profile::WebGpuCompat.limits(&wgpu::Limits::unlimited());
        assert_eq!(c.max_storage_buffers_per_shader_stage, 8);
        assert_eq!(c.max_compute_invocations_per_workgroup, 128);
        assert_eq!(c.max_texture_dimension_2d, 4096);
        assert_eq!(c.max_color_attachments, 4);
        assert_eq!(Profile::WebGpuCompat.stage_storage(), Some((0, 4)));
        assert_eq!(Profile::WebGpu.stage_storage(), None);
        assert_eq!(
            "webgpu-compat".parse::<Profile>().unwrap(),
            Profile::WebGpuCompat
        );
    }

    #[test]
    fn compatibility_mode_counts_storage_per_stage_and_names_the_limit() {
        let st = |b, vis| wgpu::BindGroupLayoutEntry {
            binding: b,
            visibility: vis,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let fc = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let four: Vec<_> = (0..4).map(|b| st(b, fc)).collect();
        let five: Vec<_> = (0..5).map(|b| st(b, fc)).collect();
        let compute: Vec<_> = (0..8).map(|b| st(b, wgpu::ShaderStages::COMPUTE)).collect();
        let c = Profile::WebGpuCompat;
        assert!(check_stage_storage(c, "k", &four).is_ok());
        assert!(check_stage_storage(c, "compute", &compute).is_ok());
        let why = check_stage_storage(c, "linked_list", &five).unwrap_err();
        assert!(
            why.contains("maxStorageBuffersInFragmentStage of 4") && why.contains("5"),
            "{why}"
        );
        let vertex = [st(0, wgpu::ShaderStages::VERTEX)];
        let why = check_stage_storage(c, "v", &vertex).unwrap_err();
        assert!(why.contains("maxStorageBuffersInVertexStage of 0"), "{why}");
        // Other profiles leave it to wgpu's per-stage limit.
        assert!(check_stage_storage(Profile::WebGpu, "linked_list", &five).is_ok());
    }

    #[test]
    fn bytes_are_written_in_the_unit_of_the_limit() {
        assert_eq!(human_bytes(128 << 20), "128 MiB");
        assert_eq!(human_bytes(2 << 30), "2 GiB");
        assert_eq!(human_bytes(171_600_000), "171.6 MB");
    }

    #[test]
    fn a_split_covers_every_element_once() {
        let s = Split {
            parts: 3,
            per_part: 10,
            elems: 25,
            elem_bytes: 4,
        };
        let total: u64 = (0..3).map(|i| s.part_elems(i)).sum();
        assert_eq!(total, 25);
        assert_eq!(s.part_elems(2), 5);
        assert_eq!(s.column().as_deref(), Some("bindings:3"));
        assert_eq!(Split::whole(25, 4).column(), None);
        // Over words, a 12 B element's three words stay in one part.
        let w = Split::whole(25, 12).words();
        assert_eq!((w.parts, w.per_part, w.elems, w.elem_bytes), (1, 75, 75, 4));
        let w = Split {
            elem_bytes: 12,
            ..s
        }
        .words();
        assert_eq!((w.per_part, w.elems, w.part_elems(2)), (30, 75, 15));
        let w = s.wgsl("entries", "Entry", 2);
        assert!(w.contains("@binding(16) var<storage, read_write> entries_1"));
        assert!(w.contains("@binding(17) var<storage, read_write> entries_2"));
        assert!(w.contains("case 2u: { return entries_2[j]; }"));
    }
}
