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
//! of travelling to the L2 cache and back every step. Per step and per four channels the kernel
//! reads and writes six state vectors (the four sums and the two starts), not nine: the
//! previous reading is the row above in the chunk, and a start value is the reading at its
//! start, so both are brought up to date once, at the end of the chunk (the bank's state, and
//! so its snapshot, is the same as stepping row by row). The alarms found in a chunk are put
//! back in step order, then channel order, before they are appended: the output is that of
//! stepping row by row.

use alloc::vec::Vec;
use core::hint::select_unpredictable;

use wide::bytemuck::{cast, cast_slice_mut};
use wide::{f64x4, u64x4};

use crate::alarm::ChannelAlarm;
use crate::cusum::{CusumLane, DROP, RISE};

/// The state of a block of channels, borrowed for one step (or one chunk of steps). Separate
/// `&mut` slices tell the compiler they do not alias, so the kernels' loops vectorize.
pub(super) struct Block<'a> {
    pub x_prev: &'a mut [f64],
    pub gp: &'a mut [f64],
    pub gn: &'a mut [f64],
    pub gp_real: &'a mut [f64],
    pub gn_real: &'a mut [f64],
    pub tap: &'a mut [u64],
    pub tan: &'a mut [u64],
    pub x_tap: &'a mut [f64],
    pub x_tan: &'a mut [f64],
}

/// Channels per tile: four 4-wide vectors in flight, enough to hide the latency of the sums'
/// loop-carried chain (`(g + s) - drift`, then a select).
pub(super) const TILE: usize = 16;

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

impl Chunk<'_> {
    /// The start value (as bits) of channel `col` whose start is `t`: its reading in the chunk
    /// if the sums reset in it (`t >= first`), else `before`, the value stored before the chunk.
    /// Branch-free: whether a channel reset in the chunk is the noise's decision.
    #[inline(always)]
    fn start_value(&self, t: u64, col: usize, before: u64) -> u64 {
        let inside = t >= self.first;
        let row = select_unpredictable(inside, t.wrapping_sub(self.first), 0) as usize;
        let v = self.rows[row * self.channels + col].to_bits();
        select_unpredictable(inside, v, before)
    }
}

/// The state of a tile of `W` channels, borrowed from the bank as fixed-size arrays (no bounds
/// checks in the kernel); over a chunk of rows it stays in the L1 cache.
///
/// Per step the kernel reads and writes only the four sums and the two starts: the previous
/// reading is the row above in the chunk, and a start value is the reading at its start, so
/// `x_prev`, `x_tap` and `x_tan` are brought up to date once, at the end of the chunk.
pub(super) struct Tile<'a, const W: usize> {
    pub x_prev: &'a mut [f64; W],
    pub gp: &'a mut [f64; W],
    pub gn: &'a mut [f64; W],
    pub gp_real: &'a mut [f64; W],
    pub gn_real: &'a mut [f64; W],
    pub tap: &'a mut [u64; W],
    pub tan: &'a mut [u64; W],
    /// The start values as bits: their selects stay blends or integer moves (as floats the
    /// compiler makes them branches or masked stores).
    pub x_tap: &'a mut [u64; W],
    pub x_tan: &'a mut [u64; W],
}

impl<'a, const W: usize> Tile<'a, W> {
    /// Channels `c..c + W` of the bank's state.
    pub(super) fn of(b: &'a mut Block<'_>, c: usize) -> Self {
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

    /// [`CusumLane::step`] for the four lanes `g..g + 4` (readings `x`, previous readings
    /// `x_prev`) as 4-wide vectors, every select a blend; without the alarm's resets, which
    /// [`collect`] does on the rare slow path, and without the start values (see [`Tile`]).
    /// Returns whether a lane's sum crossed the threshold. Additions, subtractions, comparisons
    /// and blends are exact lane by lane, so the results are those of the scalar step.
    #[inline(always)]
    fn step4<const ONE: bool>(
        &mut self,
        g: usize,
        x: f64x4,
        x_prev: f64x4,
        i: u64x4,
        c: Consts,
    ) -> bool {
        let ld = |v: &[f64; W]| f64x4::new(v[g..g + 4].try_into().expect("group"));
        let ldu = |v: &[u64; W]| u64x4::new(v[g..g + 4].try_into().expect("group"));
        let zero = f64x4::ZERO;
        // Every load before every store: the state arrays of a bank of 1 024 channels lie
        // 8 KiB apart, so a store to one and a load from the next look alike to the CPU's
        // 4 KiB address check and the load would wait (measured: row by row 1.6x slower).
        // One row (a `step`): the previous readings from the state, the readings stored there.
        let x_prev = if ONE { ld(self.x_prev) } else { x_prev };
        let s = x - x_prev;
        // Same operation order as TSNet: (g + s) - drift.
        let vp = ld(self.gp) + s - c.drift;
        let vn = ld(self.gn) - s - c.drift;
        let (rp, rn) = (vp.simd_lt(zero), vn.simd_lt(zero));
        let (rpu, rnu): (u64x4, u64x4) = (cast(rp), cast(rn));
        // 0 where the mask is set: a bitwise select (an and-not) on the comparison's all-ones
        // or all-zeros lanes, which a blend would first turn into sign masks.
        let reset = |m: f64x4, v: f64x4| m.bitselect(zero, v);
        let gp_real = reset(rp, ld(self.gp_real) + s);
        let gn_real = reset(rn, ld(self.gn_real) - s);
        let (tap, tan) = (rpu.select(i, ldu(self.tap)), rnu.select(i, ldu(self.tan)));
        // A chunk of one row (a `step`): the start values as blends here, where the resets are
        // in registers, rather than reloaded at the end of the chunk.
        let xu: u64x4 = cast(x);
        let starts = ONE.then(|| {
            (
                rpu.select(xu, ldu(self.x_tap)),
                rnu.select(xu, ldu(self.x_tan)),
            )
        });
        let st = |v: &mut [f64; W], y: f64x4| v[g..g + 4].copy_from_slice(&y.to_array());
        let stu = |v: &mut [u64; W], y: u64x4| v[g..g + 4].copy_from_slice(&y.to_array());
        stu(self.tap, tap);
        stu(self.tan, tan);
        st(self.gp, reset(rp, vp));
        st(self.gn, reset(rn, vn));
        st(self.gp_real, gp_real);
        st(self.gn_real, gn_real);
        if let Some((x_tap, x_tan)) = starts {
            stu(self.x_tap, x_tap);
            stu(self.x_tan, x_tan);
            st(self.x_prev, x);
        }
        (gp_real.simd_gt(c.thr) | gn_real.simd_gt(c.thr)).any()
    }

    /// The same step for the one lane `k` (the tiles' remainder), on the scalar lane.
    #[inline(always)]
    fn step1(&mut self, k: usize, x: f64, x_prev: f64, i: u64, c: Consts) -> bool {
        let mut lane = CusumLane {
            x_prev,
            gp: self.gp[k],
            gn: self.gn[k],
            gp_real: self.gp_real[k],
            gn_real: self.gn_real[k],
            tap: self.tap[k],
            tan: self.tan[k],
            ..CusumLane::ZERO
        };
        lane.step_sums(x, i, c.drift1);
        (self.gp[k], self.gn[k]) = (lane.gp, lane.gn);
        (self.gp_real[k], self.gn_real[k]) = (lane.gp_real, lane.gn_real);
        (self.tap[k], self.tan[k]) = (lane.tap, lane.tan);
        (lane.gp_real > c.thr1) | (lane.gn_real > c.thr1)
    }

    /// At the end of a chunk: the start values of the tile's lanes `from..W` (at column `c`)
    /// as stepping row by row leaves them.
    pub(super) fn finish(&mut self, from: usize, c: usize, chunk: &Chunk<'_>) {
        for k in from..W {
            self.x_tap[k] = chunk.start_value(self.tap[k], c + k, self.x_tap[k]);
            self.x_tan[k] = chunk.start_value(self.tan[k], c + k, self.x_tan[k]);
        }
    }
}

/// The threshold and the drift, as scalars and as vectors.
#[derive(Clone, Copy)]
struct Consts {
    thr: f64x4,
    drift: f64x4,
    thr1: f64,
    drift1: f64,
}

/// Runs the channels `c..c + W` over every row of `chunk`, starting from and returning to the
/// bank's state in `lanes`, and appends their alarms (in row order) to `out`.
#[inline(never)]
pub(super) fn tile<const W: usize, const ONE: bool>(
    lanes: &mut Block<'_>,
    c: usize,
    chunk: Chunk<'_>,
    out: &mut Vec<ChannelAlarm>,
) {
    let mut r = Tile::<W>::of(lanes, c);
    let k = Consts {
        thr: f64x4::splat(chunk.threshold),
        drift: f64x4::splat(chunk.drift),
        thr1: chunk.threshold,
        drift1: chunk.drift,
    };
    let before: [f64; W] = *r.x_prev;
    let mut prev: &[f64; W] = &before;
    for (i, row) in (chunk.first..).zip(chunk.rows.chunks_exact(chunk.channels)) {
        let xs: &[f64; W] = row[c..c + W].try_into().expect("tile width");
        let i4 = u64x4::splat(i);
        let mut any = false;
        let mut g = 0;
        while g + 4 <= W {
            let x = f64x4::new(xs[g..g + 4].try_into().expect("group"));
            let xp = f64x4::new(prev[g..g + 4].try_into().expect("group"));
            any |= r.step4::<ONE>(g, x, xp, i4, k);
            g += 4;
        }
        while g < W {
            any |= r.step1(g, xs[g], prev[g], i, k);
            g += 1;
        }
        if any {
            collect(c, &mut r, xs, i, &chunk, out);
        }
        prev = xs;
    }
    // With one row, `step4` did the start values of the groups of four.
    r.finish(if ONE { W / 4 * 4 } else { 0 }, c, &chunk);
    if !ONE {
        *r.x_prev = *prev;
    }
}

/// The rare slow path: one alarm per channel of the tile over the threshold, from its state
/// after the step (its starts, and their start values read from the chunk), and that
/// channel's four sums back to 0, as [`CusumLane::step`] does.
#[cold]
#[inline(never)]
pub(super) fn collect<const W: usize>(
    c: usize,
    r: &mut Tile<'_, W>,
    xs: &[f64; W],
    i: u64,
    chunk: &Chunk<'_>,
    out: &mut Vec<ChannelAlarm>,
) {
    let threshold = chunk.threshold;
    for (k, &x) in xs.iter().enumerate() {
        let flags =
            ((r.gp_real[k] > threshold) as u8 * RISE) | ((r.gn_real[k] > threshold) as u8 * DROP);
        if flags != 0 {
            let lane = CusumLane {
                tap: r.tap[k],
                tan: r.tan[k],
                x_tap: f64::from_bits(chunk.start_value(r.tap[k], c + k, r.x_tap[k])),
                x_tan: f64::from_bits(chunk.start_value(r.tan[k], c + k, r.x_tan[k])),
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
