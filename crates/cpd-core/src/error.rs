//! The crate's single error type.

use alloc::string::String;
use alloc::vec::Vec;
use core::fmt;

use crate::math::abs;

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
    /// A NaN, an infinite or an out-of-range sample (beyond ±[`MAX_SAMPLE`]) was fed to a
    /// single-channel detector or a batch function.
    NonFiniteSample {
        /// Index of the bad sample in the detector's stream (or in the batch slice).
        index: u64,
        /// The offending value.
        value: f64,
    },
    /// A NaN, an infinite or an out-of-range reading (beyond ±[`MAX_SAMPLE`]) was passed to a
    /// bank's `step`.
    NonFiniteReading {
        /// Channel (column) of the bad reading.
        channel: usize,
        /// The offending value.
        value: f64,
    },
    /// A NaN, an infinite or an out-of-range value (beyond ±[`MAX_SAMPLE`]) in the matrix
    /// passed to a bank's `step_many`.
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
    /// A deserialized state field holds a value no detector can reach: a NaN or an infinity, a
    /// sample beyond ±[`MAX_SAMPLE`], a negative drift sum, a real sum above the threshold.
    InvalidState {
        /// The field, as named in the serde form (`"gp"`, `"s1"`, `"ring"`, `"reference"`, ...).
        field: &'static str,
        /// The element of an array field: a bank's channel, a ring's slot (`None` for a scalar).
        index: Option<usize>,
        /// The offending value.
        value: f64,
        /// What the field must hold, e.g. `"must be finite"`.
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
    /// Snapshot bytes refused before their content is decoded (see `cpd_core::snapshot`): not a
    /// snapshot, truncated or extended, altered (checksum mismatch), or of a format version this
    /// version does not read.
    UnreadableSnapshot {
        /// The kind that was expected (`"Cusum"`, `"Shewhart"`, `"DetectorBank"`).
        kind: &'static str,
        /// What is wrong with the bytes.
        problem: SnapshotProblem,
    },
}

/// Why snapshot bytes are unreadable ([`Error::UnreadableSnapshot`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum SnapshotProblem {
    /// The bytes begin neither with the snapshot magic `CPDS` nor as a format-1 snapshot.
    NotASnapshot,
    /// Fewer bytes than the snapshot's header declares (or than a header and checksum take).
    Truncated {
        /// Bytes given.
        len: usize,
        /// Bytes expected.
        expected: u64,
    },
    /// More bytes than the snapshot's header declares.
    TrailingBytes {
        /// Bytes given.
        len: usize,
        /// Bytes expected.
        expected: u64,
    },
    /// The CRC-32C stored at the end is not that of the bytes before it: they were altered.
    ChecksumMismatch {
        /// The checksum stored in the snapshot.
        stored: u32,
        /// The checksum of the bytes as given.
        computed: u32,
    },
    /// An intact snapshot of a format version this version does not read (a newer one).
    UnknownVersion {
        /// The snapshot's format version.
        version: u8,
    },
}

impl fmt::Display for SnapshotProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SnapshotProblem::NotASnapshot => write!(f, "not a snapshot (no snapshot header)"),
            SnapshotProblem::Truncated { len, expected } => {
                write!(f, "truncated: {len} bytes of {expected}")
            }
            SnapshotProblem::TrailingBytes { len, expected } => write!(
                f,
                "{} bytes after its end ({len} bytes, the snapshot is {expected})",
                *len as u64 - expected
            ),
            SnapshotProblem::ChecksumMismatch { stored, computed } => write!(
                f,
                "checksum mismatch (CRC-32C stored {stored:#010x}, computed {computed:#010x}): \
                 the bytes were altered"
            ),
            SnapshotProblem::UnknownVersion { version } => write!(
                f,
                "unknown format version {version} (this version reads formats 1 and 2)"
            ),
        }
    }
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
                write!(
                    f,
                    "{} sample {} at index {index}",
                    bad_kind(*value),
                    Num(*value)
                )
            }
            Error::NonFiniteReading { channel, value } => {
                write!(
                    f,
                    "{} reading {} on channel {channel}",
                    bad_kind(*value),
                    Num(*value)
                )
            }
            Error::NonFiniteMatrixReading {
                row,
                channel,
                value,
            } => write!(
                f,
                "{} reading {} at row {row}, channel {channel}",
                bad_kind(*value),
                Num(*value)
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
            Error::InvalidState {
                field,
                index,
                value,
                reason,
            } => {
                write!(f, "invalid state field `{field}`")?;
                if let Some(i) = index {
                    write!(f, "[{i}]")?;
                }
                write!(f, " = {}: {reason}", Num(*value))
            }
            Error::InvalidSnapshot { kind, detail } => {
                write!(f, "invalid {kind} snapshot: {detail}")
            }
            Error::UnreadableSnapshot { kind, problem } => {
                write!(f, "unreadable {kind} snapshot: {problem}")
            }
        }
    }
}

impl core::error::Error for Error {}

/// The largest sample magnitude the detectors take: no sensor reports 1e100 of anything, and
/// below it the running sums of squares cannot overflow (a Shewhart window of up to 2^64
/// samples, each up to `(2e100)^2`, sums to about 1e220), so every state a detector reaches is
/// finite and a restored state can be held to that.
pub const MAX_SAMPLE: f64 = 1e100;

/// True for a sample the detectors take: finite and within ±[`MAX_SAMPLE`] (false for NaN).
#[inline(always)]
pub(crate) fn in_range(x: f64) -> bool {
    abs(x) <= MAX_SAMPLE
}

/// A value in a message: plain decimals in the usual range, else scientific notation (`1e160`,
/// not 161 digits); `NaN`, `inf`, `-inf` as Rust writes them.
struct Num(f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if !v.is_finite() || v == 0.0 || (1e-6..1e16).contains(&abs(v)) {
            write!(f, "{v}")
        } else {
            write!(f, "{v:e}")
        }
    }
}

/// How a refused sample is described: "non-finite" or "out-of-range".
fn bad_kind(value: f64) -> &'static str {
    if value.is_finite() {
        "out-of-range (|x| > 1e100)"
    } else {
        "non-finite"
    }
}

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

/// A restored-state field check: [`Error::InvalidState`] naming `field` (and `index`) unless
/// `ok`.
#[cfg(feature = "serde")]
pub(crate) fn field(
    ok: bool,
    field: &'static str,
    index: Option<usize>,
    value: f64,
    reason: &'static str,
) -> Result<(), Error> {
    if ok {
        Ok(())
    } else {
        Err(Error::InvalidState {
            field,
            index,
            value,
            reason,
        })
    }
}

/// A restored field that holds a sample: finite and within ±[`MAX_SAMPLE`].
#[cfg(feature = "serde")]
pub(crate) fn sample_field(name: &'static str, index: Option<usize>, x: f64) -> Result<(), Error> {
    field(
        in_range(x),
        name,
        index,
        x,
        "must be a sample: finite, within +-1e100",
    )
}

/// A restored field that holds a running sum: finite.
#[cfg(feature = "serde")]
pub(crate) fn finite_field(name: &'static str, index: Option<usize>, x: f64) -> Result<(), Error> {
    field(x.is_finite(), name, index, x, "must be finite")
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

/// Index and value of the first element of `xs` that is not a sample ([`in_range`]), if any.
#[inline]
pub(crate) fn first_non_finite(xs: &[f64]) -> Option<(usize, f64)> {
    // Branch-free (vectorizable) scan first; locate the culprit only when something is wrong.
    if xs.iter().fold(true, |ok, v| ok & in_range(*v)) {
        return None;
    }
    xs.iter()
        .enumerate()
        .find(|(_, v)| !in_range(**v))
        .map(|(i, v)| (i, *v))
}

/// Rejects a non-finite or out-of-range sample with the stream index it would have had.
#[inline(always)]
pub(crate) fn check_sample(x: f64, index: u64) -> Result<(), Error> {
    if in_range(x) {
        Ok(())
    } else {
        Err(Error::NonFiniteSample { index, value: x })
    }
}

/// Rejects a slice holding a non-finite or out-of-range sample, naming the first one by its stream index
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
