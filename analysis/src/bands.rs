//! Bands of `mfx compare --band-from`: the calibration file `mfx calibrate` writes (how far each
//! point's median moves between A/A runs of one build), read by `ab` without needing how it was
//! made (`calibrate.rs`), so the two files form no cycle.

use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};

/// The `format` of a calibration file this code reads and writes.
/// 2: a point's band also covers its typical session-state spread (`calibrate.rs`).
pub const FORMAT: &str = "mfx-calibration/2";

/// Where a point's band came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum BandSource {
    /// Its own spread in the A/A runs.
    Point,
    /// Its class's (method × scene kind): the point was not in the A/A runs.
    Class,
    /// The fixed floor (no calibration, or neither the point nor its class was calibrated).
    Fixed,
}

/// Verdicts of one method family over every A/A pair, at the fixed band.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Alarms {
    pub compared: usize,
    pub same: usize,
    pub faster: usize,
    pub slower: usize,
    pub unsure: usize,
}

impl Alarms {
    /// FASTER + SLOWER over compared: between runs of one build every such verdict is false.
    pub fn false_alarm_rate(&self) -> f64 {
        if self.compared == 0 {
            0.0
        } else {
            (self.faster + self.slower) as f64 / self.compared as f64
        }
    }
}

/// The canary's drift over one run: the median ratio of the canary to its fastest run in the
/// first 15 s of samples, and after the first minute.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Drift {
    pub run: String,
    pub canary_first_15s: Option<f64>,
    pub canary_after_60s: Option<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    pub format: String,
    /// The A/A runs, as given.
    pub runs: Vec<String>,
    /// No band is narrower than this.
    pub floor: f64,
    /// The largest A/A move of a point is multiplied by this to give its band.
    pub margin: f64,
    /// Band per point key (the compare's key: `point_key`, with ` @ platform` when merged).
    pub points: BTreeMap<String, f64>,
    /// Band per class ([`class_of`]) for points not in `points`.
    pub classes: BTreeMap<String, f64>,
    /// Per method family, at the fixed floor band (the false-alarm rate of an uncalibrated
    /// compare).
    pub false_alarms: BTreeMap<String, Alarms>,
    pub drift: Vec<Drift>,
}

/// The method of a compare key (`study|scene|WxH|method|axes`, maybe ` @ platform`).
pub fn family_of(key: &str) -> &str {
    key.split('|').nth(3).unwrap_or("")
}

/// "method × scene kind" of a compare key (the scene's name without its parameters), plus the
/// platform when the key names one.
pub fn class_of(key: &str) -> String {
    let (k, platform) = match key.split_once(" @ ") {
        Some((k, p)) => (k, Some(p)),
        None => (key, None),
    };
    let scene = k.split('|').nth(1).unwrap_or("");
    let scene = scene.split('(').next().unwrap_or(scene);
    let mut c = format!("{} × {scene}", family_of(k));
    if let Some(p) = platform {
        let _ = write!(c, " @ {p}");
    }
    c
}

impl Calibration {
    /// The band of a compare key, never below `floor`, and where it came from.
    pub fn band_for(&self, key: &str, floor: f64) -> (f64, BandSource) {
        let floor = floor.max(self.floor);
        if let Some(b) = self.points.get(key) {
            (b.max(floor), BandSource::Point)
        } else if let Some(b) = self.classes.get(&class_of(key)) {
            (b.max(floor), BandSource::Class)
        } else {
            (floor, BandSource::Fixed)
        }
    }

    pub fn load(path: &Path) -> Result<Calibration> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        let c: Calibration = serde_json::from_str(&text)
            .with_context(|| format!("{}: not an mfx calibration file", path.display()))?;
        if c.format != FORMAT {
            bail!(
                "{}: format '{}', this mfx reads '{FORMAT}' (rerun mfx calibrate)",
                path.display(),
                c.format
            );
        }
        if let Some((k, b)) = c
            .points
            .iter()
            .chain(&c.classes)
            .find(|(_, b)| !(b.is_finite() && **b >= 0.0 && **b < 10.0))
        {
            bail!("{}: band {b} of '{k}' is not in [0, 10)", path.display());
        }
        Ok(c)
    }

    pub fn save(&self, path: &Path) -> Result<()> {
        let text = serde_json::to_string_pretty(self)?;
        std::fs::write(path, text + "\n").with_context(|| format!("writing {}", path.display()))
    }
}

pub(crate) fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}
