//! Axes several methods read: the peelers' pass bound and early stop (`depth_peel`,
//! `dual_peel`) and the payload specialisation (`depth_peel` and the k-buffers).

use bench_core::axes::Axis;
use bench_core::record::cols;

/// Peeling passes at most.
pub const MAX_LAYERS: Axis = Axis::int(
    cols::MAX_LAYERS,
    "peeling passes at most (occlusion_stop may end sooner)",
    64,
    1,
    4096,
);
/// Stop peeling at the first empty pass.
pub const OCCLUSION_STOP: Axis = Axis::bool(
    cols::OCCLUSION_STOP,
    "stop at the first pass an occlusion query finds empty (a CPU round trip per pass)",
    true,
);
/// Which payload the slots or layers store.
pub const SPECIALISATION: Axis = Axis::choice(
    cols::SPECIALISATION,
    "specialised: only the effect's payload is fetched, stored and read; uber: everything",
    "specialised",
    &["specialised", "uber"],
);
