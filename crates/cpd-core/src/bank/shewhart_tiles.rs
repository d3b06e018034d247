//! The Shewhart bank's kernel: tiles of channels over chunks of rows, the sums in registers.
//!
//! A chunk is a run of rows with no ring wrap among them (so no rebuild) and one kind of step
//! (the window filling or full): at most `W - 1` rows; a wrap's row is a chunk of its own
//! (the step, the rebuilds, then the screen). For each tile of [`TILE`] channels, the kernel
//! loads the five sums once, steps them over every row of the chunk in vector registers (the
//! ring row of each step is contiguous for the tile) and stores them once; per row and per
//! vector of channels it reads the readings and the ring's oldest samples and does arithmetic
//! only (the chunk's rows are copied into the ring afterwards, in one block). The screen's
//! outcome is one branch per row and tile, taken only when a channel is not surely in
//! control: the rare slow path stores the sums and decides those channels exactly as the bank
//! always did.
//!
//! The arithmetic is [`Sums`]'s, generic over [`Lane`]: with AVX-512, vectors of 8 channels
//! (`wide::f64x8`), otherwise of 4; the channels past the last whole tile run one by one on
//! `f64`. Every lane's operations are the scalar ones in the same order, so every sum, ring
//! sample and alarm is bit-for-bit that of the scalar detector.

use alloc::vec::Vec;

use super::prefetch;
use crate::alarm::{Alarm, ChannelAlarm};
use crate::shewhart::{exact_decision, Lane, ShewhartConfig, Sums};

/// A vector of channels: the lane type of the kernel and its memory operations.
pub(super) trait Vector: Lane {
    /// Channels per vector.
    const N: usize;
    /// The first `N` values of `a`.
    fn load(a: &[f64]) -> Self;
    /// Writes the lanes to the first `N` values of `a`.
    fn store(self, a: &mut [f64]);
    /// Bit `k` set where lane `k` of `self` is not `<= t` (also where it is NaN).
    fn over(self, t: Self) -> u32;
}

impl Vector for f64 {
    const N: usize = 1;
    #[inline(always)]
    fn load(a: &[f64]) -> Self {
        a[0]
    }
    #[inline(always)]
    fn store(self, a: &mut [f64]) {
        a[0] = self;
    }
    #[inline(always)]
    fn over(self, t: Self) -> u32 {
        u32::from(self <= t) ^ 1
    }
}

/// Implements [`Lane`] and [`Vector`] for a `wide` vector of `$n` lanes.
macro_rules! wide_vector {
    ($t:ty, $n:literal) => {
        impl Lane for $t {
            #[inline(always)]
            fn splat(x: f64) -> Self {
                <$t>::splat(x)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
        }
        impl Vector for $t {
            const N: usize = $n;
            #[inline(always)]
            fn load(a: &[f64]) -> Self {
                <$t>::new(a[..$n].try_into().expect("vector"))
            }
            #[inline(always)]
            fn store(self, a: &mut [f64]) {
                a[..$n].copy_from_slice(&self.to_array());
            }
            #[inline(always)]
            fn over(self, t: Self) -> u32 {
                self.simd_le(t).to_bitmask() ^ ((1 << $n) - 1)
            }
        }
    };
}

/// The vector of the kernel: 8 channels with AVX-512 (32 registers: two vectors' sums, their
/// temporaries and the constants stay in registers), 4 otherwise.
#[cfg(target_feature = "avx512f")]
type F = wide::f64x8;
#[cfg(target_feature = "avx512f")]
wide_vector!(wide::f64x8, 8);
#[cfg(not(target_feature = "avx512f"))]
type F = wide::f64x4;
#[cfg(not(target_feature = "avx512f"))]
wide_vector!(wide::f64x4, 4);

/// Vectors per tile: with AVX-512, two chains of sums in flight; otherwise one (with 16
/// registers, the sums of two vectors would not stay in them).
#[cfg(target_feature = "avx512f")]
const G: usize = 2;
/// See the AVX-512 version.
#[cfg(not(target_feature = "avx512f"))]
const G: usize = 1;

/// Channels per tile.
pub(super) const TILE: usize = G * <F as Vector>::N;

/// How far ahead in a row the kernel asks for readings and ring samples: four tiles (measured
/// at 1 024 channels: a little faster than two).
const AHEAD: usize = 4 * TILE;

/// The bank's per-channel state, borrowed as separate slices (the ring `[W][channels]`).
pub(super) struct Lanes<'a> {
    pub reference: &'a mut [f64],
    pub s1: &'a mut [f64],
    pub c1: &'a mut [f64],
    pub s2: &'a mut [f64],
    pub c2: &'a mut [f64],
    pub ring: &'a mut [f64],
}

impl Lanes<'_> {
    /// The sums of channel `c`.
    #[inline(always)]
    fn sums(&self, c: usize) -> Sums {
        self.load::<f64>(c)
    }

    /// The sums of channels `c..c + V::N`, as one vector per sum.
    #[inline(always)]
    fn load<V: Vector>(&self, c: usize) -> Sums<V> {
        let a: [&[f64]; 5] = [self.reference, self.s1, self.c1, self.s2, self.c2];
        gather(a, c)
    }

    /// Back to channels `c..c + V::N` (the reference does not change within a chunk).
    #[inline(always)]
    fn store<V: Vector>(&mut self, c: usize, s: &Sums<V>) {
        s.s1.store(&mut self.s1[c..]);
        s.c1.store(&mut self.c1[c..]);
        s.s2.store(&mut self.s2[c..]);
        s.c2.store(&mut self.c2[c..]);
    }
}

/// The sums of channels `c..c + V::N` from the state arrays `[reference, s1, c1, s2, c2]`.
#[inline(always)]
pub(super) fn gather<V: Vector>(a: [&[f64]; 5], c: usize) -> Sums<V> {
    Sums {
        reference: V::load(&a[0][c..]),
        s1: V::load(&a[1][c..]),
        c1: V::load(&a[2][c..]),
        s2: V::load(&a[3][c..]),
        c2: V::load(&a[4][c..]),
    }
}

/// What every tile of a chunk shares.
#[derive(Clone, Copy)]
pub(super) struct Chunk<'m> {
    /// The chunk's readings, row-major, `channels` wide.
    pub rows: &'m [f64],
    pub channels: usize,
    /// The step index of the chunk's first row.
    pub first: u64,
    /// The ring slot of the chunk's first row (the rows' slots follow without a wrap).
    pub slot: usize,
    /// At a ring wrap (a chunk of one row): every channel's sums are rebuilt, not only those
    /// off centre.
    pub rebuild_all: bool,
    pub config: &'m ShewhartConfig,
}

/// The alarm of channel `c` at step `i` for its newest sample `x`, its window being
/// `window(0..W)` (oldest first), or `None`: [`Sums::decide`], with the exact window scan near
/// a tie. Called for the rare samples the screen does not pass.
#[cold]
#[inline(never)]
fn alarm_of(
    sums: &Sums,
    c: usize,
    x: f64,
    i: u64,
    window: impl Fn(usize) -> f64,
    config: &ShewhartConfig,
) -> Option<ChannelAlarm> {
    let w = config.window();
    let decision = sums.decide(x, config, || exact_decision(x, w, window, config));
    decision.map(|d| ChannelAlarm {
        channel: c,
        alarm: Alarm::at(i, d),
    })
}

/// The slow path of a tile whose screen flagged channels at row `r` of the chunk (bit `k` of
/// `flags`: channel `c + k`): each is decided from its sums, already stored, and its window
/// (its samples of rows `0..=r` from the chunk: the kernel leaves the ring to [`chunk`], the
/// older ones from the ring), and its alarm appended to `out`.
#[cold]
#[inline(never)]
fn collect(
    l: &Lanes<'_>,
    c: usize,
    mut flags: u32,
    r: usize,
    k: &Chunk<'_>,
    out: &mut Vec<ChannelAlarm>,
) {
    let (n, w) = (k.channels, k.config.window());
    // The step's ring slot is the last of the window: the oldest sample is at the next one.
    let pos = (k.slot + r + 1) % w;
    let i = k.first + r as u64;
    while flags != 0 {
        let ch = c + flags.trailing_zeros() as usize;
        flags &= flags - 1;
        let window = |j: usize| {
            let slot = if pos + j < w { pos + j } else { pos + j - w };
            if (k.slot..=k.slot + r).contains(&slot) {
                k.rows[(slot - k.slot) * n + ch]
            } else {
                l.ring[slot * n + ch]
            }
        };
        let x = k.rows[r * n + ch];
        out.extend(alarm_of(&l.sums(ch), ch, x, i, window, k.config));
    }
}

/// The cold part of a wrap: the sums of the channels `c + k` (bit `k` of `redo`) rebuilt from
/// the ring, if `all` or if off centre (the scalar test; the vector one may flag more).
#[cold]
#[inline(never)]
fn rebuild(l: &mut Lanes<'_>, c: usize, mut redo: u32, all: bool, k: &Chunk<'_>) {
    let (n, w, inv_w) = (k.channels, k.config.window(), k.config.derived().inv_w);
    while redo != 0 {
        let ch = c + redo.trailing_zeros() as usize;
        redo &= redo - 1;
        let mut sums = l.sums(ch);
        if all || sums.off_centre(inv_w) {
            let ring = &*l.ring;
            sums.rebuild(w, inv_w, |j| ring[j * n + ch]);
            l.reference[ch] = sums.reference;
            l.store(ch, &sums);
        }
    }
}

/// A ring wrap for the channels `c..c + GV * V::N`, after their step (a chunk of one row, its
/// samples already in the ring): their sums rebuilt where off centre (all of them every
/// [`crate::shewhart::REBUILD_MIN`] steps or so), then the screen on the rebuilt sums and the
/// rare alarms appended to `out`: per channel, what the bank always did at a wrap.
#[inline(always)]
fn wrap<V: Vector, const GV: usize>(
    l: &mut Lanes<'_>,
    c: usize,
    k: &Chunk<'_>,
    out: &mut Vec<ChannelAlarm>,
) {
    let width = GV * V::N;
    let d = k.config.derived();
    let (inv_w, thr) = (V::splat(d.inv_w), V::splat(k.config.threshold()));
    let mut redo = 0;
    for g in 0..GV {
        let (a, b) = l.load::<V>(c + g * V::N).centring(inv_w);
        redo |= a.over(b) << (g * V::N);
    }
    if k.rebuild_all {
        redo = u32::MAX >> (32 - width);
    }
    if redo != 0 {
        rebuild(l, c, redo, k.rebuild_all, k);
    }
    let mut flags = 0;
    for g in 0..GV {
        let x = V::load(&k.rows[c + g * V::N..]);
        flags |= l.load::<V>(c + g * V::N).screen(x, inv_w).over(thr) << (g * V::N);
    }
    if flags != 0 {
        collect(l, c, flags, 0, k, out);
    }
}

/// Runs the channels `c..c + GV * V::N` over every row of the chunk with their sums in
/// registers: the sums slid (`FULL`: the oldest sample read from the ring) or pushed, and
/// the rare alarms appended to `out`, in row order: screened in the same pass, or (`WRAP`, a
/// chunk of one row) after the rebuild of [`wrap`]. The ring is written here only for a chunk
/// of one row: storing each row into the ring, 8 KiB below the one about to be loaded at
/// 1 024 channels, would make the loads wait on the CPU's 4 KiB address check.
#[inline(always)]
fn tile<V: Vector, const GV: usize, const FULL: bool, const WRAP: bool>(
    l: &mut Lanes<'_>,
    c: usize,
    k: &Chunk<'_>,
    out: &mut Vec<ChannelAlarm>,
) {
    let n = k.channels;
    let width = GV * V::N;
    // The window is full and no wrap: screen in the same pass.
    let screen = FULL && !WRAP;
    // A chunk of one row writes the ring here, while its line is in the cache.
    let one_row = k.rows.len() == n;
    let d = k.config.derived();
    let (inv_w, thr) = (V::splat(d.inv_w), V::splat(k.config.threshold()));
    let mut s: [Sums<V>; GV] = core::array::from_fn(|g| l.load(c + g * V::N));
    for (r, row) in k.rows.chunks_exact(n).enumerate() {
        let xs = &row[c..c + width];
        let at = (k.slot + r) * n + c;
        // The readings and oldest samples of the tiles ahead, in this row: walking down
        // the rows of a wide matrix and of the ring, the hardware prefetchers do not see them
        // coming.
        if let Some(ahead) = row.get(c + AHEAD..c + AHEAD + TILE) {
            prefetch(ahead);
            if FULL {
                prefetch(&l.ring[at + AHEAD..at + AHEAD + TILE]);
            }
        }
        let ring = &mut l.ring[at..at + width];
        let mut flags = 0;
        for (g, sums) in s.iter_mut().enumerate() {
            let x = V::load(&xs[g * V::N..]);
            let old = &mut ring[g * V::N..];
            if FULL {
                sums.slide(x, V::load(old));
            } else {
                sums.push(x);
            }
            if one_row {
                x.store(old);
            }
            if screen {
                flags |= sums.screen(x, inv_w).over(thr) << (g * V::N);
            }
        }
        if screen && flags != 0 {
            for (g, sums) in s.iter().enumerate() {
                l.store(c + g * V::N, sums);
            }
            collect(l, c, flags, r, k, out);
        }
    }
    for (g, sums) in s.iter().enumerate() {
        l.store(c + g * V::N, sums);
    }
    if WRAP {
        wrap::<V, GV>(l, c, k, out);
    }
}

/// Runs every channel over the chunk: whole tiles as vectors, the rest one by one, then copies
/// the chunk's rows into their ring slots (one block: the slots follow each other; a chunk of
/// one row is written by the tiles). The alarms
/// are appended tile after tile (each in row order): the caller puts them back in step order.
#[inline(never)]
pub(super) fn chunk<const FULL: bool, const WRAP: bool>(
    l: &mut Lanes<'_>,
    k: &Chunk<'_>,
    out: &mut Vec<ChannelAlarm>,
) {
    // Two plain loops, not one over an iterator or a closure: `tile` is inlined here, and
    // anything more live across it (an iterator's state, a closure's captured references)
    // costs the kernel registers (measured: 8 % more instructions at 1 024 channels).
    let mut c = 0;
    while c + TILE <= k.channels {
        tile::<F, G, FULL, WRAP>(l, c, k, out);
        c += TILE;
    }
    while c < k.channels {
        tile::<f64, 1, FULL, WRAP>(l, c, k, out);
        c += 1;
    }
    if k.rows.len() > k.channels {
        let at = k.slot * k.channels;
        l.ring[at..at + k.rows.len()].copy_from_slice(k.rows);
    }
}
