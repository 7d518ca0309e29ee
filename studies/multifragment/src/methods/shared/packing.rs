//! Colour packed into one f32, as the bucket methods (BDP) need, and why the obvious packing
//! fails. CPU twin of `packing.wgsl` (prepend that file to a method's WGSL to use it on the GPU).
//!
//! The naive packing reinterprets `pack4x8unorm` bits as a float. The alpha byte lands on the
//! sign and exponent: alpha ≥ 0.5 gives a negative float (MAX blending against a cleared 0
//! discards it), alpha & 0x7F = 0x7F with blue ≥ 0.5 gives NaN/Inf (MAX blending's result is
//! undefined, NaNs may be canonicalised), alpha & 0x7F = 0 with blue < 0.5 gives a denormal
//! (flush-to-zero destroys it). [`pack_rgba_f32`] keeps every packed value a positive, normal,
//! finite float ordered like its 30-bit code (RGB 8 bits, alpha 6 bits), so MAX blending and
//! flush-to-zero leave it intact; the price is alpha quantised to 1/63.

/// WGSL twin of this module.
pub const PACKING_WGSL: &str = include_str!("packing.wgsl");

/// One exponent step: adding it moves code 0 past the denormals.
pub const PACK_NORMAL_OFFSET: u32 = 0x0080_0000;

fn unorm8(x: f32) -> u32 {
    (x.clamp(0.0, 1.0) * 255.0).round() as u32
}

/// WGSL `pack4x8unorm` reinterpreted as f32 bits (the failure case).
pub fn pack_rgba_f32_naive(c: [f32; 4]) -> u32 {
    unorm8(c[0]) | unorm8(c[1]) << 8 | unorm8(c[2]) << 16 | unorm8(c[3]) << 24
}

/// The fix: f32 bits of a positive normal float; RGB 8 bits, alpha 6 bits.
pub fn pack_rgba_f32(c: [f32; 4]) -> u32 {
    let a = (c[3].clamp(0.0, 1.0) * 63.0).round() as u32;
    (unorm8(c[0]) | unorm8(c[1]) << 8 | unorm8(c[2]) << 16 | a << 24) + PACK_NORMAL_OFFSET
}

pub fn unpack_rgba_f32(bits: u32) -> [f32; 4] {
    let q = bits.wrapping_sub(PACK_NORMAL_OFFSET);
    [
        (q & 0xFF) as f32 / 255.0,
        ((q >> 8) & 0xFF) as f32 / 255.0,
        ((q >> 16) & 0xFF) as f32 / 255.0,
        ((q >> 24) & 0x3F) as f32 / 63.0,
    ]
}

/// A unit normal as a 30-bit octahedral code, 15 bits per coordinate (WGSL `pack_normal_oct`;
/// the chapter's 4-byte normal). Angular error < 2e-4 rad; a zero normal decodes to +z.
pub fn pack_normal_oct(n: [f32; 3]) -> u32 {
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    let (mut x, mut y) = if l1 > 0.0 {
        (n[0] / l1, n[1] / l1)
    } else {
        (0.0, 0.0)
    };
    if n[2] < 0.0 {
        let s = |v: f32| if v >= 0.0 { 1.0 } else { -1.0 };
        (x, y) = ((1.0 - y.abs()) * s(x), (1.0 - x.abs()) * s(y));
    }
    let q = |v: f32| ((v.clamp(-1.0, 1.0) * 0.5 + 0.5) * 32767.0).round() as u32;
    q(x) | q(y) << 15
}

pub fn unpack_normal_oct(code: u32) -> [f32; 3] {
    let p = |c: u32| (c & 0x7fff) as f32 / 32767.0 * 2.0 - 1.0;
    let (mut x, mut y) = (p(code), p(code >> 15));
    let z = 1.0 - x.abs() - y.abs();
    let t = (-z).max(0.0);
    x += if x >= 0.0 { -t } else { t };
    y += if y >= 0.0 { -t } else { t };
    let l = (x * x + y * y + z * z).sqrt();
    [x / l, y / l, z / l]
}

/// What MAX blending against a cleared 0 and flush-to-zero can do to a packed float.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hazard {
    Negative,
    NaN,
    Infinite,
    Denormal,
}

/// The hazard of f32 bit pattern `bits`, if any.
pub fn hazard(bits: u32) -> Option<Hazard> {
    let f = f32::from_bits(bits);
    if f.is_nan() {
        Some(Hazard::NaN)
    } else if f.is_infinite() {
        Some(Hazard::Infinite)
    } else if f.is_sign_negative() && f != 0.0 {
        Some(Hazard::Negative)
    } else if f.is_subnormal() {
        Some(Hazard::Denormal)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing;

    /// Every colour of a 16-step grid per channel (65536 colours), corners included.
    fn grid() -> Vec<[f32; 4]> {
        let s = |i: u32| i as f32 / 15.0;
        let mut v = Vec::new();
        for r in 0..16 {
            for g in 0..16 {
                for b in 0..16 {
                    for a in 0..16 {
                        v.push([s(r), s(g), s(b), s(a)]);
                    }
                }
            }
        }
        // Exactly the patterns named in the docs: opaque with blue ≥ 0.5 (NaN) and alpha 0
        // with blue < 0.5 (denormal).
        v.push([0.2, 0.4, 0.6, 1.0]);
        v.push([0.2, 0.4, 0.2, 0.0]);
        v
    }

    #[test]
    fn naive_packing_makes_nan_negative_and_denormal_floats_the_fix_makes_none() {
        let colors = grid();
        let count = |h: Hazard| {
            colors
                .iter()
                .filter(|c| hazard(pack_rgba_f32_naive(**c)) == Some(h))
                .count()
        };
        assert!(count(Hazard::Negative) > 0, "alpha ≥ 0.5 sets the sign bit");
        assert!(count(Hazard::NaN) > 0, "opaque with blue ≥ 0.5 is NaN");
        assert!(
            count(Hazard::Denormal) > 0,
            "alpha 0 with blue < 0.5 is denormal"
        );
        assert_eq!(
            hazard(pack_rgba_f32_naive([0.2, 0.4, 0.6, 1.0])),
            Some(Hazard::NaN)
        );
        for c in &colors {
            let bits = pack_rgba_f32(*c);
            assert_eq!(hazard(bits), None, "{c:?} packs to a hazard {:08x}", bits);
            let u = unpack_rgba_f32(bits);
            for k in 0..3 {
                assert!((u[k] - c[k]).abs() <= 0.5 / 255.0 + 1e-6, "{c:?} → {u:?}");
            }
            assert!((u[3] - c[3]).abs() <= 0.5 / 63.0 + 1e-6, "{c:?} → {u:?}");
        }
        // Ordered like the code: a MAX of packed values is the packed value of the larger code.
        let (lo, hi) = (
            pack_rgba_f32([0.1, 0.1, 0.1, 0.2]),
            pack_rgba_f32([0.1, 0.1, 0.1, 0.9]),
        );
        assert!(f32::from_bits(lo) < f32::from_bits(hi));
    }

    /// GPU: both packings in WGSL, each value passed through max(0, x) as MAX blending against a
    /// cleared 0 does; the bits must equal the CPU twin's, and the fixed packing must survive.
    #[test]
    fn gpu_packing_matches_cpu_and_only_the_fix_survives_max_blending() {
        let gpu = testing::gpu();
        let colors = grid();
        let n = colors.len() as u32;
        let src = format!(
            "{PACKING_WGSL}
@group(0) @binding(0) var<storage, read> colors: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<u32>>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {{
    if id.x >= arrayLength(&colors) {{ return; }}
    let c = colors[id.x];
    let naive = pack_rgba_f32_naive(c);
    let safe = pack_rgba_f32(c);
    out[id.x] = vec4<u32>(pack4x8unorm(c), bitcast<u32>(safe), bitcast<u32>(max(0.0, naive)), bitcast<u32>(max(0.0, safe)));
}}"
        );
        let d = &gpu.device;
        use wgpu::util::DeviceExt;
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("packing test"),
            source: wgpu::ShaderSource::Wgsl(src.into()),
        });
        let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: None,
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let input = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytemuck::cast_slice(&colors),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let output = d.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: n as u64 * 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: input.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: output.as_entire_binding(),
                },
            ],
        });
        let mut enc = d.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(n.div_ceil(64), 1, 1);
        }
        gpu.queue.submit([enc.finish()]);
        let out: Vec<[u32; 4]> = bench_core::gpu_util::read_vec(gpu, &output, n as usize).unwrap();
        let mut destroyed = 0;
        for (c, o) in colors.iter().zip(&out) {
            assert_eq!(
                o[0],
                pack_rgba_f32_naive(*c),
                "{c:?}: pack4x8unorm differs from the CPU twin"
            );
            assert_eq!(
                o[1],
                pack_rgba_f32(*c),
                "{c:?}: fixed packing differs from the CPU twin"
            );
            assert_eq!(
                o[3], o[1],
                "{c:?}: the fixed packing must survive max(0, x)"
            );
            destroyed += (o[2] != o[0]) as u32;
        }
        // IEEE max(0, negative) = 0: every colour with alpha ≥ 0.5 is lost on any GPU.
        assert!(
            destroyed > 0,
            "naive packing survived max(0, x) everywhere: the case shows nothing"
        );
    }

    #[test]
    fn normal_oct_packing_keeps_direction_within_2e_4_and_stays_a_normal_float() {
        // 15-bit octahedral steps are 2/32767 of the octahedron: half a step in each coordinate,
        // stretched up to ~2× by the projection, stays below 2e-4 rad.
        let mut worst = 0.0f64;
        for i in 0..2000 {
            let (a, b) = (i as f32 * 0.7713, i as f32 * 0.31 - 300.0);
            let n = [a.cos() * b.cos(), a.sin() * b.cos(), b.sin()];
            let code = pack_normal_oct(n);
            assert!(code < 1 << 30, "30-bit code");
            assert_eq!(hazard(code + PACK_NORMAL_OFFSET), None);
            let m = unpack_normal_oct(code);
            // The angle in f64 by atan2(|n × m|, n · m): acos near 1 in f32 is noise (~3e-4).
            let (a, b) = (
                glam::DVec3::from(n.map(f64::from)).normalize(),
                glam::DVec3::from(m.map(f64::from)),
            );
            worst = worst.max(a.cross(b).length().atan2(a.dot(b)));
        }
        assert!(worst < 2e-4, "angular error {worst}");
    }
}
