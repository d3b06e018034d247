"""How `burstloc place` and `burstloc calibrate` grow with the network: size, time and peak memory
per stage, and the signatures' cost before and after the in-place EPANET project, in one run.

Usage: ``.venv/bin/python benches/bench_scale.py [NETWORK.inp ...] [--old-pipes N]``. Default
networks: ``networks/paper15.inp``, ``networks/public/Net3.inp`` (``make networks``) and L-TOWN,
the BattLeDIM network, extracted from the pinned epyt wheel that ``make networks`` keeps in
``networks/public/`` into a temporary directory (not into the repository). Per network, each
stage runs in a fresh child process (empty signature cache in a temporary directory), which
reports its wall time, its CPU time and its peak resident memory:

* ``place``: ``place_meters(..., method="arrival")`` for ``min(33, junctions // 4)`` meters;
* ``calibrate``: ``calibrate`` (every default capture interval) with those meters (on L-TOWN
  BattLeDIM's 33 pressure sensors, as in the competition), signatures included;
* ``signatures, new``: one signature set (one position, every pipe) from one EPANET project
  edited in place (:mod:`burstloc.sim.signatures.epanet_inplace`);
* ``signatures, old``: the method it replaces, a WNTR copy of the model split at the pipe
  (``split_pipe``) and a full EPANET run per pipe, timed on the first ``--old-pipes`` pipes only
  and *extrapolated* to every pipe (stated as such in the output).

The ratio printed is old (extrapolated) over new for one signature set; ``calibrate`` computes
nine (the candidate positions). On a shared machine compare the CPU columns: the wall clock
counts the other processes' time too.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import resource
import tempfile
import time
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
WHEEL_GLOB = "epyt-*-py3-none-any.whl"
LTOWN_MEMBER = "epyt/networks/L-TOWN.inp"
BWSN2_MEMBER = "epyt/networks/asce-tf-wdst/BWSN_Network_2.inp"
BATTLEDIM_SENSORS = (
    [f"n{i}" for i in (1, 4, 31, 54, 105, 114, 163, 188, 215, 229, 288, 296)]
    + [f"n{i}" for i in (332, 342, 410, 415, 429, 458, 469, 495, 506, 516, 519, 549, 613, 636, 644)]
    + [f"n{i}" for i in (679, 722, 726, 740, 752, 769)]
)
"""BattLeDIM's 33 pressure sensors on L-TOWN."""


def _measured(stage: Callable[..., Any], args: tuple[Any, ...], queue: Any) -> None:
    """Child process: run ``stage(*args)`` and report (wall, cpu, peak MB, result); the
    package and WNTR are imported before the clocks start (what a stage costs, not Python's
    start-up)."""
    import burstloc.experiments.calibrate
    import burstloc.sim.placement.methods
    import burstloc.sim.signatures.compute  # noqa: F401  (and WNTR through it)

    wall, cpu = time.perf_counter(), time.process_time()
    result = stage(*args)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    queue.put((wall, cpu, peak_mb, result))


def measure(stage: Callable[..., Any], *args: Any) -> tuple[float, float, float, Any]:
    """Run ``stage`` in a fresh (spawned) process: its wall time, CPU time, peak RSS, result."""
    ctx = mp.get_context("spawn")
    queue = ctx.Queue()
    child = ctx.Process(target=_measured, args=(stage, args, queue))
    child.start()
    out = queue.get()
    child.join()
    return out  # type: ignore[no-any-return]


def stage_place(network: str, count: int) -> tuple[str, ...]:
    from burstloc.sim.placement.methods import place_meters

    return place_meters(network, count, method="arrival").meters


def stage_calibrate(network: str, meters: list[str], cache: str) -> int:
    import os

    os.environ["BURSTLOC_CACHE_DIR"] = cache
    from burstloc.experiments.calibrate import calibrate

    return len(calibrate(network, meters=meters).intervals)


def stage_signatures_new(network: str) -> int:
    from burstloc.sim.signatures.compute import compute_signatures

    return len(compute_signatures(network, position=0.5).pipes)


def stage_signatures_old(network: str, pipes: int) -> int:
    """The replaced method on the first ``pipes`` pipes: a copy split per pipe, EPANET run."""
    from burstloc._diagnostics import capture_diagnostics
    from burstloc.network import load_network, split_pipe, steady_state
    from burstloc.sim.signatures.compute import DEFAULT_BURST_COEFF

    wn = load_network(network)
    with capture_diagnostics():
        state = steady_state(wn)
        for pipe in list(wn.pipe_name_list)[:pipes]:
            split = split_pipe(wn, pipe, 0.5)
            split.network.get_node(split.burst_node).emitter_coefficient = DEFAULT_BURST_COEFF
            heads = steady_state(split.network).heads
            _ = [state.heads[m] - heads[m] for m in wn.junction_name_list]
    return pipes


def sizes(network: str) -> tuple[int, int]:
    from burstloc.network import load_network

    wn = load_network(network)
    return wn.num_junctions, wn.num_pipes


def from_wheel(member: str, directory: Path) -> Path | None:
    """The network ``member`` of the pinned epyt wheel, extracted into ``directory`` under its
    own file name (None without the wheel or the member)."""
    wheels = sorted((REPO / "networks" / "public").glob(WHEEL_GLOB))
    if not wheels:
        return None
    with zipfile.ZipFile(wheels[-1]) as wheel:
        if member not in wheel.namelist():
            return None
        target = directory / Path(member).name
        target.write_bytes(wheel.read(member))
    return target


def ltown(directory: Path) -> Path | None:
    """L-TOWN.inp extracted from the pinned wheel into ``directory`` (None without the wheel)."""
    return from_wheel(LTOWN_MEMBER, directory)


def row(name: str, what: str, measured: tuple[float, float, float, Any], note: str = "") -> None:
    wall, cpu, peak, _ = measured
    print(f"  {what:<22} wall {wall:7.1f} s  cpu {cpu:7.1f} s  peak {peak:7.0f} MB  {note}")


def bench(network: Path, old_pipes: int) -> None:
    junctions, pipes = sizes(str(network))
    count = min(33, max(2, junctions // 4))
    print(f"\n{network.name}: {junctions} junctions, {pipes} pipes")
    placed = measure(stage_place, str(network), count)
    row(network.name, "place", placed, f"{count} meters")
    battledim = network.name == "L-TOWN.inp"
    meters = BATTLEDIM_SENSORS if battledim else list(placed[3])
    with tempfile.TemporaryDirectory(prefix="bench-scale-cache-") as cache:
        calibrated = measure(stage_calibrate, str(network), meters, cache)
    which = "BattLeDIM's 33 sensors" if battledim else f"the {count} placed meters"
    row(network.name, "calibrate", calibrated, f"{which}, 9 signature sets, empty cache")
    new = measure(stage_signatures_new, str(network))
    row(network.name, "signatures, new", new, "one set: every pipe, in place")
    subset = min(old_pipes, pipes)
    old = measure(stage_signatures_old, str(network), subset)
    factor = pipes / subset
    row(network.name, "signatures, old", old, f"first {subset} pipes only")
    print(
        f"  old extrapolated to {pipes} pipes: cpu {old[1] * factor:.1f} s per set, "
        f"{9 * old[1] * factor / 60:.1f} min for 9 sets (EXTRAPOLATED from {subset} pipes); "
        f"old / new (cpu): x{old[1] * factor / max(new[1], 1e-9):.0f}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("networks", nargs="*", type=Path)
    parser.add_argument("--old-pipes", type=int, default=30, help="pipes timed by the old method")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-scale-nets-") as tmp:
        networks = list(args.networks)
        if not networks:
            networks = [REPO / "networks" / "paper15.inp"]
            net3 = REPO / "networks" / "public" / "Net3.inp"
            networks += [net3] if net3.is_file() else []
            found = ltown(Path(tmp))
            networks += [found] if found is not None else []
            if len(networks) < 3:
                print("(run `make networks` for Net3 and L-TOWN)")
        for network in networks:
            bench(network, args.old_pipes)


if __name__ == "__main__":
    main()
