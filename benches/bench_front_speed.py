"""L-TOWN with BattLeDIM's 33 sensors: paths timed at the speed the fronts are heard at, against
the wave speed, on the same bursts.

Usage: ``.venv/bin/python benches/bench_front_speed.py [--pipes N] [--seed S] [--phases K]
[--intervals S ...] [--front-bursts B] [--front-seed F] [--workers W] [--burst-flow Q]``.
L-TOWN comes from the pinned epyt wheel ``make networks`` keeps (as in ``bench_ltown.py``).
Two configurations of the 33 sensors (sigma 0.01 m) are calibrated in this run: one timing paths
at the wave speed (1 200 m/s), one with ``calibrate --front-bursts B`` (the speed and scatter of
the fronts the meters hear, fitted per capture interval on ``B`` bursts simulated on pipes drawn
with ``--front-seed``). ``N`` other pipes drawn with ``--seed`` (default 40, seed 13: pipes the
fit did not see) burst with ``Q`` L/s (default 2.04) on the transient-ready model (24 m); both
configurations evaluate the same readings with the fused localizer. Per capture interval and
configuration: the first record (time, share inside its 95 % region, within 100 / 300 m, mean
distance) and the answer (the same); then the ratios of the fronts' configuration to the wave's.
Takes about 12 min at the defaults on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from bench_ltown import sensors_and_pipes
from bench_ltown_accuracy import _metres, _percent, _seconds, burstloc, rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pipes", type=int, default=40, help="pipes drawn (default 40)")
    parser.add_argument("--seed", type=int, default=13, help="sample seed (default 13)")
    parser.add_argument("--phases", type=int, default=1, help="clock phases (default 1)")
    parser.add_argument("--intervals", type=float, nargs="+", default=[0.05, 0.2])
    parser.add_argument("--front-bursts", type=int, default=24, help="default 24")
    parser.add_argument("--front-seed", type=int, default=1, help="default 1")
    parser.add_argument("--workers", type=int, default=2, help="evaluate's workers (default 2)")
    parser.add_argument("--burst-flow", type=float, default=2.04, help="L/s (default 2.04)")
    args = parser.parse_args()
    intervals = [f"{s:g}" for s in args.intervals]
    burst = ("--burst-flow", f"{args.burst_flow:g}", "--min-pipe-length", "24")
    tables = {}
    with tempfile.TemporaryDirectory(prefix="bench-front-speed-") as tmp:
        directory = Path(tmp)
        network, meters, names = sensors_and_pipes(directory, args.seed)
        chosen = names[: args.pipes]
        calibrate = [
            *("calibrate", str(network), "--meters-file", str(meters), "--noise", "0.01"),
            *("--capture-interval", *intervals),
        ]
        fronts = [
            *("--front-bursts", str(args.front_bursts), "--front-seed", str(args.front_seed)),
            *burst,
            *("--workers", str(args.workers)),
        ]
        for label, extra in (("wave", []), ("fronts", fronts)):
            config = directory / f"{label}.npz"
            began = time.perf_counter()
            burstloc([*calibrate, "--out", str(config), *extra])
            print(f"calibrated ({label}) in {time.perf_counter() - began:.0f} s", flush=True)
            out = directory / f"{label}.json"
            burstloc(
                [
                    *("evaluate", str(network), "--config", str(config)),
                    *("--meters-file", str(meters), "--localizer", "fused"),
                    *("--capture-interval", *intervals, "--phases", str(args.phases)),
                    *("--workers", str(args.workers), "--quiet", "--no-cache"),
                    *("--json", str(out), "--pipes", *chosen, *burst),
                ]
            )
            tables[label] = {r["interval"]: r for r in rows(json.loads(out.read_text()))}
    print(
        f"\nL-TOWN, BattLeDIM's 33 sensors: {len(chosen)} pipes (seed {args.seed}) x "
        f"{args.phases} phase(s), fused, sigma 0.01 m, {args.burst_flow:g} L/s; fronts fitted "
        f"on {args.front_bursts} other bursts (seed {args.front_seed})"
    )
    print(
        "capture  paths at  | first: time  95% held  <=100m  <=300m   mean "
        "| answer: time  95% held  <=300m   mean"
    )
    for interval in sorted(tables["wave"]):
        for label in ("wave", "fronts"):
            r = tables[label][interval]
            print(
                f"{interval:6g} s  {label:<8}  | {_seconds(r['first_time'])}     "
                f"{_percent(r['first_held'])}    {_percent(r['first_100'])}    "
                f"{_percent(r['first_300'])}  {_metres(r['first_mean'])} | "
                f"{_seconds(r['time'])}     {_percent(r['held'])}    "
                f"{_percent(r['within_300'])}  {_metres(r['mean'])}"
            )
    for interval in sorted(tables["wave"]):
        wave, front = tables["wave"][interval], tables["fronts"][interval]
        if wave["first_mean"] and front["first_mean"] and wave["first_held"]:
            print(
                f"{interval:g} s: fronts / wave, first record: mean distance "
                f"{front['first_mean'] / wave['first_mean']:.2f}x, 95 % held "
                f"{(front['first_held'] or 0) / wave['first_held']:.2f}x"
            )


if __name__ == "__main__":
    main()
