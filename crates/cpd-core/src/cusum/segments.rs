//! A long slice through one CUSUM as a bank of segments: guessed all at once, then joined.
//!
//! Sample after sample, one detector is a chain: each step's sums need the step before, through
//! `(g + s) - drift`, a comparison and a select — about 3.5 ns per sample on the AVX-512 Xeon
//! measured, whatever the vectors, since TSNet's operation order (kept for bit-identity) leaves
//! no shorter chain. But a CUSUM forgets: once each of its sides has reset, its state no longer
//! depends on the state it started from. So [`run`] cuts a block of [`SEGMENTS`] × `len` samples
//! into segments and runs them all at once, one per channel of a [`CusumBank`] (its kernel steps
//! the segments as the lanes of vectors), each from a guess: all sums 0, both starts at the sample
//! before the segment. Then, segment by segment, it steps the true state (where the segment
//! before ended) beside the guess until the two are equal bit for bit — on noisy heads within a
//! few samples, once both sides have reset — and takes the guess's alarms and end state from
//! there. Where they never meet (a ramp that keeps one side from resetting over a whole segment)
//! the true run covers the segment: as fast as the sequential run plus the guess's share.
//!
//! Each step is the detector's own step function, on the same inputs, so every sum, start and
//! alarm is bit-for-bit the sequential run's: only which copy computes a step changes.

use alloc::vec::Vec;

use super::lane::{Sides, Starts};
use super::{CusumConfig, CusumLane};
use crate::alarm::{Alarm, ChannelAlarm};
use crate::bank::CusumBank;
use crate::error::{check_samples, Error};

/// Segments per block: one tile of the bank's register-resident kernel with AVX-512 (two tiles
/// of 8 otherwise).
const SEGMENTS: usize = 16;

/// Samples per segment: a block's rows (with the guesses' previous samples) fill 33 KiB, which
/// stay in the L1 cache while the bank walks them.
const LEN: usize = 256;

/// Below this many samples per segment the joins' share outweighs the gain: run sequentially.
const MIN_LEN: usize = 32;

/// What the joins of one call share: the slice, its first stream index, where its start values
/// come from (as in the sequential run) and the config's sides.
struct Slice<'a> {
    xs: &'a [f64],
    base: u64,
    starts: Starts<'a>,
    sides: Sides,
}

impl Slice<'_> {
    /// The alarm the sequential run raises with `lane` at stream index `i` (sample `x`).
    fn alarm(&self, lane: &mut CusumLane, flags: u8, i: u64, x: f64) -> Alarm {
        self.starts.set(lane);
        lane.alarm(flags, i, x)
    }
}

/// Feeds the longest run of whole blocks at the front of `xs` (stream indices from `base >= 1`)
/// to `lane`, appending the alarms to `out` in index order, exactly as [`CusumLane::run`]
/// would. Returns how many samples it consumed: 0 for a slice too short to gain (or when the
/// bank's state cannot be allocated); the caller runs the rest sequentially. Each block is
/// checked before it runs: a non-finite sample stops the run with its error (blocks before it
/// have run: the caller puts their state and alarms back).
pub(super) fn run(
    lane: &mut CusumLane,
    xs: &[f64],
    base: u64,
    config: &CusumConfig,
    out: &mut Vec<Alarm>,
) -> Result<usize, Error> {
    let len = (xs.len() / SEGMENTS).min(LEN);
    // Without drift the sums are random walks held at 0 that come back to it late (their mean
    // return time is unbounded): the guesses seldom meet the truth within a segment (measured:
    // the true run walked 92 % of the samples), so they would only add work.
    if len < MIN_LEN || config.drift() == 0.0 {
        return Ok(0);
    }
    let mut rows = Vec::new();
    if rows.try_reserve_exact((len + 1) * SEGMENTS).is_err() {
        return Ok(0);
    }
    rows.resize((len + 1) * SEGMENTS, 0.0);
    let Ok(mut bank) = CusumBank::new(SEGMENTS, *config) else {
        return Ok(0);
    };
    let slice = Slice {
        xs,
        base,
        starts: Starts::of(lane, xs, base),
        sides: Sides::new(config.threshold(), config.drift()),
    };
    let mut guessed = Vec::new();
    let mut done = 0;
    while xs.len() - done >= SEGMENTS * len {
        let block = &xs[done..done + SEGMENTS * len];
        check_samples(block, base + done as u64)?;
        let before = if done == 0 { lane.x_prev } else { xs[done - 1] };
        transpose(block, before, len, &mut rows);
        bank.reset();
        guessed.clear();
        bank.advance_many(&rows, &mut guessed);
        let mut walked = 0;
        for (k, segment) in block.chunks_exact(len).enumerate() {
            let first = base + (done + k * len) as u64;
            let guess = Guess {
                bank: &bank,
                channel: k,
                alarms: &guessed,
                first,
            };
            walked += join(lane, segment, &guess, &slice, out);
        }
        done += SEGMENTS * len;
        // Guesses that rarely meet the truth (a drift small against the noise: the sums wander
        // far from 0 and come back late) only add work: the rest of the slice runs sequentially.
        if walked * 2 > block.len() {
            break;
        }
    }
    slice.starts.set(lane);
    Ok(done)
}

/// The bank's rows for one block: row 0 the sample before each segment (the bank's priming
/// row), row `t + 1` every segment's sample `t`. In blocks of four samples of four segments,
/// transposed in registers: written sample by sample the compiler makes the strided copy
/// gathers or scatters, which cost several times as much here.
fn transpose(block: &[f64], before: f64, len: usize, rows: &mut [f64]) {
    rows[0] = before;
    for k in 1..SEGMENTS {
        rows[k] = block[k * len - 1];
    }
    let body = &mut rows[SEGMENTS..];
    let quads = len / 4 * 4;
    for t in (0..quads).step_by(4) {
        for k in (0..SEGMENTS).step_by(4) {
            let a = transpose4(core::array::from_fn(|q| {
                let at = (k + q) * len + t;
                block[at..at + 4].try_into().expect("four samples")
            }));
            for (row, column) in body[t * SEGMENTS..(t + 4) * SEGMENTS]
                .chunks_exact_mut(SEGMENTS)
                .zip(a)
            {
                row[k..k + 4].copy_from_slice(&column);
            }
        }
    }
    for t in quads..len {
        for k in 0..SEGMENTS {
            body[t * SEGMENTS + k] = block[k * len + t];
        }
    }
}

/// Four samples of four segments as four rows: a 4 × 4 transpose, with AVX in registers.
#[cfg(target_feature = "avx")]
#[inline(always)]
fn transpose4(r: [[f64; 4]; 4]) -> [[f64; 4]; 4] {
    use safe_arch::{m256d, permute2z_m256d, unpack_hi_m256d, unpack_lo_m256d};
    let [r0, r1, r2, r3] = r.map(m256d::from);
    let (t0, t1) = (unpack_lo_m256d(r0, r1), unpack_hi_m256d(r0, r1));
    let (t2, t3) = (unpack_lo_m256d(r2, r3), unpack_hi_m256d(r2, r3));
    [
        permute2z_m256d::<0x20>(t0, t2),
        permute2z_m256d::<0x20>(t1, t3),
        permute2z_m256d::<0x31>(t0, t2),
        permute2z_m256d::<0x31>(t1, t3),
    ]
    .map(|v| v.to_array())
}

/// See the AVX version.
#[cfg(not(target_feature = "avx"))]
#[inline(always)]
fn transpose4(r: [[f64; 4]; 4]) -> [[f64; 4]; 4] {
    core::array::from_fn(|p| core::array::from_fn(|q| r[q][p]))
}

/// One segment's guess as the bank ran it: its channel, the bank's alarms, and the stream
/// index of the segment's first sample (the bank's row 1; row 0, the priming row, is the
/// sample before).
struct Guess<'a> {
    bank: &'a CusumBank,
    channel: usize,
    alarms: &'a [ChannelAlarm],
    first: u64,
}

impl Guess<'_> {
    /// The guess's state before the segment (the bank's after its priming row).
    fn start(&self, before: f64) -> CusumLane {
        CusumLane {
            x_prev: before,
            tap: self.first - 1,
            tan: self.first - 1,
            x_tap: before,
            x_tan: before,
            ..CusumLane::ZERO
        }
    }

    /// The stream index of the bank's step `b`.
    fn index(&self, b: u64) -> u64 {
        self.first - 1 + b
    }
}

/// Whether two states step on identically: the sums bit for bit and the starts (the previous
/// sample is the same data in both; the start values follow from the starts).
fn same(a: &CusumLane, b: &CusumLane) -> bool {
    a.gp.to_bits() == b.gp.to_bits()
        && a.gn.to_bits() == b.gn.to_bits()
        && a.gp_real.to_bits() == b.gp_real.to_bits()
        && a.gn_real.to_bits() == b.gn_real.to_bits()
        && a.tap == b.tap
        && a.tan == b.tan
}

/// Steps the true state `lane` through `segment` beside the guess until they are the same,
/// then takes the guess's alarms and end state from there (or the true run to the end if they
/// never meet), appending the segment's alarms to `out`. Returns how many samples the true run
/// stepped.
fn join(
    lane: &mut CusumLane,
    segment: &[f64],
    guess: &Guess<'_>,
    slice: &Slice<'_>,
    out: &mut Vec<Alarm>,
) -> usize {
    // Both states in locals (registers), not behind the reference, for the whole walk.
    let (mut truth, mut shadow) = (*lane, guess.start(lane.x_prev));
    let mut met = None;
    for (t, &x) in segment.iter().enumerate() {
        if same(&truth, &shadow) {
            met = Some(t);
            break;
        }
        let i = guess.first + t as u64;
        let (flags, _, _) = truth.advance(x, i, slice.sides);
        if flags != 0 {
            out.push(slice.alarm(&mut truth, flags, i, x));
        }
        shadow.advance(x, i, slice.sides);
    }
    *lane = truth;
    if met.is_none() && same(lane, &shadow) {
        met = Some(segment.len());
    }
    let Some(t) = met else {
        return segment.len(); // never met: the true run covered the segment
    };
    // From the segment's sample `t` on, the guess is the truth: its alarms from the bank's row
    // `t + 1`, its end state.
    let from = guess.first + t as u64;
    for a in guess.alarms.iter().filter(|a| a.channel == guess.channel) {
        let index = guess.index(a.alarm.index);
        if index >= from {
            let start = guess.index(a.alarm.start);
            let x = slice.xs[(index - slice.base) as usize];
            out.push(Alarm {
                index,
                start,
                direction: a.alarm.direction,
                amplitude: x - slice.starts.value(start, a.alarm.direction),
            });
        }
    }
    let end = guess.bank.lane(guess.channel);
    lane.gp = end.gp;
    lane.gn = end.gn;
    lane.gp_real = end.gp_real;
    lane.gn_real = end.gn_real;
    lane.tap = guess.index(end.tap);
    lane.tan = guess.index(end.tan);
    lane.x_prev = segment[segment.len() - 1];
    t
}
