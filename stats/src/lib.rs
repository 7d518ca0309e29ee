//! mfx-stats: the statistics behind a timing you can defend. Pure functions and small state
//! machines over `f64` series: no GPU, no I/O, deterministic for a given seed. Reading order:
//!
//! - [`stop`]: when to stop sampling a point (min samples/time, then a target on the relative
//!   half-width of a distribution-free 95 % CI of the median, or a cap, or drift).
//! - [`warmup`]: when the GPU is warm (frame times and SM clock have stopped moving).
//! - [`throttle`]: which samples to discard because the clock was throttled (nvbench's 75 % rule).
//! - [`canary`]: which samples to discard because a fixed kernel timed after them ran slow (a
//!   GPU state the clocks do not report).
//! - [`summary`]: what is written per point (median, mean, percentiles, bootstrap CIs, Tukey
//!   outliers).
//! - [`mwu`]: the Mann–Whitney U test (scipy's conventions: exact for small untied samples,
//!   normal approximation with tie and continuity correction otherwise).
//! - [`verdict`]: SAME / FASTER / SLOWER / UNSURE between two runs of one point.
//! - [`order`]: seeded interleaving of the repetitions of a group's points.
//!
//! Anchors: NVIDIA nvbench (stopping criterion, throttle rule, `nvbench_compare`'s four
//! verdicts), criterion.rs (bootstrap CIs, significance *and* a noise band before calling a
//! change), Google benchmark (random interleaving of repetitions, Mann–Whitney U).

pub mod canary;
pub mod median_ci;
pub mod mwu;
pub mod order;
pub mod stop;
pub mod summary;
pub mod throttle;
pub mod verdict;
pub mod warmup;

pub use canary::{canary_discard, CanaryBaseline, CANARY_MAX_RATIO};
pub use median_ci::{median_ci_order, median_of_sorted};
pub use mwu::{mann_whitney_u, MwuMethod, MwuResult};
pub use order::{interleave_order, round_order};
pub use stop::{Decision, Sampler, StopReason, StopRule, StopRuleError};
pub use summary::{Summary, BOOTSTRAP_RESAMPLES};
pub use throttle::{discard, THROTTLE_FRACTION};
pub use verdict::{
    compare_intervals, compare_matched, compare_samples, compare_sessions, cycles_k, hold_back,
    median_session, mode_gap, modes, Basis, Comparison, Interval, Matched, Matching, Modes,
    Verdict, VerdictOptions, MODE_MIN_FRAC, MODE_MIN_SEP,
};
pub use warmup::{Warmup, WarmupDecision, WarmupEnd, WarmupRule};
