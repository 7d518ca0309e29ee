//! The multi-fragment study kinds: `methods` (every method on every scene, timed and judged)
//! and `stability` (the same points on stiff inputs, with the case and its stiffness).

pub mod methods;
pub mod stability;
