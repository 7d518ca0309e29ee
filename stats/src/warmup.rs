//! When the GPU is warm: run untimed frames until the pass time and the SM clock have stopped
//! moving, instead of a fixed count.
//!
//! After every warm-up frame, in this order:
//! 1. **Steady** — at least `min_frames` frames, and over the last `window` frames
//!    - the frame times' spread `(max − min) / median` is at most `max_spread` (caches, lazy
//!      allocations and pipeline compilation make the first frames slower), and
//!    - when every one of those frames has an SM clock reading, the clocks' spread
//!      `(max − min) / max` is at most `clock_tol` (an idle GPU ramps its clock up over tens of
//!      ms; nvbench warms up once per benchmark and then relies on its throttle rule). A clock
//!      that settles lower after a boost counts as steady once it stops moving: the throttle rule
//!      ([`crate::throttle`]) then judges each timed sample against the default clock.
//! 2. **MaxFrames** / **MaxTime** — a cap (`max_frames` frames or `max_time_ms` of wall time),
//!    so a series that never settles still gets measured (and the caller may flag it).
//!
//! Frames without a clock reading (no NVML) are judged on their times alone.

#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WarmupRule {
    /// Frames always run (3 = the fixed warm-up used before this rule).
    pub min_frames: usize,
    /// Frames the steadiness is judged over.
    pub window: usize,
    /// Largest relative spread of the window's frame times (5 %: well above a warm pass's
    /// 0.1–1 % frame-to-frame noise, below the 10–50 % of a cold first frame).
    pub max_spread: f64,
    /// Largest relative spread of the window's SM clocks (1 %: one or two boost bins).
    pub clock_tol: f64,
    pub max_frames: usize,
    pub max_time_ms: f64,
}

impl Default for WarmupRule {
    fn default() -> Self {
        WarmupRule {
            min_frames: 3,
            window: 3,
            max_spread: 0.05,
            clock_tol: 0.01,
            max_frames: 50,
            max_time_ms: 2000.0,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WarmupEnd {
    Steady,
    MaxFrames,
    MaxTime,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WarmupDecision {
    Continue,
    Done(WarmupEnd),
}

#[derive(Clone, Debug)]
pub struct Warmup {
    rule: WarmupRule,
    times: Vec<f64>,
    clocks: Vec<Option<f64>>,
}

fn spread(v: &[f64], by: f64) -> f64 {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi == lo {
        0.0
    } else if by > 0.0 {
        (hi - lo) / by
    } else {
        f64::INFINITY
    }
}

impl Warmup {
    pub fn new(rule: WarmupRule) -> Warmup {
        Warmup {
            rule,
            times: Vec::new(),
            clocks: Vec::new(),
        }
    }

    /// Records one warm-up frame (its time, the SM clock read after it if known, and the wall
    /// time since warm-up began) and says whether another is needed.
    pub fn push(&mut self, frame_ms: f64, sm_mhz: Option<f64>, elapsed_ms: f64) -> WarmupDecision {
        self.times.push(frame_ms);
        self.clocks.push(sm_mhz.filter(|c| c.is_finite()));
        if self.steady() {
            WarmupDecision::Done(WarmupEnd::Steady)
        } else if self.times.len() >= self.rule.max_frames {
            WarmupDecision::Done(WarmupEnd::MaxFrames)
        } else if elapsed_ms >= self.rule.max_time_ms {
            WarmupDecision::Done(WarmupEnd::MaxTime)
        } else {
            WarmupDecision::Continue
        }
    }

    fn steady(&self) -> bool {
        let r = &self.rule;
        let n = self.times.len();
        let w = r.window.max(1);
        if n < r.min_frames.max(w) {
            return false;
        }
        let times = &self.times[n - w..];
        let mut sorted = times.to_vec();
        sorted.sort_by(f64::total_cmp);
        if spread(times, crate::median_ci::median_of_sorted(&sorted)) > r.max_spread {
            return false;
        }
        let clocks: Option<Vec<f64>> = self.clocks[n - w..].iter().copied().collect();
        match clocks {
            Some(c) => {
                let max = c.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                spread(&c, max) <= r.clock_tol
            }
            None => true,
        }
    }

    /// Warm-up frames run so far (`warmup_frames`).
    pub fn frames(&self) -> usize {
        self.times.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(rule: WarmupRule, times: &[f64], clocks: &[Option<f64>]) -> (usize, WarmupEnd) {
        let mut w = Warmup::new(rule);
        for (i, &t) in times.iter().enumerate() {
            let c = clocks.get(i).copied().flatten();
            if let WarmupDecision::Done(end) = w.push(t, c, i as f64 * 5.0) {
                return (w.frames(), end);
            }
        }
        panic!("still warming after {} frames", times.len());
    }

    #[test]
    fn flat_series_stops_at_min_frames() {
        assert_eq!(
            run(WarmupRule::default(), &[1.0; 10], &[]),
            (3, WarmupEnd::Steady)
        );
        let clocks = [Some(1980.0); 10];
        assert_eq!(
            run(WarmupRule::default(), &[1.0; 10], &clocks),
            (3, WarmupEnd::Steady)
        );
    }

    #[test]
    fn ramping_times_keep_warming() {
        // 10 % faster each frame until frame 8, flat after: the window of 3 is flat from
        // frames 8–10.
        let times: Vec<f64> = (0..20).map(|i| 2.0 * 0.9f64.powi(i.min(7))).collect();
        assert_eq!(
            run(WarmupRule::default(), &times, &[]),
            (10, WarmupEnd::Steady)
        );
    }

    #[test]
    fn rising_clock_keeps_warming_even_with_flat_times() {
        // The clock climbs 345 → 1980 MHz in steps of 300 and then holds: steady once three
        // consecutive readings agree.
        let clocks: Vec<Option<f64>> = (0..20)
            .map(|i| Some((345.0 + 300.0 * i as f64).min(1980.0)))
            .collect();
        // 345 + 300·6 = 2145 → capped: frames 6, 7, 8 (0-based) read 1980.
        assert_eq!(
            run(WarmupRule::default(), &[1.0; 20], &clocks),
            (9, WarmupEnd::Steady)
        );
        // A missing reading in the window means the times alone decide.
        let mut gappy = clocks.clone();
        gappy[2] = None;
        assert_eq!(
            run(WarmupRule::default(), &[1.0; 20], &gappy),
            (3, WarmupEnd::Steady)
        );
    }

    #[test]
    fn a_series_that_never_settles_is_capped() {
        let times: Vec<f64> = (0..100)
            .map(|i| if i % 2 == 0 { 1.0 } else { 1.5 })
            .collect();
        assert_eq!(
            run(WarmupRule::default(), &times, &[]),
            (50, WarmupEnd::MaxFrames)
        );
        let rule = WarmupRule {
            max_time_ms: 100.0,
            ..WarmupRule::default()
        };
        // Frame i is pushed at 5·i ms: frame 20 (the 21st) reaches 100 ms.
        assert_eq!(run(rule, &times, &[]), (21, WarmupEnd::MaxTime));
    }
}
