//! Multi-channel banks: one detector per pressure meter, one call per time step.
//!
//! State is kept as structure-of-arrays (one `Vec` per state variable, indexed by channel) and
//! updated with branch-free per-channel arithmetic shared with the single-channel detectors,
//! on explicit vectors across channels (tiles of channels over chunks of rows), so a bank is
//! bit-for-bit equal to `N` independent detectors. Channels that alarm are handled afterwards
//! on a rare slow path.

mod cusum;
mod cusum_resident;
mod cusum_tiles;
mod shewhart;
mod shewhart_tiles;

use alloc::vec::Vec;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

pub use cusum::CusumBank;
pub use shewhart::ShewhartBank;

use crate::alarm::ChannelAlarm;
use crate::error::{first_non_finite, Error};

fn check_channels(channels: usize) -> Result<usize, Error> {
    if channels == 0 {
        Err(Error::InvalidParameter {
            name: "channels",
            value: 0.0,
            reason: "must be >= 1",
        })
    } else {
        Ok(channels)
    }
}

/// Validates one step's readings.
fn check_readings(readings: &[f64], channels: usize) -> Result<(), Error> {
    if readings.len() != channels {
        return Err(Error::ChannelCount {
            expected: channels,
            got: readings.len(),
        });
    }
    match first_non_finite(readings) {
        Some((channel, value)) => Err(Error::NonFiniteReading { channel, value }),
        None => Ok(()),
    }
}

/// What a kind of bank supplies to the shared driver ([`drive`]): how many rows its next chunk
/// takes and how it runs one. The validated entry points ([`checked`]) and the walk over a
/// matrix are the same for every kind.
trait Kernel {
    /// Number of channels.
    fn width(&self) -> usize;
    /// Rows in the next chunk, `rows >= 1` rows being left: from 1 to `rows`.
    fn chunk_rows(&self, rows: usize) -> usize;
    /// Steps every channel over a chunk of `len` validated rows and counts them; appends the
    /// alarms tile after tile (each tile's in row order).
    fn run_chunk(&mut self, rows: &[f64], len: usize, out: &mut Vec<ChannelAlarm>);
}

/// Steps every row of a validated row-major matrix, a chunk of rows at a time. The tiles of a
/// chunk run one after another, so its alarms are put back in step, then channel order (each
/// pair is unique), as stepping row by row appends them.
#[inline]
fn drive<K: Kernel>(bank: &mut K, matrix: &[f64], out: &mut Vec<ChannelAlarm>) {
    let n = bank.width();
    // Rows counted once per call (a division: a `step` of few channels feels it).
    let mut left = matrix.len() / n;
    let mut rows = matrix;
    while left > 0 {
        let len = bank.chunk_rows(left);
        let (now, rest) = rows.split_at(len * n);
        let start = out.len();
        bank.run_chunk(now, len, out);
        out[start..].sort_unstable_by_key(|a| (a.alarm.index, a.channel));
        (rows, left) = (rest, left - len);
    }
}

/// Validates `rows` with `check` ([`check_readings`] for one step, [`check_matrix`] for a
/// matrix), then runs the kernel over them; on error the bank is unchanged. `check` is a
/// generic parameter, not a function pointer: the check is inlined (a `step` of 16 channels
/// took 4 % more instructions with an indirect call).
#[inline]
fn checked<K: Kernel>(
    bank: &mut K,
    rows: &[f64],
    out: &mut Vec<ChannelAlarm>,
    check: impl Fn(&[f64], usize) -> Result<(), Error>,
) -> Result<(), Error> {
    check(rows, bank.width())?;
    drive(bank, rows, out);
    Ok(())
}

/// Asks for the cache lines of `xs` (a hint: no fault, no effect on results).
#[inline(always)]
fn prefetch(xs: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    for x in xs.iter().step_by(8) {
        safe_arch::prefetch_t0(x);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = xs;
}

/// Validates a row-major `T x channels` matrix.
fn check_matrix(matrix: &[f64], channels: usize) -> Result<(), Error> {
    if !matrix.len().is_multiple_of(channels) {
        return Err(Error::MatrixShape {
            len: matrix.len(),
            channels,
        });
    }
    match first_non_finite(matrix) {
        Some((k, value)) => Err(Error::NonFiniteMatrixReading {
            row: k / channels,
            channel: k % channels,
            value,
        }),
        None => Ok(()),
    }
}

/// A bank of either kind, for callers that pick the detector at run time.
///
/// ```
/// use cpd_core::{Bank, CusumBank, CusumConfig};
/// let mut bank = Bank::Cusum(CusumBank::new(2, CusumConfig::new(1.0, 0.0)?)?);
/// let mut alarms = Vec::new();
/// bank.step_many(&[5.0, 5.0, 5.0, 7.0], &mut alarms)?;
/// assert_eq!(alarms.len(), 1);
/// assert_eq!((bank.channels(), bank.steps_seen(), bank.kind()), (2, 2, "cusum"));
/// # Ok::<(), cpd_core::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub enum Bank {
    /// A bank of CUSUM detectors.
    Cusum(CusumBank),
    /// A bank of Shewhart detectors.
    Shewhart(ShewhartBank),
}

impl Bank {
    /// See [`CusumBank::step`] / [`ShewhartBank::step`].
    pub fn step(&mut self, readings: &[f64], out: &mut Vec<ChannelAlarm>) -> Result<(), Error> {
        match self {
            Bank::Cusum(b) => b.step(readings, out),
            Bank::Shewhart(b) => b.step(readings, out),
        }
    }

    /// See [`CusumBank::step_many`] / [`ShewhartBank::step_many`].
    pub fn step_many(&mut self, matrix: &[f64], out: &mut Vec<ChannelAlarm>) -> Result<(), Error> {
        match self {
            Bank::Cusum(b) => b.step_many(matrix, out),
            Bank::Shewhart(b) => b.step_many(matrix, out),
        }
    }

    /// Back to a fresh bank.
    pub fn reset(&mut self) {
        match self {
            Bank::Cusum(b) => b.reset(),
            Bank::Shewhart(b) => b.reset(),
        }
    }

    /// Number of channels.
    pub fn channels(&self) -> usize {
        match self {
            Bank::Cusum(b) => b.channels(),
            Bank::Shewhart(b) => b.channels(),
        }
    }

    /// Number of steps consumed so far.
    pub fn steps_seen(&self) -> u64 {
        match self {
            Bank::Cusum(b) => b.steps_seen(),
            Bank::Shewhart(b) => b.steps_seen(),
        }
    }

    /// `"cusum"` or `"shewhart"`.
    pub fn kind(&self) -> &'static str {
        match self {
            Bank::Cusum(_) => "cusum",
            Bank::Shewhart(_) => "shewhart",
        }
    }
}

impl From<CusumBank> for Bank {
    fn from(b: CusumBank) -> Self {
        Bank::Cusum(b)
    }
}

impl From<ShewhartBank> for Bank {
    fn from(b: ShewhartBank) -> Self {
        Bank::Shewhart(b)
    }
}
