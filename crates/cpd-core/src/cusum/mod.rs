//! Streaming two-sided CUSUM (the paper's eq. 1–2 and Algorithm 1; TSNet 0.3.1's online pass).

mod segments;

use alloc::vec::Vec;
use core::hint::select_unpredictable;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

use crate::alarm::{Alarm, Direction};
use crate::error::{check_sample, check_samples, non_negative, positive, Error};
#[cfg(feature = "serde")]
use crate::error::{ensure, MAX_COUNT};

/// Validated CUSUM parameters.
///
/// `threshold` must be finite and `> 0`; `drift` finite and `>= 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "CusumConfigRepr"))]
pub struct CusumConfig {
    threshold: f64,
    drift: f64,
}

impl CusumConfig {
    /// Builds a config, naming the offending parameter on error.
    ///
    /// ```
    /// use cpd_core::CusumConfig;
    /// assert!(CusumConfig::new(0.5, 0.0).is_ok());
    /// let err = CusumConfig::new(-1.0, 0.0).unwrap_err();
    /// assert!(err.is_config());
    /// assert!(err.to_string().contains("threshold"));
    /// ```
    pub fn new(threshold: f64, drift: f64) -> Result<Self, Error> {
        Ok(Self {
            threshold: positive("threshold", threshold)?,
            drift: non_negative("drift", drift)?,
        })
    }

    /// Alarm threshold on the drift-free sums `gp_real` / `gn_real`.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Drift subtracted from every difference in `gp` / `gn`.
    pub fn drift(&self) -> f64 {
        self.drift
    }
}

/// Unvalidated mirror used to validate deserialized configs.
#[cfg(feature = "serde")]
#[derive(Deserialize)]
struct CusumConfigRepr {
    threshold: f64,
    drift: f64,
}

#[cfg(feature = "serde")]
impl TryFrom<CusumConfigRepr> for CusumConfig {
    type Error = Error;
    fn try_from(r: CusumConfigRepr) -> Result<Self, Error> {
        CusumConfig::new(r.threshold, r.drift)
    }
}

/// The sign bit of an `f64`, hidden from the optimizer (`black_box`): [`CusumLane::advance`]
/// negates `s` by flipping it, which LLVM cannot fold into the drop side's addition. Seeing a
/// plain `-s` it turns `g + (-s)` into a scalar subtraction and, with AVX-512, rebuilds the
/// vector of the two sides around it: two shuffles more on the loop-carried chain (`update_slice`
/// 5.0 -> 3.5 ns/sample with `-C target-cpu=native` on an AVX-512 Xeon, the same results).
#[inline(always)]
fn opaque_sign() -> u64 {
    core::hint::black_box(1 << 63)
}

/// What every step of [`CusumLane::advance`] shares: the config and [`opaque_sign`].
#[derive(Clone, Copy)]
struct Sides {
    threshold: f64,
    drift: f64,
    sign: u64,
}

impl Sides {
    #[inline(always)]
    fn new(threshold: f64, drift: f64) -> Self {
        Self {
            threshold,
            drift,
            sign: opaque_sign(),
        }
    }
}

/// Alarm flag bits returned by [`CusumLane::step`].
pub(crate) const RISE: u8 = 1;
/// `gn_real` crossed the threshold.
pub(crate) const DROP: u8 = 2;

/// The per-channel CUSUM state; the single detector and the bank share its arithmetic,
/// so both are bit-for-bit identical to TSNet.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub(crate) struct CusumLane {
    pub x_prev: f64,
    pub gp: f64,
    pub gn: f64,
    pub gp_real: f64,
    pub gn_real: f64,
    pub tap: u64,
    pub tan: u64,
    pub x_tap: f64,
    pub x_tan: f64,
}

impl CusumLane {
    pub(crate) const ZERO: Self = Self {
        x_prev: 0.0,
        gp: 0.0,
        gn: 0.0,
        gp_real: 0.0,
        gn_real: 0.0,
        tap: 0,
        tan: 0,
        x_tap: 0.0,
        x_tan: 0.0,
    };

    /// Sample 0: only primes `x_prev` (and the start values, `tap = tan = 0`).
    #[inline(always)]
    pub(crate) fn prime(&mut self, x: f64) {
        self.x_prev = x;
        self.x_tap = x;
        self.x_tan = x;
    }

    /// Sample `i >= 1`. Returns `RISE`/`DROP` bits (both may be set; TSNet then reports a rise).
    /// Written with selects so that the bank loop vectorizes.
    #[inline(always)]
    pub(crate) fn step(&mut self, x: f64, i: u64, threshold: f64, drift: f64) -> u8 {
        self.step_sums(x, i, drift);
        let up = self.gp_real > threshold;
        let down = self.gn_real > threshold;
        let alarm = up | down;
        self.gp = if alarm { 0.0 } else { self.gp };
        self.gn = if alarm { 0.0 } else { self.gn };
        self.gp_real = if alarm { 0.0 } else { self.gp_real };
        self.gn_real = if alarm { 0.0 } else { self.gn_real };
        (up as u8 * RISE) | (down as u8 * DROP)
    }

    /// The sums, resets and starts of [`CusumLane::step`], without the alarm test and its
    /// resets (the time-blocked bank does those on its slow path).
    #[inline(always)]
    pub(crate) fn step_sums(&mut self, x: f64, i: u64, drift: f64) {
        let s = x - self.x_prev;
        self.x_prev = x;
        // Same operation order as TSNet: (g + s) - drift.
        let gp = self.gp + s - drift;
        let gp_real = self.gp_real + s;
        let gn = self.gn - s - drift;
        let gn_real = self.gn_real - s;
        let reset_p = gp < 0.0;
        let reset_n = gn < 0.0;
        self.gp = if reset_p { 0.0 } else { gp };
        self.gp_real = if reset_p { 0.0 } else { gp_real };
        self.tap = if reset_p { i } else { self.tap };
        self.x_tap = if reset_p { x } else { self.x_tap };
        self.gn = if reset_n { 0.0 } else { gn };
        self.gn_real = if reset_n { 0.0 } else { gn_real };
        self.tan = if reset_n { i } else { self.tan };
        self.x_tan = if reset_n { x } else { self.x_tan };
    }

    /// The sums and starts of [`CusumLane::step`] for one channel, without the start values
    /// `x_tap`/`x_tan` (the caller keeps them). Bit-identical to `step`. The resets are
    /// selects: the data decides them (on noisy heads each side resets about every other sample,
    /// at random), so as branches they would be mispredicted half the time. Only the rare
    /// alarm is a branch; the loop-carried chain is `(g + s) - drift` and a max. Returns the
    /// alarm flags and the two reset decisions.
    #[inline(always)]
    fn advance(&mut self, x: f64, i: u64, c: Sides) -> (u8, bool, bool) {
        let s = x - self.x_prev;
        self.x_prev = x;
        // The two sides as two lanes of one vector (`g - s` is exactly `g + (-s)`, and `-s` is
        // `s` with its sign bit flipped), so that the compiler keeps the resets as vector
        // blends instead of scalar branches, and the sums as one vector addition.
        let t = [s, f64::from_bits(s.to_bits() ^ c.sign)];
        let (threshold, drift) = (c.threshold, c.drift);
        let g = [self.gp, self.gn];
        let real = [self.gp_real, self.gn_real];
        let mut reset = [false; 2];
        let mut g_new = [0.0; 2];
        let mut real_new = [0.0; 2];
        for k in 0..2 {
            // Same operation order as TSNet: (g + s) - drift.
            let v = g[k] + t[k] - drift;
            reset[k] = v < 0.0;
            // `0 > v ? 0 : v` is `if v < 0 { 0 } else { v }` (a -0.0 is kept): a MAXPD.
            g_new[k] = if 0.0 > v { 0.0 } else { v };
            real_new[k] = select_unpredictable(reset[k], 0.0, real[k] + t[k]);
        }
        self.tap = select_unpredictable(reset[0], i, self.tap);
        self.tan = select_unpredictable(reset[1], i, self.tan);
        let up = real_new[0] > threshold;
        let down = real_new[1] > threshold;
        if up | down {
            self.gp = 0.0;
            self.gn = 0.0;
            self.gp_real = 0.0;
            self.gn_real = 0.0;
            return ((up as u8 * RISE) | (down as u8 * DROP), reset[0], reset[1]);
        }
        [self.gp, self.gn] = g_new;
        [self.gp_real, self.gn_real] = real_new;
        (0, reset[0], reset[1])
    }

    /// Same as [`CusumLane::step`] (bit-identical results), for one channel: [`Self::advance`]
    /// plus the start values, selected on their bits (an integer CMOV; a float select would
    /// become a branch).
    #[inline(always)]
    pub(crate) fn step_scalar(&mut self, x: f64, i: u64, threshold: f64, drift: f64) -> u8 {
        let (flags, reset_p, reset_n) = self.advance(x, i, Sides::new(threshold, drift));
        let bits = x.to_bits();
        self.x_tap = f64::from_bits(select_unpredictable(reset_p, bits, self.x_tap.to_bits()));
        self.x_tan = f64::from_bits(select_unpredictable(reset_n, bits, self.x_tan.to_bits()));
        flags
    }

    /// Feeds `xs` (stream indices from `base >= 1`), pushing the alarms to `out`. The start
    /// values are not tracked sample by sample: a start inside `xs` reads its sample there.
    #[inline(always)]
    pub(crate) fn run(
        &mut self,
        xs: &[f64],
        base: u64,
        thr: f64,
        drift: f64,
        out: &mut Vec<Alarm>,
    ) {
        let (x_tap0, x_tan0) = (self.x_tap, self.x_tan);
        let at = |t: u64, before: f64| {
            if t >= base {
                xs[(t - base) as usize]
            } else {
                before
            }
        };
        let mut lane = *self;
        let sides = Sides::new(thr, drift);
        for (i, &x) in (base..).zip(xs) {
            let (flags, _, _) = lane.advance(x, i, sides);
            if flags != 0 {
                lane.x_tap = at(lane.tap, x_tap0);
                lane.x_tan = at(lane.tan, x_tan0);
                out.push(lane.alarm(flags, i, x));
            }
        }
        lane.x_tap = at(lane.tap, x_tap0);
        lane.x_tan = at(lane.tan, x_tan0);
        *self = lane;
    }

    /// Validates a restored lane after `seen` samples: every value finite, the drift sums
    /// `>= 0`, the real sums `<= threshold` (they reset on crossing it), the starts before
    /// `seen`. These hold for every state a detector reaches from finite samples.
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self, seen: u64, config: &CusumConfig) -> Result<(), Error> {
        let values = [
            self.x_prev,
            self.gp,
            self.gn,
            self.gp_real,
            self.gn_real,
            self.x_tap,
            self.x_tan,
        ];
        ensure(seen <= MAX_COUNT, "sample count out of range")?;
        ensure(
            values.iter().all(|v| v.is_finite()),
            "non-finite CUSUM state value",
        )?;
        ensure(self.gp >= 0.0 && self.gn >= 0.0, "negative CUSUM drift sum")?;
        let t = config.threshold;
        ensure(
            self.gp_real <= t && self.gn_real <= t,
            "CUSUM real sum above the threshold",
        )?;
        let last = seen.saturating_sub(1);
        ensure(
            self.tap <= last && self.tan <= last,
            "CUSUM change start past the sample count",
        )
    }

    /// The alarm for non-zero `flags` returned by [`CusumLane::step`] at sample `i` (value `x`).
    #[inline]
    pub(crate) fn alarm(&self, flags: u8, i: u64, x: f64) -> Alarm {
        if flags & RISE != 0 {
            Alarm {
                index: i,
                start: self.tap,
                direction: Direction::Rise,
                amplitude: x - self.x_tap,
            }
        } else {
            Alarm {
                index: i,
                start: self.tan,
                direction: Direction::Drop,
                amplitude: x - self.x_tan,
            }
        }
    }
}

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
/// **Non-finite samples** (NaN, ±inf) are rejected with [`Error::NonFiniteSample`] and
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
        r.lane.check(r.seen, &r.config)?;
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
    /// Errors with [`Error::NonFiniteSample`] (state unchanged) on NaN or ±inf.
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
            .step_scalar(x, i, self.config.threshold, self.config.drift);
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
        let (thr, drift) = (self.config.threshold, self.config.drift);
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
