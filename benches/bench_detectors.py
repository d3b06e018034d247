"""Benchmark burstloc's detectors against the alternatives, in one process, on fresh data.

Usage: ``make bench`` (or ``.venv/bin/python benches/bench_detectors.py [--samples N]``).

Every timed run gets a trace it has never seen (a new seed): heads of 200 m with Gaussian sensor
noise of 0.05 m and a burst (a 0.5-2 m drop with damped ringing) every ~50,000 samples, detectors
at thresholds calibrated for that noise (CUSUM 0.3 m with drift 0.01 m; Shewhart 3 sigma and
0.2 m). Replaying one trace lets the branch predictor learn it; that figure is printed too,
labelled "replayed", for comparison only. In the same run:

* burstloc ``Cusum.update`` once per sample from Python, ``Cusum.update_many`` on the whole
  array (and on 200,000-sample arrays, which stay in the L2 cache; without drift it runs the
  sequential kernel, not the segments: the same-run alternative to them),
  ``Shewhart.update_many`` for W = 10, 100, 10,000, ``DetectorBank`` with 1,024
  channels (``run`` on a matrix and ``step`` once per time step);
* a bare C-function call (``math.fabs``) per sample, the floor of any per-sample call from
  Python, measured on the same values;
* a pure-Python streaming CUSUM, River's ``PageHinkley.update`` and ``burstloc.river.Cusum``
  (if River is installed), TSNet's ``detect_cusum`` (on a slice, scaled to ns/sample).

Every per-sample figure includes the Python ``for`` loop, as a user's loop would. Each figure is
the best of ``--repeat`` runs (each on its own fresh trace), timed by default with the CPU time
of the benchmarking thread (``time.thread_time_ns``; ``update_many`` and ``run`` run on that
thread while the GIL is released) or, with ``--clock wall``, the wall clock. The script prints
the machine's load average, the figures, the ratios and the targets.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time
from collections.abc import Callable, Sequence
from itertools import count

import numpy as np

import burstloc

NOISE = 0.05  # m
CUSUM = {"threshold": 0.3, "drift": 0.01}
SHEWHART = {"sigma": 3.0, "threshold": 0.2}
SEEDS = count(1)


def fresh_trace(n: int, channels: int = 1) -> np.ndarray:
    """``n`` samples (x ``channels``) never generated before in this run (a new seed)."""
    rng = np.random.default_rng(next(SEEDS))
    x = 200.0 + rng.normal(0.0, NOISE, (n, channels))
    t = np.arange(2_000, dtype=float)
    for c in range(channels):
        for start in np.flatnonzero(rng.random(n) < 1 / 50_000):
            drop = rng.uniform(0.5, 2.0)
            ringing = 0.5 * drop * np.exp(-t / 400.0) * np.cos(t / 15.0)
            end = min(start + t.size, n)
            x[start:end, c] += ringing[: end - start]
            x[start:, c] -= drop
    return x[:, 0].copy() if channels == 1 else np.ascontiguousarray(x)


class PurePythonCusum:
    """The same two-sided CUSUM (TSNet's online pass) written as a plain Python class."""

    __slots__ = ("drift", "gn", "gn_real", "gp", "gp_real", "i", "prev", "tan", "tap", "threshold")

    def __init__(self, threshold: float, drift: float = 0.0) -> None:
        self.threshold, self.drift = threshold, drift
        self.gp = self.gn = self.gp_real = self.gn_real = 0.0
        self.tap = self.tan = self.i = 0
        self.prev = 0.0

    def update(self, x: float) -> tuple[int, int] | None:
        i = self.i
        self.i = i + 1
        if i == 0:
            self.prev = x
            return None
        s = x - self.prev
        self.prev = x
        gp = self.gp + s - self.drift
        gp_real = self.gp_real + s
        gn = self.gn - s - self.drift
        gn_real = self.gn_real - s
        if gp < 0:
            gp, gp_real, self.tap = 0.0, 0.0, i
        if gn < 0:
            gn, gn_real, self.tan = 0.0, 0.0, i
        if gp_real > self.threshold or gn_real > self.threshold:
            self.gp = self.gn = self.gp_real = self.gn_real = 0.0
            return (i, self.tap if gp_real > self.threshold else self.tan)
        self.gp, self.gn, self.gp_real, self.gn_real = gp, gn, gp_real, gn_real
        return None


#: Samples of the second ``update_many`` measurement: the size the core's targets were set on,
#: an array that stays in the L2 cache (the default ``--samples`` does not).
IN_CACHE = 200_000

CLOCKS = {"cpu": time.thread_time_ns, "wall": time.perf_counter_ns}
clock = CLOCKS["cpu"]


def best_of(repeat: int, run: Callable[[], object]) -> float:
    """Best time of ``repeat`` runs, in nanoseconds."""
    times = []
    for _ in range(repeat):
        t0 = clock()
        run()
        times.append(clock() - t0)
    return float(min(times))


def per_call(n: int, make: Callable[[], Callable[[float], object]], repeat: int) -> float:
    """ns per sample of calling ``make()``'s function once per value of a fresh trace."""
    return per_calls(n, [make], repeat)[0]


def per_calls(
    n: int, makes: Sequence[Callable[[], Callable[[float], object]]], repeat: int
) -> list[float]:
    """:func:`per_call` for several functions, taken in turn on the same fresh values in each
    repeat, so that a slower spell of the machine falls on all of them alike (their ratio is
    what is compared)."""
    times: list[list[int]] = [[] for _ in makes]
    for _ in range(repeat):
        values = fresh_trace(n).tolist()
        for k, make in enumerate(makes):
            f = make()
            t0 = clock()
            for v in values:
                f(v)
            times[k].append(clock() - t0)
    return [min(t) / n for t in times]


def batch(n: int, run: Callable[[np.ndarray], object], repeat: int, channels: int = 1) -> float:
    """ns per sample (per channel-sample) of ``run`` on fresh traces of ``n`` steps."""
    times = []
    for _ in range(repeat):
        x = fresh_trace(n, channels)
        t0 = clock()
        run(x)
        times.append(clock() - t0)
    return min(times) / (n * channels)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument("--tsnet-samples", type=int, default=100_000)
    parser.add_argument("--channels", type=int, default=1_024)
    parser.add_argument("--steps", type=int, default=2_000, help="bank time steps timed")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--clock", choices=sorted(CLOCKS), default="cpu")
    args = parser.parse_args()
    global clock
    clock = CLOCKS[args.clock]
    n, r, ch = args.samples, args.repeat, args.channels
    load = os.getloadavg()
    print(
        f"burstloc {burstloc.__version__}, Python {platform.python_version()}, "
        f"numpy {np.__version__}, {platform.machine()}, {os.cpu_count()} CPUs, load average "
        f"{load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; {n:,} samples per run, best of {r} runs "
        f"on fresh traces, {args.clock} time\n"
    )
    rows: list[tuple[str, float, str]] = []

    def row(name: str, value: float, unit: str = "ns/sample") -> float:
        rows.append((name, value, unit))
        return value

    # in turn on the same values: their ratio is a target
    pair = per_calls(n, [lambda: math.fabs, lambda: burstloc.Cusum(**CUSUM).update], r)
    floor = row("bare C-function call (math.fabs), per sample", pair[0])
    update = row("burstloc Cusum.update, per sample", pair[1])
    many = row(
        "burstloc Cusum.update_many",
        batch(n, lambda x: burstloc.Cusum(**CUSUM).update_many(x), r),
    )
    cached = row(
        f"burstloc Cusum.update_many, {IN_CACHE:,}-sample arrays (in the L2 cache)",
        batch(IN_CACHE, lambda x: burstloc.Cusum(**CUSUM).update_many(x), r),
    )
    nodrift = row(
        "burstloc Cusum.update_many, drift 0 (the sequential kernel)",
        batch(n, lambda x: burstloc.Cusum(CUSUM["threshold"]).update_many(x), r),
    )
    short, det = fresh_trace(10_000), burstloc.Cusum(**CUSUM)
    replayed = row(
        "burstloc Cusum.update_many, one 10k trace REPLAYED (flatters branches)",
        best_of(r, lambda: [det.update_many(short) for _ in range(100)]) / (100 * short.size),
    )
    shewhart = {}
    for w in (10, 100, 10_000):
        shewhart[w] = row(
            f"burstloc Shewhart.update_many (W={w:,})",
            batch(n, lambda x, w=w: burstloc.Shewhart(w, **SHEWHART).update_many(x), r),
        )
    steps = args.steps

    def bank(kind: str, **config: float) -> Callable[[np.ndarray], object]:
        return lambda m: burstloc.DetectorBank(kind, ch, **config).run(m)

    bank_c = row(
        f"burstloc DetectorBank('cusum', {ch:,}).run",
        batch(steps, bank("cusum", **CUSUM), r, ch),
        "ns/channel-sample",
    )
    bank_s = row(
        f"burstloc DetectorBank('shewhart', {ch:,}, window=50).run",
        batch(steps, bank("shewhart", window=50, **SHEWHART), r, ch),
        "ns/channel-sample",
    )

    def stepped(m: np.ndarray) -> None:
        step = burstloc.DetectorBank("cusum", ch, **CUSUM).step
        for readings in list(m):
            step(readings)

    bank_step = row(
        f"burstloc DetectorBank('cusum', {ch:,}).step, per call",
        batch(steps, stepped, r, ch) * ch / 1e3,
        "µs/step",
    )
    pure = row(
        "pure-Python streaming CUSUM, per sample",
        per_call(n // 10, lambda: PurePythonCusum(**CUSUM).update, r),
    )
    try:
        from river.drift import PageHinkley

        from burstloc.river import Cusum as RiverCusum
    except ImportError:
        river = row("River PageHinkley.update: not installed", math.nan)
    else:
        river = row(
            "River PageHinkley.update, per sample",
            per_call(n // 10, lambda: PageHinkley().update, r),
        )
        row(
            "burstloc.river.Cusum.update (River protocol), per sample",
            per_call(n // 10, lambda: RiverCusum(**CUSUM).update, r),
        )
    try:
        from tsnet.postprocessing import detect_cusum
    except ImportError:
        tsnet = row("TSNet detect_cusum: not installed", math.nan)
    else:
        part = fresh_trace(args.tsnet_samples)
        time_axis = np.arange(part.size) * 0.01
        th, dr = CUSUM["threshold"], CUSUM["drift"]
        t0 = clock()
        theirs = detect_cusum(time_axis, part, th, dr, show=False, ending=True)
        tsnet = row(
            f"TSNet detect_cusum ({part.size:,} samples, scaled)", (clock() - t0) / part.size
        )
        ours = burstloc.detect_cusum(time_axis, part, th, dr)
        same = all(np.array_equal(a, b) for a, b in zip(ours, theirs, strict=True))
        print(f"burstloc.detect_cusum == TSNet detect_cusum on the slice: {same}")

    width = max(len(name) for name, _, _ in rows)
    print(f"{'measurement':<{width}}  {'figure':>10}  unit")
    for name, value, unit in rows:
        print(f"{name:<{width}}  {value:>10.2f}  {unit}")

    checks = [
        ("Cusum.update vs bare C call", update / floor, "x", 1.6),
        ("Cusum.update_many", many, " ns", 2.0),
        (f"Cusum.update_many, {IN_CACHE:,} samples", cached, " ns", 2.0),
        ("Cusum.update_many, drift 0", nodrift, " ns", 2.0),
        *((f"Shewhart.update_many W={w:,}", v, " ns", 6.0) for w, v in shewhart.items()),
        (f"DetectorBank cusum {ch:,} ch", bank_c, " ns", 0.5),
        (f"DetectorBank shewhart W=50 {ch:,} ch", bank_s, " ns", 2.0),
    ]
    print()
    width = max(len(c[0]) for c in checks)
    print(f"{'target (fresh data)':<{width}}  {'measured':>10}  {'target':>8}  met")
    for name, value, unit, target in checks:
        status = "yes" if value <= target else "NO"
        print(f"{name:<{width}}  {value:>9.2f}{unit:<2}  <= {target:<5}  {status}")
    print(
        f"\nratios: update_many fresh / replayed {many / replayed:.1f}x; the sequential kernel "
        f"(drift 0) / update_many's segments {nodrift / many:.1f}x; Cusum.update vs pure "
        f"Python {pure / update:.1f}x, vs River PageHinkley {river / update:.1f}x; update_many "
        f"vs TSNet {tsnet / many:.0f}x; bank step {bank_step:.2f} µs per {ch:,}-channel call"
    )
    print(f"load average at the end: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
