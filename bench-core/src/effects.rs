//! Effects computed from captured fragments, and their CPU references. `transparency`
//! (front-to-back under-compositing) is the default every method supplies.

use crate::methods::Expected;
use crate::reference::FragmentLists;

/// Known effect names (the `effect` CSV column).
pub const EFFECTS: &[&str] = &["transparency"];

/// The reference image of `effect` for a capture judged against `expected`.
pub fn reference_image(
    effect: &str,
    lists: &FragmentLists,
    expected: Expected,
) -> Option<Vec<[f64; 4]>> {
    match effect {
        "transparency" => Some(match expected {
            Expected::All => lists.composite(),
            Expected::FirstK(k) => lists.composite_first(k as usize),
        }),
        _ => None,
    }
}
