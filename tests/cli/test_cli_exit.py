"""The command line's one exit-status convention, ``--version`` and defaults in ``--help``."""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import pytest

import burstloc
from burstloc import cli
from burstloc.exceptions import SimulationError, SimulatorMissingError, UnsteadyStartError


def test_version() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "burstloc", "--version"], capture_output=True, text=True, check=False
    )
    assert done.returncode == 0 and done.stdout.strip() == f"burstloc {burstloc.__version__}"


@pytest.mark.parametrize(
    ("error", "status", "says"),
    [
        # a simulation that ran and failed: 1, as `simulate` reports failed pipes (was 2 from
        # `evaluate`, 1 from `simulate`)
        (UnsteadyStartError("net.inp", "J1", 0.1, 1.0, 10.0, 0.05), 1, "burstloc: failed: "),
        (SimulationError("TSNet failed on pipe 7"), 1, "burstloc: failed: "),
        # a missing simulator is an installation problem: 2, with the error line
        (SimulatorMissingError(ImportError("x", name="tsnet")), 2, "burstloc: error: "),
    ],
)
def test_failures_exit_1_and_bad_setups_exit_2(
    error: Exception,
    status: int,
    says: str,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    def failing(args: argparse.Namespace) -> int:
        raise error

    from burstloc.cli import place

    monkeypatch.setattr(place, "run", failing)  # the handler its parser registers
    assert cli.main(["place", "x.inp", "--meters", "2"]) == status
    assert capsys.readouterr().err.startswith(says)


def test_simulate_help_shows_defaults_and_the_paper_burst(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit):
        cli.main(["simulate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    # the burst `evaluate` simulates: a share of the demand, opened in 0.3 s; the paper's
    # coefficient named
    assert "Default: 5 % of the network's demand, at most 5 L/s (2 L/s on L-TOWN)" in text
    assert "--burst-share PCT size every burst as this percentage of the network's demand" in text
    assert "final emitter coefficient instead, m^3/s/m^0.5 (the paper's: 0.02" in text
    assert "how long the burst takes to open, s (default: 0.3)" in text
    assert "(default: None)" not in text


def test_bad_input_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["simulate", str(tmp_path / "missing.inp"), "--pipe", "P1"]) == 2
    assert capsys.readouterr().err.startswith("burstloc: error: ")


@pytest.mark.parametrize("command", cli.SUBCOMMANDS)
def test_every_option_with_a_default_shows_it_in_help(command: str) -> None:
    from burstloc.cli._options import DefaultsFormatter

    parser = cli.build_parser(command)
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    formatter = DefaultsFormatter("burstloc")
    missing = [
        action.option_strings[0]
        for action in sub.choices[command]._actions
        if action.option_strings
        and action.default not in (None, False, [], argparse.SUPPRESS)
        and "default" not in (formatter._get_help_string(action) or "")
    ]
    assert missing == []


def test_the_monitor_help_names_its_defaults(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        cli.main(["monitor", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for shown in ["default: cusum", "(default: burstloc/decisions)", "(default: burstloc/health)"]:
        assert shown in text
    assert '"score"' in text  # what a decision's score means
