"""The readings kept around an alarm (``burstloc monitor --db``): what writing one capture's feed
file costs the monitor's thread: a Python loop (the first way) beside the text made in Rust
without the GIL of now.

Usage: ``.venv/bin/python benches/bench_kept.py [--meters N] [--rate HZ] [--runs N]
[--longest-runs N]`` (needs nothing beyond the package). In one process, for captures of
``--meters`` meters at ``--rate`` Hz (33 and 250: L-TOWN's sensors at the fastest capture
interval the monitor keeps up with) of the window lengths ``burstloc.incidents.kept`` defines:

* **typical**: :data:`~burstloc.incidents.kept.BEFORE` s before an onset 1 s before the first
  alarm, a second alarm 3 s later, :data:`~burstloc.incidents.kept.AFTER` s after it (64 s);
* **longest**: alarms that keep coming, so the capture runs to
  :data:`~burstloc.incidents.kept.LONGEST` s after the first (631 s);

each with the readings as meters send them (0.1 mm: four decimals, as ``burstloc simulate
--feed`` writes them) and as full doubles (a gateway that sends every digit of a computed value:
the slow path of the text), epoch timestamps to the millisecond and 0.1 % of the values filled.

Each capture is written by ``write_feed`` on a writer thread, as the recorder does, with the
text made the old way (a Python loop: one ``repr`` and one f-string per reading, every line
joined at the end; the code of ``kept.py`` before this benchmark) and the new way
(:func:`burstloc.incidents.kept.feed_bytes`: ``burstloc._core.feed_lines`` per piece of
:data:`~burstloc.incidents.kept.CHUNK` readings, which holds the GIL only to read its steps),
alternated, ``--runs`` times (``--longest-runs``
for the longest: 10-20 s each the old way). Beside it the main thread runs a busy Python loop
that records the longest gap between its iterations: how long the write held it up. Printed per
case: that longest stall (median and worst of the runs) each way and the ratio old / new, the
busy loop alone for as long (the machine's own stalls: the floor), the write's wall time and its
thread's CPU time each way, and the busy loop's iterations per second beside the write as a share
of its rate alone. The typical capture's two files are read back with
:func:`burstloc.live.parse.parse_lines` and must hold the same readings; whether they are the
same bytes (every number as ``repr`` writes it) is printed.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python"))

EPOCH = 1_800_000_000.0


def capture(meters: int, rate: float, seconds: float, digits: int | None) -> tuple[Any, list[str]]:
    """A claimed, complete capture of ``seconds`` of ``meters`` meters at ``rate`` Hz
    (``digits``: decimals of the values, ``None``: full doubles); its meters."""
    from burstloc.incidents.kept import Capture
    from burstloc.readings import Step

    rng = np.random.default_rng(2027)
    names = [f"n{k}" for k in range(meters)]
    count = round(seconds * rate)
    heads = 40.0 + 30.0 * rng.random(meters) + rng.normal(0.0, 0.02, (count, meters))
    values = heads if digits is None else np.round(heads, digits)
    filled = rng.random((count, meters)) < 0.001
    steps = [
        Step(
            round(EPOCH + k / rate, 3),
            values[k],
            tuple(n for n, f in zip(names, filled[k], strict=True) if f),
        )
        for k in range(count)
    ]
    first = steps[0].timestamp + 31.0
    held = Capture(first, steps[-1].timestamp, steps, [(first, first - 1.0)], complete=True)
    held.key, held.first_alarm = f"alarm:{first:.6f}", first
    return held, names


def python_loop(steps: Sequence[Any], meters: Sequence[str]) -> list[bytes]:
    """The feed file's text the old way (``kept.write_feed`` before this benchmark)."""
    import math

    from burstloc.readings import CSV_HEADER

    lines = [",".join(CSV_HEADER)]
    for step in steps:
        stamp = repr(float(step.timestamp))
        for meter, value in zip(meters, step.values, strict=True):
            v = float(value)
            if meter not in step.filled and math.isfinite(v):
                lines.append(f"{stamp},{meter},{v!r}")
    return [("\n".join(lines) + "\n").encode("utf-8")]


def written(held: Any, meters: Sequence[str], folder: Path, old: bool) -> Path:
    """``held`` written by ``write_feed`` (its text the old way or the new); the file."""
    from burstloc.incidents import kept

    if not old:
        return Path(kept.write_feed(held, meters, folder).path)
    new = kept.feed_bytes
    kept.feed_bytes = python_loop  # type: ignore[assignment]
    try:
        return Path(kept.write_feed(held, meters, folder).path)
    finally:
        kept.feed_bytes = new


def beside(work: Callable[[], Any]) -> tuple[float, float, float, float]:
    """``work`` on a thread while this one runs a busy loop: the loop's longest gap (s), its
    iterations per second, the work's wall time and its thread's CPU time (s)."""
    cpu = [0.0]

    def run() -> None:
        start = time.thread_time()
        work()
        cpu[0] = time.thread_time() - start

    thread = threading.Thread(target=run, name="writer")
    begin = last = time.perf_counter()
    thread.start()
    longest, turns = 0.0, 0
    while thread.is_alive():
        now = time.perf_counter()
        longest = max(longest, now - last)
        last = now
        turns += 1
    thread.join()
    wall = time.perf_counter() - begin
    return longest, turns / wall, wall, cpu[0]


def same_readings(a: Path, b: Path) -> int:
    """The readings of two feed files, equal (asserted); how many."""
    from burstloc.live.parse import parse_lines
    from burstloc.readings import Reading

    def read(path: Path) -> list[tuple[float, str, float]]:
        with path.open(encoding="utf-8") as lines:
            return [
                (r.timestamp, r.meter, r.value)
                for r in parse_lines(lines)
                if isinstance(r, Reading)
            ]

    first, second = read(a), read(b)
    assert first == second, "the two ways wrote different readings"
    return len(first)


def case(name: str, held: Any, meters: list[str], runs: int, check: bool) -> None:
    got: dict[str, list[tuple[float, float, float, float]]] = {"old": [], "new": [], "idle": []}
    with tempfile.TemporaryDirectory(prefix="bench-kept-") as tmp:
        folder = Path(tmp)
        files: dict[str, Path] = {}
        for k in range(runs):
            for way in ("old", "new") if k % 2 == 0 else ("new", "old"):
                path: list[Path] = []

                def write(old: bool = way == "old", out: list[Path] = path) -> None:
                    out.append(written(held, meters, folder, old))

                got[way].append(beside(write))
                files[way] = path[0].rename(folder / f"{way}.csv")
            # the busy loop alone for as long as the new way took: the machine's own stalls
            got["idle"].append(beside(lambda: time.sleep(got["new"][-1][2])))
        lines = sum(1 for _ in files["new"].open("rb")) - 1
        size = files["new"].stat().st_size / 1e6
        if check:
            same = same_readings(files["old"], files["new"])
            assert same == lines
            identical = files["old"].read_bytes() == files["new"].read_bytes()
    idle_rate = statistics.median(r[1] for r in got["idle"])
    stall = {w: [1000 * r[0] for r in got[w]] for w in got}
    print(f"{name}: {len(held.steps)} steps, {lines} readings, {size:.1f} MB, {runs} runs")
    for way, label in (("old", "old (Python loop)"), ("new", "new (Rust text)")):
        wall = statistics.median(r[2] for r in got[way])
        cpu = statistics.median(r[3] for r in got[way])
        share = statistics.median(r[1] for r in got[way]) / idle_rate
        print(
            f"   {label:18s} longest stall median {statistics.median(stall[way]):7.1f} ms, worst "
            f"{max(stall[way]):7.1f} ms | write {wall:6.2f} s wall, {cpu:6.2f} s CPU | busy loop "
            f"at {share:4.0%} of its rate alone"
        )
    print(
        f"   {'busy loop alone':18s} longest stall median {statistics.median(stall['idle']):7.1f}"
        f" ms, worst {max(stall['idle']):7.1f} ms (the machine's own)"
    )
    ratio = statistics.median(stall["old"]) / statistics.median(stall["new"])
    cpu_ratio = statistics.median(r[3] for r in got["old"]) / statistics.median(
        r[3] for r in got["new"]
    )
    checked = ""
    if check:
        checked = ", the same readings read back" + (", the same bytes" if identical else "")
    print(f"   old / new: longest stall x{ratio:.1f}, write CPU x{cpu_ratio:.1f}{checked}")


def main() -> None:
    from burstloc.incidents.kept import AFTER, BEFORE, LONGEST

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--meters", type=int, default=33)
    parser.add_argument("--rate", type=float, default=250.0)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--longest-runs", type=int, default=3)
    args = parser.parse_args()
    print(
        f"switch interval {sys.getswitchinterval() * 1000:g} ms; {args.meters} meters at "
        f"{args.rate:g} Hz"
    )
    spans = {"typical": BEFORE + 1.0 + 3.0 + AFTER, "longest": BEFORE + 1.0 + LONGEST}
    for span, seconds in spans.items():
        for values, digits in (("as sent", 4), ("full doubles", None)):
            held, meters = capture(args.meters, args.rate, seconds, digits)
            runs = args.runs if span == "typical" else args.longest_runs
            case(f"{span} ({seconds:g} s), {values}", held, meters, runs, span == "typical")
            del held


if __name__ == "__main__":
    main()
