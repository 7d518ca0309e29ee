//! What a k-buffer slot stores (both k-buffers), as WGSL generated for the point: the effect's
//! payload (`specialisation = specialised`, the default) or everything (`uber`), the same rule
//! and `payload` column as `depth_peel`. The key (window depth) is always kept, so a payload
//! never repeats it: transparency stores colour (16 B), translucency the linear view depth with
//! the facing in its sign (4 B: the thesis's "Z" k-buffer), fresnel that and a normal packed in
//! 4 bytes (8 B), csg the object id (4 B), dof colour and view depth (32 B), uber all (32 B).
//!
//! The generated WGSL defines `struct Entry`, `make_entry(in, front_facing)`, `entry_color(e)`
//! (what the blended tail receives; 0 without colour) and `entry_frag(e, key)` (the fold's
//! `Frag`); it needs `packing.wgsl` (the normal packing) and the fold's `Frag`.

use crate::effects::{Effect, EffectConfig, Payload};
use crate::methods::shared::axes::SPECIALISATION;
use bench_core::axes::Point;
use bench_core::study::InvalidPoint;

/// A point's effect and the payload its slots store.
#[derive(Clone, Copy, Debug)]
pub struct SlotConfig {
    pub effect: EffectConfig,
    pub payload: Payload,
}

impl SlotConfig {
    /// Transparency with the colour payload (what `hybrid` and the tail tests run).
    pub fn transparency() -> SlotConfig {
        SlotConfig {
            effect: EffectConfig::default(),
            payload: Payload::RGBA,
        }
    }

    pub fn read(point: &Point) -> std::result::Result<SlotConfig, InvalidPoint> {
        let effect = EffectConfig::from_point(point)?;
        let payload = if point.choice(&SPECIALISATION) == "uber" {
            Payload::ALL
        } else {
            effect.effect.payload()
        };
        Ok(SlotConfig { effect, payload })
    }

    /// Output images (dof: 3, one after another).
    pub fn images(&self) -> u64 {
        self.effect.effect.image_count() as u64
    }

    /// What a point cannot do: the blended tail composites colour behind the kept fragments,
    /// which only transparency's fold output is.
    pub fn check(&self, blends: bool) -> std::result::Result<(), InvalidPoint> {
        if blends && self.effect.effect != Effect::Transparency {
            return Err(InvalidPoint::combination(format!(
                "tail = blend composites the dropped fragments' colour behind the kept ones: it has no meaning for {}",
                self.effect.effect.name()
            )));
        }
        Ok(())
    }

    /// std430 size of the generated `Entry`.
    pub fn entry_bytes(&self) -> u64 {
        let p = self.payload;
        let scalars = 4 * (p.view_z as u64 + p.normal as u64 + p.object_id as u64);
        if p.color {
            16 + scalars.next_multiple_of(16)
        } else {
            scalars
        }
    }

    /// The WGSL of `Entry` and its functions for this payload.
    pub fn wgsl(&self) -> String {
        let p = self.payload;
        let mut fields = Vec::new();
        let mut make = Vec::new();
        if p.color {
            fields.push("color: vec4<f32>");
            make.push("in.color");
        }
        if p.view_z {
            fields.push("sz: f32");
            make.push("select(in.view_z, -in.view_z, ff)");
        }
        if p.normal {
            fields.push("normal: u32");
            make.push("pack_normal_oct(in.normal)");
        }
        if p.object_id {
            fields.push("object_id: u32");
            make.push("in.object_id");
        }
        let pick = |have: bool, yes: &str, no: &str| if have { yes } else { no }.to_string();
        let frag = [
            "key_window_depth(key)".to_string(),
            pick(p.view_z, "abs(e.sz)", "0.0"),
            pick(p.color, "e.color", "vec4<f32>(0.0)"),
            pick(p.normal, "unpack_normal_oct(e.normal)", "vec3<f32>(0.0)"),
            pick(p.object_id, "e.object_id", "0u"),
            pick(p.view_z, "e.sz < 0.0", "true"),
        ]
        .join(", ");
        format!(
            "// Generated (kbuffer_rmw/entry.rs): payload {name}.\n\
             struct Entry {{ {fields} }};\n\
             fn make_entry(in: Varyings, ff: bool) -> Entry {{ return Entry({make}); }}\n\
             fn entry_color(e: Entry) -> vec4<f32> {{ return {color}; }}\n\
             // The key is the window depth's bits, larger = nearer (near_key); this inverts it.\n\
             fn key_window_depth(key: u32) -> f32 {{ return select(bitcast<f32>(~key), bitcast<f32>(key), camera.near_far.z > 0.5); }}\n\
             fn entry_frag(e: Entry, key: u32) -> Frag {{ return Frag({frag}); }}\n",
            name = p.name(),
            fields = fields.join(", "),
            make = make.join(", "),
            color = pick(p.color, "e.color", "vec4<f32>(0.0)"),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entry_sizes_follow_the_payload() {
        let size = |payload| {
            SlotConfig {
                effect: EffectConfig::default(),
                payload,
            }
            .entry_bytes()
        };
        assert_eq!(size(Payload::RGBA), 16);
        assert_eq!(size(Payload::DEPTH), 4, "the thesis's Z payload");
        assert_eq!(size(Payload::DEPTH_NORMAL), 8);
        assert_eq!(size(Payload::DEPTH_ID), 4);
        assert_eq!(size(Payload::RGBA_VIEWZ), 32);
        assert_eq!(size(Payload::ALL), 32);
    }
}
