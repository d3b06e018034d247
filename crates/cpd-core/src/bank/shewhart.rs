//! The Shewhart bank: running sums per channel, a `[W][channels]` ring, one branch-free kernel
//! per block of channels and a rare slow path for the channels it flags.

use alloc::vec::Vec;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

use super::{check_channels, checked_step, checked_step_many, Kernel, BLOCK};
use crate::alarm::{Alarm, ChannelAlarm};
#[cfg(feature = "serde")]
use crate::error::ensure;
use crate::error::{filled, Error};
#[cfg(feature = "serde")]
use crate::shewhart::check_restored;
use crate::shewhart::{exact_decision, Derived, ShewhartConfig, Sums, REBUILD_MIN};

/// The state of a block of channels, borrowed for one step (disjoint slices: the kernel's
/// loop vectorizes).
struct Block<'a> {
    /// The ring row of the current time slot.
    row: &'a mut [f64],
    reference: &'a [f64],
    s1: &'a mut [f64],
    c1: &'a mut [f64],
    s2: &'a mut [f64],
    c2: &'a mut [f64],
}

/// What one step needs besides the state.
#[derive(Clone, Copy)]
struct Step {
    /// The window is full: slide instead of push.
    full: bool,
    /// Screen the samples in the same pass (false at a ring wrap, screened after the rebuild).
    screen: bool,
    derived: Derived,
    threshold: f64,
}

/// One Shewhart step for the block's channels (readings `xs`): writes the samples into the ring
/// row, updates the running sums and (when `screen`) flags the samples that the cheap test
/// cannot prove in control. Returns the OR of the flags. Branch-free per channel, so the loop
/// vectorizes.
#[inline(never)]
fn kernel(xs: &[f64], s: Block<'_>, flags: &mut [u8], p: Step) -> u8 {
    let m = xs.len();
    let (row, reference, flags) = (&mut s.row[..m], &s.reference[..m], &mut flags[..m]);
    let (s1, c1, s2, c2) = (
        &mut s.s1[..m],
        &mut s.c1[..m],
        &mut s.s2[..m],
        &mut s.c2[..m],
    );
    let (full, screen, d, thr) = (p.full, p.screen, &p.derived, p.threshold);
    let mut any = 0u8;
    for k in 0..m {
        let x = xs[k];
        let mut sums = Sums {
            reference: reference[k],
            s1: s1[k],
            c1: c1[k],
            s2: s2[k],
            c2: c2[k],
        };
        let old = row[k];
        row[k] = x;
        if full {
            sums.slide(x, old);
        } else {
            sums.push(x);
        }
        s1[k] = sums.s1;
        c1[k] = sums.c1;
        s2[k] = sums.s2;
        c2[k] = sums.c2;
        let f = (screen && !sums.surely_in_control(x, d, thr)) as u8;
        flags[k] = f;
        any |= f;
    }
    any
}

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
        let sums = [&r.reference, &r.s1, &r.c1, &r.s2, &r.c2];
        ensure(
            sums.iter().all(|v| v.len() == n) && Some(r.ring.len()) == w.checked_mul(n),
            "bank state arrays do not match the channels and window",
        )?;
        check_restored(w, r.steps, r.since_rebuild, r.pos, &r.ring)?;
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

impl Kernel for ShewhartBank {
    fn width(&self) -> usize {
        self.channels
    }
    #[inline]
    fn step_unchecked(&mut self, readings: &[f64], out: &mut Vec<ChannelAlarm>) {
        self.advance(readings, out);
    }
}

impl ShewhartBank {
    /// A fresh bank of `channels >= 1` detectors (allocates `W x channels` samples).
    ///
    /// Errors with [`Error::InvalidParameter`] (`channels`) when `channels` is 0 or the state
    /// cannot be allocated.
    pub fn new(channels: usize, config: ShewhartConfig) -> Result<Self, Error> {
        let n = check_channels(channels)?;
        let len = config
            .window()
            .checked_mul(n)
            .ok_or(Error::InvalidParameter {
                name: "channels",
                value: n as f64,
                reason: "window x channels overflows usize",
            })?;
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
            ring: filled("channels", len, 0.0)?,
        })
    }

    /// Feeds one reading per channel; appends this step's alarms to `out` in channel order.
    ///
    /// All readings are validated first ([`Error::ChannelCount`], [`Error::NonFiniteReading`]);
    /// on error the bank is unchanged.
    pub fn step(&mut self, readings: &[f64], out: &mut Vec<ChannelAlarm>) -> Result<(), Error> {
        checked_step(self, readings, out)
    }

    /// Feeds a row-major `T x channels` matrix (one row per time step), appending the alarms
    /// step by step. The whole matrix is validated first; on error the bank is unchanged.
    pub fn step_many(&mut self, matrix: &[f64], out: &mut Vec<ChannelAlarm>) -> Result<(), Error> {
        checked_step_many(self, matrix, out)
    }

    fn advance(&mut self, readings: &[f64], out: &mut Vec<ChannelAlarm>) {
        let w = self.config.window();
        let n = self.channels;
        let i = self.steps;
        if i == 0 {
            self.reference.copy_from_slice(readings);
        }
        let full = i >= w as u64;
        let slot = self.pos;
        self.pos = if slot + 1 == w { 0 } else { slot + 1 };
        self.steps = i + 1;
        self.since_rebuild += 1;
        // At a ring wrap, every channel is rebuilt periodically, and off-centre ones always.
        let wrap = self.pos == 0;
        let rebuild_all = wrap && self.since_rebuild >= REBUILD_MIN;
        let decide = self.steps >= w as u64;
        // One pass: slide the window and (except at wraps) screen the samples in the same loop.
        let fused = full && !wrap;
        let p = Step {
            full,
            screen: fused,
            derived: *self.config.derived(),
            threshold: self.config.threshold(),
        };
        let mut flags = [0u8; BLOCK];
        let mut b = 0;
        while b < n {
            let e = (b + BLOCK).min(n);
            let flags = &mut flags[..e - b];
            let block = Block {
                row: &mut self.ring[slot * n + b..slot * n + e],
                reference: &self.reference[b..e],
                s1: &mut self.s1[b..e],
                c1: &mut self.c1[b..e],
                s2: &mut self.s2[b..e],
                c2: &mut self.c2[b..e],
            };
            let any = kernel(&readings[b..e], block, flags, p);
            if any != 0 {
                self.collect(b, flags, &readings[b..e], i, out);
            }
            b = e;
        }
        if wrap {
            self.rebuild(rebuild_all);
        }
        if decide && !fused {
            self.screen_all(readings, i, out);
        }
    }

    /// The window of channel `c`, oldest first, as a getter (valid right after a step).
    fn window_of(&self, c: usize) -> impl Fn(usize) -> f64 + '_ {
        let (w, n, pos) = (self.config.window(), self.channels, self.pos);
        move |k| {
            let slot = if pos + k < w { pos + k } else { pos + k - w };
            self.ring[slot * n + c]
        }
    }

    fn sums(&self, c: usize) -> Sums {
        Sums {
            reference: self.reference[c],
            s1: self.s1[c],
            c1: self.c1[c],
            s2: self.s2[c],
            c2: self.c2[c],
        }
    }

    /// At a wrap: rebuilds the sums of every channel (`all`) or of the off-centre ones.
    #[cold]
    #[inline(never)]
    fn rebuild(&mut self, all: bool) {
        let (w, n) = (self.config.window(), self.channels);
        let inv_w = self.config.derived().inv_w;
        for c in 0..n {
            let mut sums = self.sums(c);
            if !all && !sums.off_centre(inv_w) {
                continue;
            }
            let ring = &self.ring;
            sums.rebuild(w, inv_w, |k| ring[k * n + c]);
            self.reference[c] = sums.reference;
            self.s1[c] = sums.s1;
            self.c1[c] = sums.c1;
            self.s2[c] = sums.s2;
            self.c2[c] = sums.c2;
        }
        if all {
            self.since_rebuild = 0;
        }
    }

    /// Screening pass for the steps where it cannot be fused with the update.
    fn screen_all(&self, readings: &[f64], i: u64, out: &mut Vec<ChannelAlarm>) {
        let d = *self.config.derived();
        let thr = self.config.threshold();
        let mut b = 0;
        while b < self.channels {
            let e = (b + BLOCK).min(self.channels);
            let mut flags = [0u8; BLOCK];
            let mut any = 0u8;
            for (k, f) in flags[..e - b].iter_mut().enumerate() {
                *f = !self.sums(b + k).surely_in_control(readings[b + k], &d, thr) as u8;
                any |= *f;
            }
            if any != 0 {
                self.collect(b, &flags[..e - b], &readings[b..e], i, out);
            }
            b = e;
        }
    }

    /// Decides the channels flagged by the screening (rare): fast classification, or the exact
    /// window scan near a tie.
    #[cold]
    #[inline(never)]
    fn collect(&self, b: usize, flags: &[u8], xs: &[f64], i: u64, out: &mut Vec<ChannelAlarm>) {
        for (k, &f) in flags.iter().enumerate() {
            if f == 0 {
                continue;
            }
            let c = b + k;
            let x = xs[k];
            let sums = self.sums(c);
            let decision = sums.decide(x, &self.config, || {
                exact_decision(x, self.config.window(), self.window_of(c), &self.config)
            });
            if let Some((direction, amplitude)) = decision {
                out.push(ChannelAlarm {
                    channel: c,
                    alarm: Alarm {
                        index: i,
                        start: i,
                        direction,
                        amplitude,
                    },
                });
            }
        }
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
