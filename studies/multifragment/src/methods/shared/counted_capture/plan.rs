//! How the capture's buffers lie over storage bindings (axis `bindings = auto|packed`), and the
//! workgroup ring's capacity where workgroup memory is short: what lets the compute A-buffer run
//! within WebGPU's default limits (issue 41 goal 5).
//!
//! - **native**: ten storage buffers per stage — the scene's five mesh buffers as they are, the
//!   per-pixel offsets, the fragments, the work counters, the image and the clip buffer
//!   (`native.wgsl`, `mesh.wgsl`). WebGPU allows eight.
//! - **packed**: six — the mesh packed at prepare into one vertex buffer of 48 B a vertex
//!   (`pack.wgsl`; what the resolve gathers per vertex, in one place), the indices, the offsets
//!   with the work counters after them in one buffer, the fragments, the image and the clip
//!   buffer (`packed.wgsl`). The fragments may so take three bindings where one cannot hold
//!   them (WebGPU's 128 MiB: 16.7M fragments a binding), as `limits::Split` lays them.
//!
//! `auto` (the default) is native wherever the adapter (or `--limits`) allows ten storage
//! buffers per stage, so the unlimited path is the one measured before; packed otherwise.
//! `packed` forces it (the A/B of what packing costs, on any adapter).
//!
//! The resolve sorts lists of up to [`RING`] fragments in workgroup memory (64 pixels × 32 × 8 B
//! = 16 KiB); the binned resolve adds its triangle entries (6.7 KiB), over WebGPU's 16 KiB, so
//! where the ring does not fit it holds [`RING_SHORT`] (8 KiB) and longer lists take the
//! per-thread arrays (exact either way).

use super::{Variants, FRAG_BYTES};
use bench_core::bind::Kind as B;
use bench_core::gpu::Gpu;
use bench_core::limits::{self, Split};

/// Storage buffers per stage of the native bindings (the fragments unsplit).
pub(crate) const NATIVE_BUFFERS: u32 = 10;
/// Storage buffers per stage of the packed bindings (the fragments unsplit).
pub(crate) const PACKED_BUFFERS: u32 = 6;
/// Fragments a pixel's workgroup ring holds (`WG_CAP`), and the capacity where that does not fit.
pub(crate) const RING: u32 = 32;
pub(crate) const RING_SHORT: u32 = 16;
/// Bytes of a packed vertex (`pack.wgsl`: position and object id, normal, colour).
pub(crate) const PACKED_VERTEX_BYTES: u64 = 48;

const NATIVE_WGSL: &str = include_str!("native.wgsl");
const PACKED_WGSL: &str = include_str!("packed.wgsl");
const MESH_WGSL: &str = include_str!("mesh.wgsl");
pub(crate) const PACK_WGSL: &str = include_str!("pack.wgsl");

/// The bindings of one prepared capture.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Plan {
    pub packed: bool,
    /// The fragments over their bindings (the first at binding 7, the rest at 16, 17, …).
    pub frags: Split,
    /// `WG_CAP`: [`RING`] or [`RING_SHORT`].
    pub ring: u32,
    /// `WIDE`: threads a workgroup of the transform and the scan, 256 or the device's most
    /// (128 in WebGPU's compatibility mode).
    pub wide: u32,
}

impl Plan {
    /// The plan before the fragments are counted (unsplit): packed where asked or where the
    /// adapter allows fewer than [`NATIVE_BUFFERS`] storage buffers per stage.
    pub(crate) fn before_sizing(gpu: &Gpu, v: Variants) -> Plan {
        let stage = gpu.limits.max_storage_buffers_per_shader_stage;
        let l = &gpu.limits;
        let most = l
            .max_compute_invocations_per_workgroup
            .min(l.max_compute_workgroup_size_x);
        Plan {
            packed: v.packed || stage < NATIVE_BUFFERS,
            frags: Split::whole(1, FRAG_BYTES),
            ring: v.ring,
            wide: if most >= 256 { 256 } else { 128 },
        }
    }

    /// Storage buffers beside the fragments' bindings in a stage.
    pub(crate) fn others(&self) -> u32 {
        if self.packed {
            PACKED_BUFFERS - 1
        } else {
            NATIVE_BUFFERS - 1
        }
    }

    /// The plan for `slots` fragment slots: the fragments split where one binding cannot hold
    /// them. Err (a skipped row) names the limit.
    pub(crate) fn sized(&self, gpu: &Gpu, slots: u64) -> bench_core::Result<Plan> {
        let frags = limits::split_storage(
            gpu.held(),
            "compute_abuffer fragments",
            (slots, FRAG_BYTES),
            self.others(),
        )?;
        Ok(Plan {
            frags,
            ..self.clone()
        })
    }

    /// WGSL declaring the plan's bindings and accessors (prepended to the module).
    pub(crate) fn wgsl(&self) -> String {
        let layout = if self.packed {
            PACKED_WGSL.to_string()
        } else {
            format!("{NATIVE_WGSL}\n{MESH_WGSL}")
        };
        format!(
            "const WG_CAP: u32 = {}u;\nconst WIDE: u32 = {}u;\n{}\n{layout}",
            self.ring,
            self.wide,
            self.frags.wgsl("frags", "vec2<u32>", 7)
        )
    }

    /// The bind group's rows: camera; the mesh; offsets, fragments, work, image; sizes; clip
    /// buffer; the fragments' further parts.
    pub(crate) fn rows(&self) -> Vec<(u32, B)> {
        let mut rows = vec![(0, B::Camera)];
        if self.packed {
            rows.extend([(1, B::StorageRo), (5, B::StorageRo), (6, B::Storage)]);
            rows.extend([(7, B::Storage), (9, B::Storage)]);
        } else {
            rows.extend((1..6).map(|b| (b, B::StorageRo)));
            rows.extend((6..10).map(|b| (b, B::Storage)));
        }
        rows.extend([(10, B::Uniform), (11, B::Storage)]);
        rows.extend(self.frags.more_bindings().map(|b| (b, B::Storage)));
        rows
    }

    /// The `split` column: how the fragments were split, and `packed` where the bindings were.
    pub(crate) fn column(&self) -> Option<String> {
        match (self.packed, self.frags.column()) {
            (false, c) => c,
            (true, None) => Some("packed".into()),
            (true, Some(c)) => Some(format!("packed,{c}")),
        }
    }
}

/// Workgroup memory of the pixel resolve's rings at capacity `ring`.
pub(crate) fn ring_bytes(ring: u32) -> u32 {
    2 * 64 * ring * 4
}
