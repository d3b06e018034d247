"""The control-room page (``burstloc monitor --web``): page ready, decision → highlighted, and
what the page costs the monitor.

Usage: ``.venv/bin/python benches/bench_web.py [--loads N] [--decisions N] [--runs N]
[--grid-pipes N]`` (needs the web extra, the sim extra for the feed, and Debian's Chromium:
``scripts/install-chromium.sh``). In one run, in headless Chromium driven by Selenium:

1. **Page ready** (navigation start → the network drawn and the first snapshot applied, the
   page's own ``performance.now()``), median and slowest of ``--loads`` fresh loads, on
   paper15, EPANET's Net3 (``networks/public``, when fetched) and a generated grid of
   ``--grid-pipes`` pipes; then one redraw of the whole map (a pan/zoom frame), median of 30.
2. **Decision record → highlighted**: a real decision record (paper15, a simulated burst on
   pipe 9, as the live loop emits it) handed to the hub ``--decisions`` times, naming a
   different pipe each time; the wall-clock time from the hand-off to the page's frame that
   draws the pipe (``Date.now()`` on both sides, one machine), p50/p99/max.
3. **The monitor with and without the page**: the same feed (the burst's readings, one by one)
   through a fresh live loop ``--runs`` times each way, alternated: no observer; the hub alone
   (the hand-off without a server thread); the hub and the server with no page; the hub and the
   server with a page open. Throughput (readings/s,
   median) and decision latency (wall time from feeding the reading that completes the
   decision to its record, median), each as a ratio to the loop without the page.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python"))
sys.path.insert(0, str(ROOT / "tests" / "live"))
sys.path.insert(0, str(ROOT / "tests" / "web"))

PAPER15 = ROOT / "networks" / "paper15.inp"
NET3 = ROOT / "networks" / "public" / "Net3.inp"  # `make networks`
METERS = ("N3", "N5", "N8", "2", "4", "6", "8")


def grid_network(path: Path, pipes: int) -> Path:
    """A square grid of about ``pipes`` pipes (one reservoir at a corner), as an INP file."""
    n = 2
    while 2 * n * (n - 1) < pipes:
        n += 1
    lines = ["[JUNCTIONS]"]
    lines += [f" J{i}_{j} 0 1" for i in range(n) for j in range(n)]
    lines += ["[RESERVOIRS]", " R 100", "[PIPES]"]
    count = 0
    for i in range(n):
        for j in range(n):
            for di, dj in ((1, 0), (0, 1)):
                if i + di < n and j + dj < n and count < pipes:
                    lines.append(f" P{count} J{i}_{j} J{i + di}_{j + dj} 100 200 100 0 OPEN")
                    count += 1
    lines.append(" PR R J0_0 100 300 100 0 OPEN")
    lines += ["[COORDINATES]", " R -100 -100"]
    lines += [f" J{i}_{j} {100 * i} {100 * j}" for i in range(n) for j in range(n)]
    lines.append("[END]")
    path.write_text("\n".join(lines) + "\n")
    return path


def page_ready(
    driver: Any, network: Path, loads: int
) -> tuple[list[float], float, list[float], int]:
    """Page-ready times (ms) of fresh loads, one full redraw's script time (ms, median), the
    frame intervals (ms, sorted) of 60 animation frames zooming in, pipes drawn."""
    from web_browser import page_state, wait_for

    from burstloc.web import control_room

    server = control_room(network, [], 0.2)
    server.start()
    try:
        ready = []
        for _ in range(loads):
            driver.get("about:blank")
            driver.get(server.url)
            state = wait_for(lambda: (s := page_state(driver)).get("ready") and s, "ready")
            ready.append(float(state["readyAt"]))
        frames = driver.execute_script(
            "const t = []; for (let k = 0; k < 30; k++) { view.s *= 1.01; "
            "const a = performance.now(); draw(); t.push(performance.now() - a); } "
            "t.sort((a, b) => a - b); return t;"
        )
        intervals = driver.execute_async_script(
            "const done = arguments[arguments.length - 1]; const t = []; let last = null; "
            "function f(now) { if (last !== null) t.push(now - last); last = now; "
            "view.s *= 1.01; dirty = true; "
            "if (t.length < 60) requestAnimationFrame(f); else done(t.sort((a, b) => a - b)); } "
            "requestAnimationFrame(f);"
        )
        return ready, float(statistics.median(frames)), intervals, int(state["drawnPipes"])
    finally:
        server.stop()


def real_decision(config: Any, steps: list[Any]) -> dict[str, Any]:
    from live_feed import Collected

    from burstloc.live.monitor import BurstMonitor
    from burstloc.readings import Reading

    monitor = BurstMonitor(PAPER15, config, capture_interval=0.2)
    readings = [
        Reading(s.timestamp, m, float(v))
        for s in steps
        for m, v in zip(config.meters, s.values, strict=True)
    ]
    return Collected(monitor).run(readings).decisions[0]


def highlight_latency(driver: Any, record: dict[str, Any], decisions: int) -> list[float]:
    """ms from handing a decision record to the hub to the page's frame that draws it."""
    from web_browser import page_state, wait_for

    from burstloc.inp import pipe_names_in_file
    from burstloc.web import control_room

    pipes = pipe_names_in_file(PAPER15)
    server = control_room(PAPER15, list(METERS), 0.2)
    server.start()
    try:
        driver.get(server.url)
        wait_for(lambda: page_state(driver).get("ready"), "ready")
        sent = []
        for k in range(decisions):
            pipe = pipes[k % len(pipes)]
            doc = dict(record, pipes=[dict(record["pipes"][0], pipe=pipe)], position=None,
                       time=record["time"] + k)  # fmt: skip
            sent.append(time.time() * 1000.0)
            server.hub.record(doc)
            wait_for(lambda k=k: len(page_state(driver)["highlights"]) > k, f"highlight {k}")
        shown = page_state(driver)["highlights"][:decisions]
        return [h["drawn"] - s for h, s in zip(shown, sent, strict=True)]
    finally:
        server.stop()


def monitor_run(config: Any, readings: list[Any], observer: Any) -> tuple[float, float, float]:
    """Readings/s through a fresh live loop (wall clock, and the loop thread's own CPU time),
    and the decision's latency (s, wall clock)."""
    from burstloc.live.health import Health
    from burstloc.live.loop import LiveLoop
    from burstloc.live.monitor import BurstMonitor
    from burstloc.live.plausible import PlausibleRange
    from burstloc.live.reporter import Reporter

    monitor = BurstMonitor(PAPER15, config, capture_interval=0.2)
    health = Health(
        monitor.meters,
        PlausibleRange.default(monitor.meters, monitor.steady.tolist()),
        capture_interval=0.2,
    )
    fed = [0.0]
    latency: list[float] = []

    def emit(record: dict[str, Any]) -> None:
        if record["type"] == "decision":
            latency.append(time.perf_counter() - fed[0])

    loop = LiveLoop(monitor, health, emit, Reporter(lambda s: None), observer=observer)
    start, cpu = time.perf_counter(), time.thread_time()
    for r in readings:
        fed[0] = time.perf_counter()
        loop.feed_reading(r, "bench")
    loop.finish()
    elapsed, cpu = time.perf_counter() - start, time.thread_time() - cpu
    assert len(latency) == 1, latency
    return len(readings) / elapsed, len(readings) / cpu, latency[0]


def with_and_without(driver: Any, config: Any, steps: list[Any], runs: int) -> dict[str, Any]:
    from web_browser import page_state, wait_for

    from burstloc.readings import Reading
    from burstloc.web import control_room

    readings = [
        Reading(s.timestamp, m, float(v))
        for s in steps
        for m, v in zip(config.meters, s.values, strict=True)
    ]
    from burstloc.web.hub import Hub

    setups = ("none", "hub", "server", "page")
    results: dict[str, list[tuple[float, float, float]]] = {s: [] for s in setups}
    server = control_room(PAPER15, list(config.meters), 0.2)
    server.start()
    try:
        for k in range(runs):
            for setup in setups if k % 2 == 0 else setups[::-1]:
                if setup == "page":
                    driver.get(server.url)
                    wait_for(lambda: page_state(driver).get("ready"), "ready")
                else:
                    driver.get("about:blank")
                observer = {"none": None, "hub": Hub()}.get(setup, server.hub)
                results[setup].append(monitor_run(config, readings, observer))
                time.sleep(0.3)  # the page side drains what this run handed off
    finally:
        server.stop()
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--loads", type=int, default=5)
    parser.add_argument("--decisions", type=int, default=100)
    parser.add_argument("--runs", type=int, default=15)
    parser.add_argument("--grid-pipes", type=int, default=15_000)
    parser.add_argument(
        "--network", type=Path, action="append", default=[], help="another INP file to load"
    )
    parser.add_argument("--sections", default="123", help="which parts to run, e.g. 3")
    parser.add_argument("--after", type=float, default=1800.0, help="s of readings after it")
    args = parser.parse_args()
    from live_feed import burst_steps
    from web_browser import chromium

    from burstloc.experiments.calibrate import calibrate

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        config = calibrate(PAPER15, capture_intervals=(0.2,), noise_sigma=0.01, meters=METERS)
        # a burst, then half an hour of readings: long runs, one decision each
        steps = burst_steps(PAPER15, config.meters, "9", sigma=0.003, after=args.after)
        networks = [("paper15", PAPER15)]
        if NET3.exists():
            networks.append(("Net3", NET3))
        networks += [(p.stem, p) for p in args.network]
        grid = grid_network(folder / "grid.inp", args.grid_pipes)
        networks.append((f"grid ({args.grid_pipes} pipes)", grid))
        with chromium(folder / "chromium") as driver:
            if "1" in args.sections:
                print("1. page ready (navigation start -> network drawn + snapshot applied)")
            for name, path in networks if "1" in args.sections else []:
                ready, frame, intervals, pipes = page_ready(driver, path, args.loads)
                median = statistics.median(ready)
                print(
                    f"   {name:22s} {pipes:6d} pipes: ready median {median:5.0f} ms, slowest "
                    f"{max(ready):5.0f} ms; zooming: redraw script {frame:4.1f} ms, frame "
                    f"interval median {statistics.median(intervals):5.1f} ms, slowest "
                    f"{intervals[-1]:5.1f} ms"
                )
            if "2" in args.sections:
                record = real_decision(config, steps)
                lat = sorted(highlight_latency(driver, record, args.decisions))
                p99 = lat[min(len(lat) - 1, round(0.99 * (len(lat) - 1)))]
                print(
                    f"2. decision record -> highlighted ({len(lat)} records): p50 "
                    f"{statistics.median(lat):.1f} ms, p99 {p99:.1f} ms, max {lat[-1]:.1f} ms"
                )
            if "3" not in args.sections:
                return
            results = with_and_without(driver, config, steps, args.runs)
        base_rate = statistics.median(r[0] for r in results["none"])
        base_cpu = statistics.median(r[1] for r in results["none"])
        base_lat = statistics.median(r[2] for r in results["none"])
        print(
            f"3. the monitor's live loop over {len(steps)} steps ({len(steps) * len(METERS)} "
            f"readings, one decision), {args.runs} runs each way, alternated (median); the "
            "loop thread's own CPU time beside the wall clock"
        )
        for setup, label in (
            ("none", "no observer"),
            ("hub", "hub alone (nobody drains)"),
            ("server", "hub + server, no page"),
            ("page", "hub + server + page open"),
        ):
            rate = statistics.median(r[0] for r in results[setup])
            cpu = statistics.median(r[1] for r in results[setup])
            lat_ms = statistics.median(r[2] for r in results[setup])
            print(
                f"   {label:26s} {rate:8.0f} readings/s wall (x{rate / base_rate:.3f}), "
                f"{cpu:8.0f} per CPU s (x{cpu / base_cpu:.3f}); decision latency "
                f"{1000 * lat_ms:6.2f} ms (x{lat_ms / base_lat:.3f})"
            )


if __name__ == "__main__":
    main()
