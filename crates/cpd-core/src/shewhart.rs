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

use alloc::vec;
use alloc::vec::Vec;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

use crate::alarm::{Alarm, Direction};
use crate::error::{check_sample, check_samples, positive, Error};
use crate::math::{abs, sqrt};
use crate::stats::{lane_sum, np_mean_std, out_of_control};

/// Rebuild the running sums at the first ring wrap after this many samples (at least).
pub(crate) const REBUILD_MIN: u64 = 1024;

/// At a ring wrap, the sums are also rebuilt when `mean(y)² > CANCELLATION · var`, i.e. when the
/// reference is so far from the window (after a level shift) that `E[y²] - E[y]²` would lose
/// more than about 6 of its 16 digits.
const CANCELLATION: f64 = (1u64 << 20) as f64;

/// Relative error margin of the fast decision (about 4.5e5 machine epsilons).
const MARGIN: f64 = 1e-10;

/// Classification of one sample by the fast path.
pub(crate) const NONE: u8 = 0;
/// Out of control, `x > μ`.
pub(crate) const RISE: u8 = 1;
/// Out of control, `x < μ`.
pub(crate) const DROP: u8 = 2;
/// Too close to a tie for the running sums: decide with the exact window scan.
pub(crate) const EXACT: u8 = 4;

/// Validated Shewhart parameters.
///
/// `window >= 2`; `sigma` (the paper's `s`, width of the control limits in standard deviations)
/// and `threshold` (minimum `|x - μ|`) finite and `> 0`. The paper uses one value for both.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "ShewhartConfigRepr"))]
pub struct ShewhartConfig {
    window: usize,
    sigma: f64,
    threshold: f64,
    #[cfg_attr(feature = "serde", serde(skip_serializing))]
    derived: Derived,
}

/// Constants of the hot path, derived from the config.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Derived {
    pub inv_w: f64,
    pub sigma2_hi: f64,
    pub sigma2_lo: f64,
}

impl ShewhartConfig {
    /// Builds a config, naming the offending parameter on error.
    ///
    /// ```
    /// use cpd_core::ShewhartConfig;
    /// assert!(ShewhartConfig::new(50, 0.3, 0.3).is_ok());
    /// let err = ShewhartConfig::new(1, 0.3, 0.3).unwrap_err();
    /// assert!(err.to_string().contains("window"));
    /// ```
    pub fn new(window: usize, sigma: f64, threshold: f64) -> Result<Self, Error> {
        if window < 2 {
            return Err(Error::InvalidParameter {
                name: "window",
                value: window as f64,
                reason: "must be >= 2",
            });
        }
        let sigma = positive("sigma", sigma)?;
        let threshold = positive("threshold", threshold)?;
        let sigma2 = sigma * sigma;
        Ok(Self {
            window,
            sigma,
            threshold,
            derived: Derived {
                inv_w: 1.0 / window as f64,
                sigma2_hi: sigma2 * (1.0 + MARGIN),
                sigma2_lo: sigma2 * (1.0 - MARGIN),
            },
        })
    }

    /// Window length `W` (the current sample included).
    pub fn window(&self) -> usize {
        self.window
    }

    /// Width of the control limits in standard deviations (the paper's `s`).
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// Minimum `|x - μ|` for an alarm.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    pub(crate) fn derived(&self) -> &Derived {
        &self.derived
    }
}

/// Unvalidated mirror used to validate deserialized configs.
#[cfg(feature = "serde")]
#[derive(Deserialize)]
struct ShewhartConfigRepr {
    window: usize,
    sigma: f64,
    threshold: f64,
}

#[cfg(feature = "serde")]
impl TryFrom<ShewhartConfigRepr> for ShewhartConfig {
    type Error = Error;
    fn try_from(r: ShewhartConfigRepr) -> Result<Self, Error> {
        ShewhartConfig::new(r.window, r.sigma, r.threshold)
    }
}

/// Adds `v` to the compensated sum `(s, c)` (Knuth's TwoSum; branch-free).
#[inline(always)]
fn acc(s: f64, c: f64, v: f64) -> (f64, f64) {
    let t = s + v;
    let bp = t - s;
    let err = (s - (t - bp)) + (v - bp);
    (t, c + err)
}

/// Running window sums of one channel, shared by the detector and the bank.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub(crate) struct Sums {
    /// Reference subtracted from every sample.
    pub reference: f64,
    /// Σy and its compensation.
    pub s1: f64,
    pub c1: f64,
    /// Σy² and its compensation.
    pub s2: f64,
    pub c2: f64,
}

impl Sums {
    pub(crate) const ZERO: Self = Self {
        reference: 0.0,
        s1: 0.0,
        c1: 0.0,
        s2: 0.0,
        c2: 0.0,
    };

    /// Adds a sample while the window is filling.
    #[inline(always)]
    pub(crate) fn push(&mut self, x: f64) {
        let y = x - self.reference;
        (self.s1, self.c1) = acc(self.s1, self.c1, y);
        (self.s2, self.c2) = acc(self.s2, self.c2, y * y);
    }

    /// Adds `x` and removes `old` (the window is full).
    #[inline(always)]
    pub(crate) fn slide(&mut self, x: f64, old: f64) {
        let y = x - self.reference;
        let yo = old - self.reference;
        let (s1, c1) = acc(self.s1, self.c1, y);
        (self.s1, self.c1) = acc(s1, c1, -yo);
        let (s2, c2) = acc(self.s2, self.c2, y * y);
        (self.s2, self.c2) = acc(s2, c2, -(yo * yo));
    }

    /// Recomputes the sums of the `n` window values `get(0..n)` around their mean.
    #[inline]
    pub(crate) fn rebuild(&mut self, n: usize, inv_n: f64, get: impl Fn(usize) -> f64) {
        let reference = lane_sum(n, &get) * inv_n;
        self.reference = reference;
        self.s1 = lane_sum(n, |i| get(i) - reference);
        self.c1 = 0.0;
        self.s2 = lane_sum(n, |i| {
            let y = get(i) - reference;
            y * y
        });
        self.c2 = 0.0;
    }

    /// True when the reference is far enough from the window to cost precision (see
    /// [`CANCELLATION`]).
    #[inline(always)]
    pub(crate) fn off_centre(&self, inv_w: f64) -> bool {
        let mu_y = (self.s1 + self.c1) * inv_w;
        let var = (self.s2 + self.c2) * inv_w - mu_y * mu_y;
        mu_y * mu_y > CANCELLATION * var
    }

    /// `x - μ` from the running sums (the fast amplitude).
    #[inline(always)]
    pub(crate) fn deviation(&self, x: f64, inv_w: f64) -> f64 {
        (x - self.reference) - (self.s1 + self.c1) * inv_w
    }

    /// Cheap first test, true for most in-control samples: `|x - μ| <= threshold` holds even
    /// with the worst-case error of the running sums. Uses `sqrt(m2) <= 1 + m2` instead of a
    /// square root, so it implies the [`Sums::classify`] outcome [`NONE`]; branch-free.
    #[inline(always)]
    pub(crate) fn surely_in_control(&self, x: f64, d: &Derived, threshold: f64) -> bool {
        let y = x - self.reference;
        let mu_y = (self.s1 + self.c1) * d.inv_w;
        let m2 = (self.s2 + self.c2) * d.inv_w;
        let ad = abs(y - mu_y);
        let ed = MARGIN * (abs(x) + abs(self.reference) + abs(y) + 1.0 + abs(m2) + ad);
        ad + ed <= threshold
    }

    /// Fast classification of the newest sample `x` of a full window:
    /// [`NONE`], [`RISE`], [`DROP`] or [`EXACT`] (too close to call). Branch-free.
    #[inline(always)]
    pub(crate) fn classify(&self, x: f64, d: &Derived, threshold: f64) -> u8 {
        let y = x - self.reference;
        let mu_y = (self.s1 + self.c1) * d.inv_w;
        let m2 = (self.s2 + self.c2) * d.inv_w;
        let dev = y - mu_y;
        let var = m2 - mu_y * mu_y;
        let var = if var > 0.0 { var } else { 0.0 };
        let ad = abs(dev);
        // Bound on |fast deviation - NumPy deviation| and on |fast var - NumPy var|.
        let ed = MARGIN * (abs(x) + abs(self.reference) + abs(y) + sqrt(abs(m2)) + ad);
        let ev = MARGIN * (2.0 * m2 + var) + 4.0 * ed * ed;
        let lo = ad - ed;
        let hi = ad + ed;
        let surely_out = lo > threshold && lo * lo > d.sigma2_hi * (var + ev);
        let surely_in = hi <= threshold || hi * hi < d.sigma2_lo * (var - ev);
        let dir = if dev > 0.0 { RISE } else { DROP };
        let fast = if surely_out { dir } else { NONE };
        if surely_out | surely_in {
            fast
        } else {
            EXACT
        }
    }
}

/// The exact decision for the newest sample `x` of the window `get(0..w)` (oldest first):
/// the alarm direction and `x - μ`, or `None`.
pub(crate) fn exact_decision(
    x: f64,
    w: usize,
    get: impl Fn(usize) -> f64,
    config: &ShewhartConfig,
) -> Option<(Direction, f64)> {
    let (mean, std) = np_mean_std(w, get);
    if out_of_control(x, mean, std, config.sigma, config.threshold) {
        let amp = x - mean;
        let dir = if amp > 0.0 {
            Direction::Rise
        } else {
            Direction::Drop
        };
        Some((dir, amp))
    } else {
        None
    }
}

/// The small, copyable part of a detector's state: kept in registers while stepping.
#[derive(Clone, Copy)]
struct Cursor {
    seen: u64,
    since_rebuild: u64,
    pos: usize,
    sums: Sums,
}

impl Cursor {
    /// One sample (finite): ring, sums, periodic rebuild, decision.
    #[inline(always)]
    fn step(&mut self, ring: &mut [f64], config: &ShewhartConfig, x: f64) -> Option<Alarm> {
        let w = config.window;
        let d = config.derived;
        let i = self.seen;
        let mut sums = self.sums;
        if i == 0 {
            sums.reference = x;
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
        if pos == 0 && (since >= REBUILD_MIN || sums.off_centre(d.inv_w)) {
            if since >= REBUILD_MIN {
                self.since_rebuild = 0;
            }
            sums = rebuilt(ring, sums.reference, d.inv_w);
        }
        self.sums = sums;
        if i + 1 < w as u64 || sums.surely_in_control(x, &d, config.threshold) {
            return None;
        }
        let decision = match sums.classify(x, &d, config.threshold) {
            NONE => None,
            EXACT => exact_in_ring(ring, pos, x, config),
            dir => Some((
                if dir == RISE {
                    Direction::Rise
                } else {
                    Direction::Drop
                },
                sums.deviation(x, d.inv_w),
            )),
        };
        decision.map(|(direction, amplitude)| Alarm {
            index: i,
            start: i,
            direction,
            amplitude,
        })
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
/// let mut det = Shewhart::new(ShewhartConfig::new(8, 2.0, 0.5)?);
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
        let w = r.config.window;
        if r.ring.len() != w || r.pos >= w {
            return Err(Error::CorruptState {
                reason: "ring buffer length or position does not match the window",
            });
        }
        if r.seen < w as u64 && r.pos as u64 != r.seen {
            return Err(Error::CorruptState {
                reason: "ring position does not match the sample count",
            });
        }
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

impl Shewhart {
    /// A fresh detector (allocates the `W`-sample ring).
    pub fn new(config: ShewhartConfig) -> Self {
        Self {
            config,
            seen: 0,
            since_rebuild: 0,
            pos: 0,
            sums: Sums::ZERO,
            ring: vec![0.0; config.window],
        }
    }

    /// Feeds one sample; returns the alarm it raises, if any.
    ///
    /// Errors with [`Error::NonFiniteSample`] (state unchanged) on NaN or ±inf.
    #[inline]
    pub fn update(&mut self, x: f64) -> Result<Option<Alarm>, Error> {
        check_sample(x, self.seen)?;
        Ok(self.update_unchecked(x))
    }

    #[inline(always)]
    fn cursor(&self) -> Cursor {
        Cursor {
            seen: self.seen,
            since_rebuild: self.since_rebuild,
            pos: self.pos,
            sums: self.sums,
        }
    }

    #[inline(always)]
    fn set_cursor(&mut self, c: Cursor) {
        self.seen = c.seen;
        self.since_rebuild = c.since_rebuild;
        self.pos = c.pos;
        self.sums = c.sums;
    }

    #[inline(always)]
    fn update_unchecked(&mut self, x: f64) -> Option<Alarm> {
        let mut cur = self.cursor();
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
        let mut cur = self.cursor();
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
