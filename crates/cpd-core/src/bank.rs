//! Multi-channel banks: one detector per pressure meter, one call per time step.
//!
//! State is kept as structure-of-arrays (one `Vec` per state variable, indexed by channel) and
//! updated with branch-free per-channel kernels shared with the single-channel detectors, so the
//! compiler vectorizes across channels and a bank is bit-for-bit equal to `N` independent
//! detectors. Channels that alarm are handled afterwards on a rare slow path.

use alloc::vec;
use alloc::vec::Vec;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

use crate::alarm::{Alarm, ChannelAlarm, Direction};
use crate::cusum::{CusumConfig, CusumLane};
use crate::error::{first_non_finite, Error};
use crate::shewhart::{
    exact_decision, Derived, ShewhartConfig, Sums, EXACT, NONE, REBUILD_MIN, RISE,
};

/// Channels processed per block: the alarm flags of a block live on the stack.
const BLOCK: usize = 256;

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

/// The per-step kernel of a bank: the validated entry points below are shared by every kind.
trait Kernel {
    /// Number of channels.
    fn width(&self) -> usize;
    /// Advances one step on readings already validated.
    fn step_unchecked(&mut self, readings: &[f64], out: &mut Vec<ChannelAlarm>);
}

/// Validates one step's readings, then runs the kernel; on error the bank is unchanged.
fn checked_step<K: Kernel>(
    bank: &mut K,
    readings: &[f64],
    out: &mut Vec<ChannelAlarm>,
) -> Result<(), Error> {
    check_readings(readings, bank.width())?;
    bank.step_unchecked(readings, out);
    Ok(())
}

/// Validates a whole row-major matrix, then runs the kernel row by row.
fn checked_step_many<K: Kernel>(
    bank: &mut K,
    matrix: &[f64],
    out: &mut Vec<ChannelAlarm>,
) -> Result<(), Error> {
    let channels = bank.width();
    check_matrix(matrix, channels)?;
    for row in matrix.chunks_exact(channels) {
        bank.step_unchecked(row, out);
    }
    Ok(())
}

/// Validates a row-major `T x channels` matrix.
fn check_matrix(matrix: &[f64], channels: usize) -> Result<(), Error> {
    if matrix.len() % channels != 0 {
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

/// One CUSUM step for a block of channels; returns the OR of the alarm flags written to
/// `flags`. Separate `&mut` slice arguments tell the compiler they do not alias, so the loop
/// vectorizes.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn cusum_block(
    xs: &[f64],
    x_prev: &mut [f64],
    gp: &mut [f64],
    gn: &mut [f64],
    gp_real: &mut [f64],
    gn_real: &mut [f64],
    tap: &mut [u64],
    tan: &mut [u64],
    x_tap: &mut [f64],
    x_tan: &mut [f64],
    flags: &mut [u8],
    i: u64,
    thr: f64,
    drift: f64,
) -> u8 {
    let m = xs.len();
    let (x_prev, gp, gn) = (&mut x_prev[..m], &mut gp[..m], &mut gn[..m]);
    let (gp_real, gn_real) = (&mut gp_real[..m], &mut gn_real[..m]);
    let (tap, tan, x_tap, x_tan) = (
        &mut tap[..m],
        &mut tan[..m],
        &mut x_tap[..m],
        &mut x_tan[..m],
    );
    let flags = &mut flags[..m];
    let mut any = 0u8;
    for k in 0..m {
        let mut lane = CusumLane {
            x_prev: x_prev[k],
            gp: gp[k],
            gn: gn[k],
            gp_real: gp_real[k],
            gn_real: gn_real[k],
            tap: tap[k],
            tan: tan[k],
            x_tap: x_tap[k],
            x_tan: x_tan[k],
        };
        let f = lane.step(xs[k], i, thr, drift);
        x_prev[k] = lane.x_prev;
        gp[k] = lane.gp;
        gn[k] = lane.gn;
        gp_real[k] = lane.gp_real;
        gn_real[k] = lane.gn_real;
        tap[k] = lane.tap;
        tan[k] = lane.tan;
        x_tap[k] = lane.x_tap;
        x_tan[k] = lane.x_tan;
        flags[k] = f;
        any |= f;
    }
    any
}

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
        Ok(Self {
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
        })
    }
}

impl Kernel for CusumBank {
    fn width(&self) -> usize {
        self.channels
    }
    #[inline]
    fn step_unchecked(&mut self, readings: &[f64], out: &mut Vec<ChannelAlarm>) {
        self.advance(readings, out);
    }
}

impl CusumBank {
    /// A fresh bank of `channels >= 1` detectors.
    pub fn new(channels: usize, config: CusumConfig) -> Result<Self, Error> {
        let n = check_channels(channels)?;
        Ok(Self {
            config,
            channels: n,
            steps: 0,
            x_prev: vec![0.0; n],
            gp: vec![0.0; n],
            gn: vec![0.0; n],
            gp_real: vec![0.0; n],
            gn_real: vec![0.0; n],
            tap: vec![0; n],
            tan: vec![0; n],
            x_tap: vec![0.0; n],
            x_tan: vec![0.0; n],
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
        let i = self.steps;
        self.steps += 1;
        if i == 0 {
            self.x_prev.copy_from_slice(readings);
            self.x_tap.copy_from_slice(readings);
            self.x_tan.copy_from_slice(readings);
            return;
        }
        let (thr, drift) = (self.config.threshold(), self.config.drift());
        let mut flags = [0u8; BLOCK];
        let mut b = 0;
        while b < self.channels {
            let e = (b + BLOCK).min(self.channels);
            let flags = &mut flags[..e - b];
            let any = cusum_block(
                &readings[b..e],
                &mut self.x_prev[b..e],
                &mut self.gp[b..e],
                &mut self.gn[b..e],
                &mut self.gp_real[b..e],
                &mut self.gn_real[b..e],
                &mut self.tap[b..e],
                &mut self.tan[b..e],
                &mut self.x_tap[b..e],
                &mut self.x_tan[b..e],
                flags,
                i,
                thr,
                drift,
            );
            if any != 0 {
                self.collect(b, flags, &readings[b..e], i, out);
            }
            b = e;
        }
    }

    #[cold]
    #[inline(never)]
    fn collect(&self, b: usize, flags: &[u8], xs: &[f64], i: u64, out: &mut Vec<ChannelAlarm>) {
        for (k, &f) in flags.iter().enumerate() {
            if f != 0 {
                let c = b + k;
                let lane = self.lane(c);
                out.push(ChannelAlarm {
                    channel: c,
                    alarm: lane.alarm(f, i, xs[k]),
                });
            }
        }
    }

    fn lane(&self, c: usize) -> CusumLane {
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

/// One Shewhart step for a block of channels: writes the samples into the ring row, updates the
/// running sums and (when `screen`) flags the samples that the cheap test cannot prove in
/// control. Returns the OR of the flags. Branch-free per channel, so the loop vectorizes.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn shewhart_block(
    xs: &[f64],
    row: &mut [f64],
    reference: &[f64],
    s1: &mut [f64],
    c1: &mut [f64],
    s2: &mut [f64],
    c2: &mut [f64],
    flags: &mut [u8],
    full: bool,
    screen: bool,
    d: &Derived,
    thr: f64,
) -> u8 {
    let m = xs.len();
    let (row, reference, flags) = (&mut row[..m], &reference[..m], &mut flags[..m]);
    let (s1, c1, s2, c2) = (&mut s1[..m], &mut c1[..m], &mut s2[..m], &mut c2[..m]);
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
        if sums.iter().any(|v| v.len() != n)
            || Some(r.ring.len()) != w.checked_mul(n)
            || r.pos >= w
            || (r.steps < w as u64 && r.pos as u64 != r.steps)
        {
            return Err(Error::CorruptState {
                reason: "bank state arrays do not match the channels and window",
            });
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
        Ok(Self {
            config,
            channels: n,
            steps: 0,
            since_rebuild: 0,
            pos: 0,
            reference: vec![0.0; n],
            s1: vec![0.0; n],
            c1: vec![0.0; n],
            s2: vec![0.0; n],
            c2: vec![0.0; n],
            ring: vec![0.0; len],
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
        let d = *self.config.derived();
        let thr = self.config.threshold();
        let mut flags = [0u8; BLOCK];
        let mut b = 0;
        while b < n {
            let e = (b + BLOCK).min(n);
            let flags = &mut flags[..e - b];
            let any = shewhart_block(
                &readings[b..e],
                &mut self.ring[slot * n + b..slot * n + e],
                &self.reference[b..e],
                &mut self.s1[b..e],
                &mut self.c1[b..e],
                &mut self.s2[b..e],
                &mut self.c2[b..e],
                flags,
                full,
                fused,
                &d,
                thr,
            );
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
        let d = *self.config.derived();
        let thr = self.config.threshold();
        for (k, &f) in flags.iter().enumerate() {
            if f == 0 {
                continue;
            }
            let c = b + k;
            let x = xs[k];
            let sums = self.sums(c);
            let decision = match sums.classify(x, &d, thr) {
                NONE => None,
                EXACT => exact_decision(x, self.config.window(), self.window_of(c), &self.config),
                dir => Some((
                    if dir == RISE {
                        Direction::Rise
                    } else {
                        Direction::Drop
                    },
                    sums.deviation(x, d.inv_w),
                )),
            };
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
