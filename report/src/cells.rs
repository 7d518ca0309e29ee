//! How one value is written in a page or a sentence: escaped text, numbers in three significant
//! digits, a median time with its interval. The lowest stage of the report (data → cells →
//! charts → pages): it names no chart and no page.

use schema::cols;

use mfx_analysis::data::{Interval, Rec};

/// Hand escaping, left for report/src/reproduction.rs (its HTML is the papers work's); every
/// other page is written through maud, which escapes each value itself.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A number in three significant digits (no trailing zeros), `e` notation outside
/// [0.001, 100000); "" when absent.
pub fn short(v: Option<f64>) -> String {
    let Some(x) = v else { return String::new() };
    if x == 0.0 {
        return "0".into();
    }
    if x.is_nan() {
        return "nan".into();
    }
    if x.is_infinite() {
        return if x > 0.0 { "inf" } else { "-inf" }.into();
    }
    let a = x.abs();
    if !(1e-3..1e5).contains(&a) {
        let s = format!("{x:.2e}");
        let (m, e) = s.split_once('e').expect("exponent form");
        return format!("{}e{e}", trim(m));
    }
    let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
    trim(&format!("{x:.decimals$}"))
}

fn trim(s: &str) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s.to_string()
    }
}

/// "yes" (exact), "no (within tol.)" (matches_truth but not exact), "no", or "" (no image error).
pub fn exact_cell(r: &Rec) -> &'static str {
    match (r.exact_result(), r.within_tolerance()) {
        (Some(true), _) => "yes",
        (Some(false), Some(true)) => "no (within tol.)",
        (Some(false), _) => "no",
        _ => "",
    }
}

/// "1.23 [1.20, 1.27]" (a 95 % CI), "1.23 (range 1.20–1.27, n = 3)" (too few samples for a
/// CI), the median alone, or "untrusted (3.45)" when the GPU timestamps missed part of the frame.
pub fn time_cell(r: &Rec) -> String {
    let m = r.f(cols::GPU_MS_MEDIAN);
    if m.is_some() && !r.time_trusted() {
        return format!("untrusted ({})", short(m));
    }
    match (m, r.gpu_ci(), r.interval()) {
        (Some(m), Some((lo, hi)), Interval::Ci95) => format!(
            "{} [{}, {}]",
            short(Some(m)),
            short(Some(lo)),
            short(Some(hi))
        ),
        (Some(m), Some((lo, hi)), Interval::Range(n)) => format!(
            "{} (range {}–{}{})",
            short(Some(m)),
            short(Some(lo)),
            short(Some(hi)),
            n.map(|n| format!(", n = {n}")).unwrap_or_default()
        ),
        (m, _, _) => short(m),
    }
}

#[cfg(test)]
mod tests {
    use super::short;

    #[test]
    fn numbers_keep_three_significant_digits() {
        let v: Vec<String> = [
            0.0,
            10.0,
            1.0,
            0.25,
            12.345,
            1234.6,
            5e-4,
            1.234e-6,
            2.5e7,
            f64::INFINITY,
        ]
        .iter()
        .map(|x| short(Some(*x)))
        .collect();
        assert_eq!(
            v,
            ["0", "10", "1", "0.25", "12.3", "1235", "5e-4", "1.23e-6", "2.5e7", "inf"]
        );
    }
}
