//! The experiment configuration's lowest pieces, which every section shares, and the
//! section the plant owns.
//!
//! * [`ConfigError`] — a configuration error naming the file, the key and what is
//!   allowed; [`check_float`], [`check_int`], [`check_len`] — the range checks every
//!   section's validation uses.
//! * [`Choice`] — a value chosen by name on the command line and in configuration files
//!   ([`SystemName`](crate::SystemName) is one); [`choice!`](crate::choice)
//!   defines such an enum, its spellings written once.
//! * [`RunConfig`] — `[run]`: the trial schedule, the seed and the sample-to-actuation
//!   delays, with its validation.
//!
//! The other sections belong to the crates that use them (`agent::config`,
//! `observer::config`); `runtime::config` composes them into an experiment and resolves
//! it from preset, file and flags.

mod choice;
mod error;
mod run;

pub use choice::{Choice, UnknownChoice, deserialize_choice};

#[cfg(feature = "clap")]
#[doc(hidden)]
pub use clap as __clap;
pub use error::{ConfigError, check_float, check_int, check_len};
pub use run::RunConfig;
#[doc(hidden)]
pub use serde as __serde;
