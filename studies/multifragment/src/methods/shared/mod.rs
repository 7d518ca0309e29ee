//! Pieces several methods build on; none of them is a method. (The binding table every study
//! uses is the harness's: [`bench_core::bind`].) A method folder imports from here
//! and from nothing else under `methods` (tested: `tests/method_graph.rs`).
//!
//! | module            | what it is                                                           | used by |
//! |-------------------|----------------------------------------------------------------------|---------|
//! | `axes`            | axes read by more than one method (`max_layers`, `occlusion_stop`, `specialisation`) | peelers, k-buffers |
//! | `bucket`          | bucket peeling's shared capture, packing and CPU twins               | `bdp`, `bdp2`, `adp` |
//! | `counted_capture` | the exact compute A-buffer (count → scan → fill → resolve or replay) | `compute_abuffer`, `mlab_ideal`, `adaptive_ideal` |
//! | `kslots`          | per-pixel k slots, their entries, the atomic k-slot capture          | `kbuffer_rmw`, `kbuffer_atomic`, `hybrid` |
//! | `packing`         | float colour packing (WGSL + twin)                                   | k-buffers, buckets |
//! | `race`            | a race build judged against its ideal-order twin                     | `mlab`, `adaptive` |
//! | `ssaa`            | 2×2 supersampling around any single-sample capture                   | methods offering `ssaa2x2` |
//! | `store`           | storage-buffer capture passes, depth keys, k-nearest judging          | storage methods |
//! | `tail`            | the out-of-order tail (what a bounded capture does not keep)          | k-buffers, `linked_list`, `mlab`, `hybrid` |

pub mod axes;
pub mod bucket;
pub mod counted_capture;
pub mod kslots;
pub mod packing;
pub mod race;
pub mod ssaa;
pub mod store;
pub mod tail;
