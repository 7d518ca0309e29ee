//! The multi-fragment study kinds: `methods` (every method on every scene, timed and judged)
//! `stability` (the same points on stiff inputs, with the case and its stiffness) and `views`
//! (the same points along each scene's camera path: time, error, flicker and popping per view).

pub mod methods;
pub mod stability;
pub mod views;
