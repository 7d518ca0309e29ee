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
        }
    }
}

/// Reads parameters with defaults and range checks; `finish` rejects keys nobody read.
pub struct ParamReader<'a> {
    params: &'a Params,
    scene: &'a str,
    used: Vec<&'static str>,
}

impl ParamReader<'_> {
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
        self.used.push(k);
        match self.params.get(k) {
            None => Ok(default),
            Some(ParamValue::Bool(b)) => Ok(*b),
            Some(_) => Err(self.wrong(k, "true or false")),
        }
    }

    pub fn string(&mut self, k: &'static str, default: &str, allowed: &[&str]) -> Result<String> {
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
        self.used.push(k);
        match self.params.get(k) {
            None => Ok(None),
            Some(ParamValue::Str(s)) => Ok(Some(s.clone())),
            Some(_) => Err(self.wrong(k, "a string")),
        }
    }

    /// Errors on any key that no reader call asked for (a typo in a suite file must not pass).
    pub fn finish(self) -> Result<()> {
        for k in self.params.0.keys() {
            if !self.used.contains(&k.as_str()) {
                return Err(SceneError::UnknownParam {
                    scene: self.scene.into(),
                    param: k.clone(),
                    known: self.used.join(", "),
                });
            }
        }
        Ok(())
    }
}
