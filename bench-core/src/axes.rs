//! Axes: what a method, the effects fold or a study reads from a sweep point, declared once
//! (column, doc, type, default, range or choices). A suite's values are checked against the
//! declarations before any GPU work ([`crate::check`]), resolved into a [`Point`] that holds
//! every declared axis (defaults included, so every row says which value it ran with), and read
//! back through the same declaration (`point.int(&LAYERS)`): no default or range is written
//! twice.

use std::ops::Deref;

use scenarios::{ParamValue, Params, ValueKind};
use schema::Col;

/// One declared axis.
#[derive(Clone, Copy, Debug)]
pub struct Axis {
    /// The CSV column the value is written to (its name is the axis name in suites).
    pub col: Col,
    /// What this axis means for the method or study that declares it.
    pub doc: &'static str,
    pub kind: ValueKind,
    /// When the declarer reads this axis only for some values of another ([`Axis::only_when`]);
    /// `None`: always.
    pub when: Option<When>,
}

/// The condition under which an axis is read: another axis of the same declarer has one of
/// `values` (as written in a suite).
#[derive(Clone, Copy, Debug)]
pub struct When {
    pub axis: &'static str,
    pub values: &'static [&'static str],
}

impl Axis {
    pub const fn int(col: Col, doc: &'static str, default: i64, min: i64, max: i64) -> Axis {
        Axis {
            col,
            doc,
            kind: ValueKind::Int { default, min, max },
            when: None,
        }
    }
    pub const fn float(col: Col, doc: &'static str, default: f64, min: f64, max: f64) -> Axis {
        Axis {
            col,
            doc,
            kind: ValueKind::Float { default, min, max },
            when: None,
        }
    }
    pub const fn bool(col: Col, doc: &'static str, default: bool) -> Axis {
        Axis {
            col,
            doc,
            kind: ValueKind::Bool { default },
            when: None,
        }
    }
    pub const fn choice(
        col: Col,
        doc: &'static str,
        default: &'static str,
        choices: &'static [&'static str],
    ) -> Axis {
        Axis {
            col,
            doc,
            kind: ValueKind::Choice { default, choices },
            when: None,
        }
    }
    /// Free text (`default` or none), checked by its declarer's `validate`.
    pub const fn text(col: Col, doc: &'static str, default: Option<&'static str>) -> Axis {
        Axis {
            col,
            doc,
            kind: ValueKind::Text { default },
            when: None,
        }
    }
    /// This axis is read only when `other` (declared by the same method or study) has one of
    /// `values`: elsewhere its values would repeat one configuration, which `check` reports.
    pub const fn only_when(mut self, other: &Axis, values: &'static [&'static str]) -> Axis {
        self.when = Some(When {
            axis: other.col.name,
            values,
        });
        self
    }
    /// Where `point` leaves this axis unread: the other axis's setting (`pool=counted`).
    pub fn ignored_at(&self, point: &Point) -> Option<String> {
        let w = self.when?;
        let v = point.values().get(w.axis)?.to_string();
        (!w.values.contains(&v.as_str())).then(|| format!("{}={v}", w.axis))
    }
    pub fn name(&self) -> &'static str {
        self.col.name
    }
    /// `default 8, 1..=1024` / `default plain, one of plain, heuristics` (for `mfx list`).
    pub fn summary(&self) -> String {
        let d = self
            .kind
            .default_value()
            .map(|v| v.to_string())
            .unwrap_or_else(|| "none".into());
        let when = self
            .when
            .map(|w| format!("; read only with {} = {}", w.axis, w.values.join(" | ")))
            .unwrap_or_default();
        format!(
            "{} (default {d}; {}{when})",
            self.name(),
            self.kind.expected()
        )
    }
}

/// Finds the declaration of `name` in `axes`.
pub fn find<'a>(axes: &'a [Axis], name: &str) -> Option<&'a Axis> {
    axes.iter().find(|a| a.name() == name)
}

/// A sweep point resolved against its declarations: the values the suite gave (which name the
/// point in `point_key`) and every declared axis's checked value (defaults filled in).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Point {
    given: Params,
    values: Params,
    /// Declared axes this point leaves unread ([`Axis::only_when`]): their value stays in
    /// `values` for whoever reads it, but neither the row nor the point key (`given`) records it
    /// as if it mattered.
    unread: Vec<&'static str>,
}

impl Point {
    /// Checks `given` against `axes`: an undeclared key or a bad value is an error naming it.
    pub fn resolve(axes: &[Axis], given: &Params) -> Result<Point, Vec<String>> {
        let mut problems = Vec::new();
        let mut values = Params::new();
        for (k, v) in &given.0 {
            match find(axes, k) {
                None => problems.push(format!(
                    "axis '{k}' is not declared (declared: {})",
                    axes.iter().map(|a| a.name()).collect::<Vec<_>>().join(", ")
                )),
                Some(a) => match a.kind.check(v) {
                    Ok(v) => values.set(k, v),
                    Err(why) => problems.push(format!("axis '{k}' = {v} {why}")),
                },
            }
        }
        for a in axes {
            if values.get(a.name()).is_none() {
                if let Some(d) = a.kind.default_value() {
                    values.set(a.name(), d);
                }
            }
        }
        if problems.is_empty() {
            let mut p = Point {
                given: given.clone(),
                values,
                unread: Vec::new(),
            };
            p.unread = axes
                .iter()
                .filter(|a| a.ignored_at(&p).is_some())
                .map(|a| a.name())
                .collect();
            // A value the point does not read names nothing: out of its key as out of its row.
            for k in &p.unread {
                p.given.0.remove(*k);
            }
            Ok(p)
        } else {
            Err(problems)
        }
    }

    /// A point of a method or study that declares no axes.
    pub fn empty() -> Point {
        Point::default()
    }

    /// What the suite set (the point's identity in `point_key`).
    pub fn given(&self) -> &Params {
        &self.given
    }

    /// Every declared axis's value, defaults included.
    pub fn values(&self) -> &Params {
        &self.values
    }

    /// The values a row records: every declared axis this point reads, defaults included; an
    /// axis it leaves unread (`layers` of a counted pool) has an empty cell.
    pub fn recorded(&self) -> Params {
        let mut p = Params::new();
        for (k, v) in &self.values.0 {
            if !self.unread.contains(&k.as_str()) {
                p.set(k, v.clone());
            }
        }
        p
    }

    fn value(&self, axis: &Axis) -> ParamValue {
        match self.values.get(axis.name()) {
            Some(v) => v.clone(),
            // Not declared by whoever resolved this point: a programming error that tests catch;
            // a sweep still runs with the declared default instead of stopping.
            None => {
                debug_assert!(false, "axis '{}' read but not declared", axis.name());
                axis.kind.default_value().unwrap_or(ParamValue::Int(0))
            }
        }
    }

    pub fn int(&self, axis: &Axis) -> i64 {
        match self.value(axis) {
            ParamValue::Int(i) => i,
            other => unreachable!("axis '{}' is an integer, resolved {other}", axis.name()),
        }
    }
    pub fn float(&self, axis: &Axis) -> f64 {
        match self.value(axis) {
            ParamValue::Float(x) => x,
            ParamValue::Int(i) => i as f64,
            other => unreachable!("axis '{}' is a number, resolved {other}", axis.name()),
        }
    }
    pub fn bool(&self, axis: &Axis) -> bool {
        match self.value(axis) {
            ParamValue::Bool(b) => b,
            other => unreachable!("axis '{}' is a boolean, resolved {other}", axis.name()),
        }
    }
    pub fn choice(&self, axis: &Axis) -> String {
        match self.value(axis) {
            ParamValue::Str(s) => s,
            other => unreachable!("axis '{}' is a choice, resolved {other}", axis.name()),
        }
    }
}

/// Reading a point as parameters reads the resolved values.
impl Deref for Point {
    type Target = Params;
    fn deref(&self) -> &Params {
        &self.values
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use schema::cols;

    const LAYERS: Axis = Axis::int(cols::LAYERS, "k", 8, 1, 64);
    const MODE: Axis = Axis::choice(cols::BUCKET_MODE, "m", "uniform", &["uniform", "adaptive"]);

    #[test]
    fn defaults_are_filled_and_values_read_through_the_declaration() {
        let p = Point::resolve(&[LAYERS, MODE], &Params::new()).unwrap();
        assert_eq!(p.int(&LAYERS), 8);
        assert_eq!(p.choice(&MODE), "uniform");
        assert!(p.given().0.is_empty());
        assert_eq!(p.values().0.len(), 2);
    }

    #[test]
    fn undeclared_and_bad_values_are_all_named() {
        let given = Params::new()
            .with("layer", ParamValue::Int(4))
            .with("layers", ParamValue::Int(0))
            .with("bucket_mode", ParamValue::Str("fast".into()));
        let e = Point::resolve(&[LAYERS, MODE], &given).unwrap_err();
        assert_eq!(e.len(), 3, "{e:?}");
        assert!(e
            .iter()
            .any(|m| m.contains("'layer'") && m.contains("layers")));
        assert!(e
            .iter()
            .any(|m| m.contains("'layers' = 0") && m.contains("1..=64")));
        assert!(e
            .iter()
            .any(|m| m.contains("fast") && m.contains("adaptive")));
    }

    #[test]
    fn an_axis_read_only_with_some_values_of_another_says_where_it_is_ignored() {
        const K: Axis = Axis::int(cols::LAYERS, "k", 8, 1, 64).only_when(&MODE, &["adaptive"]);
        let at = |mode: Option<&str>| {
            let mut given = Params::new();
            if let Some(m) = mode {
                given.set("bucket_mode", ParamValue::Str(m.into()));
            }
            K.ignored_at(&Point::resolve(&[K, MODE], &given).unwrap())
        };
        assert_eq!(at(Some("adaptive")), None);
        assert_eq!(at(Some("uniform")).as_deref(), Some("bucket_mode=uniform"));
        // The default counts: an unset mode is `uniform`, which ignores k.
        assert_eq!(at(None).as_deref(), Some("bucket_mode=uniform"));
        assert_eq!(
            LAYERS.ignored_at(&Point::resolve(&[LAYERS], &Params::new()).unwrap()),
            None
        );
    }

    #[test]
    fn an_integer_for_a_float_axis_becomes_a_float() {
        const S: Axis = Axis::float(cols::SIGMA, "σ", 1.0, 0.0, 1e30);
        let p = Point::resolve(&[S], &Params::new().with("sigma", ParamValue::Int(2))).unwrap();
        assert_eq!(p.float(&S), 2.0);
        assert_eq!(p.get("sigma"), Some(&ParamValue::Float(2.0)));
    }
}
