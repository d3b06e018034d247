"""L-TOWN (the BattLeDIM network, 905 pipes) evaluated at a 0.2 s capture interval: the cost per
burst, the MOC time loop in Rust beside the same loop in NumPy, peak memory, and what it means
for every pipe.

Usage: ``.venv/bin/python benches/bench_ltown.py [--pipes N] [--seed S] [--workers W]
[--config PATH] [--compare-pipes K] [--kept-pipes K] [--all]``. L-TOWN is extracted from the
pinned epyt wheel that ``make networks`` keeps in ``networks/public/`` into a temporary
directory (not into the repository). BattLeDIM's 33 pressure-sensor junctions are the meters
(a meter file written in the temporary directory). Stages, each in a fresh process, each with
wall time, CPU time (the process and its workers) and peak resident memory (the largest
process):

* ``calibrate``: the 0.2 s calibration with the 33 sensors (skipped with ``--config``);
* ``simulate, numpy`` and ``simulate, rust``: one burst (the evaluation's scenario: 220 s,
  transient-ready pipes of at least 30 m, TSNet's time step) on each of the first ``K`` pipes
  of the sample with the ``numpy`` solver and with the default one (the Rust time loop), the
  heads compared bit for bit; their CPU ratio is the speed-up measured in this run;
* ``simulate xK, afresh`` and ``simulate xK, kept``: the first ``K`` (``--kept-pipes``)
  bursts of the sample in one process, each with the time step the evaluation asks for
  (:func:`burstloc.sim.transient.time_step.capture_time_step`), with the network, its steady state
  and
  transient-ready model made afresh for each burst (as before they were kept), and kept from
  one burst to the next (:mod:`burstloc.sim.transient.intact`, as an evaluation's workers do), the
  heads
  compared bit for bit; their CPU ratio is what keeping them saves;
* ``evaluate``: ``burstloc evaluate`` (fused localizer, 0.2 s, the 33 sensors, no cache,
  ``--workers W``) of ``N`` pipes drawn at random with ``--seed`` (``--all``: every pipe);
  beside the largest process's peak, the peak of all its processes together (the parent and
  its workers, sampled from ``/proc`` every 0.2 s).

The last lines extrapolate the evaluation's CPU per burst to all 905 pipes on ``W`` cores,
printed as an extrapolation. On a shared machine compare the CPU columns: the wall clock counts
the other processes' time too.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import random
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from bench_scale import BATTLEDIM_SENSORS, ltown, measure

REPO = Path(__file__).resolve().parents[1]
CAPTURE = 0.2
MIN_PIPE_LENGTH = 30.0


def stage_simulate(network: str, pipe: str, solver: str) -> str:
    """One burst of the evaluation's scenario; the SHA-256 of its heads."""
    from burstloc.sim.scenarios.scenario import BurstScenario
    from burstloc.sim.transient.tsnet import simulate_burst

    scenario = BurstScenario(network, pipe, min_pipe_length=MIN_PIPE_LENGTH, solver=solver)
    result = simulate_burst(scenario, cache=False)
    return hashlib.sha256(result.heads.tobytes()).hexdigest()


def stage_simulate_many(network: str, pipes: list[str], kept: bool) -> list[str]:
    """The bursts of ``pipes`` in one process, as an evaluation's worker simulates them: with
    what does not depend on the pipe kept from one burst to the next (``kept``), or made
    afresh for each; each burst with the time step the evaluation asks for at 0.2 s. The
    SHA-256 of each burst's heads."""
    from dataclasses import replace

    from burstloc.sim.scenarios.scenario import BurstScenario
    from burstloc.sim.transient import intact
    from burstloc.sim.transient.time_step import capture_time_step
    from burstloc.sim.transient.tsnet import simulate_burst

    digests = []
    for pipe in pipes:
        if not kept:
            intact.clear()
        scenario = BurstScenario(network, pipe, min_pipe_length=MIN_PIPE_LENGTH)
        scenario = replace(scenario, time_step=capture_time_step(scenario, CAPTURE))
        result = simulate_burst(scenario, cache=False)
        digests.append(hashlib.sha256(result.heads.tobytes()).hexdigest())
    return digests


def stage_calibrate(network: str, out: str) -> str:
    """The 0.2 s calibration with an empty signature cache (a temporary one)."""
    with tempfile.TemporaryDirectory(prefix="bench-ltown-cache-") as cache:
        os.environ["BURSTLOC_CACHE_DIR"] = cache
        from burstloc.experiments.calibrate import calibrate

        calibrate(network, meters=BATTLEDIM_SENSORS, capture_intervals=[CAPTURE]).save(out)
    return out


def tree_rss_mb(pid: int) -> float:
    """Resident memory of ``pid`` and its descendants now, MB (0 for a process gone)."""
    try:
        pages = int(Path(f"/proc/{pid}/statm").read_text().split()[1])
        children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    except (OSError, IndexError, ValueError):
        return 0.0
    own = pages * os.sysconf("SC_PAGE_SIZE") / 2**20
    return own + sum(tree_rss_mb(int(c)) for c in children)


def run_cli(args: list[str]) -> tuple[float, float, float, float, int]:
    """``burstloc ARGS`` in a child process: wall, CPU (with its workers), peak MB of the largest
    process, peak MB of all its processes together (sampled every 0.2 s), exit code."""
    env = {**os.environ, "PYTHONPATH": str(REPO / "python")}
    wall = time.perf_counter()
    child = subprocess.Popen([sys.executable, "-m", "burstloc", *args], env=env)
    total = [0.0]
    done = threading.Event()

    def sample() -> None:
        while not done.wait(0.2):
            total[0] = max(total[0], tree_rss_mb(child.pid))

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    _, status, usage = os.wait4(child.pid, 0)
    done.set()
    sampler.join()
    child.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - wall
    cpu = usage.ru_utime + usage.ru_stime
    return wall, cpu, usage.ru_maxrss / 1024, total[0], child.returncode


def row(what: str, wall: float, cpu: float, peak: float, note: str = "") -> None:
    print(f"  {what:<18} wall {wall:8.1f} s  cpu {cpu:8.1f} s  peak {peak:7.0f} MB  {note}")


def pipe_names(network: Path) -> list[str]:
    from burstloc.network import load_network, pipe_names

    return list(pipe_names(load_network(network)))


def sensors_and_pipes(directory: Path, seed: int) -> tuple[Path, Path, list[str]]:
    """L-TOWN extracted into ``directory``, a meter file of BattLeDIM's 33 sensors beside it,
    and its pipes shuffled with ``seed``; exits naming ``make networks`` when L-TOWN is
    missing."""
    network = ltown(directory)
    if network is None:
        sys.exit("L-TOWN is missing: run `make networks` (it keeps the epyt wheel)")
    names = pipe_names(network)
    random.Random(seed).shuffle(names)
    return network, meter_file(network, directory), names


def meter_file(network: Path, directory: Path) -> Path:
    from burstloc.inp import network_hash
    from burstloc.sim.placement.methods import MeterSet

    path = directory / "battledim.meters.json"
    MeterSet(
        network=network.name,
        network_hash=network_hash(network),
        method="manual",
        meters=tuple(BATTLEDIM_SENSORS),
        junctions=len(BATTLEDIM_SENSORS),
    ).save(path)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pipes", type=int, default=10, help="pipes evaluated (default 10)")
    parser.add_argument("--seed", type=int, default=0, help="sample seed (default 0)")
    parser.add_argument("--workers", type=int, default=2, help="evaluate's workers (default 2)")
    parser.add_argument("--config", help="a 0.2 s calibration of L-TOWN with the 33 sensors")
    parser.add_argument(
        "--compare-pipes", type=int, default=1, help="bursts simulated by both loops (default 1)"
    )
    parser.add_argument(
        "--kept-pipes",
        type=int,
        default=4,
        help="bursts simulated in one process, the network kept and afresh (default 4)",
    )
    parser.add_argument("--all", action="store_true", help="evaluate every pipe")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        directory = Path(tmp)
        network = ltown(directory)
        if network is None:
            sys.exit("L-TOWN is missing: run `make networks` (it keeps the epyt wheel)")
        names = pipe_names(network)
        sample = names if args.all else random.Random(args.seed).sample(names, args.pipes)
        print(f"L-TOWN: {len(names)} pipes; meters: BattLeDIM's {len(BATTLEDIM_SENSORS)} sensors")
        config = args.config
        if config is None:
            config = str(directory / "ltown.npz")
            wall, cpu, peak, _ = measure(stage_calibrate, str(network), config)
            row("calibrate", wall, cpu, peak, f"{CAPTURE:g} s, empty cache")
        cpu_of: dict[str, float] = {"numpy": 0.0, "vectorized": 0.0}
        for pipe in sample[: args.compare_pipes]:
            digests: dict[str, Any] = {}
            for solver in ("numpy", "vectorized"):
                wall, cpu, peak, digests[solver] = measure(
                    stage_simulate, str(network), pipe, solver
                )
                cpu_of[solver] += cpu
                loop = "rust" if solver == "vectorized" else solver
                row(f"simulate, {loop}", wall, cpu, peak, f"pipe {pipe}, one burst")
            same = "identical" if digests["numpy"] == digests["vectorized"] else "DIFFERENT"
            print(f"  heads of the two loops: {same}")
        if args.compare_pipes:
            print(
                f"  numpy / rust, CPU per burst (TSNet's preparation included): "
                f"x{cpu_of['numpy'] / cpu_of['vectorized']:.1f}"
            )
        if args.kept_pipes:
            pipes = sample[: args.kept_pipes]
            cpu_kept: dict[bool, float] = {}
            digest_kept: dict[bool, Any] = {}
            for kept in (False, True):
                wall, cpu, peak, digest_kept[kept] = measure(
                    stage_simulate_many, str(network), pipes, kept
                )
                cpu_kept[kept] = cpu
                how = "kept" if kept else "afresh"
                row(f"simulate x{len(pipes)}, {how}", wall, cpu, peak, "one process")
            same = "identical" if digest_kept[True] == digest_kept[False] else "DIFFERENT"
            print(f"  heads with the network kept and made afresh: {same}")
            print(
                f"  afresh / kept, CPU per burst: {cpu_kept[False] / len(pipes):.2f} s / "
                f"{cpu_kept[True] / len(pipes):.2f} s = x{cpu_kept[False] / cpu_kept[True]:.2f}"
            )
        out = directory / "evaluation.json"
        cli = [
            "evaluate", str(network), "--localizer", "fused", "--capture-interval", str(CAPTURE),
            "--config", config, "--meters-file", str(meter_file(network, directory)),
            "--min-pipe-length", str(MIN_PIPE_LENGTH), "--no-cache", "--quiet",
            "--workers", str(args.workers), "--json", str(out), "--pipes", *sample,
            "--burst-coeff", "0.02",  # the paper's burst, as the times it keeps were measured
        ]  # fmt: skip
        wall, cpu, peak, together, code = run_cli(cli)
        row(
            "evaluate",
            wall,
            cpu,
            peak,
            f"{len(sample)} pipes, --workers {args.workers}; all processes together: "
            f"{together:.0f} MB",
        )
        if code:
            sys.exit(f"evaluate failed (exit {code})")
        runs = json.loads(out.read_text(encoding="utf-8"))["runs"]
        print("  localized: " + ", ".join(f"{r['correct']}/{r['total']}" for r in runs))
        per_burst = cpu / len(sample)
        print(f"  per burst: cpu {per_burst:.1f} s, wall {wall / len(sample):.1f} s")
        if not args.all:
            minutes = per_burst * len(names) / args.workers / 60
            print(
                f"  EXTRAPOLATED to all {len(names)} pipes from {len(sample)}: "
                f"{per_burst * len(names) / 60:.0f} CPU-min, about {minutes:.0f} min on "
                f"{args.workers} cores"
            )


if __name__ == "__main__":
    main()
