"""Meter placement at utility scale: the exact greedy against the scaled one, and the scaled one
on BWSN_Network_2, in one run.

Usage: ``.venv/bin/python benches/bench_place_scale.py [--counts 33 100] [--methods arrival
region] [--no-bwsn2] [--no-ltown]``. L-TOWN (782 junctions, 905 pipes) and BWSN_Network_2
(12 523 junctions, 14 822 pipes) are extracted from the pinned epyt wheel of ``make networks``
into a temporary directory (never into the repository). Each placement runs in a fresh child
process (``bench_scale.measure``): wall and CPU time, peak resident memory. Its quality, for the
arrival and region objectives (lower is better for ``alike`` and ``ambiguous``):

* ``alike``: one minus the ``arrival`` method's objective (:func:`arrival_objective`): the
  share of pipe pairs' separation missing below one capture interval (0.2 s), over every pipe
  (L-TOWN) or a sample of :data:`SAMPLED_PIPES` (BWSN_Network_2: seed 1, not the sample the
  placement fitted);
* ``told``: the arrival separation (:func:`burstloc.sim.placement.methods.meter_separation`, the
share
  of candidate burst points at least one capture interval, 0.2 s, from every other pipe's;
  higher is better; 0 on L-TOWN, whose short pipes lie within 0.2 s of others);
* ``ambiguous``: the expected ambiguous main (:func:`burstloc.sim.placement.methods.
  meter_ambiguity`, m, on the whole network).

On L-TOWN, below the threshold, ``place_meters`` is the exact greedy; it is set beside the
scaled placement forced onto it with half its junctions as candidates (400), half its pipes
(450, ``arrival``) and half its grid points (1 000, ``region``): time, memory and quality
ratios, scaled over exact. On BWSN_Network_2 the exact greedy is out of reach (path lengths
from every pipe end to every junction, about 12 500^2 floats: 1.3 GB, by 12 523 Dijkstra runs;
travel times from 3 points on each pipe to every junction: 4.5 GB; its first step 10^9 pairs
of points), so the scaled placement (defaults) is set beside two placements that cost
nothing: the first K junctions of the farthest-point sampling (spread, no objective) and K
junctions drawn at random (seed 0).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "benches"))

from bench_scale import BWSN2_MEMBER, LTOWN_MEMBER, from_wheel, measure  # noqa: E402

HALF_LTOWN = {"above": 0, "candidates": 400, "pipes": 450, "points": 1000}
"""The scaled placement forced onto L-TOWN at half its size."""
SAMPLED_PIPES = 1500
"""Pipes of the arrival objective's sample on BWSN_Network_2 (seed 1)."""


def stage_place(network: str, count: int, method: str, scaling: dict[str, int] | None) -> Any:
    """``place_meters`` (child process): the meters."""
    import warnings

    from burstloc.sim.placement.methods import place_meters
    from burstloc.sim.placement.scaled import DEFAULT_SCALING, Scaling

    warnings.simplefilter("ignore")  # WNTR's unused-curve warning on BWSN2
    chosen = DEFAULT_SCALING if scaling is None else Scaling(**scaling)
    return place_meters(network, count, method=method, scaling=chosen).meters


def stage_baselines(network: str, count: int) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The first ``count`` junctions of the farthest-point sampling, and ``count`` at random."""
    import warnings

    import numpy as np

    from burstloc.network import load_network
    from burstloc.sim.placement.scaled import spread_junctions

    warnings.simplefilter("ignore")
    wn = load_network(network)
    junctions = list(wn.junction_name_list)
    spread = tuple(spread_junctions(wn, count)[0])
    drawn = np.sort(np.random.default_rng(0).choice(len(junctions), size=count, replace=False))
    return spread, tuple(junctions[i] for i in drawn)


def arrival_objective(network: str, meters: tuple[str, ...], pipes: int | None) -> float:
    """The ``arrival`` method's objective of ``meters`` as a share: the mean over pipe pairs of
    ``min(separation, 0.2 s) / 0.2 s`` (:mod:`burstloc.sim.placement.methods`; 1: every pair told
    apart), over every pipe (``pipes=None``) or a uniform sample of ``pipes`` (seed 1: not the
    sample the scaled placement fits, seed 0)."""
    import numpy as np

    from burstloc.constants import WAVE_SPEED
    from burstloc.sim.model.prepare import arrival_geometry
    from burstloc.sim.placement.arrival import ARRIVAL_POINTS, _travel

    resolution = 0.2
    geometry, distances = arrival_geometry(network, list(meters))
    if pipes is not None and pipes < len(geometry):
        keep = np.sort(np.random.default_rng(1).choice(len(geometry), size=pipes, replace=False))
        geometry = [geometry[i] for i in keep]
    travel = _travel(geometry, distances, ARRIVAL_POINTS, WAVE_SPEED)
    n, k = len(geometry), len(ARRIVAL_POINTS)
    a, b = np.triu_indices(travel.shape[0], k=1)
    other = a // k != b // k
    a, b = a[other], b[other]
    best = np.full(n * n, np.inf)
    step = max(1, 4_000_000 // travel.shape[1])
    for lo in range(0, a.size, step):
        ra, rb = a[lo : lo + step], b[lo : lo + step]
        np.minimum.at(best, (ra // k) * n + rb // k, (travel[ra] - travel[rb]).std(axis=1))
    per_pair = best[np.isfinite(best)]
    return float(np.minimum(per_pair, resolution).mean() / resolution)


def stage_quality(
    network: str, meters: tuple[str, ...], pipes: int | None = None
) -> tuple[float, float, float]:
    """(arrival objective, arrival separation, expected ambiguous main in m) of ``meters``:
    the objective over every pipe or a sample of ``pipes``, the others on the whole network."""
    import warnings

    from burstloc.sim.placement.methods import meter_ambiguity, meter_separation

    warnings.simplefilter("ignore")
    objective = arrival_objective(network, meters, pipes)
    return objective, meter_separation(network, meters), meter_ambiguity(network, meters)


def line(
    what: str, timed: tuple[float, float, float, Any] | None, quality: tuple[float, float, float]
) -> None:
    """One row: time and memory (when measured) and quality."""
    objective, told, ambiguous = quality
    cost = " " * 52
    if timed is not None:
        wall, cpu, peak, _ = timed
        cost = f"wall {wall:7.1f} s  cpu {cpu:7.1f} s  peak {peak:6.0f} MB  "
    print(
        f"  {what:<38} {cost}alike {1 - objective:.5f}  told {100 * told:4.1f} %  "
        f"ambiguous {ambiguous:6.0f} m"
    )


def ratio(a: float, b: float) -> str:
    return f"x{a / b:.2f}" if b else "n/a"


def bench_ltown(network: Path, counts: list[int], methods: list[str]) -> None:
    print(f"\n{network.name}: 782 junctions, 905 pipes (exact greedy below the threshold)")
    for count in counts:
        for method in methods:
            exact = measure(stage_place, str(network), count, method, None)
            scaled = measure(stage_place, str(network), count, method, HALF_LTOWN)
            q_exact = stage_quality(str(network), exact[3])
            q_scaled = stage_quality(str(network), scaled[3])
            print(f" {count} meters, {method}")
            line("exact", exact, q_exact)
            line("scaled (400 cand., half sampled)", scaled, q_scaled)
            print(
                f"  scaled / exact: cpu {ratio(scaled[1], exact[1])}, peak "
                f"{ratio(scaled[2], exact[2])}, alike {ratio(1 - q_scaled[0], 1 - q_exact[0])}, "
                f"ambiguous {ratio(q_scaled[2], q_exact[2])}; "
                f"{len(set(exact[3]) & set(scaled[3]))} of {count} meters shared"
            )


def bench_bwsn2(network: Path, counts: list[int], methods: list[str]) -> None:
    print(f"\n{network.name}: 12 523 junctions, 14 822 pipes (scaled: the exact is out of reach)")
    for count in counts:
        spread, drawn = measure(stage_baselines, str(network), count)[3]
        q_spread = stage_quality(str(network), spread, SAMPLED_PIPES)
        q_drawn = stage_quality(str(network), drawn, SAMPLED_PIPES)
        print(f" {count} meters")
        line("spread (farthest-point, no objective)", None, q_spread)
        line("random (seed 0)", None, q_drawn)
        for method in methods:
            scaled = measure(stage_place, str(network), count, method, None)
            q = stage_quality(str(network), scaled[3], SAMPLED_PIPES)
            line(f"scaled {method}", scaled, q)
            print(
                f"  scaled {method} / spread: alike {ratio(1 - q[0], 1 - q_spread[0])}, "
                f"ambiguous {ratio(q[2], q_spread[2])}; / random: alike "
                f"{ratio(1 - q[0], 1 - q_drawn[0])}, ambiguous {ratio(q[2], q_drawn[2])}"
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", type=int, nargs="+", default=[33])
    parser.add_argument("--methods", nargs="+", default=["arrival", "region"])
    parser.add_argument("--no-ltown", action="store_true")
    parser.add_argument("--no-bwsn2", action="store_true")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-place-scale-") as tmp:
        ltown = None if args.no_ltown else from_wheel(LTOWN_MEMBER, Path(tmp))
        bwsn2 = None if args.no_bwsn2 else from_wheel(BWSN2_MEMBER, Path(tmp))
        if (ltown is None and not args.no_ltown) or (bwsn2 is None and not args.no_bwsn2):
            print("(run `make networks` for the pinned epyt wheel)")
        if ltown is not None:
            bench_ltown(ltown, args.counts, args.methods)
        if bwsn2 is not None:
            bench_bwsn2(bwsn2, args.counts, args.methods)


if __name__ == "__main__":
    main()
