"""burstloc.exceptions: the messages that tell a user what to do."""

from __future__ import annotations

from burstloc.exceptions import SimulatorMissingError


def test_simulator_not_installed_says_how_to_install_it() -> None:
    error = SimulatorMissingError(ImportError("No module named 'tsnet'", name="tsnet"))
    assert "not installed" in str(error) and SimulatorMissingError.INSTALL in str(error)
    assert error.package == "tsnet"


def test_missing_pkg_resources_names_setuptools_not_the_simulator() -> None:
    # WNTR 1.3.2 imports pkg_resources, gone from setuptools 81: the simulator is installed, and
    # reinstalling it (the message's advice before) changed nothing.
    cause = ImportError("No module named 'pkg_resources'", name="pkg_resources")
    text = str(SimulatorMissingError(cause))
    assert "not installed" not in text
    assert "pkg_resources" in text and "pip install 'setuptools<81'" in text


def test_another_missing_dependency_is_named_as_a_dependency() -> None:
    text = str(SimulatorMissingError(ImportError("No module named 'six'", name="six")))
    assert "dependency 'six' is missing" in text and "not installed" not in text
