//! Streaming Shewhart control chart over a sliding window (the paper's eq. 3 and Algorithm 2,
//! with its extra amplitude threshold).
//!
//! # How the window statistics are kept
//! Each detector keeps a ring buffer of the last `W` samples and two compensated running sums
//! (TwoSum error terms) of `y = x - reference` and `y²`, so each sample costs O(1) whatever `W`.
//! Shifting by a reference value (first the first sample, then the window mean at each
//! periodic rebuild) avoids the cancellation that plain `Σx²` suffers on heads near 200 m that
//! move by millimetres. Every `max(W, 1024)` samples (at a ring wrap) the sums are rebuilt from
//! the ring, which re-centres the reference and bounds any drift; a wrap also rebuilds them
//! early when the window has moved far from the reference (after a burst's level shift).
//!
//! # Exactness
//! The decision at sample `i` equals [`crate::detect_shewhart`] applied to the window
//! `x[i+1-W..=i]` at its last index, bit for bit. The running sums give the decision
//! directly unless the test is within a rigorous error margin of a tie (relative ~1e-10):
//! then the window is re-scanned with NumPy's exact summation order (O(W), rare on real data;
//! frequent only for exact ties such as `W = 2, sigma = 1`).

use alloc::vec::Vec;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

mod config;
mod sums;

pub use config::ShewhartConfig;

pub(crate) use sums::{exact_decision, Lane, Sums};
use sums::{PairedSums, RunningSums};

use crate::alarm::{Alarm, Direction};
use crate::error::{check_sample, check_samples, filled, Error};
#[cfg(feature = "serde")]
use crate::error::{ensure, sample_field, MAX_COUNT};
use crate::math::sqrt;

/// Rebuild the running sums at the first ring wrap after this many samples (at least).
pub(crate) const REBUILD_MIN: u64 = 1024;

/// The small, copyable part of a detector's state: kept in registers while stepping.
#[derive(Clone, Copy)]
struct Cursor<S> {
    seen: u64,
    since_rebuild: u64,
    pos: usize,
    /// The sums while stepping: [`Sums`] per `update` call, [`PairedSums`] over a slice
    /// (converted from and back to the stored [`Sums`] once per slice).
    sums: S,
}

impl<S: RunningSums> Cursor<S> {
    /// One sample (finite): ring, sums, periodic rebuild, decision.
    #[inline(always)]
    fn step(&mut self, ring: &mut [f64], config: &ShewhartConfig, x: f64) -> Option<Alarm> {
        let w = config.window;
        let d = config.derived;
        let i = self.seen;
        let mut sums = self.sums;
        if i == 0 {
            *sums.reference() = x;
        }
        let pos = self.pos;
        let old = core::mem::replace(&mut ring[pos], x);
        if i >= w as u64 {
            sums.slide(x, old);
        } else {
            sums.push(x);
        }
        let pos = if pos + 1 == w { 0 } else { pos + 1 };
        let since = self.since_rebuild + 1;
        self.pos = pos;
        self.seen = i + 1;
        self.since_rebuild = since;
        // The periodic schedule depends on the sample count only (as in a bank).
        if pos == 0 && (since >= REBUILD_MIN || sums.into().off_centre(d.inv_w)) {
            if since >= REBUILD_MIN {
                self.since_rebuild = 0;
            }
            sums = rebuilt(ring, *sums.reference(), d.inv_w).into();
        }
        self.sums = sums;
        if i + 1 < w as u64 || sums.surely_in_control(x, &d, config.threshold) {
            return None;
        }
        let decision = sums
            .into()
            .decide(x, config, || exact_in_ring(ring, pos, x, config));
        decision.map(|d| Alarm::at(i, d))
    }
}

/// The sums rebuilt from the ring (called at a wrap, when the ring is in time order).
#[cold]
#[inline(never)]
fn rebuilt(ring: &[f64], reference: f64, inv_w: f64) -> Sums {
    let mut sums = Sums {
        reference,
        ..Sums::ZERO
    };
    sums.rebuild(ring.len(), inv_w, |k| ring[k]);
    sums
}

/// The exact decision for the newest sample of a ring whose oldest sample is at `pos`.
#[cold]
#[inline(never)]
fn exact_in_ring(
    ring: &[f64],
    pos: usize,
    x: f64,
    config: &ShewhartConfig,
) -> Option<(Direction, f64)> {
    let (newer, older) = ring.split_at(pos);
    let n_old = older.len();
    let get = |k: usize| {
        if k < n_old {
            older[k]
        } else {
            newer[k - n_old]
        }
    };
    exact_decision(x, ring.len(), get, config)
}

/// Streaming Shewhart detector over the last `W` samples (the current one included).
///
/// No alarm is possible before `W` samples have been seen. Sample `i` alarms when
/// `|x_i - μ| > sigma·σ` and `|x_i - μ| > threshold`, with `μ`, `σ` the mean and population
/// standard deviation of `x[i+1-W..=i]`; the [`Alarm`] has `index = start = i`, the sign of
/// `x_i - μ` as direction and `x_i - μ` as amplitude. O(1) per sample whatever `W`; see the
/// module docs for numerical stability and exactness.
///
/// **Non-finite samples** are rejected with [`Error::NonFiniteSample`] and leave the detector
/// exactly as it was.
///
/// ```
/// use cpd_core::{Direction, Shewhart, ShewhartConfig};
///
/// let mut det = Shewhart::new(ShewhartConfig::new(8, 2.0, 0.5)?)?;
/// let mut heads = vec![200.0, 200.001, 199.999, 200.0, 200.002, 199.998, 200.0];
/// heads.push(198.0); // a sudden 2 m drop
/// let mut alarms = Vec::new();
/// det.update_slice(&heads, &mut alarms)?;
/// assert_eq!(alarms.len(), 1);
/// assert_eq!((alarms[0].index, alarms[0].direction), (7, Direction::Drop));
/// assert!((alarms[0].amplitude + 1.75).abs() < 1e-6);
/// # Ok::<(), cpd_core::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "ShewhartRepr"))]
pub struct Shewhart {
    config: ShewhartConfig,
    seen: u64,
    since_rebuild: u64,
    pos: usize,
    sums: Sums,
    ring: Vec<f64>,
}

/// Unvalidated mirror used to validate deserialized detectors.
#[cfg(feature = "serde")]
#[derive(Deserialize)]
struct ShewhartRepr {
    config: ShewhartConfig,
    seen: u64,
    since_rebuild: u64,
    pos: usize,
    sums: Sums,
    ring: Vec<f64>,
}

#[cfg(feature = "serde")]
impl TryFrom<ShewhartRepr> for Shewhart {
    type Error = Error;
    fn try_from(r: ShewhartRepr) -> Result<Self, Error> {
        ensure(
            r.ring.len() == r.config.window,
            "ring buffer length does not match the window",
        )?;
        check_restored(r.config.window, r.seen, r.since_rebuild, r.pos, &r.ring)?;
        r.sums.check(None)?;
        Ok(Self {
            config: r.config,
            seen: r.seen,
            since_rebuild: r.since_rebuild,
            pos: r.pos,
            sums: r.sums,
            ring: r.ring,
        })
    }
}

/// Validates the counters and the ring of a restored detector or bank of window `w`: counts in
/// range, the ring position consistent with them, every slot of the ring a sample (a detector
/// only ever stores samples; [`Error::InvalidState`] names the slot). The running sums are
/// checked apart ([`Sums::check`]): samples within ±[`crate::MAX_SAMPLE`] keep them finite.
#[cfg(feature = "serde")]
pub(crate) fn check_restored(
    w: usize,
    seen: u64,
    since_rebuild: u64,
    pos: usize,
    ring: &[f64],
) -> Result<(), Error> {
    ensure(seen <= MAX_COUNT, "sample count out of range")?;
    ensure(
        since_rebuild <= seen,
        "rebuild counter past the sample count",
    )?;
    ensure(
        pos < w && (seen >= w as u64 || pos as u64 == seen),
        "ring position does not match the window and the sample count",
    )?;
    ring.iter()
        .enumerate()
        .try_for_each(|(k, &x)| sample_field("ring", Some(k), x))
}

impl Shewhart {
    /// A fresh detector (allocates the `W`-sample ring).
    ///
    /// Errors with [`Error::InvalidParameter`] (`window`) when the ring cannot be allocated.
    ///
    /// ```
    /// use cpd_core::{Shewhart, ShewhartConfig};
    /// let huge = ShewhartConfig::with_threshold(1 << 60, 0.5)?;
    /// assert!(Shewhart::new(huge).unwrap_err().is_config());
    /// # Ok::<(), cpd_core::Error>(())
    /// ```
    pub fn new(config: ShewhartConfig) -> Result<Self, Error> {
        Ok(Self {
            config,
            seen: 0,
            since_rebuild: 0,
            pos: 0,
            sums: Sums::ZERO,
            ring: filled("window", config.window, 0.0)?,
        })
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
    fn cursor<S: RunningSums>(&self) -> Cursor<S> {
        Cursor {
            seen: self.seen,
            since_rebuild: self.since_rebuild,
            pos: self.pos,
            sums: self.sums.into(),
        }
    }

    #[inline(always)]
    fn set_cursor<S: RunningSums>(&mut self, c: Cursor<S>) {
        self.seen = c.seen;
        self.since_rebuild = c.since_rebuild;
        self.pos = c.pos;
        self.sums = c.sums.into();
    }

    #[inline(always)]
    fn update_unchecked(&mut self, x: f64) -> Option<Alarm> {
        let mut cur = self.cursor::<Sums>();
        let alarm = cur.step(&mut self.ring, &self.config, x);
        self.set_cursor(cur);
        alarm
    }

    /// Feeds a slice of samples, appending the alarms to `out`.
    ///
    /// The whole slice is validated first: if any sample is non-finite, nothing is consumed,
    /// the state is unchanged and the error names the first bad sample's stream index.
    pub fn update_slice(&mut self, xs: &[f64], out: &mut Vec<Alarm>) -> Result<(), Error> {
        check_samples(xs, self.seen)?;
        // The counters and sums live in locals (registers) for the whole slice.
        let mut cur = self.cursor::<PairedSums>();
        for &x in xs {
            if let Some(a) = cur.step(&mut self.ring, &self.config, x) {
                out.push(a);
            }
        }
        self.set_cursor(cur);
        Ok(())
    }

    /// Back to the state of [`Shewhart::new`] with the same config.
    pub fn reset(&mut self) {
        self.seen = 0;
        self.since_rebuild = 0;
        self.pos = 0;
        self.sums = Sums::ZERO;
        self.ring.fill(0.0);
    }

    /// The detector's config.
    pub fn config(&self) -> &ShewhartConfig {
        &self.config
    }

    /// Number of (finite) samples consumed so far.
    pub fn samples_seen(&self) -> u64 {
        self.seen
    }

    /// Number of samples currently in the window (`min(samples_seen, W)`).
    pub fn len(&self) -> usize {
        self.seen.min(self.config.window as u64) as usize
    }

    /// True before the first sample.
    pub fn is_empty(&self) -> bool {
        self.seen == 0
    }

    /// Mean of the samples in the window (from the running sums), `None` before the first sample.
    pub fn mean(&self) -> Option<f64> {
        let n = self.len();
        (n > 0).then(|| self.sums.reference + (self.sums.s1 + self.sums.c1) / n as f64)
    }

    /// Population standard deviation of the window (from the running sums), `None` before the
    /// first sample.
    pub fn std(&self) -> Option<f64> {
        let n = self.len();
        (n > 0).then(|| {
            let mu_y = (self.sums.s1 + self.sums.c1) / n as f64;
            let var = (self.sums.s2 + self.sums.c2) / n as f64 - mu_y * mu_y;
            sqrt(if var > 0.0 { var } else { 0.0 })
        })
    }
}
