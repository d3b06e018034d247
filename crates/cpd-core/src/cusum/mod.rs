//! Streaming two-sided CUSUM (the paper's eq. 1–2 and Algorithm 1; TSNet 0.3.1's online pass).

mod config;
mod lane;
mod segments;

use alloc::vec::Vec;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

pub use config::CusumConfig;
pub(crate) use lane::{CusumLane, DROP, RISE};

use crate::alarm::Alarm;
use crate::error::{check_sample, check_samples, Error};

/// Streaming two-sided CUSUM, one sample per call.
///
/// Semantics are TSNet 0.3.1's `detect_cusum` online pass (the paper's Algorithm 1):
/// sample 0 only primes the previous value; for `i >= 1`, with `s = x[i] - x[i-1]`,
/// `gp += s - drift`, `gp_real += s`, `gn += -s - drift`, `gn_real -= s`; when `gp < 0`
/// both `gp` and `gp_real` reset to 0 and the rise start `tap = i` (likewise `gn`/`tan`);
/// when `gp_real > threshold` or `gn_real > threshold` an [`Alarm`] is raised with
/// start `tap` (rise) or `tan` (drop) and amplitude `x[i] - x[start]`, and all four sums
/// reset to 0.
///
/// **Non-finite samples** (NaN, ±inf, and values beyond ±[`crate::MAX_SAMPLE`]) are rejected with [`Error::NonFiniteSample`] and
/// leave the detector exactly as it was: the sample is not counted, the next finite
/// sample continues as if the bad one never arrived. Missing readings are the caller's
/// business (skip them, or hold the last value).
///
/// ```
/// use cpd_core::{Cusum, CusumConfig, Direction};
///
/// let mut det = Cusum::new(CusumConfig::new(0.5, 0.01)?);
/// let heads = [200.0, 200.0, 200.0, 199.2, 199.2];
/// let mut alarms = Vec::new();
/// det.update_slice(&heads, &mut alarms)?;
/// assert_eq!(alarms.len(), 1);
/// let a = alarms[0];
/// // gn crossed 0 for the last time at sample 2: the drop started there.
/// assert_eq!((a.index, a.start, a.direction), (3, 2, Direction::Drop));
/// assert!((a.amplitude + 0.8).abs() < 1e-9);
/// // A NaN is refused and changes nothing.
/// let before = det.clone();
/// assert!(det.update(f64::NAN).is_err());
/// assert_eq!(det, before);
/// # Ok::<(), cpd_core::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "CusumRepr"))]
pub struct Cusum {
    config: CusumConfig,
    seen: u64,
    lane: CusumLane,
}

/// Unvalidated mirror used to validate deserialized detectors.
#[cfg(feature = "serde")]
#[derive(Deserialize)]
struct CusumRepr {
    config: CusumConfig,
    seen: u64,
    lane: CusumLane,
}

#[cfg(feature = "serde")]
impl TryFrom<CusumRepr> for Cusum {
    type Error = Error;
    fn try_from(r: CusumRepr) -> Result<Self, Error> {
        r.lane.check(r.seen, &r.config, None)?;
        Ok(Self {
            config: r.config,
            seen: r.seen,
            lane: r.lane,
        })
    }
}

impl Cusum {
    /// A fresh detector.
    pub fn new(config: CusumConfig) -> Self {
        Self {
            config,
            seen: 0,
            lane: CusumLane::ZERO,
        }
    }

    /// Feeds one sample; returns the alarm it raises, if any.
    ///
    /// Errors with [`Error::NonFiniteSample`] (state unchanged) on NaN, ±inf or a value beyond
    /// ±[`crate::MAX_SAMPLE`].
    #[inline]
    pub fn update(&mut self, x: f64) -> Result<Option<Alarm>, Error> {
        check_sample(x, self.seen)?;
        Ok(self.update_unchecked(x))
    }

    #[inline(always)]
    fn update_unchecked(&mut self, x: f64) -> Option<Alarm> {
        let i = self.seen;
        self.seen += 1;
        if i == 0 {
            self.lane.prime(x);
            return None;
        }
        let flags = self
            .lane
            .step_scalar(x, i, self.config.threshold(), self.config.drift());
        if flags == 0 {
            None
        } else {
            Some(self.lane.alarm(flags, i, x))
        }
    }

    /// Feeds a slice of samples, appending the alarms to `out`.
    ///
    /// If any sample is non-finite, nothing is consumed: the state and `out` are as they were
    /// and the error names the first bad sample's stream index.
    pub fn update_slice(&mut self, xs: &[f64], out: &mut Vec<Alarm>) -> Result<(), Error> {
        // Long slices are checked block by block as they run (each block read once from
        // memory, then from the cache), so a bad sample late in the slice puts back the state
        // and the alarms of the blocks before it.
        let (before, given) = (self.lane, out.len());
        let fed = self.feed(xs, out);
        if fed.is_err() {
            self.lane = before;
            out.truncate(given);
        }
        fed
    }

    /// [`Cusum::update_slice`] without putting anything back on error: the segments check
    /// their blocks, the rest is checked before it runs; `seen` is counted only on success.
    fn feed(&mut self, xs: &[f64], out: &mut Vec<Alarm>) -> Result<(), Error> {
        let (first, rest, seen) = match xs.split_first() {
            None => return Ok(()),
            Some((&x, rest)) if self.seen == 0 => {
                check_sample(x, 0)?;
                (Some(x), rest, 1)
            }
            Some(_) => (None, xs, self.seen),
        };
        if let Some(x) = first {
            self.lane.prime(x);
        }
        // Whole blocks as a bank of segments (`segments`), the rest sample after sample with the
        // state in locals (registers).
        let done = segments::run(&mut self.lane, rest, seen, &self.config, out)?;
        check_samples(&rest[done..], seen + done as u64)?;
        let (thr, drift) = (self.config.threshold(), self.config.drift());
        self.lane
            .run(&rest[done..], seen + done as u64, thr, drift, out);
        self.seen = seen + rest.len() as u64;
        Ok(())
    }

    /// Back to the state of [`Cusum::new`] with the same config.
    pub fn reset(&mut self) {
        *self = Self::new(self.config);
    }

    /// The detector's config.
    pub fn config(&self) -> &CusumConfig {
        &self.config
    }

    /// Number of (finite) samples consumed so far.
    pub fn samples_seen(&self) -> u64 {
        self.seen
    }

    /// Cumulative sum for a rise, with drift.
    pub fn gp(&self) -> f64 {
        self.lane.gp
    }

    /// Cumulative sum for a drop, with drift.
    pub fn gn(&self) -> f64 {
        self.lane.gn
    }

    /// Cumulative rise without drift (the amplitude tracked since `tap`).
    pub fn gp_real(&self) -> f64 {
        self.lane.gp_real
    }

    /// Cumulative drop without drift (the amplitude tracked since `tan`).
    pub fn gn_real(&self) -> f64 {
        self.lane.gn_real
    }

    /// Current start index of a rise (`tap`).
    pub fn rise_start(&self) -> u64 {
        self.lane.tap
    }

    /// Current start index of a drop (`tan`).
    pub fn drop_start(&self) -> u64 {
        self.lane.tan
    }
}
