// Two-pass bucket depth peeling (Liu et al., GPU Pro ch. 1, BDP2). Pass 1 is uniform BDP with
// the keyed packing: each bucket keeps its farthest fragment (largest in-bucket key). Pass 2
// reads pass 1 and keeps, per bucket, the largest key strictly below it: the next fragment of
// the sub-interval, so a bucket holds two fragments and collisions need three. Fragments of one
// key (within 1/127 of a bucket width) are indistinguishable and merge.

// FX (translucency): pass 1 keeps each bucket's largest view depth, pass 2 the largest below
// it; the facing rides in the depth's lowest bit.

@fragment
fn fs_first(in: Varyings, @builtin(front_facing) ff: bool) -> BucketOut {
    let zr = depth_range(vec2<i32>(in.clip.xy));
    let t = rel_position(in.clip.z, zr);
    let b = uniform_bucket(t);
    if FX {
        return fx_emit(b, in, ff);
    }
    return emit(b, pack_keyed(bucket_key(t, b), in.color), NO_CHANNEL, 0.0);
}

@fragment
fn fs_second(in: Varyings, @builtin(front_facing) ff: bool) -> BucketOut {
    let px = vec2<i32>(in.clip.xy);
    let zr = depth_range(px);
    let t = rel_position(in.clip.z, zr);
    let b = uniform_bucket(t);
    if FX {
        let first = slot_a(px, 2u * b);
        if first == 0.0 || pack_viewz_facing(in.view_z, ff) >= first {
            discard;
        }
        return fx_emit(b, in, ff);
    }
    let k = bucket_key(t, b);
    let first = slot_a(px, b);
    if first == 0.0 || k >= keyed_key(first) {
        discard;
    }
    return emit(b, pack_keyed(k, in.color), NO_CHANNEL, 0.0);
}
