// The floor: the least any method that rasterises the scene once must pay.
// floor_depth runs an empty fragment stage (no outputs); floor_depth_vs has none at all;
// floor_opaque writes one constant colour.

@fragment
fn fs_none() {}

@fragment
fn fs_constant() -> @location(0) vec4<f32> {
    return vec4<f32>(0.8, 0.8, 0.8, 1.0);
}
