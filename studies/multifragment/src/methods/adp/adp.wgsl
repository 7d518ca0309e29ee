// Adaptive bucket depth peeling (Liu et al., GPU Pro ch. 1, ADP). After the depth-range
// pre-pass, a histogram pass sets bit adp_bin(t) of a per-pixel HIST_BINS-bit occupancy mask.
// The paper ORs 32-bit words into 8 RGBA32UI targets with the logic-op blend; wgpu has no logic
// ops, so the bits are set with atomicOr on a storage buffer from the fragment shader. The
// equalisation pass lists the occupied bins nearest first and gives bucket j of pass p the
// (pK + j)-th occupied bin, so each bucket holds exactly one occupied bin; the routing pass sends
// each fragment to the bucket of its bin (binary search of the bounds). Pixels with more than K
// occupied bins need further passes of K. Fragments sharing a bin merge (a collision).

@fragment
fn fs_hist(in: Varyings) -> @location(0) vec4<f32> {
    let zr = depth_range(vec2<i32>(in.clip.xy));
    let bin = adp_bin(rel_position(in.clip.z, zr));
    let i = pixel_index(in.clip.xy);
    atomicOr(&hist[i * (HIST_BINS / 32u) + bin / 32u], 1u << (bin % 32u));
    return vec4<f32>(0.0);
}

// CPU twin: bucket::adp_equalise.
@compute @workgroup_size(8, 8)
fn equalise(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u32(camera.viewport.x);
    let h = u32(camera.viewport.y);
    if id.x >= w || id.y >= h {
        return;
    }
    let i = id.y * w + id.x;
    let words = HIST_BINS / 32u;
    let first = pass_info.index * K;
    var rank = 0u;
    var j = 0u;
    for (var wi = 0u; wi < words; wi++) {
        var bits = atomicLoad(&hist[i * words + wi]);
        let c = countOneBits(bits);
        if j >= K || rank + c <= first {
            rank += c;
            continue;
        }
        while bits != 0u {
            let bit = firstTrailingBit(bits);
            bits &= bits - 1u;
            if rank >= first && j < K {
                adp_bounds[i * K + j] = wi * 32u + bit;
                j += 1u;
            }
            rank += 1u;
        }
    }
    for (; j < K; j++) {
        adp_bounds[i * K + j] = 0xffffffffu;
    }
    // rank is now the pixel's occupied-bin count: the frame reads the maximum to plan passes.
    atomicMax(&occupied_max[0], rank);
}

@fragment
fn fs_route(in: Varyings, @builtin(front_facing) ff: bool) -> BucketOut {
    let zr = depth_range(vec2<i32>(in.clip.xy));
    let bin = adp_bin(rel_position(in.clip.z, zr));
    let base = pixel_index(in.clip.xy) * K;
    var lo = 0u;
    var hi = K;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if adp_bounds[base + mid] < bin {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    // Bins of earlier or later passes have no bucket in this one.
    if lo >= K || adp_bounds[base + lo] != bin {
        discard;
    }
    if FX {
        return fx_emit(lo, in, ff);
    }
    // MODE 5 (bucket_pairing = paired), §1.5: "we can further reduce collisions by binding the
    // buckets into pairs and performing dual depth peeling within each non-empty subinterval":
    // the bin's pair keeps max(126 − key) and max(key), its nearest and farthest fragment.
    if MODE == 5u {
        let k = bin_key(rel_position(in.clip.z, zr), bin);
        return emit(2u * lo, pack_keyed(126u - k, in.color), 2u * lo + 1u, pack_keyed(k, in.color));
    }
    return emit(lo, pack_color(in.color), NO_CHANNEL, 0.0);
}
