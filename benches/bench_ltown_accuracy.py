"""L-TOWN with BattLeDIM's 33 pressure sensors: how soon and how close the answer comes.

Usage: ``.venv/bin/python benches/bench_ltown_accuracy.py [--pipes N] [--seed S] [--phases K]
[--intervals S ...] [--workers W] [--min-pipe-length M] [--config PATH] [--burst-flow Q]``. L-TOWN
is extracted from the pinned epyt wheel that ``make networks`` keeps in ``networks/public/`` into a
temporary directory; BattLeDIM's 33 sensors are the meters. ``N`` pipes drawn with ``--seed``
(default 20 pipes, seed 11: not the seed the constants were looked at with), ``K`` clock phases
each, noise of 0.01 m (standard deviation), the CUSUM bank calibrated for those sensors
(``--config`` reuses a calibration made for them), the paper's burst (coefficient 0.02; with
``--burst-flow Q`` a burst of Q L/s, ``burstloc evaluate``'s default being 5), transient-ready
pipes of at least ``M`` m (default 30).

Every burst goes through ``burstloc evaluate`` once, with the fused localizer (the default) and
the arrival localizer beside it (the alternative measured in the same run, on the same
readings). Per capture interval and localizer, the table gives:

* the **first answer** (the first record with a search region: the fused localizer's early
  record, or its answer when it gives none): median seconds after the burst, the share of
  bursts inside its 95 % region, its named point within 100 / 300 m network distance, the
  mean distance;
* the **answer**: median seconds after the burst, the share inside its 95 % region, the
  region's median length, the named point within 300 m and the mean distance.

The last lines are ratios measured in this run: the fused localizer's first answer against its
answer, and against the arrival localizer's answer (mean distance; time).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from bench_ltown import sensors_and_pipes

REPO = Path(__file__).resolve().parents[1]


def burst_size(flow: float | None) -> tuple[str, str]:
    """The evaluation's burst: ``flow`` L/s, or the paper's coefficient."""
    return ("--burst-coeff", "0.02") if flow is None else ("--burst-flow", f"{flow:g}")


def burstloc(args: list[str]) -> None:
    """``burstloc ARGS`` with the sources in place; exits with its message on failure."""
    env = {**os.environ, "PYTHONPATH": str(REPO / "python")}
    done = subprocess.run([sys.executable, "-m", "burstloc", *args], env=env)
    if done.returncode != 0:
        sys.exit(f"burstloc {args[0]} failed (exit {done.returncode})")


def _percent(x: float | None) -> str:
    return "   -" if x is None else f"{100 * x:3.0f}%"


def _metres(x: float | None) -> str:
    return "     -" if x is None else f"{x:5.0f}m"


def _seconds(x: float | None) -> str:
    return "     -" if x is None else f"{x:5.1f}s"


def rows(doc: dict[str, Any]) -> list[dict[str, Any]]:
    """One summary per run of an evaluate JSON document."""
    out = []
    for run in doc["runs"]:
        region = run["region"] or {}
        first = region.get("first_answer") or {}
        levels = {lv["confidence"]: lv for lv in region.get("levels", [])}
        held = levels.get(0.95, {})
        out.append(
            {
                "interval": run["capture_interval"],
                "localizer": run["localizer"],
                "first_time": region.get("median_time_to_region_s"),
                "first_held": first.get("coverage_95"),
                "first_100": (first.get("within_m") or {}).get("100"),
                "first_300": (first.get("within_m") or {}).get("300"),
                "first_mean": first.get("mean_error_m"),
                "time": run["median_time_to_localize_s"],
                "held": held.get("coverage"),
                "length": held.get("median_length_m"),
                "within_300": (region.get("within_m") or {}).get("300"),
                "mean": run["position_error_m"]["mean"],
            }
        )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pipes", type=int, default=20, help="pipes drawn (default 20)")
    parser.add_argument("--seed", type=int, default=11, help="sample seed (default 11)")
    parser.add_argument("--phases", type=int, default=3, help="clock phases (default 3)")
    parser.add_argument("--intervals", type=float, nargs="+", default=[0.2, 0.05])
    parser.add_argument("--workers", type=int, default=2, help="evaluate's workers (default 2)")
    parser.add_argument("--min-pipe-length", type=float, default=30.0)
    parser.add_argument("--config", help="a calibration of L-TOWN for the 33 sensors")
    parser.add_argument(
        "--burst-flow", type=float, default=None, help="L/s (default: the paper's burst, 0.02)"
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-ltown-accuracy-") as tmp:
        directory = Path(tmp)
        network, meters, names = sensors_and_pipes(directory, args.seed)
        chosen = names[: args.pipes]
        intervals = [f"{s:g}" for s in args.intervals]
        config = args.config
        if config is None:
            config = str(directory / "ltown.npz")
            burstloc(
                [
                    *("calibrate", str(network), "--out", config),
                    *("--meters-file", str(meters), "--capture-interval", *intervals),
                ]
            )
        out = directory / "evaluate.json"
        burstloc(
            [
                *("evaluate", str(network), "--config", config, "--meters-file", str(meters)),
                *("--localizer", "fused", "arrival", "--detector", "cusum"),
                *("--capture-interval", *intervals, "--phases", str(args.phases)),
                *("--min-pipe-length", f"{args.min_pipe_length:g}"),
                *("--workers", str(args.workers), "--quiet", "--json", str(out)),
                *("--pipes", *chosen),
                *burst_size(args.burst_flow),
            ]
        )
        table = rows(json.loads(out.read_text()))
    print(
        f"\nL-TOWN, BattLeDIM's 33 sensors: {len(chosen)} pipes (seed {args.seed}) x "
        f"{args.phases} phases, CUSUM, sigma 0.01 m, burst {' '.join(burst_size(args.burst_flow))}"
    )
    print(
        "capture  localizer  | first: time  95% held  <=100m  <=300m   mean "
        "| answer: time  95% held  region  <=300m   mean"
    )
    for r in table:
        print(
            f"{r['interval']:6g} s  {r['localizer']:<9}  | {_seconds(r['first_time'])}"
            f"     {_percent(r['first_held'])}    {_percent(r['first_100'])}    "
            f"{_percent(r['first_300'])}  {_metres(r['first_mean'])} | {_seconds(r['time'])}"
            f"     {_percent(r['held'])}  {_metres(r['length'])}    {_percent(r['within_300'])}"
            f"  {_metres(r['mean'])}"
        )
    for interval in sorted({r["interval"] for r in table}):
        by = {r["localizer"]: r for r in table if r["interval"] == interval}
        fused, arrival = by.get("fused"), by.get("arrival")
        if fused and fused["first_mean"] and fused["mean"]:
            print(
                f"{interval:g} s: fused first answer / fused answer: mean distance "
                f"{fused['first_mean'] / fused['mean']:.2f}x, time "
                f"{(fused['first_time'] or 0) / max(fused['time'] or 1e-9, 1e-9):.3f}x"
            )
        if fused and arrival and fused["first_mean"] and arrival["mean"]:
            print(
                f"{interval:g} s: fused first answer / arrival answer: mean distance "
                f"{fused['first_mean'] / arrival['mean']:.2f}x"
            )


if __name__ == "__main__":
    main()
