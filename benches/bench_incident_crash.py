"""Kill -9 at 200 random moments loses no committed incident record: the crash test of
``tests/incidents/test_crash.py`` (20 moments there) at full length, on SQLite and on a
throwaway PostgreSQL server.

Usage: ``.venv/bin/python benches/bench_incident_crash.py [--moments 200] [--seed 37]
[--no-postgresql]`` (needs the incidents extra, and PostgreSQL's server binaries for its half:
``scripts/install-postgresql.sh``; about 3 minutes per store on 2 cores). A child process keeps
incidents through the monitor's recorder and acknowledges them, telling each record once it is
committed; it is killed (SIGKILL) at a random moment, ``--moments`` times, each child carrying
on in the store the last one left; then every record any child reported is checked to be in
the store, every incident's meter rows to be its alarmed meters (and SQLite's integrity check
to pass). Prints, per store, the records and acknowledgements reported and checked and the
seconds it took; exits 1 if one is missing.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "incidents"))
sys.path.insert(0, str(ROOT / "tests"))  # postgres: a throwaway server


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--moments", type=int, default=200)
    parser.add_argument("--seed", type=int, default=37)
    parser.add_argument("--no-postgresql", action="store_true")
    args = parser.parse_args()
    from crash import crash

    with tempfile.TemporaryDirectory() as tmp:
        targets = [("SQLite", lambda: str(Path(tmp) / "incidents.sqlite"))]
        if not args.no_postgresql:
            from postgres import server

            pg = server()
            running = pg.__enter__()
            targets.append(("PostgreSQL", running.database))
        failed = False
        try:
            for name, target in targets:
                start = time.perf_counter()
                try:
                    got = crash(target(), args.moments, args.seed)
                except AssertionError as exc:
                    print(f"{name:10s} LOST: {exc}")
                    failed = True
                    continue
                print(
                    f"{name:10s} {got.kills} kills ({args.moments - got.started} before the "
                    f"store was open): {len(got.records)} records and {len(got.acks)} "
                    f"acknowledgements reported committed, all present "
                    f"({time.perf_counter() - start:.0f} s)"
                )
        finally:
            if not args.no_postgresql:
                pg.__exit__(None, None, None)
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
