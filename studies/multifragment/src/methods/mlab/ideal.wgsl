// MLAB as ordering hardware would build it: compute_abuffer's exact capture, each pixel's
// fragments sorted into primitive order (replay.wgsl) and inserted one after another
// (mlab.wgsl), attributes re-derived at the pixel centre; the tail (TAIL_MODE 2) summed in
// registers. Counters: W_REPLAY pixels with more than K fragments, W_REPLAY + 1 fragments
// beyond K (merged, dropped or tailed).

@compute @workgroup_size(8, 8)
fn replay_mlab(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let p = id.y * w + id.x;
    let r = replay_range(p);
    sort_by_primitive(r);
    let ndc = pixel_ndc(id.xy);
    var s: Blend;
    s.n = 0u;
    var sums = vec4<f32>(0.0);
    var trans = 1.0;
    var count = 0.0;
    for (var i = r.x; i < r.y; i = i + 1u) {
        let e = frags_load(i);
        let f = fragment(bitcast<f32>(e.x), e.y, ndc, id.xy);
        let ins = mlab_insert(&s, f.view_z, f.color);
        if ins.fell {
            sums = sums + vec4<f32>(ins.rgb, ins.a);
            trans = trans * (1.0 - ins.a);
            count = count + 1.0;
        }
    }
    let c = mlab_resolve(&s);
    var o = vec4<f32>(c.rgb, 1.0 - c.w);
    if TAIL_MODE == 2u {
        o = tail_behind(c.rgb, c.w, sums, trans, count, false);
    }
    out_image[p] = o;
    let n = r.y - r.x;
    if n > K {
        work_add(W_REPLAY, 1u);
        work_add(W_REPLAY + 1u, n - K);
    }
}
