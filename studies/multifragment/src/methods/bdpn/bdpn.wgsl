// Multi-pass bucket depth peeling (Liu et al., GPU Pro ch. 1 §1.4's loop): the paired passes of
// bdp2.wgsl (MODE 6) repeated until an occlusion query counts no fragment. After pass p (written
// to slots_a when p is even, slots_b when odd) this gather copies its K (near, far) pairs into
// the per-pass store, which the resolve walks once every pass has run.

@compute @workgroup_size(8, 8)
fn gather(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let px = vec2<i32>(id.xy);
    let i = id.y * w + id.x;
    let p = pass_info.index;
    for (var b = 0u; b < K; b++) {
        var vn = slot_a(px, 2u * b);
        var vf = slot_a(px, 2u * b + 1u);
        if p % 2u == 1u {
            vn = slot_b(px, 2u * b);
            vf = slot_b(px, 2u * b + 1u);
        }
        let o = ((i * K + b) * MAX_PASSES + p) * 2u;
        adp_bounds[o] = bitcast<u32>(vn);
        adp_bounds[o + 1u] = bitcast<u32>(vf);
    }
}
