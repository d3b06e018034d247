//! The Shewhart bank: running sums per channel, a `[W][channels]` ring, a kernel that steps
//! tiles of channels over chunks of rows (`shewhart_tiles`), the rebuilds at ring wraps, and a
//! rare slow path for the channels that the screen flags.

use alloc::vec::Vec;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

#[cfg(feature = "serde")]
use super::shewhart_tiles::gather;
use super::shewhart_tiles::{chunk, Chunk, Lanes};
use super::{check_channels, check_matrix, check_readings, checked, Kernel};
use crate::alarm::ChannelAlarm;
#[cfg(feature = "serde")]
use crate::error::ensure;
use crate::error::{filled, Error};
#[cfg(feature = "serde")]
use crate::shewhart::check_restored;
use crate::shewhart::{ShewhartConfig, REBUILD_MIN};

/// `N` independent [`crate::Shewhart`] detectors with one config, stepped together.
///
/// The ring buffer is stored `[W][channels]` (one contiguous row per time slot).
///
/// ```
/// use cpd_core::{ShewhartBank, ShewhartConfig};
///
/// let mut bank = ShewhartBank::new(2, ShewhartConfig::new(4, 1.0, 0.5)?)?;
/// let rows = [200.0, 90.0, 200.0, 90.0, 200.0, 90.0, 200.0, 88.0];
/// let mut alarms = Vec::new();
/// bank.step_many(&rows, &mut alarms)?;
/// assert_eq!(alarms.len(), 1);
/// assert_eq!((alarms[0].channel, alarms[0].alarm.index), (1, 3));
/// # Ok::<(), cpd_core::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "ShewhartBankRepr"))]
pub struct ShewhartBank {
    config: ShewhartConfig,
    channels: usize,
    steps: u64,
    since_rebuild: u64,
    pos: usize,
    reference: Vec<f64>,
    s1: Vec<f64>,
    c1: Vec<f64>,
    s2: Vec<f64>,
    c2: Vec<f64>,
    ring: Vec<f64>,
}

/// Unvalidated mirror used to validate deserialized banks.
#[cfg(feature = "serde")]
#[derive(Deserialize)]
struct ShewhartBankRepr {
    config: ShewhartConfig,
    channels: usize,
    steps: u64,
    since_rebuild: u64,
    pos: usize,
    reference: Vec<f64>,
    s1: Vec<f64>,
    c1: Vec<f64>,
    s2: Vec<f64>,
    c2: Vec<f64>,
    ring: Vec<f64>,
}

#[cfg(feature = "serde")]
impl TryFrom<ShewhartBankRepr> for ShewhartBank {
    type Error = Error;
    fn try_from(r: ShewhartBankRepr) -> Result<Self, Error> {
        let n = check_channels(r.channels)?;
        let w = r.config.window();
        let sums: [&[f64]; 5] = [&r.reference, &r.s1, &r.c1, &r.s2, &r.c2];
        ensure(
            sums.iter().all(|v| v.len() == n) && Some(r.ring.len()) == w.checked_mul(n),
            "bank state arrays do not match the channels and window",
        )?;
        check_restored(w, r.steps, r.since_rebuild, r.pos, &r.ring)?;
        for c in 0..n {
            gather::<f64>(sums, c).check(Some(c))?;
        }
        Ok(Self {
            config: r.config,
            channels: n,
            steps: r.steps,
            since_rebuild: r.since_rebuild,
            pos: r.pos,
            reference: r.reference,
            s1: r.s1,
            c1: r.c1,
            s2: r.s2,
            c2: r.c2,
            ring: r.ring,
        })
    }
}

/// Rows per chunk for `channels` channels (a ring wrap ends a chunk sooner): about 512 KiB of
/// readings, at most 512 rows; one row from 65 536 channels on, whose ring row is then written
/// while in the cache (measured at 65 536 channels against 16 rows: 5.7 -> 5.3 ns in a
/// portable build, as fast with AVX-512).
fn rows_per_chunk(channels: usize) -> usize {
    (65_536 / channels).clamp(1, 512)
}

/// A chunk (see `shewhart_tiles`): the rows up to the next ring wrap, then the wrap's row alone
/// (the step, the rebuild of the sums, then the screening, channel by channel, as row by row).
impl Kernel for ShewhartBank {
    fn width(&self) -> usize {
        self.channels
    }

    fn chunk_rows(&self, rows: usize) -> usize {
        let (w, i, slot) = (self.config.window(), self.steps, self.pos);
        // The row whose slot is the ring's last one wraps the ring.
        if slot + 1 == w {
            return 1;
        }
        // Up to the wrap, without it, and all filling or all full.
        let filling = if i >= w as u64 {
            w
        } else {
            (w as u64 - i) as usize
        };
        (w - 1 - slot)
            .min(filling)
            .min(rows_per_chunk(self.channels))
            .min(rows)
    }

    #[inline]
    fn run_chunk(&mut self, rows: &[f64], len: usize, out: &mut Vec<ChannelAlarm>) {
        let (w, n) = (self.config.window(), self.channels);
        let (i, slot) = (self.steps, self.pos);
        if i == 0 {
            self.reference.copy_from_slice(&rows[..n]);
        }
        let full = i >= w as u64;
        let wrap = slot + 1 == w;
        // At a ring wrap, every channel is rebuilt periodically, and off-centre ones always.
        let rebuild_all = wrap && self.since_rebuild + 1 >= REBUILD_MIN;
        let k = Chunk {
            rows,
            channels: n,
            first: i,
            slot,
            rebuild_all,
            config: &self.config,
        };
        let mut lanes = Lanes {
            reference: &mut self.reference,
            s1: &mut self.s1,
            c1: &mut self.c1,
            s2: &mut self.s2,
            c2: &mut self.c2,
            ring: &mut self.ring,
        };
        match (full, wrap) {
            (true, false) => chunk::<true, false>(&mut lanes, &k, out),
            (true, true) => chunk::<true, true>(&mut lanes, &k, out),
            (false, false) => chunk::<false, false>(&mut lanes, &k, out),
            (false, true) => chunk::<false, true>(&mut lanes, &k, out),
        }
        self.steps = i + len as u64;
        self.since_rebuild = if rebuild_all {
            0
        } else {
            self.since_rebuild + len as u64
        };
        self.pos = if slot + len == w { 0 } else { slot + len };
    }
}

impl ShewhartBank {
    /// A fresh bank of `channels >= 1` detectors (allocates `W x channels` samples).
    ///
    /// Errors with [`Error::InvalidParameter`]: `channels` when it is 0 or the per-channel sums
    /// cannot be allocated, `window` when the `W x channels` ring cannot.
    pub fn new(channels: usize, config: ShewhartConfig) -> Result<Self, Error> {
        let n = check_channels(channels)?;
        // The ring holds `window` samples per channel: the window asks for that memory (the
        // channels' own arrays, allocated first, name the channels).
        let w = config.window();
        let too_big = |reason| Error::InvalidParameter {
            name: "window",
            value: w as f64,
            reason,
        };
        let len = w
            .checked_mul(n)
            .ok_or(too_big("window x channels overflows usize"))?;
        let zeros = || filled("channels", n, 0.0);
        Ok(Self {
            config,
            channels: n,
            steps: 0,
            since_rebuild: 0,
            pos: 0,
            reference: zeros()?,
            s1: zeros()?,
            c1: zeros()?,
            s2: zeros()?,
            c2: zeros()?,
            ring: filled("window", len, 0.0).map_err(|_| {
                too_big(
                    "the ring of window x channels samples needs more memory than can be allocated",
                )
            })?,
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
    /// in step order (then channel order), exactly as `T` calls of [`ShewhartBank::step`]
    /// would. The whole matrix is validated first; on error the bank is unchanged. Faster than
    /// stepping row by row: each channel's sums stay in registers over a chunk of rows.
    pub fn step_many(&mut self, matrix: &[f64], out: &mut Vec<ChannelAlarm>) -> Result<(), Error> {
        checked(self, matrix, out, check_matrix)
    }

    /// Back to the state of [`ShewhartBank::new`].
    pub fn reset(&mut self) {
        self.steps = 0;
        self.since_rebuild = 0;
        self.pos = 0;
        for v in [
            &mut self.reference,
            &mut self.s1,
            &mut self.c1,
            &mut self.s2,
            &mut self.c2,
            &mut self.ring,
        ] {
            v.fill(0.0);
        }
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
    pub fn config(&self) -> &ShewhartConfig {
        &self.config
    }
}
