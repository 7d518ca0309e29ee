// The k-buffer of Bavoil 2007 (thesis ch. 4): each pixel keeps its K nearest fragments sorted,
// nearest first, and every fragment inserts itself by insertion sort with plain loads and stores
// (read-modify-write) of the pixel's storage: no atomics, no ordering between fragments of one
// pixel in flight at once, so concurrent fragments can read the same state and one overwrite the
// other's insertion: the RMW hazards the thesis describes (measured against the CPU reference).

override K: u32 = 8u;

// `Entry` (what a slot keeps for the effects fold) is generated for the point: entry.rs.

// Per pixel K keys, larger = nearer, 0 = empty (so a cleared buffer is an empty k-buffer).
@group(0) @binding(1) var<storage, read_write> keys: array<u32>;
// `entries` (binding 2, split over more bindings where over the largest one) and
// entries_load / entries_store are generated: limits::Split::wgsl.
@group(0) @binding(3) var<storage, read_write> out_image: array<vec4<f32>>;

// Window depth → key with "larger is nearer" for both depth conventions; never 0.
fn near_key(d: f32) -> u32 {
    let b = bitcast<u32>(d) & 0x7fffffffu;
    return select(~b, max(b, 1u), camera.near_far.z > 0.5);
}

// keep = first: a full pixel takes no more fragments (the first K to arrive stay).
override KEEP_FIRST: bool = false;

// Inserts the fragment; returns what fell out as (premultiplied rgb, α): the fragment itself
// (rejected), the farthest kept one (evicted), or α = −1 when nothing did.
fn insert(in: Varyings, ff: bool) -> vec4<f32> {
    let base = (u32(in.clip.y) * u32(camera.viewport.x) + u32(in.clip.x)) * K;
    let key = near_key(in.clip.z);
    let last = keys[base + K - 1u];
    // Full and not nearer than the farthest kept (or keep = first): nothing to insert.
    if last != 0u && (KEEP_FIRST || last >= key) {
        return vec4<f32>(in.color.rgb * in.color.a, in.color.a);
    }
    var out = vec4<f32>(0.0, 0.0, 0.0, -1.0);
    if last != 0u {
        let c = entry_color(entries_load(base + K - 1u));
        out = vec4<f32>(c.rgb * c.a, c.a);
    }
    // Start at the first empty slot (or the last one when full).
    var j = K - 1u;
    loop {
        if j == 0u || keys[base + j - 1u] != 0u {
            break;
        }
        j = j - 1u;
    }
    // Shift farther fragments back by one (equal keys stay ahead: stable, like the CPU twin).
    loop {
        if j == 0u {
            break;
        }
        let prev = keys[base + j - 1u];
        if prev >= key {
            break;
        }
        keys[base + j] = prev;
        entries_store(base + j, entries_load(base + j - 1u));
        j = j - 1u;
    }
    keys[base + j] = key;
    entries_store(base + j, make_entry(in, ff));
    return out;
}

@fragment
fn fs_insert(in: Varyings, @builtin(front_facing) ff: bool) {
    _ = insert(in, ff);
}

// tail = blend: what fell out goes to the blended tail (tail.wgsl).
@fragment
fn fs_insert_tail(in: Varyings, @builtin(front_facing) ff: bool) -> TailOut {
    let o = insert(in, ff);
    if o.a < 0.0 {
        return tail_none();
    }
    return tail_of(o.rgb, o.a);
}

// ---- resolve: walk each pixel's slots nearest first through the effects fold ----

// Writes image i of pixel p for every image the effect outputs (dof: 3, one after another).
fn write_images(p: u32, s: FoldState) {
    let n = u32(camera.viewport.x) * u32(camera.viewport.y);
    for (var i = 0u; i < fold_image_count(); i = i + 1u) {
        out_image[i * n + p] = fold_finish_image(s, i);
    }
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    write_images(p, fold_kept(p * K, vec2<f32>(id.xy) + 0.5));
}

fn fold_kept(base: u32, pixel: vec2<f32>) -> FoldState {
    var s = fold_init_at(pixel);
    for (var i = 0u; i < K; i = i + 1u) {
        let key = keys[base + i];
        if key == 0u {
            break;
        }
        fold_step(&s, entry_frag(entries_load(base + i), key));
    }
    return s;
}

// tail = blend (transparency only): the kept fragments with the tail behind them (tail/resolve.wgsl).
@compute @workgroup_size(8, 8)
fn resolve_tail(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    out_image[p] = with_tail(id.xy, fold_finish(fold_kept(p * K, vec2<f32>(id.xy) + 0.5)));
}

// heuristics = sort_flush: the thesis's flush, a full-screen triangle with colour writes off
// (§4.3.2: "rendering a full-screen quadrilateral with a GL_FALSE color mask").
@vertex
fn vs_flush(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.5, 1.0);
}

@fragment
fn fs_flush() {}
