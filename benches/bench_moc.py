"""The vectorized MOC solver against TSNet's own, on the same initialized model, same run.

Usage: ``.venv/bin/python benches/bench_moc.py [--duration S] [--networks NAME ...]``. Per
network of the set (paper15, EPANET's Net1, Net2, Anytown, and Net3 on its transient-ready
model with 30 m pipes), one burst (mid-pipe, from 1 s, opening in 0.3 s, coefficient 0.01) of
``--duration`` simulated seconds, simulated by ``burstloc.sim.transient.tsnet.simulate_burst`` (no
cache)
with each solver:

* time steps; CPU seconds of the solver call alone and of the whole simulation (network
  preparation, EPANET's steady state, TSNet's discretization, the solve), with the speed-ups
  (TSNet / vectorized) and the vectorized solver's microseconds per step;
* the largest head difference at the meters and whether the heads are identical to the last
  bit (they are where NumPy's ``np.dot`` sums as OpenBLAS with NumPy 1.26 does; see
  ``burstloc.sim.transient.moc``).

TSNet is the slow side: Net3 costs it about 5 CPU s per simulated second; ``--duration``
(default 5 s) keeps the whole run to a few minutes. One solve at a time.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
NETWORKS: dict[str, tuple[str, str, float | None]] = {
    "paper15": ("networks/paper15.inp", "7", None),
    "Net1": ("networks/public/Net1.inp", "110", None),
    "Net2": ("networks/public/Net2.inp", "20", None),
    "Anytown": ("networks/public/Anytown.inp", "4", None),
    "Net3 (30 m)": ("networks/public/Net3.inp", "20", 30.0),
}


def solve_times(solver: str, scenario: Any) -> tuple[float, float, Any]:
    """Simulate ``scenario`` with ``solver``: CPU seconds of the solver call alone, of the whole
    simulation (network preparation, steady state, discretization, solve), and the result."""
    from dataclasses import replace

    from burstloc.sim.transient import _tsnet_compat, moc, tsnet

    module = _tsnet_compat.load().simulation if solver == "tsnet" else moc
    attribute = "MOCSimulator" if solver == "tsnet" else "solve"
    original = getattr(module, attribute)
    spent: list[float] = []

    def timed(*args: Any, **kwargs: Any) -> Any:
        started = time.process_time()
        try:
            return original(*args, **kwargs)
        finally:
            spent.append(time.process_time() - started)

    setattr(module, attribute, timed)
    try:
        started = time.process_time()
        result = tsnet.simulate_burst(replace(scenario, solver=solver), cache=False)
        total = time.process_time() - started
    finally:
        setattr(module, attribute, original)
    return spent[0], total, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--duration", type=float, default=5.0, help="simulated seconds")
    parser.add_argument("--networks", nargs="*", default=list(NETWORKS), choices=list(NETWORKS))
    args = parser.parse_args()
    os.chdir(ROOT)
    sys.path.insert(0, str(ROOT / "python"))
    from burstloc.sim.scenarios.scenario import BurstScenario

    print(f"one burst, {args.duration:g} s simulated; CPU seconds, one process")
    header = (
        f"{'network':<12} {'steps':>6} {'TSNet solve':>11} {'vector solve':>12} "
        f"{'speed-up':>8} {'TSNet sim':>9} {'vector sim':>10} {'speed-up':>8} "
        f"{'us/step':>7} {'max |dh| m':>10} {'identical':>9}"
    )
    print(header)
    print("-" * len(header))
    for name in args.networks:
        path, pipe, min_length = NETWORKS[name]
        if not (ROOT / path).is_file():
            print(f"{name:<12} missing {path}: run `make setup`")
            continue
        scenario = BurstScenario(
            path,
            pipe,
            burst_start=1.0,
            opening_time=0.3,
            duration=args.duration,
            min_pipe_length=min_length,
        )
        t_solve, t_total, ref = solve_times("tsnet", scenario)
        v_solve, v_total, vec = solve_times("vectorized", scenario)
        steps = ref.time.size
        diff = float(np.abs(ref.heads - vec.heads).max())
        print(
            f"{name:<12} {steps:>6} {t_solve:>11.2f} {v_solve:>12.3f} {t_solve / v_solve:>7.0f}x "
            f"{t_total:>9.2f} {v_total:>10.2f} {t_total / v_total:>7.1f}x "
            f"{1e6 * v_solve / steps:>7.0f} {diff:>10.2e} "
            f"{'yes' if np.array_equal(ref.heads, vec.heads) else 'no':>9}"
        )


if __name__ == "__main__":
    main()
