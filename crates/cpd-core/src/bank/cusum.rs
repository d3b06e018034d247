//! The CUSUM bank: structure-of-arrays state, and the driver that walks a matrix in chunks of
//! rows with the two kernels below it: `cusum_tiles` (the tile's state in memory: a `step`, the
//! remainder channels; also the tile view and the alarms' slow path both kernels share) and
//! `cusum_resident` (the state in registers over a chunk). The kernels never call back up here.

use alloc::vec::Vec;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

use super::cusum_resident::{tile_resident, TILE as TILE_R};
use super::cusum_tiles::{tile, Block, Chunk, TILE};
use super::{check_channels, check_matrix, check_readings, checked, drive, Kernel};
use crate::alarm::ChannelAlarm;
use crate::cusum::CusumConfig;
use crate::cusum::CusumLane;
use crate::error::{filled, Error};

/// `N` independent [`crate::Cusum`] detectors with one config, stepped together.
///
/// ```
/// use cpd_core::{CusumBank, CusumConfig, Direction};
///
/// let mut bank = CusumBank::new(3, CusumConfig::new(0.5, 0.01)?)?;
/// let mut alarms = Vec::new();
/// bank.step(&[200.0, 180.0, 150.0], &mut alarms)?;
/// bank.step(&[200.0, 180.0, 150.0], &mut alarms)?;
/// bank.step(&[200.0, 179.0, 150.0], &mut alarms)?; // meter 1 sees a 1 m drop
/// assert_eq!(alarms.len(), 1);
/// assert_eq!((alarms[0].channel, alarms[0].alarm.index), (1, 2));
/// assert_eq!(alarms[0].alarm.direction, Direction::Drop);
/// // A NaN reading rejects the whole step and changes nothing.
/// let before = bank.clone();
/// assert!(bank.step(&[200.0, f64::NAN, 150.0], &mut alarms).is_err());
/// assert_eq!(bank, before);
/// # Ok::<(), cpd_core::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "CusumBankRepr"))]
pub struct CusumBank {
    config: CusumConfig,
    channels: usize,
    steps: u64,
    x_prev: Vec<f64>,
    gp: Vec<f64>,
    gn: Vec<f64>,
    gp_real: Vec<f64>,
    gn_real: Vec<f64>,
    tap: Vec<u64>,
    tan: Vec<u64>,
    x_tap: Vec<f64>,
    x_tan: Vec<f64>,
}

/// Unvalidated mirror used to validate deserialized banks.
#[cfg(feature = "serde")]
#[derive(Deserialize)]
struct CusumBankRepr {
    config: CusumConfig,
    channels: usize,
    steps: u64,
    x_prev: Vec<f64>,
    gp: Vec<f64>,
    gn: Vec<f64>,
    gp_real: Vec<f64>,
    gn_real: Vec<f64>,
    tap: Vec<u64>,
    tan: Vec<u64>,
    x_tap: Vec<f64>,
    x_tan: Vec<f64>,
}

#[cfg(feature = "serde")]
impl TryFrom<CusumBankRepr> for CusumBank {
    type Error = Error;
    fn try_from(r: CusumBankRepr) -> Result<Self, Error> {
        let n = check_channels(r.channels)?;
        let f = [
            &r.x_prev, &r.gp, &r.gn, &r.gp_real, &r.gn_real, &r.x_tap, &r.x_tan,
        ];
        if f.iter().any(|v| v.len() != n) || r.tap.len() != n || r.tan.len() != n {
            return Err(Error::CorruptState {
                reason: "bank state arrays do not match the number of channels",
            });
        }
        let bank = Self {
            config: r.config,
            channels: n,
            steps: r.steps,
            x_prev: r.x_prev,
            gp: r.gp,
            gn: r.gn,
            gp_real: r.gp_real,
            gn_real: r.gn_real,
            tap: r.tap,
            tan: r.tan,
            x_tap: r.x_tap,
            x_tan: r.x_tan,
        };
        for c in 0..n {
            bank.lane(c).check(bank.steps, &bank.config, Some(c))?;
        }
        Ok(bank)
    }
}

impl Kernel for CusumBank {
    fn width(&self) -> usize {
        self.channels
    }

    /// Row 0 of a fresh bank alone (it only primes), then [`rows_per_chunk`] rows (a `step`'s
    /// one row without the division).
    #[inline]
    fn chunk_rows(&self, rows: usize) -> usize {
        if self.steps == 0 || rows == 1 {
            1
        } else {
            rows.min(rows_per_chunk(self.channels))
        }
    }

    /// Several rows: the state in registers (`cusum_resident`); one row (a `step`): the state
    /// stepped in memory, its start values blended in place; the channels past the last whole
    /// tile one by one.
    #[inline]
    fn run_chunk(&mut self, rows: &[f64], len: usize, out: &mut Vec<ChannelAlarm>) {
        let n = self.channels;
        if self.steps == 0 {
            self.prime(rows);
            return;
        }
        let chunk = Chunk {
            rows,
            channels: n,
            first: self.steps,
            threshold: self.config.threshold(),
            drift: self.config.drift(),
        };
        let one_row = len == 1;
        let mut lanes = self.block(0, n);
        let mut c = 0;
        if one_row {
            while c + TILE <= n {
                tile::<TILE, true>(&mut lanes, c, chunk, out);
                c += TILE;
            }
        } else {
            while c + TILE_R <= n {
                tile_resident(&mut lanes, c, &chunk, out);
                c += TILE_R;
            }
        }
        while c < n {
            tile::<1, false>(&mut lanes, c, chunk, out);
            c += 1;
        }
        self.steps += len as u64;
    }
}

impl CusumBank {
    /// A fresh bank of `channels >= 1` detectors.
    ///
    /// Errors with [`Error::InvalidParameter`] (`channels`) when `channels` is 0 or its state
    /// cannot be allocated.
    pub fn new(channels: usize, config: CusumConfig) -> Result<Self, Error> {
        let n = check_channels(channels)?;
        let zeros = || filled("channels", n, 0.0);
        Ok(Self {
            config,
            channels: n,
            steps: 0,
            x_prev: zeros()?,
            gp: zeros()?,
            gn: zeros()?,
            gp_real: zeros()?,
            gn_real: zeros()?,
            tap: filled("channels", n, 0)?,
            tan: filled("channels", n, 0)?,
            x_tap: zeros()?,
            x_tan: zeros()?,
        })
    }

    /// Feeds one reading per channel; appends this step's alarms to `out` in channel order.
    ///
    /// All readings are validated first ([`Error::ChannelCount`], [`Error::NonFiniteReading`]);
    /// on error the bank is unchanged.
    pub fn step(&mut self, readings: &[f64], out: &mut Vec<ChannelAlarm>) -> Result<(), Error> {
        checked(self, readings, out, check_readings)
    }

    /// Feeds a row-major `T x channels` matrix (one row per time step), appending the alarms
    /// in step order (then channel order), exactly as `T` calls of [`CusumBank::step`] would.
    /// The whole matrix is validated first; on error the bank is unchanged. Faster than
    /// stepping row by row: each channel's state stays in registers over a chunk of rows.
    pub fn step_many(&mut self, matrix: &[f64], out: &mut Vec<ChannelAlarm>) -> Result<(), Error> {
        checked(self, matrix, out, check_matrix)
    }

    /// Steps every row of a row-major matrix of samples already validated (the segmented
    /// single-channel update, `crate::cusum::segments`).
    pub(crate) fn advance_many(&mut self, matrix: &[f64], out: &mut Vec<ChannelAlarm>) {
        drive(self, matrix, out);
    }

    /// The state of channels `b..e`.
    fn block(&mut self, b: usize, e: usize) -> Block<'_> {
        Block {
            x_prev: &mut self.x_prev[b..e],
            gp: &mut self.gp[b..e],
            gn: &mut self.gn[b..e],
            gp_real: &mut self.gp_real[b..e],
            gn_real: &mut self.gn_real[b..e],
            tap: &mut self.tap[b..e],
            tan: &mut self.tan[b..e],
            x_tap: &mut self.x_tap[b..e],
            x_tan: &mut self.x_tan[b..e],
        }
    }

    /// Sample 0 of every channel: only primes the previous and start values.
    fn prime(&mut self, readings: &[f64]) {
        self.steps += 1;
        self.x_prev.copy_from_slice(readings);
        self.x_tap.copy_from_slice(readings);
        self.x_tan.copy_from_slice(readings);
    }

    /// Channel `c`'s state as one detector's lane (its starts in the bank's step indices).
    pub(crate) fn lane(&self, c: usize) -> CusumLane {
        CusumLane {
            x_prev: self.x_prev[c],
            gp: self.gp[c],
            gn: self.gn[c],
            gp_real: self.gp_real[c],
            gn_real: self.gn_real[c],
            tap: self.tap[c],
            tan: self.tan[c],
            x_tap: self.x_tap[c],
            x_tan: self.x_tan[c],
        }
    }

    /// Back to the state of [`CusumBank::new`].
    pub fn reset(&mut self) {
        self.steps = 0;
        for v in [
            &mut self.x_prev,
            &mut self.gp,
            &mut self.gn,
            &mut self.gp_real,
            &mut self.gn_real,
            &mut self.x_tap,
            &mut self.x_tan,
        ] {
            v.fill(0.0);
        }
        self.tap.fill(0);
        self.tan.fill(0);
    }

    /// Number of channels.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// Number of steps consumed so far.
    pub fn steps_seen(&self) -> u64 {
        self.steps
    }

    /// The shared config.
    pub fn config(&self) -> &CusumConfig {
        &self.config
    }
}

/// Readings per chunk of rows (512 KiB: a chunk stays in the L2 cache while its tiles walk it;
/// 64 rows at 1 024 channels, over which a tile's state stays in registers. Measured against
/// 128 and 256 KiB at 1 024 channels: as fast on a matrix from memory, 1.4x as fast on a batch
/// in the cache, where the per-chunk work of the tiles shows).
const CHUNK_READINGS: usize = 65_536;

/// Rows per chunk for `channels` channels: as many as fit [`CHUNK_READINGS`], at least 16 and at
/// most 512. A tile's work per chunk (its state loaded and stored once, its previous readings
/// and start values brought up to date) is spread over the rows; the matrix is read once
/// whatever the chunk (each tile reads its own columns of each row).
fn rows_per_chunk(channels: usize) -> usize {
    (CHUNK_READINGS / channels).clamp(16, 512)
}
