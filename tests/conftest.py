"""Shared fixtures: the shipped network, small test networks, an isolated cache, a Dask cluster.

Every test session gets its own burstloc cache directory (``BURSTLOC_CACHE_DIR`` points into
pytest's temporary directory), so tests never read or fill the user's cache.

Hypothesis: the ``ci`` profile (modest example counts, no deadline) is loaded unless
``HYPOTHESIS_PROFILE`` names another registered profile (``dev`` runs more examples).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, settings

# Where the simulator (the sim extra) is missing, tests that need it are skipped, naming it;
# the incident store's tests run on SQLite and on a real PostgreSQL server (store_targets).
pytest_plugins = ("simulator_guard", "store_targets")

settings.register_profile(
    "ci", max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.register_profile("dev", max_examples=300, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

REPO = Path(__file__).resolve().parents[1]
PAPER15 = REPO / "networks" / "paper15.inp"
TNET1 = REPO.parent / "shared" / "networks" / "Tnet1.inp"

#: A five-pipe looped network for fast simulations: R1 feeds J1, which feeds J2 and J3.
TINY_INP = """\
[TITLE]
tiny test network

[JUNCTIONS]
;ID   Elev   Demand
 J1   0      5
 J2   0      5
 J3   0      5
 J4   0      2

[RESERVOIRS]
 R1   {head}

[PIPES]
;ID  Node1  Node2  Length  Diameter  Roughness  MinorLoss  Status
 A    R1     J1     300     300       100        0          Open
 B    J1     J2     200     200       100        0          Open
 C    J1     J3     250     200       100        0          Open
 D    J2     J3     150     150       100        0          Open
 E    J3     J4     180     150       100        0          Open

[OPTIONS]
 Units              LPS
 Headloss           H-W
 Required Pressure  0.1

[COORDINATES]
 R1   0     0
 J1   300   0
 J2   500   100
 J3   500   -100
 J4   680   -100

[END]
"""


def write_tiny(path: Path, head: float = 60.0) -> Path:
    """Write the tiny network (reservoir head ``head`` m) to ``path`` and return it."""
    path.write_text(TINY_INP.format(head=head), encoding="utf-8")
    return path


@pytest.fixture(autouse=True, scope="session")
def _isolated_cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """Point burstloc's default cache at a per-session temporary directory."""
    directory = tmp_path_factory.mktemp("burstloc-cache")
    previous = os.environ.get("BURSTLOC_CACHE_DIR")
    os.environ["BURSTLOC_CACHE_DIR"] = str(directory)
    yield directory
    if previous is None:
        os.environ.pop("BURSTLOC_CACHE_DIR", None)
    else:
        os.environ["BURSTLOC_CACHE_DIR"] = previous


@pytest.fixture
def cache_dir(tmp_path: Path) -> Path:
    """An empty cache directory for one test."""
    return tmp_path / "cache"


@pytest.fixture(scope="session")
def paper15() -> Path:
    """The shipped paper network."""
    return PAPER15


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The tiny network, written once per test module."""
    return write_tiny(tmp_path_factory.mktemp("tiny") / "tiny.inp")


@pytest.fixture(scope="module")
def tiny_config(tiny: Path) -> Any:
    """The tiny network calibrated at 0.2 s for noise sigma = 0.01 m."""
    from burstloc.experiments.calibrate import calibrate

    return calibrate(tiny, capture_intervals=(0.2,), noise_sigma=0.01)


@pytest.fixture(scope="module")
def tiny_feed(tiny: Path, tiny_config: Any) -> Any:
    """A real TSNet burst on pipe ``C`` of the tiny network with noise sigma = 0.002 m, as
    per-meter readings (tests/live/live_feed.py)."""
    import sys

    live = str(Path(__file__).resolve().parent / "live")
    if live not in sys.path:  # on the path of tests/live's own tests; not of the others'
        sys.path.append(live)
    from live_feed import burst_steps, readings

    return readings(burst_steps(tiny, tiny_config.meters, "C", sigma=0.002), tiny_config.meters)


@pytest.fixture
def tiny_network(tmp_path: Path) -> Path:
    """The tiny five-pipe network, written to a temporary file."""
    return write_tiny(tmp_path / "tiny.inp")


@pytest.fixture(scope="session")
def dask_scheduler() -> Iterator[str]:
    """The address of a real Dask ``LocalCluster`` with 2 single-threaded worker processes."""
    from dask.distributed import LocalCluster

    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        yield cluster.scheduler_address
