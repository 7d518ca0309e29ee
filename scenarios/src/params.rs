//! Scene and axis parameters: small typed values read from TOML, printed stably.

use std::collections::BTreeMap;
use std::fmt;

use crate::{Result, SceneError};

/// One parameter value as a suite file gives it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
pub enum ParamValue {
    Bool(bool),
    Int(i64),
    Float(f64),
    Str(String),
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamValue::Bool(b) => write!(f, "{b}"),
            ParamValue::Int(i) => write!(f, "{i}"),
            ParamValue::Float(x) => write!(f, "{x}"),
            ParamValue::Str(s) => write!(f, "{s}"),
        }
    }
}

impl ParamValue {
    /// Converts a scalar TOML value; arrays and tables are not parameter values.
    pub fn from_toml(v: &toml::Value) -> Option<ParamValue> {
        Some(match v {
            toml::Value::Boolean(b) => ParamValue::Bool(*b),
            toml::Value::Integer(i) => ParamValue::Int(*i),
            toml::Value::Float(x) => ParamValue::Float(*x),
            toml::Value::String(s) => ParamValue::Str(s.clone()),
            _ => return None,
        })
    }
}

/// The declared type, default and range of a parameter or axis: one declaration serves the
/// check before any GPU work, the default written to the row, and the value read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ValueKind {
    Int {
        default: i64,
        min: i64,
        max: i64,
    },
    /// Integers are accepted and converted.
    Float {
        default: f64,
        min: f64,
        max: f64,
    },
    Bool {
        default: bool,
    },
    Choice {
        default: &'static str,
        choices: &'static [&'static str],
    },
    /// Free text (a file path, a name); `None`: no default (the value is optional).
    Text {
        default: Option<&'static str>,
    },
}

/// A value that is not what its key takes; the message is the rule (`must be one of a, b`),
/// to follow the key and value that the caller names.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("must be {expected}")]
pub struct NotExpected {
    /// What the key takes, as [`ValueKind::expected`] says it.
    pub expected: String,
}

impl ValueKind {
    /// The default value, if the kind has one.
    pub fn default_value(&self) -> Option<ParamValue> {
        Some(match *self {
            ValueKind::Int { default, .. } => ParamValue::Int(default),
            ValueKind::Float { default, .. } => ParamValue::Float(default),
            ValueKind::Bool { default } => ParamValue::Bool(default),
            ValueKind::Choice { default, .. } => ParamValue::Str(default.into()),
            ValueKind::Text { default } => ParamValue::Str(default?.into()),
        })
    }

    /// What a value must be, for messages: "an integer in 1..=64", "one of a, b".
    pub fn expected(&self) -> String {
        match self {
            ValueKind::Int { min, max, .. } => format!("an integer in {min}..={max}"),
            // An open end (f64::MAX) reads as a bound, not as 309 digits.
            ValueKind::Float { min, max, .. } => match (*min <= f64::MIN, *max >= f64::MAX) {
                (true, true) => "a finite number".into(),
                (false, true) => format!("a finite number ≥ {min}"),
                (true, false) => format!("a finite number ≤ {max}"),
                (false, false) => format!("a finite number in [{min}, {max}]"),
            },
            ValueKind::Bool { .. } => "true or false".into(),
            ValueKind::Choice { choices, .. } => format!("one of {}", choices.join(", ")),
            ValueKind::Text { .. } => "a string".into(),
        }
    }

    /// Checks `v` and returns it normalised (an integer given for a float becomes a float);
    /// `Err` says what was expected.
    pub fn check(&self, v: &ParamValue) -> std::result::Result<ParamValue, NotExpected> {
        let bad = || {
            Err(NotExpected {
                expected: self.expected(),
            })
        };
        match (self, v) {
            (ValueKind::Int { min, max, .. }, ParamValue::Int(i)) => {
                if i < min || i > max {
                    return bad();
                }
                Ok(v.clone())
            }
            (ValueKind::Float { min, max, .. }, ParamValue::Float(_) | ParamValue::Int(_)) => {
                let x = match v {
                    ParamValue::Float(x) => *x,
                    ParamValue::Int(i) => *i as f64,
                    _ => unreachable!(),
                };
                if !x.is_finite() || x < *min || x > *max {
                    return bad();
                }
                Ok(ParamValue::Float(x))
            }
            (ValueKind::Bool { .. }, ParamValue::Bool(_)) => Ok(v.clone()),
            (ValueKind::Choice { choices, .. }, ParamValue::Str(s)) => {
                if !choices.contains(&s.as_str()) {
                    return bad();
                }
                Ok(v.clone())
            }
            // A choice that grew out of a boolean (kbuffer_rmw's `heuristics`: false, true,
            // sort, sort_flush) still takes the suites' and papers files' `true` and `false`.
            (ValueKind::Choice { choices, .. }, ParamValue::Bool(b))
                if choices.contains(&b.to_string().as_str()) =>
            {
                Ok(ParamValue::Str(b.to_string()))
            }
            (ValueKind::Text { .. }, ParamValue::Str(_)) => Ok(v.clone()),
            _ => bad(),
        }
    }
}

/// Named parameters of one scene or one sweep point, ordered so labels are stable.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Params(pub BTreeMap<String, ParamValue>);

impl Params {
    pub fn new() -> Self {
        Self::default()
    }
    pub fn with(mut self, k: &str, v: ParamValue) -> Self {
        self.0.insert(k.to_string(), v);
        self
    }
    pub fn set(&mut self, k: &str, v: ParamValue) {
        self.0.insert(k.to_string(), v);
    }
    pub fn get(&self, k: &str) -> Option<&ParamValue> {
        self.0.get(k)
    }
    /// `k=v,k=v` in key order: the stable text form used in labels and point keys.
    pub fn label(&self) -> String {
        self.0
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(",")
    }

    /// A typed reader that remembers which keys were used, so unknown keys can be reported.
    pub fn reader<'a>(&'a self, scene: &'a str) -> ParamReader<'a> {
        ParamReader {
            params: self,
            scene,
            used: Vec::new(),
            problems: Vec::new(),
        }
    }
}

/// Reads parameters with defaults and range checks; `finish` rejects keys nobody read.
///
/// Generators read every parameter before building anything and then call `finish`, so the
/// reader calls are the parameters' one declaration. In check mode ([`check_params`]) a bad
/// value is recorded (and its default used) instead of failing, and `finish` stops the
/// generator with every problem at once, before any geometry is built.
pub struct ParamReader<'a> {
    params: &'a Params,
    scene: &'a str,
    used: Vec<&'static str>,
    problems: Vec<SceneError>,
}

thread_local! {
    static CHECK_ONLY: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

fn check_only() -> bool {
    CHECK_ONLY.with(|c| c.get())
}

/// Runs `build` in check mode: every parameter is read and checked, nothing is built. Returns
/// every problem (empty when the parameters are valid).
pub fn check_params<T>(build: impl FnOnce() -> Result<T>) -> Vec<SceneError> {
    CHECK_ONLY.with(|c| c.set(true));
    let r = build();
    CHECK_ONLY.with(|c| c.set(false));
    match r {
        Ok(_) | Err(SceneError::Checked) => vec![],
        Err(SceneError::Many(v)) => v,
        Err(e) => vec![e],
    }
}

impl ParamReader<'_> {
    /// In check mode a problem is recorded and `default` read instead.
    fn soft<T>(&mut self, r: Result<T>, default: T) -> Result<T> {
        match r {
            Err(e) if check_only() => {
                self.problems.push(e);
                Ok(default)
            }
            r => r,
        }
    }

    fn wrong(&self, param: &str, expected: &'static str) -> SceneError {
        SceneError::WrongType {
            scene: self.scene.into(),
            param: param.into(),
            expected,
        }
    }
    fn range(&self, param: &str, value: String, why: String) -> SceneError {
        SceneError::OutOfRange {
            scene: self.scene.into(),
            param: param.into(),
            value,
            why,
        }
    }

    pub fn int(&mut self, k: &'static str, default: i64, min: i64, max: i64) -> Result<i64> {
        let r = self.int_strict(k, default, min, max);
        self.soft(r, default)
    }

    fn int_strict(&mut self, k: &'static str, default: i64, min: i64, max: i64) -> Result<i64> {
        self.used.push(k);
        let v = match self.params.get(k) {
            None => default,
            Some(ParamValue::Int(i)) => *i,
            Some(_) => return Err(self.wrong(k, "an integer")),
        };
        if v < min || v > max {
            return Err(self.range(k, v.to_string(), format!("must be in {min}..={max}")));
        }
        Ok(v)
    }

    pub fn float(&mut self, k: &'static str, default: f64, min: f64, max: f64) -> Result<f64> {
        let r = self.float_strict(k, default, min, max);
        self.soft(r, default)
    }

    fn float_strict(&mut self, k: &'static str, default: f64, min: f64, max: f64) -> Result<f64> {
        self.used.push(k);
        let v = match self.params.get(k) {
            None => default,
            Some(ParamValue::Float(x)) => *x,
            Some(ParamValue::Int(i)) => *i as f64,
            Some(_) => return Err(self.wrong(k, "a number")),
        };
        if !v.is_finite() || v < min || v > max {
            return Err(self.range(
                k,
                v.to_string(),
                format!("must be finite and in [{min}, {max}]"),
            ));
        }
        Ok(v)
    }

    pub fn boolean(&mut self, k: &'static str, default: bool) -> Result<bool> {
        let r = self.boolean_strict(k, default);
        self.soft(r, default)
    }

    fn boolean_strict(&mut self, k: &'static str, default: bool) -> Result<bool> {
        self.used.push(k);
        match self.params.get(k) {
            None => Ok(default),
            Some(ParamValue::Bool(b)) => Ok(*b),
            Some(_) => Err(self.wrong(k, "true or false")),
        }
    }

    pub fn string(&mut self, k: &'static str, default: &str, allowed: &[&str]) -> Result<String> {
        let r = self.string_strict(k, default, allowed);
        self.soft(r, default.to_string())
    }

    fn string_strict(
        &mut self,
        k: &'static str,
        default: &str,
        allowed: &[&str],
    ) -> Result<String> {
        self.used.push(k);
        let v = match self.params.get(k) {
            None => default.to_string(),
            Some(ParamValue::Str(s)) => s.clone(),
            Some(_) => return Err(self.wrong(k, "a string")),
        };
        if !allowed.is_empty() && !allowed.contains(&v.as_str()) {
            return Err(self.range(k, v, format!("must be one of {}", allowed.join(", "))));
        }
        Ok(v)
    }

    /// An optional string without a default (e.g. a file path).
    pub fn opt_string(&mut self, k: &'static str) -> Result<Option<String>> {
        let r = self.opt_string_strict(k);
        self.soft(r, None)
    }

    fn opt_string_strict(&mut self, k: &'static str) -> Result<Option<String>> {
        self.used.push(k);
        match self.params.get(k) {
            None => Ok(None),
            Some(ParamValue::Str(s)) => Ok(Some(s.clone())),
            Some(_) => Err(self.wrong(k, "a string")),
        }
    }

    /// Errors on any key that no reader call asked for (a typo in a suite file must not pass).
    /// In check mode it also returns the problems recorded so far, or [`SceneError::Checked`]
    /// when there are none, so the generator stops before building.
    pub fn finish(mut self) -> Result<()> {
        for k in self.params.0.keys() {
            if !self.used.contains(&k.as_str()) {
                let e = SceneError::UnknownParam {
                    scene: self.scene.into(),
                    param: k.clone(),
                    known: self.used.join(", "),
                };
                if !check_only() {
                    return Err(e);
                }
                self.problems.push(e);
            }
        }
        if check_only() {
            return Err(match self.problems.len() {
                0 => SceneError::Checked,
                _ => SceneError::Many(std::mem::take(&mut self.problems)),
            });
        }
        Ok(())
    }

    /// In check mode, records a problem found by the generator itself (e.g. a required
    /// parameter that is missing) and goes on; otherwise returns it.
    pub fn problem(&mut self, e: SceneError) -> Result<()> {
        if check_only() {
            self.problems.push(e);
            return Ok(());
        }
        Err(e)
    }
}
