//! Typed cell values: the words of `status`, `flag`, `gpu_ms_interval` and the text of
//! `point_key` are declared here once, with `Display` writing today's CSV text and `FromStr`
//! reading it back, so no other crate spells them.

use std::collections::BTreeSet;
use std::fmt;
use std::str::FromStr;

/// A cell whose text is not one of its type's declared values.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseError {
    pub what: &'static str,
    pub text: String,
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "'{}' is not a {}", self.text, self.what)
    }
}

impl std::error::Error for ParseError {}

fn err(what: &'static str, text: &str) -> ParseError {
    ParseError {
        what,
        text: text.to_string(),
    }
}

/// Declares a cell value with a fixed vocabulary once: the enum, `ALL` (in declaration order),
/// `name` (the word in the CSV), `Display` writing it and `FromStr` reading it back (the error
/// names the value and every word).
macro_rules! words {
    (
        $(#[$m:meta])*
        pub enum $name:ident as $what:literal {
            $(#[$fm:meta])* $first:ident = $first_word:literal,
            $($(#[$vm:meta])* $variant:ident = $word:literal,)*
        }
    ) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum $name {
            $(#[$fm])* $first,
            $($(#[$vm])* $variant,)*
        }

        impl $name {
            pub const ALL: [$name; [$first_word $(, $word)*].len()] =
                [$name::$first $(, $name::$variant)*];
            pub fn name(self) -> &'static str {
                match self {
                    $name::$first => $first_word,
                    $($name::$variant => $word,)*
                }
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }

        impl FromStr for $name {
            type Err = ParseError;
            fn from_str(s: &str) -> Result<Self, ParseError> {
                $name::ALL
                    .into_iter()
                    .find(|v| v.name() == s)
                    .ok_or_else(|| {
                        err(concat!($what, " (", $first_word $(, " | ", $word)*, ")"), s)
                    })
            }
        }
    };
}

words! {
    /// The `status` of a row.
    pub enum Status as "status" {
        /// Measured (and judged, where the study judges).
        Ok = "ok",
        /// Not run: what the adapter cannot do, with the reason.
        Skipped = "skipped",
        /// Run and failed (a GPU error, a failed readback), with the reason.
        Failed = "failed",
    }
}

words! {
    /// The `kind` of a suite's `[[study]]` table and the `study` cell of its rows: which study
    /// ran the point. Parsed once where a suite is read, so a misspelt kind is a problem naming
    /// the file and the value; the binary's study table maps each to its implementation.
    pub enum StudyKind as "study kind" {
        /// Multi-fragment capture methods vs the exact CPU reference.
        Methods = "methods",
        /// Multi-fragment methods along a camera path (flicker and popping per view).
        Views = "views",
        /// Stiff and extreme inputs: finite output and error per multi-fragment method.
        Stability = "stability",
        /// Geometry feeding (Bavoil ch. 3): batch size, vertex formats, index precision.
        Geometry = "geometry",
        /// Deferred shading paths.
        Deferred = "deferred",
        /// The light pre-pass against deferred shading.
        Prepass = "prepass",
        /// Layered soft shadow maps (Bavoil ch. 5) vs a ray-traced reference.
        Shadows = "shadows",
    }
}

words! {
    /// A known, reported failure mode of a row (the `flag` column holds them `|`-joined, in this
    /// order). Each is defined in results/README.md.
    pub enum Flag as "flag" {
        /// Fragments exceeded the method's capacity (k, a pool, a sort buffer).
        Overflow = "overflow",
        /// k-buffer read-modify-write races changed the captured set.
        Hazard = "hazard",
        /// Bucket methods merged or lost fragments sharing a bucket.
        Collision = "collision",
        /// Distinct layers merged in the method's depth precision, or a non-finite output.
        Precision = "precision",
        /// Fragments at exactly equal depths lost (strict peeling).
        LostCoplanar = "lost_coplanar",
        /// An exact method's fragment set differs from the reference's (fragments missing without
        /// an overflow, or fragments the reference does not have).
        FragmentsDiffer = "fragments_differ",
        /// An exact method's image is off its own definition (or, without one, the truth) beyond
        /// the f32 bound of its arithmetic (`exact_bound`), with no overflow, coplanar loss,
        /// precision loss or fragment-set difference to explain it (e.g. an MSAA capture, which has
        /// no per-pixel counts).
        ImageDiffers = "image_differs",
        /// The image is off the truth beyond the f32 bound of its arithmetic only at pixels where
        /// fragments within the method's depth precision have no defined order, and by no more than
        /// compositing them in another order can make (`depth_tie_pixels`): the truth is ambiguous
        /// there, so the row is not `exact`, but nothing was lost or merged.
        DepthTies = "depth_ties",
        /// GPU time far below the wall-clock time of the same frames: the timestamps missed work.
        TimestampsIncomplete = "timestamps_incomplete",
        /// The stopping rule's noise target was not reached (max samples, max time or drift).
        Noisy = "noisy",
        /// A sample was taken below 75 % of the reference SM clock, or NVML reported a slowdown.
        Throttled = "throttled",
        /// Another process held the GPU while the point was timed (NVML's process lists, read
        /// after every timed frame: `gpu_other_processes` > 0): its times may include that
        /// process's work.
        GpuShared = "gpu_shared",
    }
}

impl Flag {
    /// The flags that say a fragment was lost or merged (or, for `image_differs`, that the
    /// image shows an unexplained difference): a row carrying one is never `exact`.
    pub const LOSS: [Flag; 7] = [
        Flag::Overflow,
        Flag::Hazard,
        Flag::Collision,
        Flag::Precision,
        Flag::LostCoplanar,
        Flag::FragmentsDiffer,
        Flag::ImageDiffers,
    ];
    pub fn parse(s: &str) -> Option<Flag> {
        s.parse().ok()
    }
    pub fn is_loss(self) -> bool {
        Flag::LOSS.contains(&self)
    }
}

/// The `flag` cell: a set that can only grow. Known flags print in [`Flag::ALL`]'s order; a
/// word that is not a known flag (a method's own) is kept after them, never dropped.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FlagSet {
    known: BTreeSet<Flag>,
    other: Vec<String>,
}

impl FlagSet {
    pub fn new() -> Self {
        FlagSet::default()
    }
    pub fn of(flags: &[Flag]) -> Self {
        let mut s = FlagSet::new();
        for f in flags {
            s.add(*f);
        }
        s
    }
    pub fn add(&mut self, f: Flag) -> &mut Self {
        self.known.insert(f);
        self
    }
    /// Adds every flag of `other` (known or not).
    pub fn add_all(&mut self, other: &FlagSet) -> &mut Self {
        self.known.extend(other.known.iter().copied());
        for w in &other.other {
            self.add_word(w);
        }
        self
    }
    /// Adds one word: a known flag, or kept as an unknown word.
    fn add_word(&mut self, w: &str) {
        let w = w.trim();
        if w.is_empty() {
            return;
        }
        match Flag::parse(w) {
            Some(f) => {
                self.known.insert(f);
            }
            None if !self.other.iter().any(|o| o == w) => self.other.push(w.to_string()),
            None => {}
        }
    }
    pub fn contains(&self, f: Flag) -> bool {
        self.known.contains(&f)
    }
    pub fn is_empty(&self) -> bool {
        self.known.is_empty() && self.other.is_empty()
    }
    /// The known flags, in order.
    pub fn iter(&self) -> impl Iterator<Item = Flag> + '_ {
        self.known.iter().copied()
    }
    /// Words that are not known flags, in the order first added.
    pub fn unknown(&self) -> &[String] {
        &self.other
    }
    /// Whether a flag says a fragment was lost or merged ([`Flag::LOSS`]).
    pub fn has_loss(&self) -> bool {
        self.known.iter().any(|f| f.is_loss())
    }
}

impl fmt::Display for FlagSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut first = true;
        for w in self
            .known
            .iter()
            .map(|k| k.name())
            .chain(self.other.iter().map(|s| s.as_str()))
        {
            if !first {
                f.write_str("|")?;
            }
            f.write_str(w)?;
            first = false;
        }
        Ok(())
    }
}

impl FromStr for FlagSet {
    type Err = ParseError;
    /// Never fails: unknown words are kept (older CSVs, a method's own words).
    fn from_str(s: &str) -> Result<Self, ParseError> {
        let mut set = FlagSet::new();
        for w in s.split('|') {
            set.add_word(w);
        }
        Ok(set)
    }
}

impl From<Flag> for FlagSet {
    fn from(f: Flag) -> Self {
        FlagSet::of(&[f])
    }
}

words! {
    /// What `gpu_ms_ci_lo` / `gpu_ms_ci_hi` hold.
    pub enum GpuMsInterval as "gpu_ms_interval" {
        /// A 95 % confidence interval of the median.
        Ci95 = "ci95",
        /// The minimum and maximum: too few samples for a 95 % interval of the median.
        Range = "range",
    }
}

/// The fewest samples whose extreme order statistics, `[min, max]`, cover the median with
/// ≥ 95 % probability: `1 − 2·2⁻ⁿ ≥ 0.95` ⇔ `2⁻ⁿ ≤ 0.025` ⇔ `n ≥ 6` (n = 3 gives 75 %,
/// n = 5 93.75 %, n = 6 96.9 %). Below it no distribution-free 95 % interval of the median
/// exists, and the row's interval is [`GpuMsInterval::Range`].
pub const MIN_SAMPLES_CI95: usize = min_samples_ci95();

const fn min_samples_ci95() -> usize {
    // Smallest n with 2·2⁻ⁿ ≤ 0.05, i.e. 2ⁿ ≥ 40.
    let mut n = 1;
    while (1u64 << n) < 40 {
        n += 1;
    }
    n
}

/// A row's `point_key`: `study|scene|WxH|method|axes`, axes the suite set as `k=v,k=v` (an
/// axis left at its default is absent).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PointKey {
    pub study: String,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub method: String,
    /// The axes as written (`k=v,k=v`); see [`PointKey::axes`].
    pub axes: String,
}

impl PointKey {
    /// The `k=v` pairs of the axes field, in order.
    pub fn axes(&self) -> Vec<(&str, &str)> {
        self.axes
            .split(',')
            .filter_map(|kv| kv.split_once('='))
            .collect()
    }
    /// The names of the axes the suite set.
    pub fn axis_names(&self) -> Vec<&str> {
        self.axes().into_iter().map(|(k, _)| k).collect()
    }
}

impl fmt::Display for PointKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}|{}|{}x{}|{}|{}",
            self.study, self.scene, self.width, self.height, self.method, self.axes
        )
    }
}

impl FromStr for PointKey {
    type Err = ParseError;
    /// The study is the first field and resolution, method and axes the last three, so a
    /// scene label holding `|` still parses.
    fn from_str(s: &str) -> Result<Self, ParseError> {
        let bad = || err("point_key (study|scene|WxH|method|axes)", s);
        let (study, rest) = s.split_once('|').ok_or_else(bad)?;
        let mut tail = rest.rsplitn(4, '|');
        let axes = tail.next().ok_or_else(bad)?;
        let method = tail.next().ok_or_else(bad)?;
        let res = tail.next().ok_or_else(bad)?;
        let scene = tail.next().ok_or_else(bad)?;
        let (w, h) = res.split_once('x').ok_or_else(bad)?;
        Ok(PointKey {
            study: study.to_string(),
            scene: scene.to_string(),
            width: w.parse().map_err(|_| bad())?,
            height: h.parse().map_err(|_| bad())?,
            method: method.to_string(),
            axes: axes.to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_round_trips_and_refuses_other_words() {
        for s in Status::ALL {
            assert_eq!(s.to_string().parse::<Status>(), Ok(s));
        }
        assert!("OK".parse::<Status>().is_err());
        // The error names the value and every word the macro declared.
        let e = "OK".parse::<Status>().unwrap_err().to_string();
        assert!(Status::ALL.iter().all(|s| e.contains(s.name())), "{e}");
        assert!("nope"
            .parse::<Flag>()
            .unwrap_err()
            .to_string()
            .contains("depth_ties | "));
        for f in Flag::ALL {
            assert_eq!(f.to_string().parse::<Flag>(), Ok(f));
        }
    }

    #[test]
    fn a_flag_set_only_grows_keeps_order_and_unknown_words() {
        let mut f: FlagSet = "noisy".parse().unwrap();
        f.add(Flag::Precision);
        assert_eq!(
            f.to_string(),
            "precision|noisy",
            "an earlier flag survives an add"
        );
        f.add_all(&"overflow|weird|noisy".parse().unwrap());
        f.add(Flag::Hazard);
        assert_eq!(f.to_string(), "overflow|hazard|precision|noisy|weird");
        assert!(f.contains(Flag::Hazard) && !f.contains(Flag::Collision));
        assert!(f.has_loss());
        assert_eq!(f.to_string().parse::<FlagSet>().unwrap(), f);
        assert!("".parse::<FlagSet>().unwrap().is_empty());
        assert!(!"noisy|throttled".parse::<FlagSet>().unwrap().has_loss());
        for flag in Flag::ALL {
            assert_eq!(Flag::parse(flag.name()), Some(flag));
        }
    }

    #[test]
    fn the_fewest_samples_for_a_95_percent_median_interval_is_6() {
        // [min, max] misses the median with probability 2·2⁻ⁿ.
        let cover = |n: i32| 1.0 - 2.0 * 0.5f64.powi(n);
        assert_eq!(MIN_SAMPLES_CI95, 6);
        assert!(cover(MIN_SAMPLES_CI95 as i32) >= 0.95);
        assert!(cover(MIN_SAMPLES_CI95 as i32 - 1) < 0.95);
        assert!(
            (cover(3) - 0.75).abs() < 1e-12,
            "the software profile's 3 samples"
        );
        for v in [GpuMsInterval::Ci95, GpuMsInterval::Range] {
            assert_eq!(v.to_string().parse::<GpuMsInterval>(), Ok(v));
        }
    }

    #[test]
    fn point_keys_round_trip_and_give_their_axes() {
        let s = "methods|quads(depth_complexity=8,seed=1)|128x96|kbuffer_rmw|heuristics=false,layers=16";
        let k: PointKey = s.parse().unwrap();
        assert_eq!(k.study, "methods");
        assert_eq!(k.scene, "quads(depth_complexity=8,seed=1)");
        assert_eq!((k.width, k.height), (128, 96));
        assert_eq!(k.method, "kbuffer_rmw");
        assert_eq!(k.axes(), vec![("heuristics", "false"), ("layers", "16")]);
        assert_eq!(k.to_string(), s);
        // No axes, and a scene label holding the separator.
        let k: PointKey = "geometry|obj(path=a|b)|64x64|feed|".parse().unwrap();
        assert_eq!(
            (k.scene.as_str(), k.method.as_str()),
            ("obj(path=a|b)", "feed")
        );
        assert!(k.axes().is_empty());
        assert!("methods|s|64|m|".parse::<PointKey>().is_err());
        assert!("k1".parse::<PointKey>().is_err());
    }
}
