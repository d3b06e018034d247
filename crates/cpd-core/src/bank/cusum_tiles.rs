//! The CUSUM bank's kernel: 4-wide vectors, tiles of channels, chunks of time steps.
//!
//! Every step of every channel is [`CusumLane::step`] (TSNet's operation order), computed four
//! channels at a time with explicit vectors (`wide`): each select a blend, so the resets, which
//! the noise decides about every other sample, cost no mispredicted branch. Additions,
//! subtractions, comparisons and blends are exact lane by lane, so every sum, reset, start and
//! alarm is bit-for-bit the scalar detector's. The rare alarm is a branch to a slow path.
//!
//! [`super::CusumBank::step`] is a chunk of one row. Given a `T x channels` matrix,
//! [`super::CusumBank::step_many`] walks the channels in tiles of [`TILE`] and, for each tile,
//! the rows of a chunk of steps: the tile's state stays in the L1 cache over the chunk instead
//! of travelling to the L2 cache and back every step. The alarms found in a chunk are put back
//! in step order, then channel order, before they are appended: the output is that of stepping
//! row by row.

use alloc::vec::Vec;

use wide::bytemuck::{cast, cast_slice_mut};
use wide::{f64x4, u64x4};

use super::cusum::{Block, CusumBank};
use crate::alarm::ChannelAlarm;
use crate::cusum::{CusumLane, DROP, RISE};

/// Channels per tile: four 4-wide vectors in flight, enough to hide the latency of the sums'
/// loop-carried chain (`(g + s) - drift`, then a select).
pub(super) const TILE: usize = 16;

/// Readings per chunk of rows (32 KiB): a chunk stays in the L2 cache while its tiles walk it.
const CHUNK_READINGS: usize = 4096;

/// Rows per chunk for `channels` channels: as many as fit [`CHUNK_READINGS`], at least 8 and at
/// most 512.
fn rows_per_chunk(channels: usize) -> usize {
    (CHUNK_READINGS / channels).clamp(8, 512)
}

/// What every tile of a chunk shares.
#[derive(Clone, Copy)]
pub(super) struct Chunk<'m> {
    /// The chunk's rows, row-major, `channels` wide.
    pub rows: &'m [f64],
    /// Channels per row.
    pub channels: usize,
    /// The step index of the chunk's first row (>= 1: row 0 of a fresh bank only primes).
    pub first: u64,
    pub threshold: f64,
    pub drift: f64,
}

/// The state of a tile of `W` channels, borrowed from the bank as fixed-size arrays (no bounds
/// checks in the kernel); over a chunk of rows it stays in the L1 cache.
struct Tile<'a, const W: usize> {
    x_prev: &'a mut [f64; W],
    gp: &'a mut [f64; W],
    gn: &'a mut [f64; W],
    gp_real: &'a mut [f64; W],
    gn_real: &'a mut [f64; W],
    tap: &'a mut [u64; W],
    tan: &'a mut [u64; W],
    /// The start values as bits: their selects stay blends (as floats the compiler makes them
    /// masked stores, which are slow on some CPUs).
    x_tap: &'a mut [u64; W],
    x_tan: &'a mut [u64; W],
}

impl<'a, const W: usize> Tile<'a, W> {
    /// Channels `c..c + W` of the bank's state.
    fn of(b: &'a mut Block<'_>, c: usize) -> Self {
        fn arr<T, const W: usize>(v: &mut [T], c: usize) -> &mut [T; W] {
            (&mut v[c..c + W]).try_into().expect("tile width")
        }
        Self {
            x_prev: arr(b.x_prev, c),
            gp: arr(b.gp, c),
            gn: arr(b.gn, c),
            gp_real: arr(b.gp_real, c),
            gn_real: arr(b.gn_real, c),
            tap: arr(b.tap, c),
            tan: arr(b.tan, c),
            x_tap: arr(cast_slice_mut(b.x_tap), c),
            x_tan: arr(cast_slice_mut(b.x_tan), c),
        }
    }

    /// [`CusumLane::step`] for the four lanes `g..g + 4` (readings `x`) as 4-wide vectors, every
    /// select a blend; without the alarm's resets, which [`collect`] does on the rare slow path.
    /// Returns whether a lane's sum crossed the threshold. Additions, subtractions, comparisons
    /// and blends are exact lane by lane, so the results are those of the scalar step.
    #[inline(always)]
    fn step4(&mut self, g: usize, x: f64x4, i: u64x4, thr: f64x4, drift: f64x4) -> bool {
        let ld = |v: &[f64; W]| f64x4::new(v[g..g + 4].try_into().expect("group"));
        let ldu = |v: &[u64; W]| u64x4::new(v[g..g + 4].try_into().expect("group"));
        let zero = f64x4::ZERO;
        let s = x - ld(self.x_prev);
        // Same operation order as TSNet: (g + s) - drift.
        let vp = ld(self.gp) + s - drift;
        let vn = ld(self.gn) - s - drift;
        let (rp, rn) = (vp.simd_lt(zero), vn.simd_lt(zero));
        let (rpu, rnu): (u64x4, u64x4) = (cast(rp), cast(rn));
        let gp_real = rp.select(zero, ld(self.gp_real) + s);
        let gn_real = rn.select(zero, ld(self.gn_real) - s);
        let st = |v: &mut [f64; W], y: f64x4| v[g..g + 4].copy_from_slice(&y.to_array());
        let stu = |v: &mut [u64; W], y: u64x4| v[g..g + 4].copy_from_slice(&y.to_array());
        let (tap, tan) = (rpu.select(i, ldu(self.tap)), rnu.select(i, ldu(self.tan)));
        let xu: u64x4 = cast(x);
        let (x_tap, x_tan) = (
            rpu.select(xu, ldu(self.x_tap)),
            rnu.select(xu, ldu(self.x_tan)),
        );
        stu(self.tap, tap);
        stu(self.tan, tan);
        stu(self.x_tap, x_tap);
        stu(self.x_tan, x_tan);
        st(self.x_prev, x);
        st(self.gp, rp.select(zero, vp));
        st(self.gn, rn.select(zero, vn));
        st(self.gp_real, gp_real);
        st(self.gn_real, gn_real);
        (gp_real.simd_gt(thr) | gn_real.simd_gt(thr)).any()
    }

    /// The same step for the one lane `k` (the tiles' remainder), on the scalar lane.
    #[inline(always)]
    fn step1(&mut self, k: usize, x: f64, i: u64, thr: f64, drift: f64) -> bool {
        let mut lane = CusumLane {
            x_prev: self.x_prev[k],
            gp: self.gp[k],
            gn: self.gn[k],
            gp_real: self.gp_real[k],
            gn_real: self.gn_real[k],
            tap: self.tap[k],
            tan: self.tan[k],
            x_tap: f64::from_bits(self.x_tap[k]),
            x_tan: f64::from_bits(self.x_tan[k]),
        };
        lane.step_sums(x, i, drift);
        (self.x_prev[k], self.gp[k], self.gn[k]) = (lane.x_prev, lane.gp, lane.gn);
        (self.gp_real[k], self.gn_real[k]) = (lane.gp_real, lane.gn_real);
        (self.tap[k], self.tan[k]) = (lane.tap, lane.tan);
        (self.x_tap[k], self.x_tan[k]) = (lane.x_tap.to_bits(), lane.x_tan.to_bits());
        (lane.gp_real > thr) | (lane.gn_real > thr)
    }
}

/// Runs the channels `c..c + W` over every row of `chunk`, starting from and returning to the
/// bank's state in `lanes`, and appends their alarms (in row order) to `out`.
#[inline(never)]
pub(super) fn tile<const W: usize>(
    lanes: &mut Block<'_>,
    c: usize,
    chunk: Chunk<'_>,
    out: &mut Vec<ChannelAlarm>,
) {
    let mut r = Tile::<W>::of(lanes, c);
    let (thr, drift) = (chunk.threshold, chunk.drift);
    let (thr4, drift4) = (f64x4::splat(thr), f64x4::splat(drift));
    for (i, row) in (chunk.first..).zip(chunk.rows.chunks_exact(chunk.channels)) {
        let xs: &[f64; W] = row[c..c + W].try_into().expect("tile width");
        let i4 = u64x4::splat(i);
        let mut any = false;
        let mut g = 0;
        while g + 4 <= W {
            let x = f64x4::new(xs[g..g + 4].try_into().expect("group"));
            any |= r.step4(g, x, i4, thr4, drift4);
            g += 4;
        }
        while g < W {
            any |= r.step1(g, xs[g], i, thr, drift);
            g += 1;
        }
        if any {
            collect(c, &mut r, xs, i, thr, out);
        }
    }
}

/// The rare slow path: one alarm per channel of the tile over the threshold, from its state
/// after the step (its starts and start values), and that channel's four sums back to 0, as
/// [`CusumLane::step`] does.
#[cold]
#[inline(never)]
fn collect<const W: usize>(
    c: usize,
    r: &mut Tile<'_, W>,
    xs: &[f64; W],
    i: u64,
    threshold: f64,
    out: &mut Vec<ChannelAlarm>,
) {
    for (k, &x) in xs.iter().enumerate() {
        let flags =
            ((r.gp_real[k] > threshold) as u8 * RISE) | ((r.gn_real[k] > threshold) as u8 * DROP);
        if flags != 0 {
            let lane = CusumLane {
                tap: r.tap[k],
                tan: r.tan[k],
                x_tap: f64::from_bits(r.x_tap[k]),
                x_tan: f64::from_bits(r.x_tan[k]),
                ..CusumLane::ZERO
            };
            out.push(ChannelAlarm {
                channel: c + k,
                alarm: lane.alarm(flags, i, x),
            });
            (r.gp[k], r.gn[k], r.gp_real[k], r.gn_real[k]) = (0.0, 0.0, 0.0, 0.0);
        }
    }
}

impl CusumBank {
    /// Steps every row of a validated row-major matrix, a chunk of rows at a time, tile by tile.
    pub(super) fn advance_many(&mut self, matrix: &[f64], out: &mut Vec<ChannelAlarm>) {
        let n = self.channels();
        let mut rows = matrix;
        if self.steps_seen() == 0 && !rows.is_empty() {
            let (first, rest) = rows.split_at(n);
            self.prime(first);
            rows = rest;
        }
        let (threshold, drift) = (self.config().threshold(), self.config().drift());
        for chunk_rows in rows.chunks(rows_per_chunk(n) * n) {
            let chunk = Chunk {
                rows: chunk_rows,
                channels: n,
                first: self.steps_seen(),
                threshold,
                drift,
            };
            let start = out.len();
            let mut lanes = self.block(0, n);
            let mut c = 0;
            while c + TILE <= n {
                tile::<TILE>(&mut lanes, c, chunk, out);
                c += TILE;
            }
            while c < n {
                tile::<1>(&mut lanes, c, chunk, out);
                c += 1;
            }
            // Tiles ran one after another: put the chunk's alarms back in step, then channel,
            // order (each pair is unique), as stepping row by row appends them.
            out[start..].sort_unstable_by_key(|a| (a.alarm.index, a.channel));
            self.add_steps((chunk_rows.len() / n) as u64);
        }
    }
}
