//! Axis ranges and ticks. Log axes get decades or 1-2-5 ticks, linear axes 1-2-5 steps; labels are
//! the shortest round numbers that tell every tick apart (never two ticks with one label).

/// Padding beyond the data on each side: a fraction of the span (linear) or of the decades
/// spanned (log), so no marker sits on the frame. Well inside the layout check's decade rule.
const PAD: f64 = 0.05;

/// Axis range for data in `[lo, hi]` (finite; both > 0 on a log axis). A single value gets a
/// window around it (±50 % on a linear axis, ×/÷ 1.5 on a log one).
pub fn axis_range(lo: f64, hi: f64, log: bool) -> (f64, f64) {
    if log {
        let (a, b) = (lo.log10(), hi.log10());
        let pad = if b - a < 1e-9 {
            1.5f64.log10()
        } else {
            ((b - a) * PAD).clamp(0.03, 0.3)
        };
        (10f64.powf(a - pad), 10f64.powf(b + pad))
    } else {
        let span = hi - lo;
        if span <= 1e-12 * hi.abs().max(lo.abs()) || span == 0.0 {
            let w = if hi == 0.0 { 1.0 } else { hi.abs() * 0.5 };
            return (lo - w, hi + w);
        }
        (lo - span * PAD, hi + span * PAD)
    }
}

/// A linear axis that must start at zero (bar lengths): `[0, hi]` padded above only (or the
/// mirror image for negative data).
pub fn zero_based_range(lo: f64, hi: f64) -> (f64, f64) {
    let lo = lo.min(0.0);
    let hi = hi.max(0.0);
    let span = if hi - lo > 0.0 { hi - lo } else { 1.0 };
    (
        if lo < 0.0 { lo - span * PAD } else { 0.0 },
        if hi > 0.0 { hi + span * PAD } else { 0.0 },
    )
}

/// The 1-2-5 step nearest to `raw` (geometric midpoints between 1, 2, 5 and 10).
fn nice_step(raw: f64) -> f64 {
    let e = raw.log10().floor();
    let m = raw / 10f64.powf(e);
    let f = if m < 1.42 {
        1.0
    } else if m < 3.17 {
        2.0
    } else if m < 7.08 {
        5.0
    } else {
        10.0
    };
    f * 10f64.powf(e)
}

/// Ticks at multiples of a 1-2-5 step, about `target` of them, inside `[lo, hi]`.
pub fn linear_ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return vec![lo];
    }
    let step = nice_step((hi - lo) / target.max(2) as f64);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last)
        .map(|i| {
            let v = i as f64 * step;
            // Rebuilt from the step's own digits so 0.1 × 3 prints as 0.3, and never -0.
            let v = format!("{:.12e}", v).parse::<f64>().unwrap_or(v);
            if v == 0.0 {
                0.0
            } else {
                v
            }
        })
        .collect()
}

/// Ticks of a log axis over `[lo, hi]` (> 0): 1-2-5 ticks when that gives three to nine of
/// them, else decades (every n-th beyond eight), else (a range narrower than about half a
/// decade) round linear ticks.
pub fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let (a, b) = (lo.log10(), hi.log10());
    let mut v = Vec::new();
    for d in (a.floor() as i32 - 1)..=(b.ceil() as i32) {
        for m in [1.0, 2.0, 5.0] {
            let t = m * pow10(d);
            if t >= lo * (1.0 - 1e-12) && t <= hi * (1.0 + 1e-12) {
                v.push(t);
            }
        }
    }
    if (3..=9).contains(&v.len()) {
        return v;
    }
    let decades: Vec<i32> = ((a - 1e-9).ceil() as i32..=(b + 1e-9).floor() as i32).collect();
    if decades.len() >= 3 {
        let every = decades.len().div_ceil(8);
        // Keep the decades that are multiples of `every` so ticks stay aligned across charts.
        return decades
            .iter()
            .filter(|d| d.rem_euclid(every as i32) == 0)
            .map(|d| pow10(*d))
            .collect();
    }
    let mut best = Vec::new();
    for target in [4, 6, 10] {
        best = linear_ticks(lo, hi, target)
            .into_iter()
            .filter(|t| *t > 0.0)
            .collect();
        if best.len() >= 3 {
            break;
        }
    }
    best
}

/// 10^d exactly as written (10f64.powi drifts for negative d: 1e-7 would not print as 1e-7).
fn pow10(d: i32) -> f64 {
    format!("1e{d}").parse().expect("a power of ten")
}

/// Labels for tick values: plain decimals when every tick lies in [0.001, 100000), else
/// mantissa-exponent ("2e-6", "6.5e-6"); as few digits as keep every label distinct and equal to
/// its tick (round ticks need one or two).
pub fn tick_labels(values: &[f64]) -> Vec<String> {
    let plain = values
        .iter()
        .all(|v| *v == 0.0 || (1e-3..1e5).contains(&v.abs()));
    for digits in 0..=12 {
        let labels: Vec<String> = values
            .iter()
            .map(|v| {
                if *v == 0.0 {
                    "0".to_string()
                } else if plain {
                    trim(format!("{v:.digits$}"))
                } else {
                    let s = format!("{v:.digits$e}");
                    let (m, e) = s.split_once('e').expect("exponent form");
                    format!("{}e{e}", trim(m.to_string()))
                }
            })
            .collect();
        let exact = labels.iter().zip(values).all(|(l, v)| {
            l.parse::<f64>()
                .is_ok_and(|p| (p - v).abs() <= 1e-9 * v.abs().max(1e-300))
        });
        let distinct = labels
            .iter()
            .enumerate()
            .all(|(i, l)| !labels[..i].contains(l));
        if exact && distinct {
            return labels;
        }
    }
    values.iter().map(|v| format!("{v:e}")).collect()
}

fn trim(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(lo: f64, hi: f64, log: bool) -> Vec<String> {
        let (a, b) = axis_range(lo, hi, log);
        let t = if log {
            log_ticks(a, b)
        } else {
            linear_ticks(a, b, 6)
        };
        tick_labels(&t)
    }

    /// A label is round when its mantissa has at most two significant digits (1-2-5 ticks have
    /// one; a narrow linear range needs two, e.g. 6.5e-6 next to 6.6e-6).
    fn round(l: &str) -> bool {
        let m = l.split('e').next().unwrap();
        let digits: String = m.chars().filter(|c| c.is_ascii_digit()).collect();
        digits.trim_start_matches('0').trim_end_matches('0').len() <= 2
    }

    #[test]
    fn log_ticks_are_decades_or_1_2_5_and_round() {
        // Speedups 0.8–1200: decades (3+ of them), no 1.3 / 1.6 / 2.5 / 3.2 / 15849.
        assert_eq!(labels(0.8, 1200.0, true), ["1", "10", "100", "1000"]);
        // 2–40 ms: 1-2-5 within one and a bit decades.
        assert_eq!(labels(2.0, 40.0, true), ["2", "5", "10", "20"]);
        // Data at exactly 8 is labelled by round ticks around it, never "7.9".
        let l = labels(3.0, 8.0, true);
        assert!(
            l.iter().all(|l| round(l)) && !l.contains(&"7.9".to_string()),
            "{l:?}"
        );
        // Twelve decades: every other decade, no more than eight ticks.
        let l = labels(1e-9, 1e3, true);
        assert!(l.len() <= 8 && l.contains(&"1e-8".to_string()), "{l:?}");
        for (lo, hi) in [
            (1e-7, 0.03),
            (0.5, 3.0),
            (1e-3, 2.0),
            (40.0, 60.0),
            (6.45e-6, 6.55e-6),
        ] {
            let l = labels(lo, hi, true);
            assert!(l.len() >= 2, "{lo}..{hi}: {l:?}");
            assert!(l.iter().all(|l| round(l)), "{lo}..{hi}: {l:?}");
        }
    }

    #[test]
    fn tick_labels_never_repeat() {
        // The chart whose seven ticks all read "6.5e-6".
        for (lo, hi, log) in [
            (6.49e-6, 6.51e-6, true),
            (6.49e-6, 6.51e-6, false),
            (1.0, 1.0001, false),
            (0.0, 3e-7, false),
            (99990.0, 100010.0, false),
        ] {
            let l = labels(lo, hi, log);
            for (i, a) in l.iter().enumerate() {
                assert!(!l[..i].contains(a), "{lo}..{hi} log={log}: {l:?}");
            }
            assert!(l.len() >= 2, "{lo}..{hi}: {l:?}");
        }
    }

    #[test]
    fn linear_ticks_are_1_2_5_steps_and_labels_exact() {
        assert_eq!(
            tick_labels(&linear_ticks(0.0, 1.0, 5)),
            ["0", "0.2", "0.4", "0.6", "0.8", "1"]
        );
        assert_eq!(
            tick_labels(&linear_ticks(-3.0, 3.0, 6)),
            ["-3", "-2", "-1", "0", "1", "2", "3"]
        );
        assert_eq!(tick_labels(&[1e-6, 2e-6, 5e-6]), ["1e-6", "2e-6", "5e-6"]);
        assert_eq!(
            tick_labels(&[0.001, 0.01, 0.1, 1.0]),
            ["0.001", "0.01", "0.1", "1"]
        );
    }

    #[test]
    fn ranges_hold_the_data_with_little_padding() {
        let (a, b) = axis_range(2.0, 358.0, true);
        assert!(a < 2.0 && a > 1.0 && b > 358.0 && b < 600.0, "{a} {b}");
        let (a, b) = axis_range(10.0, 20.0, false);
        assert!(a < 10.0 && a > 9.0 && b > 20.0 && b < 21.0);
        assert_eq!(zero_based_range(3.0, 10.0), (0.0, 10.5));
        let (a, b) = axis_range(5.0, 5.0, false);
        assert!(a < 5.0 && b > 5.0);
    }
}
