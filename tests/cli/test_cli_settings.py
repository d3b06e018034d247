"""`burstloc monitor --settings FILE.toml`: every option in one file, the command line over it,
errors naming the file and the key; the shipped example and service unit."""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path
from typing import Any

import pytest

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

from burstloc import cli
from burstloc.cli._settings import SettingsSpec

REPO = Path(__file__).resolve().parents[2]
EXAMPLE = REPO / "deploy" / "monitor.toml"
UNIT = REPO / "deploy" / "burstloc-monitor.service"


def _monitor_parser() -> argparse.ArgumentParser:
    parser = cli.build_parser("monitor")
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return sub.choices["monitor"]


def _parse(*argv: str) -> dict[str, Any]:
    """The monitor's options from ``argv`` (without the bookkeeping of where they came from)."""
    args = cli.build_parser("monitor").parse_args(["monitor", *argv])
    return {k: v for k, v in vars(args).items() if k not in ("settings", "settings_source")}


#: Every option of the monitor but --settings, given once, each away from its default.
FLAGS = [
    "net.inp", "--config", "cfg.json", "--capture-interval", "0.05", "--readings", "feed.csv",
    "--detector", "shewhart", "--localizer", "arrival", "--meter-model", "interval-averaged",
    "--timeout", "7", "--missing", "skip", "--classify", "cls.json", "--operations", "ops.csv",
    "--mqtt", "broker:1884", "--topic", "plant/#", "--decisions-topic", "d", "--health-topic",
    "h", "--client-id", "me", "--queue-size", "500", "--state", "state.json", "--save-every",
    "2.5", "--health-every", "10", "--silent-after", "45", "--clock-tolerance", "2",
    "--plausible", "0:100", "--plausible", "N4=1:90", "--crs", "EPSG:32633", "--web",
    "0.0.0.0:8080", "--web-token", "s3cret", "--replay-speed", "3", "--db", "incidents.sqlite",
    "--webhook", "https://alerts.example.org/a", "--webhook", "http://10.0.0.9:9000/hook",
    "--webhook-escalate-minutes", "15", "--webhook-dead-letter", "dead.jsonl",
]  # fmt: skip

SAME = """\
network = "net.inp"
config = "cfg.json"
capture-interval = 0.05
readings = "feed.csv"
detector = "shewhart"
localizer = "arrival"
meter-model = "interval-averaged"
timeout = 7
missing = "skip"
classify = "cls.json"
operations = "ops.csv"
mqtt = "broker:1884"
topic = "plant/#"
decisions-topic = "d"
health-topic = "h"
client-id = "me"
queue-size = 500
state = "state.json"
save-every = 2.5
health-every = 10
silent-after = 45
clock-tolerance = 2
plausible = ["0:100", "N4=1:90"]
crs = "EPSG:32633"
web = "0.0.0.0:8080"
web-token = "s3cret"
db = "incidents.sqlite"
replay-speed = 3
webhook = ["https://alerts.example.org/a", "http://10.0.0.9:9000/hook"]
webhook-escalate-minutes = 15
webhook-dead-letter = "dead.jsonl"
"""


def test_the_file_and_the_same_flags_make_the_same_configuration(tmp_path: Path) -> None:
    settings = tmp_path / "monitor.toml"
    settings.write_text(SAME)
    from_flags = _parse(*FLAGS)
    from_file = _parse("--settings", str(settings))
    assert from_file == from_flags
    keys = set(SettingsSpec(_monitor_parser()).actions)
    assert {line.split(" = ")[0] for line in SAME.splitlines()} == keys  # every option
    spec = SettingsSpec(_monitor_parser())
    assert [d for d, default in spec.defaults.items() if from_flags[d] == default] == []


def test_the_command_line_overrides_the_file(tmp_path: Path) -> None:
    settings = tmp_path / "monitor.toml"
    settings.write_text(SAME)
    given = _parse(
        "other.inp", "--settings", str(settings), "--health-every", "60", "--plausible", "5:50"
    )
    assert given["network"] == "other.inp"
    assert given["health_every"] == 60.0  # the command line's, though it is the default
    assert given["plausible"] == [(None, (5.0, 50.0))]  # replaces the file's list
    assert given["queue_size"] == 500  # the file's
    args = cli.build_parser("monitor").parse_args(
        ["monitor", "--settings", str(settings), "--queue-size", "9"]
    )
    assert args.settings_source.command_line == {"queue_size"}
    # a file without the required options: the command line still must give them
    partial = tmp_path / "partial.toml"
    partial.write_text("health-every = 5\n")
    with pytest.raises(SystemExit):
        _parse("--settings", str(partial))
    assert _parse("net.inp", "--config", "c", "--capture-interval", "1", "--settings",
                  str(partial))["health_every"] == 5.0  # fmt: skip
    # an option the file leaves out keeps its default
    settings.write_text(SAME.replace('meter-model = "interval-averaged"\n', ""))
    assert _parse("--settings", str(settings))["meter_model"] == "instantaneous"


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("capture_interval = 0.2", "key 'capture_interval'"),
        ('health-every = "10"', "key 'health-every': want a number, got a string"),
        ("queue-size = 10.5", "key 'queue-size': want an integer, got a number"),
        ("save-every = true", "key 'save-every': want a number, got a boolean"),
        ("save-every = inf", "key 'save-every': want a finite number, got inf"),
        ('detector = "cusum2"', "key 'detector': want one of 'cusum', 'shewhart', got 'cusum2'"),
        ('plausible = "0:10"', "key 'plausible': want an array, got a string"),
        ('plausible = ["N4=10"]', "key 'plausible': want [METER=]LOW:HIGH, got 'N4=10'"),
        ('webhook = ["ftp://x/y"]', "key 'webhook': want an http:// or https:// URL"),
        ("config = 3", "key 'config': want a string, got an integer"),
        ('settings = "other.toml"', "unknown key 'settings'"),
        ('[mqtt]\nhost = "x"', "key 'mqtt': want a string, got a table"),
        ('[broker]\nhost = "x"', "[broker] is a table; a settings file is flat"),
        ("health-every = ", "is not TOML: "),
    ],
)
def test_a_bad_key_or_value_is_one_line_naming_the_file_and_the_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], line: str, message: str
) -> None:
    settings = tmp_path / "monitor.toml"
    settings.write_text(f'network = "n.inp"\n{line}\n')
    assert cli.main(["monitor", "--settings", str(settings)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("burstloc: error: "), err
    assert str(settings) in err and message in err, err
    if line.startswith("capture_interval"):
        assert "did you mean 'capture-interval'" in err


def test_a_missing_file_is_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["monitor", "--settings", str(tmp_path / "none.toml")]) == 2
    assert "cannot read settings file" in capsys.readouterr().err


def test_the_example_file_sets_and_documents_every_option() -> None:
    spec = SettingsSpec(_monitor_parser())
    values = spec.load(EXAMPLE)  # it parses, and every key it sets is an option
    assert values["capture_interval"] == 0.2 and values["mqtt"] == "127.0.0.1:1883"
    text = EXAMPLE.read_text()
    commented = re.findall(r"^# ([a-z-]+ = .+?)(?:[ \t]+#.*)?$", text, flags=re.M)
    documented = {line.split(" = ")[0] for line in commented} | {spec.key(dest) for dest in values}
    assert documented == set(spec.actions), set(spec.actions) ^ documented
    for line in commented:  # the commented-out examples are good values too
        spec.check(tomllib.loads(line), "the example")


def test_the_service_unit_runs_the_monitor_on_the_settings_file() -> None:
    text = UNIT.read_text()
    lines = dict(
        line.split("=", 1) for line in text.splitlines() if "=" in line and line[0] not in "#;"
    )
    assert lines["ExecStart"].split()[1:] == ["monitor", "--settings", "/etc/burstloc/monitor.toml"]
    assert lines["Restart"] == "on-failure" and lines["User"] == "burstloc"
    assert lines["ExecReload"] == "/bin/kill -HUP $MAINPID"
    assert lines["StateDirectory"] == "burstloc" and lines["ProtectSystem"] == "strict"
    # the state the example keeps is where the unit lets it write
    assert SettingsSpec(_monitor_parser()).load(EXAMPLE)["state"].startswith("/var/lib/burstloc/")
