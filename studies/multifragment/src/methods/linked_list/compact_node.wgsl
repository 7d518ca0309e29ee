// `node = compact`: 12 B nodes (window depth, primitive | front << 31, next), written by a
// fragment stage that reads no attribute (vs_position; the primitive is `primitive_index`, the
// triangle's index in the one indexed draw). The resolve re-derives every attribute from the
// primitive at the pixel centre (compute_abuffer's visibility.wgsl, appended), so every effect
// folds, Fresnel included, and ties are ordered by primitive as the reference orders them.
// The module starts with `enable primitive_index;` (added by the Rust side: it must come first).

// 2 with pixel pools (no link: 8 B nodes), else 3.
override NODE_WORDS: u32 = 3u;
const NEXT: u32 = 2u;

@group(1) @binding(0) var<storage, read> positions: array<f32>;
@group(1) @binding(1) var<storage, read> normals: array<f32>;
@group(1) @binding(2) var<storage, read> colors: array<vec4<f32>>;
@group(1) @binding(3) var<storage, read> object_ids: array<u32>;
@group(1) @binding(4) var<storage, read> indices: array<u32>;

@fragment
fn fs_append(
    @builtin(position) pos: vec4<f32>,
    @builtin(front_facing) ff: bool,
    @builtin(primitive_index) prim: u32,
) {
    let n = take_node(pos);
    if n == NO_NODE {
        return;
    }
    nodes_store(n * NODE_WORDS, bitcast<u32>(pos.z));
    nodes_store(n * NODE_WORDS + 1u, prim | select(0u, 0x80000000u, ff));
    push_node(pos, n);
}

// aa_capture = coverage: one node per pixel-rate fragment, its coverage mask packed into the tag
// above the primitive (TAG_PRIM_BITS = 23: prim | mask << 23 | front << 31, as compute_abuffer).
@fragment
fn fs_append_mask(
    @builtin(position) pos: vec4<f32>,
    @builtin(front_facing) ff: bool,
    @builtin(primitive_index) prim: u32,
    @builtin(sample_mask) mask: u32,
) {
    let n = take_node(pos);
    if n == NO_NODE {
        return;
    }
    nodes_store(n * NODE_WORDS, bitcast<u32>(pos.z));
    nodes_store(n * NODE_WORDS + 1u, prim | ((mask & 0xffu) << TAG_PRIM_BITS) | select(0u, 0x80000000u, ff));
    push_node(pos, n);
}

// tail = blend: the full vertex stage, so a fragment that finds its pool full has a colour for
// the blended tail (tail.wgsl).
@fragment
fn fs_append_tail(
    in: Varyings,
    @builtin(front_facing) ff: bool,
    @builtin(primitive_index) prim: u32,
) -> TailOut {
    let n = take_node(in.clip);
    if n == NO_NODE {
        return tail_of(in.color.rgb * in.color.a, in.color.a);
    }
    nodes_store(n * NODE_WORDS, bitcast<u32>(in.clip.z));
    nodes_store(n * NODE_WORDS + 1u, prim | select(0u, 0x80000000u, ff));
    push_node(in.clip, n);
    return tail_none();
}

fn node_depth(ni: u32) -> f32 {
    return bitcast<f32>(nodes_load(ni * NODE_WORDS));
}

fn node_key(ni: u32) -> u32 {
    return nodes_load(ni * NODE_WORDS + 1u);
}

fn list_before(za: f32, ka: u32, zb: f32, kb: u32) -> bool {
    return before(za, ka, zb, kb);
}

// The coverage mask of a tag (COVERAGE; unused otherwise).
fn node_mask(tag: u32) -> u32 {
    return (tag >> TAG_PRIM_BITS) & 0xffu;
}

fn list_frag(z: f32, tag: u32, ndc: vec2<f32>) -> Frag {
    let i = tri_indices(tag_prim(tag));
    return frag_from(z, tag, ndc, i, clip_of(i.x), clip_of(i.y), clip_of(i.z));
}
