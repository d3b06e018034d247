"""A kill -9 at any moment loses no committed record: a child keeping incidents and
acknowledgements is killed at 20 random moments (SQLite and PostgreSQL); every record it
reported as committed is in the store after. ``benches/bench_incident_crash.py`` runs 200."""

from __future__ import annotations

from crash import crash


def test_kill_9_at_random_moments_loses_no_committed_record(target: str) -> None:
    reported = crash(target, moments=20, seed=37)
    assert reported.kills == 20
    # the moments fell everywhere: during start-up, and after records and acks were committed
    assert reported.started < 20 and reported.records and reported.acks
