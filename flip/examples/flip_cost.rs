//! Times LDR-FLIP of one image pair per size (FLIP runs once per image row of a sweep).
//! `cargo run --release -p mfx-flip --example flip_cost [SIZE...]` (default 256 512 1024).

use std::time::Instant;

fn main() {
    let sizes: Vec<u32> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("size in pixels"))
        .collect();
    let sizes = if sizes.is_empty() {
        vec![256, 512, 1024]
    } else {
        sizes
    };
    for s in sizes {
        // A deterministic pseudo-random pair, so FLIP's filters see detail everywhere.
        let mut x: u32 = 0x9e37_79b9;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 24) as u8
        };
        let n = (s * s * 3) as usize;
        let a: Vec<u8> = (0..n).map(|_| next()).collect();
        let b: Vec<u8> = a.iter().map(|&v| v.saturating_add(next() / 16)).collect();
        let t = Instant::now();
        let r = mfx_flip::flip_ldr(&a, &b, s, s, mfx_flip::PPD);
        let flip_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let _ = mfx_flip::magma_rgb8(&r.map);
        let magma_s = t.elapsed().as_secs_f64();
        println!(
            "{s}x{s}: flip_ldr {flip_s:.3} s (mean {:.4}), magma {magma_s:.4} s",
            r.mean
        );
    }
}
