//! A problem found while checking a suite before any GPU work: where it is (file, table, key),
//! the value, what is wrong, and the alternatives a user could have meant.

use std::fmt;

#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    /// The suite file, or `(built-in) NAME`.
    pub file: String,
    /// Where in the file: `top level`, `[software]`, `study 2 (methods)`,
    /// `study 2 (methods) › scene 1 (grass)`, `study 2 (methods) › method_axes.linked_list`.
    pub table: String,
    /// The offending key (empty when the problem is about the table itself).
    pub key: String,
    /// The offending value as written, when there is one.
    pub value: Option<String>,
    pub message: String,
    /// What is known there (keys, names, choices), for "did you mean".
    pub known: Vec<String>,
}

impl Problem {
    pub fn new(file: &str, table: &str, key: &str, message: impl Into<String>) -> Problem {
        Problem {
            file: file.into(),
            table: table.into(),
            key: key.into(),
            value: None,
            message: message.into(),
            known: Vec::new(),
        }
    }
    pub fn value(mut self, v: impl fmt::Display) -> Problem {
        self.value = Some(v.to_string());
        self
    }
    pub fn known<S: AsRef<str>>(mut self, known: impl IntoIterator<Item = S>) -> Problem {
        self.known = known.into_iter().map(|s| s.as_ref().to_string()).collect();
        self
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.file, self.table)?;
        if !self.key.is_empty() {
            write!(f, ": '{}'", self.key)?;
            if let Some(v) = &self.value {
                write!(f, " = {v}")?;
            }
        }
        write!(f, ": {}", self.message)?;
        if !self.known.is_empty() {
            write!(f, " (known: {})", self.known.join(", "))?;
        }
        Ok(())
    }
}

/// Every problem of one check, printed one per line.
pub fn report(problems: &[Problem]) -> String {
    problems
        .iter()
        .map(|p| p.to_string())
        .collect::<Vec<_>>()
        .join("\n")
}
