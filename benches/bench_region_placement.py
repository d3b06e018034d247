"""Meter placement for search regions: the three methods of `burstloc place` side by side.

Usage: ``.venv/bin/python benches/bench_region_placement.py [--public DIR] [--no-evaluate]
[--workers N] [--networks NAME ...]``. Networks: paper15 and the public networks of ``make
networks`` (Net1, Net2, Anytown, Net3 in ``networks/public/``, or ``--public``) with 10 % and
30 % of their junctions metered (at least 2), and L-TOWN (extracted from the pinned epyt wheel
into a temporary directory, never into the repository) with 33 meters, placement only and
without ``coverage`` (its greedy had not finished after 10 minutes there). Per network, meter
count and method (``coverage``, ``arrival``, ``region``):

* the placement's CPU time (in this process, the network's geometry included);
* the *expected ambiguous main* (:func:`burstloc.sim.placement.region.ambiguous_length`, m):
  the objective the ``region`` method minimises, on its own burst sample (seed 0) and, where
  the network has more points than :data:`~burstloc.sim.placement.region.BURST_SAMPLES`, on a
  fresh one (seed 1): the region method is fitted to the first;
* unless ``--no-evaluate`` (and not on L-TOWN): the measured search regions of ``burstloc
  evaluate NET --detector cusum --capture-interval 0.2 --localizer fused --meters-file F`` (every
  pipe bursts; simulations cached in the default cache directory; Net3 on its transient-ready
  model, ``--min-pipe-length 30``, as docs/results.md evaluates it, and its simulations still
  take many minutes the first time): the 95 % region's coverage and median length, and the
  share of named points within 300 m. The same meters are evaluated once.

On L-TOWN, BattLeDIM's 33 pressure sensors are scored too. Ratios: each method's ambiguous main
over the region method's, in the same run.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "benches"))

from bench_scale import BATTLEDIM_SENSORS, ltown  # noqa: E402

METHODS = ("coverage", "arrival", "region")
FRACTIONS = (0.1, 0.3)


def _objective(network: str, meters: tuple[str, ...], seed: int) -> float:
    """The expected ambiguous main of ``meters`` on burst sample ``seed`` (NaN for another seed
    where every point bursts)."""
    from burstloc.sim.model.prepare import arrival_geometry
    from burstloc.sim.placement.region import ambiguity_grid, ambiguous_length

    pipes, distances = arrival_geometry(network, list(meters))
    if seed != 0:
        grid = ambiguity_grid(pipes, meters, distances)
        if grid.bursts.size == grid.length.size:
            return float("nan")  # every point bursts: no other sample
    return ambiguous_length(pipes, meters, distances, seed=seed)


def _evaluate(network: str, meters: tuple[str, ...], workers: int) -> dict[str, Any]:
    """``burstloc evaluate`` of ``meters``: its 95 % region scores."""
    from burstloc.sim.placement.methods import MeterSet

    with tempfile.TemporaryDirectory(prefix="bench-region-") as tmp:
        placed = MeterSet(network, _hash(network), "manual", meters, _junctions(network))
        meters_file = placed.save(Path(tmp) / "meters.json")
        out = Path(tmp) / "out.json"
        command = [sys.executable, "-m", "burstloc", "evaluate", network, "--detector", "cusum"]
        command += ["--capture-interval", "0.2", "--localizer", "fused", "--quiet"]
        command += ["--meters-file", str(meters_file), "--json", str(out)]
        command += ["--burst-coeff", "0.02"]  # the paper's burst, as its tables were measured
        command += ["--workers", str(workers)]
        if Path(network).name == "Net3.inp":  # its transient-ready model (docs/results.md)
            command += ["--min-pipe-length", "30"]
        env = dict(os.environ, PYTHONPATH=str(REPO / "python"))
        subprocess.run(
            ["nice", "-n", "10", *command], check=True, env=env, stdout=subprocess.DEVNULL
        )
        region = json.loads(out.read_text())["runs"][0]["region"]
    level = region["levels"][-1]
    return {
        "coverage": level["coverage"],
        "median": level["median_length_m"],
        "within300": region["within_m"]["300"],
    }


def _hash(network: str) -> str:
    from burstloc.inp import network_hash

    return network_hash(network)


def _junctions(network: str) -> int:
    from burstloc.network import load_network

    return load_network(network).num_junctions


def _main_length(network: str) -> float:
    from burstloc.network import load_network

    wn = load_network(network)
    return float(sum(wn.get_link(p).length for p in wn.pipe_name_list))


def _percent(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.0f} %"


def bench(
    network: Path,
    counts: list[int],
    evaluate: bool,
    workers: int,
    methods: tuple[str, ...] = METHODS,
) -> None:
    from burstloc.sim.placement.methods import place_meters

    name = str(network)
    main = _main_length(name)
    print(f"\n{network.name}: {_junctions(name)} junctions, {main / 1000:.1f} km of main")
    print(
        "| meters | method | place CPU | ambiguous main (seed 0 / fresh) | x region "
        "| 95 % coverage | 95 % median | within 300 m | meters |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    scored: dict[tuple[str, ...], dict[str, Any]] = {}
    for count in counts:
        rows = []
        for method in methods:
            cpu = time.process_time()
            meters = place_meters(name, count, method=method).meters
            cpu = time.process_time() - cpu
            rows.append((method, cpu, meters, _objective(name, meters, 0)))
        if network.name == "L-TOWN.inp" and count == len(BATTLEDIM_SENSORS):
            rows.append(("BattLeDIM", float("nan"), tuple(BATTLEDIM_SENSORS), 0.0))
            rows[-1] = (*rows[-1][:3], _objective(name, tuple(BATTLEDIM_SENSORS), 0))
        best = next(r[3] for r in rows if r[0] == "region")
        for method, cpu, meters, objective in rows:
            fresh = _objective(name, meters, 1)
            scores: dict[str, Any] = {}
            if evaluate:
                if meters not in scored:
                    scored[meters] = _evaluate(name, meters, workers)
                scores = scored[meters]
            median = scores.get("median")
            shown = " ".join(meters) if len(meters) <= 12 else f"{' '.join(meters[:12])} ..."
            fresh_cell = "" if fresh != fresh else f" / {fresh:.0f}"
            cpu_cell = "-" if cpu != cpu else f"{cpu:.1f} s"
            print(
                f"| {count} | {method} | {cpu_cell} | {objective:.0f}{fresh_cell} m "
                f"| x{objective / best:.2f} | {_percent(scores.get('coverage'))} "
                f"| {'-' if median is None else f'{median:.0f} m'} "
                f"| {_percent(scores.get('within300'))} | {shown} |",
                flush=True,
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--public", type=Path, default=REPO / "networks" / "public")
    parser.add_argument("--no-evaluate", action="store_true", help="placements only")
    parser.add_argument("--workers", type=int, default=1, help="evaluate's worker processes")
    parser.add_argument(
        "--networks",
        nargs="*",
        default=["paper15", "Net1", "Net2", "Anytown", "Net3", "L-TOWN"],
        help="which of the default networks",
    )
    args = parser.parse_args()
    import burstloc.sim.placement.methods  # noqa: F401  (imports before the clocks start)

    with tempfile.TemporaryDirectory(prefix="bench-region-nets-") as tmp:
        for which in args.networks:
            if which == "L-TOWN":
                found = ltown(Path(tmp))
                if found is None:
                    print("\n(L-TOWN: run `make networks` for the epyt wheel)")
                    continue
                print("\n(L-TOWN: coverage left out, its greedy had not finished in 10 minutes)")
                counts = [len(BATTLEDIM_SENSORS)]
                bench(found, counts, False, args.workers, ("arrival", "region"))
                continue
            path = REPO / "networks" / "paper15.inp"
            if which != "paper15":
                path = args.public / f"{which}.inp"
            if not path.is_file():
                print(f"\n({which}: run `make networks`)")
                continue
            junctions = _junctions(str(path))
            counts = sorted({max(2, round(f * junctions)) for f in FRACTIONS})
            bench(path, counts, evaluate=not args.no_evaluate, workers=args.workers)


if __name__ == "__main__":
    main()
