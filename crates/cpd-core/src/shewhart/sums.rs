//! The running window sums of one Shewhart channel and the decision made from them, shared by
//! the detector and the bank (see the parent module's docs for the numerics).

use core::ops::{Add, Mul, Neg, Sub};

use wide::f64x2;

use crate::alarm::Direction;
use crate::math::{abs, sqrt};
use crate::stats::{lane_sum, np_mean_std, out_of_control};

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

#[cfg(feature = "serde")]
use crate::error::{finite_field, sample_field, Error};

use super::ShewhartConfig;

/// At a ring wrap, the sums are also rebuilt when `mean(y)² > CANCELLATION · var`, i.e. when the
/// reference is so far from the window (after a level shift) that `E[y²] - E[y]²` would lose
/// more than about 6 of its 16 digits.
const CANCELLATION: f64 = (1u64 << 20) as f64;

/// Relative error margin of the fast decision (about 4.5e5 machine epsilons).
pub(super) const MARGIN: f64 = 1e-10;

/// Classification of one sample by the fast path.
pub(crate) const NONE: u8 = 0;
/// Out of control, `x > μ`.
pub(crate) const RISE: u8 = 1;
/// Out of control, `x < μ`.
pub(crate) const DROP: u8 = 2;
/// Too close to a tie for the running sums: decide with the exact window scan.
pub(crate) const EXACT: u8 = 4;

/// Constants of the hot path, derived from the config.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Derived {
    pub inv_w: f64,
    pub sigma2_hi: f64,
    pub sigma2_lo: f64,
}

/// The arithmetic of the running sums and of the cheap screen, on one channel (`f64`) or on a
/// vector of channels (the bank's kernel): IEEE additions, subtractions, multiplications and
/// sign operations, exact lane by lane, so a vector's lanes are the scalar results bit for bit.
pub(crate) trait Lane:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    /// `x` in every lane.
    fn splat(x: f64) -> Self;
    /// `|self|` (the sign bit cleared).
    fn abs(self) -> Self;
}

impl Lane for f64 {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn abs(self) -> Self {
        abs(self)
    }
}

/// Adds `v` to the compensated sum `(s, c)` (Knuth's TwoSum; branch-free), on scalars or lane
/// by lane on vectors (exact lane by lane: each lane is the scalar result, bit for bit).
#[inline(always)]
fn acc<T: Copy + Add<Output = T> + Sub<Output = T>>(s: T, c: T, v: T) -> (T, T) {
    let t = s + v;
    let bp = t - s;
    let err = (s - (t - bp)) + (v - bp);
    (t, c + err)
}

/// The statistic of the cheap in-control test ([`Sums::surely_in_control`]: in control when
/// it is `<= threshold`) from the sample `x`, the reference and the window moments
/// `(mu_y, m2) = (Σy / W, Σy² / W)`: `|x - μ|` plus its worst-case error.
#[inline(always)]
fn screen<T: Lane>(x: T, reference: T, (mu_y, m2): (T, T)) -> T {
    let y = x - reference;
    let ad = (y - mu_y).abs();
    let ed =
        T::splat(MARGIN) * (x.abs() + reference.abs() + y.abs() + T::splat(1.0) + m2.abs() + ad);
    ad + ed
}

/// Running window sums of one channel (or, with `T` a vector, of one lane per channel: the
/// bank's kernel), shared by the detector and the bank.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub(crate) struct Sums<T = f64> {
    /// Reference subtracted from every sample.
    pub reference: T,
    /// Σy and its compensation.
    pub s1: T,
    pub c1: T,
    /// Σy² and its compensation.
    pub s2: T,
    pub c2: T,
}

impl<T: Lane> Sums<T> {
    /// Adds a sample while the window is filling.
    #[inline(always)]
    pub(crate) fn push(&mut self, x: T) {
        let y = x - self.reference;
        (self.s1, self.c1) = acc(self.s1, self.c1, y);
        (self.s2, self.c2) = acc(self.s2, self.c2, y * y);
    }

    /// Adds `x` and removes `old` (the window is full).
    #[inline(always)]
    pub(crate) fn slide(&mut self, x: T, old: T) {
        let y = x - self.reference;
        let yo = old - self.reference;
        let (s1, c1) = acc(self.s1, self.c1, y);
        (self.s1, self.c1) = acc(s1, c1, -yo);
        let (s2, c2) = acc(self.s2, self.c2, y * y);
        (self.s2, self.c2) = acc(s2, c2, -(yo * yo));
    }

    /// `(Σy / W, Σy² / W)` from the compensated sums.
    #[inline(always)]
    fn moments(&self, inv_w: T) -> (T, T) {
        ((self.s1 + self.c1) * inv_w, (self.s2 + self.c2) * inv_w)
    }

    /// The two sides of the off-centre test: off centre when the first is `>` the second
    /// (`mean(y)²` and [`CANCELLATION`] `· var`).
    #[inline(always)]
    pub(crate) fn centring(&self, inv_w: T) -> (T, T) {
        let (mu_y, m2) = self.moments(inv_w);
        let var = m2 - mu_y * mu_y;
        (mu_y * mu_y, T::splat(CANCELLATION) * var)
    }

    /// The statistic of the cheap first test for the newest sample `x` (see
    /// [`Sums::surely_in_control`]); branch-free.
    #[inline(always)]
    pub(crate) fn screen(&self, x: T, inv_w: T) -> T {
        screen(x, self.reference, self.moments(inv_w))
    }
}

impl Sums {
    /// Validates restored sums (`index`: the bank channel): the reference a sample, the sums
    /// and their compensations finite (as samples within range keep them).
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self, index: Option<usize>) -> Result<(), Error> {
        sample_field("reference", index, self.reference)?;
        for (name, x) in [
            ("s1", self.s1),
            ("c1", self.c1),
            ("s2", self.s2),
            ("c2", self.c2),
        ] {
            finite_field(name, index, x)?;
        }
        Ok(())
    }

    pub(crate) const ZERO: Self = Self {
        reference: 0.0,
        s1: 0.0,
        c1: 0.0,
        s2: 0.0,
        c2: 0.0,
    };

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
        let (a, b) = self.centring(inv_w);
        a > b
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
        self.screen(x, d.inv_w) <= threshold
    }

    /// Fast classification of the newest sample `x` of a full window:
    /// [`NONE`], [`RISE`], [`DROP`] or [`EXACT`] (too close to call). Branch-free.
    #[inline(always)]
    pub(crate) fn classify(&self, x: f64, d: &Derived, threshold: f64) -> u8 {
        let y = x - self.reference;
        let (mu_y, m2) = self.moments(d.inv_w);
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

impl Sums {
    /// The decision for the newest sample `x` of a full window: the direction and `x - μ` of
    /// an alarm, or `None`; from the running sums, or from `exact()` (the window re-scanned)
    /// when they are too close to a tie.
    #[inline(always)]
    pub(crate) fn decide(
        &self,
        x: f64,
        config: &ShewhartConfig,
        exact: impl FnOnce() -> Option<(Direction, f64)>,
    ) -> Option<(Direction, f64)> {
        let d = &config.derived;
        match self.classify(x, d, config.threshold) {
            NONE => None,
            EXACT => exact(),
            dir => {
                let direction = if dir == RISE {
                    Direction::Rise
                } else {
                    Direction::Drop
                };
                Some((direction, self.deviation(x, d.inv_w)))
            }
        }
    }
}

/// What a detector's step needs of its running sums: [`Sums`] (per `update` call, kept in
/// memory between calls) or [`PairedSums`] (over a slice, kept in registers).
pub(crate) trait RunningSums: Copy + From<Sums> + Into<Sums> {
    /// The reference subtracted from every sample.
    fn reference(&mut self) -> &mut f64;
    /// Adds a sample while the window is filling.
    fn push(&mut self, x: f64);
    /// Adds `x` and removes `old` (the window is full).
    fn slide(&mut self, x: f64, old: f64);
    /// [`Sums::surely_in_control`].
    fn surely_in_control(&self, x: f64, d: &Derived, threshold: f64) -> bool;
}

impl RunningSums for Sums {
    #[inline(always)]
    fn reference(&mut self) -> &mut f64 {
        &mut self.reference
    }
    #[inline(always)]
    fn push(&mut self, x: f64) {
        Sums::push(self, x)
    }
    #[inline(always)]
    fn slide(&mut self, x: f64, old: f64) {
        Sums::slide(self, x, old)
    }
    #[inline(always)]
    fn surely_in_control(&self, x: f64, d: &Derived, threshold: f64) -> bool {
        Sums::surely_in_control(self, x, d, threshold)
    }
}

/// [`Sums`] with the two running sums as the two lanes of one vector, `s = [Σy, Σy²]` and `c`
/// their compensations: one pair of vector TwoSums per update instead of two scalar ones, with
/// the same results bit for bit (see [`acc`]). The single detector keeps its sums this way
/// while it steps; the bank keeps [`Sums`] (its loop vectorizes across channels instead).
#[derive(Clone, Copy)]
pub(crate) struct PairedSums {
    reference: f64,
    s: f64x2,
    c: f64x2,
}

impl From<Sums> for PairedSums {
    #[inline(always)]
    fn from(v: Sums) -> Self {
        Self {
            reference: v.reference,
            s: f64x2::new([v.s1, v.s2]),
            c: f64x2::new([v.c1, v.c2]),
        }
    }
}

impl From<PairedSums> for Sums {
    #[inline(always)]
    fn from(v: PairedSums) -> Self {
        let ([s1, s2], [c1, c2]) = (v.s.to_array(), v.c.to_array());
        Self {
            reference: v.reference,
            s1,
            c1,
            s2,
            c2,
        }
    }
}

impl RunningSums for PairedSums {
    #[inline(always)]
    fn reference(&mut self) -> &mut f64 {
        &mut self.reference
    }

    #[inline(always)]
    fn push(&mut self, x: f64) {
        let y = x - self.reference;
        (self.s, self.c) = acc(self.s, self.c, f64x2::new([y, y * y]));
    }

    #[inline(always)]
    fn slide(&mut self, x: f64, old: f64) {
        let y = x - self.reference;
        let yo = old - self.reference;
        let (s, c) = acc(self.s, self.c, f64x2::new([y, y * y]));
        (self.s, self.c) = acc(s, c, -f64x2::new([yo, yo * yo]));
    }

    #[inline(always)]
    fn surely_in_control(&self, x: f64, d: &Derived, threshold: f64) -> bool {
        let [mu_y, m2] = ((self.s + self.c) * f64x2::splat(d.inv_w)).to_array();
        screen(x, self.reference, (mu_y, m2)) <= threshold
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
