// Replay kernels (Rust `Replay`): a kernel in place of the resolve that walks a pixel's captured
// fragments in primitive (submission) order, the order ordering hardware would deliver.

// work[W_REPLAY .. W_REPLAY + 6]: the replay kernel's counters.
const W_REPLAY: u32 = 10u;

// Pixel p's slots [start, end) after the fill, cut to the allocation.
fn replay_range(p: u32) -> vec2<u32> {
    var start = 0u;
    if p > 0u {
        start = min(offs_load(p - 1u), sizes.capacity);
    }
    return vec2<u32>(start, min(offs_load(p), sizes.capacity));
}

// Sorts the slots [r.x, r.y) by primitive id, in place (insertion sort: the fill leaves them
// close to primitive order; no length cap, unlike the resolve's SORT_MAX). Each triangle covers a
// pixel centre at most once, so the ids are distinct.
fn sort_by_primitive(r: vec2<u32>) {
    for (var i = r.x + 1u; i < r.y; i = i + 1u) {
        let e = frags_load(i);
        let key = e.y & 0x7fffffffu;
        var j = i;
        loop {
            if j == r.x {
                break;
            }
            let prev = frags_load(j - 1u);
            if (prev.y & 0x7fffffffu) <= key {
                break;
            }
            frags_store(j, prev);
            j = j - 1u;
        }
        frags_store(j, e);
    }
}
