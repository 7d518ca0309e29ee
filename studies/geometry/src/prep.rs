//! The CPU side of geometry feeding, the part a user pays for before the GPU sees a vertex:
//! triangle order (original, shuffled, meshopt vertex-cache, + vertex-fetch), batching into
//! draw calls (≤ 65,536 vertices per batch for 16-bit indices), strips with primitive restart,
//! and quantised vertex streams (interleaved or one buffer per attribute).
//!
//! Every encoder has a CPU twin decoder ([`decode`]) written the way the hardware and
//! `geometry.wgsl` decode, so a test can rasterize exactly what the GPU should see.

use meshopt::VertexCacheStatistics;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_pcg::Pcg32;
use rayon::prelude::*;
use scenarios::Mesh;

/// How one component is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Enc {
    F32,
    F16,
    Snorm16,
    Unorm16,
    Snorm8,
    Unorm8,
    /// r, g, b in 10 bits each (r lowest), a in the top 2 bits.
    Unorm1010102,
}

/// A vertex format as the suite names it (wgpu's names, lower case).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AttrFormat {
    pub name: &'static str,
    pub enc: Enc,
    /// Components stored (and read by the shader).
    pub comps: u32,
    pub format: wgpu::VertexFormat,
}

macro_rules! f {
    ($name:literal, $enc:ident, $n:literal, $fmt:ident) => {
        AttrFormat {
            name: $name,
            enc: Enc::$enc,
            comps: $n,
            format: wgpu::VertexFormat::$fmt,
        }
    };
}

/// Every format the study can feed. 8-bit ×2 formats are left out: WebGPU wants 4-byte
/// aligned attributes, so they would be padded to 4 bytes anyway.
pub const FORMATS: &[AttrFormat] = &[
    f!("float32x2", F32, 2, Float32x2),
    f!("float32x3", F32, 3, Float32x3),
    f!("float32x4", F32, 4, Float32x4),
    f!("float16x2", F16, 2, Float16x2),
    f!("float16x4", F16, 4, Float16x4),
    f!("snorm16x2", Snorm16, 2, Snorm16x2),
    f!("snorm16x4", Snorm16, 4, Snorm16x4),
    f!("unorm16x2", Unorm16, 2, Unorm16x2),
    f!("unorm16x4", Unorm16, 4, Unorm16x4),
    f!("snorm8x4", Snorm8, 4, Snorm8x4),
    f!("unorm8x4", Unorm8, 4, Unorm8x4),
    f!("unorm10_10_10_2", Unorm1010102, 4, Unorm10_10_10_2),
];

pub fn format_by_name(name: &str) -> Option<AttrFormat> {
    FORMATS.iter().copied().find(|f| f.name == name)
}

/// What an attribute holds: its natural component count and range.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AttrKind {
    Position,
    /// Unit vector, components in [−1, 1].
    Normal,
    /// Straight RGBA in [0, 1].
    Color,
    /// 2D, in [0, 1].
    Texcoord,
    /// The thesis's Fig. 3.3 extra 4-float texture coordinates, in [0, 1]; index 0..8.
    Extra(u32),
}

impl AttrKind {
    pub fn name(self) -> String {
        match self {
            AttrKind::Position => "position".into(),
            AttrKind::Normal => "normal".into(),
            AttrKind::Color => "color".into(),
            AttrKind::Texcoord => "texcoord".into(),
            AttrKind::Extra(i) => format!("extra{i}"),
        }
    }
    fn signed(self) -> bool {
        matches!(self, AttrKind::Position | AttrKind::Normal)
    }
    /// Formats a suite may choose for this attribute.
    pub fn allowed(self) -> &'static [&'static str] {
        match self {
            AttrKind::Position => &["float32x3", "float16x4", "snorm16x4"],
            AttrKind::Normal => &[
                "float32x3",
                "float32x4",
                "float16x4",
                "snorm16x4",
                "snorm8x4",
                "unorm8x4",
                "unorm10_10_10_2",
            ],
            AttrKind::Color => &[
                "float32x4",
                "float32x3",
                "float16x4",
                "unorm16x4",
                "snorm16x4",
                "unorm8x4",
                "snorm8x4",
                "unorm10_10_10_2",
            ],
            AttrKind::Texcoord => &[
                "float32x2",
                "float32x3",
                "float16x2",
                "snorm16x2",
                "unorm16x2",
            ],
            AttrKind::Extra(_) => &["float32x4"],
        }
    }
}

/// The format's normalised-integer range does not cover the attribute's: a signed value in an
/// unsigned format is stored as v·½ + ½ and decoded as s·2 − 1.
pub fn remapped(kind: AttrKind, fmt: AttrFormat) -> bool {
    kind.signed()
        && kind != AttrKind::Position
        && matches!(fmt.enc, Enc::Unorm16 | Enc::Unorm8 | Enc::Unorm1010102)
}

/// Positions in a compressed format are quantised to their batch's bounding box: stored
/// q = (p − centre) / half ∈ [−1, 1], decoded p = centre + half·q in the vertex shader.
pub fn position_quantised(fmt: AttrFormat) -> bool {
    fmt.enc != Enc::F32
}

/// Largest absolute error one stored component can carry, in stored units (before remap and
/// box scale), for values within the format's range and |v| ≤ 1: half a step of the grid.
pub fn quantisation_step(fmt: AttrFormat, component: usize) -> f64 {
    match fmt.enc {
        Enc::F32 => 0.5 * f32::EPSILON as f64,
        // binary16 has 11 significant bits: for |v| in [½, 1) the spacing is 2^-11, half of it 2^-12.
        Enc::F16 => 2f64.powi(-12),
        Enc::Snorm16 => 0.5 / 32767.0,
        Enc::Unorm16 => 0.5 / 65535.0,
        Enc::Snorm8 => 0.5 / 127.0,
        Enc::Unorm8 => 0.5 / 255.0,
        Enc::Unorm1010102 => {
            if component == 3 {
                0.5 / 3.0
            } else {
                0.5 / 1023.0
            }
        }
    }
}

/// Writes `v` (already in stored units) in `fmt` to `out` (exactly `fmt.format.size()` bytes).
pub fn encode(fmt: AttrFormat, v: [f32; 4], out: &mut [u8]) {
    let n = fmt.comps as usize;
    let sn = |x: f32, m: f32| (x.clamp(-1.0, 1.0) * m).round();
    let un = |x: f32, m: f32| (x.clamp(0.0, 1.0) * m).round();
    match fmt.enc {
        Enc::F32 => {
            for c in 0..n {
                out[4 * c..4 * c + 4].copy_from_slice(&v[c].to_le_bytes());
            }
        }
        Enc::F16 => {
            for c in 0..n {
                let h = half::f16::from_f32(v[c]).to_bits();
                out[2 * c..2 * c + 2].copy_from_slice(&h.to_le_bytes());
            }
        }
        Enc::Snorm16 => {
            for c in 0..n {
                out[2 * c..2 * c + 2].copy_from_slice(&(sn(v[c], 32767.0) as i16).to_le_bytes());
            }
        }
        Enc::Unorm16 => {
            for c in 0..n {
                out[2 * c..2 * c + 2].copy_from_slice(&(un(v[c], 65535.0) as u16).to_le_bytes());
            }
        }
        Enc::Snorm8 => {
            for c in 0..n {
                out[c] = (sn(v[c], 127.0) as i8) as u8;
            }
        }
        Enc::Unorm8 => {
            for c in 0..n {
                out[c] = un(v[c], 255.0) as u8;
            }
        }
        Enc::Unorm1010102 => {
            let w = un(v[0], 1023.0) as u32
                | (un(v[1], 1023.0) as u32) << 10
                | (un(v[2], 1023.0) as u32) << 20
                | (un(v[3], 3.0) as u32) << 30;
            out[..4].copy_from_slice(&w.to_le_bytes());
        }
    }
}

/// The CPU twin of the hardware's vertex fetch: stored bytes → components (missing ones 0).
pub fn decode(fmt: AttrFormat, b: &[u8]) -> [f32; 4] {
    let n = fmt.comps as usize;
    let mut v = [0.0f32; 4];
    let u16_at = |c: usize| u16::from_le_bytes([b[2 * c], b[2 * c + 1]]);
    for (c, out) in v.iter_mut().enumerate().take(n) {
        *out = match fmt.enc {
            Enc::F32 => f32::from_le_bytes([b[4 * c], b[4 * c + 1], b[4 * c + 2], b[4 * c + 3]]),
            Enc::F16 => half::f16::from_bits(u16_at(c)).to_f32(),
            // Vulkan/WebGPU snorm: max(i / (2^(n−1) − 1), −1).
            Enc::Snorm16 => (u16_at(c) as i16 as f32 / 32767.0).max(-1.0),
            Enc::Unorm16 => u16_at(c) as f32 / 65535.0,
            Enc::Snorm8 => (b[c] as i8 as f32 / 127.0).max(-1.0),
            Enc::Unorm8 => b[c] as f32 / 255.0,
            Enc::Unorm1010102 => {
                let w = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                if c == 3 {
                    (w >> 30) as f32 / 3.0
                } else {
                    ((w >> (10 * c)) & 1023) as f32 / 1023.0
                }
            }
        };
    }
    v
}

/// Triangle order of the mesh before batching.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshOrder {
    /// As the generator or file gives it.
    Original,
    /// Triangles randomly permuted (fixed seed): the post-transform cache's worst case.
    Shuffled,
    /// meshopt `optimize_vertex_cache` (Forsyth-like; ACMR ≈ 0.6–0.7 on regular meshes).
    Vcache,
    /// Vcache, then meshopt `optimize_vertex_fetch` (vertices renumbered in first-use order).
    VcacheVfetch,
}

pub const MESH_ORDERS: &[&str] = &["original", "shuffled", "vcache", "vcache_vfetch"];

impl MeshOrder {
    pub fn parse(s: &str) -> Option<MeshOrder> {
        Some(match s {
            "original" => MeshOrder::Original,
            "shuffled" => MeshOrder::Shuffled,
            "vcache" => MeshOrder::Vcache,
            "vcache_vfetch" => MeshOrder::VcacheVfetch,
            _ => return None,
        })
    }
}

/// A mesh in some order: `verts[i]` is the source vertex behind vertex i, `indices` index `verts`.
#[derive(Clone, Debug)]
pub struct Ordered {
    pub verts: Vec<u32>,
    pub indices: Vec<u32>,
}

/// Reorders the mesh's triangles (and for `VcacheVfetch` its vertices).
pub fn order_mesh(mesh: &Mesh, order: MeshOrder) -> Ordered {
    let vcount = mesh.vertex_count();
    let mut verts: Vec<u32> = (0..vcount as u32).collect();
    let indices = match order {
        MeshOrder::Original => mesh.indices.clone(),
        MeshOrder::Shuffled => {
            let mut tris: Vec<[u32; 3]> = mesh
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect();
            tris.shuffle(&mut Pcg32::seed_from_u64(0x5eed));
            tris.into_iter().flatten().collect()
        }
        MeshOrder::Vcache => meshopt::optimize_vertex_cache(&mesh.indices, vcount),
        MeshOrder::VcacheVfetch => {
            let mut idx = meshopt::optimize_vertex_cache(&mesh.indices, vcount);
            let used = meshopt::optimize_vertex_fetch_in_place(&mut idx, &mut verts);
            verts.truncate(used);
            idx
        }
    };
    Ordered { verts, indices }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Primitive {
    List,
    /// Triangle strips stitched with primitive restart (meshopt `stripify`).
    Strip,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IndexFormat {
    Uint16,
    Uint32,
}

impl IndexFormat {
    pub fn restart(self) -> u32 {
        match self {
            IndexFormat::Uint16 => 0xFFFF,
            IndexFormat::Uint32 => 0xFFFF_FFFF,
        }
    }
    /// Vertices a batch may hold: every local index must fit, and a strip's must differ from
    /// the restart value.
    pub fn max_batch_vertices(self, primitive: Primitive) -> usize {
        match (self, primitive) {
            (IndexFormat::Uint16, Primitive::List) => 65_536,
            (IndexFormat::Uint16, Primitive::Strip) => 65_535,
            (IndexFormat::Uint32, _) => u32::MAX as usize,
        }
    }
    pub fn wgpu(self) -> wgpu::IndexFormat {
        match self {
            IndexFormat::Uint16 => wgpu::IndexFormat::Uint16,
            IndexFormat::Uint32 => wgpu::IndexFormat::Uint32,
        }
    }
}

/// How to cut the ordered mesh into draw calls.
#[derive(Clone, Copy, Debug)]
pub struct BatchSpec {
    /// Triangles per draw call; 0 = as many as fit.
    pub batch_size: usize,
    /// Draw only the first this many triangles of the ordered mesh; 0 = all.
    pub draw_triangles: usize,
    pub index_format: IndexFormat,
    pub primitive: Primitive,
    pub indexed: bool,
}

/// One draw call.
#[derive(Clone, Copy, Debug, Default)]
pub struct Batch {
    pub first_vertex: u32,
    pub vertex_count: u32,
    /// Into `Batched::indices` (indexed draws only).
    pub first_index: u32,
    pub index_count: u32,
    pub triangles: u32,
    /// Bounding box of the batch's positions: centre and half extent (≥ a tiny floor).
    pub centre: [f32; 3],
    pub half: [f32; 3],
}

/// The mesh as draw calls: vertices (source ids, batch after batch) and batch-local indices.
#[derive(Clone, Debug, Default)]
pub struct Batched {
    pub verts: Vec<u32>,
    /// Batch-local indices (a draw adds `first_vertex` as its base vertex); strips hold restarts.
    pub indices: Vec<u32>,
    pub batches: Vec<Batch>,
    pub triangles: usize,
    /// meshopt's FIFO-16 analysis of the batched triangle list (what the strips were made from).
    pub cache: Option<VertexCacheStatistics>,
}

/// Cuts `ordered` into batches. Within a batch the vertices keep their order (the batch's
/// vertex set, sorted), so batching changes only what batching must change.
pub fn batch(mesh: &Mesh, ordered: &Ordered, spec: &BatchSpec) -> Batched {
    let total_tris = ordered.indices.len() / 3;
    let tris = if spec.draw_triangles == 0 {
        total_tris
    } else {
        spec.draw_triangles.min(total_tris)
    };
    let per_batch = if spec.batch_size == 0 {
        usize::MAX
    } else {
        spec.batch_size
    };
    let max_verts = if spec.indexed {
        spec.index_format.max_batch_vertices(spec.primitive)
    } else {
        usize::MAX
    };
    let mut out = Batched {
        triangles: tris,
        ..Default::default()
    };
    let mut local_of = vec![u32::MAX; ordered.verts.len()];
    let mut list_global: Vec<u32> = Vec::new(); // batched list with base vertex applied, for analysis
    let mut start = 0usize;
    let mut cur_unique: Vec<u32> = Vec::new();
    let tri_idx = |t: usize| &ordered.indices[3 * t..3 * t + 3];
    while start < tris {
        // Grow the batch while it has room for the next triangle's new vertices.
        let mut end = start;
        cur_unique.clear();
        while end < tris && end - start < per_batch {
            let t = tri_idx(end);
            // The triangle's vertices not yet in the batch (a corner may repeat).
            let mut new = [0u32; 3];
            let mut n_new = 0;
            for &v in t {
                if local_of[v as usize] == u32::MAX && !new[..n_new].contains(&v) {
                    new[n_new] = v;
                    n_new += 1;
                }
            }
            if cur_unique.len() + n_new > max_verts {
                break;
            }
            for &v in &new[..n_new] {
                local_of[v as usize] = 0; // mark: in the batch, local id assigned at close
                cur_unique.push(v);
            }
            end += 1;
        }
        let first_vertex = out.verts.len() as u32;
        let first_index = out.indices.len() as u32;
        let mut b = Batch {
            first_vertex,
            first_index,
            triangles: (end - start) as u32,
            ..Default::default()
        };
        if spec.indexed {
            cur_unique.sort_unstable();
            for (li, &g) in cur_unique.iter().enumerate() {
                local_of[g as usize] = li as u32;
                out.verts.push(ordered.verts[g as usize]);
            }
            let local: Vec<u32> = ordered.indices[3 * start..3 * end]
                .iter()
                .map(|&g| local_of[g as usize])
                .collect();
            list_global.extend(local.iter().map(|&l| l + first_vertex));
            b.vertex_count = cur_unique.len() as u32;
            match spec.primitive {
                Primitive::List => out.indices.extend_from_slice(&local),
                Primitive::Strip => {
                    let strip =
                        meshopt::stripify(&local, cur_unique.len(), spec.index_format.restart())
                            .expect("stripify output fits its bound (4 indices per triangle)");
                    out.indices.extend_from_slice(&strip);
                }
            }
            b.index_count = out.indices.len() as u32 - first_index;
        } else {
            // Non-indexed: every corner is its own vertex.
            for &g in &ordered.indices[3 * start..3 * end] {
                out.verts.push(ordered.verts[g as usize]);
            }
            b.vertex_count = (3 * (end - start)) as u32;
            list_global.extend(first_vertex..first_vertex + b.vertex_count);
        }
        for &g in &cur_unique {
            local_of[g as usize] = u32::MAX;
        }
        set_box(&mut b, mesh, &out.verts[first_vertex as usize..]);
        out.batches.push(b);
        start = end;
    }
    if !list_global.is_empty() {
        out.cache = Some(meshopt::analyze_vertex_cache(
            &list_global,
            out.verts.len(),
            16,
            0,
            0,
        ));
    }
    out
}

fn set_box(b: &mut Batch, mesh: &Mesh, verts: &[u32]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for &v in verts {
        let p = mesh.positions[v as usize];
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    for c in 0..3 {
        b.centre[c] = 0.5 * (lo[c] + hi[c]);
        // A flat box still needs a nonzero scale; q is then 0 and the decode exact.
        b.half[c] = (0.5 * (hi[c] - lo[c])).max(1e-20);
    }
}

/// Vertex buffers interleaved (one stream, all attributes) or separate (one per attribute).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    Interleaved,
    Separate,
}

/// What to feed: formats per attribute (None = attribute absent) and the buffer layout.
#[derive(Clone, Debug)]
pub struct FeedFormats {
    pub position: AttrFormat,
    pub normal: Option<AttrFormat>,
    pub color: Option<AttrFormat>,
    pub texcoord: Option<AttrFormat>,
    pub extra_attributes: u32,
    pub layout: Layout,
}

/// One attribute of the feed: its shader location and format.
#[derive(Clone, Copy, Debug)]
pub struct Slot {
    pub kind: AttrKind,
    pub format: AttrFormat,
    pub location: u32,
}

impl FeedFormats {
    /// Attributes in location order: position first.
    pub fn slots(&self) -> Vec<Slot> {
        let mut v = vec![(AttrKind::Position, self.position)];
        v.extend(self.normal.map(|f| (AttrKind::Normal, f)));
        v.extend(self.color.map(|f| (AttrKind::Color, f)));
        v.extend(self.texcoord.map(|f| (AttrKind::Texcoord, f)));
        let extra = format_by_name("float32x4").expect("known format");
        v.extend((0..self.extra_attributes).map(|i| (AttrKind::Extra(i), extra)));
        v.into_iter()
            .enumerate()
            .map(|(i, (kind, format))| Slot {
                kind,
                format,
                location: i as u32,
            })
            .collect()
    }
    /// Vertex buffers the layout needs.
    pub fn buffer_count(&self) -> usize {
        match self.layout {
            Layout::Interleaved => 1,
            Layout::Separate => self.slots().len(),
        }
    }
}

/// Encoded vertex streams: bytes per buffer and the attributes (location, format, offset) in it.
#[derive(Clone, Debug)]
pub struct Streams {
    pub buffers: Vec<Vec<u8>>,
    pub strides: Vec<u64>,
    pub attributes: Vec<Vec<wgpu::VertexAttribute>>,
    /// Stream and byte offset of each slot, in slot order.
    pub placement: Vec<(usize, usize)>,
}

impl Streams {
    pub fn bytes(&self) -> u64 {
        self.buffers.iter().map(|b| b.len() as u64).sum()
    }
}

/// The attribute's natural value at source vertex `v` (position in world units).
pub fn natural(kind: AttrKind, mesh: &Mesh, v: u32) -> [f32; 4] {
    let i = v as usize;
    match kind {
        AttrKind::Position => {
            let p = mesh.positions[i];
            [p[0], p[1], p[2], 0.0]
        }
        AttrKind::Normal => {
            let n = mesh.normals[i];
            [n[0], n[1], n[2], 0.0]
        }
        AttrKind::Color => mesh.colors[i],
        AttrKind::Texcoord => {
            let p = mesh.positions[i];
            // Planar mapping of the unit-sized scenes into [0, 1].
            [
                (p[0] * 0.5 + 0.5).clamp(0.0, 1.0),
                (p[1] * 0.5 + 0.5).clamp(0.0, 1.0),
                0.0,
                0.0,
            ]
        }
        AttrKind::Extra(k) => {
            // Smooth in space like real texture coordinates (a per-vertex hash would be noise
            // that no interpolation reproduces to better than its gradient), distinct per k.
            let p = mesh.positions[i];
            std::array::from_fn(|c| {
                let a = 1.0 + ((4 * k + c as u32) % 5) as f32 * 0.7;
                let ph = (4 * k + c as u32) as f32 * 0.9;
                0.5 + 0.5 * (a * p[0] - 0.8 * a * p[1] + 0.5 * p[2] + ph).sin()
            })
        }
    }
}

/// Natural value → stored units (box-normalised positions, remapped signed values).
fn to_stored(kind: AttrKind, fmt: AttrFormat, b: &Batch, mut v: [f32; 4]) -> [f32; 4] {
    if kind == AttrKind::Position && position_quantised(fmt) {
        for (c, x) in v.iter_mut().enumerate().take(3) {
            *x = (*x - b.centre[c]) / b.half[c];
        }
        v[3] = 0.0;
    } else if remapped(kind, fmt) {
        for x in &mut v {
            *x = *x * 0.5 + 0.5;
        }
    }
    v
}

/// Stored components → the value the shader computes (the CPU twin of `geometry.wgsl`'s
/// decode), in f32 in the same order of operations.
pub fn from_stored(kind: AttrKind, fmt: AttrFormat, b: &Batch, d: [f32; 4]) -> [f32; 4] {
    let n = fmt.comps as usize;
    let mut v = d;
    if kind == AttrKind::Position {
        if position_quantised(fmt) {
            for c in 0..3 {
                v[c] = b.centre[c] + b.half[c] * d[c];
            }
        }
        v[3] = 0.0;
    } else if remapped(kind, fmt) {
        for x in v.iter_mut().take(n) {
            *x = *x * 2.0 - 1.0;
        }
    }
    v
}

/// Encodes every vertex of `batched` in `formats`.
pub fn encode_streams(mesh: &Mesh, batched: &Batched, formats: &FeedFormats) -> Streams {
    let slots = formats.slots();
    let sizes: Vec<usize> = slots
        .iter()
        .map(|s| s.format.format.size() as usize)
        .collect();
    let mut placement = Vec::new();
    let (strides, attributes): (Vec<u64>, Vec<Vec<wgpu::VertexAttribute>>) = match formats.layout {
        Layout::Interleaved => {
            let mut off = 0usize;
            let mut attrs = Vec::new();
            for (s, &sz) in slots.iter().zip(&sizes) {
                attrs.push(wgpu::VertexAttribute {
                    format: s.format.format,
                    offset: off as u64,
                    shader_location: s.location,
                });
                placement.push((0, off));
                off += sz;
            }
            (vec![off as u64], vec![attrs])
        }
        Layout::Separate => slots
            .iter()
            .zip(&sizes)
            .enumerate()
            .map(|(i, (s, &sz))| {
                placement.push((i, 0));
                (
                    sz as u64,
                    vec![wgpu::VertexAttribute {
                        format: s.format.format,
                        offset: 0,
                        shader_location: s.location,
                    }],
                )
            })
            .unzip(),
    };
    let nv = batched.verts.len();
    let mut buffers: Vec<Vec<u8>> = strides
        .iter()
        .map(|&s| vec![0u8; s as usize * nv])
        .collect();
    let firsts: Vec<u32> = batched.batches.iter().map(|b| b.first_vertex).collect();
    for (buf, data) in buffers.iter_mut().enumerate() {
        let stride = strides[buf] as usize;
        let in_buf: Vec<usize> = (0..slots.len())
            .filter(|&si| placement[si].0 == buf)
            .collect();
        // Parallel over vertices: the encode of tens of millions of vertices is the user's wait.
        data.par_chunks_mut(stride)
            .enumerate()
            .for_each(|(vi, vertex)| {
                let b = &batched.batches[firsts.partition_point(|&f| f as usize <= vi) - 1];
                let v = batched.verts[vi];
                for &si in &in_buf {
                    let s = &slots[si];
                    let off = placement[si].1;
                    let stored = to_stored(s.kind, s.format, b, natural(s.kind, mesh, v));
                    encode(s.format, stored, &mut vertex[off..off + sizes[si]]);
                }
            });
    }
    Streams {
        buffers,
        strides,
        attributes,
        placement,
    }
}

/// Decodes slot `si` of vertex `vi` (in batch `b`) from the streams, as the GPU would.
pub fn decode_slot(streams: &Streams, slot: &Slot, si: usize, b: &Batch, vi: usize) -> [f32; 4] {
    let (buf, off) = streams.placement[si];
    let at = vi * streams.strides[buf] as usize + off;
    let sz = slot.format.format.size() as usize;
    let d = decode(slot.format, &streams.buffers[buf][at..at + sz]);
    from_stored(slot.kind, slot.format, b, d)
}

/// The weight and the w-component mix of slot k's contribution to the check value
/// (`geometry.wgsl` is generated from the same numbers): distinct per slot, so a swapped or
/// wrongly decoded attribute changes the image.
pub fn check_coeffs(k: usize) -> (f32, [f32; 3]) {
    let w = 0.6 / (1.0 + 0.5 * k as f32);
    let s = match k % 3 {
        0 => [0.3, -0.2, 0.1],
        1 => [-0.1, 0.25, 0.2],
        _ => [0.2, 0.1, -0.3],
    };
    (w, s)
}

/// Check value of a decoded vertex (attributes other than position, slot order).
pub fn check_value(decoded: &[[f32; 4]]) -> [f32; 3] {
    let mut acc = [0.0f32; 3];
    for (k, d) in decoded.iter().enumerate() {
        let (w, s) = check_coeffs(k);
        for c in 0..3 {
            acc[c] += w * (d[c] + d[3] * s[c]);
        }
    }
    acc
}

/// Triangles of a batched mesh as source-vertex triples (strips unrolled through meshopt).
pub fn source_triangles(b: &Batched, restart: u32, primitive: Primitive) -> Vec<[u32; 3]> {
    let mut out = Vec::new();
    for bt in &b.batches {
        let idx = &b.indices[bt.first_index as usize..(bt.first_index + bt.index_count) as usize];
        let list = match primitive {
            Primitive::List => idx.to_vec(),
            Primitive::Strip => meshopt::unstripify(idx, restart).expect("valid strip"),
        };
        for t in list.chunks_exact(3) {
            out.push([0, 1, 2].map(|c| b.verts[(bt.first_vertex + t[c]) as usize]));
        }
    }
    out
}

/// A triangle up to rotation (winding kept): the smallest index first.
pub fn canonical(t: [u32; 3]) -> [u32; 3] {
    let m = (0..3).min_by_key(|&i| t[i]).unwrap();
    [t[m], t[(m + 1) % 3], t[(m + 2) % 3]]
}
