// `node = full`: 32 B nodes carrying what the fold reads (every effect but Fresnel, whose normal
// they do not store): colour (4 words), window depth, view depth, object id | front << 31, next.

const NODE_WORDS: u32 = 8u;
const NEXT: u32 = 7u;

@fragment
fn fs_append(in: Varyings, @builtin(front_facing) ff: bool) {
    _ = append(in, ff);
}

// tail = blend: a fragment that finds its pool full goes to the blended tail (tail.wgsl).
@fragment
fn fs_append_tail(in: Varyings, @builtin(front_facing) ff: bool) -> TailOut {
    if append(in, ff) {
        return tail_none();
    }
    return tail_of(in.color.rgb * in.color.a, in.color.a);
}

// Appends the fragment; false if its pool is full.
fn append(in: Varyings, ff: bool) -> bool {
    let n = take_node(in.clip);
    if n == NO_NODE {
        return false;
    }
    let b = n * NODE_WORDS;
    nodes_store(b, bitcast<u32>(in.color.r));
    nodes_store(b + 1u, bitcast<u32>(in.color.g));
    nodes_store(b + 2u, bitcast<u32>(in.color.b));
    nodes_store(b + 3u, bitcast<u32>(in.color.a));
    nodes_store(b + 4u, bitcast<u32>(in.clip.z));
    nodes_store(b + 5u, bitcast<u32>(in.view_z));
    nodes_store(b + 6u, (in.object_id & 0x7fffffffu) | select(0u, 0x80000000u, ff));
    push_node(in.clip, n);
    return true;
}

fn node_depth(ni: u32) -> f32 {
    return bitcast<f32>(nodes_load(ni * NODE_WORDS + 4u));
}

// The sort key is the node itself (its payload is read again by the fold).
fn node_key(ni: u32) -> u32 {
    return ni;
}

// Depth only: equal depths keep list order (the reference orders them by primitive).
fn list_before(za: f32, ka: u32, zb: f32, kb: u32) -> bool {
    return nearer(za, zb);
}

// Full nodes carry no coverage mask (aa_capture = coverage needs compact nodes): every sample.
fn node_mask(ni: u32) -> u32 {
    return 0xffu;
}

fn list_frag(z: f32, ni: u32, ndc: vec2<f32>) -> Frag {
    let b = ni * NODE_WORDS;
    let c = vec4<f32>(bitcast<f32>(nodes_load(b)), bitcast<f32>(nodes_load(b + 1u)), bitcast<f32>(nodes_load(b + 2u)), bitcast<f32>(nodes_load(b + 3u)));
    let oid = nodes_load(b + 6u);
    return Frag(z, bitcast<f32>(nodes_load(b + 5u)), c, vec3<f32>(0.0), oid & 0x7fffffffu, (oid >> 31u) != 0u);
}
