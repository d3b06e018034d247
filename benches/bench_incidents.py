"""The incident store (``burstloc monitor --db``): what a write costs, what the page's list of
10 000 incidents costs, and what keeping incidents costs the monitor.

Usage: ``.venv/bin/python benches/bench_incidents.py [--writes N] [--incidents N] [--runs N]
[--no-postgresql] [--sections 123] [--one-process] [--instructions]`` (needs the incidents, web
and sim extras; PostgreSQL's server binaries, ``scripts/install-postgresql.sh``, for its columns;
Valgrind for ``--instructions``):

1. **Write latency**: one incident kept (one transaction: the incident and its history row,
   :meth:`IncidentStore.take`) and one acknowledgement (:meth:`IncidentStore.act`), ``--writes``
   of each, p50 / p99 / max, on SQLite as the store runs it (WAL; the monitor's records with
   ``synchronous=NORMAL``, put on disk by :meth:`IncidentStore.sync` once a second between
   writes, as the recorder does, timed apart; the acknowledgements ``FULL``), beside SQLite
   with every commit ``FULL`` (what the monitor's records would cost on disk at once), a JSON
   line appended and fsync'ed (the least a durable write costs on this disk) and PostgreSQL (a
   throwaway server on loopback). Target: p99 <= 5 ms on SQLite.
2. **The page's list of 10 000 incidents**: ``GET /incidents.json`` over HTTP from the page's
   server (every incident, open first), median and slowest of ``--runs``, beside the query alone
   (:meth:`IncidentStore.incidents`) and the page's poll when nothing changed
   (``?after=VERSION``). Target: <= 1 s. Then what ``/metrics`` asks of the same store at each
   scrape, the old way and the new, alternated, ``--runs`` times: the open incidents' gauge
   (every open incident read, then counted: ``len(store.incidents(open_only=True))``; counted by
   the database: :meth:`IncidentStore.open_count`); the meters' false-alarm gauges (every
   incident read, then :func:`~burstloc.incidents.outcomes.meter_outcomes`; counted by the
   database: :meth:`IncidentStore.meter_counts`, checked equal); and the store's whole share of
   a scrape (the open gauge counted by the database, with the meters' gauges old and new), each
   as old / new. ``--sections 2 --no-page`` times only ``/metrics``.
3. **The monitor with the store on and off**: a feed of ``--bursts`` simulated bursts on
   paper15 (a real TSNet burst, repeated), one by one through a fresh live loop, ``--runs``
   times each way, alternated: no observer; the recorder on SQLite; on PostgreSQL (each
   keeping the readings around every alarm in a directory beside it, as the monitor does). Decisions
   per second of wall time and readings/s (median), and the decision latency (wall time from the
   reading that completes a decision to its record, median), each as a ratio to the loop
   without the store. Target: within 5 %. Each run is a fresh Python process (the feed and the
   configuration read from files made once), so that no run inherits another's state;
   ``--one-process`` runs them all in this process, warm (a fresh process replays about a
   quarter slower and its runs scatter more: benches/README.md).
   ``--instructions`` counts instead of timing: each way, a fresh process runs the feed of
   ``--bursts`` bursts and one of a single burst under Valgrind's callgrind (Debian's
   ``valgrind``; ``PYTHONHASHSEED=0``), and the difference of the two counts is what replaying
   ``--bursts - 1`` bursts costs in executed instructions, every thread of the process (the
   writer's with the monitor's), its start, imports and the store's opening left out. The
   counts do not depend on what else the machine runs: the store's share of the work, where
   the wall clock of a shared machine scatters by more than the target between two identical
   runs. (The database server's own work, PostgreSQL's, runs in its processes and is not
   counted; the time the writer waits for the disk is not work either.)
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.request
from collections.abc import Callable
from contextlib import ExitStack
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "live"))
sys.path.insert(0, str(ROOT / "tests" / "incidents"))
sys.path.insert(0, str(ROOT / "tests"))  # postgres: a throwaway server

PAPER15 = ROOT / "networks" / "paper15.inp"
METERS = ("N3", "N5", "N8", "2", "4", "6", "8")


def pct(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def decision(k: int) -> dict[str, Any]:
    """A decision record like the monitor's (a region, the health of 7 meters)."""
    meters = {m: {"last": 100.0 + k, "silent": False, "clock_offset": 0.0, "readings": k}
              for m in METERS}  # fmt: skip
    return {
        "type": "decision", "burst": True, "time": 10.0 * k + 3.2, "first_alarm": 10.0 * k,
        "pipes": [{"pipe": "9", "start": "N5", "end": "N6", "score": 0.0},
                  {"pipe": "8", "start": "N4", "end": "N5", "score": -1.3}],
        "position": {"pipe": "9", "from": "N5", "metres": 310.0, "low": 250.0, "high": 400.0,
                     "length": 600.0},
        "region": {"length_m": 420.0, "confidence": 0.95,
                   "stretches": [{"pipe": "9", "from": "N5", "low": 200.0, "high": 600.0}]},
        "decision_delay_s": 3.2, "localizer": "fused", "meters": list(METERS), "excluded": [],
        "alarmed": ["N5", "N8"], "health": {"type": "health", "meters": meters, "silent": []},
    }  # fmt: skip


def write_latency(store: Any, writes: int) -> tuple[list[float], list[float], list[float]]:
    """ms per incident kept (one transaction), per acknowledgement, and per sync of the
    monitor's records to disk, called as the recorder calls it (once a second, between
    writes, on the writer's thread)."""
    from burstloc.incidents.intake import from_record

    keep, ack, sync = [], [], []
    for k in range(1, writes + 1):
        item = from_record(decision(k), time.time())
        assert item is not None
        t = time.perf_counter()
        (incident,) = store.take([item])
        keep.append(1000 * (time.perf_counter() - t))
        if store.sync_due():
            t = time.perf_counter()
            store.sync()
            sync.append(1000 * (time.perf_counter() - t))
        t = time.perf_counter()
        store.acknowledge(incident, "ann", "bench")
        ack.append(1000 * (time.perf_counter() - t))
    return keep, ack, sync


def jsonl_latency(folder: Path, writes: int) -> list[float]:
    """ms per JSON line appended and fsync'ed (the floor of a durable write here)."""
    out = []
    with open(folder / "incidents.jsonl", "ab") as f:
        for k in range(writes):
            t = time.perf_counter()
            f.write(json.dumps(decision(k)).encode() + b"\n")
            f.flush()
            os.fsync(f.fileno())
            out.append(1000 * (time.perf_counter() - t))
    return out


def fill(store: Any, count: int) -> None:
    """``count`` past incidents: every one answered, a third closed with an outcome."""
    from burstloc.incidents import Outcome
    from burstloc.incidents.intake import from_record

    start = time.time() - 86_400 * 365
    for first in range(0, count, 500):
        items = [
            from_record(decision(k), start + 3000 * k)
            for k in range(first, min(first + 500, count))
        ]
        store.take(items)
    for row in store.incidents()[: count // 3]:
        store.acknowledge(row["id"], "ann", "bench")
        store.close_incident(row["id"], "ann", "bench", Outcome.false_alarm())


def page_listing(store: Any, runs: int) -> dict[str, list[float]]:
    """s per GET /incidents.json (HTTP), per query alone, per unchanged poll."""
    from burstloc.web import control_room

    server = control_room(PAPER15, list(METERS), 0.2, token="bench", incidents=store)
    server.start()
    base = f"http://127.0.0.1:{server.port}/incidents.json"
    headers = {"Authorization": "Bearer bench"}
    out: dict[str, list[float]] = {"route": [], "query": [], "poll": []}
    try:
        for _ in range(runs):
            t = time.perf_counter()
            with urllib.request.urlopen(urllib.request.Request(base, headers=headers)) as r:
                doc = json.loads(r.read())
            out["route"].append(time.perf_counter() - t)
            t = time.perf_counter()
            store.incidents()
            out["query"].append(time.perf_counter() - t)
            t = time.perf_counter()
            poll = urllib.request.Request(f"{base}?after={doc['version']}", headers=headers)
            with urllib.request.urlopen(poll) as r:
                assert json.loads(r.read())["unchanged"]
            out["poll"].append(time.perf_counter() - t)
        out["rows"] = [float(len(doc["incidents"]))]
    finally:
        server.stop()
    return out


def scrape_reads(store: Any, runs: int) -> dict[str, list[float]]:
    """s per read of ``store`` that ``/metrics`` makes at each scrape (``burstloc monitor``'s
    wiring), the old way and the new, alternated: the open incidents' gauge, the meters'
    false-alarm gauges, and both (the store's whole share of a scrape)."""
    from burstloc.incidents.outcomes import meter_outcomes

    def old_gauge() -> int:
        return len(store.incidents(open_only=True))

    def old_meters() -> list[Any]:
        return [m.counts() for m in meter_outcomes(store.incidents())]

    reads: dict[str, Callable[[], Any]] = {
        "gauge, old": old_gauge,
        "gauge, new": store.open_count,
        "meters, old": old_meters,
        "meters, new": store.meter_counts,
        "scrape, old": lambda: (store.open_count(), old_meters()),  # as before this change
        "scrape, new": lambda: (store.open_count(), store.meter_counts()),
    }
    assert old_gauge() == store.open_count()
    assert old_meters() == store.meter_counts()
    out: dict[str, list[float]] = {name: [] for name in reads}
    for k in range(runs):
        for name in reads if k % 2 == 0 else reversed(list(reads)):
            t = time.perf_counter()
            reads[name]()
            out[name].append(time.perf_counter() - t)
    return out


Run = tuple[float, float, float, int, float]


def monitor_run(config: Any, readings: list[Any], observer: Any) -> Run:
    """Decisions/s and readings/s through a fresh live loop (wall clock), the median decision
    latency (s), the decisions, readings/s of the loop thread's own CPU time."""
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
    rate = len(readings) / elapsed
    return (
        len(latency) / elapsed,
        rate,
        statistics.median(latency),
        len(latency),
        len(readings) / cpu,
    )


def burst_feed(config: Any, bursts: int) -> list[Any]:
    """``bursts`` copies of a real burst on pipe 9, one after another (each from the steady
    state again), as readings."""
    from live_feed import burst_steps

    from burstloc.readings import Reading

    steps = burst_steps(PAPER15, config.meters, "9", sigma=0.003, after=400.0)
    span = steps[-1].timestamp + 0.2
    return [
        Reading(round(b * span + s.timestamp, 6), m, float(v))
        for b in range(bursts)
        for s in steps
        for m, v in zip(config.meters, s.values, strict=True)
    ]


def one_run(config: Any, readings: list[Any], store: Any) -> Run:
    """One run of the loop, with the recorder on ``store`` (``None``: without it), keeping the
    readings around each alarm in a directory beside it, as the monitor does."""
    from burstloc.incidents.recorder import Recorder

    with tempfile.TemporaryDirectory(prefix="bench-readings-") as kept:
        recorder = (
            None
            if store is None
            else Recorder(store, print, meters=config.meters, readings=Path(kept))
        )
        gc.collect()  # each run from the same start: opening a store leaves garbage
        got = monitor_run(config, readings, recorder)
        if recorder is not None:
            recorder.close()
            assert recorder.dropped == 0
            store.close()
    return got


def save_feed(readings: list[Any], path: Path) -> None:
    """The feed's readings in ``path`` (NumPy arrays: times, meter names, values)."""
    import numpy as np

    np.savez(
        path,
        t=np.array([r.timestamp for r in readings]),
        meter=np.array([r.meter for r in readings]),
        value=np.array([r.value for r in readings]),
    )


def load_feed(path: Path) -> list[Any]:
    """The readings :func:`save_feed` wrote."""
    import numpy as np

    from burstloc.readings import Reading

    with np.load(path) as f:
        return [
            Reading(float(t), str(m), float(v))
            for t, m, v in zip(f["t"], f["meter"], f["value"], strict=True)
        ]


def child(config_path: str, feed_path: str, store_url: str | None) -> None:
    """``--child``: one run in this fresh process; its :data:`Run` printed as JSON."""
    from burstloc.incidents import IncidentStore
    from burstloc.localize.config import Calibration

    config = Calibration.load(config_path)
    readings = load_feed(Path(feed_path))
    store = None if store_url is None else IncidentStore.open(store_url)
    print(json.dumps(one_run(config, readings, store)))


def on_and_off(
    config: Any,
    readings: list[Any],
    runs: int,
    stores: dict[str, Callable[[], Any]],
    folder: Path,
    one_process: bool,
) -> dict[str, list[Run]]:
    # "off, again": the same loop without the store a second time, alternated with the others:
    # its ratio to "off" is what the machine's noise alone makes of a ratio
    setups = ["off", "off, again", *stores]
    results: dict[str, list[Run]] = {s: [] for s in setups}
    config_path, feed_path = folder / "config.json", folder / "feed.npz"
    if not one_process:
        config.save(config_path)
        save_feed(readings, feed_path)
    for k in range(runs):
        for setup in setups if k % 2 == 0 else setups[::-1]:
            if one_process:
                store = None if setup.startswith("off") else stores[setup]()
                results[setup].append(one_run(config, readings, store))
                continue
            url = None
            if not setup.startswith("off"):
                made = stores[setup]()  # a fresh database (migrated), left to the child
                url = made.url
                made.close()
            command = [sys.executable, __file__, "--child", str(config_path), str(feed_path)]
            done = subprocess.run(
                [*command, *([] if url is None else [url])],
                capture_output=True, text=True, check=True,
            )  # fmt: skip
            results[setup].append(tuple(json.loads(done.stdout.splitlines()[-1])))  # type: ignore[arg-type]
    return results


def instruction_counts(
    config: Any, bursts: int, stores: dict[str, Callable[[], Any]], folder: Path
) -> dict[str, float]:
    """Instructions (callgrind's count, every thread) of replaying ``bursts`` bursts less one
    burst, through a fresh process per count: without the store (``"off"``) and on each of
    ``stores`` (a fresh database each), two processes at a time."""
    from concurrent.futures import ThreadPoolExecutor

    config_path = folder / "config-instructions.json"
    config.save(config_path)
    feeds = {n: folder / f"feed-{n}.npz" for n in (1, bursts)}
    for n, path in feeds.items():
        save_feed(burst_feed(config, n), path)

    def fresh(setup: str) -> str | None:
        if setup == "off":
            return None
        made = stores[setup]()  # a fresh database (migrated), left to the child
        url: str = made.url
        made.close()
        return url

    def count(setup: str, n: int, url: str | None) -> int:
        command = [
            "valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
            sys.executable, __file__, "--child", str(config_path), str(feeds[n]),
        ]  # fmt: skip
        done = subprocess.run(
            [*command, *([] if url is None else [url])],
            capture_output=True, text=True, check=True,
            env={**os.environ, "PYTHONHASHSEED": "0"},
        )  # fmt: skip
        for line in done.stderr.splitlines():
            if "Collected :" in line:
                return int(line.split(":")[-1])
        raise RuntimeError(f"no instruction count from callgrind:\n{done.stderr[-2000:]}")

    setups = ["off", *stores]
    jobs = [(s, n, fresh(s)) for s in setups for n in (bursts, 1)]
    with ThreadPoolExecutor(2) as pool:
        done = pool.map(lambda job: count(*job), jobs)
        counts = {(s, n): c for (s, n, _), c in zip(jobs, done, strict=True)}
    return {s: float(counts[(s, bursts)] - counts[(s, 1)]) for s in setups}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--writes", type=int, default=2000)
    parser.add_argument("--incidents", type=int, default=10_000)
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--bursts", type=int, default=6)
    parser.add_argument("--no-postgresql", action="store_true")
    parser.add_argument("--sections", default="123", help="which parts to run, e.g. 13")
    parser.add_argument(
        "--no-page", action="store_true", help="section 2: only what /metrics asks of the store"
    )
    parser.add_argument(
        "--one-process", action="store_true", help="section 3: every run in this process"
    )
    parser.add_argument(
        "--instructions",
        action="store_true",
        help="section 3: executed instructions under callgrind instead of wall time",
    )
    parser.add_argument("--child", nargs="+", help=argparse.SUPPRESS)  # CONFIG FEED [STORE]
    args = parser.parse_args()
    if args.child:
        child(args.child[0], args.child[1], args.child[2] if len(args.child) > 2 else None)
        return
    from burstloc.incidents import IncidentStore

    with tempfile.TemporaryDirectory() as tmp, ExitStack() as stack:
        folder = Path(tmp)
        pg = None
        if not args.no_postgresql:
            from postgres import server

            pg = stack.enter_context(server())
        counter = iter(range(1_000_000))

        def sqlite() -> Any:
            return IncidentStore.open(str(folder / f"s{next(counter)}.sqlite"))

        stores: dict[str, Callable[[], Any]] = {"SQLite": sqlite}
        if pg is not None:
            stores["PostgreSQL"] = lambda: IncidentStore.open(pg.database())
        if "1" in args.sections:
            print(f"1. write latency, ms ({args.writes} incidents kept, each then acknowledged)")
            rows: list[tuple[str, list[float], list[float], list[float]]] = []
            store = sqlite()  # as it runs: the monitor's records NORMAL (synced once a second)
            rows.append(("SQLite, as the store runs", *write_latency(store, args.writes)))
            store.close()
            full = sqlite()
            full.monitor_sync = "FULL"
            rows.append(("SQLite, every commit FULL", *write_latency(full, args.writes)))
            full.close()
            if pg is not None:
                other = stores["PostgreSQL"]()
                rows.append(("PostgreSQL (loopback)", *write_latency(other, args.writes)))
                other.close()
            line = jsonl_latency(folder, args.writes)
            base = pct(rows[0][1], 0.99)
            for name, keep, ack, sync in rows:
                syncs = (
                    f" | {len(sync)} syncs p50 {statistics.median(sync):6.2f} max {max(sync):7.2f}"
                    if sync
                    else ""
                )
                print(
                    f"   {name:32s} keep p50 {statistics.median(keep):6.2f} p99 "
                    f"{pct(keep, 0.99):6.2f} max {max(keep):7.2f} | ack p50 "
                    f"{statistics.median(ack):6.2f} p99 {pct(ack, 0.99):6.2f} max "
                    f"{max(ack):7.2f} | keep p99 / the store's: x{pct(keep, 0.99) / base:.2f}"
                    + syncs
                )
            print(
                f"   {'JSON line + fsync':32s} p50 {statistics.median(line):6.2f} p99 "
                f"{pct(line, 0.99):6.2f} max {max(line):7.2f} | p99 / the store's keep: "
                f"x{pct(line, 0.99) / base:.2f}"
            )
        if "2" in args.sections:
            print(f"2. the page's list of {args.incidents} incidents, s")
            for name, make in stores.items():
                store = make()
                fill(store, args.incidents)
                got = None if args.no_page else page_listing(store, args.runs)
                scrape = {
                    k: statistics.median(v) for k, v in scrape_reads(store, args.runs).items()
                }
                opened, meters = store.open_count(), len(store.meter_counts())
                store.close()
                if got is not None:
                    route, query = (statistics.median(got[k]) for k in ("route", "query"))
                    print(
                        f"   {name:12s} GET /incidents.json median {route:.3f} slowest "
                        f"{max(got['route']):.3f} ({int(got['rows'][0])} rows) | the query "
                        f"alone {query:.3f} (x{query / route:.2f} of the route) | unchanged "
                        f"poll {statistics.median(got['poll']) * 1000:.1f} ms"
                    )
                parts = []
                for what, label in [("gauge", "the open gauge"), ("meters", "the meters' gauges"),
                                    ("scrape", "the whole")]:  # fmt: skip
                    old, new = scrape[f"{what}, old"] * 1000, scrape[f"{what}, new"] * 1000
                    parts.append(f"{label} old {old:.1f} ms, new {new:.2f} ms (x{old / new:.1f})")
                print(
                    f"   {name if got is None else '':12s} /metrics ({opened} open, {meters} "
                    "meters): " + " | ".join(parts)
                )
        if "3" not in args.sections:
            return
        from burstloc.experiments.calibrate import calibrate

        config = calibrate(PAPER15, capture_intervals=(0.2,), noise_sigma=0.01, meters=METERS)
        if args.instructions:
            counted = instruction_counts(config, args.bursts, stores, folder)
            print(
                f"3. the monitor, executed instructions of replaying {args.bursts - 1} bursts "
                f"(a feed of {args.bursts} less one of 1; callgrind, every thread)"
            )
            for setup, count in counted.items():
                print(
                    f"   store {setup:10s} {count / 1e9:7.3f} G instructions "
                    f"(x{count / counted['off']:.4f})"
                )
            return
        readings = burst_feed(config, args.bursts)
        results = on_and_off(config, readings, args.runs, stores, folder, args.one_process)
        off = results["off"]
        base_d = statistics.median(r[0] for r in off)
        base_r = statistics.median(r[1] for r in off)
        base_l = statistics.median(r[2] for r in off)
        base_c = statistics.median(r[4] for r in off)
        print(
            f"3. the monitor, {len(readings)} readings, {off[0][3]} decisions, {args.runs} runs "
            f"each way (medians), {'in one process' if args.one_process else 'each fresh'}"
        )
        for setup, got in results.items():
            d = statistics.median(r[0] for r in got)
            rate = statistics.median(r[1] for r in got)
            lat = statistics.median(r[2] for r in got)
            cpu = statistics.median(r[4] for r in got)
            assert all(r[3] == off[0][3] for r in got), "the same decisions every way"
            print(
                f"   store {setup:10s} {d:7.2f} decisions/s (x{d / base_d:.3f}), "
                f"{rate / 1000:6.1f} k readings/s (x{rate / base_r:.3f}; loop thread's CPU: "
                f"x{cpu / base_c:.3f}), decision latency {lat * 1000:6.2f} ms "
                f"(x{lat / base_l:.3f})"
            )


if __name__ == "__main__":
    main()
