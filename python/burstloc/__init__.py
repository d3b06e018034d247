"""burstloc: real-time pipe-burst localization in water distribution networks.

What a user imports (``docs/api.md`` describes each):

* the detectors, implemented in Rust (``cpd-core``): :class:`Cusum`, :class:`Shewhart`,
  :class:`DetectorBank`, :class:`Alarm`, and the batch references :func:`detect_cusum`,
  :func:`detect_shewhart`;
* the errors: :class:`ConfigError`, :class:`InputError`, :class:`StreamError`,
  :class:`NetworkError` (all ``ValueError``), :class:`SimulationError` and its
  :class:`UnsteadyStartError`; the warning :class:`DemandDrivenWarning`;
* the live path: :class:`BurstMonitor`, fed complete time steps (:class:`Step`) that a
  :class:`StepFeed` assembles from readings (:class:`Reading`; :func:`parse_lines` reads them,
  and :class:`BadReading` what is not one, from CSV lines), :class:`ReadingStream` (the paper's
  localization windows),
  :class:`Calibration` (the stored configuration, with its :class:`LocalizationModel`), and
  what a decision holds: :class:`Decision`, :class:`Ranking`, :class:`RankedPipe`,
  :class:`BurstEvidence`;
* the offline side: :func:`calibrate`, :func:`evaluate`, :class:`BurstScenario`,
  :func:`simulate_burst`.

Importing ``burstloc`` loads only the native module and the exceptions; every other name is
imported on first use, so the live path never pays for the simulator (TSNet, WNTR), which
only :func:`simulate_burst`, :func:`evaluate` and :func:`calibrate` load.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from burstloc._core import (
    Alarm,
    Cusum,
    DetectorBank,
    Shewhart,
    __version__,
    detect_cusum,
    detect_shewhart,
)
from burstloc.exceptions import (
    ConfigError,
    DemandDrivenWarning,
    InputError,
    NetworkError,
    SimulationError,
    StreamError,
    UnsteadyStartError,
)

if TYPE_CHECKING:
    from burstloc.experiments.calibrate import calibrate
    from burstloc.experiments.evaluate import evaluate
    from burstloc.live.feeds import StepFeed
    from burstloc.live.monitor import BurstMonitor
    from burstloc.live.parse import BadReading, parse_lines
    from burstloc.live.windows import ReadingStream
    from burstloc.localize.classify import Classification, ClassifierConfig, Operation
    from burstloc.localize.config import Calibration
    from burstloc.localize.decide import Decision
    from burstloc.localize.evidence import BurstEvidence, RankedPipe, Ranking
    from burstloc.localize.model import LocalizationModel
    from burstloc.readings import Reading, Step
    from burstloc.sim.events.operations import EventScenario, simulate_event
    from burstloc.sim.scenarios.scenario import BurstScenario
    from burstloc.sim.transient.tsnet import simulate_burst

#: Names imported on first use, and the module each comes from.
_LAZY: dict[str, str] = {
    "BurstMonitor": "burstloc.live.monitor",
    "ReadingStream": "burstloc.live.windows",
    "StepFeed": "burstloc.live.feeds",
    "BadReading": "burstloc.live.parse",
    "parse_lines": "burstloc.live.parse",
    "Reading": "burstloc.readings",
    "Step": "burstloc.readings",
    "Calibration": "burstloc.localize.config",
    "Classification": "burstloc.localize.classify",
    "ClassifierConfig": "burstloc.localize.classify",
    "Operation": "burstloc.localize.classify",
    "LocalizationModel": "burstloc.localize.model",
    "Decision": "burstloc.localize.decide",
    "Ranking": "burstloc.localize.evidence",
    "RankedPipe": "burstloc.localize.evidence",
    "BurstEvidence": "burstloc.localize.evidence",
    "calibrate": "burstloc.experiments.calibrate",
    "evaluate": "burstloc.experiments.evaluate",
    "BurstScenario": "burstloc.sim.scenarios.scenario",
    "simulate_burst": "burstloc.sim.transient.tsnet",
    "EventScenario": "burstloc.sim.events.operations",
    "simulate_event": "burstloc.sim.events.operations",
}

__all__ = [
    "Alarm",
    "BadReading",
    "BurstEvidence",
    "BurstMonitor",
    "BurstScenario",
    "Calibration",
    "Classification",
    "ClassifierConfig",
    "ConfigError",
    "Cusum",
    "Decision",
    "DemandDrivenWarning",
    "DetectorBank",
    "EventScenario",
    "InputError",
    "LocalizationModel",
    "NetworkError",
    "Operation",
    "RankedPipe",
    "Ranking",
    "Reading",
    "ReadingStream",
    "Shewhart",
    "SimulationError",
    "Step",
    "StepFeed",
    "StreamError",
    "UnsteadyStartError",
    "__version__",
    "calibrate",
    "detect_cusum",
    "detect_shewhart",
    "evaluate",
    "parse_lines",
    "simulate_burst",
    "simulate_event",
]


def __getattr__(name: str) -> Any:
    """Import a public name of a layer on first use (PEP 562)."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'burstloc' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The public names and the module's own."""
    return sorted(set(globals()) | set(__all__))
