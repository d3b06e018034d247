//! The per-channel CUSUM step, shared by the single detector, its segments and the bank.

use alloc::vec::Vec;
use core::hint::select_unpredictable;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

#[cfg(feature = "serde")]
use super::CusumConfig;
use crate::alarm::{Alarm, Direction};
#[cfg(feature = "serde")]
use crate::error::{ensure, field, finite_field, sample_field, Error, MAX_COUNT};

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
pub(super) struct Sides {
    threshold: f64,
    drift: f64,
    sign: u64,
}

impl Sides {
    #[inline(always)]
    pub(super) fn new(threshold: f64, drift: f64) -> Self {
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

/// Where the start values come from while a lane steps a slice `xs` (stream indices from
/// `base`): a start inside the slice reads its sample there, one before it keeps the value the
/// lane held when the slice began. They are brought up to date only where they are read (at an
/// alarm, at the end of the slice), not sample by sample.
#[derive(Clone, Copy)]
pub(super) struct Starts<'a> {
    xs: &'a [f64],
    base: u64,
    x_tap0: f64,
    x_tan0: f64,
}

impl<'a> Starts<'a> {
    /// The start values of `lane` about to step `xs` from `base`.
    #[inline(always)]
    pub(super) fn of(lane: &CusumLane, xs: &'a [f64], base: u64) -> Self {
        Self {
            xs,
            base,
            x_tap0: lane.x_tap,
            x_tan0: lane.x_tan,
        }
    }

    /// The start value of a change of `direction` that started at stream index `t`.
    #[inline(always)]
    pub(super) fn value(&self, t: u64, direction: Direction) -> f64 {
        if t >= self.base {
            self.xs[(t - self.base) as usize]
        } else {
            match direction {
                Direction::Rise => self.x_tap0,
                Direction::Drop => self.x_tan0,
            }
        }
    }

    /// `lane`'s start values for its current starts.
    #[inline(always)]
    pub(super) fn set(&self, lane: &mut CusumLane) {
        lane.x_tap = self.value(lane.tap, Direction::Rise);
        lane.x_tan = self.value(lane.tan, Direction::Drop);
    }
}

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
    pub(super) fn advance(&mut self, x: f64, i: u64, c: Sides) -> (u8, bool, bool) {
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
        let starts = Starts::of(self, xs, base);
        let mut lane = *self;
        let sides = Sides::new(thr, drift);
        for (i, &x) in (base..).zip(xs) {
            let (flags, _, _) = lane.advance(x, i, sides);
            if flags != 0 {
                starts.set(&mut lane);
                out.push(lane.alarm(flags, i, x));
            }
        }
        starts.set(&mut lane);
        *self = lane;
    }

    /// Validates a restored lane after `seen` samples (`index`: the bank channel it is): the
    /// sample values within range, the sums finite, the drift sums `>= 0`, the real sums
    /// `<= threshold` (they reset on crossing it), the starts before `seen`. These hold for
    /// every state a detector reaches from samples; [`Error::InvalidState`] names the field.
    #[cfg(feature = "serde")]
    pub(crate) fn check(
        &self,
        seen: u64,
        config: &CusumConfig,
        index: Option<usize>,
    ) -> Result<(), Error> {
        ensure(seen <= MAX_COUNT, "sample count out of range")?;
        for (name, x) in [
            ("x_prev", self.x_prev),
            ("x_tap", self.x_tap),
            ("x_tan", self.x_tan),
        ] {
            sample_field(name, index, x)?;
        }
        for (name, g) in [("gp", self.gp), ("gn", self.gn)] {
            finite_field(name, index, g)?;
            field(g >= 0.0, name, index, g, "a drift sum must be >= 0")?;
        }
        let t = config.threshold();
        for (name, g) in [("gp_real", self.gp_real), ("gn_real", self.gn_real)] {
            finite_field(name, index, g)?;
            field(
                g <= t,
                name,
                index,
                g,
                "a real sum must be <= the threshold",
            )?;
        }
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
