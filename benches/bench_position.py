"""What the burst position and the meter placements cost, and what the position estimate can
resolve, on fresh seeded bursts (no TSNet: the arrival times come from the network's geometry).

Usage: ``.venv/bin/python benches/bench_position.py [NETWORK.inp ...] [--bursts N]
[--repeat R]`` (default: ``networks/paper15.inp`` and ``networks/awumah11.inp``). Per network,
in one process:

* ``ArrivalLocalizer.rank`` (every pipe, its 9 candidate points) beside
  ``ArrivalLocalizer.position`` on the named pipe (1 m points), per burst: the price of the
  answer in metres relative to the ranking it refines;
* the position error (network distance, mean / p90) on ideal alarms: a burst at a random point
  of a random pipe, every junction metered, each alarm stamped at the last capture tick before
  the wave arrives (no detector, no noise), at 0.01 s and 0.2 s capture intervals: the floor the
  capture interval sets (one 0.2 s step is 240 m of wave travel at 1200 m/s);
* ``burstloc place`` with each method for a quarter of the junctions: seconds (the coverage
  method's signatures are cached on disk after their first run; the best of the repeats is the
  cached figure).

Every burst is drawn from a new seed; each timing is the best of ``--repeat`` runs.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from pathlib import Path

import numpy as np

from burstloc.experiments.position import NetworkDistance, PipePoint, estimated_point
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.evidence import BurstEvidence, MeterAlarm
from burstloc.network import load_network
from burstloc.sim.model.prepare import arrival_localizer
from burstloc.sim.placement.methods import PLACEMENT_METHODS, place_meters

REPO = Path(__file__).resolve().parents[1]
NETWORKS = [REPO / "networks" / "paper15.inp", REPO / "networks" / "awumah11.inp"]


def ideal_bursts(
    loc: ArrivalLocalizer, distance: NetworkDistance, count: int, dt: float, seed: int
) -> list[tuple[PipePoint, BurstEvidence]]:
    """``count`` bursts at random points of random pipes; alarms at the tick before the wave."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        geo = loc.pipes[int(rng.integers(len(loc.pipes)))]
        truth = PipePoint(geo.pipe, geo.start, float(rng.uniform(0.0, geo.length)))
        t0 = 10.0 + float(rng.uniform(0.0, dt))
        alarms = {}
        for m in loc.meters:
            arrive = t0 + distance.to_node(truth, m) / loc.wave_speed
            alarms[m] = MeterAlarm(m, math.floor(arrive / dt - 1e-9) * dt, -1.0)
        times = np.arange(0.0, 14.0, dt)
        out.append(
            (
                truth,
                BurstEvidence(
                    meters=loc.meters,
                    times=times,
                    readings=np.zeros((times.size, len(loc.meters))),
                    onset=min(a.start for a in alarms.values()),
                    capture_interval=dt,
                    alarms=alarms,
                ),
            )
        )
    return out


def best_of(repeat: int, work: object) -> float:
    """Best wall time (s) of ``repeat`` calls of ``work(run)``."""
    times = []
    for run in range(repeat):
        start = time.perf_counter()
        work(run)  # type: ignore[operator]
        times.append(time.perf_counter() - start)
    return min(times)


def bench_network(network: Path, bursts: int, repeat: int) -> None:
    wn = load_network(network)
    loc = arrival_localizer(wn)
    distance = NetworkDistance(wn)
    print(f"\n{network.name}: {len(loc.meters)} junctions metered, {len(loc.pipes)} pipes")
    seed = int.from_bytes(os.urandom(4), "little")
    for dt in (0.01, 0.2):
        errors, rank_s, position_s, named = [], [], [], 0
        for k in range(repeat):
            cases = ideal_bursts(loc, distance, bursts, dt, seed + 1000 * k + int(dt * 100))
            start = time.perf_counter()
            rankings = [loc.rank(e) for _, e in cases]
            rank_s.append((time.perf_counter() - start) / bursts)
            start = time.perf_counter()
            positions = [
                loc.position(e, r.best.pipe)  # type: ignore[union-attr]
                for (_, e), r in zip(cases, rankings, strict=True)
            ]
            position_s.append((time.perf_counter() - start) / bursts)
            for (truth, _), at in zip(cases, positions, strict=True):
                errors.append(distance.between(truth, estimated_point(at)))
                named += at.pipe == truth.pipe
        e = np.array(errors)
        print(
            f"  {dt:g} s: rank {1e3 * min(rank_s):.2f} ms, position {1e3 * min(position_s):.2f} "
            f"ms per burst (x{min(position_s) / min(rank_s):.2f} of rank); ideal alarms: pipe "
            f"{100 * named / e.size:.0f} %, position error mean {e.mean():.0f} m, p90 "
            f"{np.percentile(e, 90):.0f} m over {e.size} bursts"
        )
    count = max(2, round(len(loc.meters) / 4))
    for method in PLACEMENT_METHODS:
        seconds = best_of(repeat, lambda _, m=method: place_meters(network, count, method=m))
        meters = place_meters(network, count, method=method).meters
        print(f"  place {count} meters, {method}: {seconds:.2f} s -> {' '.join(meters)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("networks", nargs="*", type=Path, default=NETWORKS)
    parser.add_argument("--bursts", type=int, default=200, help="bursts per run")
    parser.add_argument("--repeat", type=int, default=3, help="runs (fresh seeds)")
    args = parser.parse_args()
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    for network in args.networks:
        bench_network(network, args.bursts, args.repeat)
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
