"""Meters added to the ones a utility owns: the measured gain of `burstloc place --keep`.

Usage: ``.venv/bin/python benches/bench_place_keep.py [NETWORK.inp --keep IDS|FILE] [--add K]
[--sample N] [--workers N]``. Default: L-TOWN (extracted from the pinned epyt wheel into a
temporary directory, never into the repository) with BattLeDIM's 33 pressure sensors owned, 10
added, 100 seeded pipes burst (seed 2027, as ``bench_regions.py --sample``; ``--bursts M``: the
first M of them by name, so that a shorter run reuses a longer one's cached simulations). Meter
sets, each placed and evaluated in this run:

* ``owned``: the owned meters alone (what the utility has today);
* ``+K region``: ``burstloc place --keep OWNED --meters K`` (the ``region`` method, the default
  with ``--keep``);
* ``+K arrival``: the same with ``--method arrival``;
* ``+K random``: K junctions drawn at random (seed 0) among the unowned ones.

Each is scored by the placement's model measure (the expected ambiguous main, m: what
``region`` minimises) and measured by ``burstloc evaluate NET --detector cusum
--capture-interval 0.2 --localizer fused --meters-file F --pipes (sample)`` (mid-pipe bursts, 5
clock phases, calibrated for those meters, the calibrated noise; simulations cached; L-TOWN on
its 30 m transient-ready model): top-1, the named point within 300 m, the 95 % region's coverage
and median length. Printed with the ratios of each set's median region to the owned set's and
to the random addition's.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import random
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "benches"))

from bench_regions import _run, sample_pipes  # noqa: E402
from bench_scale import BATTLEDIM_SENSORS, ltown  # noqa: E402


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.0f} %"


def main() -> None:
    """Place, score, evaluate and print every set."""
    from burstloc.network import load_network
    from burstloc.sim.placement.methods import MeterSet, meter_list, place_meters, score_meters

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("network", nargs="?", type=Path)
    parser.add_argument("--keep", nargs="+", default=None, metavar="IDS|FILE")
    parser.add_argument("--add", type=int, default=10, metavar="K")
    parser.add_argument("--sample", type=int, default=100, metavar="N")
    parser.add_argument(
        "--bursts",
        type=int,
        default=None,
        metavar="M",
        help="burst the first M pipes (by name) of the sample only (default: all of it)",
    )
    parser.add_argument("--workers", type=int)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-place-keep-") as tmp:
        if args.network is None:
            network = ltown(Path(tmp))
            if network is None:
                raise SystemExit("no epyt wheel in networks/public/: give NETWORK.inp --keep")
            owned = tuple(BATTLEDIM_SENSORS)
        else:
            network = args.network
            if args.keep is None:
                raise SystemExit("give the owned meters with --keep IDS|FILE")
            owned = meter_list(args.keep, network)
        bursts = sample_pipes(network, args.sample)[: args.bursts]
        wn = load_network(network)
        junctions = list(wn.junction_name_list)
        main_m = sum(wn.get_link(p).length for p in wn.pipe_name_list)
        order = {j: i for i, j in enumerate(junctions)}
        unowned = sorted(set(junctions) - set(owned), key=order.__getitem__)
        drawn = random.Random(0).sample(unowned, args.add)
        sets: list[tuple[str, tuple[str, ...], float]] = [(f"owned {len(owned)}", owned, 0.0)]
        for method in ("region", "arrival"):
            cpu = time.process_time()
            placed = place_meters(network, args.add, method=method, keep=owned).meters
            sets.append((f"+{args.add} {method}", placed, time.process_time() - cpu))
        with_random = tuple(sorted((*owned, *drawn), key=order.__getitem__))
        sets.append((f"+{args.add} random", with_random, 0.0))
        print(
            f"{network.name}: {len(junctions)} junctions, {main_m / 1000:.1f} km of main, "
            f"{len(owned)} owned meters, {len(bursts)} seeded pipes x 5 phases"
        )
        rows = []
        for label, meters, cpu in sets:
            path = Path(tmp) / f"{label.replace(' ', '-')}.json"
            MeterSet(str(network), _hash(network), "manual", meters, len(junctions)).save(path)
            model = score_meters(network, meters).ambiguous
            wall = time.perf_counter()
            with contextlib.redirect_stdout(io.StringIO()):  # evaluate's own tables
                run = _run(network, path, Path(tmp) / "out.json", args.workers, None, bursts)
            wall = time.perf_counter() - wall
            level = run["region"]["levels"][2]
            rows.append((label, meters, cpu, model, run, level, wall))
            print(f"  {label}: evaluated in {wall:.0f} s", flush=True)
        base = rows[0][5]["median_length_m"]
        rand = rows[-1][5]["median_length_m"]
        print(
            "| set | meters | place CPU | ambiguous main (model) | top-1 | within 300 m | "
            "95 % coverage | 95 % median | x owned | x random |"
        )
        print("|---|---|---|---|---|---|---|---|---|---|")
        for label, meters, cpu, model, run, level, _ in rows:
            median = level["median_length_m"]
            print(
                f"| {label} | {len(meters)} | {cpu:.1f} s | {model:.0f} m | {_pct(run['top1'])} | "
                f"{_pct(run['region']['within_m']['300'])} | {_pct(level['coverage'])} | "
                f"{median:.0f} m | x{median / base:.2f} | x{median / rand:.2f} |"
            )
        for label, meters, *_ in rows[1:3]:
            added = [m for m in meters if m not in set(owned)]
            print(f"{label} added: {' '.join(added)}")
        print(f"random added: {' '.join(sorted(drawn, key=order.__getitem__))}")


def _hash(network: Path) -> str:
    from burstloc.inp import network_hash

    return network_hash(network)


if __name__ == "__main__":
    main()
