"""Do the simulated waves arrive when the arrival model says? L-TOWN's meters, burst by burst.

Usage: ``.venv/bin/python benches/bench_travel_times.py [--pipes N] [--seed S]
[--min-pipe-length M ...] [--threshold H] [--opening-time T]``. L-TOWN is extracted from the
pinned epyt wheel (``make networks``) into a temporary directory; BattLeDIM's 33 sensor
junctions are the meters.

For ``N`` pipes drawn with ``--seed`` (default 10, seed 11) a mid-pipe burst opening in ``T`` s
(default 0.3, the evaluation's) is simulated for 30 s on the transient-ready model of each
``--min-pipe-length`` (default 30 m, the evaluation's, and 15 m beside it: the alternative
measured in the same run; 0: the INP's own pipes, TSNet's step then fits L-TOWN's shortest pipe).
At each meter the *simulated first arrival* is the first instant after the burst opens at which
the pressure head has moved by more than 5 % of the largest change the burst makes there, and
at least ``H`` (default 1 cm: a model's heads drift by millimetres before the burst); the
*model's* arrival is the shortest path length along the INP's pipes from the burst point to the
meter over the wave speed (1 200 m/s), what the arrival localizer and the search regions assume.
The table gives, per minimum length, the difference (simulated minus model, seconds) over every
meter the wave reached: its mean, 90th percentile and largest, and the same as a share of the
model's travel time; then the same difference with the path measured on the simulated model's
lengths (its pipes shorter than the minimum lengthened to it): what is left is the front's own
delay (the burst's opening, a weak front crossing the level late, TSNet's wave-speed adjustment
to its step). A positive difference is a wave later than the model says.
"""

from __future__ import annotations

import argparse
import copy
import random
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from bench_ltown import pipe_names
from bench_scale import BATTLEDIM_SENSORS, ltown

FRONT_SHARE = 0.05
"""The first arrival at a meter: its head has moved by this share of the largest change the
burst makes there (or by the threshold, if more)."""


def lengthened_network(wn: Any, minimum: float) -> Any:
    """A copy of ``wn`` with the pipe lengths the simulation's transient-ready model gives them:
    each pipe shorter than ``minimum`` lengthened to it (every junction kept, as a simulation
    keeps them, so no pipe is merged)."""
    from burstloc.network import junction_names
    from burstloc.skeleton import prepare_transient_model

    prepared = prepare_transient_model(wn, minimum, keep=junction_names(wn))
    lengthened = copy.deepcopy(wn)
    for model_pipe, before in prepared.lengthened.items():
        for name in prepared.originals(model_pipe):
            lengthened.get_link(name).length *= minimum / before
    return lengthened


def differences(
    network: Path, pipes: list[str], minimum: float | None, threshold: float, opening: float
) -> np.ndarray:
    """``(simulated - model, simulated - model on the simulated lengths, model)`` arrival times
    (s) at the meters, one row per meter and burst."""
    from burstloc.constants import WAVE_SPEED
    from burstloc.experiments.position import NetworkDistance, true_point
    from burstloc.network import load_network
    from burstloc.sim.scenarios.scenario import BurstScenario
    from burstloc.sim.transient.tsnet import simulate_burst

    wn = load_network(network)
    distance = NetworkDistance(wn)
    simulated = distance if minimum is None else NetworkDistance(lengthened_network(wn, minimum))
    rows = []
    for pipe in pipes:
        scenario = BurstScenario(
            str(network), pipe, min_pipe_length=minimum, opening_time=opening, duration=30.0
        )
        result = simulate_burst(scenario)
        start = float(result.metadata["burst_start"])
        truth = true_point(result, wn)
        before = int(np.searchsorted(result.time, start)) - 1
        for meter in BATTLEDIM_SENSORS:
            column = result.junctions.index(meter)
            moved = np.abs(result.heads[:, column] - result.heads[max(before, 0), column])
            late = result.time > start
            # the front: a share of the largest change the burst makes at the meter, at least
            # the threshold (a model's drift before the burst moves heads by millimetres)
            level = max(threshold, FRONT_SHARE * float(moved[late].max(initial=0.0)))
            after = np.flatnonzero(late & (moved > level))
            if after.size == 0:
                continue
            model = distance.to_node(truth, meter) / WAVE_SPEED
            own = simulated.to_node(truth, meter) / WAVE_SPEED
            arrival = float(result.time[after[0]]) - start
            rows.append((arrival - model, arrival - own, model))
    return np.array(rows, dtype=np.float64)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pipes", type=int, default=10, help="pipes drawn (default 10)")
    parser.add_argument("--seed", type=int, default=11, help="sample seed (default 11)")
    parser.add_argument(
        "--min-pipe-length",
        type=float,
        nargs="+",
        default=[30.0, 15.0],
        help="transient-ready models' shortest pipe, m; 0: the INP's own pipes",
    )
    parser.add_argument("--threshold", type=float, default=0.01, help="head change, m")
    parser.add_argument("--opening-time", type=float, default=0.3, help="s (default 0.3)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-travel-times-") as tmp:
        network = ltown(Path(tmp))
        if network is None:
            sys.exit("L-TOWN is missing: run `make networks` (it keeps the epyt wheel)")
        names = pipe_names(network)
        random.Random(args.seed).shuffle(names)
        chosen = names[: args.pipes]
        print(
            f"L-TOWN: {len(chosen)} mid-pipe bursts (seed {args.seed}), BattLeDIM's 33 meters, "
            f"opened in {args.opening_time:g} s, front at {FRONT_SHARE:.0%} of the change and "
            f">= {args.threshold:g} m"
        )
        print(
            "min pipe   arrivals   late: mean     p90     max | relative: mean   p90    max "
            "| on the simulated lengths: mean     max"
        )
        means = {}
        for minimum in args.min_pipe_length:
            began = time.perf_counter()
            found = differences(network, chosen, minimum or None, args.threshold, args.opening_time)
            late, own, model = found[:, 0], found[:, 1], found[:, 2]
            relative = late / np.maximum(model, 1e-3)
            means[minimum] = float(np.mean(np.abs(late)))
            print(
                f"{minimum:6g} m   {late.size:8d}   {np.mean(late):9.3f} s "
                f"{np.percentile(late, 90):7.3f} s {np.max(np.abs(late)):7.3f} s | "
                f"{np.mean(relative):11.1%} {np.percentile(relative, 90):6.1%} "
                f"{np.max(np.abs(relative)):6.1%} | {np.mean(own):29.3f} s "
                f"{np.max(np.abs(own)):7.3f} s  ({time.perf_counter() - began:.0f} s)",
                flush=True,
            )
        first, *others = args.min_pipe_length
        for other in others:
            print(
                f"mean |late| at {other:g} m / at {first:g} m: "
                f"{means[other] / max(means[first], 1e-12):.2f}x"
            )


if __name__ == "__main__":
    main()
