//! The shading study kinds: `deferred` (the deferred shading paths) and `prepass` (the light
//! pre-pass against full deferred, and the light buffer lit on CPU cores).

pub mod deferred;
pub mod prepass;
