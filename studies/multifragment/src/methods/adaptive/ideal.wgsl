// Adaptive transparency as ordering hardware would build it: compute_abuffer's exact capture,
// each pixel's fragments sorted into primitive order (replay.wgsl) and inserted one after another
// (adaptive.wgsl), then every fragment shaded through the final nodes, attributes re-derived at
// the pixel centre. Counters: W_REPLAY pixels with more than K fragments, W_REPLAY + 1 removals.

@compute @workgroup_size(8, 8)
fn replay_adaptive(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    let r = replay_range(p);
    sort_by_primitive(r);
    let ndc = pixel_ndc(id.xy);
    var s: Nodes;
    s.n = 0u;
    for (var i = r.x; i < r.y; i = i + 1u) {
        let e = frags_load(i);
        let f = fragment(bitcast<f32>(e.x), e.y, ndc, id.xy);
        _ = at_insert(&s, f.view_z, f.color.a);
    }
    var c = vec3<f32>(0.0);
    for (var i = r.x; i < r.y; i = i + 1u) {
        let e = frags_load(i);
        let f = fragment(bitcast<f32>(e.x), e.y, ndc, id.xy);
        c = c + f.color.rgb * (visibility(&s, f.view_z) * f.color.a);
    }
    out_image[p] = vec4<f32>(c, 1.0 - total_transmittance(&s));
    let n = r.y - r.x;
    if n > K {
        work_add(W_REPLAY, 1u);
        work_add(W_REPLAY + 1u, n - K);
    }
}
