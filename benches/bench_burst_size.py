"""Burst sizes: the flow of the default burst, and the pressures a burst leaves, per network.

Usage: ``.venv/bin/python benches/bench_burst_size.py [NETWORK.inp ...] [--flows 5 10 20]
[--coefficients 0.02 ...] [--transient N|all] [--duration S] [--workers W] [--ltown]``. Default
networks: the committed paper15,
paper15_assets, awumah11 and EPANET's Net1, Net2, Anytown, Net3 (``networks/public/``); ``--ltown``
adds L-TOWN (extracted from the pinned epyt wheel into a temporary directory). Every pipe bursts at
mid-pipe, sized by each of ``--coefficients`` (default: the paper's, 0.02 m³/s/m^½; none with
``--coefficients`` alone) and by each of ``--flows`` (L/s, the coefficient that draws it at the
burst point's pressure before it opens: ``burstloc simulate --burst-flow``). Printed per network
and size: the bursts' nominal flow (median and largest, L/s, and as a share of the network's
demand), the lowest junction pressure of EPANET's pressure-driven steady state once the burst has
opened (over every pipe), and the bursts that take a junction below zero there.

The steady state cannot show what the opening does: an emitter draws less as its pressure
falls, so the steady state holds the pressures near zero, while the downsurge of a burst that
opens in 0.3 s takes junctions far below it. ``--transient N`` (or ``all``) also simulates N seeded
pipes per
network and size (``burstloc simulate``'s model, ``--duration`` 30 s by default, the transient-ready
model with 30 m pipes
on Net3 and L-TOWN, not cached) and prints the lowest junction pressure over the whole transient and
the three pipes whose bursts go lowest and the junctions the solver reports below zero.
"""

from __future__ import annotations

import argparse
import random
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "benches"))

from bench_scale import ltown  # noqa: E402

NETWORKS = [
    REPO / "networks" / name for name in ("paper15.inp", "paper15_assets.inp", "awumah11.inp")
] + [REPO / "networks" / "public" / f"{n}.inp" for n in ("Net1", "Net2", "Anytown", "Net3")]
TRANSIENT_READY = {"Net3.inp": 30.0, "L-TOWN.inp": 30.0}
DEFAULT_COEFF = 0.02


def _transient(
    network: Path,
    pipes: list[str],
    coeff: float | None,
    flow: float | None,
    duration: float,
    workers: int,
) -> str:
    """The lowest junction pressure head over the transients of ``pipes`` once their bursts
    start, the pipes whose burst takes the network lowest, and the most junctions a burst takes
    below zero (the solver's report)."""
    from burstloc.sim.scenarios.scenario import burst_scenarios
    from burstloc.sim.signatures.burst_size import sized_scenarios
    from burstloc.sim.transient.tsnet import simulate_many

    scenarios = burst_scenarios(
        network,
        pipes,
        duration=duration,
        burst_coeff=coeff or DEFAULT_COEFF,
        opening_time=0.3,
        min_pipe_length=TRANSIENT_READY.get(network.name),
    )
    scenarios, _ = sized_scenarios(scenarios, flow)
    lows: dict[str, float] = {}
    below = [0]
    failures: list[str] = []
    for first in range(0, len(scenarios), 16):  # a few at a time: only their lowest kept
        chunk = scenarios[first : first + 16]
        report = simulate_many(chunk, cache=False, progress=False, workers=workers)
        for _, result in report.succeeded():  # pressure heads, after the burst starts
            after = result.time >= result.metadata["burst_start"]
            lows[result.pipe] = float(result.heads[after].min())
            below.append(len(result.metadata.get("negative_pressure_nodes") or []))
        failures += report.failure_lines()
    worst = sorted(lows, key=lows.__getitem__)[:3]
    failed = len(pipes) - len(lows)
    return (
        f"{len(lows)} transients ({duration:g} s{f', {failed} failed' if failed else ''}): "
        f"lowest {lows[worst[0]]:.1f} m ("
        + ", ".join(f"{p} {lows[p]:.1f} m" for p in worst)
        + f"), below zero at up to {max(below)} junctions"
        + "".join(f"\n    {line}" for line in failures)
    )


def main() -> None:
    """Size, solve and print every network."""
    from burstloc.network import load_network, steady_state
    from burstloc.sim.signatures.burst_size import burst_sizes

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("networks", nargs="*", type=Path)
    parser.add_argument("--flows", type=float, nargs="+", default=[5.0, 10.0, 20.0, 50.0])
    parser.add_argument(
        "--coefficients", type=float, nargs="*", default=[DEFAULT_COEFF], metavar="C"
    )
    parser.add_argument(
        "--transient", default="0", metavar="N|all", help="pipes simulated per network and size"
    )
    parser.add_argument("--duration", type=float, default=30.0, help="each transient, s")
    parser.add_argument("--workers", type=int, default=1, help="simulations at once")
    parser.add_argument("--ltown", action="store_true")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-burst-size-") as tmp:
        networks = list(args.networks or NETWORKS)
        if args.ltown:
            found = ltown(Path(tmp))
            if found is not None:
                networks.append(found)
        for network in networks:
            wn = load_network(network)
            state = steady_state(wn)
            demand = sum(q for q in state.demands.values() if q > 0)
            pressure = min(state.heads[j] - wn.get_node(j).elevation for j in wn.junction_name_list)
            pipes = list(wn.pipe_name_list)
            print(
                f"{network.name}: {len(pipes)} pipes, {wn.num_junctions} junctions, demand "
                f"{1000 * demand:.1f} L/s, lowest pressure {pressure:.1f} m before any burst"
            )
            count = len(pipes) if args.transient == "all" else int(args.transient)
            sample = sorted(random.Random(0).sample(pipes, min(count, len(pipes))))
            sizes: list[tuple[str, float | None, float | None]] = [
                (f"coefficient {c:g}", c, None) for c in args.coefficients
            ]
            sizes += [(f"{q:g} L/s", None, q / 1000.0) for q in args.flows]
            for label, coeff, flow in sizes:
                began = time.perf_counter()
                found_sizes = burst_sizes(wn, pipes, 0.5, coeff=coeff, flow=flow, check=True)
                flows = np.array([s.flow_lps for s in found_sizes])
                lows = np.array([s.lowest_pressure for s in found_sizes], dtype=float)
                below = sum(1 for s in found_sizes if s.below_zero)
                line = (
                    f"  {label:>18}: {np.median(flows):6.1f} L/s median, {flows.max():6.1f} max "
                    f"(x{np.median(flows) / (1000 * demand):.2f} the demand); steady lowest "
                    f"{lows.min():6.1f} m, {below} of {len(pipes)} bursts below zero "
                    f"({time.perf_counter() - began:.0f} s)"
                )
                if sample:
                    line += "; " + _transient(
                        network, sample, coeff, flow, args.duration, args.workers
                    )
                print(line, flush=True)


if __name__ == "__main__":
    main()
