"""The live path runs no hydraulic model: ``burstloc monitor`` decides with WNTR, TSNet (and the
EPANET inside WNTR), :mod:`burstloc.sim` and :mod:`burstloc.experiments` unimportable.

The configuration is made beforehand by ``burstloc calibrate`` (which does need WNTR); the
monitor then reads a burst from a CSV feed in a subprocess whose ``sitecustomize`` puts a
meta-path finder first that refuses those modules, and must print exactly what it prints
without the blocker.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from burstloc.cli import main
from burstloc.experiments.harness import readings_at_offset
from burstloc.experiments.runs import RunSpec
from burstloc.live.windows import readings_of
from burstloc.localize.config import Calibration
from burstloc.localize.detection import DetectorConfig
from burstloc.readings import Step
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.tsnet import simulate_burst

BLOCKED = ("wntr", "tsnet", "burstloc.sim", "burstloc.experiments")

SITECUSTOMIZE = f'''
"""Test blocker: the hydraulic-model stack cannot be imported in this interpreter."""
import sys

BLOCKED = {BLOCKED!r}


class _Blocker:
    def find_spec(self, name, path=None, target=None):
        if any(name == b or name.startswith(b + ".") for b in BLOCKED):
            raise ImportError(f"{{name}} is blocked: the live path must not import it")
        return None


sys.meta_path.insert(0, _Blocker())
'''

BURST_PIPE = "C"
DT = 0.2


@pytest.fixture(scope="module")
def setup(tiny: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A configuration from ``burstloc calibrate``, a feed with a burst on pipe C, a blocker."""
    folder = tmp_path_factory.mktemp("live-no-model")
    config = folder / "tiny.json"
    argv = ["calibrate", str(tiny), "--out", str(config), "--capture-interval", str(DT)]
    assert main([*argv, "--noise", "0.01"]) == 0
    scenario = BurstScenario(os.fspath(tiny), BURST_PIPE, burst_start=2.0, duration=156.0)
    result = simulate_burst(scenario)
    spec = RunSpec(DetectorConfig("cusum", 0.3), DT, 5, localizer="fused")
    times, values = readings_at_offset(result, spec, 0.0)
    steps = [Step(float(t), v) for t, v in zip(times, values, strict=True)]
    meters = Calibration.load(config).meters
    lines = ["timestamp,meter,value"]
    lines += [f"{r.timestamp!r},{r.meter},{r.value!r}" for r in readings_of(steps, meters)]
    feed = folder / "feed.csv"
    feed.write_text("\n".join(lines) + "\n")
    blocker = folder / "blocker"
    blocker.mkdir()
    (blocker / "sitecustomize.py").write_text(SITECUSTOMIZE)
    return {"network": tiny, "config": config, "feed": feed, "blocker": blocker, "dir": folder}


def _run(
    args: list[str], setup: dict[str, Path], *, blocked: bool, cache: Path
) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, BURSTLOC_CACHE_DIR=str(cache))
    path = [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]
    if blocked:
        path.insert(0, str(setup["blocker"]))
    env["PYTHONPATH"] = os.pathsep.join(path)
    return subprocess.run(
        [sys.executable, *args], capture_output=True, text=True, env=env, check=False
    )


def _monitor(localizer: str, setup: dict[str, Path]) -> list[str]:
    return [
        "-m",
        "burstloc",
        "monitor",
        str(setup["network"]),
        "--config",
        str(setup["config"]),
        "--capture-interval",
        str(DT),
        "--localizer",
        localizer,
        "--readings",
        str(setup["feed"]),
    ]


def test_the_blocker_blocks(setup: dict[str, Path], tmp_path: Path) -> None:
    for module in BLOCKED:
        done = _run(["-c", f"import {module}"], setup, blocked=True, cache=tmp_path)
        assert done.returncode != 0
        assert f"{module} is blocked" in done.stderr
    # calibrating needs the hydraulic model, so it cannot run behind the blocker
    argv = ["-m", "burstloc", "calibrate", str(setup["network"]), "--out", str(tmp_path / "x")]
    done = _run(argv, setup, blocked=True, cache=tmp_path)
    assert done.returncode != 0 and "is blocked" in done.stderr


@pytest.mark.parametrize("localizer", ["fused", "arrival", "signature"])
def test_the_monitor_decides_the_same_without_any_hydraulic_model(
    setup: dict[str, Path], localizer: str, tmp_path: Path
) -> None:
    free = _run(_monitor(localizer, setup), setup, blocked=False, cache=tmp_path / "free")
    assert free.returncode == 0, free.stderr
    blocked_cache = tmp_path / "blocked"
    blocked = _run(_monitor(localizer, setup), setup, blocked=True, cache=blocked_cache)
    assert blocked.returncode == 0, blocked.stderr
    assert blocked.stdout == free.stdout
    records = [json.loads(line) for line in blocked.stdout.splitlines()]
    decisions = [r for r in records if r["type"] == "decision"]
    assert decisions, "no burst located"
    assert decisions[0]["pipes"][0]["pipe"] == BURST_PIPE
    assert decisions[0]["first_alarm"] <= decisions[0]["time"]
    assert not blocked_cache.exists()  # nothing computed, nothing cached
