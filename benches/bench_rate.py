"""The live monitor at a high-rate logger's pace: does it keep up with L-TOWN's 33 sensors?

Usage: ``.venv/bin/python benches/bench_rate.py [--intervals 0.004 0.01 0.2] [--seconds 120]
[--pipe p518] [--repeat 3] [--work DIR]``. L-TOWN is extracted from the pinned epyt wheel that
``make networks`` keeps in ``networks/public/`` (as ``bench_ltown_accuracy.py`` does), with
BattLeDIM's 33 pressure sensors as the meters. Per capture interval, on fresh data:

1. the CUSUM bank calibrated for those sensors at a noise of 0.01 m (``burstloc calibrate``);
2. one feed of ``--seconds`` of readings with a 2.04 L/s burst on ``--pipe`` at its middle
   (``burstloc simulate --feed``, the 24 m transient-ready model, noise 0.01 m, seed 3);
3. the feed through a fresh live loop in this process, three ways, alternated ``--repeat``
   times (best of each): ``messages``, one JSON message per capture tick
   (``LiveLoop.feed_payload``, what ``burstloc monitor --mqtt`` does with a gateway's batches);
   ``rows``, the file's lines as rows, 64 kB of lines at a time
   (:func:`burstloc.live.lines.rows_of_lines`, what ``burstloc monitor --readings FILE`` does);
   ``lines``, line by line (``parse_line`` + ``LiveLoop.feed``: what ``--readings FILE`` did
   before, and does with ``--replay-speed``).

Printed per interval and way: readings, readings per second of the loop thread's CPU and of wall
time, the **headroom** (readings per second of CPU over what the meters send, 33 / interval: 10
means the monitor needs a tenth of a core to keep up), the first record with a search region
(seconds after the burst, the named pipe, the 95 % region's length); then the ratios to line
by line and whether every way answered the same. Target: headroom >= 10 at 0.004 s (250 Hz).
The wall time counts the other processes' time too; on a shared machine compare the CPU
columns.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bench_ltown import sensors_and_pipes
from bench_ltown_accuracy import burstloc

SIGMA = 0.01
FLOW = 2.04
MIN_PIPE = 24.0
READ = 1 << 16  # bytes the monitor reads from a file at a time


def feed_of(network: Path, meters: Path, work: Path, dt: float, seconds: float, pipe: str) -> Path:
    """The simulated feed (CSV lines) of one burst at the middle of ``seconds``."""
    feed = work / f"feed_{dt:g}.csv"
    burstloc(
        [
            "simulate", str(network), "--pipe", pipe, "--feed", str(feed),
            "--capture-interval", f"{dt:g}", "--noise", f"{SIGMA:g}", "--seed", "3",
            "--meters", str(meters), "--duration", f"{seconds:g}",
            "--burst-start", f"{seconds / 2:g}", "--min-pipe-length", f"{MIN_PIPE:g}",
            "--burst-flow", f"{FLOW:g}", "--no-cache", "--out", str(work / "sim"), "--quiet",
        ]
    )  # fmt: skip
    return feed


def messages(lines: list[bytes]) -> list[bytes]:
    """One JSON batch per capture tick (the lines of one timestamp), as a gateway sends them."""
    out: list[bytes] = []
    batch: list[dict[str, Any]] = []
    tick = None
    for line in lines:
        t, meter, value = line.decode().strip().split(",")
        if t != tick and batch:
            out.append(json.dumps(batch).encode())
            batch = []
        tick = t
        batch.append({"t": float(t), "meter": meter, "value": float(value)})
    if batch:
        out.append(json.dumps(batch).encode())
    return out


def fresh_loop(network: Path, config: Any, dt: float) -> tuple[Any, list[dict[str, Any]]]:
    """A live loop as ``burstloc monitor`` builds it, and the records it emits."""
    from burstloc.live.health import Health
    from burstloc.live.loop import LiveLoop
    from burstloc.live.monitor import BurstMonitor
    from burstloc.live.plausible import PlausibleRange
    from burstloc.live.reporter import Reporter

    monitor = BurstMonitor(network, config, capture_interval=dt)
    health = Health(
        monitor.meters,
        PlausibleRange.default(monitor.meters, monitor.steady.tolist()),
        capture_interval=dt,
    )
    records: list[dict[str, Any]] = []
    loop = LiveLoop(monitor, health, records.append, Reporter(lambda s: None), health_every=600)
    return loop, records


def timed(run: Callable[[], None]) -> tuple[float, float]:
    """(wall s, CPU s of this thread) of ``run()``."""
    wall, cpu = time.perf_counter(), time.thread_time()
    run()
    return time.perf_counter() - wall, time.thread_time() - cpu


def decision(records: list[dict[str, Any]], burst: float) -> str:
    """The first record with a search region (the early record or the decision): its type,
    seconds after the burst, named pipe and region length."""
    for r in records:
        region = r.get("region")
        if r["type"] != "health" and region:
            return (
                f"{r['type']} {r['time'] - burst:5.2f} s after the burst, "
                f"{r['pipes'][0]['pipe']}, region {region['length_m']:.0f} m"
            )
    return "no record with a region"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--intervals", type=float, nargs="+", default=[0.004, 0.01, 0.2])
    parser.add_argument("--seconds", type=float, default=120.0)
    parser.add_argument("--pipe", default="p518")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--work", type=Path, default=None, help="keep the files here")
    args = parser.parse_args()
    from burstloc.live.lines import rows_of_lines
    from burstloc.live.parse import parse_line
    from burstloc.localize.config import Calibration

    with tempfile.TemporaryDirectory() as tmp:
        work = args.work or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        network, meters, _ = sensors_and_pipes(work, 11)
        sensors = len(json.loads(meters.read_text())["meters"])
        print(f"L-TOWN, {sensors} meters, {args.seconds:g} s of readings per interval, burst on "
              f"{args.pipe} at {args.seconds / 2:g} s")  # fmt: skip
        for dt in args.intervals:
            path = work / f"config_{dt:g}.npz"
            burstloc(
                [
                    "calibrate", str(network), "--meters-file", str(meters),
                    "--capture-interval", f"{dt:g}", "--min-pipe-length", f"{MIN_PIPE:g}",
                    "--burst-flow", f"{FLOW:g}", "--out", str(path),
                ]
            )  # fmt: skip
            config = Calibration.load(path)
            lines = feed_of(network, meters, work, dt, args.seconds, args.pipe)
            raw = lines.read_bytes().splitlines()[1:]  # the header left out
            batches = messages(raw)

            pieces: list[list[bytes]] = [[]]
            size = 0
            for line in raw:  # what each 64 kB read gives
                if size + len(line) + 1 > READ:
                    pieces.append([])
                    size = 0
                pieces[-1].append(line)
                size += len(line) + 1

            def by_messages(loop: Any, batches: list[bytes] = batches) -> None:
                for k, payload in enumerate(batches):
                    loop.feed_payload(payload, f"message {k}")

            def by_rows(loop: Any, pieces: list[list[bytes]] = pieces) -> None:
                columns = {m: j for j, m in enumerate(loop.monitor.meters)}
                first = 2
                for piece in pieces:
                    row = rows_of_lines(piece, first, columns, loop.timestamps, 1 << 16)
                    loop.feed_row(row, f"lines {first}-{first + len(piece) - 1}")
                    first += len(piece)

            def by_lines(loop: Any, raw: list[bytes] = raw) -> None:
                for k, line in enumerate(raw):
                    where = f"line {k + 2}"
                    item = parse_line(line, where, loop.timestamps)
                    if item is not None:
                        loop.feed(item, where)

            best: dict[str, tuple[float, float]] = {}
            said: dict[str, str] = {}
            for _ in range(args.repeat):
                for name, run in (
                    ("messages", by_messages),
                    ("rows", by_rows),
                    ("lines", by_lines),
                ):
                    loop, records = fresh_loop(network, config, dt)
                    took = timed(lambda: run(loop))  # noqa: B023
                    loop.finish()
                    old = best.get(name, (float("inf"), float("inf")))
                    best[name] = (min(old[0], took[0]), min(old[1], took[1]))
                    said[name] = decision(records, args.seconds / 2)
            need = sensors / dt
            for name in ("messages", "rows", "lines"):
                wall, cpu = best[name]
                rate, paced = len(raw) / cpu, len(raw) / wall
                print(
                    f"{dt:6.3f} s {name:8s} {len(raw):9d} readings  {rate / 1e3:7.1f} k/s CPU "
                    f"({paced / 1e3:7.1f} k/s wall)  headroom x{rate / need:6.1f} "
                    f"(wall x{paced / need:6.1f})  {said[name]}"
                )
            print(
                f"{dt:6.3f} s over line by line (CPU): messages "
                f"x{best['lines'][1] / best['messages'][1]:.2f}, rows "
                f"x{best['lines'][1] / best['rows'][1]:.2f}; the same answer every way: "
                f"{len(set(said.values())) == 1}"
            )


if __name__ == "__main__":
    main()
