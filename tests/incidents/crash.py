"""Kill -9 at random moments: a child process keeps incidents (through the monitor's recorder
and its writer thread) and acknowledges them (as an operator does), telling on stdout each
record once it is committed; the parent kills it at a random moment, again and again, then
checks that every record a child reported as committed is in the store, and that every stored
incident's meter rows (``incident_meters``) are its alarmed meters.

``python crash.py TARGET RUN`` is the child (RUN keeps its alarms apart from the other runs');
:func:`crash` is the parent (the test and ``benches/bench_incident_crash.py``).
"""

from __future__ import annotations

import os
import random
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import Any


def child(target: str, run: int) -> None:
    """Keep incidents and acknowledge them until killed; ``R KEY ID`` on stdout once a record
    is committed, ``A ID NAME`` once an acknowledgement is."""
    from burstloc.incidents import IncidentStore
    from burstloc.incidents.recorder import Recorder

    store = IncidentStore.open(target)
    committed: list[int] = []
    lock = threading.Lock()

    def told(batch: list, changed: list[int]) -> None:
        lines = "".join(f"R {item.key} {n}\n" for item, n in zip(batch, changed, strict=True))
        os.write(1, lines.encode())  # one write: whole lines, unbuffered
        with lock:
            committed.extend(n for n in changed if n)

    recorder = Recorder(store, lambda text: os.write(2, f"{text}\n".encode()), committed=told)
    os.write(1, b"S\n")  # started: the store is open (its schema made)
    k = 0
    while True:
        k += 1
        first = run * 1_000_000 + k
        recorder.record(
            {
                "type": "decision",
                "burst": True,
                "first_alarm": float(first),
                "time": first + 1.5,
                "pipes": [{"pipe": f"P{k % 25}", "score": 0.0}],
                "alarmed": [f"M{k % 7}", f"M{(k + 3) % 7}"],
            }
        )
        if k % 3 == 0:
            with lock:
                pending = committed[:]
                committed.clear()
            for incident in pending:
                name = f"op{run}"
                store.acknowledge(incident, name, "cli", note=f"run {run}")
                os.write(1, f"A {incident} {name}\n".encode())
        time.sleep(0.001)  # incidents come one by one, operators act between them


@dataclass
class Reported:
    """What the children reported as committed."""

    records: dict[str, int] = field(default_factory=dict)  # key -> incident
    acks: dict[int, str] = field(default_factory=dict)  # incident -> operator
    kills: int = 0
    started: int = 0  # children killed after they had opened the store


def _child_run(target: str, run: int, rng: random.Random, reported: Reported) -> None:
    proc = subprocess.Popen(  # the same burstloc as the parent's (its environment)
        [sys.executable, __file__, target, str(run)],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
    )
    assert proc.stdout is not None
    lines = rng.choice([0, 1, rng.randint(2, 10), rng.randint(10, 200)])
    got = 0
    while got < lines:
        line = proc.stdout.readline()
        if not line:
            break  # the child ended on its own: an error; found by the check below
        got += 1
        _note(line, reported)
    time.sleep(rng.random() * 0.02)  # into the middle of whatever it does now
    proc.kill()  # SIGKILL
    proc.wait()
    for line in proc.stdout:  # what it wrote before it died was committed too
        _note(line, reported)
    proc.stdout.close()
    reported.kills += 1
    if proc.returncode != -9:
        raise AssertionError(f"the child ended by itself (status {proc.returncode}), not killed")


def _note(line: bytes, reported: Reported) -> None:
    parts = line.decode().split()
    if parts[0] == "S":
        reported.started += 1
    elif parts[0] == "R" and parts[2] != "0":
        reported.records[parts[1]] = int(parts[2])
    elif parts[0] == "A":
        reported.acks[int(parts[1])] = parts[2]


def crash(target: str, moments: int, seed: int = 0) -> Reported:
    """Run and kill ``moments`` children on the store at ``target``; check that it holds every
    record they reported (raises ``AssertionError`` naming the first one missing)."""
    from burstloc.incidents import IncidentStore

    rng = random.Random(seed)
    reported = Reported()
    for run in range(1, moments + 1):
        _child_run(target, run, rng, reported)
    store = IncidentStore.open(target)
    try:
        if store.engine.dialect.name == "sqlite":
            with store.engine.connect() as connection:
                check = connection.exec_driver_sql("PRAGMA integrity_check").scalar()
            assert check == "ok", f"SQLite integrity check: {check}"
        rows = {r["id"]: r for r in store.incidents()}
        histories = store.histories()
        from sqlalchemy import select

        from burstloc.incidents.schema import incidents as t

        with store.engine.connect() as connection:
            keys = {r.key: r.id for r in connection.execute(select(t.c.key, t.c.id))}
        for key, incident in reported.records.items():
            assert keys.get(key) == incident, f"record {key} (incident {incident}) lost"
        _check_meters(store, rows)
        for incident, name in reported.acks.items():
            assert rows[incident]["state"] == "acknowledged", f"incident {incident} not acked"
            acks = [h for h in histories[incident] if h["action"] == "acknowledged"]
            assert [h["by"] for h in acks] == [name], f"incident {incident}'s ack lost"
    finally:
        store.close()
    return reported


def _check_meters(store: Any, incidents: dict[int, dict[str, Any]]) -> None:
    """Every incident's ``incident_meters`` rows are its ``alarmed`` meters: written in the
    incident's transaction, so no kill leaves one without the other."""
    from sqlalchemy import select

    from burstloc.incidents.schema import incident_meters as im

    rows: dict[int, set[str]] = {}
    with store.engine.connect() as connection:
        for incident, meter in connection.execute(select(im.c.incident_id, im.c.meter)):
            rows.setdefault(incident, set()).add(meter)
    for incident, row in incidents.items():
        alarmed = row["alarmed"]
        assert alarmed, f"incident {incident} kept without its alarmed meters"
        assert rows.get(incident, set()) == set(alarmed), (
            f"incident {incident}: meter rows {sorted(rows.get(incident, ()))} are not its "
            f"alarmed meters {alarmed}"
        )


if __name__ == "__main__":
    child(sys.argv[1], int(sys.argv[2]))
