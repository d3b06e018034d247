"""Pytest plugin: where the simulator (the ``sim`` extra) is not installed, a test that needs it
is reported as skipped, naming the extra, instead of failing.

A test "needs it" when it stops (at collection, in a fixture or in the test) on
:class:`~burstloc.exceptions.SimulatorMissingError` or on importing one of
:data:`SIMULATOR_PACKAGES`, or fails with that error's message in its output or its failure
(a command run through ``burstloc.cli.main`` or in a subprocess prints it). With the simulator
installed (both of CI's environments) this plugin changes nothing, so nothing is skipped there.
Loaded by ``conftest.py``.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Generator
from typing import Any

import pytest

from burstloc.exceptions import SimulatorMissingError

#: The packages of the ``sim`` extra that burstloc and its tests import.
SIMULATOR_PACKAGES = ("tsnet", "wntr", "pandas", "dask", "matplotlib")
#: Whether every one of them is installed.
SIMULATOR = all(importlib.util.find_spec(name) is not None for name in SIMULATOR_PACKAGES)
#: The errors already found to be the simulator's absence.
_SEEN: list[BaseException] = []
REASON = f"needs the simulator: {SimulatorMissingError.INSTALL}"


def missing_simulator(error: BaseException) -> bool:
    """Whether ``error`` is the simulator (or one of its packages) being absent."""
    if isinstance(error, SimulatorMissingError):
        return True
    if isinstance(error, ModuleNotFoundError) and error.name is not None:
        return error.name.split(".")[0] in SIMULATOR_PACKAGES
    return False


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Generator[Any]:
    report = yield
    if SIMULATOR or not report.failed:
        return report
    error = call.excinfo.value if call.excinfo is not None else None
    raised = error is not None and (missing_simulator(error) or error in _SEEN)
    printed = any(
        SimulatorMissingError.INSTALL in text for text in (report.capstderr, str(report.longrepr))
    )
    if raised or printed:
        if error is not None:
            _SEEN.append(error)  # a fixture's error is raised again in its later tests
        report.outcome = "skipped"
        report.longrepr = (str(item.path), item.location[1], f"Skipped: {REASON}")
    return report


@pytest.hookimpl(wrapper=True)
def pytest_make_collect_report(collector: pytest.Collector) -> Generator[Any]:
    report = yield
    if not SIMULATOR and report.failed and isinstance(collector, pytest.Module):
        text = str(report.longrepr)
        if any(f"No module named '{name}" in text for name in SIMULATOR_PACKAGES):  # an import
            report.outcome = "skipped"
            report.longrepr = (str(collector.path), 0, f"Skipped: {REASON}")
    return report
