"""The live monitor's looks at the arrivals on a large network: resumed, or all taken again.

Usage: ``.venv/bin/python benches/bench_live_looks.py [--cache-dir DIR] [--pipes P ...]
[--corroborate N] [--resumed-only]``. On
EPANET's Net3 (every junction metered, its 30 m transient-ready model, a burst mid-pipe, the
paper's 0.2 s capture interval), each burst is simulated (or read from the cache) and its
captured readings streamed through ``BurstMonitor`` twice: as it runs (each call to
``rank_alarms`` resumes the looks at the arrivals at the last ``look_again``), and with the
looks taken from the start at every reading (``resume`` dropped: the monitor before the
change; ``--resumed-only`` skips it). ``--corroborate``: the meters that must alarm (default
the monitor's, 2; on Net3 a burst on a large main is first heard by one meter alone for
seconds). Printed per burst: the readings pushed, the monitor's CPU time over them both ways,
the slowest single push, whether both gave the same decision (pipe and time), then the
monitor's decisions (pipe @ reading time) and how many alarms it dismissed.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
NET3 = ROOT / "networks" / "public" / "Net3.inp"


def stream(
    monitor: Any, times: np.ndarray, values: np.ndarray
) -> tuple[float, float, list[Any], int]:
    """Push every reading: total CPU, the slowest push, the decisions, the alarms dismissed."""
    from burstloc.readings import Step

    total, slowest, decisions = 0.0, 0.0, []
    for t, row in zip(times, values, strict=True):
        started = time.process_time()
        decided = monitor.push(Step(float(t), row))
        spent = time.process_time() - started
        total += spent
        slowest = max(slowest, spent)
        if decided is not None:
            decisions.append(decided)
    return total, slowest, decisions, monitor.dismissed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cache-dir", default=None)
    parser.add_argument("--pipes", nargs="*", default=["20", "40", "101", "133", "189"])
    parser.add_argument("--corroborate", type=int, default=2)
    parser.add_argument("--resumed-only", action="store_true")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT / "python"))
    from burstloc.experiments.calibrate import calibrate
    from burstloc.experiments.harness import Clock, capture_readings
    from burstloc.live import monitor as live
    from burstloc.sim.scenarios.cache import DiskCache
    from burstloc.sim.scenarios.scenario import BurstScenario
    from burstloc.sim.transient.tsnet import simulate_burst

    if not NET3.is_file():
        raise SystemExit(f"{NET3} is missing: run `make setup`")
    cache = DiskCache(args.cache_dir) if args.cache_dir else True
    config = calibrate(str(NET3), capture_intervals=[0.2])
    resumed = live.rank_alarms

    def from_start(*a: Any, **kw: Any) -> Any:
        kw.pop("resume", None)
        return resumed(*a, **kw)

    print(
        "burst   readings  resumed CPU s (slowest push)  from start CPU s (slowest push)  same"
        "  decisions (pipe @ s)  dismissed"
    )
    for pipe in args.pipes:
        scenario = BurstScenario(
            str(NET3), pipe, opening_time=0.3, burst_coeff=0.02, min_pipe_length=30.0
        )
        result = simulate_burst(scenario, cache=cache)
        times, values = capture_readings(
            result, Clock(0.2, history=100), meters=list(config.meters)
        )
        runs = []
        for rank in (resumed,) if args.resumed_only else (resumed, from_start):
            live.rank_alarms = rank
            try:
                monitor = live.BurstMonitor(
                    str(NET3), config, capture_interval=0.2, corroborate=args.corroborate
                )
                runs.append(stream(monitor, times, values))
            finally:
                live.rank_alarms = resumed
        a, a_max, da, dismissed = runs[0]
        other, same = "-", "-"
        if len(runs) > 1:
            b, b_max, db, _ = runs[1]
            other = f"{b:>13.2f} ({b_max:.3f})"
            same = "yes" if [_key(d) for d in da] == [_key(d) for d in db] else "NO"
        found = ", ".join(f"{d.decision.pipe} @ {d.decision.time:.1f}" for d in da) or "none"
        print(
            f"{pipe:<7} {times.size:>8}  {a:>13.2f} ({a_max:.3f})"
            f"           {other:>21}            {same:>4}  {found:<20}  {dismissed:>9}"
        )


def _key(decided: Any) -> tuple[Any, float]:
    return decided.decision.pipe, decided.decision.time


if __name__ == "__main__":
    os.chdir(tempfile.gettempdir())
    main()
