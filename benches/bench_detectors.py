"""Benchmark burstloc's detectors against the alternatives, in one process, on one trace.

Usage: ``make bench`` (or ``.venv/bin/python benches/bench_detectors.py [--samples N]``).

A seeded pressure-like trace (1,000,000 samples of a 50 m head with sensor noise and a burst
transient every 100,000 samples) is fed to:

* burstloc ``Cusum.update`` called once per sample from Python, ``Cusum.update_many`` on the
  whole array, ``Shewhart.update`` (W = 50) per sample, and ``DetectorBank.step`` with 1,000
  channels (one call per time step);
* a pure-Python streaming CUSUM (the same algorithm, a class with an ``update`` method), River's
  ``PageHinkley.update`` (if River is installed) and TSNet's ``detect_cusum`` (on a slice if it
  is slow, scaled to ns/sample);
* a bare C-function call (``math.fabs``) per sample: the floor of any per-sample call from
  Python.

Every per-sample figure includes the Python ``for`` loop, as a user's loop would. Each figure
is the best of ``--repeat`` runs, timed by default with the CPU time of the benchmarking thread
(``time.thread_time_ns``: on a shared machine it leaves out the time the thread waits for a
core; ``update_many`` runs on that same thread while the GIL is released) or, with
``--clock wall``, with the wall clock. The script prints the figures, the ratios and the
targets.
"""

from __future__ import annotations

import argparse
import math
import platform
import sys
import time
from collections.abc import Callable

import numpy as np

import burstloc


def pressure_trace(n: int, seed: int = 2024) -> np.ndarray:
    """A 50 m head with 1 cm noise and, every 100,000 samples, a burst (a drop plus ringing)."""
    rng = np.random.default_rng(seed)
    x = 50.0 + rng.normal(0.0, 0.01, n)
    t = np.arange(2_000, dtype=float)
    for start in range(50_000, n, 100_000):
        drop = rng.uniform(0.5, 5.0)
        ringing = drop * np.exp(-t / 400.0) * np.cos(2.0 * np.pi * t / 90.0)
        end = min(start + t.size, n)
        x[start:end] += (-drop + 0.5 * ringing)[: end - start]
        x[end:] -= drop * 0.2  # the new steady state after the burst
    return x


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


def per_call(values: list[float], make: Callable[[], Callable[[float], object]], repeat: int):
    """ns per sample of calling ``make()``'s function once per value, in a Python loop."""

    def run() -> None:
        f = make()
        for v in values:
            f(v)

    return best_of(repeat, run) / len(values)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument("--tsnet-samples", type=int, default=100_000)
    parser.add_argument("--channels", type=int, default=1_000)
    parser.add_argument("--steps", type=int, default=2_000, help="bank time steps timed")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--clock", choices=sorted(CLOCKS), default="cpu")
    args = parser.parse_args()
    global clock
    clock = CLOCKS[args.clock]

    x = pressure_trace(args.samples)
    values = x.tolist()
    threshold, drift = 0.3, 0.02
    r = args.repeat
    print(
        f"burstloc {burstloc.__version__}, Python {platform.python_version()}, "
        f"numpy {np.__version__}, {platform.machine()}; {x.size:,} samples, "
        f"best of {r}, {args.clock} time"
    )

    alarms = burstloc.Cusum(threshold, drift).update_many(x)
    print(f"trace: {len(alarms)} CUSUM alarms (threshold {threshold} m, drift {drift} m)\n")

    rows: list[tuple[str, float, str]] = []
    floor = per_call(values, lambda: math.fabs, r)
    rows.append(("bare C-function call (math.fabs)", floor, "ns/sample"))
    update = per_call(values, lambda: burstloc.Cusum(threshold, drift).update, r)
    rows.append(("burstloc Cusum.update, per sample", update, "ns/sample"))
    many = best_of(r, lambda: burstloc.Cusum(threshold, drift).update_many(x)) / x.size
    rows.append(("burstloc Cusum.update_many", many, "ns/sample"))
    shewhart = per_call(values, lambda: burstloc.Shewhart(50, 0.3).update, r)
    rows.append(("burstloc Shewhart.update (W=50), per sample", shewhart, "ns/sample"))
    shewhart_many = best_of(r, lambda: burstloc.Shewhart(50, 0.3).update_many(x)) / x.size
    rows.append(("burstloc Shewhart.update_many (W=50)", shewhart_many, "ns/sample"))

    matrix = np.ascontiguousarray(
        np.column_stack(
            [np.roll(x[: args.steps * 4], 7 * c)[: args.steps] for c in range(args.channels)]
        )
    )
    steps = list(matrix)  # row views, made before timing

    def bank_steps(kind: str, **config: float) -> None:
        bank = burstloc.DetectorBank(kind, args.channels, **config)
        step = bank.step
        for row in steps:
            step(row)

    bank = best_of(r, lambda: bank_steps("cusum", threshold=threshold, drift=drift)) / len(steps)
    rows.append((f"burstloc DetectorBank.step, cusum, {args.channels} ch", bank / 1e3, "µs/step"))
    bank_sh = best_of(r, lambda: bank_steps("shewhart", window=50, threshold=0.3)) / len(steps)
    name = f"burstloc DetectorBank.step, shewhart W=50, {args.channels} ch"
    rows.append((name, bank_sh / 1e3, "µs/step"))

    pure = per_call(values, lambda: PurePythonCusum(threshold, drift).update, r)
    rows.append(("pure-Python streaming CUSUM, per sample", pure, "ns/sample"))
    try:
        from river.drift import PageHinkley
    except ImportError:
        river = math.nan
        rows.append(("River PageHinkley.update: not installed", river, "ns/sample"))
    else:
        river = per_call(values, lambda: PageHinkley().update, r)
        rows.append(("River PageHinkley.update, per sample", river, "ns/sample"))
    try:
        from tsnet.postprocessing import detect_cusum
    except ImportError:
        tsnet = math.nan
        rows.append(("TSNet detect_cusum: not installed", tsnet, "ns/sample"))
    else:
        part = x[: args.tsnet_samples]
        time_axis = np.arange(part.size) * 0.01
        tsnet = (
            best_of(
                r, lambda: detect_cusum(time_axis, part, threshold, drift, show=False, ending=True)
            )
            / part.size
        )
        rows.append((f"TSNet detect_cusum ({part.size:,} samples, scaled)", tsnet, "ns/sample"))
        ours = burstloc.detect_cusum(time_axis, part, threshold, drift)
        theirs = detect_cusum(time_axis, part, threshold, drift, show=False, ending=True)
        same = all(np.array_equal(a, b) for a, b in zip(ours, theirs, strict=True))
        batch = best_of(r, lambda: burstloc.detect_cusum(time_axis, part, threshold, drift))
        rows.append(("burstloc detect_cusum (same slice)", batch / part.size, "ns/sample"))
        print(f"burstloc.detect_cusum == TSNet detect_cusum on the slice: {same}")

    width = max(len(name) for name, _, _ in rows)
    print(f"{'measurement':<{width}}  {'figure':>10}  unit")
    for name, value, unit in rows:
        print(f"{name:<{width}}  {value:>10.2f}  {unit}")

    checks = [
        ("Cusum.update per call", f"{update:.1f} ns", "<= 80 ns", update <= 80.0),
        ("Cusum.update vs pure Python", f"{pure / update:.1f}x", ">= 5x", pure / update >= 5.0),
        ("Cusum.update vs River", f"{river / update:.1f}x", ">= 10x", river / update >= 10.0),
        ("Cusum.update vs bare C call", f"{update / floor:.2f}x the floor", "(info)", True),
        ("Cusum.update_many", f"{many:.2f} ns/sample", "<= 3 ns", many <= 3.0),
        ("Cusum.update_many vs TSNet", f"{tsnet / many:.0f}x", ">= 500x", tsnet / many >= 500.0),
        (f"DetectorBank.step ({args.channels} ch)", f"{bank / 1e3:.2f} µs", "<= 3 µs", bank <= 3e3),
    ]
    print()
    width = max(len(c[0]) for c in checks)
    print(f"{'ratio / target':<{width}}  {'measured':>18}  {'target':>8}  met")
    for name, measured, target, ok in checks:
        status = "-" if target == "(info)" else ("yes" if ok else "NO")
        print(f"{name:<{width}}  {measured:>18}  {target:>8}  {status}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
