// Adaptive transparency (Salvi, Montgomery & Lefohn 2011), the rule of the CPU twin
// `oit::adaptive`: each pixel's visibility function as at most K nodes (depth, transmittance just
// behind it) sorted by depth. A fragment (z, α) multiplies every node behind it by 1 − α and
// inserts (z, vis(z)·(1 − α)) in front of nodes of equal depth; with K + 1 nodes the node whose
// removal changes the area under vis least, (dᵢ − dᵢ₋₁)·(tᵢ₋₁ − tᵢ), is removed (never the
// first; the smallest index wins ties) and its predecessor takes its transmittance.

override K: u32 = 4u;
// Largest K (the layers axis' maximum); arrays hold one node more during an insertion.
const KMAX: u32 = 16u;

struct Nodes {
    z: array<f32, 17>,
    t: array<f32, 17>,
    n: u32,
};

// Inserts (z, α); returns the first node index it changed.
fn at_insert(s: ptr<function, Nodes>, z: f32, alpha: f32) -> u32 {
    let t = 1.0 - alpha;
    let n = (*s).n;
    var at = 0u;
    loop {
        if at == n || !((*s).z[at] < z) {
            break;
        }
        at = at + 1u;
    }
    var before = 1.0;
    if at > 0u {
        before = (*s).t[at - 1u];
    }
    for (var i = n; i > at; i = i - 1u) {
        (*s).z[i] = (*s).z[i - 1u];
        (*s).t[i] = (*s).t[i - 1u] * t;
    }
    (*s).z[at] = z;
    (*s).t[at] = before * t;
    (*s).n = n + 1u;
    var first = at;
    if n + 1u > K {
        // k = 1 keeps the single node: the second merges into the first.
        var best = 1u;
        var best_err = 0.0;
        for (var i = 1u; i <= n; i = i + 1u) {
            let err = ((*s).z[i] - (*s).z[i - 1u]) * ((*s).t[i - 1u] - (*s).t[i]);
            if i == 1u || err < best_err {
                best = i;
                best_err = err;
            }
        }
        (*s).t[best - 1u] = (*s).t[best];
        for (var i = best; i < n; i = i + 1u) {
            (*s).z[i] = (*s).z[i + 1u];
            (*s).t[i] = (*s).t[i + 1u];
        }
        (*s).n = n;
        first = min(first, best - 1u);
    }
    return first;
}

// vis(z): the transmittance of the last node strictly in front of z, 1 before the first.
fn visibility(s: ptr<function, Nodes>, z: f32) -> f32 {
    var v = 1.0;
    for (var i = 0u; i < (*s).n; i = i + 1u) {
        if !((*s).z[i] < z) {
            break;
        }
        v = (*s).t[i];
    }
    return v;
}

fn total_transmittance(s: ptr<function, Nodes>) -> f32 {
    if (*s).n == 0u {
        return 1.0;
    }
    return (*s).t[(*s).n - 1u];
}
