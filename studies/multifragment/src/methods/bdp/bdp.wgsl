// Uniform bucket depth peeling (Liu et al., GPU Pro ch. 1, BDP): one geometry pass after the
// depth-range pre-pass. The pixel's [zmin, zmax] is split into K equal sub-intervals; each
// fragment goes to the bucket of its sub-interval (uniform_bucket) and MAX blending keeps one
// value per channel. Single: the bucket keeps one colour (pack_color); two fragments in one
// bucket collide and one survives. Paired ("dual within a bucket"): two channels per bucket keep
// max(126 − key) and max(key), i.e. the nearest and the farthest fragment of the sub-interval
// (the paper's (1 − d, d) pair, on the quantised in-bucket key so the colour rides along).

override PAIRED: bool = false;

@fragment
fn fs_route(in: Varyings, @builtin(front_facing) ff: bool) -> BucketOut {
    let zr = depth_range(vec2<i32>(in.clip.xy));
    let t = rel_position(in.clip.z, zr);
    let b = uniform_bucket(t);
    if FX {
        return fx_emit(b, in, ff);
    }
    if PAIRED {
        let k = bucket_key(t, b);
        return emit(2u * b, pack_keyed(126u - k, in.color), 2u * b + 1u, pack_keyed(k, in.color));
    }
    return emit(b, pack_color(in.color), NO_CHANNEL, 0.0);
}
