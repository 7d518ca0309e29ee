//! What a run says, as typed data: `data` reads runs.csv into rows with typed accessors,
//! `verdict` names the fastest exact configuration per scene (and what was left out and why),
//! `ab` compares two runs point by point (`mfx compare`), `calibrate` measures each point's
//! A/A band (`mfx calibrate`) and `bands` reads it back. No GPU, no drawing: the `report` crate
//! draws these; `mfx` prints them. criterion's split, measure → analyse → report, with this
//! crate as the middle stage.

pub mod ab;
pub mod bands;
pub mod calibrate;
pub mod data;
pub mod verdict;

pub use data::{Rec, Runs};
