//! `--texture-memory dedicated`: render targets in Vulkan allocations of their own give the
//! same images as wgpu's pool, start zeroed as wgpu's own textures do, and are really taken
//! (not a silent fallback to the pool).

use std::sync::atomic::Ordering;

use bench_core::gpu::{read_texture, Gpu, GpuOptions};
use bench_core::texture_memory::TextureMemory;
use mfx_multifragment::methods;
use mfx_multifragment::testing::{gpu, params, render, scene};
use scenarios::ParamValue;

fn dedicated_gpu() -> Gpu {
    let g = Gpu::new(&GpuOptions {
        texture_memory: Some(TextureMemory::Dedicated),
        ..Default::default()
    })
    .expect("a Vulkan adapter (scripts/setup.sh)");
    assert_eq!(g.texture_memory, TextureMemory::Dedicated);
    g
}

#[test]
fn the_pool_is_the_default_and_takes_no_dedicated_allocation() {
    let g = gpu();
    assert_eq!(g.texture_memory, TextureMemory::Pooled);
    let s = scene("quads", &[("depth_complexity", ParamValue::Int(4))]);
    let _ = render(g, &s, &*methods::get("depth_peel"), &params(&[]), 32, 32);
    assert_eq!(g.dedicated_textures.load(Ordering::Relaxed), 0);
}

#[test]
fn dedicated_render_targets_give_the_pools_images_bit_for_bit() {
    let pooled = gpu();
    let ded = dedicated_gpu();
    let s = scene(
        "shells",
        &[
            ("count", ParamValue::Int(3)),
            ("segments", ParamValue::Int(12)),
        ],
    );
    // Peeling (depth + colour targets), the RMW k-buffer (MRT read-modify-write), WBOIT
    // (float blending) and the per-sample atomic k-buffer under MSAA (multisampled targets).
    let cases = [
        ("depth_peel", params(&[])),
        ("kbuffer_rmw", params(&[("layers", ParamValue::Int(4))])),
        ("wboit", params(&[])),
        (
            "kbuffer_atomic",
            params(&[
                ("layers", ParamValue::Int(8)),
                ("aa", ParamValue::Str("msaa4".into())),
            ]),
        ),
    ];
    for (name, p) in cases {
        let m = methods::get(name);
        let before = ded.dedicated_textures.load(Ordering::Relaxed);
        let (a, _) = render(pooled, &s, &*m, &p, 48, 40);
        let (b, _) = render(&ded, &s, &*m, &p, 48, 40);
        assert!(
            ded.dedicated_textures.load(Ordering::Relaxed) > before,
            "{name}: no render target took the dedicated path"
        );
        let (a, b) = (a.image.expect(name), b.image.expect(name));
        assert_eq!(a.len(), b.len(), "{name}");
        let differ = a
            .iter()
            .zip(&b)
            .filter(|(x, y)| x.map(f32::to_bits) != y.map(f32::to_bits))
            .count();
        assert_eq!(
            differ, 0,
            "{name}: {differ} pixels differ between pooled and dedicated"
        );
    }
}

#[test]
fn a_dedicated_target_starts_zeroed_like_wgpus_own() {
    let ded = dedicated_gpu();
    for (format, bpp, aspect) in [
        (
            wgpu::TextureFormat::Rgba32Float,
            16,
            wgpu::TextureAspect::All,
        ),
        (
            wgpu::TextureFormat::Depth32Float,
            4,
            wgpu::TextureAspect::DepthOnly,
        ),
    ] {
        let before = ded.dedicated_textures.load(Ordering::Relaxed);
        let t = ded.create_texture(&wgpu::TextureDescriptor {
            label: Some("zeroed?"),
            size: wgpu::Extent3d {
                width: 37,
                height: 19,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        assert_eq!(ded.dedicated_textures.load(Ordering::Relaxed), before + 1);
        let bytes = read_texture(&ded, &t, bpp, aspect).unwrap();
        assert_eq!(bytes.len(), 37 * 19 * bpp as usize);
        assert!(bytes.iter().all(|b| *b == 0), "{format:?} not zeroed");
    }
}

#[test]
fn texture_memory_names_parse_and_a_misspelt_one_is_refused() {
    assert_eq!("pooled".parse::<TextureMemory>(), Ok(TextureMemory::Pooled));
    assert_eq!(
        "Dedicated".parse::<TextureMemory>(),
        Ok(TextureMemory::Dedicated)
    );
    let e = "dedicate".parse::<TextureMemory>().unwrap_err();
    assert_eq!((e.what, e.text.as_str()), ("texture memory", "dedicate"));
    assert_eq!(
        e.to_string(),
        "unknown texture memory 'dedicate' (pooled, dedicated)"
    );
}
