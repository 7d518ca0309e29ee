// tail = blend for linked lists (appended with methods/shared/tail/tail.wgsl): the fragments that found
// their pool full were blended into the tail targets by the append pass; those the resolve's sort
// dropped were summed in `sort_tail_*`. Both join the tail composited behind the sorted list.

@group(2) @binding(0) var tail_sums: texture_2d<f32>;
@group(2) @binding(1) var tail_trans: texture_2d<f32>;
@group(2) @binding(2) var tail_count: texture_2d<f32>;

@compute @workgroup_size(8, 8)
fn resolve_tail(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let kept = fold_finish(resolve_lists(id.xy));
    let xy = vec2<i32>(id.xy);
    let sums = textureLoad(tail_sums, xy, 0) + sort_tail_sums;
    let trans = textureLoad(tail_trans, xy, 0).x * sort_tail_trans;
    let count = textureLoad(tail_count, xy, 0).x + sort_tail_count;
    out_image[id.y * w + id.x] = tail_behind(kept.rgb, 1.0 - kept.a, sums, trans, count, false);
}
