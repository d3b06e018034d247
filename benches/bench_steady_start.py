"""Which networks start steady under TSNet, and what a simulated burst second costs on each.

Usage: ``.venv/bin/python benches/bench_steady_start.py [NETWORK.inp ...] [--onset S]
[--after S] [--timeout S]`` (default: ``networks/paper15.inp``, ``networks/paper15_assets.inp``
and the public networks of ``make networks``). Per network, in a child process killed after
``--timeout`` seconds, one burst (no cache) on the network's longest pipe (splitting it leaves
TSNet's time step to the network's shortest pipe) at ``--onset`` s, simulated ``--after`` s
beyond it; printed as a Markdown table row:

* the network's junctions, pipes, pumps / valves / tanks / reservoirs and shortest pipe;
* what :mod:`burstloc.sim.transient.tsnet_ready` changes (closed pipes and pumps removed, supply
junctions
  made fixed inflows, connector pipes for pumps and valves at a branch), and the largest change
  it makes to a junction's steady head (EPANET, pressure-driven);
* TSNet's time step (:func:`burstloc.sim.transient.time_step.expected_time_step`, before running);
* the steady-start check (:mod:`burstloc.sim.transient.steady`): the largest movement of a
junction's
  pressure head before the onset, where and when; or the error that stopped the run;
* CPU seconds of the run and per simulated second.

A network whose run would exceed the timeout is reported with its step count (and so an
estimate from the CPU per step of the runs that finished).
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
NETWORKS = [REPO / "networks" / n for n in ("paper15.inp", "paper15_assets.inp")] + [
    REPO / "networks" / "public" / n for n in ("Net1.inp", "Net2.inp", "Anytown.inp", "Net3.inp")
]


def describe(path: Path) -> dict[str, Any]:
    """The network's size and assets, and the burst scenario used on it."""
    from burstloc.network import junction_names, load_network, steady_state
    from burstloc.sim.transient.tsnet_ready import prepare_for_tsnet

    wn = load_network(str(path))
    pipes = {name: float(pipe.length) for name, pipe in wn.pipes()}
    before = steady_state(wn).heads
    connected = load_network(str(path))
    prepared = prepare_for_tsnet(connected)
    after = steady_state(connected).heads
    change = max(abs(float(after[j]) - float(before[j])) for j in junction_names(wn))
    return {
        "connectors": "; ".join(
            [f"closed {p} removed" for p in prepared.removed_closed_links]
            + [f"supply {s.junction} a fixed inflow" for s in prepared.supply_boundaries]
            + [f"{c.link} at {c.node}" for c in prepared.connectors]
        )
        or "none",
        "connector_change_m": change,
        "junctions": wn.num_junctions,
        "pipes": wn.num_pipes,
        "assets": f"{wn.num_pumps} / {wn.num_valves} / {wn.num_tanks} / {wn.num_reservoirs}",
        "shortest_m": min(pipes.values()),
        "pipe": max(pipes, key=lambda p: pipes[p]),
    }


def _run(path: str, pipe: str, onset: float, duration: float, queue: Any) -> None:
    from burstloc.exceptions import UnsteadyStartError
    from burstloc.sim.scenarios.scenario import BurstScenario
    from burstloc.sim.transient.tsnet import simulate_burst

    scenario = BurstScenario(path, pipe, burst_start=onset, duration=duration)
    cpu = time.process_time()
    try:
        meta = simulate_burst(scenario, cache=False).metadata
        s = meta["steady_start"]
        out = {"movement": s["max_movement_m"], "junction": s["junction"], "at": s["time"]}
        out["steady"] = True
    except UnsteadyStartError as exc:
        out = {"movement": exc.movement, "junction": exc.junction, "at": exc.time}
        out["steady"] = False
    except Exception as exc:
        out = {"error": f"{type(exc).__name__}: {exc}"[:300]}
    out["cpu"] = time.process_time() - cpu
    queue.put(out)


def measure(path: Path, onset: float, after: float, timeout: float) -> dict[str, Any]:
    """Describe ``path`` and run its burst in a child process (at most ``timeout`` s)."""
    from burstloc.sim.scenarios.scenario import BurstScenario
    from burstloc.sim.transient.time_step import expected_time_step

    row = describe(path)
    duration = onset + after
    scenario = BurstScenario(str(path), row["pipe"], burst_start=onset, duration=duration)
    dt = expected_time_step(scenario)
    row.update(dt=dt, steps=int(duration / dt), duration=duration)
    queue: Any = mp.get_context("spawn").Queue()
    child = mp.get_context("spawn").Process(
        target=_run, args=(str(path), row["pipe"], onset, duration, queue)
    )
    started = time.perf_counter()
    child.start()
    child.join(timeout)
    if child.is_alive():
        child.terminate()
        child.join()
        row["error"] = f"stopped after {timeout:g} s ({row['steps']} time steps)"
        return row
    row["wall"] = time.perf_counter() - started
    row.update(queue.get() if not queue.empty() else {"error": "no result"})
    return row


def table_row(name: str, row: dict[str, Any]) -> str:
    """One Markdown table row."""
    if "error" in row:
        steady = row["error"]
    else:
        verdict = "yes" if row["steady"] else "**no**"
        steady = f"{verdict}: {row['movement']:.3g} m at {row['junction']} ({row['at']:.3g} s)"
    cost = (
        f"{row['cpu']:.1f} s, {row['cpu'] / row['duration']:.2f}"
        if "cpu" in row
        else f"> {row.get('wall', 0):.0f} s"
    )
    return (
        f"| {name} | {row['junctions']} | {row['pipes']} | {row['assets']} | "
        f"{row['shortest_m']:.1f} m | {row['connectors']} ({row['connector_change_m']:.2g} m) | "
        f"{row['pipe']} | {row['dt']:.4g} s ({row['steps']}) | "
        f"{steady} | {cost} |"
    )


def main() -> None:
    """Measure every network named (or the default set) and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("networks", nargs="*", type=Path, default=NETWORKS)
    parser.add_argument("--onset", type=float, default=5.0, help="burst onset (s)")
    parser.add_argument("--after", type=float, default=1.0, help="simulated after it (s)")
    parser.add_argument("--timeout", type=float, default=300.0, help="per network (s)")
    args = parser.parse_args()
    print(
        "| network | junctions | pipes | pumps / valves / tanks / reservoirs | shortest pipe "
        "| prepared for TSNet (steady head change) | burst pipe | TSNet step (steps) "
        "| steady start: max pre-burst movement | CPU: run, per simulated s |"
    )
    print("|---|---:|---:|---|---:|---|---|---|---|---|")
    for path in args.networks:
        row = measure(path, args.onset, args.after, args.timeout)
        print(table_row(path.name, row), flush=True)


if __name__ == "__main__":
    main()
