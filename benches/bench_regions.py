"""Search regions with the meters a utility has: coverage, length and time, per network.

Usage: ``.venv/bin/python benches/bench_regions.py [NETWORK.inp ...] [--fractions 0.1 0.3]
[--meters-file F ...] [--workers N] [--capture-interval S]``. Default networks: paper15 and EPANET's
Net1, Net2, Anytown and Net3 (``make networks``). For each network and fraction of its junctions (at
least two meters), the meters are placed by ``burstloc place`` (arrival method), then ``burstloc
evaluate`` runs every pipe burst at mid-pipe through the calibrated CUSUM bank at 0.2 s
(``--capture-interval``: another), 5 clock phases, the fused localizer, with the calibrated sensor
noise, exactly as on the command line (simulations cached; Net3 on its transient-ready model, 30 m
pipes). ``--meters-file`` evaluates given meter files instead (e.g. BattLeDIM's sensors on L-TOWN,
written with the format of ``burstloc place --out``).

Printed per run: top-1 / top-3; the named point within 100 / 300 m of the burst; the coverage of
the 50 / 80 / 95 % regions; the 95 % region's median and p90 length, also as a share of the
network's main; the median time from the burst to the first region and to a region of at most
1 km; and, beside the 95 % region, the answer it adds to: the named pipe's position interval
(how often it held the burst, its mean width). All measured in the same run.

``--front-bursts B`` evaluates each network a second time with a configuration whose arrival
localizer times paths at the speed its meters hear the fronts (``burstloc calibrate
--front-bursts B``, the same burst and transient model) and prints that run's coverage beside
the first (the wave speed's): the fit checked on networks nothing was tuned on.
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
NETWORKS = [
    REPO / "networks/paper15.inp",
    *(REPO / "networks/public" / f"{n}.inp" for n in ("Net1", "Anytown", "Net2", "Net3")),
]
TRANSIENT_READY = {"Net3.inp": 30.0, "L-TOWN.inp": 30.0}
"""Networks simulated on their transient-ready model (``--min-pipe-length``, m): Net3's 0.3 m
pipes would set TSNet's step to 0.127 ms."""


def _main_length(network: Path) -> float:
    from burstloc.network import load_network

    wn = load_network(network)
    return float(sum(wn.get_link(p).length for p in wn.pipe_name_list))


def sample_pipes(network: Path, sample: int) -> list[str]:
    """``sample`` of the network's open pipes drawn with a fixed seed, sorted by name."""
    import random

    from burstloc.network import closed_pipes, load_network, pipe_names

    wn = load_network(network)
    closed = set(closed_pipes(wn))
    pipes = [p for p in pipe_names(wn) if p not in closed]
    return sorted(random.Random(2027).sample(pipes, min(sample, len(pipes))))


def _run(
    network: Path,
    meters_file: Path,
    out: Path,
    workers: int | None,
    sample: int | None,
    pipes: list[str] | None = None,
    config: Path | None = None,
    interval: float = 0.2,
) -> dict:
    """``burstloc evaluate`` as on the command line (every open pipe, ``sample`` of them
    drawn with a fixed seed, or ``pipes``; with ``config`` that calibration); its JSON's first
    run."""
    from burstloc.cli import main

    args = [
        "evaluate", str(network), "--detector", "cusum", "--capture-interval", f"{interval:g}",
        "--localizer", "fused", "--meters-file", str(meters_file), "--json", str(out), "--quiet",
        "--burst-coeff", "0.02",  # the paper's burst, as the tables it keeps were measured
    ]  # fmt: skip
    args += _common(network, workers)
    if config is not None:
        args += ["--config", str(config)]
    if sample is not None:
        pipes = sample_pipes(network, sample)
    if pipes is not None:
        args += ["--pipes", *pipes]
    status = main(args)
    if status != 0:
        raise SystemExit(f"evaluate failed on {network.name} ({status})")
    return json.loads(out.read_text())["runs"][0]


def _common(network: Path, workers: int | None) -> list[str]:
    """The options evaluate and the fronts' calibration share: workers, transient model."""
    args = ["--workers", str(workers)] if workers else []
    if network.name in TRANSIENT_READY:
        args += ["--min-pipe-length", f"{TRANSIENT_READY[network.name]:g}"]
    return args


def _fronts(
    network: Path, meters_file: Path, out: Path, bursts: int, workers: int | None, interval: float
) -> None:
    """A calibration at ``interval`` s whose paths are timed at the fronts' speed, written to
    ``out``."""
    from burstloc.cli import main

    args = [
        "calibrate", str(network), "--meters-file", str(meters_file), "--out", str(out),
        "--capture-interval", f"{interval:g}", "--front-bursts", str(bursts),
        "--burst-coeff", "0.02",
    ]  # fmt: skip
    if main(args + _common(network, workers)) != 0:
        raise SystemExit(f"calibrate --front-bursts failed on {network.name}")


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.0f}%"


def _report(name: str, meters: int, junctions: int, run: dict, main_m: float, wall: float) -> None:
    g = run["region"]
    levels = g["levels"]
    median, p90 = levels[2]["median_length_m"], levels[2]["p90_length_m"]
    pos = run["position_error_m"]
    held = pos["interval_hits"] / pos["attempts"] if pos["attempts"] else None
    first, short = g["median_time_to_region_s"], g["median_time_to_searchable_s"]
    print(
        f"{name}: {meters} of {junctions} junctions metered, {main_m / 1000:.1f} km of main, "
        f"{g['attempts']} bursts x phases, {wall:.0f} s wall"
    )
    print(f"  top-1 / top-3 {_pct(run['top1'])} / {_pct(run['top3'])}; named point within "
          f"100 / 300 m: {_pct(g['within_m']['100'])} / {_pct(g['within_m']['300'])}")  # fmt: skip
    print(
        "  region coverage 50 / 80 / 95 %: "
        + " / ".join(_pct(level["coverage"]) for level in levels)
        + f"; 95 % region median {median:.0f} m ({100 * median / main_m:.1f} % of the main), "
        f"p90 {p90:.0f} m"
    )
    print(
        f"  time to the first region {'-' if first is None else f'{first:.1f} s'}, to a region "
        f"<= 1 km {'-' if short is None else f'{short:.1f} s'} ({_pct(g['searchable'])} get one)"
    )
    width = pos["mean_width"]
    print(
        f"  the named pipe's position interval held the burst in {_pct(held)} "
        f"(mean width {'-' if width is None else f'{width:.0f} m'}); the 95 % region in "
        f"{_pct(levels[2]['coverage'])}: x{levels[2]['coverage'] / held if held else math.inf:.2f}"
    )


def main() -> None:
    """Place, evaluate and report every network and fraction."""
    from burstloc.network import load_network
    from burstloc.sim.placement.methods import place_meters

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("networks", nargs="*", type=Path)
    parser.add_argument("--fractions", type=float, nargs="+", default=[0.1, 0.3])
    parser.add_argument("--meters-file", type=Path, nargs="+", default=[])
    parser.add_argument("--workers", type=int)
    parser.add_argument(
        "--capture-interval", type=float, default=0.2, help="seconds between readings (0.2)"
    )
    parser.add_argument(
        "--sample", type=int, help="burst this many pipes (seeded) instead of every pipe"
    )
    parser.add_argument(
        "--front-bursts", type=int, help="also evaluate with the fronts' speed fitted on B bursts"
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        jobs: list[tuple[Path, Path]] = []
        for f in args.meters_file:
            jobs.append((Path(json.loads(f.read_text())["network"]), f))
        for network in args.networks or ([] if args.meters_file else NETWORKS):
            junctions = len(load_network(network).junction_name_list)
            for fraction in args.fractions:
                count = max(2, math.ceil(fraction * junctions))
                path = Path(tmp) / f"{network.stem}-{count}.json"
                place_meters(network, count).save(path)
                jobs.append((network, path))
        for network, meters_file in jobs:
            meters = json.loads(meters_file.read_text())["meters"]
            junctions = len(load_network(network).junction_name_list)
            wall = time.perf_counter()
            run = _run(
                network, meters_file, Path(tmp) / "out.json", args.workers, args.sample,
                interval=args.capture_interval,
            )  # fmt: skip
            wall = time.perf_counter() - wall
            name = f"{network.name} at {args.capture_interval:g} s"
            _report(name, len(meters), junctions, run, _main_length(network), wall)
            if args.front_bursts:
                config = Path(tmp) / "fronts.json"
                _fronts(
                    network, meters_file, config, args.front_bursts, args.workers,
                    args.capture_interval,
                )  # fmt: skip
                again = _run(
                    network,
                    meters_file,
                    Path(tmp) / "out.json",
                    args.workers,
                    args.sample,
                    config=config,
                    interval=args.capture_interval,
                )
                levels = [_pct(level["coverage"]) for level in again["region"]["levels"]]
                print(
                    f"  with the fronts' speed: region coverage 50 / 80 / 95 % "
                    f"{' / '.join(levels)}; named point within 300 m "
                    f"{_pct(again['region']['within_m']['300'])}; 95 % region median "
                    f"{again['region']['levels'][2]['median_length_m']:.0f} m"
                )


if __name__ == "__main__":
    main()
