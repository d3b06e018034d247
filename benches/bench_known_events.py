"""Known events on L-TOWN: does calibrating on three of them bring a wrong model back?

Usage: ``.venv/bin/python benches/bench_known_events.py [--pipes N] [--phases K] [--interval S]
[--wrong-speed A] [--burst-flow Q] [--workers W] [--truth --truth-...]``. L-TOWN is extracted from
the pinned epyt wheel (``make networks``) into a temporary directory; BattLeDIM's 33 sensors are the
meters. Three *known events* (bursts of ``Q`` L/s, default 5, on three pipes drawn with seed 5
outside the evaluated ones, at 10 s) are simulated as the meters would send them (``burstloc
simulate --feed``, ``S`` s readings, default 0.05, 1 cm of noise) and listed in a known-events file.
Four configurations are calibrated for the 33 sensors: the simulation's wave speed (1 200 m/s) and a
wrong one (``A``, default 1 020 m/s: 15 % slow), each as it is and learnt from the known events
(``burstloc calibrate --known-events``). Each is evaluated on the same ``N`` pipes (default 20, seed
11, as ``bench_ltown_accuracy.py`` draws them) x ``K`` phases (default 2), ``Q`` L/s bursts, the
fused and arrival localizers, CUSUM, the 30 m model. ``--truth --truth-...`` (last): the known
events and the evaluated bursts simulated on a perturbed truth (``burstloc simulate``'s and
``evaluate``'s ``--truth-*`` options) while every configuration keeps the model.

Printed per configuration and localizer: the wave speed it assumes, the 95 % region's coverage
and median length, the named point within 300 m, the mean distance; then the ratios measured in
this run: learnt against as it was, and the wrong model learnt against the exact one.
"""

from __future__ import annotations

import argparse
import json
import random
import tempfile
from pathlib import Path

from bench_ltown import sensors_and_pipes
from bench_ltown_accuracy import burstloc, rows

CONFIGS = ("exact", "exact, learnt", "wrong", "wrong, learnt")


def _known_events(
    network: Path,
    meters: Path,
    pipes: list[str],
    directory: Path,
    interval: float,
    flow: float,
    truth: list[str],
) -> Path:
    """Simulate the known events' feeds and write the known-events file."""
    events = []
    for k, pipe in enumerate(pipes):
        feed = directory / f"known-{pipe}.csv"
        burstloc(
            [
                *("simulate", str(network), "--pipe", pipe, "--duration", "20", "--quiet"),
                *("--capture-interval", f"{interval:g}", "--noise", "0.01", "--seed", str(k)),
                *("--meters", str(meters), "--feed", str(feed), "--out", str(directory / "sims")),
                *("--min-pipe-length", "30", "--burst-flow", f"{flow:g}"),
                *truth,
            ]
        )
        events.append(
            {"name": f"burst on {pipe}", "readings": feed.name, "time": 10.0, "pipe": pipe}
        )
    path = directory / "known-events.json"
    path.write_text(json.dumps({"events": events}, indent=1), encoding="utf-8")
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pipes", type=int, default=20, help="pipes evaluated (default 20)")
    parser.add_argument("--phases", type=int, default=2, help="clock phases (default 2)")
    parser.add_argument("--interval", type=float, default=0.05, help="capture interval, s")
    parser.add_argument("--wrong-speed", type=float, default=1020.0, help="m/s (default 1020)")
    parser.add_argument("--burst-flow", type=float, default=5.0, help="L/s (default 5)")
    parser.add_argument("--workers", type=int, default=2, help="evaluate's workers (default 2)")
    parser.add_argument(
        "--only", nargs="+", choices=CONFIGS, default=CONFIGS, help="configurations to evaluate"
    )
    parser.add_argument(
        "--truth",
        nargs=argparse.REMAINDER,
        default=[],
        help="the rest: `burstloc evaluate`'s --truth-* options, for the known events and the "
        "evaluated bursts alike (e.g. --truth --truth-wave-speed-spread 0.15)",
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-known-events-") as tmp:
        directory = Path(tmp)
        network, meters, names = sensors_and_pipes(directory, 11)
        chosen, rest = names[: args.pipes], sorted(names[args.pipes :])
        known = random.Random(5).sample(rest, 3)
        events = _known_events(
            network, meters, known, directory, args.interval, args.burst_flow, args.truth
        )
        table = []
        for label in args.only:
            speed = args.wrong_speed if label.startswith("wrong") else 1200.0
            config = directory / f"{label.replace(', ', '-')}.json"
            calibrate = ["calibrate", str(network), "--meters-file", str(meters)]
            calibrate += ["--capture-interval", f"{args.interval:g}", "--out", str(config)]
            calibrate += ["--wave-speed", f"{speed:g}"]
            if label.endswith("learnt"):
                calibrate += ["--known-events", str(events)]
            burstloc(calibrate)
            assumed = json.loads(config.read_text())["model"]["wave_speed"]
            out = directory / f"{config.stem}-evaluate.json"
            burstloc(
                [
                    *("evaluate", str(network), "--config", str(config)),
                    *("--meters-file", str(meters), "--localizer", "fused", "arrival"),
                    *("--detector", "cusum", "--capture-interval", f"{args.interval:g}"),
                    *("--phases", str(args.phases), "--min-pipe-length", "30"),
                    *("--workers", str(args.workers), "--quiet", "--json", str(out)),
                    *("--burst-flow", f"{args.burst_flow:g}", *args.truth),
                    *("--pipes", *chosen),
                ]
            )
            table += [
                {**r, "config": label, "speed": assumed} for r in rows(json.loads(out.read_text()))
            ]
    print(
        f"\nL-TOWN, BattLeDIM's 33 sensors, {args.interval:g} s readings: known events on "
        f"{', '.join(known)}; {len(chosen)} pipes x {args.phases} phases, "
        f"{args.burst_flow:g} L/s bursts"
        + (f"; the truth perturbed: {' '.join(args.truth)}" if args.truth else "")
    )
    print("configuration   speed  localizer | 95% held  region  <=300m     mean")
    for r in table:
        print(
            f"{r['config']:<14} {r['speed']:6.0f}  {r['localizer']:<9} |     "
            f"{100 * (r['held'] or 0):3.0f}%  {r['length'] or 0:5.0f}m    "
            f"{100 * (r['within_300'] or 0):3.0f}%  {r['mean']:7.1f}m"
        )
    by = {(r["config"], r["localizer"]): r for r in table}
    if set(args.only) != set(CONFIGS):
        return  # the ratios need every configuration
    for localizer in ("fused", "arrival"):
        for base in ("exact", "wrong"):
            was, now = by[(base, localizer)], by[(f"{base}, learnt", localizer)]
            print(
                f"{localizer}: {base} learnt / as it was: mean distance "
                f"{now['mean'] / was['mean']:.2f}x, coverage {100 * (now['held'] or 0):.0f}% / "
                f"{100 * (was['held'] or 0):.0f}%"
            )
        wrong, exact = by[("wrong, learnt", localizer)], by[("exact", localizer)]
        print(
            f"{localizer}: wrong learnt / exact: mean distance {wrong['mean'] / exact['mean']:.2f}x"
        )


if __name__ == "__main__":
    main()
