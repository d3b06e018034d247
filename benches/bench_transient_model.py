"""What a transient-ready model (:mod:`burstloc.skeleton`) buys in TSNet time and costs in heads.

Usage: ``.venv/bin/python benches/bench_transient_model.py NETWORK.inp:PIPE ...
[--min-pipe-length M] [--duration S] [--timeout S] [--compare]``. Per network, one burst on
``PIPE`` (split at mid-length, opening over a quarter of the run, TSNet's burst coefficient
0.01), simulated on the network as it is and on its transient-ready model (every short pipe
merged or lengthened to ``M`` m; the network's junctions kept, so the meters are the same):

* pipes, the shortest pipe, TSNet's Courant step ``min L / (2 a)`` and the step it used;
* CPU seconds of TSNet's MOC solver per simulated second (the solver call alone: the steady
  state and the discretization are left out), in a child process killed after ``--timeout``;
  a run whose estimated time (TSNet's own estimate after 3 steps, times the steps) exceeds the
  timeout is shortened to what fits, and said so;
* the pre-burst drift (largest |head - head at t = 0| at any meter before the burst: a model
  that does not start steady moves before anything happens) and any error, naming TSNet's
  message;
* ``--connectors L`` first rewrites each network with short connector pipes of ``L`` m (a
  model where the original can still be simulated): at each junction of ``--split-nodes``, the
  junction's last ``--moved`` pipes move to a new junction ``<node>x`` (same elevation, no
  demand) joined to it by an ``L`` m connector as wide as its widest pipe; and the pipe
  ``--split-pipe`` is cut ``L`` m before its end node (a connector in series);
* with ``--localize``: the arrival localizer of the network as given (every junction metered,
  :func:`burstloc.sim.model.prepare.arrival_localizer`) ranks each run's burst from alarms at the
  arrival times below (amplitude: the head change then): the pipe it names first, the rank
  of the burst pipe and the position error on it, for the original model and the prepared
  one (whose pipes are the original's: nothing is merged when every junction is kept);
* with ``--compare`` (both models simulated over the same duration): the largest head
  difference at the meters (the prepared model's heads interpolated to the original's times)
  and the difference of the arrival times (first time a meter's head moves more than 1 % of
  its largest change after the burst starts).

One simulation at a time (each in its own process, for the timeout).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import queue as queue_module
import re
import sys
import tempfile
import time
from typing import Any

import numpy as np

WAVE_SPEED = 1200.0


def _simulate(
    path: str, pipe: str, min_length: float | None, duration: float, out: Any, log: str
) -> None:  # pragma: no cover - child process
    from burstloc import network
    from burstloc.sim.transient import _tsnet_compat
    from burstloc.sim.transient.tsnet import TransientSettings, isolated_run, run_transient
    from burstloc.skeleton import prepare_transient_model

    tsnet = _tsnet_compat.load()
    moc = tsnet.simulation.MOCSimulator
    spent: dict[str, float] = {}

    def timed(*args: Any, **kwargs: Any) -> Any:
        started = time.process_time()
        try:
            return moc(*args, **kwargs)
        finally:
            spent["moc"] = time.process_time() - started

    tsnet.simulation.MOCSimulator = timed
    sys.stdout = open(log, "w", buffering=1)  # noqa: SIM115 - TSNet's progress, child only
    try:
        wn = network.load_network(path)
        meters = network.junction_names(wn)
        model, model_pipe, position = wn, pipe, 0.5
        if min_length is not None:
            prepared = prepare_transient_model(wn, min_length, keep=meters)
            model = prepared.network
            model_pipe, position = prepared.locate(pipe, 0.5)
        split = network.split_pipe(model, model_pipe, position)
        start = duration / 5.0
        settings = TransientSettings(WAVE_SPEED, duration, None, "PDD", "steady")
        with isolated_run() as tmp:

            def burst(tm: Any) -> None:
                tm.add_burst(split.burst_node, start, duration / 4.0, 0.01)

            steps, heads, dt = run_transient(
                split.network, meters, f"{tmp}/b.inp", settings, burst, where=path
            )
        out.put(
            {
                "dt": dt,
                "moc_cpu": spent.get("moc"),
                "time": steps.tolist(),
                "heads": heads.tolist(),
                "start": start,
            }
        )
    except Exception as exc:
        out.put({"error": f"{type(exc).__name__}: {exc}", "moc_cpu": spent.get("moc")})


def simulate(
    path: str, pipe: str, min_length: float | None, duration: float, timeout: float
) -> dict[str, Any]:
    """One burst in a child process; after ``timeout`` s, ``{"error": "timeout ..."}`` with
    TSNet's own estimate of the run's wall time (after its first 3 steps), if it printed one."""
    queue: Any = mp.get_context("fork").Queue()
    with tempfile.NamedTemporaryFile("r", suffix=".log") as log:
        child = mp.get_context("fork").Process(
            target=_simulate, args=(path, pipe, min_length, duration, queue, log.name)
        )
        child.start()
        try:
            return dict(queue.get(timeout=timeout))
        except queue_module.Empty:
            return {"error": f"timeout: over {timeout:g} s", **_estimate(log.read())}
        finally:
            child.kill()
            child.join()


def _estimate(log: str) -> dict[str, Any]:
    """TSNet's printed step count and estimated wall time (s) of the whole run."""
    steps = re.search(r"Total Time Step in this simulation (\d+)", log)
    wall = re.search(r"Estimated simulation time (?:(\d+) days?, )?(\d+):(\d+):([\d.]+)", log)
    if not (steps and wall):
        return {}
    days, hours, minutes, seconds = (float(g or 0) for g in wall.groups())
    total = ((days * 24 + hours) * 60 + minutes) * 60 + seconds
    return {"tsnet_steps": int(steps.group(1)), "tsnet_estimate_s": total}


def with_connectors(
    path: str, out: str, length: float, nodes: list[str], pipe: str | None, moved: int
) -> str:
    """Write ``path`` with short connector pipes to ``out`` (module docstring); return it."""
    import wntr

    from burstloc import network

    wn = network.load_network(path)
    for node in nodes:
        links = wn.get_links_for_node(node)
        widest = max(wn.get_link(p).diameter for p in links)
        twin = f"{node}x"
        junction = wn.get_node(node)
        wn.add_junction(twin, 0.0, elevation=junction.elevation, coordinates=junction.coordinates)
        for name in links[-moved:]:
            link = wn.get_link(name)
            start = twin if link.start_node_name == node else link.start_node_name
            end = twin if link.end_node_name == node else link.end_node_name
            wn.remove_link(name)
            wn.add_pipe(name, start, end, link.length, link.diameter, link.roughness)
        wn.add_pipe(f"C{node}", node, twin, length, widest, 120.0)
    if pipe is not None:
        link = wn.get_link(pipe)
        wn = wntr.morph.split_pipe(
            wn, pipe, f"C{pipe}", f"{pipe}x", split_at_point=1 - length / link.length
        )
    wntr.network.write_inpfile(wn, out, units=wn.options.hydraulic.inpfile_units)
    return out


def shape(path: str, min_length: float) -> dict[str, Any]:
    """Pipes, shortest pipe and Courant step before and after preparation."""
    from burstloc import network
    from burstloc.skeleton import courant_time_step, prepare_transient_model, shortest_pipe

    wn = network.load_network(path)
    prepared = prepare_transient_model(wn, min_length, keep=network.junction_names(wn))
    row: dict[str, Any] = {}
    for label, model in (("original", wn), ("prepared", prepared.network)):
        name, length = shortest_pipe(model)
        row[label] = {
            "pipes": model.num_pipes,
            "shortest": f"{name} ({length:.2f} m)",
            "courant_dt": courant_time_step(model, WAVE_SPEED),
            "reaches": int(
                sum(
                    model.get_link(p).length // (WAVE_SPEED * courant_time_step(model, WAVE_SPEED))
                    for p in model.pipe_name_list
                )
            ),
        }
    row["summary"] = prepared.summary()
    return row


def arrivals(time_: np.ndarray, heads: np.ndarray, start: float) -> np.ndarray:
    """Per meter: the first time after ``start`` its head moves > 1 % of its largest change."""
    base = heads[np.searchsorted(time_, start) - 1]
    change = np.abs(heads - base)
    out = np.full(heads.shape[1], np.nan)
    for m in range(heads.shape[1]):
        after = time_ >= start
        limit = 0.01 * change[after, m].max()
        moved = np.nonzero(after & (change[:, m] > limit))[0]
        if moved.size and limit > 0:
            out[m] = time_[moved[0]]
    return out


def compare(original: dict[str, Any], prepared: dict[str, Any]) -> dict[str, Any]:
    """Head and arrival-time differences at the meters, prepared vs original."""
    t0, h0 = np.array(original["time"]), np.array(original["heads"])
    t1, h1 = np.array(prepared["time"]), np.array(prepared["heads"])
    common = t0 <= t1[-1]
    h1i = np.column_stack([np.interp(t0[common], t1, h1[:, m]) for m in range(h1.shape[1])])
    diff = np.abs(h1i - h0[common])
    a0 = arrivals(t0, h0, original["start"])
    a1 = arrivals(t1, h1, prepared["start"])
    swing = np.abs(h0 - h0[0]).max()
    return {
        "max_head_diff_m": float(diff.max()),
        "mean_head_diff_m": float(diff.mean()),
        "largest_head_change_m": float(swing),
        "arrival_diff_s_max": float(np.nanmax(np.abs(a1 - a0))),
        "arrival_diff_s_mean": float(np.nanmean(np.abs(a1 - a0))),
    }


def localize(path: str, pipe: str, run: dict[str, Any]) -> dict[str, Any]:
    """The arrival localizer's first pipe and the burst pipe's rank, from ``run``'s arrivals."""
    from burstloc.localize.evidence import BurstEvidence, MeterAlarm
    from burstloc.sim.model.prepare import arrival_localizer

    loc = arrival_localizer(path)
    t, h = np.array(run["time"]), np.array(run["heads"])
    at = arrivals(t, h, run["start"])
    base = h[np.searchsorted(t, run["start"]) - 1]
    alarms = {
        m: MeterAlarm(m, float(a), float(h[-1, j] - base[j]))
        for j, (m, a) in enumerate(zip(loc.meters, at, strict=True))
        if np.isfinite(a)
    }
    evidence = BurstEvidence(
        meters=loc.meters,
        times=t,
        readings=h,
        onset=min(a.start for a in alarms.values()),
        capture_interval=float(run["dt"]),
        alarms=alarms,
    )
    ranking = [r.pipe for r in loc.rank(evidence)]
    at_pipe = loc.position(evidence, pipe)  # the burst is mid-pipe: length / 2 from either end
    return {
        "named": ranking[0],
        "rank_of_burst_pipe": ranking.index(pipe) + 1,
        "position_error_m": round(abs(at_pipe.metres - at_pipe.length / 2), 1),
    }


def summarize(run: dict[str, Any], duration: float) -> dict[str, Any]:
    """A run's numbers without its arrays."""
    if "error" in run:
        out = {k: v for k, v in run.items() if k != "moc_cpu" or v is not None}
        if "tsnet_estimate_s" in run:
            out["estimated_s_per_sim_s"] = round(run["tsnet_estimate_s"] / duration, 1)
        return out
    t, h = np.array(run["time"]), np.array(run["heads"])
    before = t < run["start"]
    drift = np.abs(h[before] - h[0]).max(axis=0)
    return {
        "drift_meter_index": int(np.argmax(drift)),
        "dt": run["dt"],
        "steps": len(t),
        "duration": duration,
        "moc_cpu_s": round(run["moc_cpu"], 2),
        "cpu_per_sim_s": round(run["moc_cpu"] / duration, 3),
        "pre_burst_drift_m": float(drift.max()),
    }


def main() -> None:
    """Measure every ``NETWORK.inp:PIPE`` given."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("cases", nargs="+", metavar="NETWORK.inp:PIPE")
    parser.add_argument("--min-pipe-length", type=float, default=30.0)
    parser.add_argument("--duration", type=float, default=5.0)
    parser.add_argument("--original-duration", type=float, default=None)
    parser.add_argument("--timeout", type=float, default=540.0)
    parser.add_argument("--compare", action="store_true")
    parser.add_argument("--localize", action="store_true")
    parser.add_argument("--connectors", type=float, default=None, metavar="L")
    parser.add_argument("--split-nodes", nargs="*", default=["N2", "N5", "7"])
    parser.add_argument("--split-pipe", default="P7")
    parser.add_argument("--moved", type=int, default=2)
    args = parser.parse_args()
    for case in args.cases:
        path, pipe = case.rsplit(":", 1)
        if args.connectors is not None:
            out = f"/tmp/{os.path.basename(path)[:-4]}_connectors.inp"
            path = with_connectors(
                path, out, args.connectors, args.split_nodes, args.split_pipe, args.moved
            )
        row: dict[str, Any] = {"network": path, "pipe": pipe, **shape(path, args.min_pipe_length)}
        runs = {}
        for label, length in (("original", None), ("prepared", args.min_pipe_length)):
            duration = args.duration
            if label == "original" and args.original_duration is not None:
                duration = args.original_duration
            runs[label] = simulate(path, pipe, length, duration, args.timeout)
            row[label]["run"] = summarize(runs[label], duration)
            if args.localize and "error" not in runs[label]:
                row[label]["run"]["localized"] = localize(path, pipe, runs[label])
        if args.compare and all("error" not in r for r in runs.values()):
            row["comparison"] = compare(runs["original"], runs["prepared"])
        print(json.dumps(row, indent=1), flush=True)


if __name__ == "__main__":
    main()
