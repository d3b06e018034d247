//! The CUSUM bank's chunk kernel with the tile's state in registers.
//!
//! Over a chunk of rows, a tile's four sums and two starts are loaded into vector registers
//! once, stepped row after row there, and stored once at the end (and around the rare alarm's
//! slow path). Per row and per vector of channels the kernel then does arithmetic only: one
//! load of the readings, no state traffic. With AVX-512 the vectors are 8 channels wide (two
//! vector ports of 512 bits), otherwise 4 (three of 256 bits); the tile holds enough vectors
//! in flight to hide the loop-carried chain `(g + s) - drift`, compare, reset.
//!
//! The arithmetic is [`crate::cusum::CusumLane::step`]'s, lane by lane, in TSNet's operation
//! order: every sum, reset, start and alarm is bit-for-bit the scalar detector's.

use alloc::vec::Vec;

use wide::bytemuck::cast;

use super::cusum_tiles::{collect, Block, Chunk, Tile};
use crate::alarm::ChannelAlarm;

/// The vector operations of the kernel: AVX-512 (8 channels per vector, comparisons into mask
/// registers, blends on them) where the build targets it, 4-wide `wide` vectors otherwise
/// (comparisons into all-ones lanes, bitwise selects).
#[cfg(target_feature = "avx512f")]
mod v {
    use core::arch::x86_64::{_CMP_GT_OQ, _CMP_NLT_UQ};
    use safe_arch::{
        add_m512d, blend_varying_m512d, cmp_op_mask_f64, m512d, max_m512d, mmask8, set_splat_m512d,
        sub_m512d,
    };
    /// Channels per vector.
    pub const N: usize = 8;
    /// A vector of channels.
    pub type F = m512d;
    /// A per-channel decision.
    pub type M = mmask8;
    #[inline(always)]
    pub fn load(a: [f64; N]) -> F {
        m512d::from(a)
    }
    #[inline(always)]
    pub fn array(v: F) -> [f64; N] {
        v.to_array()
    }
    #[inline(always)]
    pub fn splat(x: f64) -> F {
        set_splat_m512d(x)
    }
    #[inline(always)]
    pub fn add(a: F, b: F) -> F {
        add_m512d(a, b)
    }
    #[inline(always)]
    pub fn sub(a: F, b: F) -> F {
        sub_m512d(a, b)
    }
    /// `!(a < 0)`, per channel: where a sum is kept (the mask of the kept lanes lets the
    /// compiler fold "add, then 0 where reset" into one zero-masked addition).
    #[inline(always)]
    pub fn kept(a: F) -> M {
        cmp_op_mask_f64::<_CMP_NLT_UQ>(a, set_splat_m512d(0.0))
    }
    /// `yes` where `m`, else `no` (an exact move of the bits: also for integers as bits).
    #[inline(always)]
    pub fn pick(m: M, yes: F, no: F) -> F {
        blend_varying_m512d(no, yes, m)
    }
    #[inline(always)]
    pub fn max(a: F, b: F) -> F {
        max_m512d(a, b)
    }
    /// Whether any channel of `a` is over `t`.
    #[inline(always)]
    pub fn any_over(a: F, t: F) -> bool {
        cmp_op_mask_f64::<_CMP_GT_OQ>(a, t) != 0
    }
    // The bank's hint: asks for the cache lines of a slice (no fault, no effect on results).
    pub(super) use super::super::prefetch;
}

/// See the AVX-512 version.
#[cfg(not(target_feature = "avx512f"))]
mod v {
    use wide::f64x4;
    /// Channels per vector.
    pub const N: usize = 4;
    /// A vector of channels.
    pub type F = f64x4;
    /// A per-channel decision: all-ones or all-zeros lanes.
    pub type M = f64x4;
    #[inline(always)]
    pub fn load(a: [f64; N]) -> F {
        F::new(a)
    }
    #[inline(always)]
    pub fn array(v: F) -> [f64; N] {
        v.to_array()
    }
    #[inline(always)]
    pub fn splat(x: f64) -> F {
        F::splat(x)
    }
    #[inline(always)]
    pub fn add(a: F, b: F) -> F {
        a + b
    }
    #[inline(always)]
    pub fn sub(a: F, b: F) -> F {
        a - b
    }
    /// `!(a < 0)`, per channel (the sums are finite: `a >= 0`).
    #[inline(always)]
    pub fn kept(a: F) -> M {
        a.simd_ge(F::ZERO)
    }
    #[inline(always)]
    pub fn pick(m: M, yes: F, no: F) -> F {
        m.bitselect(yes, no)
    }
    #[inline(always)]
    pub fn max(a: F, b: F) -> F {
        a.fast_max(b)
    }
    #[inline(always)]
    pub fn any_over(a: F, t: F) -> bool {
        a.simd_gt(t).any()
    }
    /// No prefetch hint in this form.
    #[inline(always)]
    pub fn prefetch(_: &[f64]) {}
}
use v::{add, pick, sub, F, N};

/// Channels per tile: two 8-wide vectors with AVX-512 (32 vector registers hold their six
/// state vectors each and the constants), two 4-wide ones otherwise (16 registers).
pub(super) const TILE: usize = 2 * N;

/// How far ahead in a row the kernel asks for readings: two tiles.
const AHEAD: usize = 2 * TILE;

/// The four sums and the two starts (as the bits of their `u64`) of one vector of channels.
#[derive(Clone, Copy)]
struct Sums {
    gp: F,
    gn: F,
    gp_real: F,
    gn_real: F,
    tap: F,
    tan: F,
}

impl Sums {
    /// Channels `g..g + N` of the tile's state.
    #[inline(always)]
    fn load<const W: usize>(r: &Tile<'_, W>, g: usize) -> Self {
        let f = |a: &[f64; W]| v::load(a[g..g + N].try_into().expect("vector"));
        let u = |a: &[u64; W]| {
            let bits: [u64; N] = a[g..g + N].try_into().expect("vector");
            v::load(cast(bits))
        };
        Self {
            gp: f(r.gp),
            gn: f(r.gn),
            gp_real: f(r.gp_real),
            gn_real: f(r.gn_real),
            tap: u(r.tap),
            tan: u(r.tan),
        }
    }

    /// Back to channels `g..g + N` of the tile's state.
    #[inline(always)]
    fn store<const W: usize>(self, r: &mut Tile<'_, W>, g: usize) {
        let f = |a: &mut [f64; W], y: F| a[g..g + N].copy_from_slice(&v::array(y));
        let u = |a: &mut [u64; W], y: F| {
            let bits: [u64; N] = cast(v::array(y));
            a[g..g + N].copy_from_slice(&bits);
        };
        f(r.gp, self.gp);
        f(r.gn, self.gn);
        f(r.gp_real, self.gp_real);
        f(r.gn_real, self.gn_real);
        u(r.tap, self.tap);
        u(r.tan, self.tan);
    }

    /// One step on the difference `s` at index `i` (its bits), without the alarm's resets (the
    /// slow path's). Returns the larger real sum per channel: a channel alarms if it is over
    /// the threshold (for finite sums, `max(a, b) > t` is `a > t || b > t`).
    #[inline(always)]
    fn step(&mut self, s: F, i: F, drift: F) -> F {
        let zero = v::splat(0.0);
        // Same operation order as TSNet: (g + s) - drift.
        let vp = sub(add(self.gp, s), drift);
        let vn = sub(sub(self.gn, s), drift);
        // A side resets where its sum went below 0 (`!kept`).
        let (kp, kn) = (v::kept(vp), v::kept(vn));
        self.gp = pick(kp, vp, zero);
        self.gn = pick(kn, vn, zero);
        self.gp_real = pick(kp, add(self.gp_real, s), zero);
        self.gn_real = pick(kn, sub(self.gn_real, s), zero);
        self.tap = pick(kp, self.tap, i);
        self.tan = pick(kn, self.tan, i);
        v::max(self.gp_real, self.gn_real)
    }
}

/// Runs the channels `c..c + TILE` over every row of `chunk` (of two or more rows) with their
/// state in registers, starting from and returning to the bank's state in `lanes`, and
/// appends their alarms (in row order) to `out`.
#[inline(never)]
pub(super) fn tile_resident(
    lanes: &mut Block<'_>,
    c: usize,
    chunk: &Chunk<'_>,
    out: &mut Vec<ChannelAlarm>,
) {
    let mut r = Tile::<TILE>::of(lanes, c);
    let (drift, thr) = (v::splat(chunk.drift), v::splat(chunk.threshold));
    let ld = |a: &[f64; TILE], g: usize| v::load(a[g..g + N].try_into().expect("vector"));
    let mut a = Sums::load(&r, 0);
    let mut b = Sums::load(&r, N);
    let (mut pa, mut pb) = (ld(r.x_prev, 0), ld(r.x_prev, N));
    for (i, row) in (chunk.first..).zip(chunk.rows.chunks_exact(chunk.channels)) {
        let xs: &[f64; TILE] = row[c..c + TILE].try_into().expect("tile width");
        // The readings of the tile after next, in this row: walking down the rows of a wide
        // matrix, the hardware prefetchers do not see them coming.
        if let Some(ahead) = row.get(c + AHEAD..c + AHEAD + TILE) {
            v::prefetch(ahead);
            v::prefetch(&ahead[TILE - 1..]);
        }
        let (xa, xb) = (ld(xs, 0), ld(xs, N));
        let iu = v::splat(f64::from_bits(i));
        let m = v::max(
            a.step(sub(xa, pa), iu, drift),
            b.step(sub(xb, pb), iu, drift),
        );
        (pa, pb) = (xa, xb);
        if v::any_over(m, thr) {
            a.store(&mut r, 0);
            b.store(&mut r, N);
            collect(c, &mut r, xs, i, chunk, out);
            a = Sums::load(&r, 0);
            b = Sums::load(&r, N);
        }
    }
    a.store(&mut r, 0);
    b.store(&mut r, N);
    // The previous readings: the chunk's last row.
    let end = chunk.rows.len() - chunk.channels + c;
    r.x_prev.copy_from_slice(&chunk.rows[end..end + TILE]);
    r.finish(0, c, chunk);
}
