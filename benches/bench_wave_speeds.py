"""L-TOWN with mains of two materials: what knowing each pipe's wave speed is worth.

Usage: ``.venv/bin/python benches/bench_wave_speeds.py [--pipes N] [--seed S] [--phases K]
[--intervals S ...] [--share F] [--slow A] [--workers W]``. L-TOWN (from the pinned epyt wheel
``make networks`` keeps) with BattLeDIM's 33 sensors; each pipe of 100 mm or less is drawn a
plastic main (``--slow`` m/s, default 400) with probability ``--share`` (default 0.5; seed 1),
the rest run at 1 200 m/s: the truth every burst is simulated on (``burstloc evaluate
--wave-speeds``). ``N`` pipes drawn with ``--seed`` (default 20, seed 11), ``K`` clock phases,
noise 0.01 m, bursts of 2.04 L/s, transient-ready pipes of at least 24 m, at 100 and 20 Hz.

Two calibrations of the same sensors are evaluated on the same simulated bursts: one told the
pipes' speeds (``burstloc calibrate --wave-speeds``), one that assumes 1 200 m/s everywhere (the
alternative, measured in the same run). The table gives, per capture interval and calibration,
the fused localizer's first record (as ``bench_ltown_accuracy.py``) and the answer; the last
lines compare told and assumed, for the first record and for the answer: the ratio of the mean
distances and the shares of bursts inside the 95 % region.
"""

from __future__ import annotations

import argparse
import json
import random
import sys
import tempfile
from pathlib import Path

from bench_ltown import meter_file, pipe_names
from bench_ltown_accuracy import _metres, _percent, _seconds, burstloc, rows
from bench_scale import ltown


def materials(network: Path, share: float, slow: float, out: Path) -> int:
    """Write the wave-speeds file (pipes of at most 100 mm drawn plastic with ``share``);
    the number of plastic pipes."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
    from burstloc.network import load_network

    wn = load_network(network)
    rng = random.Random(1)
    chosen = [
        p for p in wn.pipe_name_list if wn.get_link(p).diameter <= 0.1001 and rng.random() < share
    ]
    out.write_text("pipe,wave_speed\n" + "".join(f"{p},{slow:g}\n" for p in chosen))
    return len(chosen)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pipes", type=int, default=20, help="pipes drawn (default 20)")
    parser.add_argument("--seed", type=int, default=11, help="sample seed (default 11)")
    parser.add_argument("--phases", type=int, default=1, help="clock phases (default 1)")
    parser.add_argument("--intervals", type=float, nargs="+", default=[0.01, 0.05])
    parser.add_argument("--share", type=float, default=0.5, help="plastic share of small mains")
    parser.add_argument("--slow", type=float, default=400.0, help="plastic mains' speed, m/s")
    parser.add_argument("--workers", type=int, default=2, help="evaluate's workers (default 2)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-wave-speeds-") as tmp:
        directory = Path(tmp)
        network = ltown(directory)
        if network is None:
            sys.exit("L-TOWN is missing: run `make networks` (it keeps the epyt wheel)")
        meters = meter_file(network, directory)
        speeds = directory / "materials.csv"
        plastic = materials(network, args.share, args.slow, speeds)
        names = pipe_names(network)
        random.Random(args.seed).shuffle(names)
        chosen = names[: args.pipes]
        intervals = [f"{s:g}" for s in args.intervals]
        tables = {}
        for name, told in (("told", True), ("assumed", False)):
            config = directory / f"{name}.npz"
            burstloc(
                [
                    *("calibrate", str(network), "--out", str(config)),
                    *("--meters-file", str(meters), "--capture-interval", *intervals),
                    *(("--wave-speeds", str(speeds)) if told else ()),
                ]
            )
            out = directory / f"{name}.json"
            burstloc(
                [
                    *("evaluate", str(network), "--config", str(config)),
                    *("--meters-file", str(meters), "--wave-speeds", str(speeds)),
                    *("--localizer", "fused", "--detector", "cusum", "--burst-flow", "2.04"),
                    *("--capture-interval", *intervals, "--phases", str(args.phases)),
                    *("--min-pipe-length", "24", "--workers", str(args.workers)),
                    *("--quiet", "--json", str(out), "--pipes", *chosen),
                ]
            )
            tables[name] = {r["interval"]: r for r in rows(json.loads(out.read_text()))}
    print(
        f"\nL-TOWN, BattLeDIM's 33 sensors, {plastic} plastic pipes at {args.slow:g} m/s, the "
        f"rest at 1200 m/s: {len(chosen)} pipes (seed {args.seed}) x {args.phases} phase(s), "
        "CUSUM, sigma 0.01 m, 2.04 L/s"
    )
    print(
        "capture  model    | first: time  95% held  <=100m  <=300m   mean "
        "| answer: time  95% held  region   mean"
    )
    for interval in sorted(tables["told"]):
        for name in ("told", "assumed"):
            r = tables[name][interval]
            print(
                f"{interval:6g} s  {name:<7}  | {_seconds(r['first_time'])}     "
                f"{_percent(r['first_held'])}    {_percent(r['first_100'])}    "
                f"{_percent(r['first_300'])}  {_metres(r['first_mean'])} | "
                f"{_seconds(r['time'])}     {_percent(r['held'])}  {_metres(r['length'])}  "
                f"{_metres(r['mean'])}"
            )
    for interval in sorted(tables["told"]):
        told, assumed = tables["told"][interval], tables["assumed"][interval]
        for what, mean, held in (
            ("first record", "first_mean", "first_held"),
            ("answer", "mean", "held"),
        ):
            if told[mean] and assumed[mean]:
                print(
                    f"{interval:g} s, {what}: told / assumed: mean distance "
                    f"{told[mean] / assumed[mean]:.2f}x, 95 % region held "
                    f"{told[held] or 0:.2f} / {assumed[held] or 0:.2f}"
                )


if __name__ == "__main__":
    main()
