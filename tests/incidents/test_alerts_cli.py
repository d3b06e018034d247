"""``burstloc monitor --webhook``: a real monitor process replaying a real burst alerts a real
receiver that fails on purpose, escalates the unacknowledged incident, and after a restart
delivers what the last run left before the new run's alerts; bad values are refused by name."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from receiver import receiver

from burstloc.localize.config import Calibration
from burstloc.readings import Reading

PIPE = "C"  # the burst pipe of the tiny_feed fixture
NEW, ESCALATED = "incident.new", "incident.escalated"


@pytest.fixture(scope="module")
def setup(
    tiny: Path, tiny_config: Calibration, tiny_feed: list[Reading], tmp_path_factory: Any
) -> tuple[Path, Path, Path, Path]:
    folder = tmp_path_factory.mktemp("alerts")
    config = tiny_config.save(folder / "tiny.json")
    feed, later = folder / "feed.csv", folder / "later.csv"
    feed.write_text("".join(f"{r.timestamp:.1f},{r.meter},{r.value:.4f}\n" for r in tiny_feed))
    later.write_text(  # the same burst an hour later: another incident
        "".join(f"{r.timestamp + 3600:.1f},{r.meter},{r.value:.4f}\n" for r in tiny_feed)
    )
    return tiny, config, feed, later


def _monitor(setup: tuple[Path, Path, Path, Path], feed: Path, *extra: str) -> Any:
    network, config, _, _ = setup
    return subprocess.run(
        [
            sys.executable, "-m", "burstloc", "monitor", str(network), "--config", str(config),
            "--capture-interval", "0.2", "--health-every", "0", "--readings", str(feed), *extra,
        ],
        capture_output=True, text=True, check=False, env=dict(os.environ),
    )  # fmt: skip


def test_the_monitor_alerts_through_a_failing_receiver_and_escalates(
    setup: tuple[Path, Path, Path, Path], tmp_path: Path
) -> None:
    faults: list[int | str] = [503, "close"]
    db = tmp_path / "incidents.sqlite"
    with receiver(lambda: faults.pop(0) if faults else None) as got:
        done = _monitor(
            setup, setup[2], "--db", str(db), "--webhook", got.url,
            "--webhook-escalate-minutes", "1",
        )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert got.events == [(1, NEW), (1, ESCALATED)]  # nobody acknowledged it within a minute
    assert got.refused == [503, "close"]
    new = got.accepted[0][1]["incident"]
    assert new["pipe"] == PIPE and new["summary"].startswith(("burst", "alarm"))
    assert got.accepted[1][1]["at"] - got.accepted[0][1]["at"] == pytest.approx(60.0)  # replay time
    assert "webhook alerts to 1 URL(s)" in done.stderr
    assert "HTTP 503" in done.stderr and "RemoteDisconnected" in done.stderr
    assert "delivering again" in done.stderr
    assert (tmp_path / "incidents.webhook-dead.jsonl").exists() is False


def test_a_restarted_monitor_delivers_what_the_last_run_left_first(
    setup: tuple[Path, Path, Path, Path], tmp_path: Path
) -> None:
    db, dead = tmp_path / "incidents.sqlite", tmp_path / "dead.jsonl"
    options = ("--db", str(db), "--webhook-dead-letter", str(dead))
    down = [True]
    with receiver(lambda: 503 if down[0] else None) as got:
        first = _monitor(setup, setup[2], *options, "--webhook", got.url)
        assert first.returncode == 0, first.stderr
        assert "1 webhook alerts not delivered yet: kept in the outbox" in first.stderr
        assert got.accepted == [] and got.requests >= 2  # retried while the replay ran
        down[0] = False  # the receiver is back; the monitor starts again on the next file
        second = _monitor(setup, setup[3], *options, "--webhook", got.url)
    assert second.returncode == 0, second.stderr
    assert got.events == [(1, NEW), (2, NEW)]  # the last run's first, each once
    assert "not delivered yet" not in second.stderr and not dead.exists()


@pytest.mark.parametrize(
    ("argv", "settings", "message"),
    [
        (["--webhook", "ftp://host/x"], None, "argument --webhook: want an http:// or https://"),
        (["--webhook", "http://127.0.0.1:9/"], None, "--webhook needs --db"),
        (["--db", "DB", "--webhook-escalate-minutes", "5"], None, "needs --webhook"),
        (["--db", "DB"], 'webhook = ["not a url"]', "key 'webhook': want an http:// or https://"),
        (["--db", "DB"], 'webhook = "http://127.0.0.1:9/"', "key 'webhook': want an array"),
        (
            ["--db", "DB"],
            'webhook = ["http://127.0.0.1:9/"]\nwebhook-escalate-minutes = -5',
            "--webhook-escalate-minutes (settings key webhook-escalate-minutes) must be",
        ),
        (
            ["--db", "DB"],
            "webhook_escalate_minutes = 5",
            "did you mean 'webhook-escalate-minutes'?",
        ),
    ],
)
def test_bad_webhook_values_are_refused_by_name(
    setup: tuple[Path, Path, Path, Path],
    tmp_path: Path,
    argv: list[str],
    settings: str | None,
    message: str,
) -> None:
    argv = [str(tmp_path / "i.sqlite") if a == "DB" else a for a in argv]
    if settings is not None:
        (tmp_path / "monitor.toml").write_text(settings + "\n")
        argv += ["--settings", str(tmp_path / "monitor.toml")]
    done = _monitor(setup, setup[2], *argv)
    assert done.returncode == 2 and message in done.stderr, done.stderr
