"""``burstloc incidents shelve | unshelve | shelve-meter | unshelve-meter`` on a real store
(SQLite and PostgreSQL): recorded with who, until when and why; ``list`` marks the shelved;
refusals name the problem and exit 2."""

from __future__ import annotations

from typing import Any

import pytest

from burstloc.cli import main
from burstloc.incidents import IncidentStore
from burstloc.incidents.intake import from_record

RECORD = {
    "type": "decision", "burst": True, "first_alarm": 62.4, "time": 75.0,
    "pipes": [{"pipe": "9", "score": 0.0}], "region": {"length_m": 80.0},
}  # fmt: skip


@pytest.fixture
def incident(target: str) -> int:
    store = IncidentStore.open(target)
    try:
        item = from_record(RECORD, 1_800_000_000.0)
        assert item is not None
        return store.take([item])[0]
    finally:
        store.close()


def _run(capsys: Any, target: str, *argv: str) -> tuple[int, str, str]:
    status = main(["incidents", *argv, "--db", target])
    out, err = capsys.readouterr()
    return status, out, err


def test_an_incident_is_shelved_listed_apart_and_unshelved(
    target: str, incident: int, capsys: Any
) -> None:
    n = str(incident)
    status, out, _ = _run(
        capsys, target, "shelve", n, "--for", "1h30m", "--reason", "hydrant flush", "--by", "ann"
    )
    assert status == 0 and out.startswith(f"incident {n}: shelved until ")
    store = IncidentStore.open(target)
    try:
        doc = store.get(incident)
    finally:
        store.close()
    last = doc["history"][-1]
    assert (last["action"], last["by"], last["via"], last["note"]) == (
        "shelved", "ann", "cli", "hydrant flush",
    )  # fmt: skip
    assert doc["shelved_until"] - last["at"] == 5400.0
    status, out, _ = _run(capsys, target, "list")
    assert status == 0 and "[shelved until " in out
    status, out, _ = _run(capsys, target, "show", n)
    assert "shelved until" in out and "by ann: hydrant flush" in out
    status, out, _ = _run(capsys, target, "unshelve", n, "--by", "bob")
    assert status == 0 and "unshelved" in out
    status, out, _ = _run(capsys, target, "list")
    assert "[shelved until " not in out


@pytest.mark.parametrize(
    ("argv", "said"),
    [(["--for", "30h", "--reason", "x"], "at most 24 h, got '30h'"),
     (["--for", "soon", "--reason", "x"], "a number with a unit"),
     (["--for", "30m", "--reason", " "], "shelving needs a reason")],
)  # fmt: skip
def test_a_bad_shelving_is_refused_by_name(
    target: str, incident: int, capsys: Any, argv: list[str], said: str
) -> None:
    status, _, err = _run(capsys, target, "shelve", str(incident), *argv, "--by", "ann")
    assert status == 2 and said in err


def test_a_meter_is_shelved_from_the_command_line(target: str, capsys: Any) -> None:
    argv = ("shelve-meter", "N3", "--for", "4h", "--reason", "recalibration", "--by", "ann")
    status, out, _ = _run(capsys, target, *argv)
    assert status == 0 and "meter N3: shelved until" in out and "localization" in out
    status, out, err = _run(capsys, target, "list")
    assert "meter N3 shelved until" in out and "by ann: recalibration" in out
    assert _run(capsys, target, "unshelve-meter", "N3", "--by", "ann")[0] == 0
    status, _, err = _run(capsys, target, "unshelve-meter", "N3", "--by", "ann")
    assert status == 2 and "meter 'N3' is not shelved" in err
