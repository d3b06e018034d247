"""burstloc.inp_hydraulic: EPANET's time forms and water-quality lines, on real INP files read
by burstloc.network.load_network (WNTR)."""

from __future__ import annotations

from pathlib import Path

import pytest

from burstloc import network
from burstloc.exceptions import NetworkError
from burstloc.inp_hydraulic import clock_seconds, hydraulic_text, time_seconds
from conftest import TINY_INP


@pytest.mark.parametrize(
    ("value", "unit", "seconds"),
    [
        ("6", None, 21600),
        ("1.5", None, 5400),
        ("1:30", None, 5400),
        ("1:30:15", None, 5415),
        ("30", "MIN", 1800),
        ("30", "minutes", 1800),
        ("90", "SEC", 90),
        ("2", "Hours", 7200),
        ("1.5", "DAYS", 129600),
    ],
)
def test_time_values_as_epanet_reads_them(value: str, unit: str | None, seconds: float) -> None:
    assert time_seconds(value, unit) == pytest.approx(seconds)


@pytest.mark.parametrize(
    ("value", "am_pm", "seconds"),
    [
        ("6", "AM", 21600),
        ("6", "pm", 64800),
        ("12", "AM", 0),
        ("12", "PM", 43200),
        ("12:30", "AM", 1800),
        ("6:30", "PM", 66600),
        ("13", None, 46800),
        ("6.5", "AM", 23400),
    ],
)
def test_clock_times_as_epanet_reads_them(value: str, am_pm: str | None, seconds: float) -> None:
    assert clock_seconds(value, am_pm) == pytest.approx(seconds)


@pytest.mark.parametrize(("value", "unit"), [("13", "PM"), ("1:30", "MIN"), ("2", "FORTNIGHTS")])
def test_times_epanet_refuses_are_refused(value: str, unit: str) -> None:
    with pytest.raises(ValueError, match=value):
        time_seconds(value, unit)


_EXTRA = """
[TIMES]
 Duration           30 MIN
 Hydraulic Timestep 90 SEC
 Pattern Timestep   15 min
 Start ClockTime    6 PM
 Report Start       312
 Statistic          Average

[OPTIONS]
 Quality            Chemical TIME
 Diffusivity        1
 Segments           1000

[QUALITY]
 J1   0.5

[RULES]
RULE 1
IF SYSTEM CLOCKTIME >= 6 AM
AND SYSTEM CLOCKTIME < 8:30 PM
THEN PIPE E STATUS IS CLOSED

[CONTROLS]
 PIPE D CLOSED AT CLOCKTIME 12 AM

"""


def _with(tmp_path: Path, extra: str) -> Path:
    path = tmp_path / "clock.inp"
    text = TINY_INP.format(head=60)
    path.write_text(text.replace("[END]", extra + "[END]"), encoding="utf-8")
    return path


def test_clock_times_units_and_quality_options_load_as_epanet_reads_them(tmp_path: Path) -> None:
    # before: WNTR stopped at '6 AM' in the rule and at 'Chemical TIME', and read 30 MIN as 30 h
    path = _with(tmp_path, _EXTRA)
    text = path.read_text(encoding="utf-8")
    rewritten = hydraulic_text(path, text)
    assert rewritten is not None
    assert len(rewritten.splitlines()) == len(text.splitlines())  # errors keep their lines
    wn = network.load_network(path)
    times = wn.options.time
    assert (times.duration, times.hydraulic_timestep, times.pattern_timestep) == (1800, 90, 900)
    assert times.start_clocktime == 18 * 3600
    assert times.report_start == 0  # results from time 0 (Net3_trace: 312 h, no t = 0)
    assert wn.options.quality.parameter == "NONE"
    assert wn.name == str(path)
    condition = wn.get_control("1")._condition
    thresholds = (condition._condition_1._threshold, condition._condition_2._threshold)
    assert thresholds == (6 * 3600, 20.5 * 3600)
    control = wn.get_control("control 1")
    assert control.condition._threshold == 0  # 12 AM: midnight (was noon)
    assert network.steady_state(wn).flows["A"] > 0  # EPANET solves it


def test_an_untouched_file_is_read_as_it_is(tmp_path: Path) -> None:
    path = tmp_path / "tiny.inp"
    path.write_text(TINY_INP.format(head=60), encoding="utf-8")
    assert hydraulic_text(path, path.read_text(encoding="utf-8")) is None


def test_a_time_epanet_refuses_names_the_line(tmp_path: Path) -> None:
    path = _with(tmp_path, "\n[TIMES]\n Duration 13 PM\n\n")
    line = path.read_text(encoding="utf-8").splitlines().index(" Duration 13 PM") + 1
    with pytest.raises(NetworkError, match=rf"clock.inp:{line}: not a value EPANET accepts"):
        network.load_network(path)


def test_an_undefined_default_pattern_means_constant_demands(tmp_path: Path) -> None:
    path = _with(tmp_path, "\n[OPTIONS]\n Pattern  daily\n\n")
    wn = network.load_network(path)  # WNTR alone: "undefined time pattern, 'daily'"
    assert network.steady_state(wn).flows["A"] == pytest.approx(0.017, abs=1e-3)
    both = _with(tmp_path, "\n[PATTERNS]\n 1  1.0 0.5\n\n[OPTIONS]\n Pattern  daily\n\n")
    with pytest.raises(NetworkError, match="default pattern 'daily' is not defined"):
        network.load_network(both)
