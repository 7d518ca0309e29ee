// Per-pixel linked lists (an A-buffer; Yang et al. 2010). Capture: every fragment takes the next
// node of one fixed pool (atomicAdd on a counter), stores its payload there and pushes the node
// onto its pixel's list (atomicExchange of the head). A fragment finding the pool full is counted
// as lost in its pixel (atomicAdd), never dropped silently. Resolve: per pixel, walk the list,
// insertion-sort it (bounded by SORT_MAX, beyond which the farthest are dropped and counted),
// fold nearest first, and count overflowed pixels and lost fragments.

override POOL: u32 = 1u;
// Per-pixel sort capacity of the resolve (a register/local array; WGSL needs a constant size).
const SORT_MAX: u32 = 128u;

struct Node {
    color: vec4<f32>,
    depth: f32,
    view_z: f32,
    // bit 31: front facing
    object_id: u32,
    // next node index + 1; 0 ends the list
    next: u32,
};

// node index + 1 of the pixel's newest node; 0 = empty list.
@group(0) @binding(1) var<storage, read_write> heads: array<atomic<u32>>;
@group(0) @binding(2) var<storage, read_write> nodes: array<Node>;
@group(0) @binding(3) var<storage, read_write> out_image: array<vec4<f32>>;
// 0: next free node, 1: overflowed pixels, 2: lost fragments (pool full or over SORT_MAX)
@group(0) @binding(4) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> lost: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> counts: array<u32>;

@fragment
fn fs_append(in: Varyings, @builtin(front_facing) ff: bool) {
    let p = u32(in.clip.y) * u32(camera.viewport.x) + u32(in.clip.x);
    let i = atomicAdd(&counters[0], 1u);
    if i >= POOL {
        atomicAdd(&lost[p], 1u);
        return;
    }
    let oid = (in.object_id & 0x7fffffffu) | select(0u, 0x80000000u, ff);
    nodes[i] = Node(in.color, in.clip.z, in.view_z, oid, 0u);
    nodes[i].next = atomicExchange(&heads[p], i + 1u);
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    var d: array<f32, SORT_MAX>;
    var ix: array<u32, SORT_MAX>;
    var n = 0u;
    var dropped = 0u;
    var cur = atomicLoad(&heads[p]);
    loop {
        if cur == 0u {
            break;
        }
        let ni = cur - 1u;
        let z = nodes[ni].depth;
        cur = nodes[ni].next;
        if n == SORT_MAX {
            dropped = dropped + 1u;
            if !nearer(z, d[n - 1u]) {
                continue;
            }
            n = n - 1u;
        }
        var j = n;
        loop {
            if j == 0u || !nearer(z, d[j - 1u]) {
                break;
            }
            d[j] = d[j - 1u];
            ix[j] = ix[j - 1u];
            j = j - 1u;
        }
        d[j] = z;
        ix[j] = ni;
        n = n + 1u;
    }
    var s = fold_init_at(vec2<f32>(id.xy) + 0.5);
    for (var i = 0u; i < n; i = i + 1u) {
        let e = nodes[ix[i]];
        fold_step(&s, Frag(e.depth, e.view_z, e.color, vec3<f32>(0.0), e.object_id & 0x7fffffffu, (e.object_id >> 31u) != 0u));
    }
    for (var k = 0u; k < fold_image_count(); k = k + 1u) {
        out_image[k * w * h + p] = fold_finish_image(s, k);
    }
    counts[p] = n;
    let gone = atomicLoad(&lost[p]) + dropped;
    if gone > 0u {
        atomicAdd(&counters[1], 1u);
        atomicAdd(&counters[2], gone);
    }
}
