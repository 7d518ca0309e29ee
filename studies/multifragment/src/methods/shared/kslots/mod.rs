//! Per-pixel k slots shared by the k-buffers (`kbuffer_rmw`, `kbuffer_atomic`, `hybrid`): the
//! `layers` axis, the slot buffers and their layout, readback and the k-nearest judge;
//! [`entry`] is what a slot stores, [`atomic`] the hazard-free atomic capture.

pub mod atomic;
pub mod entry;

use super::store;
use crate::methods::shared::tail::TailTargets;
use crate::methods::{Capture, Expected};
use bench_core::axes::Axis;
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, GpuScene};
use bench_core::gpu_util::{camera_entry, read_vec, storage_entry, STORAGE_RW};
use bench_core::limits::{self, Split};
use bench_core::record::{cols, Flag};
use bench_core::Result;
use entry::SlotConfig;
use mfx_reference::FragmentLists;

pub const MAX_K: i64 = 64;

/// k, the fragments a k-buffer keeps per pixel (both k-buffers).
pub const LAYERS: Axis = Axis::int(cols::LAYERS, "k: fragments kept per pixel", 8, 1, MAX_K);
/// Per-pixel k slots: keys (u32, larger = nearer, 0 = empty), entries, and the resolved image.
pub struct KSlots {
    pub k: u32,
    /// Output images (dof: 3).
    pub images: u64,
    /// MSAA samples with k slots each (1: single-sample).
    pub samples: u32,
    pub keys: wgpu::Buffer,
    /// The entries, or their first part where they are split over several bindings.
    pub entries: wgpu::Buffer,
    /// The entries' further parts (bound at `limits::SPLIT_BINDING` + 0, 1, …).
    pub entries_more: Vec<wgpu::Buffer>,
    pub split: Split,
    pub image: wgpu::Buffer,
    /// Captured depths of the last readback (k per pixel, nearest first), for `judge`.
    pub captured: Vec<Option<f32>>,
}

impl KSlots {
    pub fn new(
        gpu: &Gpu,
        alloc: &mut AllocCounter,
        scene: &GpuScene,
        k: u32,
        slot: &SlotConfig,
    ) -> Result<Self> {
        Self::per_sample(gpu, alloc, scene, (k, slot), 1)
    }

    /// k slots of `slot`'s entries for each of `samples` samples per pixel (MSAA per-sample
    /// capture); the effect's images.
    pub fn per_sample(
        gpu: &Gpu,
        alloc: &mut AllocCounter,
        scene: &GpuScene,
        (k, slot): (u32, &SlotConfig),
        samples: u32,
    ) -> Result<Self> {
        let px = scene.pixels() as u64;
        let slots = px * samples as u64 * k as u64;
        let split = entries_split(gpu, scene, (k, slot), samples)?;
        limits::check_storage(gpu.held(), "k-buffer keys", slots * 4)?;
        let images = slot.images();
        let keys = alloc.buffer(gpu, "k-buffer keys", slots * 4, STORAGE_RW);
        let mut parts = store::split_buffers(gpu, alloc, "k-buffer entries", &split);
        let entries = parts.remove(0);
        Ok(KSlots {
            k,
            images,
            samples,
            keys,
            entries,
            entries_more: parts,
            split,
            image: alloc.buffer(gpu, "k-buffer image", px * 16 * images, STORAGE_RW),
            captured: vec![],
        })
    }

    /// A bind group of `buffers` at bindings 0, 1, …, the tail's textures at 5–7 if given, and
    /// the entries' further parts.
    pub fn bind(
        &self,
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        buffers: &[&wgpu::Buffer],
        tail: Option<&TailTargets>,
    ) -> wgpu::BindGroup {
        let mut e: Vec<wgpu::BindGroupEntry<'_>> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        if let Some(t) = tail {
            e.extend(t.bind_entries(5));
        }
        e.extend(
            self.split
                .more_bindings()
                .zip(&self.entries_more)
                .map(|(binding, b)| wgpu::BindGroupEntry {
                    binding,
                    resource: b.as_entire_binding(),
                }),
        );
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("k-buffer"),
            layout,
            entries: &e,
        })
    }

    /// Image, counts (non-empty slots) and the captured depths (kept for `judge`). Per-sample
    /// slots read back the image only: per-pixel counts and the hazard judge are single-sample
    /// by contract (the image is judged against each sample's k nearest).
    pub fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let n = scene.pixels();
        let k = self.k as usize;
        let mut cap = Capture::empty();
        let images = n * self.images as usize;
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.image, images)?);
        cap.expected = Expected::FirstK(self.k);
        if self.samples > 1 {
            self.captured.clear();
            return Ok(cap);
        }
        let keys = read_vec::<u32>(gpu, &self.keys, n * k)?;
        self.captured = keys
            .iter()
            .map(|&key| (key != 0).then(|| store::key_depth(key, scene.reversed_z)))
            .collect();
        cap.counts = Some(
            keys.chunks(k)
                .map(|s| s.iter().take_while(|&&x| x != 0).count() as u32)
                .collect(),
        );
        Ok(cap)
    }

    /// `hazard_pixels`: pixels whose captured depths are not the true k nearest. It cannot tell
    /// an RMW race from a raster-coverage disagreement with the reference (a fragment the GPU
    /// did not rasterize: seen on 1 pixel of 128² grass on lavapipe, where depth_peel and
    /// linked_list miss it too), so read it beside depth_peel's `layer_count_accuracy`.
    pub fn judge(&self, cap: &mut Capture, lists: &FragmentLists, races: Races) {
        if self.captured.len() != lists.pixels() * self.k as usize {
            return;
        }
        let m = store::k_nearest_mismatch(&self.captured, self.k as usize, lists);
        let mut notes = Vec::new();
        match races {
            Races::Possible => {
                cap.hazard_pixels = Some(m.hazards);
                if let Some(p) = m.first_hazard {
                    cap.flag.add(Flag::Hazard);
                    let (x, y) = (p as u32 % lists.width, p as u32 / lists.width);
                    notes.push(format!("first hazard pixel ({x},{y})"));
                }
            }
            Races::None => {
                // An insertion without read-modify-write races: a pixel off the true k nearest
                // is the rasteriser's fragment set differing from the reference's (the same
                // pixels depth_peel and linked_list miss), never a hazard.
                cap.hazard_pixels = Some(0);
                if let Some(p) = m.first_hazard {
                    cap.flag.add(Flag::FragmentsDiffer);
                    let (x, y) = (p as u32 % lists.width, p as u32 / lists.width);
                    notes.push(format!(
                        "{} pixels hold other fragments than the reference's k nearest (raster coverage; first ({x},{y}))",
                        m.hazards
                    ));
                }
            }
        }
        if let Some(p) = m.first_tie {
            // Not a race: the true k + 1 nearest hold an f32 depth tie the GPU cannot order.
            cap.flag.add(Flag::LostCoplanar);
            let (x, y) = (p as u32 % lists.width, p as u32 / lists.width);
            notes.push(format!(
                "{} pixels differ at f32 depth ties (not counted as hazards; first ({x},{y}))",
                m.ties
            ));
        }
        for note in notes {
            cap.notes = if cap.notes.is_empty() {
                note
            } else {
                format!("{}; {note}", cap.notes)
            };
        }
    }
}

/// Whether a k-buffer's insertion can race ([`KSlots::judge`]): what a pixel off the true k
/// nearest is named.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Races {
    /// Read-modify-write of the slots (kbuffer_rmw): a wrong pixel is a `hazard`.
    Possible,
    /// Atomic insertion (kbuffer_atomic): hazard-free by construction, a wrong pixel is
    /// `fragments_differ`.
    None,
}

/// Bind group layout shared by the insert and resolve stages: camera, keys, entries, image.
pub fn kslots_layout(gpu: &Gpu, extra: u32, split: &Split) -> wgpu::BindGroupLayout {
    let entries = kslots_entries(extra, split);
    gpu.note_layout("k-buffer", &entries);
    gpu.device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("k-buffer"),
            entries: &entries,
        })
}

/// The entries of [`kslots_layout`] (a tail resolve adds its textures to them), the entries'
/// further parts at `limits::SPLIT_BINDING` + 0, 1, ….
pub fn kslots_entries(extra: u32, split: &Split) -> Vec<wgpu::BindGroupLayoutEntry> {
    let fc = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
    let mut entries = vec![camera_entry(0)];
    for b in 1..4 + extra {
        entries.push(storage_entry(b, false, fc));
    }
    for b in split.more_bindings() {
        entries.push(storage_entry(b, false, fc));
    }
    entries
}

/// How the k slots' entries lie over storage bindings here (`limits::split_storage`; keys,
/// image and the atomic k-buffer's claims share the stage).
pub fn entries_split(
    gpu: &Gpu,
    scene: &GpuScene,
    (k, slot): (u32, &SlotConfig),
    samples: u32,
) -> Result<Split> {
    let slots = scene.pixels() as u64 * samples as u64 * k as u64;
    limits::split_storage(
        gpu.held(),
        "k-buffer entries",
        (slots, slot.entry_bytes()),
        3,
    )
}
