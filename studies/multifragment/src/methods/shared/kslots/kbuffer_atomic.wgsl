// A hazard-free k-buffer: the same K nearest as kbuffer_rmw, with atomics.
// Pass 1 (keys): every fragment bubbles its depth key through the pixel's K slots with 32-bit
// atomicMax (larger key = nearer): a slot keeps the larger of (old, new), the smaller carries on
// to the next slot, an empty slot (0) ends the walk. Every step is one atomic, so no insertion is
// ever lost; the slots end sorted, nearest first, holding the K nearest keys.
// Pass 2 (payload): every fragment whose key is in its pixel's slots claims the first unclaimed
// slot with that key (atomicAdd on a claim counter, so exact depth ties get one slot each) and
// writes its payload there. 64-bit atomicMin of (depth << 32 | payload) would need one pass, but
// naga allows 64-bit min/max only without a return value (SHADER_INT64_ATOMIC_MIN_MAX), and the
// bubbling needs the returned old value; 32-bit atomics work everywhere.

override K: u32 = 8u;
// MSAA per-sample capture (aa_capture = sample): K slots per sample; every fragment entry runs
// per sample (gpu_util::per_sample_source sets SAMPLE) and the resolve averages the samples.
override SAMPLES: u32 = 1u;
var<private> SAMPLE: i32 = 0;

// `Entry` (what a slot keeps for the effects fold) is generated for the point: kbuffer_rmw/entry.rs.

@group(0) @binding(1) var<storage, read_write> keys: array<atomic<u32>>;
// `entries` (binding 2, split over more bindings where over the largest one) and
// entries_load / entries_store are generated: limits::Split::wgsl.
@group(0) @binding(3) var<storage, read_write> out_image: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> claims: array<atomic<u32>>;

// Window depth → key with "larger is nearer" for both depth conventions; never 0.
fn near_key(d: f32) -> u32 {
    let b = bitcast<u32>(d) & 0x7fffffffu;
    return select(~b, max(b, 1u), camera.near_far.z > 0.5);
}

fn slot_base(clip: vec4<f32>) -> u32 {
    let p = u32(clip.y) * u32(camera.viewport.x) + u32(clip.x);
    return (p * SAMPLES + select(0u, u32(SAMPLE), SAMPLES > 1u)) * K;
}

@fragment
fn fs_keys(in: Varyings) {
    let base = slot_base(in.clip);
    var v = near_key(in.clip.z);
    // Slots only grow and a key reaches the last slot only through all others, so a last slot
    // at least as near as v means K fragments at least as near exist: v cannot enter.
    if atomicLoad(&keys[base + K - 1u]) >= v {
        return;
    }
    for (var i = 0u; i < K; i = i + 1u) {
        let old = atomicMax(&keys[base + i], v);
        if old == 0u {
            return;
        }
        v = min(old, v);
    }
}

// Writes the fragment's payload if its key was captured; false if it was not (the tail's).
fn payload(in: Varyings, ff: bool) -> bool {
    let base = slot_base(in.clip);
    let key = near_key(in.clip.z);
    for (var i = 0u; i < K; i = i + 1u) {
        let s = atomicLoad(&keys[base + i]);
        // Sorted nearest first: past this key (or at the empty tail) it is not captured.
        if s < key {
            return false;
        }
        if s == key && atomicAdd(&claims[base + i], 1u) == 0u {
            entries_store(base + i, make_entry(in, ff));
            return true;
        }
    }
    return false;
}

@fragment
fn fs_payload(in: Varyings, @builtin(front_facing) ff: bool) {
    _ = payload(in, ff);
}

// tail = blend: a fragment that was not captured goes to the blended tail (tail.wgsl).
@fragment
fn fs_payload_tail(in: Varyings, @builtin(front_facing) ff: bool) -> TailOut {
    if payload(in, ff) {
        return tail_none();
    }
    return tail_of(in.color.rgb * in.color.a, in.color.a);
}

// keep = first, one pass instead of keys + payload: the first K fragments to arrive claim the
// pixel's slots in arrival order (claims[base] counts arrivals; atomic, so none is lost).
fn keep_first(in: Varyings, ff: bool) -> bool {
    let base = slot_base(in.clip);
    let i = atomicAdd(&claims[base], 1u);
    if i >= K {
        return false;
    }
    atomicStore(&keys[base + i], near_key(in.clip.z));
    entries_store(base + i, make_entry(in, ff));
    return true;
}

@fragment
fn fs_first(in: Varyings, @builtin(front_facing) ff: bool) {
    _ = keep_first(in, ff);
}

@fragment
fn fs_first_tail(in: Varyings, @builtin(front_facing) ff: bool) -> TailOut {
    if keep_first(in, ff) {
        return tail_none();
    }
    return tail_of(in.color.rgb * in.color.a, in.color.a);
}

// ---- resolve: walk each pixel's slots nearest first through the effects fold ----

// keep = first: the slots hold the first arrivals unsorted; the resolve sorts them.
override KEEP_FIRST: bool = false;
// Largest K the resolve sorts (kbuffer_rmw's MAX_K).
const KMAX: u32 = 64u;

fn fold_kept(p: u32, pixel: vec2<f32>) -> FoldState {
    let base = p * K;
    var s = fold_init_at(pixel);
    if !KEEP_FIRST {
        // keep = nearest: the slots are sorted nearest first.
        for (var i = 0u; i < K; i = i + 1u) {
            let key = atomicLoad(&keys[base + i]);
            if key == 0u {
                break;
            }
            fold_step(&s, entry_frag(entries_load(base + i), key));
        }
        return s;
    }
    // keep = first: sort the slots nearest first (larger key); equal keys keep arrival order.
    var order: array<u32, KMAX>;
    var n = 0u;
    for (var i = 0u; i < K; i = i + 1u) {
        let key = atomicLoad(&keys[base + i]);
        if key == 0u {
            break;
        }
        var j = n;
        loop {
            if j == 0u || atomicLoad(&keys[base + order[j - 1u]]) >= key {
                break;
            }
            order[j] = order[j - 1u];
            j = j - 1u;
        }
        order[j] = i;
        n = n + 1u;
    }
    for (var i = 0u; i < n; i = i + 1u) {
        let j = base + order[i];
        fold_step(&s, entry_frag(entries_load(j), atomicLoad(&keys[j])));
    }
    return s;
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    let pixel = vec2<f32>(id.xy) + 0.5;
    if SAMPLES == 1u {
        // Every image the effect outputs (dof: 3, one after another).
        let s = fold_kept(p, pixel);
        for (var i = 0u; i < fold_image_count(); i = i + 1u) {
            out_image[i * w * h + p] = fold_finish_image(s, i);
        }
        return;
    }
    // Per-sample slots (transparency only): the samples' folds averaged.
    var sum = vec4<f32>(0.0);
    for (var s = 0u; s < SAMPLES; s = s + 1u) {
        sum = sum + fold_finish(fold_kept(p * SAMPLES + s, pixel));
    }
    out_image[p] = sum / f32(SAMPLES);
}

// tail = blend: the kept fragments with the tail behind them (tail/resolve.wgsl).
@compute @workgroup_size(8, 8)
fn resolve_tail(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    out_image[p] = with_tail(id.xy, fold_finish(fold_kept(p, vec2<f32>(id.xy) + 0.5)));
}
