"""Burst signatures from one factorization of the linearized steady state (``linear``), and
anchored on an exact mid-pipe drop (``hybrid``), against the exact ones (one EPANET steady state
per pipe and position): time and agreement, measured in one run.

Usage: ``.venv/bin/python benches/bench_linear_signatures.py [NETWORK.inp ...] [--sample N]
[--meters M] [--seed S]``. Default networks: paper15, Net1, Net2, Anytown, Net3 and, from the
pinned epyt wheel that ``make networks`` keeps in ``networks/public/`` (extracted into a temporary
directory, not into the repository), L-TOWN and BWSN_Network_2. Per network, each stage in a fresh
child process (wall time, CPU time, peak resident memory):

* ``exact``: EPANET steady states of the network split at 10 %, 50 % and 90 % of every pipe (in
  one project edited in place, as :func:`burstloc.sim.signatures.compute.compute_signatures`); on
  networks above ``--sample`` pipes only ``--sample`` pipes drawn with ``--seed``. The cost of
  the nine positions ``calibrate`` computes is *extrapolated* from the CPU per EPANET run (stated
  as such), plus loading the network once;
* ``linear``: :func:`burstloc.sim.signatures.compute.linear_signature_sets`, nine positions, every
pipe;
* ``hybrid``: its cost is one exact run per pipe (at the ``exact`` stage's CPU per run) plus the
  ``linear`` stage; its signatures are :func:`burstloc.sim.signatures.linear.anchored` of those.

Agreement: at 10 %, 50 % and 90 % along the (sampled) pipes heard at the meters, the cosine between
each pipe's exact signature and the linear or hybrid one (the signature localizer fits a free
scale, so the shape is what counts; the hybrid is exact at mid-pipe by construction). Meters:
``--meters`` junctions drawn with ``--seed`` (L-TOWN: BattLeDIM's 33 pressure sensors).
"""

from __future__ import annotations

import argparse
import random
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from bench_scale import BATTLEDIM_SENSORS, BWSN2_MEMBER, LTOWN_MEMBER, REPO, from_wheel, measure

MEMBERS = (LTOWN_MEMBER, BWSN2_MEMBER)
POSITIONS = (0.1, 0.5, 0.9)


def stage_exact(network: str, meters: list[str], pipes: list[str]) -> Any:
    """Exact signatures of ``pipes`` at ``meters`` at each of :data:`POSITIONS`, and the CPU
    time of the EPANET runs alone (loading the network is paid once, not per pipe)."""
    import time

    from burstloc._diagnostics import capture_diagnostics
    from burstloc.network import load_network
    from burstloc.sim.signatures.compute import DEFAULT_BURST_COEFF
    from burstloc.sim.signatures.epanet_inplace import InPlaceSplitter

    wn = load_network(network)
    out = np.empty((len(POSITIONS), len(pipes), len(meters)))
    with capture_diagnostics(), InPlaceSplitter(wn) as splitter:
        intact = splitter.heads(meters)
        start = time.process_time()
        for k, x in enumerate(POSITIONS):
            for i, pipe in enumerate(pipes):
                out[k, i] = intact - splitter.split_heads(pipe, x, DEFAULT_BURST_COEFF, meters)
        runs = time.process_time() - start
    return runs, out


def stage_linear(network: str, meters: list[str]) -> Any:
    """The nine linear sets; those at :data:`POSITIONS` and the pipe order."""
    from burstloc.constants import CANDIDATE_POSITIONS
    from burstloc.sim.signatures.compute import linear_signature_sets

    sets = linear_signature_sets(network, meters)
    at = [sets[list(CANDIDATE_POSITIONS).index(x)] for x in POSITIONS]
    return np.array([s.matrix for s in at]), list(at[0].pipes)


def unit(matrix: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(matrix, axis=1, keepdims=True)
    return matrix / np.where(norm > 0, norm, 1.0)


def cosine(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.sum(unit(a) * unit(b), axis=1)


def bench(network: Path, sample: int, count: int, seed: int) -> None:
    from burstloc.inp import junction_names_in_file, pipe_names_in_file
    from burstloc.sim.signatures.linear import anchored

    junctions = junction_names_in_file(network)
    all_pipes = pipe_names_in_file(network)
    rng = random.Random(seed)
    if network.stem == "L-TOWN":
        meters = list(BATTLEDIM_SENSORS)
    else:
        meters = sorted(rng.sample(junctions, min(count, len(junctions))), key=junctions.index)
    sampled = len(all_pipes) > sample
    pipes = sorted(rng.sample(all_pipes, sample), key=all_pipes.index) if sampled else all_pipes
    sizes = f"{len(junctions)} junctions, {len(all_pipes)} pipes, {len(meters)} meters"
    print(f"{network.stem}: {sizes}")
    _, ex_cpu, _, (runs, exact) = measure(stage_exact, str(network), meters, pipes)
    _, li_cpu, li_peak, (linear, order) = measure(stage_linear, str(network), meters)
    per_run = runs / (len(POSITIONS) * len(pipes))
    setup = ex_cpu - runs
    exact_cpu = setup + per_run * 9 * len(all_pipes)
    hybrid_cpu = li_cpu + per_run * len(all_pipes)
    note = f" (extrapolated: {per_run * 1e3:.1f} ms per run from {len(pipes)} pipes x 3 positions)"
    print(f"  exact, nine positions  cpu {exact_cpu:8.1f} s{note}")
    print(f"  hybrid, nine positions cpu {hybrid_cpu:8.1f} s  (linear + one exact run per pipe)")
    print(f"  linear, nine positions cpu {li_cpu:8.1f} s  peak {li_peak:.0f} MB")
    print(
        f"  CPU exact / hybrid {exact_cpu / hybrid_cpu:6.1f} x   exact / linear "
        f"{exact_cpu / li_cpu:8.1f} x"
    )
    rows = np.array([order.index(p) for p in pipes])
    mine = linear[:, rows]
    heard = (np.linalg.norm(exact[1], axis=1) > 1e-6) & (np.linalg.norm(mine[1], axis=1) > 1e-6)
    print(f"  cosine to exact over {heard.sum()} heard pipes (p5 / median):")
    for k, x in enumerate(POSITIONS):
        hybrid = anchored(exact[1], mine[1], mine[k])
        lin, hyb = cosine(exact[k], mine[k])[heard], cosine(exact[k], hybrid)[heard]
        print(
            f"    at {x:.0%} of the pipe: linear {np.percentile(lin, 5):.4f} / "
            f"{np.median(lin):.5f}   hybrid {np.percentile(hyb, 5):.4f} / {np.median(hyb):.5f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("networks", nargs="*")
    parser.add_argument("--sample", type=int, default=1000, help="exact pipes above this many")
    parser.add_argument("--meters", type=int, default=33)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-linear-") as tmp:
        networks = [Path(n) for n in args.networks]
        if not networks:
            public = REPO / "networks" / "public"
            networks = [REPO / "networks" / "paper15.inp"]
            networks += [public / f"{n}.inp" for n in ("Net1", "Net2", "Anytown", "Net3")]
            for member in MEMBERS:
                path = from_wheel(member, Path(tmp))
                if path is None:
                    print(f"skipped {member}: the pinned epyt wheel is missing (make networks)")
                else:
                    networks.append(path)
        for network in networks:
            bench(network, args.sample, args.meters, args.seed)


if __name__ == "__main__":
    main()
