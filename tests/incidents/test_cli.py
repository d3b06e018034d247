"""``burstloc monitor --db`` and ``burstloc incidents``: a real monitor process keeps a real
burst as an incident; operators list, show, act on and export it from the command line; without
the incidents extra the monitor runs as before and ``--db`` says what to install."""

from __future__ import annotations

import csv
import io
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from burstloc.localize.config import Calibration
from burstloc.readings import Reading

sys.path.insert(0, str(Path(__file__).parents[1] / "live"))  # live_feed: a real burst

PIPE = "C"  # the burst pipe of the tiny_feed fixture


def _burstloc(*argv: str, stdin: str = "", env: dict[str, str] | None = None) -> Any:
    return subprocess.run(
        [sys.executable, "-m", "burstloc", *argv],
        input=stdin,
        capture_output=True,
        text=True,
        check=False,
        env={**os.environ, **(env or {})},
    )


@pytest.fixture(scope="module")
def setup(
    tiny: Path, tiny_config: Calibration, tiny_feed: list[Reading], tmp_path_factory: Any
) -> tuple[Path, Path, str]:
    folder = tmp_path_factory.mktemp("cli")
    config = tiny_config.save(folder / "tiny.json")
    csv_text = "".join(f"{r.timestamp:.1f},{r.meter},{r.value:.4f}\n" for r in tiny_feed)
    return tiny, config, csv_text


def _monitor(setup: tuple[Path, Path, str], *extra: str, env: Any = None) -> Any:
    network, config, feed = setup
    return _burstloc(
        "monitor", str(network), "--config", str(config), "--capture-interval", "0.2",
        "--health-every", "0", *extra, stdin=feed, env=env,
    )  # fmt: skip


def test_operators_act_on_the_monitors_incidents_from_the_command_line(
    setup: tuple[Path, Path, str], target: str, tmp_path: Path
) -> None:
    done = _monitor(setup, "--db", target)
    assert done.returncode == 0, done.stderr
    records = [json.loads(line) for line in done.stdout.splitlines()]
    (decision,) = [r for r in records if r["type"] == "decision"]
    assert "incidents kept in" in done.stderr
    listed = _burstloc("incidents", "list", "--db", target)
    assert listed.returncode == 0, listed.stderr
    header, row = listed.stdout.splitlines()
    assert header.split()[:5] == ["ID", "STATE", "KIND", "AGE", "DETECTED"]
    incident = row.split()[0]
    assert row.split()[1:3] == ["detected", "burst"] and f"pipe {PIPE}" in row
    steps = [
        ("ack", "--by", "ann", "--note", "on it"),
        ("dispatch", "--by", "ann"),
        ("close", "--by", "bob", "--found", "410.5,-95", "--note", "under the road"),
    ]
    for action, *options in steps:
        acted = _burstloc("incidents", action, incident, "--db", target, *options)
        assert acted.returncode == 0, acted.stderr
    refused = _burstloc("incidents", "ack", incident, "--db", target, "--by", "carol")
    assert refused.returncode == 2
    assert f"incident {incident} is closed: it cannot be acknowledged" in refused.stderr
    shown = _burstloc("incidents", "show", incident, "--db", target)
    assert shown.returncode == 0, shown.stderr
    lines = [line.split() for line in shown.stdout.splitlines() if line.startswith("  20")]
    early = [("answered", "monitor")] if records[0]["type"] == "transient" else []
    assert [(w[1], w[3]) for w in lines] == [
        ("detected", "monitor"), *early, ("acknowledged", "ann"), ("dispatched", "ann"),
        ("closed", "bob"),
    ]  # fmt: skip
    assert "found at 410.5,-95" in shown.stdout and "under the road" in shown.stdout
    exported = _burstloc("incidents", "export", "--db", target, "--format", "csv")
    (doc,) = list(csv.DictReader(io.StringIO(exported.stdout)))
    assert doc["id"] == incident and doc["pipe"] == PIPE and doc["outcome"] == "found"
    assert (doc["acknowledged_by"], doc["closed_by"]) == ("ann", "bob")
    assert float(doc["found_x"]) == 410.5 and float(doc["reading_time"]) == decision["first_alarm"]
    assert doc["alarmed"].split() == decision["alarmed"]
    if target.startswith("postgresql"):  # no --state: nowhere on this machine to keep them
        assert doc["readings"] == ""
        assert "the readings around each alarm not kept (a PostgreSQL store" in done.stderr
    else:
        assert Path(doc["readings"]).parent == Path(target).with_suffix(".readings")
    out = tmp_path / "incidents.json"
    written = _burstloc(
        "incidents", "export", "--db", target, "--format", "json", "--out", str(out)
    )
    assert written.returncode == 0, written.stderr
    (full,) = json.loads(out.read_text())
    assert full["record"]["time"] == decision["time"] and full["state"] == "closed"
    assert full["alarmed"] == decision["alarmed"]
    assert [h["action"] for h in full["history"]][-1] == "closed"


def test_bad_requests_are_refused_by_name(setup: tuple[Path, Path, str], tmp_path: Path) -> None:
    db = str(tmp_path / "i.sqlite")
    cases = [
        (["list"], "which incident store?"),
        (["show", "7", "--db", db], "no incident 7 in the incident store"),
        (["close", "1", "--db", db, "--by", "a", "--found", "1;2"], "a point is X,Y"),
        (["list", "--db", "mysql://x/y"], "postgresql:// URL"),
        (["list", "--state", str(tmp_path / "none.json")], "no incident store beside"),
    ]
    for argv, message in cases:
        done = _burstloc("incidents", *argv, env={"BURSTLOC_DB": ""})
        assert done.returncode == 2 and message in done.stderr, (argv, done.stderr)
    no_outcome = _burstloc("incidents", "close", "1", "--db", db, "--by", "a")
    assert no_outcome.returncode == 2 and "--found" in no_outcome.stderr
    alone = _monitor(setup, "--db")
    assert alone.returncode == 2 and "--db without a PATH or URL" in alone.stderr


def test_the_store_beside_the_state_file(setup: tuple[Path, Path, str], tmp_path: Path) -> None:
    state = tmp_path / "monitor.json"
    done = _monitor(setup, "--state", str(state), "--db")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "monitor.incidents.sqlite").exists()
    listed = _burstloc("incidents", "list", "--state", str(state))
    assert listed.returncode == 0 and "burst" in listed.stdout


def test_without_the_extra_the_monitor_runs_and_db_says_what_to_install(
    setup: tuple[Path, Path, str], tmp_path: Path
) -> None:
    blocked = tmp_path / "blocked"
    for name in ("sqlalchemy", "alembic"):  # as if not installed: importing them fails
        (blocked / name).mkdir(parents=True)
        (blocked / name / "__init__.py").write_text(
            f"raise ModuleNotFoundError(\"No module named '{name}'\", name='{name}')\n"
        )
    env = {"PYTHONPATH": os.pathsep.join([str(blocked), os.environ.get("PYTHONPATH", "")])}
    plain = _monitor(setup, env=env)
    assert plain.returncode == 0, plain.stderr
    assert json.loads(plain.stdout.splitlines()[-1])["pipes"][0]["pipe"] == PIPE
    with_db = _monitor(setup, "--db", str(tmp_path / "i.sqlite"), env=env)
    assert with_db.returncode == 2
    assert "--db needs the incidents extra: pip install 'burstloc[incidents]'" in with_db.stderr
    listed = _burstloc("incidents", "list", "--db", str(tmp_path / "i.sqlite"), env=env)
    assert listed.returncode == 2 and "pip install 'burstloc[incidents]'" in listed.stderr
