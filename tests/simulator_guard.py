"""Pytest plugin: where the simulator (the ``sim`` extra) is not installed, a test that needs it
is reported as skipped, naming the extra, instead of failing.

A test "needs it" when it stops on :class:`~burstloc.exceptions.SimulatorMissingError` or on
importing one of :data:`SIMULATOR_PACKAGES` (at collection, in a fixture or in the test). With
the simulator installed (both of CI's environments) this plugin changes nothing, so nothing is
skipped there. Loaded by ``conftest.py``.
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
REASON = "needs the simulator: pip install 'burstloc[sim]'"


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
    if not SIMULATOR and call.excinfo is not None and missing_simulator(call.excinfo.value):
        report.outcome = "skipped"
        report.longrepr = (str(item.path), item.location[1], f"Skipped: {REASON}")
    return report


@pytest.hookimpl(wrapper=True)
def pytest_make_collect_report(collector: pytest.Collector) -> Generator[Any]:
    report = yield
    if not SIMULATOR and report.failed and isinstance(collector, pytest.Module):
        text = str(report.longrepr)
        if any(f"No module named '{name}" in text for name in SIMULATOR_PACKAGES):
            report.outcome = "skipped"
            report.longrepr = (str(collector.path), 0, f"Skipped: {REASON}")
    return report
