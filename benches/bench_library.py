"""The published-model library: which models of the epyt wheel simulate a burst from a steady start.

Usage: ``.venv/bin/python benches/bench_library.py [--library DIR] [--timeout S] [--markdown]
[NAME ...]`` (default: ``networks/public/library``, which ``python networks/fetch_public.py
--library`` fills from the pinned epyt wheel; NAMEs restrict the run to those files).

Every INP file of the library is first opened and solved by EPANET itself (the toolkit WNTR
ships, one hydraulic step, the file as published); those it solves with at least
:data:`MIN_PIPES` pipes are the library this benchmark judges. For each, in a child process
killed after ``--timeout`` seconds, burstloc does what ``burstloc simulate NET --pipe <first
pipe> --min-pipe-length 30 --duration 20 --no-cache`` does (the first pipe in INP order that is
open: a closed pipe has nothing to burst) and the row says:

* the model's size: junctions, pipes, pumps, valves, sources (reservoirs + tanks) and parallel
  links (links that share both end nodes with another link);
* the outcome: ``simulated`` with the largest movement of a junction before the burst (the
  steady-start check, :mod:`burstloc.sim.transient.steady`), or ``refused`` with burstloc's one-line
  reason, or ``timeout``;
* the wall-clock seconds of the child (loading, preparation, simulation).

The last line gives the share simulated. ``--json`` keeps the rows; ``--before ROWS.json`` (the
rows of an earlier run, e.g. of an older burstloc: ``PYTHONPATH=OLD/python``) adds its outcome
as a column and its share to the last line.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import multiprocessing as mp
import os
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
LIBRARY = REPO / "networks" / "public" / "library"
#: Models with fewer pipes are textbook examples, not utility models.
MIN_PIPES = 30
#: The scenario: ``--min-pipe-length 30 --duration 20`` (burst at burstloc's default onset).
MIN_PIPE_LENGTH = 30.0
DURATION = 20.0


def epanet_solves(path: Path) -> str | None:
    """``None`` when EPANET's toolkit opens ``path`` and solves its first hydraulic step, else
    its error."""
    from wntr.epanet import toolkit

    with tempfile.TemporaryDirectory(prefix="bench-library-") as tmp:
        en = toolkit.ENepanet()
        try:
            en.ENopen(str(path), os.path.join(tmp, "x.rpt"), os.path.join(tmp, "x.bin"))
            en.ENopenH()
            en.ENinitH(0)
            en.ENrunH()
            en.ENcloseH()
        except Exception as exc:  # the toolkit raises its error code as an exception
            return f"{type(exc).__name__}: {exc}".splitlines()[0]
        finally:
            with contextlib.suppress(Exception):
                en.ENclose()
    return None


def size(path: Path) -> dict[str, Any]:
    """Counts of the model's elements, read by WNTR (``None`` values when it cannot)."""
    from burstloc.network import load_network

    try:
        wn = load_network(str(path))
    except Exception:
        return {}
    pairs = Counter(frozenset((link.start_node_name, link.end_node_name)) for _, link in wn.links())
    return {
        "junctions": wn.num_junctions,
        "pipes": wn.num_pipes,
        "pumps": wn.num_pumps,
        "valves": wn.num_valves,
        "sources": wn.num_reservoirs + wn.num_tanks,
        "parallel": sum(n for n in pairs.values() if n > 1),
    }


def first_open_pipe(path: Path) -> str:
    """The first pipe in INP order that is open at the start."""
    from burstloc.network import closed_pipes, load_network, pipe_names

    wn = load_network(str(path))
    closed = set(closed_pipes(wn))
    return next(p for p in pipe_names(wn) if p not in closed)


def _one(path: str, queue: Any) -> None:
    """Child: simulate one burst as ``burstloc simulate`` does; put the outcome on ``queue``."""
    try:
        from burstloc.sim.scenarios.scenario import burst_scenarios
        from burstloc.sim.transient.tsnet import simulate_burst

        pipe = first_open_pipe(Path(path))
        (scenario,) = burst_scenarios(
            path, [pipe], duration=DURATION, min_pipe_length=MIN_PIPE_LENGTH
        )
        result = simulate_burst(scenario, cache=False)
        steady = result.metadata["steady_start"]
        queue.put({"outcome": "simulated", "pipe": pipe, "steady": steady})
    except Exception as exc:
        queue.put({"outcome": "refused", "reason": f"{type(exc).__name__}: {exc}"})


def run_one(path: Path, timeout: float) -> dict[str, Any]:
    """Simulate in a child process; the outcome and its wall-clock seconds."""
    ctx = mp.get_context("spawn")
    queue = ctx.Queue()
    started = time.perf_counter()
    child = ctx.Process(target=_one, args=(str(path), queue))
    child.start()
    child.join(timeout)
    if child.is_alive():
        child.terminate()
        child.join()
        row: dict[str, Any] = {"outcome": "timeout", "reason": f"over {timeout:g} s"}
    elif queue.empty():
        row = {"outcome": "refused", "reason": f"the child process died ({child.exitcode})"}
    else:
        row = queue.get()
    row["seconds"] = time.perf_counter() - started
    if "reason" in row:  # the model's file name is enough
        row["reason"] = row["reason"].replace(f"{path.parent}{os.sep}", "")
    return row


def _outcome(row: dict[str, Any]) -> str:
    """A row's outcome as one table cell."""
    if row["outcome"] == "simulated":
        return f"simulated (pipe {row['pipe']}{_movement(row['steady'])})"
    return f"{row['outcome']}: {row['reason']}".replace("|", "/").replace("\n", " ")


def _movement(steady: dict[str, Any]) -> str:
    moved = steady.get("max_movement_m", steady.get("movement_m"))
    return f", {float(moved) * 100:.2g} cm before the burst" if moved is not None else ""


def main(argv: list[str] | None = None) -> int:
    """Sweep the library; print one row per model and the share simulated."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", help="only these files (names, with .inp)")
    parser.add_argument("--library", type=Path, default=LIBRARY)
    parser.add_argument("--timeout", type=float, default=600.0, help="per model (s)")
    parser.add_argument("--json", type=Path, help="also write the rows here")
    parser.add_argument("--before", type=Path, help="rows of an earlier run (its --json)")
    args = parser.parse_args(argv)
    before = (
        {r["model"]: r for r in json.loads(args.before.read_text(encoding="utf-8"))}
        if args.before
        else {}
    )
    files = sorted(args.library.rglob("*.inp"), key=lambda p: p.name.lower())
    if args.names:
        files = [f for f in files if f.name in set(args.names)]
    if not files:
        print(
            f"no INP files under {args.library}: run `python networks/fetch_public.py --library`",
            file=sys.stderr,
        )
        return 1
    rows = []
    print(
        "| model | junctions | pipes | pumps | valves | sources | parallel links | outcome | "
        f"time (s) |{' before |' if before else ''}"
    )
    print(f"|---|---|---|---|---|---|---|---|---|{'---|' if before else ''}")
    skipped = []
    for path in files:
        error = epanet_solves(path)
        counts = size(path)
        if error is not None:
            skipped.append(f"{path.name}: EPANET does not solve it ({error})")
            continue
        if counts and counts["pipes"] < MIN_PIPES:
            skipped.append(f"{path.name}: {counts['pipes']} pipes")
            continue
        row = {"model": path.name, **counts, **run_one(path, args.timeout)}
        rows.append(row)
        cells = [
            counts.get(k, "?")
            for k in ("junctions", "pipes", "pumps", "valves", "sources", "parallel")
        ]
        then = f" {_outcome(before[path.name])} |" if path.name in before else ""
        print(
            f"| {path.name} | {' | '.join(map(str, cells))} | {_outcome(row)} | "
            f"{row['seconds']:.1f} |{then}",
            flush=True,
        )
    done = sum(r["outcome"] == "simulated" for r in rows)
    share = 100 * done / max(len(rows), 1)
    summary = f"\nsimulated from a steady start: {done} of {len(rows)} ({share:.0f} %)"
    if before:
        then = sum(
            before[r["model"]]["outcome"] == "simulated" for r in rows if r["model"] in before
        )
        summary += f"; before: {then} of {len(rows)}"
    print(summary)
    for reason in skipped:
        print(f"not judged: {reason}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1, default=str) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
