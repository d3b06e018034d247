//! API (for binding authors; everything is re-exported at the crate root):
//! - errors: [`Error`] (`InvalidParameter`, `NonFiniteSample`, `NonFiniteReading`,
//!   `NonFiniteMatrixReading`, `ChannelCount`, `MatrixShape`, `CorruptState`,
//!   `InvalidState`, `InvalidSnapshot`, `UnreadableSnapshot`), [`SnapshotProblem`]
//!   (`NotASnapshot`, `Truncated`, `TrailingBytes`, `ChecksumMismatch`, `UnknownVersion`),
//!   [`Error::is_config`], [`MAX_SAMPLE`];
//! - results: [`Alarm`] `{ index, start, direction, amplitude }`, [`Direction`] `{ Rise, Drop }`,
//!   [`ChannelAlarm`] `{ channel, alarm }`;
//! - CUSUM: [`CusumConfig::new`]`(threshold, drift)`, [`Cusum::new`]`(config)` with `update`,
//!   `update_slice`, `reset`, `config`, `samples_seen`, `gp`, `gn`, `gp_real`, `gn_real`,
//!   `rise_start`, `drop_start`;
//! - Shewhart: [`ShewhartConfig::new`]`(window, sigma, threshold)`,
//!   [`ShewhartConfig::with_threshold`]`(window, threshold)` (`sigma = threshold`, the paper's
//!   rule), [`Shewhart::new`]`(config) -> Result` (the ring is allocated fallibly) with
//!   `update`, `update_slice`, `reset`, `config`, `samples_seen`, `len`, `is_empty`, `mean`,
//!   `std`;
//! - banks: [`CusumBank::new`]`(channels, config)`, [`ShewhartBank::new`]`(channels, config)`,
//!   [`Bank`] `{ Cusum, Shewhart }` (constructors return `Result`: channel count and memory
//!   checked), all with `step`, `step_many`, `reset`, `channels`,
//!   `steps_seen` (plus `config`; `Bank::kind`);
//! - batch references: [`detect_cusum`]`(x, threshold, drift, ending) -> `[`CusumChanges`]
//!   `{ start, end, amplitude }`, [`detect_shewhart`]`(x, sigma, threshold) -> `
//!   [`ShewhartChanges`] `{ index, amplitude }`;
//! - feature `serde`: every config, detector, bank and result type is `Serialize + Deserialize`
//!   (deserialization re-validates configs and every state field);
//! - feature `snapshot`: `snapshot::to_bytes` / `snapshot::from_bytes`, the versioned,
//!   checksummed (CRC-32C) CBOR snapshots the Python package reads and writes (format 2; format
//!   1 still read), `snapshot::crc32c`.
//!
//! Non-finite input policy: a NaN, ±inf or out-of-range (beyond ±[`MAX_SAMPLE`] = 1e100)
//! sample/reading is *rejected* with a typed error and the detector or bank is left exactly as
//! it was (nothing consumed). A restored state is held to what a detector can reach: every
//! float field finite, samples within range, sums in their bounds ([`Error::InvalidState`]
//! names the field). Missing readings are
//! handled by the caller (skip, or hold the last value) above this crate.
#![doc = include_str!("../README.md")]
#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

extern crate alloc;

mod alarm;
mod bank;
mod batch;
mod cusum;
mod error;
mod math;
mod shewhart;
#[cfg(feature = "snapshot")]
pub mod snapshot;
mod stats;

pub use alarm::{Alarm, ChannelAlarm, Direction};
pub use bank::{Bank, CusumBank, ShewhartBank};
pub use batch::{detect_cusum, detect_shewhart, CusumChanges, ShewhartChanges};
pub use cusum::{Cusum, CusumConfig};
pub use error::{Error, SnapshotProblem, MAX_SAMPLE};
pub use shewhart::{Shewhart, ShewhartConfig};
