// Two-pass bucket depth peeling (Liu et al., GPU Pro ch. 1, BDP2).
//
// MODE 2 (bucket_pairing unset or single: mfx's two-pass of single buckets). Pass 1 is uniform
// BDP with the keyed packing: each bucket keeps its farthest fragment (largest in-bucket key).
// Pass 2 reads pass 1 and keeps, per bucket, the largest key strictly below it: the next fragment
// of the sub-interval, so a bucket holds two fragments and collisions need three. Fragments of one
// key (within 1/127 of a bucket width) are indistinguishable and merge.
//
// MODE 4 (bucket_pairing = paired: §1.4 as the chapter describes it). §1.4: "In the second
// geometry pass, we allocate a new bucket array for each pixel and the bucket array captured in
// the first pass will be taken as eight input textures. For a fragment within the kth
// subinterval, if its depth value d_f satisfies condition d_f ≥ dmax_k^1 or d_f ≤ dmin_k^2 [read:
// dmin_k^1, the first pass's minimum], it must have been captured in the previous pass, thus can
// be simply discarded. When the second pass is over, the second minimal and maximum depth values
// dmin_k^2 and dmax_k^2 in the kth subinterval can be retrieved from the kth pair of buckets
// similarly." Pass 1 is BDP paired (channels 2k, 2k + 1 keep max(126 − key) and max(key): the
// nearest and farthest of the sub-interval, colour riding on the in-bucket key); pass 2 keeps the
// nearest and farthest strictly between them, so a bucket holds four fragments in order
// dmin¹ ≤ dmin² ≤ dmax² ≤ dmax¹.

// MODE 6 (bdpn, §1.4's loop) runs these two entry points: fs_first once, then fs_second every
// pass with the previous pass's pairs bound as slots_a.
//
// FX (translucency, MODE 2 only): pass 1 keeps each bucket's largest view depth, pass 2 the
// largest below it; the facing rides in the depth's lowest bit.

fn paired_emit(b: u32, k: u32, c: vec4<f32>) -> BucketOut {
    return emit(2u * b, pack_keyed(126u - k, c), 2u * b + 1u, pack_keyed(k, c));
}

@fragment
fn fs_first(in: Varyings, @builtin(front_facing) ff: bool) -> BucketOut {
    let zr = depth_range(vec2<i32>(in.clip.xy));
    let t = rel_position(in.clip.z, zr);
    let b = uniform_bucket(t);
    if FX {
        return fx_emit(b, in, ff);
    }
    if MODE == 4u || MODE == 6u {
        return paired_emit(b, bucket_key(t, b), in.color);
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
    if MODE == 4u || MODE == 6u {
        let near = slot_a(px, 2u * b);
        // Captured by pass 1: at or outside its (nearest, farthest) keys.
        if near == 0.0 || k <= 126u - keyed_key(near) || k >= keyed_key(slot_a(px, 2u * b + 1u)) {
            discard;
        }
        return paired_emit(b, k, in.color);
    }
    let first = slot_a(px, b);
    if first == 0.0 || k >= keyed_key(first) {
        discard;
    }
    return emit(b, pack_keyed(k, in.color), NO_CHANNEL, 0.0);
}
