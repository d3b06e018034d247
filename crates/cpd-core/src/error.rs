//! The crate's single error type.

use alloc::string::String;
use alloc::vec::Vec;
use core::fmt;

/// Everything that can go wrong in `cpd-core`.
///
/// Configuration problems ([`Error::InvalidParameter`], see [`Error::is_config`]) are
/// reported when a config or bank is built; the other variants are bad *input*
/// (a non-finite sample, a wrong number of readings). Whenever an input error is
/// returned, the detector or bank is left exactly as it was before the call.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// A configuration parameter is out of its domain.
    InvalidParameter {
        /// The parameter's name, as spelled in the constructor (`"threshold"`, `"window"`, ...).
        name: &'static str,
        /// The rejected value (integers are converted to `f64`).
        value: f64,
        /// What the value must satisfy, e.g. `"must be finite and > 0"`.
        reason: &'static str,
    },
    /// A NaN or infinite sample was fed to a single-channel detector or a batch function.
    NonFiniteSample {
        /// Index of the bad sample in the detector's stream (or in the batch slice).
        index: u64,
        /// The offending value.
        value: f64,
    },
    /// A NaN or infinite reading was passed to a bank's `step`.
    NonFiniteReading {
        /// Channel (column) of the bad reading.
        channel: usize,
        /// The offending value.
        value: f64,
    },
    /// A NaN or infinite value in the matrix passed to a bank's `step_many`.
    NonFiniteMatrixReading {
        /// Row (time step within the call) of the bad reading.
        row: usize,
        /// Channel (column) of the bad reading.
        channel: usize,
        /// The offending value.
        value: f64,
    },
    /// A bank step got a number of readings different from its number of channels.
    ChannelCount {
        /// The bank's number of channels.
        expected: usize,
        /// The number of readings passed.
        got: usize,
    },
    /// The row-major matrix passed to `step_many` is not a whole number of rows.
    MatrixShape {
        /// Length of the flat matrix.
        len: usize,
        /// The bank's number of channels (the row length).
        channels: usize,
    },
    /// A deserialized state is internally inconsistent (e.g. a ring buffer of the wrong length)
    /// or holds a value no detector can reach (a non-finite sample, an index past the count).
    CorruptState {
        /// What is inconsistent.
        reason: &'static str,
    },
    /// Snapshot bytes that cannot be restored (see `cpd_core::snapshot`): not a snapshot, of
    /// another kind or format, or holding an invalid configuration or state.
    InvalidSnapshot {
        /// The kind that was expected (`"Cusum"`, `"Shewhart"`, `"DetectorBank"`).
        kind: &'static str,
        /// What is wrong, e.g. the decoder's message.
        detail: String,
    },
}

impl Error {
    /// True for configuration errors ([`Error::InvalidParameter`]), false for bad input.
    pub fn is_config(&self) -> bool {
        matches!(self, Error::InvalidParameter { .. })
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::InvalidParameter {
                name,
                value,
                reason,
            } => write!(f, "invalid parameter `{name}` = {value}: {reason}"),
            Error::NonFiniteSample { index, value } => {
                write!(f, "non-finite sample {value} at index {index}")
            }
            Error::NonFiniteReading { channel, value } => {
                write!(f, "non-finite reading {value} on channel {channel}")
            }
            Error::NonFiniteMatrixReading {
                row,
                channel,
                value,
            } => write!(
                f,
                "non-finite reading {value} at row {row}, channel {channel}"
            ),
            Error::ChannelCount { expected, got } => {
                write!(
                    f,
                    "expected {expected} readings (one per channel), got {got}"
                )
            }
            Error::MatrixShape { len, channels } => write!(
                f,
                "matrix of {len} values is not a whole number of rows of {channels} channels"
            ),
            Error::CorruptState { reason } => write!(f, "corrupt detector state: {reason}"),
            Error::InvalidSnapshot { kind, detail } => {
                write!(f, "invalid {kind} snapshot: {detail}")
            }
        }
    }
}

impl core::error::Error for Error {}

/// Checks that `value` is finite and strictly positive.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64, Error> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            name,
            value,
            reason: "must be finite and > 0",
        })
    }
}

/// `n` copies of `value`, or [`Error::InvalidParameter`] naming `name` (the parameter that sets
/// the size) when the memory cannot be reserved: a huge window or channel count is a config
/// error, never an allocation abort.
pub(crate) fn filled<T: Clone>(name: &'static str, n: usize, value: T) -> Result<Vec<T>, Error> {
    let mut v = Vec::new();
    if v.try_reserve_exact(n).is_err() {
        return Err(Error::InvalidParameter {
            name,
            value: n as f64,
            reason: "needs more memory than can be allocated",
        });
    }
    v.resize(n, value);
    Ok(v)
}

/// Largest sample or step count a restored state may hold (2^62, i.e. 146 years at 1 GHz), so
/// that counting on from it can never overflow.
#[cfg(feature = "serde")]
pub(crate) const MAX_COUNT: u64 = 1 << 62;

/// A restored-state check: [`Error::CorruptState`] with `reason` unless `ok`.
#[cfg(feature = "serde")]
pub(crate) fn ensure(ok: bool, reason: &'static str) -> Result<(), Error> {
    if ok {
        Ok(())
    } else {
        Err(Error::CorruptState { reason })
    }
}

/// Checks that `value` is finite and non-negative.
pub(crate) fn non_negative(name: &'static str, value: f64) -> Result<f64, Error> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            name,
            value,
            reason: "must be finite and >= 0",
        })
    }
}

/// Index and value of the first non-finite element of `xs`, if any.
#[inline]
pub(crate) fn first_non_finite(xs: &[f64]) -> Option<(usize, f64)> {
    // Branch-free (vectorizable) scan first; locate the culprit only when something is wrong.
    if xs.iter().fold(true, |ok, v| ok & v.is_finite()) {
        return None;
    }
    xs.iter()
        .enumerate()
        .find(|(_, v)| !v.is_finite())
        .map(|(i, v)| (i, *v))
}

/// Rejects a non-finite sample with the stream index it would have had.
#[inline(always)]
pub(crate) fn check_sample(x: f64, index: u64) -> Result<(), Error> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(Error::NonFiniteSample { index, value: x })
    }
}

/// Rejects a slice holding a non-finite sample, naming the first one by its stream index
/// (`offset` = the stream index of `xs[0]`).
#[inline]
pub(crate) fn check_samples(xs: &[f64], offset: u64) -> Result<(), Error> {
    match first_non_finite(xs) {
        Some((k, value)) => Err(Error::NonFiniteSample {
            index: offset + k as u64,
            value,
        }),
        None => Ok(()),
    }
}
