//! Charts read as a reader would: palette distances, legends outside, ranges on the data,
//! zero bands, dodged markers, and the layout check catching what it should.

use std::path::Path;

use super::xy::DODGE_PX;
use super::*;

fn lab(c: u32) -> [f64; 3] {
    let lin = |u: u32| {
        let u = u as f64 / 255.0;
        if u <= 0.04045 {
            u / 12.92
        } else {
            ((u + 0.055) / 1.055).powf(2.4)
        }
    };
    let (r, g, b) = (lin(c >> 16 & 255), lin(c >> 8 & 255), lin(c & 255));
    let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
    let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    let z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
    let f = |t: f64| {
        if t > 0.008856 {
            t.cbrt()
        } else {
            7.787 * t + 16.0 / 116.0
        }
    };
    [
        116.0 * f(y) - 16.0,
        500.0 * (f(x) - f(y)),
        200.0 * (f(y) - f(z)),
    ]
}

#[test]
fn palette_colours_are_far_apart_and_read_on_white() {
    // 23 legend entries used to share near-identical colours (depth_peel and wboit both
    // crimson). ΔE76 ≥ 25 is clearly distinguishable side by side.
    for (i, c) in PALETTE.iter().enumerate().take(24) {
        let a = lab(*c);
        assert!(a[0] < 75.0, "colour {i} too light on white");
        for (j, c2) in PALETTE.iter().enumerate().take(i) {
            let b = lab(*c2);
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            assert!(d >= 25.0, "colours {j} and {i}: ΔE {d:.1}");
        }
    }
}

/// A temp folder removed when the test ends, pass or fail (derefs to its path).
struct Tmp(tempfile::TempDir);
impl std::ops::Deref for Tmp {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}
impl AsRef<Path> for Tmp {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

fn tmp(name: &str) -> Tmp {
    Tmp(tempfile::Builder::new()
        .prefix(&format!("mfx-charts-{name}-"))
        .tempdir()
        .expect("a temp folder"))
}

fn read_layout(d: &Path, stem: &str) -> Layout {
    serde_json::from_str(&std::fs::read_to_string(d.join(format!("{stem}.layout.json"))).unwrap())
        .unwrap()
}

#[test]
fn a_crowded_chart_keeps_its_legend_outside_and_its_range_on_the_data() {
    // 23 configurations with points in every corner: the old chart stretched y to 1e10.
    let d = tmp("crowded");
    let series: Vec<Series> = (0..23)
        .map(|i| Series {
            name: format!(
                "configuration number {i} with a long name, layers={}",
                1 << (i % 6)
            ),
            family: i % 5,
            color: None,
            points: (0..4)
                .map(|k| {
                    Pt::new(
                        1.0 + 100.0 * k as f64 + i as f64,
                        1.0 + 1200.0 * ((i + k) % 4) as f64 / 3.0,
                    )
                    .flagged(k == 2)
                })
                .collect(),
        })
        .collect();
    let xy = XY {
        title: "Speedup".into(),
        x_label: "ms".into(),
        y_label: "×".into(),
        log_x: true,
        log_y: true,
        series,
        ..Default::default()
    };
    let f = xy.draw(&d, "c", "").unwrap();
    assert!(f.is_chart());
    let l = read_layout(&d, "c");
    assert_eq!(layout::check(&l), Ok(()));
    assert!(l.legend.is_some() && l.y.range[1] < 1e4, "{:?}", l.y);
    assert!(d.join("c.png").is_file() && d.join("c.svg").is_file());
}

#[test]
fn zero_errors_get_their_own_band_and_one_point_is_a_note() {
    let d = tmp("zero");
    let xy = XY {
        title: "Error vs time".into(),
        log_x: true,
        log_y: true,
        zero_label: "exact (0)".into(),
        series: vec![Series::new(
            "a",
            vec![Pt::new(1.0, 0.0), Pt::new(2.0, 1e-3), Pt::new(3.0, 2e-2)],
        )],
        ..Default::default()
    };
    assert!(xy.draw(&d, "z", "").unwrap().is_chart());
    let l = read_layout(&d, "z");
    assert!(l.zero_band > 0.0);
    // The log axis spans the non-zero errors only: no 1e-7 floor.
    assert!(l.y.range[0] > 1e-4, "{:?}", l.y);
    assert_eq!(layout::check(&l), Ok(()));
    let one = XY {
        title: "t".into(),
        series: vec![Series::new("a", vec![Pt::new(1.0, 1.0)])],
        ..Default::default()
    };
    let f = one.draw(&d, "one", "").unwrap();
    assert!(f.note.as_deref().unwrap().contains("one point"));
    assert!(!d.join("one.png").exists());
}

#[test]
fn bars_start_at_zero_and_decades_become_dots() {
    let d = tmp("bars");
    let cats: Vec<String> = (0..3)
        .map(|i| format!("obj(path=/a/very/long/folder/name/holes-{i}.obj,instances=4)"))
        .collect();
    let b = Bars {
        title: "x floor".into(),
        y_label: "×".into(),
        log_y: true,
        categories: cats.clone(),
        series: vec![(
            "s".into(),
            vec![Some(Pt::new(0.0, 2.0)), Some(Pt::new(0.0, 3.0)), None],
        )],
        reference: Some(1.0),
    };
    assert!(b
        .draw(&d, "b", "")
        .unwrap()
        .caption
        .contains("start at zero"));
    let l = read_layout(&d, "b");
    assert_eq!((l.kind.as_str(), l.x.range[0]), ("bars", 0.0));
    // Full category names are kept (the check would catch two equal ones).
    // A category without any value is left out.
    assert_eq!(l.y.ticks, cats[..2]);
    assert_eq!(layout::check(&l), Ok(()));
    let dots = Bars {
        series: vec![(
            "s".into(),
            vec![Some(Pt::new(0.0, 0.5)), Some(Pt::new(0.0, 900.0)), None],
        )],
        ..b
    };
    assert!(dots.draw(&d, "d", "").unwrap().caption.contains("log axis"));
    let l = read_layout(&d, "d");
    assert!(l.kind == "dots" && l.x.log);
    assert_eq!(layout::check(&l), Ok(()));
}

#[test]
fn look_alike_series_fail_the_check() {
    // Two configurations given the same colour and marker: the reader cannot tell them apart.
    let d = tmp("alike");
    let s = |name: &str, y: f64| Series {
        name: name.into(),
        family: 1,
        color: Some(3),
        points: vec![Pt::new(1.0, y), Pt::new(2.0, y * 2.0)],
    };
    let xy = XY {
        title: "t".into(),
        series: vec![s("a", 1.0), s("b", 5.0)],
        ..Default::default()
    };
    xy.draw(&d, "alike", "").unwrap();
    let e = layout::check(&read_layout(&d, "alike")).unwrap_err();
    assert!(e.iter().any(|m| m.contains("looks like")), "{e:?}");
}

#[test]
fn equal_points_are_spread_and_the_check_sees_them_hidden_otherwise() {
    // k=4 and k=8 with the same hazard rate at the same complexity: one used to hide the other.
    let d = tmp("equal");
    let s = |name: &str, c: usize| Series {
        name: name.into(),
        family: 2,
        color: Some(c),
        points: vec![Pt::new(8.0, 0.0), Pt::new(32.0, 0.1 * c as f64)],
    };
    let xy = XY {
        title: "hazard rate".into(),
        series: vec![s("k=4", 1), s("k=8", 2)],
        ..Default::default()
    };
    let f = xy.draw(&d, "eq", "").unwrap();
    assert!(f.caption.contains("moved apart"), "{}", f.caption);
    let mut l = read_layout(&d, "eq");
    assert_eq!(layout::check(&l), Ok(()));
    let (a, b) = (l.marks[0].rect, l.marks[2].rect);
    assert!((a.x - b.x).abs() >= DODGE_PX && a.y == b.y, "{a:?} {b:?}");
    // The same chart without the spreading fails.
    l.marks[2].rect = a;
    let e = layout::check(&l).unwrap_err();
    assert!(e.iter().any(|m| m.contains("same spot")), "{e:?}");
}

#[test]
fn close_floors_and_front_names_keep_clear_and_the_check_sees_an_overlap() {
    // floor_depth 0.494 and floor_opaque 0.581: rotated names used to cross each other.
    let d = tmp("floors");
    let series: Vec<Series> = (0..6)
        .map(|i| Series {
            name: format!("method {i}"),
            family: i,
            color: Some(i),
            points: vec![Pt::new(0.6 + 0.05 * i as f64, 1e-3 / (1.0 + i as f64))],
        })
        .collect();
    let xy = XY {
        title: "Error vs time".into(),
        log_x: true,
        log_y: true,
        series,
        front: (0..6)
            .map(|i| Named {
                x: 0.6 + 0.05 * i as f64,
                y: 1e-3 / (1.0 + i as f64),
                text: format!("method {i} with a long name"),
            })
            .collect(),
        front_name: "front".into(),
        vlines: vec![
            (0.494, "floor_depth 0.494".into()),
            (0.581, "floor_opaque 0.581".into()),
            (0.6, "floor_blend 0.6".into()),
        ],
        ..Default::default()
    };
    xy.draw(&d, "fl", "").unwrap();
    let mut l = read_layout(&d, "fl");
    assert_eq!(layout::check(&l), Ok(()));
    assert!(l.labels.len() >= 3, "{:?}", l.labels);
    // Floor names sit above the plot, never over a marker.
    assert!(l.labels[..3].iter().all(|t| t.rect.bottom() <= l.plot.y));
    // Put the second floor's name where the first one is: caught.
    l.labels[1].rect = l.labels[0].rect;
    let e = layout::check(&l).unwrap_err();
    assert!(e.iter().any(|m| m.contains("overlaps label")), "{e:?}");
    // A name over a marker: caught.
    let mut l = read_layout(&d, "fl");
    l.labels[0].rect = l.marks[0].rect;
    let e = layout::check(&l).unwrap_err();
    assert!(e.iter().any(|m| m.contains("covers a marker")), "{e:?}");
}
